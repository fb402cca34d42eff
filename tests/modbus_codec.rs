//! The Modbus RTU codec of the core (SPEC §13): CRC-16/MODBUS, framing verdicts, every
//! function and exception against a map shaped like §13's (the kit's [`TestMap`]), replies
//! produced byte by byte.

use utile_core::modbus::crc::{crc16_modbus, Crc16};
use utile_core::modbus::frame::{self, Drop, Receiver, Verdict, FRAME_MAX};
use utile_core::modbus::map::{Map, Table};
use utile_core::modbus::reply::Reply;
use utile_core::modbus::request::{handle, Answer};
use utile_core::modbus::Exception;
use utile_kit::modbus::map::TestMap;
use utile_kit::modbus::{crc_ok, frame as request, with_crc};

/// A request to slave 1 as a master sends it; the reply as the slave produces it.
fn transact(map: &mut TestMap, pdu: &[u8]) -> Vec<u8> {
    let frame = request(1, pdu);
    let mut rx = Receiver::new();
    for &b in &frame {
        rx.push(b, false);
    }
    let len = match rx.end() {
        Verdict::Frame { len } => usize::from(len),
        other => panic!("frame {frame:02X?} not taken: {other:?}"),
    };
    assert_eq!(len, frame.len());
    let got = rx.frame().to_vec();
    let pdu = &got[1..len - 2];
    let answer = handle(pdu, map);
    let mut reply = Reply::new(1, answer, map);
    let mut out = Vec::new();
    while let Some(b) = reply.next_byte(map, pdu) {
        out.push(b);
    }
    assert!(reply.is_done());
    assert_eq!(out.len(), usize::from(reply.size()));
    assert!(crc_ok(&out), "reply CRC");
    assert_eq!(map.outside.take(), None, "the codec stayed in the map");
    out
}

/// The reply without address and CRC.
fn pdu_of(reply: &[u8]) -> &[u8] {
    &reply[1..reply.len() - 2]
}

fn exception(map: &mut TestMap, pdu: &[u8]) -> (u8, u8) {
    let r = transact(map, pdu);
    assert_eq!(r.len(), 5, "exception replies are 5 bytes: {r:02X?}");
    (r[1], r[2])
}

#[test]
fn crc_matches_the_specifications_examples() {
    // Modbus over serial line, the FC03 example: 11 03 00 6B 00 03 -> CRC 76 87 on the wire.
    assert_eq!(
        crc16_modbus(&[0x11, 0x03, 0x00, 0x6B, 0x00, 0x03]).to_le_bytes(),
        [0x76, 0x87]
    );
    assert_eq!(
        crc16_modbus(&[0x01, 0x03, 0x00, 0x00, 0x00, 0x0A]).to_le_bytes(),
        [0xC5, 0xCD]
    );
    let mut c = Crc16::new();
    c.update(0x01);
    assert_ne!(c.value(), Crc16::new().value());
}

#[test]
fn frames_are_taken_or_dropped_as_the_spec_says() {
    let good = with_crc(&[1, 3, 0, 0, 0, 1]);
    let mut rx = Receiver::new();
    assert_eq!(rx.end(), Verdict::Empty);

    for &b in &good {
        rx.push(b, false);
    }
    assert_eq!(rx.end(), Verdict::Frame { len: 8 });
    assert_eq!(rx.frame(), &good[..]);

    // One bit flipped anywhere: bad CRC.
    for i in 0..good.len() {
        let mut bad = good.clone();
        bad[i] ^= 0x10;
        for &b in &bad {
            rx.push(b, false);
        }
        assert_eq!(rx.end(), Verdict::Dropped(Drop::Crc), "flip in byte {i}");
        assert!(rx.frame().is_empty());
    }

    // A gap of more than 1.5 characters inside the frame.
    for (i, &b) in good.iter().enumerate() {
        rx.push(b, i == 4);
    }
    assert_eq!(rx.end(), Verdict::Dropped(Drop::Gap));

    // Longer than the slave takes.
    for i in 0..=FRAME_MAX {
        rx.push(i as u8, false);
    }
    assert_eq!(rx.end(), Verdict::Dropped(Drop::TooLong));

    // The terminal's break key alone, and short frames.
    rx.push(b'/', false);
    assert_eq!(rx.end(), Verdict::Slash);
    rx.push(b'/', false);
    rx.push(b'/', false);
    assert_eq!(rx.end(), Verdict::Dropped(Drop::Short));

    // A valid frame that contains 0x2F is a frame, never a break.
    let slashy = with_crc(&[0x2F, 6, 0, 0x2F, 0, 0x2F]);
    for &b in &slashy {
        rx.push(b, false);
    }
    assert_eq!(rx.end(), Verdict::Frame { len: 8 });
}

