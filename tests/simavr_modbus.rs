//! The Modbus RTU slave of SPEC §13 and §17 on the REAL firmware image in simavr, with the
//! line timed as a wire at 19200 8N1 in both directions (`RxPacing::Line`): a master in this
//! test sends requests with the silences it chooses and reads the replies with the cycle of
//! each stop bit; D10, the RS-485 driver enable, is sampled all along (`support/master.rs`).
//!
//! Needs `out/m328-nano-utile.elf` (`cargo fw`).

mod support;

use support::chip::CYCLES_PER_MS;
use support::master::{bytes, char_cycles, pdu, read_input, stored, Line, ADDRESS};
use support::scenario::listing as listing_of;
use utile_core::engine::Program;
use utile_core::modbus::plc::{STATUS_RUNNING, STATUS_STORED};
use utile_core::modbus::snapshot::{self, Snapshot, PROGRAM, SNAPSHOT, SNAPSHOT_LEN};
use utile_kit::listing;
use utile_kit::modbus;
use utile_kit::rng::Rng;
use utile_kit::simavr::{CpuState, RxPacing};

fn remote_start() -> Program {
    listing::commands(&["U0.", ".Y0", "KEY", "END"])
}

#[test]
fn a_master_reads_and_writes_and_the_program_follows() {
    let mut line = Line::new(&remote_start());
    assert_eq!(line.nano.outputs() & 1, 0);
    let (_, reply) = line.transact(&[0x05, 0, 8, 0xFF, 0]);
    assert_eq!(
        pdu(&reply),
        vec![0x05, 0, 8, 0xFF, 0],
        "write single coil U0 echoed"
    );
    line.run(2 * CYCLES_PER_MS);
    assert_eq!(line.nano.outputs() & 1, 1, "the program saw U0 and set Y0");
    let (_, reply) = line.transact(&[0x01, 0, 0, 0, 16]);
    assert_eq!(pdu(&reply), vec![0x01, 2, 0x01, 0x01], "coils: Y0 and U0");
    let (_, reply) = line.transact(&[0x04, 0, 0, 0, 8]);
    let r = pdu(&reply);
    assert_eq!(&r[..2], &[0x04, 16]);
    let status = u16::from_be_bytes([r[2], r[3]]);
    assert_eq!(status & 0b101, 0b101, "running, a stored image");
    let scans = u32::from_be_bytes([r[10], r[11], r[12], r[13]]);
    assert!(scans > 1000, "scans since RUN: {scans}");
    let (_, reply) = line.transact(&[0x03, 0, 26, 0, 1]);
    assert_eq!(pdu(&reply), vec![0x83, 2], "exception 02 past the map");
}

#[test]
fn replies_start_soon_and_d10_frames_each_reply_exactly() {
    let mut line = Line::new(&remote_start());
    for _ in 0..5 {
        let (end, reply) = line.transact(&[0x03, 0, 0, 0, 16]);
        assert_eq!(reply.len(), 5 + 32);
        let c = char_cycles();
        let first_start = reply[0].1 - c;
        let last_stop = reply.last().unwrap().1;
        let latency_ms = (first_start - end) as f64 / CYCLES_PER_MS as f64;
        assert!(
            latency_ms >= 1.75,
            "the slave waits out 3.5 characters: {latency_ms:.2} ms"
        );
        assert!(
            latency_ms <= 5.0,
            "SPEC §13: a reply within 5 ms ({latency_ms:.2} ms)"
        );
        // Back to back: no gap of 1.5 characters inside the reply.
        for w in reply.windows(2) {
            assert!(w[1].1 - w[0].1 < c * 3 / 2, "a gap inside the reply");
        }
        // D10 rose before the first start bit and fell after the last stop bit, within a
        // character, and was low before and after.
        let rises: Vec<u64> = line.de.iter().filter(|d| d.1).map(|d| d.0).collect();
        let falls: Vec<u64> = line.de.iter().filter(|d| !d.1).map(|d| d.0).collect();
        // D10 is sampled every `step` cycles: a change is seen up to a step late.
        let step = CYCLES_PER_MS / 32;
        let rise = *rises
            .iter()
            .rev()
            .find(|&&t| t <= first_start + step)
            .expect("D10 rose");
        let fall = *falls.iter().find(|&&t| t >= rise).expect("D10 fell");
        assert!(
            first_start.saturating_sub(rise) < 2 * CYCLES_PER_MS,
            "D10 up just before"
        );
        assert!(
            fall + step >= last_stop,
            "D10 held until the last stop bit has left"
        );
        assert!(
            fall.saturating_sub(last_stop) < c,
            "and dropped right after it"
        );
        line.de.clear();
        line.de.push((line.nano.chip.cycle(), line.de_level()));
        assert!(!line.de_level());
    }
}

