//! `utile sim`: a listing simulated against a timeline of inputs; the output changes as a
//! table, a timing diagram (SVG) or a VCD file.

use std::path::PathBuf;

use utile_kit::diagram;
use utile_kit::simulate::{self, Signal};

use crate::files::{load_listing, read_text, write_file};

/// A list of signals as one value (`--signals A0,Y0,TQ0`).
type SignalList = Vec<Signal>;

/// `utile sim PROG.utl [--inputs TIMELINE] ...`.
#[derive(clap::Args)]
#[command(after_help = "Examples:\n  \
    utile sim examples/tank-fill.utl --inputs examples/tank-fill.timeline\n  \
    utile sim prog.utl --inputs t.timeline --until 120s --scans 4 --signals A0,Y0,TQ0,C0,A6,H6\n  \
    utile sim prog.utl --inputs t.timeline --svg out.svg --vcd out.vcd")]
pub struct Sim {
    /// The listing
    #[arg(value_name = "PROG.utl")]
    input: PathBuf,
    /// The timeline of inputs (switches, analog levels; see docs)
    #[arg(long, value_name = "TIMELINE")]
    inputs: Option<PathBuf>,
    /// How long to simulate, e.g. 1500ms, 0.5s, 2min (default: the timeline's, else 5 s
    /// after its last event)
    #[arg(long, value_name = "TIME", value_parser = length)]
    until: Option<u32>,
    /// Scans per millisecond, 1..1000
    #[arg(long, value_name = "N", default_value_t = 4, value_parser = clap::value_parser!(u32).range(1..=1000))]
    scans: u32,
    /// The signals to show, e.g. A0,Y0,TQ0,C0,A6,H6 (default: the timeline's, else the
    /// inputs it touches and what the program writes)
    #[arg(long, value_name = "LIST", value_parser = simulate::parse_signals)]
    signals: Option<SignalList>,
    /// Write a timing diagram
    #[arg(long, value_name = "OUT.svg")]
    svg: Option<PathBuf>,
    /// Write a VCD file (for GTKWave and the like)
    #[arg(long, value_name = "OUT.vcd")]
    vcd: Option<PathBuf>,
}

/// A simulated length that is none.
#[derive(Debug, thiserror::Error)]
enum LengthError {
    /// Not a time.
    #[error(transparent)]
    Time(#[from] simulate::TimeError),
    /// No time at all.
    #[error("the simulation must last at least 1 ms")]
    Zero,
}

/// A simulated length of at least 1 ms.
fn length(text: &str) -> Result<u32, LengthError> {
    match simulate::parse_time(text)? {
        0 => Err(LengthError::Zero),
        ms => Ok(ms),
    }
}

impl Sim {
    /// Simulates and prints the table; writes the diagram and VCD asked for.
    pub fn run(self) -> anyhow::Result<()> {
        let prog = load_listing(&self.input)?;
        let timeline = match &self.inputs {
            Some(t) => simulate::parse_timeline(&t.display().to_string(), &read_text(t)?)?,
            None => simulate::Timeline::default(),
        };
        let until_ms = self.until.unwrap_or_else(|| {
            timeline.until_ms.unwrap_or_else(|| {
                let last_digital = timeline.events.last().map_or(0, |e| e.ms);
                let last_analog = timeline.analog.last().map_or(0, |e| e.ms);
                last_digital.max(last_analog).saturating_add(5_000)
            })
        });
        if until_ms == 0 {
            anyhow::bail!("the timeline's until: the simulation must last at least 1 ms");
        }
        let signals = self.signals.unwrap_or_else(|| {
            timeline.signals.clone().unwrap_or_else(|| {
                simulate::default_signals_with_analog(&prog, &timeline.events, &timeline.analog)
            })
        });
        let result = simulate::simulate_timeline(&prog, &timeline, until_ms, self.scans, &signals);
        print!("{}", simulate::output_table(&result.output_log));
        let name = self
            .input
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        if let Some(svg) = &self.svg {
            let title = format!(
                "{name}: {} scans/ms, {}",
                self.scans,
                simulate::format_time(until_ms)
            );
            write_file(svg, diagram::svg(&result, &title).as_bytes())?;
        }
        if let Some(vcd) = &self.vcd {
            write_file(vcd, simulate::vcd(&result, &name).as_bytes())?;
        }
        Ok(())
    }
}
