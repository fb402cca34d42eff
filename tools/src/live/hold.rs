//! SPEC §18 as the live view speaks it: the page's actions (hold, run, step) and the register
//! write each one is, what a request's PDU does to a hold, and whether a uTile's firmware
//! holds at all ([`PROBE`], once per uTile). Plain data and rules: no I/O, no clock.

use serde::Serialize;

use utile_core::modbus::hold::{HR_SCAN_CONTROL, HR_STEPS, MAX_STEPS};
use utile_core::modbus::{
    Exception, READ_HOLDING_REGISTERS, WRITE_MULTIPLE_REGISTERS, WRITE_SINGLE_REGISTER,
};

use super::rtu::{MASK_WRITE_REGISTER, READ_WRITE_MULTIPLE_REGISTERS};

/// Why a uTile's Run, Hold and Step are disabled: its firmware has no §18.
pub const NO_HOLD: &str = "this uTile's firmware cannot hold or step its scan (no SPEC §18: \
                           holding register 32 is outside its map): update the firmware";

/// The read that tells whether a uTile has §18: holding registers 32–33 (hold, steps left).
pub const PROBE: [u8; 5] = {
    let [a0, a1] = HR_SCAN_CONTROL.to_be_bytes();
    [READ_HOLDING_REGISTERS, a0, a1, 0, 2]
};

/// What a card knows of its uTile's hold and step.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ScanControl {
    /// The firmware has §18 (`null` until the line has asked).
    pub supported: Option<bool>,
    /// Why the buttons are disabled, in words.
    pub why: Option<&'static str>,
}

impl ScanControl {
    /// From the answer to [`PROBE`] (`Some(code)` for an exception).
    pub fn from_answer(exception: Option<u8>) -> ScanControl {
        if exception == Some(Exception::IllegalDataAddress as u8) {
            ScanControl {
                supported: Some(false),
                why: Some(NO_HOLD),
            }
        } else {
            ScanControl {
                supported: Some(true),
                why: None,
            }
        }
    }
}

/// Why a hold, run or step is refused before anything is sent.
#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    /// An action the route does not know.
    #[error("{0:?} is no action: the body takes {{\"action\": \"hold\" | \"run\" | \"step\", \"n\": 1..{MAX_STEPS}}}")]
    Action(String),
    /// Steps out of range.
    #[error("step takes n = 1..{MAX_STEPS} scans, not {0}")]
    Steps(i64),
    /// The firmware has no §18.
    #[error("{NO_HOLD}")]
    NoHold,
}

/// What the page asks of a uTile's scan.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    /// Hold the scan at its next END (register 32 = 1).
    Hold,
    /// Let it run freely (register 32 = 0).
    Run,
    /// Run exactly n scans, then hold (register 33 = n).
    Step(u16),
}

impl Action {
    /// `{"action": …, "n": …}` as the route takes it (`n` 1 when left out).
    pub fn parse(action: &str, n: Option<i64>) -> Result<Action, ScanError> {
        match action {
            "hold" => Ok(Action::Hold),
            "run" => Ok(Action::Run),
            "step" => {
                let n = n.unwrap_or(1);
                match u16::try_from(n) {
                    Ok(s @ 1..=MAX_STEPS) => Ok(Action::Step(s)),
                    _ => Err(ScanError::Steps(n)),
                }
            }
            other => Err(ScanError::Action(other.to_string())),
        }
    }

    /// The one register write it is (FC06).
    pub fn pdu(self) -> Vec<u8> {
        let (register, value) = match self {
            Action::Hold => (HR_SCAN_CONTROL, 1),
            Action::Run => (HR_SCAN_CONTROL, 0),
            Action::Step(n) => (HR_STEPS, n),
        };
        let [r0, r1] = register.to_be_bytes();
        let [v0, v1] = value.to_be_bytes();
        vec![WRITE_SINGLE_REGISTER, r0, r1, v0, v1]
    }

    /// Whether sending it twice does what sending it once does: a hold or a run sets the
    /// register to a value; a step asks for n *more* scans, so a second one runs 2n.
    pub fn harmless_again(self) -> bool {
        !matches!(self, Action::Step(_))
    }

    /// The scans asked for (a step's n, else 0).
    pub fn steps(self) -> u16 {
        match self {
            Action::Step(n) => n,
            _ => 0,
        }
    }

