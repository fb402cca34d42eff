//! SPEC §18, hold and step over Modbus, on the REAL firmware image in simavr, its line timed
//! as a wire (`support/master.rs`): a hold stops the scan count and keeps every pin; a timer
//! that runs out while held shows TQ = 0 at the next step; n steps raise the scan count by
//! exactly n; the lease ends a hold 10 s (simulated) after the last frame and sets status
//! bit 5, and broadcasts do not renew it; `/` still stops a program with KEY while held, and
//! changes nothing for one without (a lone 0x2F of noise never un-freezes the plant);
//! exception 03 for bad values; a reset and EX0 start free.
//!
//! Most tests run tests/data/scan_counter.utl, whose Y0..Y7 count the scans: its pins and
//! its snapshot's Y show each scan that ran, and only those.
//!
//! Needs `out/m328-nano-utile.elf` (`cargo fw`).

mod support;

use support::chip::CYCLES_PER_MS;
use support::master::{char_cycles, pdu, read_input, Line};
use support::scenario::listing as listing_of;
use utile_core::modbus::hold::{STATUS_HELD, STATUS_LAPSED};
use utile_core::modbus::plc::{STATUS_RUNNING, STATUS_STORED};
use utile_core::modbus::snapshot::SNAPSHOT;
use utile_core::opcodes::{END, KEY};
use utile_kit::listing;
use utile_kit::modbus;

/// The scan counter, running (autostarted).
fn counter() -> Line {
    Line::new(&listing_of("scan_counter"))
}

/// What one snapshot read shows: status, Y0..Y7, TQ0..TQF, scans since RUN.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Picture {
    status: u16,
    y: u8,
    tq: u16,
    scans: u32,
}

fn picture(line: &mut Line) -> Picture {
    let r = read_input(line, SNAPSHOT, 8);
    Picture {
        status: r[0],
        y: (r[1] >> 8) as u8,
        tq: r[4],
        scans: u32::from(r[6]) << 16 | u32::from(r[7]),
    }
}

/// FC06 of holding register `addr`: the reply's PDU.
fn write(line: &mut Line, addr: u16, value: u16) -> Vec<u8> {
    let [a0, a1] = addr.to_be_bytes();
    let [v0, v1] = value.to_be_bytes();
    pdu(&line.transact(&[0x06, a0, a1, v0, v1]).1)
}

/// Holding registers 32 (held) and 33 (steps not yet run).
fn scan_control(line: &mut Line) -> [u16; 2] {
    let r = modbus::registers(&pdu(&line.transact(&[0x03, 0, 32, 0, 2]).1));
    [r[0], r[1]]
}

/// Hold, and the picture once the hold has settled.
fn hold(line: &mut Line) -> Picture {
    assert_eq!(write(line, 32, 1), vec![0x06, 0, 32, 0, 1]);
    picture(line)
}

#[test]
fn a_hold_stops_the_scan_count_and_keeps_every_pin() {
    let mut line = counter();
    let free = picture(&mut line);
    assert_eq!(
        free.status & (STATUS_HELD | STATUS_LAPSED),
        0,
        "RUN starts free"
    );
    assert_eq!(scan_control(&mut line), [0, 0]);
    let held = hold(&mut line);
    assert!(held.scans > free.scans);
    assert_eq!(held.status, STATUS_RUNNING | STATUS_STORED | STATUS_HELD);
    assert_eq!(u32::from(held.y), held.scans & 0xFF, "Y counts the scans");
    let pins = line.nano.outputs();
    assert_eq!(pins, held.y, "the pins show the held scan's Y");
    for _ in 0..20 {
        line.run(100 * CYCLES_PER_MS);
        assert_eq!(line.nano.outputs(), pins, "every pin stays while held");
    }
    assert_eq!(picture(&mut line), held, "2 s held: not one scan more");
    assert_eq!(scan_control(&mut line), [1, 0]);
    // Release: free from line 0, the count runs on from where it stood.
    assert_eq!(write(&mut line, 32, 0), vec![0x06, 0, 32, 0, 0]);
    let after = picture(&mut line);
    assert!(after.scans > held.scans + 100, "{after:?}");
    assert_eq!(u32::from(after.y), after.scans & 0xFF, "no scan cut short");
    assert_eq!(after.status & STATUS_HELD, 0);
}

