//! Programs as text: the `.utl` listing format, and the hex image that WRITE sends.
//!
//! A listing holds one command per line, in the editor's spelling (any case):
//!
//! ```text
//! # Push-button switch and timer (manual 11.1)
//! FILL            # lines not given are NOP (without FILL they stay blank)
//! 000 AL0.        # a 3-digit line number puts the command on that line
//! DUP             # no number: the line after the previous command
//! T0 = 50         # timer preset, T0..TF, 0..255
//! C0 = 100        # counter preset, C0..C7, 0..65535 (image format 2)
//! S6 = 512        # analog set-point, S6 or S7, 0..1023 (image format 2)
//! ```
//!
//! `#` or `;` start a comment. `.....` is an explicit blank line and `$1F` a raw byte (an
//! unassigned opcode, which runs as NOP); [`print`] uses it only for such bytes. LIST's output
//! (`NNN NAME` lines, then `Tm = value`, `Cm = value` and `Sn = value` lines) is a valid
//! listing.

use std::fmt;
use std::string::String;
use std::vec::Vec;

use utile_core::engine::{Program, COUNTERS, LINES, SET_POINTS, UNITS};
use utile_core::hex;
use utile_core::ihex::{write_hex, HexError, HexEvent, HexReader};
use utile_core::image::{self, ImageError};
use utile_core::opcodes::{self, BLANK, NOP};

/// One problem found in a text file, at a 1-based line of that file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    /// Line of the text file (1-based).
    pub line: usize,
    /// What is wrong, in words.
    pub message: String,
}

/// All problems found in one file; shown as `file:line: problem`, one per line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileErrors {
    /// The file's name as the user gave it.
    pub file: String,
    /// The problems, in file order.
    pub problems: Vec<Problem>,
}

impl fmt::Display for FileErrors {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, p) in self.problems.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{}:{}: {}", self.file, p.line, p.message)?;
        }
        Ok(())
    }
}

impl std::error::Error for FileErrors {}

/// The text of a line without its comment (`#` or `;` to the end of the line).
pub(crate) fn strip_comment(line: &str) -> &str {
    match line.find(['#', ';']) {
        Some(i) => &line[..i],
        None => line,
    }
}

/// The value of a one-character hex digit (either case).
fn hex_digit(s: &str) -> Option<u8> {
    match s.as_bytes() {
        &[c] => hex::value(c),
        _ => None,
    }
}

