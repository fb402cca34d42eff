//! Send a program from the page: `POST /api/units/{addr}/program` with
//! `{"listing": "…", "store": bool, "run": bool}`. The listing is checked whole first (the
//! kit's parser, `utile asm`'s messages): one with mistakes sends nothing. Then the send is a
//! job of the line's owner, like the terminal's editor session: polling pauses while the
//! editor has the line. On the line it is `utile push --stop`'s steps
//! ([`crate::link::Session`], on a clone of the line's port): `/` stops the program (a program
//! without KEY is refused), READ takes the image (only a whole, checked file replaces the
//! program), STORE if asked, EX0 if asked; then the line reads it back: the §17 program block
//! and the snapshot's fingerprint must be the image's (without EX0, WRITE reads it back).

use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::{Deserialize, Serialize};
use serialport::TTYPort;
use tokio::sync::oneshot;

use utile_core::modbus::snapshot;
use utile_core::Program;

use super::api::{ApiError, ErrorDoc};
use super::check;
use super::hub::{Hub, Input};
use crate::link::port::Port;
use crate::link::port::PortError;
use crate::link::session::{LinkError, Session};

/// The longest the page's request waits for the line (stop, READ, WRITE, STORE, EX0 take
/// about 2 s at 19200 baud; the session's own time-outs end a silent uTile sooner).
const WAIT: Duration = Duration::from_secs(40);

/// What the page says when a program without KEY runs.
pub const NO_KEY: &str = "a program without KEY is running: `/` does not stop it, so nothing \
                          was sent: stop it at the uTile — remove D8 and reset — or add KEY";

/// `POST /api/units/{addr}/program`'s body.
#[derive(Debug, Deserialize)]
pub struct SendBody {
    /// The listing's text, as a `.utl` file holds it.
    #[serde(default)]
    pub listing: String,
    /// STORE it into EEPROM (autostart with D8) after it is loaded.
    #[serde(default)]
    pub store: bool,
    /// Start it (EX0) after it is loaded.
    #[serde(default)]
    pub run: bool,
}

/// A program sent.
#[derive(Debug, Serialize)]
pub struct Sent {
    /// The image's fingerprint (SPEC §17), the one the snapshot shows once it runs.
    pub fingerprint: u16,
    /// From the line taking the job to the last step done, ms.
    pub ms: f64,
    /// STOREd.
    pub stored: bool,
    /// Running.
    pub running: bool,
}

/// Why a send failed.
#[derive(Debug, thiserror::Error)]
pub enum SendError {
    /// What any route of the API may answer.
    #[error(transparent)]
    Api(#[from] ApiError),
    /// The listing has mistakes: nothing was sent.
    #[error("line {line}: {message} (nothing was sent)")]
    Listing {
        /// The first mistake's line, 1-based.
        line: usize,
        /// `utile asm`'s words.
        message: String,
    },
    /// More than one uTile on the line.
    #[error("this line has {0} uTiles: sending a program needs one uTile on the cable (the editor answers every one of them); nothing was sent")]
    Bus(usize),
    /// A program without KEY runs.
    #[error("{NO_KEY}")]
    NoKey,
    /// The port is not open, or the editor did not answer.
    #[error("{0}")]
    NoAnswer(String),
    /// The port failed during the send.
    #[error("the serial port was lost during the send ({0}): READ replaces the program only with a whole, checked file, so uTile keeps a whole program (the one before if READ had not finished). Reconnect and send again")]
    Lost(String),
    /// uTile refused the file, or it read back different.
    #[error("{0}")]
    Refused(String),
}

impl IntoResponse for SendError {
    fn into_response(self) -> Response {
        let (status, line) = match &self {
            SendError::Api(_) => {
                let SendError::Api(e) = self else {
                    unreachable!("matched above")
                };
                return e.into_response();
            }
            SendError::Listing { line, .. } => (StatusCode::BAD_REQUEST, Some(*line)),
            SendError::Bus(_) | SendError::NoKey => (StatusCode::CONFLICT, None),
            SendError::NoAnswer(_) | SendError::Lost(_) => (StatusCode::GATEWAY_TIMEOUT, None),
            SendError::Refused(_) => (StatusCode::UNPROCESSABLE_ENTITY, None),
        };
        let error = self.to_string();
        match line {
            Some(line) => (status, Json(ListingDoc { error, line })).into_response(),
            None => (status, Json(ErrorDoc { error })).into_response(),
        }
    }
}

/// `{"error": …, "line": N}`: a listing's mistake.
#[derive(Debug, Serialize)]
struct ListingDoc {
    error: String,
    line: usize,
}

/// A send for the line's owner.
#[derive(Debug)]
pub struct SendJob {
    /// The uTile.
    pub addr: u8,
    /// The image, checked.
    pub prog: Program,
    /// STORE after READ.
    pub store: bool,
    /// EX0 at the end.
    pub run: bool,
    /// Where the outcome goes.
    pub reply: oneshot::Sender<Result<Sent, SendError>>,
}

/// What the line's owner knows when it takes a send.
pub struct LineNow<'a> {
    /// The port's path (for the messages).
    pub path: &'a str,
    /// The open port, if any.
    pub port: Option<&'a TTYPort>,
    /// uTiles on the line.
    pub units: usize,
    /// A program runs (RUN mode).
    pub running: bool,
}

