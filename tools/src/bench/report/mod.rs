//! The `bench` binary's report: one row a measurement, the original assembly firmware's
//! figure and the goal beside it, which BENCHMARKS.md mirrors row by row. Each file gives
//! the rows of its sections: [`scan`] (`scan`, `opcodes`), [`timing`] (`latency`,
//! `autostart`, `timers`), [`editor`] (`size`, `uart`, `store`, `stack`), [`modbus`],
//! [`live`] and [`mqtt`].

pub mod editor;
pub mod live;
pub mod modbus;
pub mod mqtt;
pub mod scan;
pub mod timing;

use super::chip::F_CPU;
use super::stats::Spread;

/// One row of the report.
struct Row {
    what: String,
    ours: String,
    original: String,
    goal: String,
}

/// The rows measured so far.
#[derive(Default)]
pub struct Report {
    rows: Vec<Row>,
}

impl Report {
    /// Adds a row (and says it on standard error at once: the whole run takes minutes).
    pub fn row(
        &mut self,
        what: impl Into<String>,
        ours: impl Into<String>,
        original: &str,
        goal: &str,
    ) {
        let r = Row {
            what: what.into(),
            ours: ours.into(),
            original: original.into(),
            goal: goal.into(),
        };
        eprintln!("  {} = {}", r.what, r.ours);
        self.rows.push(r);
    }

    /// Adds the row of one measurement: its figure, or why there is none.
    pub fn measured(
        &mut self,
        what: impl Into<String>,
        figure: Result<String, impl std::fmt::Display>,
        original: &str,
        goal: &str,
    ) {
        let ours = figure.unwrap_or_else(|e| format!("not measurable: {e}"));
        self.row(what, ours, original, goal);
    }

    /// The report as a Markdown table.
    pub fn markdown(&self) -> String {
        let mut out = String::from("| measurement | uTile in Rust | original (asm) | goal |\n");
        out.push_str("|---|---|---|---|\n");
        for r in &self.rows {
            out.push_str(&format!(
                "| {} | {} | {} | {} |\n",
                r.what, r.ours, r.original, r.goal
            ));
        }
        out
    }
}

/// Cycles: min / median / max.
fn cyc(s: &Spread) -> String {
    format!("{:.0} / {:.0} / {:.0}", s.min, s.median, s.max)
}

/// Cycles as microseconds at the Nano's clock.
fn us(cycles: f64) -> String {
    format!("{:.1} µs", cycles * 1e6 / F_CPU as f64)
}

/// Milliseconds: min / median / max.
fn ms(s: &Spread) -> String {
    format!("{:.2} / {:.2} / {:.2} ms", s.min, s.median, s.max)
}
