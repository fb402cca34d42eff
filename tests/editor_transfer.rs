//! STORE, LOAD, WRITE and READ from the editor (SPEC §9, §10).

mod support;

use support::editor::Session;
use utile_core::opcodes::{lookup, END};

fn with_program() -> Session {
    let mut r = Session::new();
    r.enter("fill");
    r.enter("A0.");
    r.enter(".Y0");
    r.enter("END");
    r.eng.prog.presets[0] = 1;
    r.eng.prog.presets[2] = 255;
    r
}

/// WRITE's output: the hex text between the CR that starts it and the end record.
fn write_file(r: &mut Session) -> Vec<u8> {
    r.enter("write");
    assert!(r
        .text()
        .contains("File write .... 'CR' to send .... '/' to abort"));
    let start = r.sent();
    r.type_bytes(b"\r");
    let file = r.b.tx_log[start..].to_vec();
    r.type_bytes(b"\r");
    assert_eq!(r.status(), " *** User File 0 ***");
    file
}

#[test]
fn write_sends_intel_hex_and_read_takes_it_back_bit_exactly() {
    let mut r = with_program();
    let file = write_file(&mut r);
    let text = String::from_utf8(file.clone()).unwrap();
    assert!(text.starts_with(":10000000"), "{text}");
    assert!(text.ends_with(":00000001FF\r\n"));
    assert!(!text.contains('\x1b'));
    for line in text.split("\r\n").filter(|l| !l.is_empty()) {
        assert!(
            line.starts_with(':')
                && line[1..]
                    .chars()
                    .all(|c| c.is_ascii_hexdigit() && !c.is_ascii_lowercase())
        );
    }
    let saved = r.eng.prog.clone();

    // Change the program, then READ the file back.
    r.enter("fill");
    r.eng.prog.presets = [0; 16];
    r.enter("read");
    assert!(r.text().contains("Reading file ...... '/' to abort"));
    r.type_bytes(&file);
    r.wait_ms(250);
    assert!(
        r.status()
            .contains("File read completed - 'CR' for menu -->"),
        "{}",
        r.status()
    );
    assert_eq!(r.eng.prog, saved);
    r.type_bytes(b"\r");
    assert_eq!(r.status(), " *** User File 0 ***");
    assert_eq!(r.entry(0), "000 A0.");
    assert_eq!(r.entry(2), "002 END");
}

#[test]
fn a_bad_file_changes_nothing_and_its_rest_is_drained() {
    let mut r = with_program();
    let file = write_file(&mut r);
    let saved = r.eng.prog.clone();
    // Corrupt one data digit of the second record (checksum then fails).
    let mut bad = file.clone();
    let second = bad
        .iter()
        .enumerate()
        .filter(|(_, &c)| c == b':')
        .nth(1)
        .unwrap()
        .0;
    bad[second + 12] = if bad[second + 12] == b'0' { b'1' } else { b'0' };
    // The file is followed at once by lines that look like commands.
    bad.extend_from_slice(b"fill\r");
    r.enter("read");
    r.type_bytes(&bad);
    r.wait_ms(150);
    r.type_bytes(b"FILL\r");
    r.wait_ms(250);
    let status = r.status();
    assert!(status.contains("Read error! - "), "{status}");
    assert!(status.ends_with("'CR' for menu -->"), "{status}");
    assert_eq!(
        r.eng.prog, saved,
        "nothing changed, the drained lines were not run"
    );
    r.type_bytes(b"x\r");
    assert_eq!(r.status(), " *** User File 0 ***");
    assert_eq!(r.eng.prog, saved);
}

#[test]
fn a_file_without_end_record_times_out_after_3_s() {
    let mut r = with_program();
    let file = write_file(&mut r);
    let saved = r.eng.prog.clone();
    let cut = String::from_utf8(file)
        .unwrap()
        .replace(":00000001FF\r\n", "");
    r.enter("read");
    r.type_bytes(cut.as_bytes());
    r.wait_ms(2900);
    assert!(!r.status().contains("Read error"));
    r.wait_ms(400);
    assert!(
        r.status()
            .contains("Read error! - no end record (time-out) - 'CR' for menu -->"),
        "{}",
        r.status()
    );
    assert_eq!(r.eng.prog, saved);
    r.type_bytes(b"\r");
    assert_eq!(r.entry(0), "000 A0.");
}

#[test]
fn read_aborts_on_slash() {
    let mut r = with_program();
    let saved = r.eng.prog.clone();
    r.enter("read");
    r.type_bytes(b"/");
    r.wait_ms(250);
    assert!(
        r.status().contains("Read error! - aborted"),
        "{}",
        r.status()
    );
    r.type_bytes(b"\r");
    assert_eq!(r.eng.prog, saved);
    assert_eq!(r.status(), " *** User File 0 ***");
}

#[test]
fn write_aborts_on_slash_without_sending() {
    let mut r = with_program();
    r.enter("write");
    let start = r.sent();
    r.type_bytes(b"x/");
    let out = &r.b.tx_log[start..];
    assert!(!out.windows(3).any(|w| w == b":10"));
    assert_eq!(r.status(), " *** User File 0 ***");
    assert_eq!(r.entry(0), "000 A0.");
}

#[test]
fn store_and_load() {
    let mut r = Session::new();
    // Nothing stored yet: LOAD says so and changes nothing.
    r.enter("fill");
    r.enter("load");
    assert!(
        r.status().contains("No stored program - nothing loaded"),
        "{}",
        r.status()
    );
    assert!(r.eng.prog.uf.iter().all(|&op| op == 0));

    r.enter("END");
    r.eng.prog.presets[3] = 9;
    r.enter("store");
    assert!(
        r.status().contains("UF0 stored in EEPROM"),
        "{}",
        r.status()
    );
    let saved = r.eng.prog.clone();
    r.enter("fill");
    r.eng.prog.presets[3] = 0;
    r.enter("load");
    assert!(
        r.status().contains("UF0 loaded from EEPROM"),
        "{}",
        r.status()
    );
    assert_eq!(r.eng.prog, saved);
    assert_eq!(r.entry(0), "000 END");
    assert_eq!(r.eng.prog.uf[0], END);
    assert_eq!(lookup(b"END"), Some(END));
}
