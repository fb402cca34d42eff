//! Hold, run and step (SPEC §18) from the page: `POST /api/units/{addr}/scan` with
//! `{"action": "hold" | "run" | "step", "n": N}` becomes one register write (holding register
//! 32 = 1 or 0, or 33 = n) that goes through the line's queue ahead of the polls, like any
//! write of the page. A uTile whose firmware has no §18 answers exception 02: the card says
//! so and its buttons stay disabled (the line learns it once per uTile, [`PROBE`]).

use std::sync::Arc;
use std::time::Duration;

use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::{Deserialize, Serialize};

use utile_core::modbus::hold::{HR_SCAN_CONTROL, HR_STEPS, MAX_STEPS};
use utile_core::modbus::{Exception, READ_HOLDING_REGISTERS, WRITE_SINGLE_REGISTER};

use super::api::{ApiError, ErrorDoc};
use super::hub::{Hub, Input};
use super::queue::{Job, Origin};
use super::rtu;

/// Why a uTile's Run, Hold and Step are disabled: its firmware has no §18.
pub const NO_HOLD: &str = "this uTile's firmware cannot hold or step its scan (no SPEC §18: \
                           holding register 32 is outside its map): update the firmware";

/// The read that tells whether a uTile has §18: holding registers 32–33 (hold, steps left).
pub const PROBE: [u8; 5] = {
    let [a0, a1] = HR_SCAN_CONTROL.to_be_bytes();
    [READ_HOLDING_REGISTERS, a0, a1, 0, 2]
};

/// The longest the page's request waits for the line.
const WAIT: Duration = Duration::from_secs(5);

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

/// `POST /api/units/{addr}/scan`'s body.
#[derive(Debug, Deserialize)]
pub struct ScanBody {
    /// `hold`, `run` or `step`.
    #[serde(default)]
    pub action: String,
    /// Scans to run for `step` (1..1000; 1 when left out).
    pub n: Option<i64>,
}

/// A hold, run or step carried out.
#[derive(Debug, Serialize)]
pub struct ScanDone {
    /// Always true.
    pub ok: bool,
    /// The action.
    pub action: String,
    /// Scans asked for (`step`), else 0.
    pub n: u16,
    /// From the request's first byte out to the reply's last byte in, ms.
    pub on_line_ms: f64,
}

/// Why a hold, run or step failed.
#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    /// What any route of the API may answer.
    #[error(transparent)]
    Api(#[from] ApiError),
    /// An action the route does not know.
    #[error("{0:?} is no action: the body takes {{\"action\": \"hold\" | \"run\" | \"step\", \"n\": 1..{MAX_STEPS}}}")]
    Action(String),
    /// Steps out of range.
    #[error("step takes n = 1..{MAX_STEPS} scans, not {0}")]
    Steps(i64),
    /// The firmware has no §18.
    #[error("{NO_HOLD}")]
    NoHold,
    /// The uTile refused with another exception.
    #[error("uTile {addr} refused {action}: {}", rtu::exception_text(*code))]
    Exception {
        /// The uTile.
        addr: u8,
        /// The action.
        action: String,
        /// The exception code.
        code: u8,
    },
}

impl IntoResponse for ScanError {
    fn into_response(self) -> Response {
        let e = match self {
            ScanError::Api(e) => return e.into_response(),
            other => other,
        };
        let status = match &e {
            ScanError::Action(_) | ScanError::Steps(_) => StatusCode::BAD_REQUEST,
            ScanError::NoHold => StatusCode::CONFLICT,
            ScanError::Api(_) | ScanError::Exception { .. } => StatusCode::UNPROCESSABLE_ENTITY,
        };
        (
            status,
            Json(ErrorDoc {
                error: e.to_string(),
            }),
        )
            .into_response()
    }
}

/// The register write an action is: (register, value, steps).
pub fn write_for(action: &str, n: Option<i64>) -> Result<(u16, u16, u16), ScanError> {
    match action {
        "hold" => Ok((HR_SCAN_CONTROL, 1, 0)),
        "run" => Ok((HR_SCAN_CONTROL, 0, 0)),
        "step" => {
            let n = n.unwrap_or(1);
            match u16::try_from(n) {
                Ok(s @ 1..=MAX_STEPS) => Ok((HR_STEPS, s, s)),
                _ => Err(ScanError::Steps(n)),
            }
        }
        other => Err(ScanError::Action(other.to_string())),
    }
}

/// `POST /api/units/{addr}/scan`: hold, run or step, ahead of the polls.
pub async fn post(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
    body: Result<Json<ScanBody>, JsonRejection>,
) -> Result<Json<ScanDone>, ScanError> {
    let Path(addr) = addr.map_err(ApiError::from)?;
    let view = hub.view();
    let unit = view.unit(addr).ok_or(ApiError::NoUnit(addr))?;
    let Json(body) = body.map_err(ApiError::from)?;
    let (register, value, n) = write_for(&body.action, body.n)?;
    if hub.read_only {
        return Err(ApiError::ReadOnly.into());
    }
    if unit.scan_control.supported == Some(false) {
        return Err(ScanError::NoHold);
    }
    let [r0, r1] = register.to_be_bytes();
    let [v0, v1] = value.to_be_bytes();
    let pdu = vec![WRITE_SINGLE_REGISTER, r0, r1, v0, v1];
    let (job, rx) = Job::new(addr, pdu, Origin::Page);
    hub.inputs
        .send(Input::Job(job))
        .map_err(|_| ApiError::LineStopped)?;
    let done = match tokio::time::timeout(WAIT, rx).await {
        Ok(Ok(Ok(done))) => done,
        Ok(Ok(Err(f))) => return Err(ApiError::Line(f).into()),
        Ok(Err(_)) => return Err(ApiError::LineStopped.into()),
        Err(_) => return Err(ApiError::LineTimeout.into()),
    };
    match rtu::exception(&done.pdu) {
        Some(code) if code == Exception::IllegalDataAddress as u8 => Err(ScanError::NoHold),
        Some(code) => Err(ScanError::Exception {
            addr,
            action: body.action,
            code,
        }),
        None => {
            if value == 0 && register == HR_SCAN_CONTROL {
                hub.holds.ran(addr);
            } else {
                hub.holds.held(addr);
            }
            Ok(Json(ScanDone {
                ok: true,
                action: body.action,
                n,
                on_line_ms: done.on_line.as_secs_f64() * 1e3,
            }))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_action_is_one_register_write_and_bad_ones_are_refused() {
        assert_eq!(write_for("hold", None).unwrap(), (32, 1, 0));
        assert_eq!(write_for("run", Some(5)).unwrap(), (32, 0, 0));
        assert_eq!(write_for("step", None).unwrap(), (33, 1, 1));
        assert_eq!(write_for("step", Some(1000)).unwrap(), (33, 1000, 1000));
        assert!(matches!(
            write_for("step", Some(0)),
            Err(ScanError::Steps(0))
        ));
        assert!(matches!(
            write_for("step", Some(1001)),
            Err(ScanError::Steps(1001))
        ));
        assert!(matches!(
            write_for("pause", None),
            Err(ScanError::Action(_))
        ));
        assert_eq!(
            write_for("step", Some(-1)).unwrap_err().to_string(),
            "step takes n = 1..1000 scans, not -1"
        );
    }

    #[test]
    fn exception_02_to_the_probe_means_no_hold() {
        assert_eq!(ScanControl::from_answer(Some(2)).supported, Some(false));
        assert_eq!(ScanControl::from_answer(Some(2)).why, Some(NO_HOLD));
        assert_eq!(ScanControl::from_answer(None).supported, Some(true));
    }
}