#[test]
fn broken_frames_get_no_answer_and_are_counted() {
    let mut line = Line::new(&remote_start());
    // Bad CRC.
    let bad = modbus::with_wrong_crc(&[ADDRESS, 0x03, 0, 0, 0, 1], 0x0101);
    line.send(4 * char_cycles(), &bad);
    assert!(line.collect().is_empty(), "no answer to a bad CRC");
    // Another address.
    let other = modbus::frame(9, &[0x03, 0, 0, 0, 1]);
    line.send(4 * char_cycles(), &other);
    assert!(line.collect().is_empty(), "no answer for another slave");
    // A gap of 2.5 characters inside a frame.
    let good = modbus::frame(ADDRESS, &[0x03, 0, 0, 0, 1]);
    line.send(4 * char_cycles(), &good[..3]);
    line.send(5 * char_cycles() / 2, &good[3..]);
    assert!(line.collect().is_empty(), "no answer to a frame with a gap");
    let (_, reply) = line.transact(&[0x04, 0, 7, 0, 1]);
    assert_eq!(pdu(&reply), vec![0x04, 2, 0, 3], "three frames dropped");
}

/// Modbus RTU's t1.5 (issue 32): a silence of up to 1.5 characters between two characters of
/// a frame, from one stop bit's end to the next start bit, leaves the frame whole; a longer
/// one breaks it, and the broken frame is counted (input register 7). With 3 characters
/// between bytes a slave that learns of a character only at its stop bit has timed t3.5 from
/// the last one before the next shows: each byte is a frame of its own, each counted.
#[test]
fn pauses_up_to_one_and_a_half_characters_inside_a_frame_are_allowed() {
    let mut line = Line::new(&remote_start());
    let c = char_cycles();
    // The request reads the drop count, so each answer also says how many were dropped.
    let read = [0x04, 0, 7, 0, 1];
    let request = modbus::frame(ADDRESS, &read);
    let mut dropped = 0u16;
    let mut seen = Vec::new();
    let mut wrong = Vec::new();
    // (pause in tenths of a character, answered, frames dropped at least and at most)
    for (tenths, answered, least, most) in [
        (5, true, 0, 0),
        (10, true, 0, 0),
        (14, true, 0, 0),
        (20, false, 1, 1),
        (30, false, 1, request.len() as u16),
    ] {
        line.nano.chip.take_output_timed();
        line.send_paused(c * tenths / 10, &request);
        let reply = bytes(&line.collect());
        let pause = tenths as f64 / 10.0;
        seen.push(format!(
            "{pause}: {}",
            if reply.is_empty() {
                "dropped"
            } else {
                "answered"
            }
        ));
        let (_, count) = line.transact(&read);
        let now = modbus::registers(&pdu(&count))[0];
        let more = now - dropped;
        dropped = now;
        if answered != !reply.is_empty() || !(least..=most).contains(&more) {
            wrong.push(format!(
                "pauses of {pause} characters: reply {reply:02X?}, {more} frames dropped"
            ));
        }
    }
    assert!(
        wrong.is_empty(),
        "{} ({})",
        wrong.join("; "),
        seen.join(", ")
    );
}

