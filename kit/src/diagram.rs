//! SVG timing diagrams of simulated traces: one row per signal, a time axis below. A bit
//! is a logic trace; a count (C0..C7) or an analog level (A6, A7) is a taller row with a
//! step trace scaled to the row and its value written at each change where there is room.

use std::fmt::Write as _;
use std::string::String;

use crate::simulate::{SimResult, Trace};

/// Width of the label column.
const LABEL_W: f64 = 56.0;
/// Width of the plot area.
const PLOT_W: f64 = 900.0;
/// Height of one signal row.
const ROW_H: f64 = 30.0;
/// Height of a high level above the row's low line.
const HIGH_H: f64 = 18.0;
/// Height of a value row (counts, analog levels).
const VALUE_ROW_H: f64 = 50.0;
/// Height of the full scale of a value row's step trace.
const VALUE_H: f64 = 30.0;
/// Width of one character of a value label (font-size 10, monospace).
const VALUE_CHAR_W: f64 = 6.0;
/// Room above the first row (title).
const TOP: f64 = 34.0;
/// Room below the last row (axis and its labels).
const BOTTOM: f64 = 36.0;
/// Right margin.
const RIGHT: f64 = 24.0;

/// A tick step (ms) giving at most about 12 ticks over `until_ms`.
fn tick_step(until_ms: u32) -> u32 {
    let mut step = 1u32;
    loop {
        for m in [1, 2, 5] {
            let s = step.saturating_mul(m);
            if until_ms / s <= 12 {
                return s;
            }
        }
        step = step.saturating_mul(10);
    }
}

/// A tick label: ms below one second, seconds (with decimals only when needed) above.
fn tick_label(ms: u32, step: u32) -> String {
    if step < 1000 && ms < 1000 {
        format!("{ms} ms")
    } else if ms.is_multiple_of(1000) {
        format!("{} s", ms / 1000)
    } else {
        let s = format!("{}.{:03}", ms / 1000, ms % 1000);
        format!("{} s", s.trim_end_matches('0'))
    }
}

