//! `utile asm` / `dis` / `fmt`: the listing format, every error message, and round trips.

mod support;

use support::utile::*;
use utile_core::engine::Program;
use utile_core::opcodes::{self, BLANK, NOP};
use utile_kit::listing;

/// `asm` of a listing must fail with exactly these `file:line: problem` lines.
fn expect_errors(text: &str, expected: &[(usize, &str)]) {
    let path = write_scratch("bad.utl", text);
    let hex = scratch("bad.hex");
    let err = utile_err(&["asm", &path, "-o", hex.to_str().unwrap()]);
    let want: Vec<String> = expected
        .iter()
        .map(|(l, m)| format!("{path}:{l}: {m}"))
        .collect();
    let got: Vec<&str> = err.lines().collect();
    assert_eq!(got, want, "listing:\n{text}");
    assert!(
        !hex.exists(),
        "no image may be written when the listing has errors"
    );
}

#[test]
fn unknown_word() {
    expect_errors("000 A0.\nFOO\n", &[(2, "unknown word 'FOO'")]);
    // Interpreter commands are not program lines; near misses of names are not commands.
    expect_errors(
        "RUN\nA6.\n.Y8\nQ0\n",
        &[
            (1, "unknown word 'RUN'"),
            (2, "unknown word 'A6.'"),
            (3, "unknown word '.Y8'"),
            (4, "unknown word 'Q0'"),
        ],
    );
}

#[test]
fn line_numbers_out_of_range_or_alone() {
    expect_errors("256 AND\n", &[(1, "line number 256 is past 255")]);
    expect_errors(
        "# c\n99999999999999999999999 AND\n",
        &[(2, "line number 99999999999999999999999 is past 255")],
    );
    expect_errors("012\n", &[(1, "line number 012 without a command")]);
    expect_errors(
        "255 END\nNOP\n",
        &[(2, "no room for 'NOP': line 256 is past 255")],
    );
}

#[test]
fn two_commands_for_one_line() {
    expect_errors(
        "005 AND\n\n005 OR\n",
        &[(3, "two commands for line 005 (first on line 1)")],
    );
    // An unnumbered line follows the previous command and can collide too.
    expect_errors(
        "001 AND\n000 SET\nCLR\n",
        &[(3, "two commands for line 001 (first on line 1)")],
    );
}

#[test]
fn extra_text_and_fill_with_number() {
    expect_errors(
        "A0. .Y0\n",
        &[(1, "extra text '.Y0' after 'A0.' (one command per line)")],
    );
    expect_errors("003 FILL\n", &[(1, "FILL takes no line number")]);
    expect_errors(
        "$1\n$XYZ\n",
        &[
            (1, "bad raw byte '$1' (expected $00..$FF)"),
            (2, "bad raw byte '$XYZ' (expected $00..$FF)"),
        ],
    );
}

#[test]
fn preset_errors() {
    expect_errors("T4 = 256\n", &[(1, "preset T4 = 256 is past 255")]);
    expect_errors(
        "TG = 5\nT10 = 5\nX = 1\n = 3\n",
        &[
            (
                1,
                "bad setting name 'TG' (expected T0..TF, C0..C7, S6 or S7)",
            ),
            (
                2,
                "bad setting name 'T10' (expected T0..TF, C0..C7, S6 or S7)",
            ),
            (
                3,
                "bad setting name 'X' (expected T0..TF, C0..C7, S6 or S7)",
            ),
            (4, "bad setting name '' (expected T0..TF, C0..C7, S6 or S7)"),
        ],
    );
    expect_errors(
        "T1 = abc\nT2 = -1\nT3 =\n",
        &[
            (1, "bad preset value 'abc' for T1 (expected 0..255)"),
            (2, "bad preset value '-1' for T2 (expected 0..255)"),
            (3, "bad preset value '' for T3 (expected 0..255)"),
        ],
    );
    expect_errors(
        "tf = 1\n\nTF = 2\n",
        &[(3, "timer TF preset given twice (first on line 1)")],
    );
}

#[test]
fn all_errors_are_reported_in_one_run() {
    expect_errors(
        "A0.\nBAD\n300 AND\nT0 = 999\n.Y0\n",
        &[
            (2, "unknown word 'BAD'"),
            (3, "line number 300 is past 255"),
            (4, "preset T0 = 999 is past 255"),
        ],
    );
}