#[test]
fn a_lone_slash_breaks_key_and_a_frame_with_0x2f_does_not() {
    let mut line = Line::new(&remote_start());
    // Write single register 0x2F (exception 02) and a coil write carrying 0x2F bytes.
    let (_, reply) = line.transact(&[0x06, 0, 0x2F, 0, 0x2F]);
    assert_eq!(pdu(&reply), vec![0x86, 2]);
    line.run(50 * CYCLES_PER_MS);
    let text = String::from_utf8_lossy(&line.nano.chip.take_output()).into_owned();
    assert!(!text.contains("Strike any key"), "still running");
    line.send(4 * char_cycles(), b"/");
    line.run(100 * CYCLES_PER_MS);
    assert!(
        String::from_utf8_lossy(&line.nano.chip.take_output()).contains("Strike any key"),
        "the break key stopped the program"
    );
}

/// `n` random bytes, none a `/`.
fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut rng = Rng::new(seed);
    let mut bytes = Vec::with_capacity(n);
    while bytes.len() < n {
        let b = rng.byte();
        if b != b'/' {
            bytes.push(b);
        }
    }
    bytes
}

#[test]
fn a_lone_slash_breaks_key_after_line_noise_on_the_wire() {
    // SPEC §12, §13 (issue 24): noise changes nothing, and a lone `/` after a silence
    // breaks KEY, however much noise came first.
    for (n, seed) in [(8, 1), (64, 2), (500, 3)] {
        let mut line = Line::new(&listing::commands(&["PA.", ".PY", "KEY", "END"]));
        line.send(0, &noise(n, seed));
        line.send(20 * CYCLES_PER_MS, b"/");
        let bytes_ms = n as u64 * char_cycles() / CYCLES_PER_MS;
        line.run((bytes_ms + 100) * CYCLES_PER_MS);
        let text = String::from_utf8_lossy(&line.nano.chip.take_output()).into_owned();
        assert!(
            text.contains("Strike any key"),
            "{n} noise bytes, 20 ms, `/`: {text:?}"
        );
    }
}

#[test]
fn a_lone_slash_typed_after_line_noise_breaks_key_in_the_virtual_nano_too() {
    // The virtual Nano's terminal (`RxPacing::AfterRead`) once fed the line at 11 bits a
    // byte: a writer at the true 19200 baud ran ahead of it, and after 500 bytes its 20 ms
    // of silence was gone: the `/` joined the noise's frame and KEY never saw it alone.
    let mut nano = stored(&listing::commands(&["PA.", ".PY", "KEY", "END"]), false);
    nano.chip.set_rx_pacing(RxPacing::AfterRead);
    assert!(nano.wait_for("User File", 2_000));
    // Started from the terminal, as the issue's user did.
    for line in ["LOAD", "EX0"] {
        nano.enter(line, 500);
    }
    assert!(nano.wait_for("Running", 1_000));
    nano.run_ms(500);
    nano.take_output();
    // A writer at the line rate: one byte every character time, whatever the chip does.
    for byte in noise(500, 4) {
        nano.chip.send(&[byte]);
        nano.run_cycles(char_cycles());
    }
    nano.run_ms(20);
    nano.type_bytes(b"/");
    assert!(
        nano.wait_for("Strike any key", 300),
        "500 noise bytes, 20 ms, `/`: {:?}",
        String::from_utf8_lossy(&nano.take_output())
    );
}

