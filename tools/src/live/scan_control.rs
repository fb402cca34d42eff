//! Hold, run and step (SPEC §18) from the page or a script: `POST /api/units/{addr}/scan`
//! with `{"action": "hold" | "run" | "step", "n": N, "page": ID}` becomes one register write
//! (holding register 32 = 1 or 0, or 33 = n, [`Action`]) that goes through the line's queue
//! ahead of the polls, like any write of the page. Its holder is the page that names itself
//! (and follows the events), else the API: the line keeps each holder's lease
//! ([`crate::live::lease`]). A step is never sent twice. A uTile whose firmware has no §18
//! answers exception 02: the card says so and its buttons stay disabled.

use std::sync::Arc;
use std::time::Duration;

use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::extract::{Path, State};
use axum::Json;
use serde::{Deserialize, Serialize};

use utile_core::modbus::Exception;

use super::api::ApiError;
use super::hold::{Action, ScanError};
use super::hub::Hub;
use super::job::{Failure, Job};
use super::lease::{Holder, PageId};
use super::rtu;

/// The longest the request waits for the line to take it.
const WAIT: Duration = Duration::from_secs(5);

/// `POST /api/units/{addr}/scan`'s body.
#[derive(Debug, Deserialize)]
pub struct ScanBody {
    /// `hold`, `run` or `step`.
    #[serde(default)]
    pub action: String,
    /// Scans to run for `step` (1..1000; 1 when left out).
    pub n: Option<i64>,
    /// The page that asks (its events' `?page=`): its hold lives while it follows them.
    pub page: Option<String>,
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

/// Who holds by a request naming `page`: that page while it follows the events (or did
/// lately), else the API.
fn holder(hub: &Hub, page: Option<&str>) -> Result<Holder, ApiError> {
    let Some(name) = page else {
        return Ok(Holder::Api);
    };
    let id = PageId::parse(name)?;
    Ok(if hub.pages.borrow().knows(&id) {
        Holder::Page(id)
    } else {
        Holder::Api
    })
}

/// `POST /api/units/{addr}/scan`: hold, run or step, ahead of the polls.
pub async fn post(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
    body: Result<Json<ScanBody>, JsonRejection>,
) -> Result<Json<ScanDone>, ApiError> {
    let Path(addr) = addr?;
    let view = hub.view();
    let unit = view.unit(addr).ok_or(ApiError::NoUnit(addr))?;
    let Json(body) = body?;
    let action = Action::parse(&body.action, body.n)?;
    if hub.read_only {
        return Err(ApiError::ReadOnly);
    }
    if unit.scan_control.supported == Some(false) {
        return Err(ScanError::NoHold.into());
    }
    let holder = holder(&hub, body.page.as_deref())?;
    let done = match hub.ask(Job::scan(addr, action, holder), WAIT).await {
        Err(Failure::NoAnswer) if !action.harmless_again() => {
            return Err(ApiError::Unanswered {
                addr,
                what: format!("step {}", action.steps()),
            })
        }
        other => other?,
    };
    match rtu::exception(&done.pdu) {
        Some(code) if code == Exception::IllegalDataAddress as u8 => Err(ScanError::NoHold.into()),
        Some(code) => Err(ApiError::Exception {
            addr,
            what: body.action,
            code,
        }),
        None => Ok(Json(ScanDone {
            ok: true,
            action: body.action,
            n: action.steps(),
            on_line_ms: done.on_line.as_secs_f64() * 1e3,
        })),
    }
}
