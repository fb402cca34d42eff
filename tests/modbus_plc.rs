//! The slave of SPEC §13 on the engine (host): §13's map over a running program, writes that
//! the program sees at its next scan, range checks that change nothing, broadcasts, drops,
//! the break key, and the master's activity window; SPEC §17's snapshot (one scan's bits
//! however late a reply reads them) and program window; SPEC §18's hold and steps
//! (holding registers 32–33, status bits 4–5, the lease) with the RUN loop's decision.

use utile_core::engine::{Engine, Program};
use utile_core::modbus::hold::{Hold, Next, STATUS_HELD, STATUS_LAPSED};
use utile_core::modbus::plc::{PlcMap, Status, STATUS_RUNNING};
use utile_core::modbus::slave::{Event, Slave, ACTIVE_MS};
use utile_core::modbus::snapshot::{self, Snapshot, PROGRAM, SNAPSHOT, SNAPSHOT_LEN};
use utile_core::stats::ScanStats;
use utile_kit::listing;
use utile_kit::modbus;
use utile_kit::sim::SimBoard;

const ADDRESS: u8 = 7;

struct Rig {
    eng: Engine,
    b: SimBoard,
    slave: Slave,
    status: Status,
}

impl Rig {
    fn new(words: &[&str]) -> Self {
        Self::with(listing::commands(words))
    }

    /// The program starts, as RUN starts it: the status takes its fingerprint.
    fn with(prog: Program) -> Self {
        let mut eng = Engine::new(prog);
        let mut b = SimBoard::new();
        eng.clear_runtime(&mut b);
        let mut status = Status::new(STATUS_RUNNING, &ScanStats::new(), 0, 0);
        status.start(&eng.prog.uf);
        Rig {
            eng,
            b,
            slave: Slave::new(),
            status,
        }
    }

    fn scan(&mut self, ms: u32) {
        self.b.run_for(&mut self.eng, ms, 4);
    }

    /// Send `frame` (CRC appended unless `raw`), end it, and collect the reply.
    fn send(&mut self, bytes: &[u8], raw: bool) -> (Event, Vec<u8>) {
        let ev = self.judge(bytes, raw);
        let mut reply = Vec::new();
        while let Some(x) = self.next_byte() {
            reply.push(x);
        }
        (ev, reply)
    }

    /// Send `frame` (CRC appended unless `raw`) and judge it between two scans, as the
    /// firmware does: §17's registers of one scan are taken first.
    fn judge(&mut self, bytes: &[u8], raw: bool) -> Event {
        let frame = if raw {
            bytes.to_vec()
        } else {
            modbus::with_crc(bytes)
        };
        for &x in &frame {
            self.slave.push(x, false);
        }
        let now = self.b.ticker.now_ms();
        self.status.take_scan(&self.eng, &mut self.b);
        let mut map = PlcMap {
            eng: &mut self.eng,
            b: &mut self.b,
            status: &mut self.status,
        };
        self.slave.end(ADDRESS, &mut map, now)
    }

    /// The reply's next byte, read from the map now.
    fn next_byte(&mut self) -> Option<u8> {
        let mut map = PlcMap {
            eng: &mut self.eng,
            b: &mut self.b,
            status: &mut self.status,
        };
        self.slave.next_byte(&mut map)
    }

    /// A request to this slave; its reply's PDU after checking address and CRC.
    fn ask(&mut self, pdu: &[u8]) -> Vec<u8> {
        let mut req = vec![ADDRESS];
        req.extend_from_slice(pdu);
        let (ev, reply) = self.send(&req, false);
        assert_eq!(ev, Event::Reply);
        modbus::reply_pdu(ADDRESS, &reply)
            .unwrap_or_else(|e| panic!("{e}: {reply:02X?}"))
            .to_vec()
    }
}

#[test]
fn a_remote_start_on_u0_runs_the_program_and_the_coils_show_it() {
    let mut r = Rig::new(&["U0.", ".Y0", "U0.", "!", ".Y1", "END"]);
    r.scan(5);
    assert_eq!(r.ask(&[0x01, 0, 0, 0, 16]), vec![0x01, 2, 0b10, 0]);
    // Write single coil U0 (coil 8) on.
    assert_eq!(r.ask(&[0x05, 0, 8, 0xFF, 0]), vec![0x05, 0, 8, 0xFF, 0]);
    r.scan(2);
    assert!(
        r.b.output(0) && !r.b.output(1),
        "the program saw U0 at its next scan"
    );
    assert_eq!(r.ask(&[0x01, 0, 0, 0, 16]), vec![0x01, 2, 0b01, 1]);
    // Off again with write multiple coils (U0..U7 = 0).
    assert_eq!(r.ask(&[0x0F, 0, 8, 0, 8, 1, 0]), vec![0x0F, 0, 8, 0, 8]);
    r.scan(2);
    assert!(!r.b.output(0) && r.b.output(1));
}