#[test]
fn the_terminal_is_quiet_while_a_master_is_active_and_redrawn_whole_three_seconds_after() {
    // PPA every scan: RUN mode shows the port byte every 100 ms.
    let mut line = Line::new(&listing::commands(&["PPA", "KEY", "END"]));
    line.run(300 * CYCLES_PER_MS);
    assert!(
        !line.nano.chip.take_output().is_empty(),
        "the RUN screen shows PPA"
    );
    line.transact(&[0x08, 0, 0, 0x12, 0x34]);
    // Within the next 2.5 s: nothing but replies.
    for _ in 0..5 {
        let (_, reply) = line.transact(&[0x08, 0, 0, 0xAB, 0xCD]);
        assert_eq!(
            pdu(&reply),
            vec![0x08, 0, 0, 0xAB, 0xCD],
            "only the reply is sent"
        );
        line.run(400 * CYCLES_PER_MS);
        assert!(
            line.nano.chip.take_output_timed().is_empty(),
            "the terminal is quiet"
        );
    }
    // After 3 s the RUN screen is drawn again whole (SPEC §13: a reply may have dropped
    // terminal bytes), title and status line included, and the displays go on.
    // (The last request was 0.4 s ago.)
    line.run(2_500 * CYCLES_PER_MS);
    assert!(line.nano.chip.take_output().is_empty(), "quiet for 3 s");
    line.run(1_500 * CYCLES_PER_MS);
    let text = String::from_utf8_lossy(&line.nano.chip.take_output()).into_owned();
    for part in ["u T I L E", "Running User File Program"] {
        assert!(text.contains(part), "redrawn whole after 3 s: {text:?}");
    }
    line.run(300 * CYCLES_PER_MS);
    assert!(
        !line.nano.chip.take_output().is_empty(),
        "the displays resumed"
    );
}

#[test]
fn a_long_write_then_reads_are_each_answered() {
    let mut line = Line::new(&remote_start());
    let (_, r) = line.transact(&[0x10, 0, 14, 0, 4, 8, 0, 9, 0, 10, 0x12, 0x34, 0x01, 0x00]);
    assert_eq!(pdu(&r), vec![0x10, 0, 14, 0, 4]);
    let (_, r) = line.transact(&[0x04, 0, 32, 0, 16]);
    assert_eq!(pdu(&r).len(), 2 + 32, "time left of T0..TF");
    let (_, r) = line.transact(&[0x03, 0, 16, 0, 2]);
    assert_eq!(
        pdu(&r),
        vec![0x03, 4, 0x12, 0x34, 0x01, 0x00],
        "C0, C1 as written"
    );
}

#[test]
fn a_slow_program_still_gets_every_reply_whole_and_without_gaps() {
    // Every opcode once: about 140 µs a scan, so the slave is visited every 2.2 ms.
    use utile_core::opcodes::{is_valid, END, NOP};
    let mut p = Program::blank();
    p.uf = [NOP; 256];
    let ops: Vec<u8> = (0..=0xFEu8)
        .filter(|&op| op != END && is_valid(op))
        .collect();
    for (l, op) in p.uf.iter_mut().zip(&ops) {
        *l = *op;
    }
    p.uf[ops.len()] = END;
    p.presets = [10; 16];
    let mut line = Line::new(&p);
    let requests: [(&[u8], usize); 6] = [
        (&[0x03, 0, 0, 0, 26], 2 + 52),
        (&[0x06, 0, 14, 0, 9], 5),
        (&[0x04, 0, 32, 0, 16], 2 + 32),
        (&[0x10, 0, 16, 0, 2, 4, 0x12, 0x34, 0, 7], 5),
        (&[0x02, 0, 8, 0, 42], 2 + 6),
        (&[0x11], 2 + 2 + 11),
    ];
    for (req, len) in requests {
        let (_, reply) = line.transact(req);
        assert_eq!(pdu(&reply).len(), len, "reply to {req:02X?}");
        for w in reply.windows(2) {
            assert!(
                w[1].1 - w[0].1 < char_cycles() * 3 / 2,
                "a gap inside the reply to {req:02X?}"
            );
        }
    }
}