#[test]
fn accepted_forms() {
    let text = "\
; semicolon comment
# hash comment

000 al0.        # lower case
2dup            # a command that starts with a digit is not a line number
010 .tk0 ; trailing comment
.....           # explicit blank line 11
$1F             # raw unassigned byte
tf=255
T4 = 5
t0 = 0
";
    let prog = listing::parse("ok.utl", text).expect("valid listing");
    assert_eq!(prog.uf[0], opcodes::lookup(b"AL0.").unwrap());
    assert_eq!(prog.uf[1], opcodes::DUP2);
    assert_eq!(prog.uf[10], opcodes::POP_TK);
    assert_eq!(prog.uf[11], BLANK);
    assert_eq!(prog.uf[12], 0x1F);
    assert!(
        prog.uf[2..10].iter().all(|&b| b == BLANK),
        "unlisted lines stay blank"
    );
    assert!(prog.uf[13..].iter().all(|&b| b == BLANK));
    assert_eq!(prog.presets[15], 255);
    assert_eq!(prog.presets[4], 5);
    assert_eq!(prog.presets.iter().filter(|&&p| p != 0).count(), 2);
}

#[test]
fn fill_makes_unlisted_lines_nop() {
    let prog = listing::parse("f.utl", "003 END\nFILL\n005 .....\n").unwrap();
    assert_eq!(prog.uf[3], opcodes::END);
    assert_eq!(prog.uf[5], BLANK, "an explicit blank stays blank");
    for (i, &op) in prog.uf.iter().enumerate() {
        if i != 3 && i != 5 {
            assert_eq!(op, NOP, "line {i}");
        }
    }
}

/// The editor's LIST prints `NNN NAME` for every non-blank line and `Tm = v` presets.
#[test]
fn list_output_is_a_listing() {
    let list = "000 A0.\r\n001 .Y0\r\n002 END\r\n100 NOP\r\nT0 = 50\r\nTF = 1\r\n";
    let prog = listing::parse("list.txt", list).unwrap();
    let mut want = Program::blank();
    want.uf[0] = opcodes::PUSH_A;
    want.uf[1] = opcodes::POP_Y;
    want.uf[2] = opcodes::END;
    want.uf[100] = NOP;
    want.presets[0] = 50;
    want.presets[15] = 1;
    assert_eq!(prog, want);
    assert_eq!(listing::print(&prog), list.replace("\r\n", "\n"));
}

/// A program that uses every byte value on some line and every preset.
fn every_byte_program() -> Program {
    let mut prog = Program::blank();
    for (i, op) in prog.uf.iter_mut().enumerate() {
        *op = (i as u8).wrapping_mul(7).wrapping_add(3); // a permutation of 0..=255
    }
    for (m, p) in prog.presets.iter_mut().enumerate() {
        *p = (m as u8) * 17;
    }
    prog
}

#[test]
fn dis_then_asm_is_byte_identical() {
    let prog = every_byte_program();
    assert!(prog.uf.contains(&BLANK) && prog.uf.contains(&0x1F) && prog.uf.contains(&NOP));
    let hex = listing::to_hex(&prog);
    let hex_path = scratch("every.hex");
    std::fs::write(&hex_path, &hex).unwrap();
    let utl_path = scratch("every.utl");
    utile_ok(&[
        "dis",
        hex_path.to_str().unwrap(),
        "-o",
        utl_path.to_str().unwrap(),
    ]);
    let again = scratch("again.hex");
    utile_ok(&[
        "asm",
        utl_path.to_str().unwrap(),
        "-o",
        again.to_str().unwrap(),
    ]);
    assert_eq!(std::fs::read(&again).unwrap(), hex);
    // dis to stdout gives the same canonical listing as dis -o.
    assert_eq!(
        utile_ok(&["dis", hex_path.to_str().unwrap()]),
        std::fs::read_to_string(&utl_path).unwrap()
    );
}