#[test]
fn n_steps_raise_the_scan_count_by_exactly_n() {
    let mut line = counter();
    let mut before = hold(&mut line);
    for n in [1u16, 1, 2, 10, 255, 1000] {
        assert_eq!(
            write(&mut line, 33, n),
            vec![0x06, 0, 33, (n >> 8) as u8, n as u8]
        );
        // 1000 scans of 244 lines take about 0.2 s.
        line.run(400 * CYCLES_PER_MS);
        let now = picture(&mut line);
        assert_eq!(now.scans, before.scans + u32::from(n), "{n} steps");
        assert_eq!(
            u32::from(now.y),
            now.scans & 0xFF,
            "every step a whole scan"
        );
        assert_eq!(line.nano.outputs(), now.y, "the pins of the last step");
        assert_eq!(
            now.status & STATUS_HELD,
            STATUS_HELD,
            "held after the steps"
        );
        assert_eq!(scan_control(&mut line), [1, 0]);
        before = now;
    }
    // Steps asked for while free: n scans, then held.
    assert_eq!(write(&mut line, 32, 0), vec![0x06, 0, 32, 0, 0]);
    line.run(50 * CYCLES_PER_MS);
    write(&mut line, 33, 3);
    let a = picture(&mut line);
    line.run(300 * CYCLES_PER_MS);
    assert_eq!(picture(&mut line), a, "held after its 3 steps");
    // The steps not yet run read back: 1000 scans of 244 lines outlast one request.
    write(&mut line, 33, 1000);
    let [held, left] = scan_control(&mut line);
    assert_eq!(held, 1);
    assert!(left < 1000, "some steps ran before the read: {left}");
}

#[test]
fn a_timer_that_runs_out_while_held_shows_tq_0_at_the_next_step() {
    // U0 triggers T0 (0.3 s); Y1 is TQ0 as the scan saw it.
    let mut prog = listing::commands(&["U0.", ".TK0", "TQ0.", ".Y1", "END"]);
    prog.presets[0] = 3;
    let mut line = Line::new(&prog);
    for on in [0xFF, 0] {
        pdu(&line.transact(&[0x05, 0, 8, on, 0]).1);
    }
    let held = hold(&mut line);
    assert_eq!(held.tq & 1, 1, "T0 runs");
    assert_eq!(line.nano.outputs() & 2, 2, "Y1: TQ0");
    line.run(500 * CYCLES_PER_MS);
    assert_eq!(
        read_input(&mut line, 32, 1),
        vec![0],
        "T0's time ran out while held"
    );
    assert_eq!(line.nano.outputs() & 2, 2, "the pin waits for a scan");
    assert_eq!(write(&mut line, 33, 1), vec![0x06, 0, 33, 0, 1]);
    line.run(5 * CYCLES_PER_MS);
    let stepped = picture(&mut line);
    assert_eq!(stepped.scans, held.scans + 1);
    assert_eq!(stepped.tq & 1, 0, "TQ0 = 0 at the step");
    assert_eq!(line.nano.outputs() & 2, 0, "the program saw TQ0 = 0");
    let di = pdu(&line.transact(&[0x02, 0, 24, 0, 1]).1);
    assert_eq!(di, vec![0x02, 1, 0], "discrete input TQ0");
}

#[test]
fn the_lease_ends_a_hold_ten_seconds_after_the_last_frame_and_sets_bit_5() {
    let mut line = counter();
    let held = hold(&mut line);
    // The last frame was judged when the request's silence ended: before the reply, and
    // before the 10 ms of quiet `transact` waits for.
    let judged = line.nano.chip.cycle();
    let pins = line.nano.outputs();
    while line.nano.chip.cycle() < judged + 9_950 * CYCLES_PER_MS {
        // The chip alone (no D10 sampling): 10 s of simulated time.
        line.nano.chip.run_for(50 * CYCLES_PER_MS);
        assert_eq!(
            line.nano.outputs(),
            pins,
            "held 9.95 s after the last frame"
        );
    }
    // Free by 10.05 s: the pins count again.
    let mut freed = None;
    while line.nano.chip.cycle() < judged + 10_050 * CYCLES_PER_MS {
        line.nano.chip.run_for(CYCLES_PER_MS);
        if line.nano.outputs() != pins {
            freed = Some(line.nano.chip.cycle());
            break;
        }
    }
    assert!(freed.is_some(), "the hold ended by itself");
    let free = picture(&mut line);
    assert!(free.scans > held.scans);
    assert_eq!(free.status & (STATUS_HELD | STATUS_LAPSED), STATUS_LAPSED);
    assert_eq!(scan_control(&mut line), [0, 0]);
    // Bit 5 stays; a frame every 4 s keeps a new hold for 12 s.
    let again = hold(&mut line);
    assert_eq!(again.status & STATUS_LAPSED, STATUS_LAPSED);
    for _ in 0..3 {
        line.nano.chip.run_for(4_000 * CYCLES_PER_MS);
        assert_eq!(picture(&mut line).scans, again.scans, "the lease renewed");
    }
}

