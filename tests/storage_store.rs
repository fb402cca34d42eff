//! Two-slot EEPROM storage (SPEC §9, docs/FORMAT.md): alternation, sequence wrap, writing
//! only changed bytes, read-back verification, and fault injection (a reset at every point
//! of a STORE, flipped bytes, erased and random EEPROM).

use utile_core::engine::Program;
use utile_core::image;
use utile_core::store::{self, LoadError, StoreError, SLOT_ADDR};
use utile_kit::rng::Rng;
use utile_kit::sim::{EepromFault, SimBoard, Tear};

/// A typical small program: a few lines, the rest blank.
fn small_program() -> Program {
    let mut p = Program::blank();
    p.uf[..6].copy_from_slice(&[0x20, 0x30, 0x03, 0x40, 0x01, 0x00]);
    p.presets[4] = 5;
    p
}

fn seq(b: &SimBoard, slot: usize) -> u16 {
    let a = usize::from(SLOT_ADDR[slot]);
    u16::from_le_bytes([b.eeprom[a], b.eeprom[a + 1]])
}

fn slot_image(b: &SimBoard, slot: usize) -> &[u8] {
    let a = usize::from(SLOT_ADDR[slot]) + 2;
    &b.eeprom[a..a + image::IMAGE_LEN]
}

/// Byte writes a STORE of `new` over the EEPROM of `b` needs.
fn writes_needed(b: &SimBoard, new: &Program) -> u32 {
    let mut dry = b.clone();
    dry.eeprom_writes = 0;
    store::store(new, &mut dry).expect("store");
    dry.eeprom_writes
}

/// Reset STORE of `new` after every possible number of writes, with every tear mode:
/// afterwards LOAD must give `old` or `new` (or nothing when there was nothing before), and
/// a following STORE must work. Returns the number of cases checked.
fn reset_during_store(before: &SimBoard, old: Option<&Program>, new: &Program) -> u32 {
    let total = writes_needed(before, new);
    let mut cases = 0;
    let mut saw_new = false;
    let mut saw_old = false;
    for n in 0..=total {
        for tear in [Tear::Old, Tear::Erased, Tear::Partial] {
            let mut fb = before.clone();
            fb.eeprom_fault = EepromFault::PowerFail { writes: n, tear };
            let result = store::store(new, &mut fb);
            if n < total && matches!(tear, Tear::Old) {
                assert_eq!(
                    result,
                    Err(StoreError::Verify),
                    "cut after {n} of {total} writes"
                );
            } else if n < total {
                // A torn byte may happen to hold the intended value; then STORE succeeded.
                if result == Ok(()) {
                    assert_eq!(store::load(&mut fb.clone()).as_ref(), Ok(new));
                }
            } else {
                assert_eq!(result, Ok(()));
            }
            // Reboot: power back, LOAD.
            let mut after = fb;
            after.eeprom_fault = EepromFault::None;
            match store::load(&mut after) {
                Ok(p) if &p == new => saw_new = true,
                Ok(p) => {
                    assert_eq!(Some(&p), old, "garbage after cut {n}/{total} ({tear:?})");
                    saw_old = true;
                }
                Err(LoadError::NoValidImage) => {
                    assert!(
                        old.is_none(),
                        "old program lost after cut {n}/{total} ({tear:?})"
                    )
                }
            }
            // The next STORE works and wins.
            let mut next = new.clone();
            next.uf[200] = next.uf[200].wrapping_add(1);
            assert_eq!(store::store(&next, &mut after), Ok(()));
            assert_eq!(store::load(&mut after), Ok(next));
            cases += 1;
        }
    }
    assert!(saw_new, "the complete STORE gives the new program");
    assert!(
        saw_old || old.is_none() || old == Some(new),
        "an early cut keeps the old one"
    );
    cases
}

#[test]
fn erased_eeprom_has_no_image_and_load_changes_nothing() {
    let mut b = SimBoard::new();
    assert_eq!(store::load(&mut b), Err(LoadError::NoValidImage));
    assert_eq!(b.eeprom_writes, 0);
    assert!(b.eeprom.iter().all(|&x| x == 0xFF));
}