/// Parse a listing. `file` names it in error messages.
///
/// Lines the listing does not give are blank (0xFF, shown `.....`, run as NOP), or NOP when
/// the listing contains `FILL` anywhere (as if typed after the editor's FILL command).
pub fn parse(file: &str, text: &str) -> Result<Program, FileErrors> {
    let mut prog = Program::blank();
    // Where each UF line and preset was given (text line), to report duplicates.
    let mut line_src: [Option<usize>; LINES] = [None; LINES];
    let mut preset_src: [Option<usize>; UNITS] = [None; UNITS];
    let mut counter_src: [Option<usize>; COUNTERS] = [None; COUNTERS];
    let mut set_point_src: [Option<usize>; SET_POINTS] = [None; SET_POINTS];
    let mut fill = false;
    let mut next: usize = 0;
    let mut problems = Vec::new();
    let mut problem = |line: usize, message: String| problems.push(Problem { line, message });

    for (i, raw) in text.lines().enumerate() {
        let at = i + 1;
        let body = strip_comment(raw).trim();
        if body.is_empty() {
            continue;
        }
        if let Some((name, value)) = body.split_once('=') {
            let (name, value) = (name.trim(), value.trim());
            if let Some(setting) = setting(name) {
                let (label, max, src, index) = match setting {
                    Setting::Counter(m) => ("counter preset", 65_535u64, &mut counter_src[m], m),
                    Setting::SetPoint(k) => ("set-point", 1023, &mut set_point_src[k], k),
                };
                let name = name.to_ascii_uppercase();
                let v = match value.parse::<u64>() {
                    Ok(v) if v <= max => v as u16,
                    Ok(v) => {
                        problem(at, format!("{label} {name} = {v} is past {max}"));
                        continue;
                    }
                    Err(_) => {
                        problem(
                            at,
                            format!("bad {label} value '{value}' for {name} (expected 0..{max})"),
                        );
                        continue;
                    }
                };
                if let Some(first) = *src {
                    problem(
                        at,
                        format!("{label} {name} given twice (first on line {first})"),
                    );
                    continue;
                }
                *src = Some(at);
                match setting {
                    Setting::Counter(_) => prog.counter_presets[index] = v,
                    Setting::SetPoint(_) => prog.set_points[index] = v,
                }
                continue;
            }
            let unit = name
                .strip_prefix(['T', 't'])
                .and_then(hex_digit)
                .map(usize::from)
                .filter(|&m| m < UNITS);
            let Some(m) = unit else {
                problem(
                    at,
                    format!("bad setting name '{name}' (expected T0..TF, C0..C7, S6 or S7)"),
                );
                continue;
            };
            let v = match value.parse::<u64>() {
                Ok(v) => v,
                Err(_) => {
                    problem(
                        at,
                        format!("bad preset value '{value}' for T{m:X} (expected 0..255)"),
                    );
                    continue;
                }
            };
            let Ok(v) = u8::try_from(v) else {
                problem(at, format!("preset T{m:X} = {v} is past 255"));
                continue;
            };
            if let Some(first) = preset_src[m] {
                problem(
                    at,
                    format!("timer T{m:X} preset given twice (first on line {first})"),
                );
                continue;
            }
            preset_src[m] = Some(at);
            prog.presets[m] = v;
            continue;
        }

        let mut words = body.split_whitespace();
        let mut word = words.next().unwrap_or("");
        let mut number = None;
        if word.bytes().all(|b| b.is_ascii_digit()) {
            // All digits: a line number (`2DUP` is a command, not a number).
            let n = word.parse::<u64>().unwrap_or(u64::MAX);
            if n >= LINES as u64 {
                problem(at, format!("line number {word} is past 255"));
                continue;
            }
            number = Some(n as usize);
            match words.next() {
                Some(w) => word = w,
                None => {
                    problem(at, format!("line number {word} without a command"));
                    continue;
                }
            }
        }
        if let Some(extra) = words.next() {
            problem(
                at,
                format!("extra text '{extra}' after '{word}' (one command per line)"),
            );
            continue;
        }
        if word.eq_ignore_ascii_case("FILL") {
            if number.is_some() {
                problem(at, "FILL takes no line number".into());
            } else {
                fill = true;
            }
            continue;
        }
        let op = if word == "....." {
            BLANK
        } else if let Some(hex) = word.strip_prefix('$') {
            match (hex.len(), u8::from_str_radix(hex, 16)) {
                (2, Ok(b)) => b,
                _ => {
                    problem(at, format!("bad raw byte '{word}' (expected $00..$FF)"));
                    continue;
                }
            }
        } else if let Some(op) = opcodes::lookup(word.as_bytes()) {
            op
        } else {
            problem(at, format!("unknown word '{word}'"));
            continue;
        };
        let uf_line = match number {
            Some(n) => n,
            None if next < LINES => next,
            None => {
                problem(at, format!("no room for '{word}': line 256 is past 255"));
                continue;
            }
        };
        if let Some(first) = line_src[uf_line] {
            problem(
                at,
                format!("two commands for line {uf_line:03} (first on line {first})"),
            );
            continue;
        }
        line_src[uf_line] = Some(at);
        prog.uf[uf_line] = op;
        next = uf_line + 1;
    }

    if !problems.is_empty() {
        return Err(FileErrors {
            file: file.into(),
            problems,
        });
    }
    if fill {
        for (op, src) in prog.uf.iter_mut().zip(line_src) {
            if src.is_none() {
                *op = NOP;
            }
        }
    }
    Ok(prog)
}

/// The longest listing [`check`] reads (a full program with a comment on every line fits
/// many times).
pub const MAX_LISTING: usize = 256 * 1024;

/// The problems of a listing's `text`, in [`parse`]'s words (`utile asm`'s), none when it is
/// a good listing: what an editor shows while the user types (`utile live`'s `/api/check`,
/// the playground). A text past [`MAX_LISTING`] is one problem, on line 1, and is not read.
pub fn check(text: &str) -> Vec<Problem> {
    if text.len() > MAX_LISTING {
        return vec![Problem {
            line: 1,
            message: format!(
                "the listing has {} bytes: more than {MAX_LISTING} is no uTile program",
                text.len()
            ),
        }];
    }
    match parse("listing", text) {
        Ok(_) => Vec::new(),
        Err(e) => e.problems,
    }
}