/// The line's silences in a board's clock (issue 32): t1.5 is measured from one stop bit to
/// the next start bit, so between two receive stamps (the same point of each character) the
/// limit is the later character plus t1.5; t3.5 runs from the last stamp.
#[test]
fn the_silences_in_clock_counts_hold_the_character_itself() {
    // Timer1 at 2 MHz, 19200 baud: a character is 1,041.7 counts.
    assert_eq!(frame::char_counts(2_000_000, 19_200, 10), 1042);
    assert_eq!(frame::pause_limit(2_000_000, 19_200), 2605);
    assert_eq!(frame::end_silence(2_000_000, 19_200), 3646);
    // In microseconds at 9600 baud: 1,041.7 µs a character.
    assert_eq!(frame::pause_limit(1_000_000, 9600), 2605);
    // A stamp 1.4 characters of silence after the last character's is inside the frame,
    // 1.6 characters after it is not.
    let c = 2_000_000.0 / 1920.0;
    let limit = f64::from(frame::pause_limit(2_000_000, 19_200));
    assert!(2.4 * c < limit && 2.6 * c > limit);
}

#[test]
fn read_coils_and_discrete_inputs_pack_bits_lsb_first() {
    let mut m = TestMap::new();
    m.coils[0] = true;
    m.coils[3] = true;
    m.coils[9] = true;
    assert_eq!(
        pdu_of(&transact(&mut m, &[1, 0, 0, 0, 10])),
        &[1, 2, 0x09, 0x02]
    );
    // Discrete inputs 8..17: every third address (9, 12, 15) is 1.
    assert_eq!(
        pdu_of(&transact(&mut m, &[2, 0, 8, 0, 10])),
        &[2, 2, 0x92, 0x00]
    );
    // The whole table from 8: 42 bits, 6 bytes.
    let r = transact(&mut m, &[2, 0, 8, 0, 42]);
    assert_eq!(r[2], 6);
}

#[test]
fn read_registers_send_high_byte_first() {
    let mut m = TestMap::new();
    m.holding[24] = 0x0203;
    m.holding[25] = 1023;
    assert_eq!(
        pdu_of(&transact(&mut m, &[3, 0, 24, 0, 2])),
        &[3, 4, 0x02, 0x03, 0x03, 0xFF]
    );
    let r = transact(&mut m, &[4, 0, 32, 0, 16]);
    assert_eq!(r[2], 32);
    assert_eq!(&r[3..7], &[0x10, 0x20, 0x10, 0x21]);
}

#[test]
fn writes_change_the_map_and_echo_the_request() {
    let mut m = TestMap::new();
    assert_eq!(
        pdu_of(&transact(&mut m, &[5, 0, 8, 0xFF, 0])),
        &[5, 0, 8, 0xFF, 0]
    );
    assert!(m.coils[8]);
    transact(&mut m, &[5, 0, 8, 0, 0]);
    assert!(!m.coils[8]);

    assert_eq!(
        pdu_of(&transact(&mut m, &[6, 0, 24, 0x01, 0xF4])),
        &[6, 0, 24, 0x01, 0xF4]
    );
    assert_eq!(m.holding[24], 500);

    // FC15: ten coils from 14, 0b11_0000_0101.
    let r = transact(&mut m, &[15, 0, 14, 0, 10, 2, 0x05, 0x03]);
    assert_eq!(pdu_of(&r), &[15, 0, 14, 0, 10]);
    let set: Vec<usize> = (0..24).filter(|&i| m.coils[i]).collect();
    assert_eq!(set, vec![14, 16, 22, 23]);

    // FC16: T0, T1 and C0.
    let r = transact(&mut m, &[16, 0, 15, 0, 2, 4, 0, 200, 0xEA, 0x60]);
    assert_eq!(pdu_of(&r), &[16, 0, 15, 0, 2]);
    assert_eq!((m.holding[15], m.holding[16]), (200, 60000));
}

#[test]
fn diagnostics_echo_and_server_id() {
    let mut m = TestMap::new();
    let pdu = [8, 0, 0, 0xA5, 0x5A, 0x2F];
    assert_eq!(pdu_of(&transact(&mut m, &pdu)), &pdu);
    let r = transact(&mut m, &[17]);
    assert_eq!(pdu_of(&r), &[17, 7, 1, 0xFF, b'u', b'T', b'i', b'l', b'e']);
    m.running = false;
    assert_eq!(transact(&mut m, &[17])[4], 0x00);
}

