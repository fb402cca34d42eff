//! The line on a real RS-485 bus (issue 40, SPEC §13): the real image in the kit's `Bus`,
//! which puts a byte on the line only if D10 (the driver enable) was high over its whole
//! wire time, start bit to stop bit, and flags a byte during which D10 changed. A master
//! asks while the RUN screen is being drawn (after autostart, after RUN and EX0 typed on
//! the line, and while it is drawn again whole after the master went quiet): each reply
//! starts within 5 ms of the request, and the only bytes on the wire are the reply's.
//!
//! Needs `out/m328-nano-utile.elf` (`cargo fw`).

mod support;

use support::chip::CYCLES_PER_MS;
use utile_core::engine::Program;
use utile_core::store;
use utile_kit::listing;
use utile_kit::modbus;
use utile_kit::setup::firmware_elf;
use utile_kit::sim::SimBoard;
use utile_kit::simavr::{frame_cycles, Bus, Chip, RigPin};

/// One character at 19200 8N1, in CPU cycles.
fn char_cycles() -> u64 {
    frame_cycles(19_200)
}

/// One chip with `prog` stored (slave address 1) on a bus that watches D10; `d8`: the
/// autostart jumper fitted.
fn bus_of_one(prog: &Program, d8: bool) -> Bus {
    let mut b = SimBoard::new();
    store::store(prog, &mut b).expect("STORE");
    utile_kit::setup::yield_to_wall_clock_tests();
    let mut c = Chip::load(&firmware_elf()).unwrap_or_else(|e| panic!("{e}"));
    c.set_eeprom(0, &b.eeprom);
    c.hold_low(RigPin::D8, d8);
    Bus::new(vec![c], 19_200).with_driver_enable()
}

/// What one request brought: the reply's first start bit after the request's last stop bit
/// (ms), every byte on the line, the bytes that were half on it.
struct Answer {
    latency_ms: f64,
    line: Vec<u8>,
    half_on: usize,
}

/// FC03 of holding registers 0..3 to slave 1 after 4 characters of silence; the line for
/// the next 80 ms.
fn ask(bus: &mut Bus) -> Answer {
    let half_before = bus.half_on().len();
    bus.take_master();
    let request = modbus::frame(1, &[0x03, 0, 0, 0, 4]);
    let end = bus.cycle() + (4 + request.len() as u64) * char_cycles();
    bus.send_after(4 * char_cycles(), &request);
    assert!(
        bus.run_for(80 * CYCLES_PER_MS).is_none(),
        "the chip stopped"
    );
    let got = bus.take_master();
    let first_start = got.first().map_or(u64::MAX, |b| b.cycle - char_cycles());
    Answer {
        latency_ms: first_start.saturating_sub(end) as f64 / CYCLES_PER_MS as f64,
        line: got.iter().map(|b| b.byte).collect(),
        half_on: bus.half_on().len() - half_before,
    }
}

/// `a` against SPEC §13 (the reply alone on the line, whole, within 5 ms); what is wrong
/// goes to `wrong`. Returns the reply's start.
fn check(a: &Answer, when: &str, wrong: &mut Vec<String>) -> f64 {
    let reply_ok = modbus::reply_pdu(1, &a.line).is_ok_and(|pdu| pdu.len() == 2 + 8);
    if !reply_ok || a.half_on != 0 || a.latency_ms > 5.0 {
        wrong.push(format!(
            "{when}: reply start {:.2} ms, {} bytes half on the line, the line {:02X?}",
            a.latency_ms, a.half_on, a.line
        ));
    }
    a.latency_ms
}

/// Run the bus `ms` milliseconds.
fn run_ms(bus: &mut Bus, ms: u64) {
    assert!(
        bus.run_for(ms * CYCLES_PER_MS).is_none(),
        "the chip stopped"
    );
}

/// The program of these tests: the remote start of SPEC §13's examples.
fn remote_start() -> Program {
    listing::commands(&["U0.", ".Y0", "KEY", "END"])
}

#[test]
fn requests_while_the_autostart_draws_the_run_screen_get_their_reply_alone_within_5_ms() {
    let mut wrong = Vec::new();
    let mut worst = 0f64;
    for ms in [9, 25, 70, 160, 300, 600] {
        let mut bus = bus_of_one(&remote_start(), true);
        run_ms(&mut bus, ms);
        let a = ask(&mut bus);
        worst = worst.max(check(&a, &format!("{ms} ms after the reset"), &mut wrong));
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    eprintln!("autostart: the slowest reply started {worst:.2} ms after its request");
}

#[test]
fn requests_right_after_run_and_ex0_typed_on_the_line_get_their_reply_alone_within_5_ms() {
    let mut wrong = Vec::new();
    let mut worst = 0f64;
    for command in ["RUN", "EX0"] {
        for ms in [4, 6, 10, 30, 100] {
            let mut bus = bus_of_one(&remote_start(), false);
            // The editor's power-up screen (about 0.6 s of line), then LOAD and the command
            // typed on the line, as a terminal on the same wire would.
            run_ms(&mut bus, 1_000);
            bus.send(b"LOAD\r");
            run_ms(&mut bus, 300);
            bus.send(format!("{command}\r").as_bytes());
            // The CR's stop bit, then `ms`.
            run_ms(&mut bus, 1 + ms);
            let a = ask(&mut bus);
            worst = worst.max(check(&a, &format!("{ms} ms after {command}"), &mut wrong));
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    eprintln!("RUN, EX0: the slowest reply started {worst:.2} ms after its request");
}

#[test]
fn after_the_master_goes_quiet_the_run_screen_is_drawn_again_and_requests_during_it_still_win() {
    // PPA at every scan: the RUN screen shows the port byte every 100 ms.
    let prog = listing::commands(&["PPA", "KEY", "END"]);
    let mut bus = bus_of_one(&prog, true);
    run_ms(&mut bus, 50);
    let mut wrong = Vec::new();
    check(&ask(&mut bus), "during the autostart's screen", &mut wrong);
    let mut worst = 0f64;
    for ms in [5, 40, 150, 400] {
        // The master is quiet for 3 s: the screen is drawn again whole (simavr_modbus checks
        // it on the terminal); the master asks `ms` into it.
        run_ms(&mut bus, 3_000 + ms);
        let a = ask(&mut bus);
        worst = worst.max(check(&a, &format!("{ms} ms into the redraw"), &mut wrong));
    }
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
    eprintln!("redraw: the slowest reply started {worst:.2} ms after its request");
}
