//! `--rig PATH`: the virtual Nano's rig (`cargo nano --control PATH`, a Unix socket, one JSON
//! object a line) worked from the page. A task keeps the socket open (and opens it again when
//! the virtual Nano restarts), asks the rig's state every [`ASK_EVERY`] and carries out the
//! page's requests: `POST /api/units/{addr}/rig` takes the socket's own JSON (`{"press": 0}`,
//! `{"release": 0}`, `{"a6": 2.5}`, `{"d8": true}`, `{"reset": true}`, `{}`) and answers the
//! rig's state after it. The line's owner publishes the latest [`RigView`] with its view
//! (`/api/state`'s `rig`), so the page shows its rig panel only while a rig answers.

use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::extract::{Path, State};
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use axum::Json;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use tokio::io::{AsyncBufReadExt, AsyncWriteExt, BufReader};
use tokio::net::UnixStream;
use tokio::sync::{mpsc, oneshot, watch};

use super::api::{ApiError, ErrorDoc};
use super::hub::Hub;

/// How often the rig's state is asked when the page asks nothing (the plant and the
/// terminal's rig keys move it too).
pub const ASK_EVERY: Duration = Duration::from_millis(200);
/// The longest wait for the rig's answer.
const ANSWER_WAIT: Duration = Duration::from_secs(3);
/// The wait before the socket is tried again.
const RETRY: Duration = Duration::from_millis(500);

/// The rig's state as the virtual Nano answers it.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RigState {
    /// Switches A0..A5, `true` when pressed.
    pub switches: [bool; 6],
    /// The chip's A0..A5 pins as it reads them (a pressed switch pulls its pin low).
    pub pins: [bool; 6],
    /// Jumper D8 fitted (autostart).
    pub d8: bool,
    /// Jumper D9 fitted.
    pub d9: bool,
    /// A6's level, volts.
    pub a6: f64,
    /// A7's level, volts.
    pub a7: f64,
    /// Outputs Y0..Y7 as the pins show them.
    pub outputs: [bool; 8],
}

/// `/api/state`'s `rig`: the socket, whether it answers, its state.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RigView {
    /// `--rig`'s path.
    pub path: String,
    /// The rig answers (the page shows its panel).
    pub connected: bool,
    /// Its latest state.
    pub state: Option<RigState>,
    /// Why it does not answer, in words.
    pub error: Option<String>,
}

/// One request for the rig and where its answer goes.
type Request = (Value, oneshot::Sender<Result<RigState, RigError>>);

/// The rig's client: its requests and its latest view.
pub struct Rig {
    requests: mpsc::UnboundedSender<Request>,
    view: watch::Receiver<RigView>,
    changes: Arc<AtomicU64>,
}

impl Rig {
    /// Starts the client of the socket at `path` on the current tokio runtime.
    pub fn spawn(path: PathBuf) -> Rig {
        let (requests, rx) = mpsc::unbounded_channel();
        let (tx, view) = watch::channel(RigView {
            path: path.display().to_string(),
            error: Some("not connected yet".into()),
            ..RigView::default()
        });
        let changes = Arc::new(AtomicU64::new(0));
        let counter = changes.clone();
        let mut seen = view.clone();
        // Counts each change, so the line's owner publishes a view when the rig moved.
        tokio::spawn(async move {
            while seen.changed().await.is_ok() {
                counter.fetch_add(1, Ordering::Relaxed);
            }
        });
        tokio::spawn(run(path, rx, tx));
        Rig {
            requests,
            view,
            changes,
        }
    }

    /// How many times the view changed so far.
    pub fn changes(&self) -> u64 {
        self.changes.load(Ordering::Relaxed)
    }

    /// The latest view.
    pub fn view(&self) -> RigView {
        self.view.borrow().clone()
    }

    /// Carries `request` out on the rig: its state after it.
    pub async fn ask(&self, request: Value) -> Result<RigState, RigError> {
        let (tx, rx) = oneshot::channel();
        self.requests
            .send((request, tx))
            .map_err(|_| RigError::NotConnected("the rig's client has stopped".into()))?;
        match tokio::time::timeout(ANSWER_WAIT * 2, rx).await {
            Ok(Ok(answer)) => answer,
            Ok(Err(_)) => Err(RigError::NotConnected(
                "the rig's client has stopped".into(),
            )),
            Err(_) => Err(RigError::NoAnswer),
        }
    }
}

/// Why a rig request failed.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// What any route of the API may answer.
    #[error(transparent)]
    Api(#[from] ApiError),
    /// `utile live` has no `--rig`.
    #[error(
        "no rig: this utile live was started without --rig PATH (the virtual Nano's \
         --control socket; ./x run --live wires it)"
    )]
    NoRig,
    /// The socket does not answer.
    #[error("the rig does not answer: {0}")]
    NotConnected(String),
    /// The body is no JSON object.
    #[error("a rig request is one JSON object, e.g. {{\"press\": 0}}")]
    NotAnObject,
    /// The rig refused the request (nothing changed).
    #[error("the rig refused it: {0}")]
    Refused(String),
    /// No answer in time.
    #[error("the rig did not answer within {} s", ANSWER_WAIT.as_secs())]
    NoAnswer,
}

