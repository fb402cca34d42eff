//! Reading an LDmicro file's text: the version line, the header fields, the `IO LIST`,
//! `VAR LIST` and `PULL-UP LIST` sections, and the `PROGRAM`'s rungs (`RUNG` in 0.1,
//! `RUNG 1`, `RUNG 2`… in 0.2) as trees of `SERIES` and `PARALLEL` in one arena, read
//! without recursion. Any other line is a problem: unknown means refused.

use std::string::String;
use std::vec::Vec;

use super::elements::words;
use super::{Problem, MAX_DEPTH, MAX_ELEMENTS};

/// What a node of a rung is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// Its children one after the other (a rung is one).
    Series,
    /// Its children side by side.
    Parallel,
    /// One element.
    Leaf,
}

/// One node of a rung.
#[derive(Clone, Debug)]
pub(super) struct Node {
    /// What it is.
    pub(super) kind: Kind,
    /// Its line in the file (1 is the first).
    pub(super) line: usize,
    /// A series' or parallel's nodes, in order.
    pub(super) children: Vec<usize>,
    /// A leaf's words.
    pub(super) words: Vec<String>,
}

/// One rung: its series and its line.
#[derive(Clone, Copy, Debug)]
pub(super) struct Rung {
    /// Its series' node.
    pub(super) root: usize,
    /// The line of its `RUNG`.
    pub(super) line: usize,
    /// Past the limits: read, not lowered.
    pub(super) skipped: bool,
}

/// An LDmicro file read.
#[derive(Debug, Default)]
pub(super) struct File {
    /// Every rung's nodes, in the file's order.
    pub(super) nodes: Vec<Node>,
    /// The rungs in order.
    pub(super) rungs: Vec<Rung>,
    /// The IO LIST's inputs (`X…`) and outputs (`Y…`) in its order.
    pub(super) inputs: Vec<String>,
    /// See [`File::inputs`].
    pub(super) outputs: Vec<String>,
    /// Every element and subcircuit the file has (past [`MAX_ELEMENTS`] not kept).
    pub(super) elements: usize,
}

/// The header fields LDmicro writes before its sections (`MICRO=…`, `CYCLE=10000 us at
/// Timer1, …`): uTile's own pins and timing replace them. The Boolean: its value starts
/// with a digit.
const HEADER: &[(&str, bool)] = &[
    ("MICRO=", false),
    ("CYCLE=", true),
    ("CRYSTAL=", true),
    ("BAUD=", true),
    ("COMPILED=", false),
    ("COMPILER=", false),
];

/// The lines of a file: (line number, trimmed text), blank ones left out.
type Lines<'a> = std::vec::IntoIter<(usize, &'a str)>;

fn numbered(text: &str) -> Lines<'_> {
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|l| !l.1.is_empty())
        .collect();
    lines.into_iter()
}

/// Read `text` (its first line `LDmicro0.1` or `LDmicro0.2`, checked by the caller).
pub(super) fn read(text: &str, problems: &mut Vec<Problem>) -> File {
    let mut lines = numbered(text);
    lines.next();
    let mut file = File::default();
    let mut program = false;
    let mut stray = Stray::new(0, "is not a line of an LDmicro file (its header fields, IO LIST, VAR LIST, PULL-UP LIST, PROGRAM)", "that are not lines of an LDmicro file");
    while let Some((no, line)) = lines.next() {
        if !header(line) && !matches!(line, "IO LIST" | "VAR LIST" | "PULL-UP LIST" | "PROGRAM") {
            stray.add(no, line);
            continue;
        }
        stray.flush(problems);
        match line {
            "IO LIST" => io_list(&mut lines, no, &mut file, problems),
            "VAR LIST" => section(&mut lines, no, line, var_line, problems),
            "PULL-UP LIST" => section(&mut lines, no, line, pull_up_line, problems),
            "PROGRAM" => {
                program = true;
                break;
            }
            _ => {}
        }
    }
    stray.flush(problems);
    if !program {
        problems.push(Problem::file(
            0,
            "file: no PROGRAM line, so no rungs — save the file again from LDmicro".into(),
        ));
        return file;
    }
    let mut stray = Stray::new(1, "where a RUNG should begin", "where a RUNG should begin");
    while let Some((no, line)) = lines.next() {
        if is_rung(line) {
            stray.flush(problems);
            rung(&mut lines, no, &mut file, problems);
            stray.rung = file.rungs.len() + 1;
        } else {
            stray.add(no, line);
        }
    }
    stray.flush(problems);
    if file.elements > MAX_ELEMENTS {
        problems.push(Problem::file(0, format!(
            "file: {} elements; uTile reads up to {MAX_ELEMENTS} (its program holds 256 lines) — is it the right file?",
            file.elements
        )));
    }
    file
}