#[test]
fn random_eeprom_has_no_image() {
    let mut rng = Rng(0xABCD);
    for _ in 0..300 {
        let mut b = SimBoard::new();
        b.eeprom.iter_mut().for_each(|x| *x = rng.byte());
        let snapshot = b.eeprom.clone();
        assert_eq!(store::load(&mut b), Err(LoadError::NoValidImage));
        assert_eq!(b.eeprom, snapshot, "LOAD never writes");
        // Random contents with a correct header still fail the CRC.
        for &a in &SLOT_ADDR {
            let a = usize::from(a) + 2;
            b.eeprom[a..a + 4].copy_from_slice(&[b'u', b'T', 1, 0]);
        }
        assert_eq!(store::load(&mut b), Err(LoadError::NoValidImage));
        // And STORE works on top of any junk.
        let p = rng.program();
        assert_eq!(store::store(&p, &mut b), Ok(()));
        assert_eq!(store::load(&mut b), Ok(p));
    }
}

#[test]
fn store_then_load_round_trip_and_slots_alternate() {
    let mut rng = Rng(42);
    let mut b = SimBoard::new();
    let mut expect_slot = 0;
    for k in 1..=10u16 {
        let p = rng.program_v2();
        assert_eq!(store::store(&p, &mut b), Ok(()));
        assert_eq!(
            slot_image(&b, expect_slot),
            &image::encode(&p)[..],
            "STORE {k}"
        );
        assert_eq!(seq(&b, expect_slot), k, "sequence numbers count up");
        assert_eq!(store::load(&mut b), Ok(p.clone()));
        // The other slot still holds the previous program (if any).
        expect_slot ^= 1;
    }
    // Slot layout: nothing outside the two slots (2 + 298 bytes each) is touched.
    assert!(b.eeprom[0x12C..0x200].iter().all(|&x| x == 0xFF));
    assert!(b.eeprom[0x32C..].iter().all(|&x| x == 0xFF));
}

#[test]
fn sequence_number_wraps() {
    let mut b = SimBoard::new();
    let progs: Vec<Program> = (0..6u8)
        .map(|k| {
            let mut p = small_program();
            p.uf[10] = k;
            p
        })
        .collect();
    store::store(&progs[0], &mut b).unwrap();
    // Pretend slot 0 was stored as number 0xFFFE.
    b.eeprom[0] = 0xFE;
    b.eeprom[1] = 0xFF;
    assert_eq!(store::load(&mut b), Ok(progs[0].clone()));
    let expected = [(1, 0xFFFF), (0, 0x0000), (1, 0x0001), (0, 0x0002)];
    for (k, &(slot, s)) in expected.iter().enumerate() {
        store::store(&progs[k + 1], &mut b).unwrap();
        assert_eq!(seq(&b, slot), s);
        assert_eq!(
            store::load(&mut b),
            Ok(progs[k + 1].clone()),
            "after wrap step {k}"
        );
    }
}

#[test]
fn only_changed_bytes_are_written() {
    let mut b = SimBoard::new();
    let mut p = small_program();

    // First STORE on erased EEPROM.
    store::store(&p, &mut b).unwrap();
    let first = b.eeprom_writes;

    // Fill the second slot too, then one-line edits as a user makes them.
    let mut counts = Vec::new();
    for line in 6..14 {
        p.uf[line] = 0x20 + line as u8;
        let before = b.eeprom_writes;
        store::store(&p, &mut b).unwrap();
        counts.push(b.eeprom_writes - before);
        assert_eq!(store::load(&mut b), Ok(p.clone()));
    }
    // Steady state: the older slot is two edits behind, so two lines differ; plus the CRC
    // (2), the magic clear/restore (2) and the sequence number (1 or 2).
    let typical = *counts.last().unwrap();
    assert!(typical <= 8, "one-line edit wrote {typical} bytes");

    // The same program again: only the sequence number (and the lines the older slot lacks).
    let before = b.eeprom_writes;
    store::store(&p, &mut b).unwrap();
    let same_again = b.eeprom_writes - before;
    let before = b.eeprom_writes;
    store::store(&p, &mut b).unwrap();
    let same_twice = b.eeprom_writes - before;
    assert!(
        same_twice <= 2,
        "identical slot: only the sequence number ({same_twice})"
    );

    // A full rewrite: every line and preset different from both slots.
    let mut q = p.clone();
    q.uf.iter_mut().for_each(|x| *x ^= 0x5A);
    q.presets.iter_mut().for_each(|x| *x ^= 0xA5);
    let before = b.eeprom_writes;
    store::store(&q, &mut b).unwrap();
    let full = b.eeprom_writes - before;
    assert!((272..=278).contains(&full), "full rewrite wrote {full}");

    let ms = |n: u32| f64::from(n) * 3.3;
    println!("STORE figures (EEPROM byte writes, at 3.3 ms each):");
    println!(
        "  first STORE on erased EEPROM: {first} writes = {:.0} ms",
        ms(first)
    );
    println!("  one-line edits, successive STOREs: {counts:?}");
    println!(
        "  typical one-line change: {typical} writes = {:.0} ms",
        ms(typical)
    );
    println!("  same program again: {same_again} then {same_twice} writes");
    println!("  full rewrite: {full} writes = {:.0} ms", ms(full));
}

