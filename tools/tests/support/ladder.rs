//! What the ladder tests share: random input timelines, a program run on the core's engine
//! sampled every ms, the SVG's elements, and an import refused as a user sees it.

use utile_core::engine::{Engine, Program};
use utile_kit::rng::Rng;
use utile_kit::sim::SimBoard;
use utile_kit::simulate::Event;

use super::utile::{scratch, utile};

/// `utile import` must fail with each of `wants` in its message (which starts with the
/// file's name), exit 1, write nothing and print nothing.
pub fn import_refused(name: &str, text: &[u8], map: Option<&str>, wants: &[&str]) -> String {
    import_fails(name, text, map, 1, wants)
}

/// `utile import` must fail with exit status `status` (2: a `--map` that does not fit the
/// file), each of `wants` in its message, writing and printing nothing.
pub fn import_fails(
    name: &str,
    text: &[u8],
    map: Option<&str>,
    status: i32,
    wants: &[&str],
) -> String {
    let path = scratch(name);
    std::fs::write(&path, text).unwrap();
    let path = path.to_str().unwrap().to_string();
    let out = scratch("out.utl");
    let mut args = vec!["import", path.as_str(), "-o", out.to_str().unwrap()];
    if let Some(m) = map {
        args.extend(["--map", m]);
    }
    let r = utile(&args);
    let err = String::from_utf8_lossy(&r.stderr).to_string();
    assert_eq!(r.status.code(), Some(status), "{name}: {err}");
    assert!(r.stdout.is_empty());
    assert!(!out.exists(), "{name}: nothing may be written");
    assert!(!err.contains("panicked"), "{err}");
    assert!(err.starts_with(&format!("{path}: ")), "{name}: {err}");
    for w in wants {
        assert!(err.contains(w), "{name}: '{w}' not in: {err}");
    }
    err
}

/// Random changes of the inputs in `mask` over `until_ms`, at least `min_gap` ms apart on
/// one input (longer than the debouncer, so every change is seen).
pub fn random_events(rng: &mut Rng, mask: u8, until_ms: u32, min_gap: u32) -> Vec<Event> {
    let mut events = Vec::new();
    for input in 0..6u8 {
        if mask & (1 << input) == 0 {
            continue;
        }
        let mut high = rng.below(2) == 0;
        events.push(Event { ms: 0, input, high });
        let mut t = 0;
        loop {
            let span = if rng.below(3) == 0 { 4000 } else { 400 };
            t += min_gap + rng.below(span);
            if t >= until_ms {
                break;
            }
            high = !high;
            events.push(Event { ms: t, input, high });
        }
    }
    events.sort_by_key(|e| e.ms);
    events
}

/// One ms of a run: the debounced inputs the scans saw, and the outputs after them.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Sample {
    /// The debounced input levels (bit n: An).
    pub inputs: u8,
    /// The output pins (PY) at the end of the ms.
    pub outputs: u8,
}

/// `prog` on the core's engine with `events`, `scans` scans a ms, sampled every ms.
pub fn run(prog: &Program, events: &[Event], until_ms: u32, scans: u32) -> Vec<Sample> {
    let mut board = SimBoard::new();
    let mut engine = Engine::new(prog.clone());
    let mut pending = events.iter().peekable();
    while let Some(e) = pending.next_if(|e| e.ms == 0) {
        board.set_input(e.input, e.high);
    }
    engine.clear_runtime(&mut board);
    let mut out = Vec::with_capacity(until_ms as usize);
    for t in 0..until_ms {
        while let Some(e) = pending.next_if(|e| e.ms <= t) {
            board.set_input(e.input, e.high);
        }
        let inputs = board.ticker.inputs.level();
        board.run_for(&mut engine, 1, scans);
        out.push(Sample {
            inputs,
            outputs: board.outputs,
        });
    }
    out
}

/// One element of a ladder SVG.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Element {
    /// `contact`, `coil`, `function`, `rung`, `rung block`, `line`.
    pub class: String,
    /// Its rung.
    pub rung: Option<usize>,
    /// `data-signal`.
    pub signal: Option<String>,
    /// `data-lines`.
    pub lines: Vec<u8>,
}

fn attr(tag: &str, name: &str) -> Option<String> {
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    let rest = &tag[i..];
    Some(rest[..rest.find('"')?].to_string())
}

/// Every element of a ladder SVG with a `data-lines` attribute, in document order.
pub fn elements(svg: &str) -> Vec<Element> {
    svg.split('<')
        .filter(|t| t.contains("data-lines=\""))
        .map(|t| Element {
            class: attr(t, "class").unwrap_or_default(),
            rung: attr(t, "data-rung").and_then(|r| r.parse().ok()),
            signal: attr(t, "data-signal"),
            lines: attr(t, "data-lines")
                .unwrap_or_default()
                .split(',')
                .filter(|s| !s.is_empty())
                .map(|s| s.parse().expect("a line number"))
                .collect(),
        })
        .collect()
}