#[test]
fn asm_then_dis_gives_the_canonical_listing() {
    for stem in example_stems() {
        let src = example(&format!("{stem}.utl"));
        let hex = scratch(&format!("{stem}.hex"));
        utile_ok(&["asm", &src, "-o", hex.to_str().unwrap()]);
        let dis = utile_ok(&["dis", hex.to_str().unwrap()]);
        let canonical = utile_ok(&["fmt", &src]);
        assert_eq!(dis, canonical, "{stem}");
        // The canonical listing is a fixed point.
        let dis_path = write_scratch("canon.utl", &dis);
        assert_eq!(utile_ok(&["fmt", &dis_path]), dis, "{stem}");
        // It says the same program as the source.
        let text = std::fs::read_to_string(&src).unwrap();
        assert_eq!(listing::parse(&stem, &dis), listing::parse(&stem, &text));
        // Every line is `NNN NAME`, `Tm = v`, `Cm = v` or `Sn = v`.
        for l in dis.lines() {
            let ok = (l.len() > 4
                && l.as_bytes()[..3].iter().all(u8::is_ascii_digit)
                && &l[3..4] == " ")
                || (l.starts_with(['T', 'C', 'S']) && l.contains(" = "));
            assert!(ok, "{stem}: {l}");
        }
    }
}

#[test]
fn asm_writes_the_image_as_write_sends_it() {
    let src = example("11.1-push-button-timer.utl");
    let hex = scratch("wr.hex");
    utile_ok(&["asm", &src, "-o", hex.to_str().unwrap()]);
    let text = std::fs::read_to_string(&hex).unwrap();
    assert!(text.ends_with(":00000001FF\r\n"), "EOF record last");
    let records: Vec<&str> = text.split_terminator("\r\n").collect();
    assert!(
        !text.replace("\r\n", "").contains('\n'),
        "CR LF line ends only"
    );
    let mut addr = 0usize;
    for r in &records[..records.len() - 1] {
        assert_eq!(r, &r.to_ascii_uppercase(), "upper case");
        let len = usize::from_str_radix(&r[1..3], 16).unwrap();
        assert_eq!(
            usize::from_str_radix(&r[3..7], 16).unwrap(),
            addr,
            "records in order from 0"
        );
        assert!(
            len == 16 || addr + len == utile_core::image::IMAGE_LEN,
            "16-byte records"
        );
        addr += len;
    }
    assert_eq!(addr, utile_core::image::IMAGE_LEN);
    // The default output name is the listing's with .hex.
    let copy = write_scratch("default.utl", &std::fs::read_to_string(&src).unwrap());
    utile_ok(&["asm", &copy]);
    let default_hex = copy.replace(".utl", ".hex");
    assert_eq!(std::fs::read_to_string(default_hex).unwrap(), text);
}

#[test]
fn dis_refuses_bad_hex_files() {
    let prog = every_byte_program();
    let good = String::from_utf8(listing::to_hex(&prog)).unwrap();

    let truncated = write_scratch("trunc.hex", &good[..good.len() - ":00000001FF\r\n".len()]);
    assert_eq!(
        utile_err(&["dis", &truncated]).trim(),
        format!("{truncated}: no end-of-file record")
    );

    // Flip one data digit of the first record: its checksum no longer matches.
    let mut bad = good.clone().into_bytes();
    bad[9] = if bad[9] == b'0' { b'1' } else { b'0' };
    let bad_sum = write_scratch("sum.hex", std::str::from_utf8(&bad).unwrap());
    assert_eq!(
        utile_err(&["dis", &bad_sum]).trim(),
        format!("{bad_sum}: a record checksum does not match")
    );

    let missing = scratch("missing.hex");
    let err = utile_err(&["dis", missing.to_str().unwrap()]);
    assert!(err.starts_with(missing.to_str().unwrap()), "{err}");
}

#[test]
fn usage_errors() {
    // clap's words (tests/cli.rs checks the exit status 2 of each).
    assert!(utile_err(&[]).contains("Usage: utile <COMMAND>"));
    assert!(utile_err(&["frobnicate"]).contains("unrecognized subcommand 'frobnicate'"));
    assert!(utile_err(&["asm"]).contains("required arguments were not provided"));
    assert!(utile_err(&["asm", "a.utl", "b.utl"]).contains("unexpected argument 'b.utl'"));
    assert!(utile_err(&["asm", "a.utl", "--bogus", "1"]).contains("unexpected argument '--bogus'"));
    assert!(utile_err(&["asm", "a.utl", "-o"]).contains("a value is required for '-o <PROG.hex>'"));
}