    /// What `pdu` does to a hold, when it is one of the writes the page makes (FC06 to
    /// register 32 or 33).
    pub fn of(pdu: &[u8]) -> Option<Action> {
        let [WRITE_SINGLE_REGISTER, a0, a1, v0, v1] = *pdu else {
            return None;
        };
        let value = u16::from_be_bytes([v0, v1]);
        match u16::from_be_bytes([a0, a1]) {
            HR_SCAN_CONTROL if value == 0 => Some(Action::Run),
            HR_SCAN_CONTROL if value == 1 => Some(Action::Hold),
            HR_STEPS if (1..=MAX_STEPS).contains(&value) => Some(Action::Step(value)),
            _ => None,
        }
    }
}

/// Whether `pdu` writes holding register 33 (steps): such a write asks for more scans each
/// time it lands, so it is never sent twice, from the page or through the gateway.
pub fn writes_steps(pdu: &[u8]) -> bool {
    let word = |at: usize| {
        pdu.get(at..at + 2)
            .map(|w| u16::from_be_bytes([w[0], w[1]]))
    };
    let covers = |start: Option<u16>, count: Option<u16>| match (start, count) {
        (Some(s), Some(n)) => (u32::from(s)..u32::from(s) + u32::from(n)).contains(&33),
        _ => false,
    };
    match pdu.first().copied() {
        Some(WRITE_SINGLE_REGISTER | MASK_WRITE_REGISTER) => word(1) == Some(HR_STEPS),
        Some(WRITE_MULTIPLE_REGISTERS) => covers(word(1), word(3)),
        Some(READ_WRITE_MULTIPLE_REGISTERS) => covers(word(5), word(7)),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_action_is_one_register_write_and_bad_ones_are_refused() {
        assert_eq!(Action::parse("hold", None).unwrap().pdu(), [6, 0, 32, 0, 1]);
        assert_eq!(
            Action::parse("run", Some(5)).unwrap().pdu(),
            [6, 0, 32, 0, 0]
        );
        assert_eq!(Action::parse("step", None).unwrap(), Action::Step(1));
        assert_eq!(
            Action::parse("step", Some(1000)).unwrap().pdu(),
            [6, 0, 33, 0x03, 0xE8]
        );
        assert!(matches!(
            Action::parse("step", Some(0)),
            Err(ScanError::Steps(0))
        ));
        assert!(matches!(
            Action::parse("step", Some(1001)),
            Err(ScanError::Steps(1001))
        ));
        assert!(matches!(
            Action::parse("pause", None),
            Err(ScanError::Action(_))
        ));
        assert_eq!(
            Action::parse("step", Some(-1)).unwrap_err().to_string(),
            "step takes n = 1..1000 scans, not -1"
        );
    }

    #[test]
    fn a_pdu_tells_its_action_and_only_steps_are_harmful_twice() {
        for a in [Action::Hold, Action::Run, Action::Step(1), Action::Step(10)] {
            assert_eq!(Action::of(&a.pdu()), Some(a));
            assert_eq!(a.harmless_again(), !writes_steps(&a.pdu()), "{a:?}");
        }
        assert_eq!(Action::of(&[6, 0, 24, 0, 1]), None, "a set-point");
        assert_eq!(
            Action::of(&[6, 0, 32, 0, 2]),
            None,
            "exception 03 on the uTile"
        );
        // Writes of register 33 by any function, as a gateway client may send them.
        assert!(writes_steps(&[0x10, 0, 32, 0, 2, 4, 0, 1, 0, 5]));
        assert!(writes_steps(&[0x10, 0, 33, 0, 1, 2, 0, 5]));
        assert!(!writes_steps(&[0x10, 0, 24, 0, 2, 4, 0, 1, 0, 2]));
        assert!(writes_steps(&[0x17, 0, 0, 0, 1, 0, 33, 0, 1, 2, 0, 5]));
        assert!(
            !writes_steps(&[0x17, 0, 33, 0, 1, 0, 0, 0, 1, 2, 0, 5]),
            "reads 33"
        );
        assert!(writes_steps(&[0x16, 0, 33, 0, 0, 0, 5]));
        assert!(!writes_steps(&[3, 0, 33, 0, 1]));
    }

    #[test]
    fn exception_02_to_the_probe_means_no_hold() {
        assert_eq!(ScanControl::from_answer(Some(2)).supported, Some(false));
        assert_eq!(ScanControl::from_answer(Some(2)).why, Some(NO_HOLD));
        assert_eq!(ScanControl::from_answer(None).supported, Some(true));
    }
}