#[test]
fn store_keeps_presets_and_set_points_written_over_modbus() {
    let mut line = Line::new(&remote_start());
    // Write multiple registers 15..25: TF = 42, C0 = 0x1234, C1..C7 = 0, S6 = 500, S7 = 0.
    let mut req = vec![0x10, 0, 15, 0, 11, 22];
    let values: [u16; 11] = [42, 0x1234, 0, 0, 0, 0, 0, 0, 0, 500, 0];
    for v in values {
        req.extend_from_slice(&v.to_be_bytes());
    }
    let (_, r) = line.transact(&req);
    assert_eq!(pdu(&r), vec![0x10, 0, 15, 0, 11], "TF, C0..C7, S6 written");
    // The master goes quiet; the user stops the program at the terminal and STOREs.
    line.run(3_100 * CYCLES_PER_MS);
    line.nano.chip.take_output();
    line.send(4 * char_cycles(), b"/");
    line.run(200 * CYCLES_PER_MS);
    assert!(String::from_utf8_lossy(&line.nano.chip.take_output()).contains("Strike any key"));
    line.send(0, b" ");
    line.run(300 * CYCLES_PER_MS);
    for &c in b"store\r" {
        line.send(0, &[c]);
        line.run(5 * CYCLES_PER_MS);
    }
    line.run(2_000 * CYCLES_PER_MS);
    let ee = line.nano.eeprom();
    let stored: Vec<Program> = [&ee[2..300], &ee[0x202..0x202 + 298]]
        .into_iter()
        .filter_map(|img| utile_core::image::decode(img).ok())
        .collect();
    assert!(
        stored.iter().any(|p| p.presets[15] == 42
            && p.counter_presets[0] == 0x1234
            && p.set_points == [500, 0]),
        "a stored image holds the values written over Modbus"
    );
}

#[test]
fn the_snapshot_and_the_program_of_a_listing_are_read_whole_and_its_fingerprint_agrees() {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/tank-fill.utl"),
    )
    .expect("the tank example");
    let prog = listing::parse("tank-fill", &text).expect("the tank listing");
    let mut line = Line::new(&prog);
    // The level at 1.0 V (204 counts): under the low mark, the pump and the alarm are on.
    line.nano.chip.set_analog_mv(6, 1000);
    line.nano.chip.set_analog_mv(7, 1000);
    line.run(200 * CYCLES_PER_MS);
    let regs = read_input(&mut line, SNAPSHOT, SNAPSHOT_LEN);
    let s = Snapshot::from_registers(&regs.clone().try_into().expect("40 registers"));
    assert_eq!(
        s.fingerprint,
        snapshot::fingerprint(&prog.uf),
        "the running program is the listing's"
    );
    assert_eq!(
        s.status & (STATUS_RUNNING | STATUS_STORED),
        STATUS_RUNNING | STATUS_STORED
    );
    assert_eq!(s.inputs, 0x3F, "A0..A5 open");
    assert_eq!(
        (s.thresholds, s.outputs, s.q),
        (0, 0b11, 1),
        "pump, alarm, Q0"
    );
    assert!(
        s.readings.iter().all(|r| (190..=220).contains(r)),
        "{:?}",
        s.readings
    );
    assert!(s.scans > 1000, "scans since RUN: {}", s.scans);
    assert!(
        s.scan_us[0] > 0 && s.scan_us[0] <= s.scan_us[2],
        "{:?}",
        s.scan_us
    );
    // The same figures as §13's registers (read a little later: the scan count grew).
    let ir = read_input(&mut line, 0, 8);
    assert_eq!(ir[0], s.status);
    assert!(u32::from(ir[4]) << 16 | u32::from(ir[5]) > s.scans);
    // The program window: the listing's 256 lines, two per register.
    let mut words = read_input(&mut line, PROGRAM, 125);
    words.extend(read_input(&mut line, PROGRAM + 125, 3));
    let uf = snapshot::program_from_registers(&words.try_into().expect("128 registers"));
    assert_eq!(uf, prog.uf);
    // Any part of a read outside the map: exception 02.
    for (start, qty) in [
        (SNAPSHOT - 1, 2),
        (SNAPSHOT + SNAPSHOT_LEN - 1, 2),
        (PROGRAM + 127, 2),
    ] {
        let [s0, s1] = start.to_be_bytes();
        let (_, reply) = line.transact(&[0x04, s0, s1, 0, qty as u8]);
        assert_eq!(pdu(&reply), vec![0x84, 2], "{start} x {qty}");
    }
}

