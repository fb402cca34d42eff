//! Replays the fuzz corpus (`fuzz/corpus/<target>/`) through the same harnesses the
//! cargo-fuzz targets call (`utile_kit::fuzzing`), so the README's test command checks every
//! seed and every crash input ever saved, without libFuzzer.
//!
//! The seeds are made by `write_seed_corpus` (ignored; run it with
//! `cargo test --test fuzz_replay -- --ignored write_seed_corpus` to regenerate them).

use std::num::NonZeroU16;
use std::path::{Path, PathBuf};

use utile_core::engine::Program;
use utile_core::ihex::write_hex;
use utile_core::image::{encode, IMAGE_LEN};
use utile_kit::fuzzing::{self, sample_program, TARGETS};
use utile_kit::listing;
use utile_kit::rng::Rng;
use utile_kit::sim::SimBoard;

fn corpus_dir(target: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target)
}

fn files(target: &str) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(corpus_dir(target))
        .unwrap_or_else(|e| panic!("fuzz/corpus/{target}: {e}"))
        .map(|e| e.expect("directory entry").path())
        .filter(|p| p.is_file())
        .collect();
    v.sort();
    v
}

#[test]
fn every_corpus_file_keeps_every_invariant() {
    let mut failures = Vec::new();
    for (target, harness) in TARGETS {
        let files = files(target);
        assert!(
            files.len() >= 3,
            "fuzz/corpus/{target} has only {} files",
            files.len()
        );
        for f in files {
            let data = std::fs::read(&f).expect("read corpus file");
            if let Err(why) = harness(&data) {
                failures.push(format!("{}: {why}", f.display()));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The terminal model of the harness agrees with a real VT100 emulator (`vt100`, 80×24)
/// on where the cursor ends, for every editor seed.
#[test]
fn the_terminal_model_agrees_with_vt100() {
    let size = |n| NonZeroU16::new(n).expect("non-zero");
    for f in files("editor") {
        let data = std::fs::read(&f).expect("read corpus file");
        let main_loop =
            fuzzing::editor_loop(&data).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let mut p = vt100::Parser::new(size(24), size(80), 0);
        p.process(&main_loop.transcript);
        let (row, col) = p.screen().cursor_position();
        let want_col = main_loop.term.col.min(80);
        assert_eq!(
            (row + 1, col + 1),
            (u16::from(main_loop.term.row), u16::from(want_col)),
            "{}",
            f.display()
        );
        assert!(
            main_loop.term.violation.is_none(),
            "{}: {:?}",
            f.display(),
            main_loop.term.violation
        );
    }
}

/// The checks do fail on broken behaviour: off-screen addresses, writes past column 80,
/// scrolls; and a program that never reads KEY is told apart from a lock-up.
#[test]
fn the_checks_can_fail() {
    let mut t = fuzzing::Term::new();
    t.feed(b"\x1b[25;1H", false);
    assert!(t.violation.is_some(), "row 25 must be refused");
    let mut t = fuzzing::Term::new();
    t.feed(b"\x1b[1;80Hxy", false);
    assert!(
        t.violation.is_some(),
        "a character past column 80 must be refused"
    );
    let mut t = fuzzing::Term::new();
    t.feed(b"\x1b[24H\r\n", false);
    assert!(t.violation.is_some(), "a scroll must be refused");

    // A running program without KEY cannot be stopped by the recovery keys: reported as
    // such, not as a lock-up.
    let mut endless = Program::blank();
    endless.uf[0] = utile_core::opcodes::END;
    let mut main_loop = fuzzing::MainLoop::autostart(&endless).expect("autostart");
    assert_eq!(main_loop.recover_and_fill(), Ok(false));
    assert!(fuzzing::image_decode(&[0u8; IMAGE_LEN]).is_ok());
    assert!(fuzzing::ihex(b":00000001FF").is_ok());
}

// ---------------------------------------------------------------------------------------
// The seed corpus.
// ---------------------------------------------------------------------------------------

fn cat(parts: &[&[u8]]) -> Vec<u8> {
    parts.concat()
}

fn write(target: &str, name: &str, data: &[u8]) {
    let dir = corpus_dir(target);
    std::fs::create_dir_all(&dir).expect("create corpus dir");
    std::fs::write(dir.join(name), data).expect("write seed");
}

#[test]
#[ignore = "regenerates the committed seed corpus"]
fn write_seed_corpus() {
    let prog = sample_program();
    let hex = listing::to_hex(&prog);
    let lower = hex.to_ascii_lowercase();
    let mut bad_sum = hex.clone();
    bad_sum[10] = if bad_sum[10] == b'0' { b'1' } else { b'0' };
    let truncated = hex[..hex.len() / 2].to_vec();
    let no_eof = hex[..hex.len() - 13].to_vec();
    let mut other_version = encode(&prog);
    other_version[2] = 2;
    let mut v2_text = Vec::new();
    write_hex(&other_version, &mut |c| v2_text.push(c));

    // editor: first byte = flags (0x80 autostart, 0x40 sample program, 0x20 busy
    // transmitter, 0x10 READ time-outs).
    let editor: &[(&str, Vec<u8>)] = &[
        ("commands", cat(&[b"\x00", b"a0.\r.y0\rclka.\r.y7\rend\r"])),
        ("help", cat(&[b"\x00", b"?\rx"])),
        ("ldt", cat(&[b"\x00", b"ldt\r5\r300\r\x1b[C7\rz\r\x1b[D\r"])),
        (
            "arrows",
            cat(&[
                b"\x40",
                b"\x1b[A\x1b[B\x1b[C\x1b[D\x1bOA\x1bOD\x1b[1~\x1b[H\x1bH\x1b[7~",
            ]),
        ),
        (
            "ins_del_keys",
            cat(&[b"\x40", b"\x1b[B\x1b[2~\x1b[3~\x1b[3~"]),
        ),
        ("fill_ins_del", cat(&[b"\x40", b"5\rins\rdel\rfill\r"])),
        (
            "run_key_break",
            cat(&[b"\x40", b"\x1b[A\x1b[Brun\rxy/zstat\r"]),
        ),
        ("ex0", cat(&[b"\x40", b"ex0\r12/q"])),
        ("autostart", cat(&[b"\x80", b"abc/x?\r "])),
        ("autostart_busy_tx", cat(&[b"\xa0", b"......../x"])),
        ("read_good", cat(&[b"\x00", b"read\r", &hex, b"\r"])),
        ("read_lower", cat(&[b"\x00", b"read\r\r\n", &lower, b"\r"])),
        (
            "read_bad_checksum",
            cat(&[b"\x00", b"read\r", &bad_sum, b"\r"]),
        ),
        ("read_truncated", cat(&[b"\x10", b"read\r", &truncated])),
        ("read_no_eof", cat(&[b"\x10", b"read\r", &no_eof, b"\r"])),
        ("read_version2", cat(&[b"\x00", b"read\r", &v2_text, b"\r"])),
        ("read_abort", cat(&[b"\x00", b"read\r:1000/\r"])),
        ("write", cat(&[b"\x40", b"write\r\r\r"])),
        ("list", cat(&[b"\x40", b"list\r\r\r"])),
        ("list_abort", cat(&[b"\x40", b"list\r/"])),
        ("store_load", cat(&[b"\x40", b"store\rfill\rload\r"])),
        ("load_empty", cat(&[b"\x00", b"load\r"])),
        ("overlong", cat(&[b"\x00", b"abcdefghijk\r99999\r65535\r"])),
        ("erase", cat(&[b"\x00", b"a0x\x08\x7f.\x18set\r"])),
        ("crlf", cat(&[b"\x00", b"set\r\n.y7\n\r\n\n"])),
        (
            "broken_escapes",
            cat(&[b"\x00", b"\x1b[\rset\x1bend\r\x1b[END\r\x1b[15~\x1b[1;5P"]),
        ),
        ("stat_ver", cat(&[b"\x00", b"stat\rver\r/\r"])),
        ("noise", {
            let mut rng = Rng::new(200);
            (0..200).map(|_| rng.byte()).collect()
        }),
    ];
    for (name, data) in editor {
        write("editor", name, data);
    }

    let lines: &[(&str, &[u8])] = &[
        ("program", b"a0.\n.tk0\na1.\n.tr0\ntq0.\n.y0\nend"),
        ("interpreter", b"?\nver\nstat\n/\nins\ndel\nfill"),
        ("ldt", b"ldt\n5\n300\n  z \n7\n\nset"),
        ("numbers", b"0\n65535\n65536\n99999999\n007"),
        ("overlong", b"123456789\nabcdefghi\n  set   \n set x"),
        ("transfer", b"list\nwrite\nread\nset"),
        ("store_load", b"set\nstore\nfill\nload"),
        ("run", b"a0.\nrun"),
        ("key_ex0", b"key\nend\nex0"),
    ];
    for (name, data) in lines {
        write("lines", name, data);
    }

    let keys: &[(&str, &[u8])] = &[
        (
            "arrows",
            b"\x1b[A\x1b[B\x1b[C\x1b[D\x1bOA\x1bOB\x1bOC\x1bOD",
        ),
        (
            "home_ins_del",
            b"\x1b[1~\x1b[7~\x1b[H\x1bOH\x1bH\x1b[2~\x1b[3~",
        ),
        ("params", b"\x1b[1;5C\x1b[15~\x1b[1;5P\x1b[?25h"),
        ("broken", b"\x1bend\x1b[\r\x1b[END\x1b\x1b[A"),
        ("overlong", b"\x1b[1111111111111111A"),
        ("slow", b"\x1b\xff\xc8O\x1b[\xff\x10A"),
        ("plain", b"set\r.y7\r"),
    ];
    for (name, data) in keys {
        write("keys", name, data);
    }

    let mut gap = Vec::new();
    let mut skip = hex.clone();
    // Drop the second record: a gap in the addresses.
    let first_end = skip.iter().position(|&c| c == b'\n').unwrap() + 1;
    let second_end = first_end + skip[first_end..].iter().position(|&c| c == b'\n').unwrap() + 1;
    skip.drain(first_end..second_end);
    gap.extend_from_slice(&skip);
    let ihex_seeds: &[(&str, Vec<u8>)] = &[
        ("valid", hex.clone()),
        ("lower", lower.clone()),
        ("screen_before", cat(&[b"Reading file ...\r\n\r\n", &hex])),
        ("bad_checksum", bad_sum.clone()),
        ("truncated", truncated.clone()),
        ("gap", gap),
        ("eof_only", b":00000001FF\r\n".to_vec()),
        ("bad_type", b":0000000200FE\r\n".to_vec()),
        ("overlong_record", b":0100000000FF00\r\n".to_vec()),
        ("bad_char", b":01000000GG\r\n".to_vec()),
        ("version2", v2_text.clone()),
    ];
    for (name, data) in ihex_seeds {
        write("ihex", name, data);
    }

    let mut blank_like = vec![0u8; 272];
    blank_like[..4].copy_from_slice(&[1, 2, 3, 4]);
    write("hex_roundtrip", "blank", &vec![0xFF; 272]);
    write("hex_roundtrip", "zeros", &blank_like);
    write("hex_roundtrip", "sample", &encode(&prog)[4..276]);

    let img = encode(&prog).to_vec();
    let mut bad_crc = img.clone();
    bad_crc[IMAGE_LEN - 1] ^= 1;
    let mut bad_magic = img.clone();
    bad_magic[0] = b'x';
    write("image", "valid", &img);
    write("image", "blank", &encode(&Program::blank()));
    write("image", "bad_crc", &bad_crc);
    write("image", "bad_magic", &bad_magic);
    write("image", "version2", &other_version);
    write("image", "short", &img[..IMAGE_LEN - 1]);

    let mut board = SimBoard::new();
    utile_core::store::store(&prog, &mut board).unwrap();
    let one_slot: Vec<u8> = board.eeprom[..560].to_vec();
    let mut p2 = prog.clone();
    p2.presets[3] = 9;
    utile_core::store::store(&p2, &mut board).unwrap();
    let two_slots = cat(&[&board.eeprom[..280], &board.eeprom[0x200..0x200 + 280]]);
    let mut damaged = two_slots.clone();
    damaged[300] ^= 0x40;
    write("eeprom", "erased", &[0xFF; 560]);
    write("eeprom", "one_slot", &one_slot);
    write("eeprom", "two_slots", &two_slots);
    write("eeprom", "newest_damaged", &damaged);
    write("eeprom", "zeros", &[0u8; 600]);
}
