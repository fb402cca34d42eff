//! The simavr harness's own speed, in simulated MHz per second of this process's CPU time
//! (and of wall time): one idle chip, one chip under a master polling at line rate (the
//! Modbus soak's pattern), and three chips on a [`Bus`] polled in turn. BENCHMARKS.md ("The
//! test loop") records the figures.
//!
//! `cargo run -p utile-kit --example harness_speed [-- SECONDS [ONLY]]` (the test profile's build,
//! as the tests run it; add `--release` for the virtual Nano's). Only the measurements whose name contains ONLY run. Needs
//! `out/m328-nano-utile.elf` (`cargo fw`) or `$UTILE_ELF`.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use utile_core::store;
use utile_kit::listing;
use utile_kit::modbus;
use utile_kit::sim::SimBoard;
use utile_kit::simavr::{frame_cycles, Bus, Chip, RigPin, RxPacing, CYCLES_PER_MS, F_CPU};

/// CPU time of this process so far (user + system).
fn cpu_time() -> Duration {
    // SAFETY: a plain C struct that getrusage fills; all-zero is a valid value.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    // SAFETY: RUSAGE_SELF with a valid pointer to a rusage.
    unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) };
    let tv = |t: libc::timeval| Duration::new(t.tv_sec as u64, t.tv_usec as u32 * 1000);
    tv(usage.ru_utime) + tv(usage.ru_stime)
}

fn elf() -> PathBuf {
    std::env::var_os("UTILE_ELF").map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../out/m328-nano-utile.elf"),
        PathBuf::from,
    )
}

/// A chip with the soak's program stored and autostarted (D8), slave address `address`.
fn chip(address: u8) -> Chip {
    let prog = listing::commands(&[
        "CLKA.", ".Y0", "A0.", "!", ".Y1", "U0.", ".Y2", "KEY", "END",
    ]);
    let mut b = SimBoard::new();
    store::store(&prog, &mut b).expect("STORE");
    assert!(store::set_slave_address(&mut b, address));
    let mut c = Chip::load(&elf()).unwrap_or_else(|e| panic!("{e}"));
    c.set_eeprom(0, &b.eeprom);
    c.hold_low(RigPin::D8, true);
    c
}

/// [`chip`] after a second of boot and autostart, its RUN screen taken.
fn started(address: u8, pacing: RxPacing) -> Chip {
    let mut c = chip(address);
    c.set_rx_pacing(pacing);
    c.run_for(F_CPU);
    c.take_output();
    c
}

/// FNV-1a over what a run produced (bytes with their cycles, final cycles): the same
/// figure before and after a change of the harness means the simulation did not change.
struct Fingerprint(u64);

impl Fingerprint {
    fn add(&mut self, value: u64) {
        for b in value.to_le_bytes() {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x100_0000_01B3);
        }
    }
}

/// Runs `work` for `seconds` of simulated time prints the
/// simulated MHz per CPU second and per wall second.
fn measure(
    name: &str,
    chips: u64,
    seconds: u64,
    mut work: impl FnMut(u64, &mut Fingerprint) -> u64,
) {
    if std::env::args()
        .nth(2)
        .is_some_and(|only| !name.contains(&only))
    {
        return;
    }
    let mut print = Fingerprint(0xCBF2_9CE4_8422_2325);
    let (cpu0, wall0) = (cpu_time(), Instant::now());
    let cycles = work(seconds * F_CPU, &mut print) * chips;
    let (cpu, wall) = (cpu_time() - cpu0, wall0.elapsed());
    let mhz = |t: Duration| cycles as f64 / t.as_secs_f64() / 1e6;
    println!(
        "{name:<34} {:>6.1} simulated MHz per CPU second ({:>5.2}x the wall clock per chip), \
         {:>6.1} per wall second; fingerprint {:016x}",
        mhz(cpu),
        mhz(cpu) / chips as f64 / 16.0,
        mhz(wall),
        print.0
    );
}

/// The soak's exchange: a request after 4 characters of silence, then quarter-millisecond
/// slices until the reply is in (or 20 ms more passed).
fn exchange(c: &mut Chip, frame: &[u8], expect: usize, print: &mut Fingerprint) -> usize {
    let ch = frame_cycles(19_200);
    c.send_after(4 * ch, frame);
    let end = c.cycle() + (4 + frame.len() as u64) * ch;
    c.run_for(end - c.cycle());
    let mut got = 0;
    let deadline = c.cycle() + (expect as u64 + 2) * ch + 20 * CYCLES_PER_MS;
    while c.cycle() < deadline {
        c.run_for(CYCLES_PER_MS / 4);
        for (byte, stop) in c.take_output_timed() {
            print.add(u64::from(byte) << 56 | stop);
            got += 1;
        }
        if got >= expect {
            c.run_for(2 * ch);
            break;
        }
    }
    got
}

fn main() {
    let seconds: u64 = std::env::args()
        .nth(1)
        .map_or(10, |s| s.parse().expect("SECONDS"));
    println!(
        "{seconds} simulated seconds each, image {}",
        elf().display()
    );

    let mut idle = started(1, RxPacing::default());
    measure("one chip, idle (RUN, no input)", 1, seconds, |n, print| {
        let start = idle.cycle();
        idle.run_for(n);
        print.add(idle.cycle());
        print.add(u64::from(idle.pc()));
        idle.cycle() - start
    });

    let mut polled = started(1, RxPacing::Line { baud: 19_200 });
    let request = modbus::frame(1, &[0x03, 0, 0, 0, 26]);
    measure("one chip, master at line rate", 1, seconds, |n, print| {
        let start = polled.cycle();
        while polled.cycle() - start < n {
            assert_eq!(exchange(&mut polled, &request, 5 + 52, print), 5 + 52);
        }
        print.add(polled.cycle());
        polled.cycle() - start
    });

    let mut bus = Bus::new(vec![chip(1), chip(2), chip(3)], 19_200).with_driver_enable();
    assert!(bus.run_for(F_CPU).is_none(), "a chip stopped");
    bus.take_master();
    let mut to = 0u8;
    measure("three chips on a bus, polled", 3, seconds, |n, print| {
        let start = bus.cycle();
        while bus.cycle() - start < n {
            to = to % 3 + 1;
            bus.send_after(
                4 * frame_cycles(19_200),
                &modbus::frame(to, &[0x03, 0, 0, 0, 26]),
            );
            assert!(bus.run_for(40 * CYCLES_PER_MS).is_none(), "a chip stopped");
            let reply = bus.take_master();
            assert_eq!(reply.len(), 5 + 52, "slave {to} answered");
            for b in reply {
                print.add(u64::from(b.byte) << 56 | (b.from as u64) << 48 | b.cycle);
            }
        }
        for i in 0..bus.len() {
            print.add(bus.chip(i).cycle());
        }
        print.add(bus.collisions().len() as u64);
        bus.cycle() - start
    });
}
