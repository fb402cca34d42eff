//! The JSON API's documents besides the view itself (a program's listing is
//! [`Listing`](super::view::Listing)): a write's body and answer, the trend, and the one error
//! type, [`ApiError`], with one [`IntoResponse`] (as axum's error-handling example): every
//! failure of every route, axum's own rejections included (a path that names no address, a
//! body that is not JSON), the line's ([`Failure`]), a send's ([`SendFailure`]), a hold's
//! ([`ScanError`]) and the rig's ([`RigError`]), is answered as `{"error": "…"}` with its
//! status, in words the page shows as they are (a listing's mistake adds its `"line"`).

use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use utile_core::modbus::MAX_ADDRESS;

use super::hold::ScanError;
use super::job::{Failure, SendFailure};
use super::lease::{BadPage, TooManyPages};
use super::rtu::exception_text;
use super::signals::Refused;

/// `{"error": "…"}`, and for a listing's mistake its line.
#[derive(Debug, Serialize, Deserialize)]
pub struct ErrorDoc {
    /// What went wrong, and what the user can do.
    pub error: String,
    /// The listing's line the mistake is on, 1-based (a send's refused listing).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub line: Option<usize>,
}

/// Why a request to the virtual rig failed (`--rig`).
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// `utile live` has no `--rig`.
    #[error(
        "no rig: this utile live was started without --rig PATH (the virtual Nano's \
         --control socket; ./x run --live wires it)"
    )]
    NoRig,
    /// The socket does not answer.
    #[error("the rig does not answer: {0}")]
    NotConnected(String),
    /// Too many requests wait for the rig.
    #[error("too many requests are waiting for the rig: nothing was sent; try again")]
    Busy,
    /// The body is no rig request.
    #[error(
        "a rig request is one JSON object of press, release (switches 0..5), a6, a7 (volts), \
         d8, d9 (true or false), reset, e.g. {{\"press\": 0}}: {0}"
    )]
    NotARequest(String),
    /// The page named the Nano itself.
    #[error("the uTile's address picks its Nano: leave \"nano\" out")]
    NanoGiven,
    /// The bus has no Nano at the uTile's address.
    #[error("the rig's bus has no Nano at address {addr} (Nanos 1..{nanos})")]
    NoNano {
        /// The uTile's address.
        addr: u8,
        /// How many Nanos the rig has.
        nanos: usize,
    },
    /// The rig refused the request (nothing changed).
    #[error("the rig refused it: {0}")]
    Refused(String),
    /// No answer in time (within this many seconds).
    #[error("the rig did not answer within {0} s")]
    NoAnswer(u64),
}