#[test]
fn reset_at_every_point_of_a_store() {
    let mut rng = Rng(0x5EED);
    let mut cases = 0;

    // First STORE ever: nothing or the new program.
    let erased = SimBoard::new();
    let p = rng.program();
    cases += reset_during_store(&erased, None, &p);

    for round in 0..12 {
        // Two programs already stored (both slots valid), then a third.
        let mut b = SimBoard::new();
        let a = rng.program();
        let old = rng.program();
        store::store(&a, &mut b).unwrap();
        if round % 3 != 0 {
            store::store(&old, &mut b).unwrap();
        }
        let old_now = store::load(&mut b).unwrap();
        let new = match round % 4 {
            0 => rng.program(), // full rewrite
            1 => {
                let mut n = old_now.clone();
                n.uf[(rng.next_u32() % 256) as usize] ^= 0x11; // one line
                n
            }
            2 => {
                let mut n = old_now.clone();
                n.presets[3] = n.presets[3].wrapping_add(1); // one preset
                n
            }
            _ => old_now.clone(), // the same program again
        };
        cases += reset_during_store(&b, Some(&old_now), &new);
    }
    println!("reset-during-STORE cases checked: {cases}");
    assert!(cases > 3000);
}

#[test]
fn flipped_bytes_in_either_slot_fall_back_to_the_other() {
    let mut rng = Rng(31337);
    let a = rng.program();
    let bp = rng.program();
    let mut base = SimBoard::new();
    store::store(&a, &mut base).unwrap(); // slot 0, older
    store::store(&bp, &mut base).unwrap(); // slot 1, newest
    assert_eq!(store::load(&mut base.clone()), Ok(bp.clone()));

    for (slot, survivor) in [(0usize, &bp), (1, &a)] {
        let start = usize::from(SLOT_ADDR[slot]);
        for i in 2..2 + image::IMAGE_LEN {
            for flip in [0x01u8, 0x80] {
                let mut b = base.clone();
                b.eeprom[start + i] ^= flip;
                assert_eq!(
                    store::load(&mut b),
                    Ok(survivor.clone()),
                    "slot {slot} byte {i}"
                );
            }
        }
        // A flipped sequence number only changes which (valid) program is newest.
        for i in 0..2 {
            let mut b = base.clone();
            b.eeprom[start + i] ^= 0x80;
            let got = store::load(&mut b).unwrap();
            assert!(got == a || got == bp);
        }
    }

    // Damage the newest slot, then STORE: it must go into the damaged slot and keep `a`.
    let mut b = base.clone();
    b.eeprom[usize::from(SLOT_ADDR[1]) + 100] ^= 0xFF;
    let c = rng.program();
    store::store(&c, &mut b).unwrap();
    assert_eq!(
        slot_image(&b, 0),
        &image::encode(&a)[..],
        "the good slot is kept"
    );
    assert_eq!(store::load(&mut b), Ok(c));

    // Both damaged: nothing to load.
    let mut b = base.clone();
    b.eeprom[10] ^= 1;
    b.eeprom[usize::from(SLOT_ADDR[1]) + 10] ^= 1;
    assert_eq!(store::load(&mut b), Err(LoadError::NoValidImage));
}

