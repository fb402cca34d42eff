//! `ADDR` (SPEC §13): the Modbus address, typed as a number then `ADDR`, shown by
//! `ADDR` alone and by `VER`, kept in its own EEPROM cell that STORE, LOAD and FILL leave
//! alone.

mod support;

use support::editor::Session;
use utile_core::store::{self, ADDR_CELL};

#[test]
fn a_number_then_addr_sets_the_address_and_addr_alone_shows_it() {
    let mut r = Session::new();
    r.enter("addr");
    assert!(r.row(19).contains("Modbus address 1"), "{}", r.row(19));
    r.enter("17");
    r.enter("addr");
    assert!(r.row(19).contains("Modbus address 17"), "{}", r.row(19));
    assert_eq!(r.b.eeprom[usize::from(ADDR_CELL)], 17);
    assert_eq!(r.b.eeprom[usize::from(ADDR_CELL) + 1], !17);
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
    // A damaged cell reads as the default address, 1.
    r.b.eeprom[usize::from(ADDR_CELL) + 1] ^= 0x10;
    assert_eq!(store::slave_address(&mut r.b), 1);
}
