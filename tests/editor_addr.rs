//! `ADDR` (SPEC §13): the Modbus address, typed as a number then `ADDR`, shown by
//! `ADDR` alone and by `VER`, kept in two copies of its own EEPROM cells that STORE, LOAD
//! and FILL leave alone, written one at a time so that a power cut at any moment brings the
//! slave back at its old address or its new one, never at the default (issue 40).

mod support;

use support::editor::Session;
use utile_core::store::{self, ADDR_CELL, ADDR_CELLS, DEFAULT_ADDRESS};
use utile_kit::sim::{EepromFault, SimBoard, Tear};

#[test]
fn a_number_then_addr_sets_the_address_and_addr_alone_shows_it() {
    let mut r = Session::new();
    r.enter("addr");
    assert!(r.row(19).contains("Modbus address 1"), "{}", r.row(19));
    r.enter("17");
    r.enter("addr");
    assert!(r.row(19).contains("Modbus address 17"), "{}", r.row(19));
    for cell in ADDR_CELLS.map(usize::from) {
        assert_eq!(r.b.eeprom[cell..cell + 2], [17, !17], "both copies");
    }
    // A command in between: ADDR no longer takes the old number.
    r.enter("42");
    r.enter("A0.");
    r.enter("addr");
    assert!(r.row(19).contains("address 17"), "{}", r.row(19));
    r.enter("ver");
    assert!(r.row(19).contains("Modbus address 17"), "VER shows it");
}

#[test]
fn addresses_outside_1_to_247_are_refused_and_nothing_changes() {
    let mut r = Session::new();
    r.enter("9");
    r.enter("addr");
    for bad in ["0", "248", "300", "65535"] {
        r.enter(bad);
        r.enter("addr");
        assert!(
            r.status().contains("Address 1..247"),
            "{bad}: {}",
            r.status()
        );
        assert!(r.row(19).contains("address 9"), "{bad}: {}", r.row(19));
    }
    assert_eq!(store::slave_address(&mut r.b), 9);
}

#[test]
fn store_load_and_fill_leave_the_address_alone() {
    let mut r = Session::new();
    r.enter("200");
    r.enter("addr");
    r.enter("A0.");
    r.enter("store");
    r.enter("fill");
    r.enter("load");
    assert_eq!(store::slave_address(&mut r.b), 200);
    // A damaged copy: the other one holds the address.
    r.b.eeprom[usize::from(ADDR_CELL) + 1] ^= 0x10;
    assert_eq!(store::slave_address(&mut r.b), 200);
    // Both damaged: the default address, 1.
    r.b.eeprom[usize::from(ADDR_CELLS[1])] ^= 0x01;
    assert_eq!(store::slave_address(&mut r.b), DEFAULT_ADDRESS);
}

#[test]
fn an_eeprom_with_the_one_copy_of_versions_2_to_4_keeps_its_address() {
    let mut b = SimBoard::new();
    let at = usize::from(ADDR_CELL);
    b.eeprom[at] = 23;
    b.eeprom[at + 1] = !23;
    assert_eq!(store::slave_address(&mut b), 23);
    // The next ADDR writes both copies.
    assert!(store::set_slave_address(&mut b, 42));
    assert_eq!(store::slave_address(&mut b), 42);
}

/// A power cut after every number of EEPROM byte writes of an ADDR, with every way the
/// byte under way can be left (kept, erased, half programmed): the address read at the
/// next power-up is the old one or the new one. Before, one copy was rewritten in place,
/// and a cut between the address and its complement brought the slave back at address 1.
#[test]
fn a_power_cut_anywhere_in_addr_keeps_the_old_address_or_the_new_one() {
    let mut cases = 0;
    for (old, new) in [(5u8, 17u8), (17, 5), (1, 247), (200, 55)] {
        let mut before = SimBoard::new();
        // The old address set by this firmware (both copies), and by versions 2–4 (one).
        let mut one_copy = SimBoard::new();
        assert!(store::set_slave_address(&mut before, old));
        one_copy.eeprom[usize::from(ADDR_CELL)] = old;
        one_copy.eeprom[usize::from(ADDR_CELL) + 1] = !old;
        for start in [before, one_copy] {
            let mut dry = start.clone();
            dry.eeprom_writes = 0;
            assert!(store::set_slave_address(&mut dry, new));
            let total = dry.eeprom_writes;
            assert!(total >= 2, "{old} → {new}: {total} writes");
            let mut seen = Vec::new();
            for n in 0..=total {
                for tear in [Tear::Old, Tear::Erased, Tear::Partial] {
                    let mut b = start.clone();
                    b.eeprom_fault = EepromFault::PowerFail { writes: n, tear };
                    store::set_slave_address(&mut b, new);
                    b.eeprom_fault = EepromFault::None;
                    let got = store::slave_address(&mut b);
                    assert!(
                        got == old || got == new,
                        "{old} → {new}, cut after {n} of {total} writes ({tear:?}): {got}"
                    );
                    seen.push(got);
                    cases += 1;
                }
            }
            assert!(seen.contains(&old) && seen.contains(&new), "{old} → {new}");
        }
    }
    assert!(cases > 100, "{cases}");
}
