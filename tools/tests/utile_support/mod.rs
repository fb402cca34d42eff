//! Helpers shared by the `utile` tool tests: run the binary, scratch files, example paths.
#![allow(dead_code)]

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
pub fn edges(rows: &[(u32, u8)], n: u8) -> Vec<(u32, bool)> {
    let mut last = false;
    let mut out = Vec::new();
    for &(ms, py) in rows {
        let v = py & (1 << n) != 0;
        if v != last {
            out.push((ms, v));
            last = v;
        }
    }
    out
}

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
