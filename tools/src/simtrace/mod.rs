//! The cross-check's scenarios and traces (docs/SIMULATORS.md): one scenario file
//! (`play/scenarios/*.json`) read by both simulators' runners, this one on the kit's simavr
//! harness ([`simavr::run`]) and `play/test/support/runner.js` on the avr8js adapter; each
//! writes a [`Trace`] (what the line carried both ways, each output pin's changes), and the
//! Node test compares the two.
//!
//! A scenario is a list of steps run one after the other in simulated time. Steps that
//! need the host's own code (a Modbus frame's CRC, a listing's Intel HEX) are made here,
//! once: the trace records every byte sent into the chip with its step, and the avr8js
//! runner sends those same bytes. No second assembler or CRC in JavaScript.

pub mod simavr;

use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One scenario: a firmware image, the tolerance of the pins' times, the steps.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// What it shows, in words.
    pub about: String,
    /// The firmware image (Intel HEX), relative to the workspace's root.
    #[serde(default = "default_image")]
    pub image: PathBuf,
    /// One scan of the scenario's program, in µs: how far apart the two simulators' times of
    /// one pin change may be.
    pub scan_us: u32,
    /// The steps, in order.
    pub steps: Vec<Step>,
}

fn default_image() -> PathBuf {
    PathBuf::from("out/m328-nano-utile.hex")
}

/// One step of a scenario. Times are simulated; bytes go down the line at 19200 baud, back
/// to back after what is already on its way.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Step {
    /// Run this many milliseconds.
    RunMs(f64),
    /// Run until this many milliseconds after the first power-up.
    UntilMs(f64),
    /// Type this text at the terminal (its bytes, `\r` for Enter).
    Type(String),
    /// Send these bytes.
    Bytes(Vec<u8>),
    /// A Modbus request to slave 1: the PDU in hex digits (spaces allowed), after a silence
    /// of 4 characters; the address and CRC are added (`utile_kit::modbus::frame`).
    Modbus(String),
    /// A listing's file as READ takes it, the Intel HEX `utile asm` writes (the path is
    /// relative to the workspace's root).
    Read(PathBuf),
    /// Press a push-button or fit a jumper: A0..A5, D8, D9 held low.
    Press(String),
    /// Release it: the pin is open (pulled up).
    Release(String),
    /// Volts on A6 or A7: `["A6", 2.5]`.
    Volts(String, f64),
    /// The reset button.
    Reset,
    /// Power off and on.
    PowerCycle,
}

/// Bytes a step put on the line into the chip.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
pub struct Sent {
    /// The step's index.
    pub step: usize,
    /// The cycle the first byte's start bit begins.
    pub start: u64,
    /// The bytes.
    pub bytes: Vec<u8>,
}

/// One output pin's change.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
pub struct PinChange {
    /// Y0..Y7 or D10.
    pub pin: String,
    /// 1 = driven high.
    pub level: u8,
    /// The cycle.
    pub cycle: u64,
}

/// What one simulator did on one scenario.
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
pub struct Trace {
    /// The simulator: "simavr" or "avr8js".
    pub simulator: String,
    /// Every byte sent into the chip, by step.
    pub sent: Vec<Sent>,
    /// Every byte the firmware sent: `[byte, cycle its stop bit ends]`.
    pub uart: Vec<(u8, u64)>,
    /// Every change of an output pin, oldest first.
    pub pins: Vec<PinChange>,
    /// The cycle the run ended.
    pub end: u64,
}

/// Why a scenario cannot be run.
#[derive(Debug, thiserror::Error)]
pub enum TraceError {
    /// The scenario file cannot be read.
    #[error("cannot read the scenario {path}")]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        error: std::io::Error,
    },
    /// The scenario file is not a scenario.
    #[error("{path} is not a scenario")]
    Parse {
        /// The file.
        path: PathBuf,
        /// Where and why.
        #[source]
        error: serde_json::Error,
    },
    /// A step that cannot be carried out.
    #[error("step {step}: {why}")]
    Step {
        /// The step's index.
        step: usize,
        /// Why, in words.
        why: String,
    },
    /// The firmware image cannot be loaded.
    #[error("the firmware image")]
    Image(#[from] utile_kit::simavr::LoadError),
}

/// Reads a scenario file.
pub fn read(path: &Path) -> Result<Scenario, TraceError> {
    let text = std::fs::read_to_string(path).map_err(|error| TraceError::Read {
        path: path.to_owned(),
        error,
    })?;
    serde_json::from_str(&text).map_err(|error| TraceError::Parse {
        path: path.to_owned(),
        error,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scenario_of_the_playground_reads_and_names_its_image() {
        let dir = utile_kit::setup::workspace_root().join("play/scenarios");
        let mut read = 0;
        for entry in std::fs::read_dir(&dir).expect("play/scenarios") {
            let path = entry.expect("an entry").path();
            let scenario = read_scenario(&path);
            assert!(!scenario.steps.is_empty(), "{}", path.display());
            assert!(scenario.scan_us > 0);
            assert_eq!(
                scenario.image.extension().and_then(|e| e.to_str()),
                Some("hex")
            );
            read += 1;
        }
        assert!(read >= 9, "{read} scenarios");
    }

    fn read_scenario(path: &Path) -> Scenario {
        read(path).unwrap_or_else(|e| panic!("{e:#?}"))
    }

    #[test]
    fn a_step_it_does_not_know_is_refused_by_name() {
        let text = r#"{"about": "x", "scan_us": 10, "steps": [{"run_ms": 5}, {"jump": 1}]}"#;
        let err = serde_json::from_str::<Scenario>(text)
            .unwrap_err()
            .to_string();
        assert!(err.contains("unknown variant `jump`"), "{err}");
        let steps: Vec<Step> =
            serde_json::from_str(r#"["reset", {"volts": ["A6", 2.5]}, {"type": "EX0\r"}]"#)
                .expect("steps");
        assert_eq!(
            steps,
            vec![
                Step::Reset,
                Step::Volts("A6".into(), 2.5),
                Step::Type("EX0\r".into())
            ]
        );
    }
}
