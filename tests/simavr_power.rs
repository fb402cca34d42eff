//! Nothing lost to a reset or a power cut (issue 40), on the REAL firmware image in simavr:
//! the kept program survives a warm reset at any moment after a Modbus master wrote a
//! preset; `ADDR` survives a power cut after any of its EEPROM writes (the old address or
//! the new one, never the default); the scan count wraps at 2³² and the mean scan time
//! stays right across the wrap.
//!
//! Needs `out/m328-nano-utile.elf` (`cargo fw`).

mod support;

use support::chip::{static_address, Board, Rig, CYCLES_PER_MS};
use support::master::{char_cycles, pdu, read_input, Line, ADDRESS};
use support::scenario::listing as listing_of;
use utile_core::modbus::snapshot::{self, SNAPSHOT};
use utile_core::store;
use utile_kit::listing;
use utile_kit::modbus;
use utile_kit::sim::SimBoard;
use utile_kit::simavr::RxPacing;

/// Holding register 0 (T0's preset) as the master reads it.
fn preset_t0(line: &mut Line) -> u16 {
    let (_, reply) = line.transact(&[0x03, 0, 0, 0, 1]);
    modbus::registers(&pdu(&reply))[0]
}

/// The running program's fingerprint (SPEC §17, input register 103).
fn fingerprint(line: &mut Line) -> u16 {
    read_input(line, SNAPSHOT + 39, 1)[0]
}

/// Type `text` and CR on the line (the terminal and the master share it), then run `ms`
/// and on until the terminal has been quiet for 20 ms (at most 2 s), its output taken.
fn typed(line: &mut Line, text: &str, ms: u64) {
    line.send(0, format!("{text}\r").as_bytes());
    line.run(ms * CYCLES_PER_MS);
    let mut quiet = 0;
    for _ in 0..200 {
        line.nano.chip.run_for(10 * CYCLES_PER_MS);
        if line.nano.chip.take_output().is_empty() {
            quiet += 1;
            if quiet == 2 {
                return;
            }
        } else {
            quiet = 0;
        }
    }
}