/// A send's steps on the line, and what came in meanwhile (for the terminal).
pub fn carry_out(line: LineNow, job: &SendJob) -> (Result<Sent, SendError>, Vec<u8>) {
    let start = Instant::now();
    if line.units > 1 {
        return (Err(SendError::Bus(line.units)), Vec::new());
    }
    let Some(tty) = line.port else {
        return (
            Err(SendError::NoAnswer(format!(
                "{}: the serial port is not open: nothing was sent",
                line.path
            ))),
            Vec::new(),
        );
    };
    let port = match tty.try_clone_native() {
        Ok(t) => match Port::wrap(Box::new(t)) {
            Ok(p) => p,
            Err(e) => return (Err(classify(e.into())), Vec::new()),
        },
        Err(e) => return (Err(SendError::Lost(e.to_string())), Vec::new()),
    };
    let mut say = |m: &str| {
        tracing::info!(
            addr = job.addr,
            at_ms = start.elapsed().as_millis() as u64,
            "send: {m}"
        )
    };
    let mut session = match Session::attach(port, line.path, line.running, &mut say) {
        Ok(s) => s,
        Err(e) => return (Err(classify(e)), Vec::new()),
    };
    let result = steps(&mut session, job, &mut say).map(|()| Sent {
        fingerprint: snapshot::fingerprint(&job.prog.uf),
        ms: start.elapsed().as_secs_f64() * 1e3,
        stored: job.store,
        running: job.run,
    });
    (result.map_err(classify), session.transcript().to_vec())
}

/// READ (with WRITE's read-back when it is not started), STORE, EX0.
fn steps(s: &mut Session, job: &SendJob, say: &mut dyn FnMut(&str)) -> Result<(), LinkError> {
    if job.run {
        // Read back over Modbus once it runs (the §17 program block, by the line).
        s.load(&job.prog, say).map(drop)?;
    } else {
        // It will not run: read back through WRITE.
        s.push(&job.prog, say)?;
    }
    if job.store {
        s.store(say)?;
    }
    if job.run {
        s.run(say)?;
    }
    Ok(())
}

/// A session's failure as the API's error: the port failing is a lost port, a program `/`
/// does not stop one without KEY, a refused or differing file a refusal, the rest no answer.
fn classify(e: LinkError) -> SendError {
    // The whole cause chain, as the page shows it.
    let mut words = e.to_string();
    let mut cause = std::error::Error::source(&e);
    while let Some(c) = cause {
        words.push_str(&format!(": {c}"));
        cause = c.source();
    }
    match e {
        LinkError::Port(PortError::Read(_) | PortError::Write(_) | PortError::Timeout(_)) => {
            SendError::Lost(words)
        }
        LinkError::DidNotStop(_) => SendError::NoKey,
        LinkError::Refused(_) | LinkError::ReadBackDiffers => SendError::Refused(words),
        _ => SendError::NoAnswer(words),
    }
}

/// `POST /api/units/{addr}/program`: check, then send through the line's owner.
pub async fn post(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
    body: Result<Json<SendBody>, JsonRejection>,
) -> Result<Json<Sent>, SendError> {
    let Path(addr) = addr.map_err(ApiError::from)?;
    let Json(body) = body.map_err(ApiError::from)?;
    if let Some(p) = check::problems(&body.listing).into_iter().next() {
        return Err(SendError::Listing {
            line: p.line,
            message: p.message,
        });
    }
    let prog =
        utile_kit::listing::parse("listing", &body.listing).map_err(|e| SendError::Listing {
            line: 1,
            message: e.to_string(),
        })?;
    if hub.read_only {
        return Err(ApiError::ReadOnly.into());
    }
    let view = hub.view();
    view.unit(addr).ok_or(ApiError::NoUnit(addr))?;
    let (reply, rx) = oneshot::channel();
    hub.inputs
        .send(Input::Send(Box::new(SendJob {
            addr,
            prog,
            store: body.store,
            run: body.run,
            reply,
        })))
        .map_err(|_| ApiError::LineStopped)?;
    match tokio::time::timeout(WAIT, rx).await {
        Ok(Ok(outcome)) => outcome.map(Json),
        Ok(Err(_)) => Err(ApiError::LineStopped.into()),
        Err(_) => Err(ApiError::LineTimeout.into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_port_failing_is_a_lost_port_and_a_refused_file_is_no_time_out() {
        let io = || std::io::Error::other("Input/output error");
        assert!(matches!(
            classify(LinkError::Port(PortError::Read(io()))),
            SendError::Lost(w) if w.contains("Input/output error")
        ));
        assert!(matches!(
            classify(LinkError::Refused("CRC".into())),
            SendError::Refused(_)
        ));
        assert!(matches!(
            classify(LinkError::DidNotStop("/dev/ttyUSB0".into())),
            SendError::NoKey
        ));
        assert!(matches!(
            classify(LinkError::NotTaken("READ")),
            SendError::NoAnswer(_)
        ));
        assert!(SendError::NoKey
            .to_string()
            .contains("stop it at the uTile — remove D8 and reset — or add KEY"));
    }
}