#[test]
fn presets_and_set_points_are_holding_registers_with_their_ranges() {
    let mut r = Rig::new(&["A0.", "!", ".CU0", "CQ0.", ".Y0", "END"]);
    r.eng.prog.presets[3] = 42;
    r.eng.prog.counter_presets[0] = 300;
    r.eng.prog.set_points = [512, 0];
    let pdu = r.ask(&[0x03, 0, 0, 0, 26]);
    let regs = modbus::registers(&pdu);
    assert_eq!(regs.len(), 26);
    assert_eq!((regs[3], regs[16], regs[24], regs[25]), (42, 300, 512, 0));
    // Out of range: exception 03 and nothing changes.
    let before = r.eng.prog.clone();
    assert_eq!(
        r.ask(&[0x06, 0, 5, 1, 0]),
        vec![0x86, 3],
        "timer preset 256"
    );
    assert_eq!(r.ask(&[0x06, 0, 25, 4, 0]), vec![0x86, 3], "set-point 1024");
    assert_eq!(
        r.ask(&[0x10, 0, 24, 0, 2, 4, 0x01, 0, 0x04, 0]),
        vec![0x90, 3],
        "S6 fine, S7 1024: neither written"
    );
    assert_eq!(r.eng.prog, before);
    assert_eq!(r.ask(&[0x03, 0, 26, 0, 1]), vec![0x83, 2], "past the map");
    // In range: the counter preset takes effect for CQ at once.
    r.scan(2);
    for _ in 0..3 {
        r.b.press(0);
        r.scan(20);
        r.b.release(0);
        r.scan(20);
    }
    assert!(!r.b.output(0));
    assert_eq!(r.ask(&[0x06, 0, 16, 0, 3]), vec![0x06, 0, 16, 0, 3]);
    r.scan(2);
    assert!(r.b.output(0), "preset 3 reached");
    assert_eq!(
        modbus::registers(&r.ask(&[0x04, 0, 8, 0, 1])),
        vec![3],
        "count C0 as input register 8"
    );
    assert_eq!(
        r.ask(&[0x06, 0, 24, 0x03, 0xFF]),
        vec![0x06, 0, 24, 3, 0xFF]
    );
    assert_eq!(r.eng.prog.set_points[0], 1023);
}

#[test]
fn discrete_inputs_show_levels_flip_flops_timers_counters_and_thresholds() {
    let mut r = Rig::new(&["SET", ".S2", "SET", ".TK1", "H6.", ".Y0", "END"]);
    r.eng.prog.presets[1] = 20; // 2 s
    r.eng.prog.set_points = [100, 0];
    r.b.analog.set_points([100, 0]);
    r.b.set_analog(6, 700);
    r.b.press(4);
    r.scan(30);
    assert_eq!(
        r.ask(&[0x02, 0, 0, 0, 50]),
        vec![0x82, 2],
        "6 and 7 are not in the map"
    );
    let pdu = r.ask(&[0x02, 0, 0, 0, 6]);
    assert_eq!(pdu, vec![0x02, 1, 0b10_1111], "A0..A3, A5 open, A4 pressed");
    let pdu = r.ask(&[0x02, 0, 8, 0, 42]);
    let bits: Vec<bool> = (0..50)
        .map(|n| n >= 8 && pdu[2 + (n - 8) / 8] >> ((n - 8) % 8) & 1 == 1)
        .collect();
    assert!(bits[8 + 2], "Q2");
    assert!(bits[24 + 1], "TQ1 running");
    assert!(bits[48] && !bits[49], "H6 on, H7 disabled");
    let regs = modbus::registers(&r.ask(&[0x04, 0, 16, 0, 2]));
    assert_eq!(regs, vec![700, 0], "readings of A6, A7");
    let left = modbus::registers(&r.ask(&[0x04, 0, 33, 0, 1]))[0];
    assert_eq!(
        left, 20,
        "T1 retriggered every scan: 2.0 s left, in 0.1 s steps"
    );
    assert_eq!(
        r.ask(&[0x04, 0, 18, 0, 1]),
        vec![0x84, 2],
        "18..31 are not in the map"
    );
}