/// A warm reset (the reset button) at 30 moments from the end of a master's write of T0's
/// preset to well after its reply: each time the program the editor comes back with is the
/// one that ran (its fingerprint), with T0's preset old or new, and new once the reply has
/// begun. Before, the presets were sealed with the program and resealed a visit after the
/// reply was queued: a reset in between found the seal stale and started with a blank
/// program.
#[test]
fn the_kept_program_survives_a_warm_reset_at_any_moment_after_a_preset_written_over_modbus() {
    // 0.5 ms a scan: the visits of a reply are far apart.
    let prog = listing_of("slowest_scan");
    let mut b = SimBoard::new();
    store::store(&prog, &mut b).expect("STORE");
    let eeprom: &'static [u8] = Box::leak(b.eeprom.into_boxed_slice());
    let mut nano = Board::boot_with(Rig {
        d8: false,
        d9: false,
        eeprom: Some(eeprom),
    });
    nano.chip.set_rx_pacing(RxPacing::Line { baud: 19_200 });
    let mut line = Line {
        nano,
        de: Vec::new(),
    };
    line.run(700 * CYCLES_PER_MS);
    typed(&mut line, "LOAD", 300);
    typed(&mut line, "EX0", 300);
    let want = snapshot::fingerprint(&prog.uf);
    assert_eq!(fingerprint(&mut line), want, "the program runs");
    let mut old = preset_t0(&mut line);
    let c = char_cycles();
    let mut wrong = Vec::new();
    // Microseconds after the request's last stop bit: the silence ends at 1,823.
    let moments: Vec<u64> = (0..24)
        .map(|k| 1_700 + 50 * k)
        .chain([3_200, 4_000, 5_000, 7_000, 10_000, 20_000])
        .collect();
    for (k, us) in moments.into_iter().enumerate() {
        let new = 10 + k as u16;
        let frame = modbus::frame(ADDRESS, &[0x06, 0, 0, 0, new as u8]);
        line.nano.chip.take_output_timed();
        let end = line.send(4 * c, &frame);
        let at = end + us * CYCLES_PER_MS / 1000;
        line.nano.chip.run_for(at - line.nano.chip.cycle());
        let sent = line.nano.chip.take_output_timed();
        let replied = sent.first().is_some_and(|&(_, stop)| stop - c <= at);
        line.nano.reset_button();
        // The editor comes back (a warm reset, no D8): run the program it kept again.
        line.run(100 * CYCLES_PER_MS);
        typed(&mut line, "EX0", 300);
        let (got, t0) = (fingerprint(&mut line), preset_t0(&mut line));
        if got != want || !(t0 == old || t0 == new) || (replied && t0 != new) {
            wrong.push(format!(
                "reset {us} µs after the write (reply begun: {replied}): fingerprint \
                 {got:04X} (the program's {want:04X}), T0 {t0} (old {old}, new {new})"
            ));
            // Put the program back for the next moment (a blank program has no KEY).
            line.nano.reset_button();
            line.run(100 * CYCLES_PER_MS);
            typed(&mut line, "LOAD", 300);
            typed(&mut line, "EX0", 300);
        }
        old = preset_t0(&mut line);
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The address `ADDR` alone shows on the editor's screen.
fn shown_address(nano: &mut Board) -> u8 {
    nano.take_output();
    nano.enter("ADDR", 300);
    let screen = nano.screen();
    let at = screen.find("Modbus address ").expect("ADDR's line") + "Modbus address ".len();
    screen[at..]
        .chars()
        .take_while(char::is_ascii_digit)
        .collect::<String>()
        .parse()
        .expect("a number")
}

/// A power cut after each EEPROM byte write of `17` `ADDR` over address 5 (as this firmware
/// keeps it, and as versions 2–4 kept it: one copy): at the next power-up the slave is at
/// 5 or 17. Before, a cut between the address and its complement brought it back at 1.
#[test]
fn a_power_cut_after_any_eeprom_write_of_addr_leaves_the_old_address_or_the_new_one() {
    let mut wrong = Vec::new();
    for one_copy in [false, true] {
        let mut b = SimBoard::new();
        if one_copy {
            let at = usize::from(store::ADDR_CELL);
            b.eeprom[at] = 5;
            b.eeprom[at + 1] = !5;
        } else {
            assert!(store::set_slave_address(&mut b, 5));
        }
        let eeprom: &'static [u8] = Box::leak(b.eeprom.into_boxed_slice());
        let mut n = 0;
        loop {
            let mut nano = Board::boot_with(Rig {
                eeprom: Some(eeprom),
                ..Rig::default()
            });
            assert!(nano.wait_for("User File", 2_000));
            assert_eq!(shown_address(&mut nano), 5, "the address before");
            nano.enter("17", 300);
            // Each byte write takes the chip's 3.4 ms, so a cut within 50 µs of a write's
            // start comes before the next.
            nano.chip.set_eeprom_write_time(true);
            let before = nano.chip.ee_writes();
            nano.type_bytes(b"ADDR\r");
            // Until the n-th write has started (or 300 ms without it: ADDR is done).
            let limit = nano.cycles() + 300 * CYCLES_PER_MS;
            while nano.chip.ee_writes() < before + n && nano.cycles() < limit {
                nano.run_cycles(CYCLES_PER_MS / 20);
            }
            assert!(nano.chip.ee_writes() <= before + n, "one write at a time");
            let done = nano.chip.ee_writes() < before + n;
            nano.power_cycle();
            nano.run_ms(50);
            assert!(nano.wait_for("User File", 2_000));
            let got = shown_address(&mut nano);
            if got != 5 && got != 17 || (done && got != 17) {
                wrong.push(format!(
                    "one copy before: {one_copy}; cut after {n} writes: address {got}"
                ));
            }
            if done {
                break;
            }
            n += 1;
        }
        assert!(n >= 2, "ADDR wrote {} bytes", n.saturating_sub(1));
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

/// The scan count (input registers 4–5) wraps at 2³² and the mean scan time (register 2)
/// stays the run time over the scans counted. The count's high word is set to 0xFFFF in RAM
/// (`SERVER`'s first field) so the wrap comes within 65,536 scans; before, the mean went on
/// dividing the whole run's time by the few scans since the wrap.
#[test]
fn the_scan_count_wraps_at_two_to_the_32_and_the_mean_stays_right() {
    let mut line = Line::new(&listing::commands(&["A0.", ".Y0", "END"]));
    let server = static_address("6SERVER");
    // The run's first 5 s: a mean of a run long enough that a wrong one shows.
    line.nano.chip.run_for(5_000 * CYCLES_PER_MS);
    let before = read_input(&mut line, 0, 6);
    line.nano.chip.poke(usize::from(server), 0xFF);
    line.nano.chip.poke(usize::from(server) + 1, 0xFF);
    let high = read_input(&mut line, 4, 2);
    assert_eq!(high[0], 0xFFFF, "the count's high word set: {high:?}");
    // 65,536 scans of about 4 µs, and more.
    line.nano.chip.run_for(400 * CYCLES_PER_MS);
    let r = read_input(&mut line, 0, 6);
    let count = u32::from(r[4]) << 16 | u32::from(r[5]);
    let (min, mean, max) = (r[1], r[2], r[3]);
    assert!(
        count < 1 << 20,
        "the count wrapped to the scans since: {count}"
    );
    assert!(
        min <= mean && mean <= max + 1,
        "mean {mean} µs between min {min} and max {max} (before the wrap: {before:?})"
    );
    assert!(
        mean.abs_diff(before[2]) <= 1,
        "the mean {mean} µs, as before the wrap ({} µs)",
        before[2]
    );
}