/// A line at most 60 characters long, for a refusal.
fn clip(line: &str) -> String {
    match line.char_indices().nth(60) {
        Some((at, _)) => format!("{}…", &line[..at]),
        None => line.into(),
    }
}

fn header(line: &str) -> bool {
    HEADER.iter().any(|&(field, digit)| {
        line.strip_prefix(field)
            .is_some_and(|v| !digit || v.starts_with(|c: char| c.is_ascii_digit()))
    })
}

/// `RUNG` (0.1) or `RUNG n` (0.2).
fn is_rung(line: &str) -> bool {
    let mut w = line.split_whitespace();
    w.next() == Some("RUNG")
        && w.next().is_none_or(|n| n.parse::<u32>().is_ok())
        && w.next().is_none()
}

/// The IO LIST: `name at pin [slave address]`; X names are inputs, Y names outputs; the
/// other kinds (A, P, I, M, C, H) only serve elements uTile refuses by name.
fn io_list(lines: &mut Lines<'_>, start: usize, file: &mut File, problems: &mut Vec<Problem>) {
    let (inputs, outputs) = (&mut file.inputs, &mut file.outputs);
    let mut good = |line: &str| {
        let Some(name) = io_line(line) else {
            return false;
        };
        let list = match name.as_bytes()[0] {
            b'X' => &mut *inputs,
            b'Y' => &mut *outputs,
            _ => return true,
        };
        if !list.iter().any(|n| n == name) {
            list.push(name.into());
        }
        true
    };
    section(lines, start, "IO LIST", &mut good, problems);
}

fn io_line(line: &str) -> Option<&str> {
    let mut w = line.split_whitespace();
    let (name, at, pin) = (w.next()?, w.next()?, w.next()?);
    (at == "at" && !pin.is_empty()).then_some(name)
}

fn var_line(line: &str) -> bool {
    let w: Vec<&str> = line.split_whitespace().collect();
    matches!(w.as_slice(), [n, "bytes", _, ..] if n.parse::<u32>().is_ok())
        || matches!(w.as_slice(), [_, "signed", n, "bit", "variable", ..] if n.parse::<u32>().is_ok())
}

fn pull_up_line(line: &str) -> bool {
    let w: Vec<&str> = line.split_whitespace().collect();
    matches!(w.as_slice(), [port, value] if port.len() == 3 && port.ends_with(':') && value.starts_with("0x"))
}

/// The lines of a section up to its END, each checked by `good`.
fn section(
    lines: &mut Lines<'_>,
    start: usize,
    what: &str,
    mut good: impl FnMut(&str) -> bool,
    problems: &mut Vec<Problem>,
) {
    let one = format!("is not a line of the {what}");
    let many = format!("that are not lines of the {what}");
    let mut stray = Stray::new(0, &one, &many);
    for (no, line) in lines.by_ref() {
        if line == "END" {
            stray.flush(problems);
            return;
        }
        if good(line) {
            stray.flush(problems);
        } else {
            stray.add(no, line);
        }
    }
    stray.flush(problems);
    problems.push(Problem::file(
        start,
        format!("line {start}: the {what} has no END — save the file again from LDmicro"),
    ));
}

