//! The JSON API's documents besides the view itself (a program's listing is
//! [`Listing`](super::view::Listing)): a write's body and answer, the trend, and the one error
//! type. Every failure, axum's own rejections included (a path that names no address, a body
//! that is not JSON), is answered as `{"error": "…"}` with its status, in words the page
//! shows as they are.

use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::{Deserialize, Serialize};
use serde_json::Value;

use utile_core::modbus::MAX_ADDRESS;

use super::queue::Failure;
use super::rtu::exception_text;
use super::signals::Refused;

/// `{"error": "…"}`.
#[derive(Debug, Serialize, Deserialize)]
pub struct ErrorDoc {
    /// What went wrong, and what the user can do.
    pub error: String,
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
    /// The line's owner is gone.
    #[error("the line has stopped")]
    LineStopped,
    /// The line did not carry it out.
    #[error("{}", .0.text())]
    Line(Failure),
    /// The line did not get to it in time.
    #[error("the line did not get to it")]
    LineTimeout,
    /// The uTile answered with an exception.
    #[error("uTile {addr} refused {signal} = {value}: {}", exception_text(*code))]
    Exception {
        /// The uTile.
        addr: u8,
        /// The signal written.
        signal: String,
        /// The value.
        value: i64,
        /// The exception code.
        code: u8,
    },
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
            ApiError::NoUnit(_) | ApiError::NoProgram | ApiError::NoRoute(_) => {
                StatusCode::NOT_FOUND
            }
            ApiError::BadAddress(_)
            | ApiError::BadPath(_)
            | ApiError::NotANumber(_)
            | ApiError::KeysBody(_)
            | ApiError::Refused(_) => StatusCode::BAD_REQUEST,
            ApiError::BadBody { status, .. } => *status,
            ApiError::ReadOnly | ApiError::ReadOnlyKeys => StatusCode::FORBIDDEN,
            ApiError::LineStopped => StatusCode::SERVICE_UNAVAILABLE,
            ApiError::Line(Failure::Editing) => StatusCode::CONFLICT,
            ApiError::Line(Failure::NoAnswer) | ApiError::LineTimeout => {
                StatusCode::GATEWAY_TIMEOUT
            }
            ApiError::Line(_) => StatusCode::SERVICE_UNAVAILABLE,
            ApiError::Exception { .. } => StatusCode::UNPROCESSABLE_ENTITY,
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
        (
            status,
            Json(ErrorDoc {
                error: self.to_string(),
            }),
        )
            .into_response()
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
