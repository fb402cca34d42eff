//! SVG timing diagrams of simulated traces: one row per signal, a time axis below.

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

/// The path and the high-level fill of one trace in row `row`.
fn trace_shapes(tr: &Trace, row: usize, until_ms: u32) -> (String, String) {
    let base = TOP + ROW_H * (row as f64 + 1.0) - 6.0;
    let x_of = |ms: u32| LABEL_W + PLOT_W * f64::from(ms) / f64::from(until_ms.max(1));
    let y_of = |high: bool| if high { base - HIGH_H } else { base };
    let mut path = format!("M{:.1},{:.1}", x_of(0), y_of(tr.initial));
    let mut fill = String::new();
    let mut level = tr.initial;
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
        level = v;
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

/// The SVG document for a simulation; `title` is shown at the top.
pub fn svg(result: &SimResult, title: &str) -> String {
    let until = result.until_ms.max(1);
    let rows = result.traces.len();
    let width = LABEL_W + PLOT_W + RIGHT;
    let height = TOP + ROW_H * rows as f64 + BOTTOM;
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
    let axis_y = TOP + ROW_H * rows as f64 + 4.0;
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

    for (row, tr) in result.traces.iter().enumerate() {
        let name = tr.signal.name();
        let (path, fill) = trace_shapes(tr, row, until);
        let label_y = TOP + ROW_H * (row as f64 + 1.0) - 10.0;
        let _ = writeln!(
            out,
            r##"<g class="trace" data-signal="{name}"><text x="6" y="{label_y:.1}">{name}</text><g fill="#4a90d9" fill-opacity="0.25">{fill}</g><path d="{path}" fill="none" stroke="#1f4e8c" stroke-width="1.5"/></g>"##
        );
    }
    out.push_str("</svg>\n");
    out
}