/// Why a request to the API failed.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// The path names an address with no uTile.
    #[error("no uTile {0} on this line")]
    NoUnit(u8),
    /// The path's address is no number 0..255.
    #[error("{0:?} is no uTile's address: the path takes a slave address, 1..{MAX_ADDRESS}")]
    BadAddress(String),
    /// A path that axum could not take apart otherwise.
    #[error("this path cannot be read: {0}")]
    BadPath(String),
    /// The body is not the JSON the route takes.
    #[error("the body must be JSON such as {{\"signal\": \"U0\", \"value\": 1}}: {why}")]
    BadBody {
        /// axum's status for it.
        status: StatusCode,
        /// axum's words for it.
        why: String,
    },
    /// No program read yet.
    #[error("the program has not been read yet")]
    NoProgram,
    /// A write's value is not a whole number.
    #[error("{0}: the value must be a whole number")]
    NotANumber(String),
    /// A write the signal table refuses.
    #[error(transparent)]
    Refused(#[from] Refused),
    /// `--read-only`.
    #[error("read-only: this utile live was started with --read-only, every write is refused")]
    ReadOnly,
    /// `--read-only`, for keys.
    #[error("read-only: keys are refused")]
    ReadOnlyKeys,
    /// Keys sent as JSON that is not `{"keys": "…"}`.
    #[error("keys as JSON are {{\"keys\": \"EX0\\r\"}}: {0}")]
    KeysBody(String),
    /// The line did not carry the request out, or got no reply.
    #[error(transparent)]
    Line(#[from] Failure),
    /// The uTile answered with an exception.
    #[error("uTile {addr} refused {what}: {}", exception_text(*code))]
    Exception {
        /// The uTile.
        addr: u8,
        /// What was asked (`U0 = 5`, `hold`).
        what: String,
        /// The exception code.
        code: u8,
    },
    /// A write that is never sent twice (a step) got no answer: it may have landed.
    #[error("uTile {addr} did not answer {what}: it may have been carried out (it is never sent twice); the card shows what it did")]
    Unanswered {
        /// The uTile.
        addr: u8,
        /// What was asked (`step 10`).
        what: String,
    },
    /// A hold, run or step refused before anything was sent.
    #[error(transparent)]
    Scan(#[from] ScanError),
    /// A listing to send has a mistake: nothing was sent.
    #[error("line {line}: {message} (nothing was sent)")]
    Listing {
        /// The first mistake's line, 1-based.
        line: usize,
        /// `utile asm`'s words.
        message: String,
    },
    /// A send failed on the line.
    #[error(transparent)]
    Send(#[from] SendFailure),
    /// The rig refused or did not answer.
    #[error(transparent)]
    Rig(#[from] RigError),
    /// A page named itself wrongly (`?page=`, `"page"`).
    #[error(transparent)]
    Page(#[from] BadPage),
    /// Too many pages follow the events.
    #[error(transparent)]
    TooManyPages(#[from] TooManyPages),
    /// The state could not be written as JSON (a bug).
    #[error("the state cannot be serialized: {0}")]
    Unserializable(String),
    /// Refused at the door: what another web page could send (`origin.rs`).
    #[error(transparent)]
    Door(#[from] super::origin::Refused),
    /// No such route.
    #[error("there is no {0} in this API: see docs/LIVE.md")]
    NoRoute(String),
    /// The route does not take this method.
    #[error("{0} is not served here: see docs/LIVE.md")]
    Method(String),
}

impl ApiError {
    /// The HTTP status.
    pub fn status(&self) -> StatusCode {
        match self {
            ApiError::NoUnit(_)
            | ApiError::NoProgram
            | ApiError::NoRoute(_)
            | ApiError::Rig(RigError::NoRig | RigError::NoNano { .. }) => StatusCode::NOT_FOUND,
            ApiError::BadAddress(_)
            | ApiError::BadPath(_)
            | ApiError::NotANumber(_)
            | ApiError::KeysBody(_)
            | ApiError::Refused(_)
            | ApiError::Scan(ScanError::Action(_) | ScanError::Steps(_))
            | ApiError::Listing { .. }
            | ApiError::Page(_)
            | ApiError::Rig(
                RigError::NotARequest(_) | RigError::NanoGiven | RigError::Refused(_),
            ) => StatusCode::BAD_REQUEST,
            ApiError::BadBody { status, .. } => *status,
            ApiError::ReadOnly | ApiError::ReadOnlyKeys => StatusCode::FORBIDDEN,
            ApiError::Line(Failure::Editing)
            | ApiError::Scan(ScanError::NoHold)
            | ApiError::Send(SendFailure::Bus(_) | SendFailure::NoKey) => StatusCode::CONFLICT,
            ApiError::Line(Failure::NoAnswer)
            | ApiError::Unanswered { .. }
            | ApiError::Send(SendFailure::NoAnswer(_) | SendFailure::Lost(_))
            | ApiError::Rig(RigError::NoAnswer(_)) => StatusCode::GATEWAY_TIMEOUT,
            ApiError::Line(
                Failure::PortClosed | Failure::Busy | Failure::Stopped | Failure::NotTaken(_),
            )
            | ApiError::TooManyPages(_)
            | ApiError::Rig(RigError::NotConnected(_) | RigError::Busy) => {
                StatusCode::SERVICE_UNAVAILABLE
            }
            ApiError::Exception { .. } | ApiError::Send(SendFailure::Refused(_)) => {
                StatusCode::UNPROCESSABLE_ENTITY
            }
            ApiError::Unserializable(_) => StatusCode::INTERNAL_SERVER_ERROR,
            ApiError::Door(r) => r.status(),
            ApiError::Method(_) => StatusCode::METHOD_NOT_ALLOWED,
        }
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let status = self.status();
        if status.is_server_error() {
            tracing::warn!(%status, error = %self, "an API request failed");
        }
        let line = match &self {
            ApiError::Listing { line, .. } => Some(*line),
            _ => None,
        };
        let error = self.to_string();
        (status, Json(ErrorDoc { error, line })).into_response()
    }
}

impl From<PathRejection> for ApiError {
    fn from(r: PathRejection) -> Self {
        match r {
            PathRejection::FailedToDeserializePathParams(e) => match e.into_kind() {
                axum::extract::path::ErrorKind::ParseErrorAtKey { value, .. }
                | axum::extract::path::ErrorKind::ParseError { value, .. }
                | axum::extract::path::ErrorKind::ParseErrorAtIndex { value, .. } => {
                    ApiError::BadAddress(value)
                }
                other => ApiError::BadPath(other.to_string()),
            },
            other => ApiError::BadPath(other.body_text()),
        }
    }
}

impl From<JsonRejection> for ApiError {
    fn from(r: JsonRejection) -> Self {
        ApiError::BadBody {
            status: r.status(),
            why: r.body_text(),
        }
    }
}

/// `POST /api/units/{addr}/write`'s body: `{"signal": "U0", "value": 1}` (the value may be
/// text as typed in a field).
#[derive(Debug, Deserialize)]
pub struct WriteBody {
    /// The listing's name.
    #[serde(default)]
    pub signal: String,
    /// The value: a number, or text holding one.
    #[serde(default)]
    pub value: Value,
}

impl WriteBody {
    /// The value as a whole number.
    pub fn number(&self) -> Result<i64, ApiError> {
        match &self.value {
            Value::Number(n) => n.as_i64(),
            Value::String(s) => s.trim().parse().ok(),
            Value::Bool(b) => Some(i64::from(*b)),
            _ => None,
        }
        .ok_or_else(|| ApiError::NotANumber(self.signal.clone()))
    }
}

/// A write carried out.
#[derive(Debug, Serialize)]
pub struct WriteDone {
    /// Always true.
    pub ok: bool,
    /// How long it waited for the line, ms.
    pub waited_ms: f64,
    /// Its time on the line, ms.
    pub on_line_ms: f64,
}

/// `POST /api/terminal`'s body as JSON (`Content-Type: application/json`): the keys as text.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct KeysBody {
    /// What is typed, e.g. `"EX0\r"`.
    pub keys: String,
}

/// Keys sent.
#[derive(Debug, Serialize)]
pub struct KeysSent {
    /// Always true.
    pub ok: bool,
}

/// `GET /api/units/{addr}/trend`.
#[derive(Debug, Serialize)]
pub struct TrendDoc {
    /// One point per this many ms.
    pub step_ms: u64,
    /// What each series is.
    pub names: &'static [&'static str],
    /// Each point's time, seconds before now.
    pub t: Vec<f64>,
    /// A series per name.
    pub series: Vec<Vec<u16>>,
}