#[test]
fn broadcasts_are_done_silently_and_other_frames_are_dropped_and_counted() {
    let mut r = Rig::new(&["U1.", ".Y1", "END"]);
    let (ev, reply) = r.send(&[0, 0x05, 0, 9, 0xFF, 0], false);
    assert_eq!((ev, reply.len()), (Event::Broadcast, 0));
    r.scan(2);
    assert!(r.b.output(1), "the broadcast write was done");
    // A broadcast read does nothing and answers nothing.
    assert_eq!(
        r.send(&[0, 0x03, 0, 0, 0, 1], false),
        (Event::Broadcast, vec![])
    );
    // Another slave's request, a bad CRC, a short frame: no answer, counted.
    assert_eq!(
        r.send(&[9, 0x03, 0, 0, 0, 1], false),
        (Event::Dropped, vec![])
    );
    let bad = modbus::with_wrong_crc(&[ADDRESS, 0x03, 0, 0, 0, 1], 1);
    assert_eq!(r.send(&bad, true), (Event::Dropped, vec![]));
    assert_eq!(r.send(&[ADDRESS, 0x03], true), (Event::Dropped, vec![]));
    assert_eq!(r.slave.dropped(), 3);
    // A lone `/` is the break key; a frame containing 0x2F is not.
    assert_eq!(r.send(b"/", true), (Event::Slash, vec![]));
    let pdu = r.ask(&[0x06, 0, 0x2F, 0, 0x2F]);
    assert_eq!(pdu, vec![0x86, 2], "register 47 is not a holding register");
}

/// Issue 40: frames are closed at their silence (the board's timer interrupt), and carried
/// out later, between two scans. A frame for another slave is counted and forgotten when it
/// closes, so a request right behind it is a frame of its own; a frame this slave must
/// carry out keeps the line until it has been, and the bytes meanwhile are never glued on.
#[test]
fn a_frame_closed_at_its_silence_is_never_glued_to_the_next() {
    let mut r = Rig::new(&["U1.", ".Y1", "END"]);
    let push = |r: &mut Rig, frame: &[u8]| {
        for &x in frame {
            r.slave.push(x, false);
        }
    };
    // Another slave's reply, closed; our request before the main loop looked.
    push(&mut r, &modbus::frame(9, &[0x03, 2, 0x12, 0x34]));
    assert!(
        !r.slave.close(ADDRESS),
        "another slave's frame: nothing to carry out"
    );
    assert_eq!(r.slave.dropped(), 1, "counted when it closed");
    push(&mut r, &modbus::frame(ADDRESS, &[0x08, 0, 0, 0xAB, 0xCD]));
    assert!(r.slave.close(ADDRESS));
    let now = r.b.ticker.now_ms();
    let mut map = PlcMap {
        eng: &mut r.eng,
        b: &mut r.b,
        status: &mut r.status,
    };
    assert_eq!(r.slave.judge(&mut map, now), Event::Reply);
    let mut reply = Vec::new();
    while let Some(x) = r.next_byte() {
        reply.push(x);
    }
    assert_eq!(
        modbus::reply_pdu(ADDRESS, &reply).ok(),
        Some(&[0x08, 0, 0, 0xAB, 0xCD][..]),
        "the request answered whole"
    );
    // A broadcast waits to be carried out: a byte meanwhile joins no frame.
    push(&mut r, &modbus::frame(0, &[0x05, 0, 9, 0xFF, 0]));
    assert!(r.slave.close(ADDRESS));
    assert!(
        r.slave.line_busy(now),
        "the terminal waits for the closed frame"
    );
    push(&mut r, &[ADDRESS]);
    let mut map = PlcMap {
        eng: &mut r.eng,
        b: &mut r.b,
        status: &mut r.status,
    };
    assert_eq!(r.slave.judge(&mut map, now), Event::Broadcast);
    assert_eq!(r.slave.judge(&mut map, now), Event::None, "judged once");
    assert!(!r.slave.receiving(), "the byte meanwhile was no frame's");
    assert_eq!(r.slave.dropped(), 1);
}

