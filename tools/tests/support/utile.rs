//! Helpers shared by the `utile` tool tests: run the binary, scratch files, example paths,
//! the output table, SVG and VCD checks.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicU32, Ordering};

/// Run `utile` with `args`.
pub fn utile(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_utile"))
        .args(args)
        .output()
        .expect("run utile")
}

/// Run `utile`, require success, return stdout.
pub fn utile_ok(args: &[&str]) -> String {
    let out = utile(args);
    assert!(
        out.status.success(),
        "utile {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8 stdout")
}

/// Run `utile`, require failure, return stderr.
pub fn utile_err(args: &[&str]) -> String {
    let out = utile(args);
    assert!(!out.status.success(), "utile {args:?} should fail");
    String::from_utf8(out.stderr).expect("utf-8 stderr")
}

static NEXT: AtomicU32 = AtomicU32::new(0);

/// A fresh scratch path ending in `name`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("utile-tests");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let n = NEXT.fetch_add(1, Ordering::Relaxed);
    dir.join(format!("{}-{n}-{name}", std::process::id()))
}

/// Write `text` to a fresh scratch file named `name`; returns its path as a string.
pub fn write_scratch(name: &str, text: &str) -> String {
    let p = scratch(name);
    std::fs::write(&p, text).expect("write scratch");
    p.to_str().expect("utf-8 path").to_owned()
}

/// The repository's `examples/` directory.
pub fn examples_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples")
}

/// Every example listing (stem without `.utl`), sorted.
pub fn example_stems() -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(examples_dir())
        .expect("examples dir")
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            name.strip_suffix(".utl").map(str::to_owned)
        })
        .collect();
    v.sort();
    v
}

/// Path of an example file as a string.
pub fn example(file: &str) -> String {
    examples_dir()
        .join(file)
        .to_str()
        .expect("utf-8 path")
        .to_owned()
}

/// Parse `utile sim`'s output table into (ms, PY image) rows.
pub fn parse_table(stdout: &str) -> Vec<(u32, u8)> {
    let mut lines = stdout.lines();
    let header = lines.next().expect("table header");
    assert_eq!(
        header.split_whitespace().collect::<Vec<_>>(),
        ["time", "Y0", "Y1", "Y2", "Y3", "Y4", "Y5", "Y6", "Y7"]
    );
    lines
        .map(|l| {
            let mut w = l.split_whitespace();
            let t = w
                .next()
                .expect("time")
                .strip_suffix('s')
                .expect("time in s");
            let (s, ms) = t.split_once('.').expect("s.mmm");
            let ms = s.parse::<u32>().unwrap() * 1000 + ms.parse::<u32>().unwrap();
            let mut py = 0u8;
            for n in 0..8 {
                match w.next().expect("bit") {
                    "1" => py |= 1 << n,
                    "0" => {}
                    other => panic!("bad bit {other}"),
                }
            }
            assert!(w.next().is_none(), "extra column in {l}");
            (ms, py)
        })
        .collect()
}

/// The edges of output bit `n`: (ms, new level), from the output change rows.
pub use utile_kit::simulate::edges;

/// Level of output bit `n` at `ms` (after every change at or before `ms`).
pub fn level(rows: &[(u32, u8)], n: u8, ms: u32) -> bool {
    rows.iter()
        .take_while(|r| r.0 <= ms)
        .last()
        .is_some_and(|r| r.1 & (1 << n) != 0)
}

/// Simulate an example with its own timeline; returns the output change rows.
pub fn sim_example(stem: &str) -> Vec<(u32, u8)> {
    let prog = example(&format!("{stem}.utl"));
    let tl = example(&format!("{stem}.timeline"));
    parse_table(&utile_ok(&["sim", &prog, "--inputs", &tl]))
}

/// Check an SVG: one `trace` group per signal, in order, and balanced tags.
pub fn check_svg(svg: &str, signals: &[&str]) {
    assert!(svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""));
    assert!(svg.trim_end().ends_with("</svg>"));
    let names: Vec<&str> = svg
        .match_indices("class=\"trace\" data-signal=\"")
        .map(|(i, m)| {
            let rest = &svg[i + m.len()..];
            &rest[..rest.find('"').unwrap()]
        })
        .collect();
    assert_eq!(names, signals);
    assert_eq!(
        svg.matches("<path ").count(),
        signals.len(),
        "one waveform per signal"
    );
    assert_eq!(
        svg.matches("<g").count(),
        svg.matches("</g>").count(),
        "balanced groups"
    );
    let opens = svg.matches('<').count();
    let closes = svg.matches('>').count();
    assert_eq!(opens, closes);
}

/// A VCD variable: (id, name).
pub type VcdVar = (String, String);
/// A VCD value change: (time, id, value; a bit is 0 or 1).
pub type VcdChange = (u32, String, u32);

/// Parse a VCD: (variables, every value change), checking the header.
pub fn parse_vcd(vcd: &str) -> (Vec<VcdVar>, Vec<VcdChange>) {
    let (header, body) = vcd
        .split_once("$enddefinitions $end\n")
        .expect("enddefinitions");
    assert!(header.contains("$timescale 1ms $end"));
    assert!(header.contains("$scope module utile $end") && header.contains("$upscope $end"));
    let vars: Vec<VcdVar> = header
        .lines()
        .filter(|l| l.starts_with("$var"))
        .map(|l| {
            let w: Vec<&str> = l.split_whitespace().collect();
            assert_eq!((w[1], w[5]), ("wire", "$end"), "{l}");
            assert!(["1", "10", "16"].contains(&w[2]), "width in {l}");
            (w[3].to_owned(), w[4].to_owned())
        })
        .collect();
    let mut values = Vec::new();
    let mut now = None;
    for l in body.lines() {
        if let Some(t) = l.strip_prefix('#') {
            let t: u32 = t.parse().expect("time");
            assert!(now.is_none_or(|n| t > n), "times increase");
            now = Some(t);
        } else if l == "$dumpvars" || l == "$end" {
        } else if let Some(vector) = l.strip_prefix('b') {
            let (v, id) = vector.split_once(' ').expect("b<value> <id>");
            assert!(vars.iter().any(|(i, _)| i == id), "unknown id in {l}");
            let v = u32::from_str_radix(v, 2).expect("binary value");
            values.push((now.expect("time before values"), id.to_owned(), v));
        } else {
            let (v, id) = l.split_at(1);
            assert!(vars.iter().any(|(i, _)| i == id), "unknown id in {l}");
            assert!(v == "0" || v == "1", "{l}");
            values.push((
                now.expect("time before values"),
                id.to_owned(),
                u32::from(v == "1"),
            ));
        }
    }
    (vars, values)
}