#[test]
fn a_lone_slash_stops_a_held_program_with_key_and_leaves_the_hold_of_one_without() {
    let mut line = Line::new(&listing::commands(&["U0.", ".Y0", "KEY", "END"]));
    hold(&mut line);
    line.run(50 * CYCLES_PER_MS);
    line.nano.chip.take_output();
    line.send(4 * char_cycles(), b"/");
    line.run(100 * CYCLES_PER_MS);
    assert!(
        String::from_utf8_lossy(&line.nano.chip.take_output()).contains("Strike any key"),
        "the break key stopped the held program"
    );
    // Programs without KEY (none at all; one only after END, which no scan reaches): a
    // lone `/` (or a noise byte 0x2F between two silences) changes nothing, the plant
    // stays frozen and the master still reads it held.
    let after_end = {
        let mut p = listing_of("scan_counter");
        let end = p.uf.iter().position(|&op| op == END).expect("END");
        p.uf[end + 1] = KEY;
        p
    };
    for (name, prog) in [
        ("no KEY", listing_of("scan_counter")),
        ("KEY after END", after_end),
    ] {
        let mut line = Line::new(&prog);
        let held = hold(&mut line);
        let pins = line.nano.outputs();
        for _ in 0..3 {
            line.send(4 * char_cycles(), b"/");
            line.run(100 * CYCLES_PER_MS);
        }
        assert_eq!(line.nano.outputs(), pins, "{name}: every pin stays");
        let now = picture(&mut line);
        assert_eq!(now, held, "{name}: still held, not one scan more");
        assert_eq!(
            scan_control(&mut line),
            [1, 0],
            "{name}: register 32 reads 1"
        );
    }
}

#[test]
fn broadcasts_do_not_renew_the_lease() {
    let mut line = counter();
    let held = hold(&mut line);
    let judged = line.nano.chip.cycle();
    let pins = line.nano.outputs();
    // A broadcast every 2 s (V7 off: the program copies V anew at each scan), and a request
    // to another slave: neither is a frame for this slave's own address.
    for to in [0, 0, 9, 0] {
        line.run(2_000 * CYCLES_PER_MS);
        line.send(4 * char_cycles(), &modbus::frame(to, &[0x05, 0, 23, 0, 0]));
    }
    // 10 s after the hold (the request that held it): free, bit 5 set.
    while line.nano.chip.cycle() < judged + 10_050 * CYCLES_PER_MS {
        line.nano.chip.run_for(10 * CYCLES_PER_MS);
    }
    assert_ne!(line.nano.outputs(), pins, "the hold ended by itself");
    let free = picture(&mut line);
    assert!(free.scans > held.scans, "{free:?}");
    assert_eq!(free.status & (STATUS_HELD | STATUS_LAPSED), STATUS_LAPSED);
}

#[test]
fn bad_values_are_exception_03_and_change_nothing() {
    let mut line = counter();
    for (addr, value) in [(32, 2), (32, 0xFFFF), (33, 0), (33, 1001), (33, 0xFFFF)] {
        assert_eq!(
            write(&mut line, addr, value),
            vec![0x86, 3],
            "register {addr} = {value}"
        );
    }
    // Both in one write, the second bad: neither written.
    let r = pdu(&line.transact(&[0x10, 0, 32, 0, 2, 4, 0, 1, 0, 0]).1);
    assert_eq!(r, vec![0x90, 3]);
    assert_eq!(scan_control(&mut line), [0, 0]);
    // Registers 26..31 and 34 lie outside the map.
    assert_eq!(pdu(&line.transact(&[0x03, 0, 31, 0, 2]).1), vec![0x83, 2]);
    assert_eq!(write(&mut line, 34, 1), vec![0x86, 2]);
    let a = picture(&mut line);
    line.run(20 * CYCLES_PER_MS);
    assert!(picture(&mut line).scans > a.scans, "still free");
}

#[test]
fn a_reset_and_ex0_start_free() {
    let mut line = counter();
    hold(&mut line);
    line.nano.reset_button();
    // The autostart again (D8), its RUN screen drawn.
    line.run(1_000 * CYCLES_PER_MS);
    line.nano.chip.take_output();
    let a = picture(&mut line);
    assert_eq!(a.status & (STATUS_HELD | STATUS_LAPSED), 0);
    assert_eq!(scan_control(&mut line), [0, 0]);
    line.run(20 * CYCLES_PER_MS);
    assert!(picture(&mut line).scans > a.scans, "a reset starts free");
    // Held, stopped with `/`, started again with EX0: free.
    let mut line = Line::new(&listing::commands(&["Y0.", "!", ".Y0", "KEY", "END"]));
    hold(&mut line);
    line.send(4 * char_cycles(), b"/");
    line.run(100 * CYCLES_PER_MS);
    assert!(line.nano.wait_for("Strike any key", 200));
    line.nano.type_bytes(b" ");
    line.nano.run_ms(300);
    line.nano.enter("EX0", 300);
    assert!(line.nano.wait_for("Running", 1_000));
    line.run(500 * CYCLES_PER_MS);
    line.nano.chip.take_output();
    let a = picture(&mut line);
    assert_eq!(a.status & STATUS_HELD, 0, "EX0 starts free");
    line.run(20 * CYCLES_PER_MS);
    assert!(picture(&mut line).scans > a.scans);
}