#[test]
fn a_master_is_active_for_three_seconds_after_its_last_frame() {
    let mut r = Rig::new(&["END"]);
    assert!(!r.slave.master_active(0));
    r.scan(100);
    r.ask(&[0x08, 0, 0, 0x12, 0x34]);
    let t = r.b.ticker.now_ms();
    assert!(r.slave.master_active(t));
    assert!(r.slave.master_active(t + ACTIVE_MS - 1));
    assert!(!r.slave.master_active(t + ACTIVE_MS));
    // Frames to other slaves do not count as this slave's master.
    r.scan(4000);
    r.send(&[3, 0x03, 0, 0, 0, 1], false);
    assert!(!r.slave.master_active(r.b.ticker.now_ms()));
}

#[test]
fn report_server_id_names_utile_and_its_version() {
    let mut r = Rig::new(&["END"]);
    let pdu = r.ask(&[0x11]);
    assert_eq!(pdu[0], 0x11);
    assert_eq!(pdu[2], ADDRESS);
    assert_eq!(pdu[3], 0xFF, "running");
    let text = std::str::from_utf8(&pdu[4..]).unwrap();
    assert_eq!(text, concat!("uTile ", env!("CARGO_PKG_VERSION")));
    assert_eq!(usize::from(pdu[1]), pdu.len() - 2);
}

/// FC04 of `qty` input registers from `start`: the registers, or the exception's code.
fn read_input(r: &mut Rig, start: u16, qty: u16) -> Result<Vec<u16>, u8> {
    let [s0, s1] = start.to_be_bytes();
    let [q0, q1] = qty.to_be_bytes();
    let pdu = r.ask(&[0x04, s0, s1, q0, q1]);
    if pdu[0] == 0x84 {
        return Err(pdu[1]);
    }
    Ok(modbus::registers(&pdu))
}

#[test]
fn the_snapshot_shows_the_whole_picture_in_one_read() {
    let mut prog = listing::commands(&[
        "SET", ".S2", "SET", ".TK1", "U0.", ".Y0", "A0.", "!", ".CU0", "CQ0.", ".Y3", "H6.", ".Y1",
        "SET", ".V7", "END",
    ]);
    prog.presets[1] = 20; // 2 s
    prog.counter_presets[0] = 2;
    prog.set_points = [100, 0];
    let mut r = Rig::with(prog);
    r.b.analog.set_points([100, 0]);
    r.b.set_analog(6, 700);
    r.b.set_analog(7, 33);
    r.eng.pu = 0b1000_0001;
    for _ in 0..2 {
        r.b.press(0);
        r.scan(30);
        r.b.release(0);
        r.scan(30);
    }
    r.b.press(4);
    r.scan(30);
    r.status = Status::new(
        STATUS_RUNNING,
        &ScanStats {
            min: 80,
            max: 300,
            count: 0x0001_2345,
            run_ms: 1000,
        },
        4,
        5,
    );
    r.status.start(&r.eng.prog.uf);
    let regs = read_input(&mut r, SNAPSHOT, SNAPSHOT_LEN).expect("the snapshot");
    let s = Snapshot::from_registers(&regs.clone().try_into().unwrap());
    assert_eq!(s.status, STATUS_RUNNING);
    assert_eq!(s.inputs, 0b10_1111, "A0..A3, A5 open, A4 pressed");
    assert_eq!(s.thresholds, 0b01, "H6 on, H7 disabled");
    assert_eq!(s.outputs, 0b1011, "Y0 (U0), Y1 (H6), Y3 (CQ0)");
    assert_eq!((s.u, s.v), (0b1000_0001, 0b1000_0000));
    assert_eq!(s.q, 1 << 2);
    assert_eq!(s.tq, 1 << 1);
    assert_eq!(s.cq, 1);
    assert_eq!(s.scans, 0x0001_2345);
    assert_eq!(s.counts[0], 2);
    assert_eq!(s.readings, [700, 33]);
    assert_eq!(s.time_left[1], 20, "T1 retriggered every scan: 2.0 s");
    // Min and max halved (Timer1 ticks), the mean 1000 ms over 74,565 scans.
    assert_eq!(s.scan_us, [40, 13, 150]);
    assert_eq!((s.overruns, s.dropped), (4, 5));
    assert_eq!(s.fingerprint, snapshot::fingerprint(&r.eng.prog.uf));
    // Every register but the fingerprint repeats its §13 twin.
    let ir = |r: &mut Rig, a, n| read_input(r, a, n).unwrap();
    assert_eq!(regs[0], ir(&mut r, 0, 1)[0]);
    assert_eq!(regs[6..8], ir(&mut r, 4, 2)[..]);
    assert_eq!(regs[8..18], ir(&mut r, 8, 10)[..]);
    assert_eq!(regs[18..34], ir(&mut r, 32, 16)[..]);
    assert_eq!(regs[34..37], ir(&mut r, 1, 3)[..]);
    assert_eq!(regs[37..39], ir(&mut r, 6, 2)[..]);
}