/// Escape text for XML.
fn xml(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The height of a trace's row.
fn row_height(tr: &Trace) -> f64 {
    if tr.signal.is_bit() {
        ROW_H
    } else {
        VALUE_ROW_H
    }
}

/// The x of time `ms`.
fn x_of(ms: u32, until_ms: u32) -> f64 {
    LABEL_W + PLOT_W * f64::from(ms) / f64::from(until_ms.max(1))
}

/// The path and the high-level fill of one bit trace in the row starting at `top`.
fn trace_shapes(tr: &Trace, top: f64, until_ms: u32) -> (String, String) {
    let base = top + ROW_H - 6.0;
    let x_of = |ms: u32| x_of(ms, until_ms);
    let y_of = |v: u16| if v != 0 { base - HIGH_H } else { base };
    let mut path = format!("M{:.1},{:.1}", x_of(0), y_of(tr.initial));
    let mut fill = String::new();
    let mut level = tr.initial != 0;
    let mut since = 0u32;
    for &(ms, v) in &tr.changes {
        if level {
            let _ = write!(
                fill,
                r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{HIGH_H}"/>"#,
                x_of(since),
                base - HIGH_H,
                x_of(ms) - x_of(since)
            );
        }
        let _ = write!(path, " H{:.1} V{:.1}", x_of(ms), y_of(v));
        level = v != 0;
        since = ms;
    }
    if level {
        let _ = write!(
            fill,
            r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{HIGH_H}"/>"#,
            x_of(since),
            base - HIGH_H,
            x_of(until_ms) - x_of(since)
        );
    }
    let _ = write!(path, " H{:.1}", x_of(until_ms));
    (path, fill)
}

/// The full scale of a value trace: 1023 for an analog level, else the largest count (at
/// least 1).
fn full_scale(tr: &Trace) -> u16 {
    if tr.signal.width() == 10 {
        utile_core::analog::MAX
    } else {
        tr.max().max(1)
    }
}

/// The step path and the value labels of one value trace in the row starting at `top`.
fn value_shapes(tr: &Trace, top: f64, until_ms: u32) -> (String, String) {
    let base = top + VALUE_ROW_H - 6.0;
    let scale = f64::from(full_scale(tr));
    let x_of = |ms: u32| x_of(ms, until_ms);
    let y_of = |v: u16| base - VALUE_H * f64::from(v) / scale;
    let mut path = format!("M{:.1},{:.1}", x_of(0), y_of(tr.initial));
    let mut labels = String::new();
    let steps: Vec<(u32, u16)> = core::iter::once((0, tr.initial))
        .chain(tr.changes.iter().copied())
        .collect();
    // A label is written only where it does not run into the previous one or the next
    // change: a fast-changing value (a quick count) shows its settled values, the trace the
    // rest.
    let mut free_x = f64::MIN;
    for (k, &(ms, v)) in steps.iter().enumerate() {
        if k > 0 {
            let _ = write!(path, " H{:.1} V{:.1}", x_of(ms), y_of(v));
        }
        let x = x_of(ms) + 2.0;
        let text = v.to_string();
        let next = steps.get(k + 1).map_or(until_ms, |c| c.0);
        let w = VALUE_CHAR_W * text.len() as f64;
        if x >= free_x && (x_of(next) - x >= w || next == until_ms) {
            let _ = write!(
                labels,
                r#"<text x="{x:.1}" y="{:.1}">{text}</text>"#,
                top + 12.0
            );
            free_x = x + w + 4.0;
        }
    }
    let _ = write!(path, " H{:.1}", x_of(until_ms));
    (path, labels)
}

/// The SVG document for a simulation; `title` is shown at the top.
pub fn svg(result: &SimResult, title: &str) -> String {
    let until = result.until_ms.max(1);
    let rows_h: f64 = result.traces.iter().map(row_height).sum();
    let width = LABEL_W + PLOT_W + RIGHT;
    let height = TOP + rows_h + BOTTOM;
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" viewBox="0 0 {width} {height}" font-family="monospace" font-size="12">"#
    );
    let _ = writeln!(
        out,
        r#"<rect width="{width}" height="{height}" fill="white"/>"#
    );
    let _ = writeln!(
        out,
        r#"<text x="{LABEL_W}" y="20" font-size="14">{}</text>"#,
        xml(title)
    );

    // Time grid and axis.
    let axis_y = TOP + rows_h + 4.0;
    let step = tick_step(until);
    let _ = writeln!(out, r##"<g class="axis" stroke="#ccc" fill="#444">"##);
    let mut t = 0u32;
    while t <= until {
        let x = LABEL_W + PLOT_W * f64::from(t) / f64::from(until);
        let _ = writeln!(
            out,
            r#"<line x1="{x:.1}" y1="{TOP}" x2="{x:.1}" y2="{:.1}"/><text x="{x:.1}" y="{:.1}" stroke="none" text-anchor="middle">{}</text>"#,
            axis_y + 4.0,
            axis_y + 18.0,
            tick_label(t, step)
        );
        t = match t.checked_add(step) {
            Some(n) => n,
            None => break,
        };
    }
    let _ = writeln!(
        out,
        r##"<line x1="{LABEL_W}" y1="{axis_y:.1}" x2="{:.1}" y2="{axis_y:.1}" stroke="#444"/></g>"##,
        LABEL_W + PLOT_W
    );

    let mut top = TOP;
    for tr in &result.traces {
        let name = tr.signal.name();
        if tr.signal.is_bit() {
            let (path, fill) = trace_shapes(tr, top, until);
            let label_y = top + ROW_H - 10.0;
            let _ = writeln!(
                out,
                r##"<g class="trace" data-signal="{name}"><text x="6" y="{label_y:.1}">{name}</text><g fill="#4a90d9" fill-opacity="0.25">{fill}</g><path d="{path}" fill="none" stroke="#1f4e8c" stroke-width="1.5"/></g>"##
            );
        } else {
            let (path, labels) = value_shapes(tr, top, until);
            let _ = writeln!(
                out,
                r##"<g class="trace" data-signal="{name}"><text x="6" y="{:.1}">{name}</text><text x="6" y="{:.1}" font-size="9" fill="#666">0..{}</text><g font-size="10" fill="#1f4e8c">{labels}</g><path d="{path}" fill="none" stroke="#1f4e8c" stroke-width="1.5"/></g>"##,
                top + 24.0,
                top + 36.0,
                full_scale(tr)
            );
        }
        top += row_height(tr);
    }
    out.push_str("</svg>\n");
    out
}
