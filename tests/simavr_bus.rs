//! Three uTiles on one RS-485 line (SPEC §13, issue 16): the real image three times in the
//! kit's `Bus`, addresses 1, 2 and 3 set with `ADDR`'s EEPROM cell, each autostarting
//! `U0. .Y0 KEY END`. The master polls each one, only that one answers, a broadcast reaches
//! all three, and no two drivers (D10) are ever enabled at once.
//!
//! Needs `out/m328-nano-utile.elf` (`cargo fw`).

mod support;

use support::chip::CYCLES_PER_MS;
use utile_core::store;
use utile_kit::listing;
use utile_kit::modbus;
use utile_kit::setup::firmware_elf;
use utile_kit::sim::SimBoard;
use utile_kit::simavr::{frame_cycles, Bus, BusByte, Chip, RigPin};

/// A chip with the program stored, slave address `address`, D8 fitted (autostart).
fn chip(address: u8) -> Chip {
    let mut b = SimBoard::new();
    store::store(&listing::commands(&["U0.", ".Y0", "KEY", "END"]), &mut b).expect("STORE");
    assert!(store::set_slave_address(&mut b, address));
    utile_kit::setup::yield_to_wall_clock_tests();
    let mut c = Chip::load(&firmware_elf()).unwrap_or_else(|e| panic!("{e}"));
    c.set_eeprom(0, &b.eeprom);
    c.hold_low(RigPin::D8, true);
    c
}

/// A request to `to` (CRC appended) after 4 characters of silence; what came back in the
/// next 60 ms.
fn ask(bus: &mut Bus, to: u8, pdu: &[u8]) -> Vec<BusByte> {
    bus.send_after(4 * frame_cycles(19_200), &modbus::frame(to, pdu));
    assert!(bus.run_for(60 * CYCLES_PER_MS).is_none(), "a chip stopped");
    bus.take_master()
}

/// The Y0 pin of chip `i`.
fn y0(bus: &Bus, i: usize) -> bool {
    bus.chip(i).outputs() & 1 != 0
}

#[test]
fn three_slaves_on_one_line_each_answer_their_own_address_and_all_take_a_broadcast() {
    let mut bus = Bus::new(vec![chip(1), chip(2), chip(3)], 19_200).with_driver_enable();
    // Boot, autostart and the RUN screens (which go out with D10 low: not on the bus).
    assert!(bus.run_for(1_000 * CYCLES_PER_MS).is_none());
    bus.take_master();
    for address in 1..=3u8 {
        let reply = ask(&mut bus, address, &[0x11]);
        assert!(!reply.is_empty(), "slave {address} answered");
        assert!(
            reply.iter().all(|b| b.from == usize::from(address - 1)),
            "only slave {address} answered: {reply:?}"
        );
        let bytes: Vec<u8> = reply.iter().map(|b| b.byte).collect();
        assert_eq!(bytes[0], address);
        assert!(modbus::crc_ok(&bytes), "a valid frame");
    }
    // Slave 2's U0 on: only its Y0 follows.
    let reply = ask(&mut bus, 2, &[0x05, 0, 8, 0xFF, 0]);
    assert_eq!(reply.len(), 8);
    assert!(bus.run_for(5 * CYCLES_PER_MS).is_none());
    assert_eq!(
        (y0(&bus, 0), y0(&bus, 1), y0(&bus, 2)),
        (false, true, false)
    );
    // A broadcast (address 0) of U0 on: all three follow, none answers.
    let reply = ask(&mut bus, 0, &[0x05, 0, 8, 0xFF, 0]);
    assert!(reply.is_empty(), "nobody answers a broadcast: {reply:?}");
    assert!(bus.run_for(5 * CYCLES_PER_MS).is_none());
    assert_eq!((y0(&bus, 0), y0(&bus, 1), y0(&bus, 2)), (true, true, true));
    // An address nobody has: silence.
    assert!(ask(&mut bus, 4, &[0x03, 0, 0, 0, 1]).is_empty());
    assert!(
        bus.collisions().is_empty(),
        "two drivers at once: {:?}",
        bus.collisions()
    );
    // Each slave counts the frames for others as dropped, the other slaves' replies too
    // (they share the line). Slave 1: requests to 2, 3, 2 and 4, replies from 2, 3 and 2.
    let reply = ask(&mut bus, 1, &[0x04, 0, 7, 0, 1]);
    let bytes: Vec<u8> = reply.iter().map(|b| b.byte).collect();
    assert_eq!(
        &bytes[..5],
        &[1, 0x04, 2, 0, 7],
        "slave 1's dropped-frame count"
    );
}