#[test]
fn the_program_window_holds_every_line_two_per_register() {
    let mut prog = Program::blank();
    for (i, line) in prog.uf.iter_mut().enumerate() {
        *line = (i as u8).wrapping_mul(37);
    }
    let mut r = Rig::with(prog.clone());
    let mut regs = read_input(&mut r, PROGRAM, 125).unwrap();
    regs.extend(read_input(&mut r, PROGRAM + 125, 3).unwrap());
    let uf = snapshot::program_from_registers(&regs.try_into().unwrap());
    assert_eq!(uf, prog.uf);
    assert_eq!(
        read_input(&mut r, PROGRAM, 1).unwrap(),
        vec![u16::from_be_bytes([prog.uf[0], prog.uf[1]])],
        "line 000 in the high byte"
    );
    // Holding registers still hold the presets, not the program.
    assert_eq!(r.ask(&[0x03, 1, 0, 0, 1]), vec![0x83, 2]);
}

#[test]
fn any_part_of_a_read_outside_the_windows_is_exception_02() {
    let mut r = Rig::new(&["END"]);
    for (start, qty) in [
        (SNAPSHOT - 1, 2),
        (SNAPSHOT + SNAPSHOT_LEN - 1, 2),
        (SNAPSHOT + SNAPSHOT_LEN, 1),
        (48, 17),
        (0, 104),
        (PROGRAM - 1, 2),
        (PROGRAM + 127, 2),
        (PROGRAM + 128, 1),
        (300, 125),
    ] {
        assert_eq!(read_input(&mut r, start, qty), Err(2), "{start} x {qty}");
    }
    assert!(read_input(&mut r, SNAPSHOT + SNAPSHOT_LEN - 1, 1).is_ok());
    assert!(read_input(&mut r, PROGRAM + 127, 1).is_ok());
    assert!(read_input(&mut r, PROGRAM + 3, 125).is_ok());
    // The discrete inputs, coils and holding registers have no §17 windows.
    assert_eq!(r.ask(&[0x02, 0, 64, 0, 1]), vec![0x82, 2]);
    assert_eq!(r.ask(&[0x01, 1, 0, 0, 1]), vec![0x81, 2]);
}

#[test]
fn a_reply_read_over_later_scans_still_shows_the_bits_of_one_scan() {
    // Y0..Y7 count the scans; U and V copy them; every Q and TQ follows Y0.
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/scan_counter.utl");
    let text = std::fs::read_to_string(path).expect("the listing");
    let mut r = Rig::with(listing::parse(path, &text).unwrap_or_else(|e| panic!("{e}")));
    let mut scans = 0u32;
    for round in 0..5 {
        for _ in 0..round * 7 + 3 {
            r.eng.scan(&mut r.b);
            scans += 1;
        }
        let st = ScanStats {
            count: scans,
            ..ScanStats::new()
        };
        r.status.refresh(STATUS_RUNNING, &st, 0, 0);
        let ev = r.judge(&[ADDRESS, 0x04, 0, SNAPSHOT as u8, 0, 8], false);
        assert_eq!(ev, Event::Reply);
        let y = u16::from(r.eng.py);
        assert_eq!(y, (scans & 0xFF) as u16, "the program counts its scans");
        // Between every two bytes of the reply, a scan changes every bit.
        let mut reply = Vec::new();
        while let Some(x) = r.next_byte() {
            reply.push(x);
            r.eng.scan(&mut r.b);
            scans += 1;
        }
        let regs = modbus::registers(modbus::reply_pdu(ADDRESS, &reply).unwrap());
        // A0..A5 open; Y, U and V the count; Q and TQ all Y0: of the judged scan.
        let q = 0u16.wrapping_sub(y & 1);
        assert_eq!(regs[1..5], [y << 8 | 0x3F, y << 8 | y, q, q]);
        assert_eq!(u32::from(regs[6]) << 16 | u32::from(regs[7]), scans - 21);
    }
}