#[test]
fn a_reply_streamed_over_many_scans_shows_the_bits_of_one_scan() {
    // Y0..Y7 count the scans; U and V copy them; every Q and TQ follows Y0.
    let mut line = Line::new(&listing_of("scan_counter"));
    for (k, qty) in [8u16, SNAPSHOT_LEN, 8, SNAPSHOT_LEN, 8]
        .into_iter()
        .enumerate()
    {
        let (_, reply) = line.transact(&[0x04, 0, SNAPSHOT as u8, 0, qty as u8]);
        let first = reply[0].1;
        let regs = modbus::registers(&pdu(&reply));
        let scans = u32::from(regs[6]) << 16 | u32::from(regs[7]);
        // The reply took many scans to go out (about 0.5 ms a byte).
        let spent = (reply.last().unwrap().1 - first) / CYCLES_PER_MS;
        assert!(spent >= 10, "request {k}: the reply took {spent} ms");
        let y = (scans & 0xFF) as u16;
        let all = if y & 1 == 1 { 0xFFFF } else { 0 };
        assert_eq!(regs[1] >> 8, y, "request {k}: Y0..Y7 at scan {scans}");
        assert_eq!(
            regs[2..5],
            [y << 8 | y, all, all],
            "request {k}: U/V, Q and TQ of scan {scans}"
        );
    }
}

#[test]
fn the_longest_programs_still_answer_within_the_spec_and_without_gaps() {
    // 256 lines scanned (no END), and 255 of the slowest lines there are (each restarts
    // TF: a 32-bit deadline), about 0.5 ms a scan.
    let no_end = listing::commands(&["Y0.", "!", ".Y0"]);
    let slowest = listing_of("slowest_scan");
    let mut write = vec![0x10, 0, 0, 0, 16, 32];
    for _ in 0..16 {
        write.extend_from_slice(&[0, 10]);
    }
    let c = char_cycles();
    for (name, prog) in [("no END", no_end), ("127 x SET .TKF", slowest)] {
        let mut line = Line::new(&prog);
        for _ in 0..3 {
            for req in [&[0x03, 0, 0, 0, 16][..], &[0x04, 0, 64, 0, 40], &write] {
                let (end, reply) = line.transact(req);
                assert_eq!(pdu(&reply)[0], req[0], "{name}: reply to {req:02X?}");
                let latency_ms = (reply[0].1 - c - end) as f64 / CYCLES_PER_MS as f64;
                assert!(
                    latency_ms <= 5.0,
                    "{name}: SPEC §13, a reply within 5 ms ({latency_ms:.2} ms)"
                );
                for w in reply.windows(2) {
                    assert!(
                        w[1].1 - w[0].1 < c * 3 / 2,
                        "{name}: a gap inside the reply to {req:02X?}: {:?}",
                        reply
                            .iter()
                            .map(|r| (r.1 - reply[0].1) / 100)
                            .collect::<Vec<_>>()
                    );
                }
            }
        }
    }
}

/// `cli`: the first instruction of each critical section (`interrupt::free`).
const CLI: u16 = 0x94F8;
/// UCSR0A and UCSR0B's data-space addresses, and the bits the holds below look at.
const UCSR0A: usize = 0xC0;
const UCSR0B: usize = 0xC1;
const TXC0: u8 = 1 << 6;
const TXCIE0: u8 = 1 << 6;
const UDRIE0: u8 = 1 << 5;

impl Line {
    /// The transmitter has nothing left: the last byte's stop bit has gone, the ring is
    /// empty (data-register-empty off) and a transmit complete, if wanted, has been taken.
    fn tx_drained(&self) -> bool {
        let chip = &self.nano.chip;
        let b = chip.peek(UCSR0B);
        chip.cycle() >= chip.tx_free_at()
            && b & UDRIE0 == 0
            && !(b & TXCIE0 != 0 && chip.peek(UCSR0A) & TXC0 != 0)
    }

