//! `utile sim`: a program run by the firmware's own engine on a [`SimBoard`](crate::sim::SimBoard) with simulated
//! time, against an input timeline; the result is a set of traces (one per signal).
//!
//! A timeline file holds one event per line, in time order:
//!
//! ```text
//! 0s    set A3 low       # level at the start (inputs start high: open, pull-ups)
//! 0.5s  press A0         # pull A0 low (a normally-open push-button to ground)
//! 2s    release A0       # A0 back high
//! 3s    set A6 2.5V      # analog level on A6 or A7: volts (0..5V) or ADC counts (0..1023)
//! until 12s              # how long to simulate (the command line may override it)
//! signals A0,Y0,TQ0,Q0   # what to draw (the command line may override it)
//! ```
//!
//! Times are `ms`, `s` or `min`, with decimals down to 1 ms (`1500ms`, `1.5s`).
//!
//! One job a file: [`timeline`] (the language above), [`signal`] (what can be traced and the
//! default choice), [`run`] (the simulation) and [`output`] (the table and the VCD; the SVG
//! is [`crate::diagram`]). Their items are re-exported here, so `simulate::parse_timeline`,
//! `simulate::Signal`, `simulate::simulate_timeline` and `simulate::vcd` name them. Its tests
//! are tools/tests/utile_sim.rs.

pub mod output;
pub mod run;
pub mod signal;
pub mod timeline;

pub use output::{edges, output_table, vcd};
pub use run::{
    simulate, simulate_after_boot, simulate_timeline, simulate_timeline_after_boot, SimResult,
    Trace,
};
pub use signal::{
    default_signals, default_signals_with_analog, parse_signals, Signal, SignalError,
};
pub use timeline::{
    format_time, mv_to_counts, parse_time, parse_timeline, AnalogEvent, Event, TimeError, Timeline,
    AVCC_MV,
};