/// SPEC §18: the RUN loop between two scans as the firmware runs it, `ms` times: the hold
/// decides whether a scan runs (free: four scans a ms, a step: one), then a ms passes.
/// Returns the scans run.
fn run_held(r: &mut Rig, ms: u32) -> u32 {
    let mut scans = 0;
    for _ in 0..ms {
        let n = match r.status.hold.next(&mut r.b) {
            Next::Free => 4,
            Next::Step => 1,
            Next::Held => 0,
        };
        for _ in 0..n {
            r.eng.scan(&mut r.b);
        }
        scans += n;
        r.b.advance_ms(1);
    }
    scans
}

/// FC03 of holding registers 32 and 33.
fn scan_control(r: &mut Rig) -> Vec<u16> {
    modbus::registers(&r.ask(&[0x03, 0, 32, 0, 2]))
}

#[test]
fn holding_registers_32_and_33_hold_and_step_and_refuse_other_values() {
    let mut r = Rig::new(&["Y0.", "!", ".Y0", "END"]);
    assert_eq!(scan_control(&mut r), vec![0, 0], "RUN starts free");
    // Exception 03 for every value outside 0..1 and 1..1000, and nothing changes.
    let before = r.status.hold;
    assert_eq!(r.ask(&[0x06, 0, 32, 0, 2]), vec![0x86, 3]);
    assert_eq!(r.ask(&[0x06, 0, 32, 0xFF, 0xFF]), vec![0x86, 3]);
    assert_eq!(r.ask(&[0x06, 0, 33, 0, 0]), vec![0x86, 3], "0 steps");
    assert_eq!(
        r.ask(&[0x06, 0, 33, 0x03, 0xE9]),
        vec![0x86, 3],
        "1001 steps"
    );
    assert_eq!(
        r.ask(&[0x10, 0, 32, 0, 2, 4, 0, 1, 0, 0]),
        vec![0x90, 3],
        "hold fine, 0 steps: neither written"
    );
    assert_eq!(r.status.hold, before);
    // Registers 26..31 are no part of the map: a read across the gap is exception 02.
    assert_eq!(r.ask(&[0x03, 0, 25, 0, 8]), vec![0x83, 2]);
    assert_eq!(r.ask(&[0x03, 0, 33, 0, 2]), vec![0x83, 2]);
    assert_eq!(r.ask(&[0x06, 0, 34, 0, 1]), vec![0x86, 2]);
    // Hold: 1, and status bit 4 at the next request.
    assert_eq!(r.ask(&[0x06, 0, 32, 0, 1]), vec![0x06, 0, 32, 0, 1]);
    assert_eq!(scan_control(&mut r), vec![1, 0]);
    r.status.refresh(STATUS_RUNNING, &ScanStats::new(), 0, 0);
    assert_eq!(
        read_input(&mut r, 0, 1).unwrap()[0],
        STATUS_RUNNING | STATUS_HELD
    );
    // 1000 steps are taken, and counted down as they run.
    assert_eq!(
        r.ask(&[0x06, 0, 33, 0x03, 0xE8]),
        vec![0x06, 0, 33, 3, 0xE8]
    );
    assert_eq!(scan_control(&mut r), vec![1, 1000]);
    assert_eq!(run_held(&mut r, 10), 10);
    assert_eq!(scan_control(&mut r), vec![1, 990]);
    // Release: free again, the steps dropped; bit 4 off.
    assert_eq!(r.ask(&[0x06, 0, 32, 0, 0]), vec![0x06, 0, 32, 0, 0]);
    assert_eq!(scan_control(&mut r), vec![0, 0]);
    r.status.refresh(STATUS_RUNNING, &ScanStats::new(), 0, 0);
    assert_eq!(read_input(&mut r, 64, 1).unwrap()[0], STATUS_RUNNING);
    // Both in one write, in address order: release, then 5 steps and a hold.
    assert_eq!(
        r.ask(&[0x10, 0, 32, 0, 2, 4, 0, 0, 0, 5]),
        vec![0x10, 0, 32, 0, 2]
    );
    assert_eq!(scan_control(&mut r), vec![1, 5]);
}