impl IntoResponse for RigError {
    fn into_response(self) -> Response {
        let status = match &self {
            RigError::Api(e) => e.status(),
            RigError::NoRig => StatusCode::NOT_FOUND,
            RigError::NotConnected(_) => StatusCode::SERVICE_UNAVAILABLE,
            RigError::NotAnObject | RigError::Refused(_) => StatusCode::BAD_REQUEST,
            RigError::NoAnswer => StatusCode::GATEWAY_TIMEOUT,
        };
        (
            status,
            Json(ErrorDoc {
                error: self.to_string(),
            }),
        )
            .into_response()
    }
}

/// The socket's answer: the state, or the rig's refusal.
fn answer(line: &str) -> Result<RigState, RigError> {
    let value: Value = serde_json::from_str(line)
        .map_err(|e| RigError::NotConnected(format!("its answer is not JSON: {e}")))?;
    if let Some(why) = value.get("error").and_then(Value::as_str) {
        return Err(RigError::Refused(why.to_string()));
    }
    serde_json::from_value(value)
        .map_err(|e| RigError::NotConnected(format!("its answer is no rig state: {e}")))
}

/// The client: connects, serves, connects again.
async fn run(
    path: PathBuf,
    mut rx: mpsc::UnboundedReceiver<Request>,
    view: watch::Sender<RigView>,
) {
    let name = path.display().to_string();
    loop {
        let why = match UnixStream::connect(&path).await {
            Ok(stream) => serve(stream, &mut rx, &view, &name).await,
            Err(e) => format!("{name}: {e} (is the virtual Nano running with --control {name}?)"),
        };
        if rx.is_closed() {
            return;
        }
        view.send_if_modified(|v| {
            let was = v.clone();
            v.connected = false;
            v.state = None;
            v.error = Some(why.clone());
            *v != was
        });
        let wait = tokio::time::sleep(RETRY);
        tokio::pin!(wait);
        loop {
            tokio::select! {
                _ = &mut wait => break,
                r = rx.recv() => match r {
                    Some((_, reply)) => {
                        let _ = reply.send(Err(RigError::NotConnected(why.clone())));
                    }
                    None => return,
                },
            }
        }
    }
}

/// Serves one connection until it fails; the reason in words.
async fn serve(
    stream: UnixStream,
    rx: &mut mpsc::UnboundedReceiver<Request>,
    view: &watch::Sender<RigView>,
    name: &str,
) -> String {
    let (read, mut write) = stream.into_split();
    let mut lines = BufReader::new(read).lines();
    let ask = |request: Value| {
        let mut text = request.to_string();
        text.push('\n');
        text
    };
    let mut tick = tokio::time::interval(ASK_EVERY);
    loop {
        let (request, reply) = tokio::select! {
            r = rx.recv() => match r {
                Some((request, reply)) => (request, Some(reply)),
                None => return "utile live is stopping".into(),
            },
            _ = tick.tick() => (Value::Object(Default::default()), None),
        };
        if let Err(e) = write.write_all(ask(request).as_bytes()).await {
            return format!("{name}: {e}");
        }
        let line = match tokio::time::timeout(ANSWER_WAIT, lines.next_line()).await {
            Ok(Ok(Some(line))) => line,
            Ok(Ok(None)) => return format!("{name}: the virtual Nano closed the socket"),
            Ok(Err(e)) => return format!("{name}: {e}"),
            Err(_) => {
                if let Some(reply) = reply {
                    let _ = reply.send(Err(RigError::NoAnswer));
                }
                return format!("{name}: no answer within {} s", ANSWER_WAIT.as_secs());
            }
        };
        let got = answer(&line);
        let state = match &got {
            Ok(s) => Some(s.clone()),
            // A refusal still tells nothing new: the state stays the last one.
            Err(_) => view.borrow().state.clone(),
        };
        view.send_if_modified(|v| {
            let now = RigView {
                path: name.to_string(),
                connected: true,
                state: state.clone(),
                error: None,
            };
            let changed = *v != now;
            *v = now;
            changed
        });
        if let Some(reply) = reply {
            let _ = reply.send(got);
        }
    }
}

/// `POST /api/units/{addr}/rig`: one request for the rig (the socket's JSON), its state after.
pub async fn post(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
    body: Result<Json<Value>, JsonRejection>,
) -> Result<Json<RigState>, RigError> {
    let Path(addr) = addr.map_err(ApiError::from)?;
    hub.view().unit(addr).ok_or(ApiError::NoUnit(addr))?;
    let Json(body) = body.map_err(ApiError::from)?;
    if hub.read_only {
        return Err(ApiError::ReadOnly.into());
    }
    let rig = hub.rig.as_ref().ok_or(RigError::NoRig)?;
    if !body.is_object() {
        return Err(RigError::NotAnObject);
    }
    let view = rig.view();
    if !view.connected {
        return Err(RigError::NotConnected(view.error.unwrap_or_default()));
    }
    Ok(Json(rig.ask(body).await?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_answer_is_the_state_or_the_rigs_refusal() {
        let s = answer(
            r#"{"switches":[true,false,false,false,false,false],"pins":[false,true,true,true,true,true],
                "d8":true,"d9":false,"a6":2.5,"a7":0.0,"outputs":[true,false,false,false,false,false,false,false]}"#,
        )
        .unwrap();
        assert!(s.switches[0] && !s.pins[0] && s.d8 && s.outputs[0]);
        assert_eq!(s.a6, 2.5);
        let e = answer(r#"{"error":"press: switches are 0..5 (A0..A5), not 9","switches":[]}"#);
        assert!(matches!(e, Err(RigError::Refused(w)) if w.contains("0..5")));
        assert!(matches!(answer("nonsense"), Err(RigError::NotConnected(_))));
    }
}