#[test]
fn every_exception_changes_nothing() {
    let mut m = TestMap::new();
    m.holding[0] = 7;
    let before = m.clone();
    let cases: &[(&[u8], u8)] = &[
        // 01: unknown function, diagnostics other than sub-function 0.
        (&[7], 1),
        (&[0x2B, 0x0E, 1, 0], 1),
        (&[8, 0, 1, 0, 0], 1),
        // 03: quantity 0 or past the limits, a malformed length, a bad coil value.
        (&[1, 0, 0, 0, 0], 3),
        (&[1, 0, 0, 0x07, 0xD1], 3),
        (&[3, 0, 0, 0, 0], 3),
        (&[3, 0, 0, 0, 126], 3),
        (&[4, 0, 0, 0], 3),
        (&[5, 0, 0, 0x12, 0x34], 3),
        (&[15, 0, 0, 0, 10, 1, 0xFF], 3),
        (&[16, 0, 0, 0, 2, 3, 0, 1, 0], 3),
        (&[16, 0, 0, 0, 124, 248], 3),
        // 02: any address of the range outside the map.
        (&[1, 0, 20, 0, 5], 2),
        (&[2, 0, 4, 0, 3], 2),
        (&[2, 0, 49, 0, 2], 2),
        (&[3, 0, 24, 0, 3], 2),
        (&[4, 0, 17, 0, 2], 2),
        (&[4, 0xFF, 0xFF, 0, 2], 2),
        (&[5, 0, 24, 0xFF, 0], 2),
        (&[6, 0, 26, 0, 1], 2),
        (&[15, 0, 20, 0, 8, 1, 0xFF], 2),
        (&[16, 0, 25, 0, 2, 4, 0, 1, 0, 1], 2),
        // 03: a value out of range (a timer preset past 255), even as the last of several.
        (&[6, 0, 0, 1, 0], 3),
        (&[16, 0, 14, 0, 2, 4, 0, 9, 1, 0], 3),
        (&[16, 0, 23, 0, 3, 6, 0, 1, 0, 1, 0x04, 0], 3),
    ];
    for &(pdu, code) in cases {
        let (function, got) = exception(&mut m, pdu);
        assert_eq!((function, got), (pdu[0] | 0x80, code), "request {pdu:02X?}");
        assert_eq!(m, before, "request {pdu:02X?} changed the map");
    }
    assert!(matches!(
        handle(&[3, 0, 0, 0, 0], &mut m),
        Answer::Exception {
            function: 3,
            code: Exception::IllegalDataValue
        }
    ));
}

#[test]
fn the_largest_reads_fit_a_frame_and_the_limits_hold() {
    struct Wide;
    impl Map for Wide {
        fn contains(&self, _: Table, _: u16) -> bool {
            true
        }
        fn read(&mut self, _: Table, addr: u16) -> u16 {
            addr
        }
        fn accepts(&self, _: u16, _: u16) -> bool {
            true
        }
        fn write(&mut self, _: Table, _: u16, _: u16) {}
        fn running(&self) -> bool {
            true
        }
        fn id_len(&self) -> u8 {
            0
        }
        fn id_byte(&self, _: u8) -> u8 {
            0
        }
    }
    let mut w = Wide;
    let a = handle(&[3, 0, 0, 0, 125], &mut w);
    let mut r = Reply::new(9, a, &w);
    assert_eq!(r.size(), 255);
    let bytes: Vec<u8> = std::iter::from_fn(|| r.next_byte(&mut w, &[3, 0, 0, 0, 125])).collect();
    assert_eq!(bytes.len(), 255);
    assert_eq!(&bytes[..5], &[9, 3, 250, 0, 0]);
    assert_eq!(&bytes[251..253], &[0, 124]);
    let a = handle(&[1, 0, 0, 0x07, 0xD0], &mut w);
    assert_eq!(Reply::new(9, a, &w).size(), 5 + 250);
    // The top of the address space: 0xFFFF plus one register is past it.
    assert!(matches!(
        handle(&[3, 0xFF, 0xFF, 0, 1], &mut w),
        Answer::Read { .. }
    ));
    assert!(matches!(
        handle(&[3, 0xFF, 0xFF, 0, 2], &mut w),
        Answer::Exception {
            code: Exception::IllegalDataAddress,
            ..
        }
    ));
}