#[test]
fn held_the_scan_count_moves_only_by_the_steps_asked_for_and_nothing_else_changes() {
    // U0 triggers T0 (0.3 s); Y1 shows TQ0 as the scan saw it; Y0 toggles each scan.
    let mut r = Rig::new(&["U0.", ".TK0", "TQ0.", ".Y1", "Y0.", "!", ".Y0", "END"]);
    r.eng.prog.presets[0] = 3;
    r.eng.pu = 1;
    assert!(run_held(&mut r, 5) > 0, "free, it scans");
    r.eng.pu = 0;
    run_held(&mut r, 5);
    assert!(r.b.output(1), "T0 runs");
    r.ask(&[0x06, 0, 32, 0, 1]);
    let (eng, outputs) = (r.eng.clone(), r.b.outputs);
    assert_eq!(run_held(&mut r, 500), 0, "held: no scan");
    assert_eq!(r.b.outputs, outputs, "the pins stay");
    assert_eq!(r.eng, eng, "the engine stays");
    assert_eq!(r.eng.time_left_ms(0, r.b.ticker.now_ms()), 0, "T0 ran out");
    // One step: one scan, which sees TQ0 = 0 (the timer ran out while held).
    r.ask(&[0x06, 0, 33, 0, 1]);
    assert_eq!(run_held(&mut r, 50), 1);
    assert_eq!(r.eng.tq & 1, 0, "TQ0 = 0 at the step");
    assert!(!r.b.output(1), "the program saw TQ0 = 0");
    assert_ne!(r.eng.py & 1, eng.py & 1, "the step's scan toggled Y0");
    for n in [1u16, 7, 250, 1000] {
        r.ask(&[0x06, 0, 33, (n >> 8) as u8, n as u8]);
        assert_eq!(run_held(&mut r, 1500), u32::from(n), "{n} steps");
        assert_eq!(scan_control(&mut r), vec![1, 0]);
    }
    // Steps asked for while free run and then hold.
    r.ask(&[0x06, 0, 32, 0, 0]);
    assert!(run_held(&mut r, 3) > 3);
    r.ask(&[0x06, 0, 33, 0, 2]);
    assert_eq!(run_held(&mut r, 100), 2);
}

#[test]
fn a_hold_ends_by_itself_ten_seconds_after_the_last_frame() {
    let mut r = Rig::new(&["Y0.", "!", ".Y0", "END"]);
    let now = r.b.ticker.now_ms();
    r.ask(&[0x06, 0, 32, 0, 1]);
    // The firmware renews the lease at every valid frame for it (src/modbus.rs).
    r.status.hold.heard(now);
    assert_eq!(run_held(&mut r, 9_000), 0);
    // A read 9 s later renews it.
    r.ask(&[0x03, 0, 32, 0, 1]);
    r.status.hold.heard(r.b.ticker.now_ms());
    assert_eq!(
        run_held(&mut r, 9_999),
        0,
        "held until 9.999 s after the last frame"
    );
    assert_eq!(run_held(&mut r, 2), 4, "free at 10 s");
    assert!(!r.status.hold.held());
    r.status.refresh(STATUS_RUNNING, &ScanStats::new(), 0, 0);
    assert_eq!(
        read_input(&mut r, 0, 1).unwrap()[0],
        STATUS_RUNNING | STATUS_LAPSED,
        "bit 5: a hold ended by itself"
    );
    // Steps left when the lease ends are dropped: 5 steps, then free.
    r.ask(&[0x06, 0, 33, 0x03, 0xE8]);
    r.status.hold.heard(r.b.ticker.now_ms() - 9_995);
    assert_eq!(run_held(&mut r, 10), 5 + 5 * 4);
    assert!(!r.status.hold.held());
    assert_eq!(scan_control(&mut r), vec![0, 0]);
    // Bit 5 stays with a new hold.
    r.ask(&[0x06, 0, 32, 0, 1]);
    r.status.hold.heard(r.b.ticker.now_ms());
    r.status.refresh(STATUS_RUNNING, &ScanStats::new(), 0, 0);
    assert_eq!(
        read_input(&mut r, 0, 1).unwrap()[0],
        STATUS_RUNNING | STATUS_HELD | STATUS_LAPSED
    );
    // A new RUN starts free, bit 5 clear.
    assert_eq!(Status::default().hold, Hold::default());
    assert_eq!(Hold::default().bits, 0);
}