/// A program from command names (any case), from line 0 on; the other lines NOP, as after
/// FILL; presets 0. The listing of those commands, one per line, for tests and benches.
///
/// # Panics
///
/// If a name is not a command (the message says which).
pub fn commands(names: &[&str]) -> Program {
    let text = format!("FILL\n{}", names.join("\n"));
    parse("commands", &text).unwrap_or_else(|e| panic!("{e}"))
}

/// A counter preset `Cm` or an analog set-point `S6`/`S7` named on the left of `=`.
#[derive(Clone, Copy)]
enum Setting {
    Counter(usize),
    SetPoint(usize),
}

/// Which counter preset or set-point `name` is (any case), if it is one.
fn setting(name: &str) -> Option<Setting> {
    let n = name.as_bytes();
    let (&letter, &digit) = (n.first()?, n.get(1)?);
    if n.len() != 2 || !digit.is_ascii_digit() {
        return None;
    }
    let d = usize::from(digit - b'0');
    match letter.to_ascii_uppercase() {
        b'C' if d < COUNTERS => Some(Setting::Counter(d)),
        b'S' if (6..6 + SET_POINTS).contains(&d) => Some(Setting::SetPoint(d - 6)),
        _ => None,
    }
}

/// The canonical listing of a program: `NNN NAME` for every non-blank line (NOP included),
/// then `Tm = v`, `Cm = v` and `Sn = v` for every preset and set-point that is not 0.
/// Unassigned bytes are written `$XX`.
pub fn print(prog: &Program) -> String {
    let mut out = String::new();
    for (line, &op) in prog.uf.iter().enumerate() {
        if op == BLANK {
            continue;
        }
        match opcodes::name(op) {
            Some(n) => out.push_str(&format!("{line:03} {}\n", n.as_str())),
            None => out.push_str(&format!("{line:03} ${op:02X}\n")),
        }
    }
    for (m, &v) in prog.presets.iter().enumerate() {
        if v != 0 {
            out.push_str(&format!("T{m:X} = {v}\n"));
        }
    }
    for (m, &v) in prog.counter_presets.iter().enumerate() {
        if v != 0 {
            out.push_str(&format!("C{m} = {v}\n"));
        }
    }
    for (k, &v) in prog.set_points.iter().enumerate() {
        if v != 0 {
            out.push_str(&format!("S{} = {v}\n", k + 6));
        }
    }
    out
}

/// The Intel HEX text of a program, exactly as WRITE sends it.
pub fn to_hex(prog: &Program) -> Vec<u8> {
    let image = image::encode(prog);
    let mut out = Vec::new();
    write_hex(&image, &mut |b| out.push(b));
    out
}

/// Why an Intel HEX file is not a program READ would take: the hex reader's error, the
/// image's, or no end.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum HexFileError {
    /// The hex text is damaged (the core's reader says how).
    #[error("{}", hex_error_text(*.0))]
    Hex(HexError),
    /// The records are whole but the image in them is refused.
    #[error("{}", image_error_text(*.0))]
    Image(ImageError),
    /// The text ends before its end-of-file record.
    #[error("no end-of-file record")]
    NoEnd,
}

/// Words for a hex reader error.
fn hex_error_text(e: HexError) -> &'static str {
    match e {
        HexError::BadChar => "a character that is not a hex digit inside a record",
        HexError::Checksum => "a record checksum does not match",
        HexError::Address => "a record address is outside the image or leaves a gap",
        HexError::RecordType => "a record type other than data or end-of-file",
        HexError::Short => "the end-of-file record came before the whole image",
        HexError::TooLong => "a record is too long",
    }
}

/// Words for an image error.
fn image_error_text(e: ImageError) -> String {
    match e {
        ImageError::Length => "the image has the wrong length".into(),
        ImageError::Magic => "not a uTile image (wrong magic bytes)".into(),
        ImageError::Version(v) => format!("image format version {v} is not known"),
        ImageError::Crc => "the image CRC does not match (damaged)".into(),
        ImageError::Value => "an analog set-point is above 1023".into(),
    }
}

/// Read a hex file (as READ would) into a program; the error says why it was refused.
pub fn from_hex(bytes: &[u8]) -> Result<Program, HexFileError> {
    let mut reader = HexReader::new();
    for &b in bytes {
        match reader.feed(b) {
            HexEvent::More => {}
            HexEvent::Error(e) => return Err(HexFileError::Hex(e)),
            HexEvent::Done { len } => {
                let data = reader.data().get(..usize::from(len)).unwrap_or(&[]);
                return image::decode(data).map_err(HexFileError::Image);
            }
        }
    }
    Err(HexFileError::NoEnd)
}
