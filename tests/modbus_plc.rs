//! The slave of SPEC §13 on the engine (host): §13's map over a running program, writes that
//! the program sees at its next scan, range checks that change nothing, broadcasts, drops,
//! the break key, and the master's activity window.

use utile_core::engine::Engine;
use utile_core::modbus::plc::{PlcMap, Status, STATUS_RUNNING};
use utile_core::modbus::slave::{Event, Slave, ACTIVE_MS};
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
        let mut eng = Engine::new(listing::commands(words));
        let mut b = SimBoard::new();
        eng.clear_runtime(&mut b);
        Rig {
            eng,
            b,
            slave: Slave::new(),
            status: Status::new(STATUS_RUNNING, &ScanStats::new(), 0, 0),
        }
    }

    fn scan(&mut self, ms: u32) {
        self.b.run_for(&mut self.eng, ms, 4);
    }

    /// Send `frame` (CRC appended unless `raw`), end it, and collect the reply.
    fn send(&mut self, bytes: &[u8], raw: bool) -> (Event, Vec<u8>) {
        let frame = if raw {
            bytes.to_vec()
        } else {
            modbus::with_crc(bytes)
        };
        for &x in &frame {
            self.slave.push(x, false);
        }
        let now = self.b.ticker.now_ms();
        let mut map = PlcMap {
            eng: &mut self.eng,
            b: &mut self.b,
            status: &self.status,
        };
        let ev = self.slave.end(ADDRESS, &mut map, now);
        let mut reply = Vec::new();
        while let Some(x) = self.slave.next_byte(&mut map) {
            reply.push(x);
        }
        (ev, reply)
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
