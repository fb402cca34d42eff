//! What the ladder tests share: random input timelines, a program run on the core's engine
//! sampled every ms, and the SVG's elements.

use utile_core::engine::{Engine, Program};
use utile_kit::rng::Rng;
use utile_kit::sim::SimBoard;
use utile_kit::simulate::Event;

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