/// A rung from its `RUNG` line (`start`) to its END, without recursion: a stack of the
/// open subcircuits. Past [`MAX_DEPTH`] levels the lines are counted, not kept; past
/// [`MAX_ELEMENTS`] in the file likewise.
fn rung(lines: &mut Lines<'_>, start: usize, file: &mut File, problems: &mut Vec<Problem>) {
    let number = file.rungs.len() + 1;
    let root = file.nodes.len();
    file.nodes.push(node(Kind::Series, start, Vec::new()));
    let mut open: Vec<(usize, &str)> = std::vec![(root, "RUNG")];
    // Levels open past MAX_DEPTH, and the deepest level seen.
    let (mut over, mut deepest) = (0usize, 1usize);
    let mut skipped = false;
    loop {
        let Some((no, line)) = lines.next() else {
            let what = if over > 0 {
                "SERIES"
            } else {
                open.last().map_or("RUNG", |o| o.1)
            };
            problems.push(Problem::at(number, start, format!(
                "rung {number} (line {start}): the file ends inside a {what} with no END — save the file again from LDmicro"
            )));
            skipped = true;
            break;
        };
        if line.starts_with(';') {
            continue;
        }
        let w = words(line);
        let sub = match w[0].as_str() {
            "SERIES" if w.len() == 1 => Some((Kind::Series, "SERIES")),
            "PARALLEL" if w.len() == 1 => Some((Kind::Parallel, "PARALLEL")),
            "END" if w.len() == 1 => {
                if over > 0 {
                    over -= 1;
                } else {
                    open.pop();
                    if open.is_empty() {
                        break;
                    }
                }
                continue;
            }
            _ => None,
        };
        file.elements += 1;
        let depth = open.len() + over + usize::from(sub.is_some());
        deepest = deepest.max(depth);
        if over > 0 || file.elements > MAX_ELEMENTS || (sub.is_some() && depth > MAX_DEPTH) {
            over += usize::from(sub.is_some());
            skipped = true;
            continue;
        }
        let at = file.nodes.len();
        let parent = open.last().map_or(root, |o| o.0);
        file.nodes[parent].children.push(at);
        match sub {
            Some((kind, name)) => {
                file.nodes.push(node(kind, no, Vec::new()));
                open.push((at, name));
            }
            None => file.nodes.push(node(Kind::Leaf, no, w)),
        }
    }
    if deepest > MAX_DEPTH {
        problems.push(Problem::at(number, start, format!(
            "rung {number} (line {start}): SERIES and PARALLEL nested {deepest} deep; uTile reads up to {MAX_DEPTH} — LDmicro draws far less; is it the right file?"
        )));
    }
    file.rungs.push(Rung {
        root,
        line: start,
        skipped,
    });
}

fn node(kind: Kind, line: usize, words: Vec<String>) -> Node {
    Node {
        kind,
        line,
        children: Vec::new(),
        words,
    }
}

/// A run of lines that are not understood, given as one problem (a file of them is one
/// reason, not a million).
struct Stray<'a> {
    /// The rung the run is before (0: the file's).
    rung: usize,
    one: &'a str,
    many: &'a str,
    /// The run's first and last line, its length, its first line's text.
    first: usize,
    last: usize,
    count: usize,
    text: String,
}

impl<'a> Stray<'a> {
    fn new(rung: usize, one: &'a str, many: &'a str) -> Stray<'a> {
        Stray {
            rung,
            one,
            many,
            first: 0,
            last: 0,
            count: 0,
            text: String::new(),
        }
    }

    fn add(&mut self, no: usize, line: &str) {
        if self.count == 0 {
            self.first = no;
            self.text = clip(line);
        }
        self.last = no;
        self.count += 1;
    }

    fn flush(&mut self, problems: &mut Vec<Problem>) {
        let (first, last, text) = (self.first, self.last, &self.text);
        let what = match self.count {
            0 => return,
            1 => format!("line {first}: '{text}' {}", self.one),
            n => format!(
                "lines {first}–{last}: {n} lines {}, the first '{text}'",
                self.many
            ),
        };
        problems.push(Problem::at(
            self.rung,
            first,
            format!("{what} — save the file again from LDmicro"),
        ));
        self.count = 0;
    }
}