/// A board with a stuck EEPROM cell (writes to it are lost).
#[test]
fn failing_eeprom_is_reported_and_the_old_program_kept() {
    let mut rng = Rng(8);
    let old = rng.program();
    let new = rng.program();
    let mut base = SimBoard::new();
    store::store(&old, &mut base).unwrap(); // slot 0
                                            // Slot 1 byte 50 is stuck at its erased value, which differs from the new image.
    let stuck = usize::from(SLOT_ADDR[1]) + 50;
    assert_ne!(image::encode(&new)[48], 0xFF);
    let mut fb = base;
    fb.eeprom_fault = EepromFault::Stuck(stuck as u16);
    assert_eq!(store::store(&new, &mut fb), Err(StoreError::Verify));
    fb.eeprom_fault = EepromFault::None;
    assert_eq!(store::load(&mut fb), Ok(old));
}

/// STORE feeds the watchdog while it writes (each byte takes 3.3 ms on the chip).
#[test]
fn store_feeds_the_watchdog() {
    let mut rng = Rng(3);
    let mut d = SimBoard::new();
    store::store(&rng.program(), &mut d).unwrap();
    assert!(d.watchdog_feeds >= 278, "fed {} times", d.watchdog_feeds);
    assert_eq!(
        d.max_writes_between_feeds, 1,
        "at most one byte write between feeds"
    );
}

/// A slot as the version-1 firmware left it: sequence number, then the 278-byte image.
fn version_1_slot(b: &mut SimBoard, at: usize, seq: u16, prog: &Program) {
    let mut v1 = image::encode(prog)[..image::COUNTER_PRESETS_OFFSET].to_vec();
    v1[image::VERSION_OFFSET] = image::VERSION_1;
    let crc = image::crc16_ccitt(&v1);
    v1.extend_from_slice(&crc.to_be_bytes());
    b.eeprom[at..at + 2].copy_from_slice(&seq.to_le_bytes());
    b.eeprom[at + 2..at + 2 + v1.len()].copy_from_slice(&v1);
}

#[test]
fn version_1_slots_load_and_the_next_store_writes_version_2_beside_them() {
    let mut rng = Rng(77);
    let old = rng.program();
    let mut b = SimBoard::new();
    version_1_slot(&mut b, 0, 7, &old);
    assert_eq!(
        store::load(&mut b),
        Ok(old.clone()),
        "counter presets and set-points 0"
    );
    // STORE goes to the other slot, as version 2; the version-1 slot stays as it was.
    let new = rng.program_v2();
    let slot0: Vec<u8> = b.eeprom[..280].to_vec();
    store::store(&new, &mut b).unwrap();
    assert_eq!(&b.eeprom[..280], &slot0[..]);
    assert_eq!(slot_image(&b, 1), &image::encode(&new)[..]);
    assert_eq!(store::load(&mut b), Ok(new.clone()));
    // The next STORE overwrites the version-1 slot with a whole version-2 image.
    let newer = rng.program_v2();
    store::store(&newer, &mut b).unwrap();
    assert_eq!(slot_image(&b, 0), &image::encode(&newer)[..]);
    assert_eq!(store::load(&mut b), Ok(newer));
}

#[test]
fn a_stored_set_point_above_1023_makes_the_slot_invalid() {
    let mut b = SimBoard::new();
    let mut p = Program::blank();
    p.set_points = [1023, 0];
    store::store(&p, &mut b).unwrap();
    assert_eq!(store::load(&mut b), Ok(p.clone()));
    // 1024 with a CRC that matches (only a damaged or foreign EEPROM holds that).
    let mut img = image::encode(&p);
    img[image::SET_POINTS_OFFSET..image::SET_POINTS_OFFSET + 2]
        .copy_from_slice(&1024u16.to_be_bytes());
    let crc = image::crc16_ccitt(&img[..image::CRC_OFFSET]);
    img[image::CRC_OFFSET..].copy_from_slice(&crc.to_be_bytes());
    b.eeprom[2..2 + image::IMAGE_LEN].copy_from_slice(&img);
    assert_eq!(store::load(&mut b), Err(store::LoadError::NoValidImage));
}