    /// Run `cycles` one instruction at a time. While D10 is up (a reply goes out), the main
    /// program's critical sections are counted (a `cli` with interrupts on). At the `k`-th
    /// it is held until the transmitter is on its last queued byte (the ring empty), as a
    /// slow scan holds it; then, on the instruction before its next critical section, until
    /// that byte has left: the line goes idle exactly there (the interleaving a slow visit
    /// makes, with the transmit complete in the last gap before a critical section).
    /// Returns how many critical sections there were.
    fn run_held(&mut self, cycles: u64, k: u32) -> u32 {
        let end = self.nano.chip.cycle() + cycles;
        let mut seen = 0;
        let mut armed = false;
        while self.nano.chip.cycle() < end {
            let chip = &self.nano.chip;
            let main = self.de_level() && chip.interrupts_on();
            if main && armed && chip.flash_word(chip.pc() + 2) == CLI {
                armed = false;
                self.hold_while(|l| !l.tx_drained());
            }
            let chip = &self.nano.chip;
            if main && chip.flash_word(chip.pc()) == CLI {
                seen += 1;
                if seen == k + 1 {
                    self.hold_while(|l| l.nano.chip.peek(UCSR0B) & UDRIE0 != 0);
                    armed = true;
                }
            }
            self.step_sampled();
        }
        seen
    }

    /// Hold the main program where it is while the interrupts run, as long as `wait` says.
    fn hold_while(&mut self, wait: impl Fn(&Line) -> bool) {
        let at = self.nano.chip.pc();
        while wait(self) {
            let chip = &mut self.nano.chip;
            let held = chip.interrupts_on() && chip.pc() == at;
            let state = if held { chip.step_held() } else { chip.step() };
            assert_eq!(state, CpuState::Running, "the chip stopped");
            self.sample_de();
        }
    }

    /// One instruction, D10 sampled after it.
    fn step_sampled(&mut self) {
        let state = self.nano.chip.step();
        assert_eq!(state, CpuState::Running, "the chip stopped");
        self.sample_de();
    }

    /// D10 now, recorded if it changed.
    fn sample_de(&mut self) {
        let level = self.de_level();
        if self.de.last().map(|&(_, l)| l) != Some(level) {
            self.de.push((self.nano.chip.cycle(), level));
        }
    }
}

/// Issue 32: a transmit complete between the main program's "not idle" mark and its push
/// of a reply byte made the line look idle with the byte still to go, and the reply's end
/// then dropped D10 (and transmit complete) before that byte had left. With the line going
/// idle in the last gap before each of its critical sections in turn (one per request,
/// `Line::run_held`), the main program must still give every reply whole, with D10 up until
/// its last stop bit.
#[test]
fn a_reply_keeps_d10_up_to_its_last_stop_bit_whatever_the_interleaving() {
    let mut line = Line::new(&remote_start());
    let c = char_cycles();
    let mut k = 0;
    loop {
        let req = [0x05, 0, 3, if k % 2 == 0 { 0xFF } else { 0 }, 0];
        line.nano.chip.take_output_timed();
        line.de.clear();
        line.de.push((line.nano.chip.cycle(), line.de_level()));
        line.send(4 * c, &modbus::frame(ADDRESS, &req));
        let seen = line.run_held(20 * CYCLES_PER_MS, k);
        let reply = line.nano.chip.take_output_timed();
        let got = bytes(&reply);
        assert_eq!(
            modbus::reply_pdu(ADDRESS, &got).ok(),
            Some(&req[..]),
            "held at critical section {k} of {seen}: the echo came as {got:02X?}"
        );
        let last_stop = reply.last().unwrap().1;
        let first_start = reply[0].1 - c;
        let rise = line.de.iter().find(|d| d.1).expect("D10 rose").0;
        let fall = line
            .de
            .iter()
            .find(|d| !d.1 && d.0 > rise)
            .expect("D10 fell")
            .0;
        assert!(rise <= first_start, "D10 up before the first start bit");
        // simavr's transmit complete and the harness's stop bits agree within a few
        // cycles; half a bit is the margin.
        assert!(
            fall + c / 20 >= last_stop,
            "held at critical section {k} of {seen}: D10 fell {} cycles before the last \
             stop bit had left",
            last_stop.saturating_sub(fall)
        );
        assert!(!line.de_level(), "D10 down after the reply");
        k += 1;
        if k >= seen {
            break;
        }
    }
    assert!(
        k > 10,
        "only {k} critical sections while the reply went out"
    );
}

/// Issue 32: a byte on the line while a reply goes out (noise, a master that gave up) is
/// ignored, and its silence must not end a frame: that took a new snapshot in the middle of
/// the reply and emptied the request an echo reply is still built from.
#[test]
fn a_stray_byte_during_a_reply_changes_nothing_in_it() {
    let mut line = Line::new(&listing_of("scan_counter"));
    let c = char_cycles();
    // Diagnostics echoes its request: 52 bytes of PDU, over many visits.
    let mut echo = vec![0x08, 0, 0];
    echo.extend((0..49u8).map(|i| i.wrapping_mul(37) ^ 0x5A));
    let snapshot_read = [0x04, 0, SNAPSHOT as u8, 0, SNAPSHOT_LEN as u8];
    for (k, req) in [&echo[..], &snapshot_read, &echo, &snapshot_read]
        .into_iter()
        .enumerate()
    {
        line.nano.chip.take_output_timed();
        let end = line.send(4 * c, &modbus::frame(ADDRESS, req));
        // 10 characters after the request: the reply (about 50 characters) is under way,
        // and the stray byte's 3.5-character silence ends in the middle of it.
        line.send(10 * c, &[0x55]);
        line.run(end.saturating_sub(line.nano.chip.cycle()));
        let reply = line.collect();
        let got = pdu(&reply);
        if req[0] == 0x08 {
            assert_eq!(got, req, "request {k}: the echo is the request");
            continue;
        }
        let regs = modbus::registers(&got);
        let scans = u32::from(regs[6]) << 16 | u32::from(regs[7]);
        let y = (scans & 0xFF) as u16;
        let all = if y & 1 == 1 { 0xFFFF } else { 0 };
        assert_eq!(regs[1] >> 8, y, "request {k}: Y0..Y7 of scan {scans}");
        assert_eq!(
            regs[2..5],
            [y << 8 | y, all, all],
            "request {k}: U/V, Q and TQ of scan {scans}"
        );
    }
    // The stray bytes were no frames: nothing dropped.
    let (_, reply) = line.transact(&[0x04, 0, 7, 0, 1]);
    assert_eq!(pdu(&reply), vec![0x04, 2, 0, 0], "no frame dropped");
}

/// Issue 40: a byte that came after a frame's closing silence but before the main loop had
/// judged the frame was glued onto it, so with a scan of 0.5 ms another slave's reply and a
/// request to this one 3.5 characters after it were both lost. Now a frame is closed in the
/// silence's interrupt: the foreign reply is counted there, and the request is answered,
/// whatever the phase of the scan when the silence ends.
#[test]
fn a_request_three_and_a_half_characters_after_another_slaves_reply_is_answered() {
    let mut line = Line::new(&listing_of("slowest_scan"));
    let c = char_cycles();
    let read = [0x04, 0, 7, 0, 1];
    // Another slave's reply to FC03 x 2 (address 9), then ours 3.5 characters after its
    // last stop bit, at 32 phases of the 0.5 ms scan.
    let foreign = modbus::frame(9, &[0x03, 4, 0x12, 0x34, 0x56, 0x78]);
    let (_, first) = line.transact(&read);
    let mut dropped = modbus::registers(&pdu(&first))[0];
    let mut wrong = Vec::new();
    for k in 0..32u64 {
        line.run(20 * CYCLES_PER_MS + k * CYCLES_PER_MS / 64);
        line.nano.chip.take_output_timed();
        line.send(4 * c, &foreign);
        let end = line.send(7 * c / 2, &modbus::frame(ADDRESS, &read));
        line.run(end.saturating_sub(line.nano.chip.cycle()));
        let reply = line.collect();
        match modbus::reply_pdu(ADDRESS, &bytes(&reply)) {
            Ok(p) if p.len() == 4 => {
                let now = u16::from_be_bytes([p[2], p[3]]);
                if now != dropped + 1 {
                    wrong.push(format!(
                        "phase {k}: {} frames counted, not 1",
                        now - dropped
                    ));
                }
                dropped = now;
            }
            _ => wrong.push(format!("phase {k}: no answer ({:02X?})", bytes(&reply))),
        }
    }
    assert!(wrong.is_empty(), "{}", wrong.join("; "));
}
