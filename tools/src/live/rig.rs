//! `--rig PATH`: the virtual Nano's rig (`cargo nano --control PATH`, a Unix socket, one JSON
//! object a line) worked from the page. A task keeps the socket open (and opens it again when
//! the virtual Nano restarts), asks the rig's state every [`ASK_EVERY`] and carries out the
//! page's requests: `POST /api/units/{addr}/rig` takes the socket's own JSON (`{"press": 0}`,
//! `{"release": 0}`, `{"a6": 2.5}`, `{"d8": true}`, `{"reset": true}`, `{}`: the socket's
//! [`RigRequest`], the one struct both ends use) and answers the rig's state after it. The
//! client publishes the latest [`RigView`] (a `watch` it owns; the state's `rig`), so the page
//! shows its rig panel only while a rig answers.
//!
//! On a bus (`cargo nano --bus N --control PATH`) the socket serves N Nanos, Nano k being
//! the one at slave address k: each is asked in turn, the view holds each one's state, and
//! the card of uTile k works Nano k (the route adds `"nano": k` to the page's request). A
//! single Nano's rig is on every card.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::extract::{Path, State};
use axum::Json;
use serde::{Deserialize, Serialize};
use serde_json::Value;
use tokio::io::{AsyncBufReadExt, AsyncWriteExt, BufReader};
use tokio::net::UnixStream;
use tokio::sync::{mpsc, oneshot, watch};

use super::api::{ApiError, RigError};
use super::hub::Hub;
use crate::vnano::control::RigRequest;

/// At most this many requests wait for the rig (a page's buttons and sliders); more are
/// refused as busy.
const REQUESTS: usize = 16;
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
    /// Which Nano of the socket (1..`nanos`, its slave address on a bus).
    #[serde(default = "one")]
    pub nano: u8,
    /// How many Nanos the socket serves (1 without a bus).
    #[serde(default = "one")]
    pub nanos: u8,
}

/// A single Nano's `nano` and `nanos`.
fn one() -> u8 {
    1
}

/// `/api/state`'s `rig`: the socket, whether it answers, its state.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RigView {
    /// `--rig`'s path.
    pub path: String,
    /// The rig answers (the page shows its panel).
    pub connected: bool,
    /// Each Nano's latest state, Nano 1 first (one without a bus; empty until it answers).
    pub nanos: Vec<RigState>,
    /// Why it does not answer, in words.
    pub error: Option<String>,
}

/// One request for the rig and where its answer goes.
type Request = (RigRequest, oneshot::Sender<Result<RigState, RigError>>);

/// The rig's client: its requests and its latest view.
pub struct Rig {
    requests: mpsc::Sender<Request>,
    view: watch::Receiver<RigView>,
}

impl RigView {
    /// The Nano (1..) that uTile `addr`'s card works: the one Nano without a bus, else the
    /// one at that slave address; `None` when the rig has none there.
    pub fn nano_of(&self, addr: u8) -> Option<u8> {
        match self.nanos.len() {
            0 => None,
            1 => Some(1),
            n => (1..=n).contains(&usize::from(addr)).then_some(addr),
        }
    }
}

impl Rig {
    /// Starts the client of the socket at `path` on the current tokio runtime.
    pub fn spawn(path: PathBuf) -> Rig {
        let (requests, rx) = mpsc::channel(REQUESTS);
        let (tx, view) = watch::channel(RigView {
            path: path.display().to_string(),
            error: Some("not connected yet".into()),
            ..RigView::default()
        });
        tokio::spawn(run(path, rx, tx));
        Rig { requests, view }
    }

    /// Each new view as it comes.
    pub fn views(&self) -> watch::Receiver<RigView> {
        self.view.clone()
    }

    /// The latest view.
    pub fn view(&self) -> RigView {
        self.view.borrow().clone()
    }

    /// Carries `request` out on the rig: its state after it.
    pub async fn ask(&self, request: RigRequest) -> Result<RigState, RigError> {
        let (tx, rx) = oneshot::channel();
        self.requests.try_send((request, tx)).map_err(|e| match e {
            mpsc::error::TrySendError::Full(_) => RigError::Busy,
            mpsc::error::TrySendError::Closed(_) => {
                RigError::NotConnected("the rig's client has stopped".into())
            }
        })?;
        match tokio::time::timeout(ANSWER_WAIT * 2, rx).await {
            Ok(Ok(answer)) => answer,
            Ok(Err(_)) => Err(RigError::NotConnected(
                "the rig's client has stopped".into(),
            )),
            Err(_) => Err(RigError::NoAnswer(ANSWER_WAIT.as_secs())),
        }
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
async fn run(path: PathBuf, mut rx: mpsc::Receiver<Request>, view: watch::Sender<RigView>) {
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
            v.nanos.clear();
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
    rx: &mut mpsc::Receiver<Request>,
    view: &watch::Sender<RigView>,
    name: &str,
) -> String {
    let (read, write) = stream.into_split();
    let mut socket = Socket {
        lines: BufReader::new(read).lines(),
        write,
        name,
    };
    let mut nanos: Vec<RigState> = Vec::new();
    let mut tick = tokio::time::interval(ASK_EVERY);
    loop {
        let asks: Vec<(RigRequest, Option<_>)> = tokio::select! {
            r = rx.recv() => match r {
                Some((request, reply)) => vec![(request, Some(reply))],
                None => return "utile live is stopping".into(),
            },
            // Each Nano in turn (`{}` until the first answer tells how many there are).
            _ = tick.tick() => (1..=nanos.len().max(1)).map(|k| (ask_of(k, nanos.len()), None)).collect(),
        };
        for (request, reply) in asks {
            let line = match socket.exchange(&request).await {
                Ok(line) => line,
                Err(why) => {
                    if let Some(reply) = reply {
                        let _ = reply.send(Err(RigError::NotConnected(why.clone())));
                    }
                    return why;
                }
            };
            let got = answer(&line);
            // A refusal tells nothing new: the states stay the last ones.
            if let Ok(s) = &got {
                nanos.resize(usize::from(s.nanos.max(1)), RigState::default());
                if let Some(slot) = nanos.get_mut(usize::from(s.nano.max(1)) - 1) {
                    *slot = s.clone();
                }
            }
            view.send_if_modified(|v| {
                let now = RigView {
                    path: name.to_string(),
                    connected: true,
                    nanos: nanos.clone(),
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
}

/// The periodic request for Nano `k` of `count`: `{}` for a single one (or before the first
/// answer), `{"nano": k}` on a bus.
fn ask_of(k: usize, count: usize) -> RigRequest {
    RigRequest {
        nano: (count > 1).then(|| u8::try_from(k).unwrap_or(u8::MAX)),
        ..RigRequest::default()
    }
}

/// The socket's two ends.
struct Socket<'a> {
    lines: tokio::io::Lines<BufReader<tokio::net::unix::OwnedReadHalf>>,
    write: tokio::net::unix::OwnedWriteHalf,
    name: &'a str,
}

impl Socket<'_> {
    /// Sends one request line and reads its answer; why not, in words.
    async fn exchange(&mut self, request: &RigRequest) -> Result<String, String> {
        let name = self.name;
        let mut text = serde_json::to_string(request).map_err(|e| format!("{name}: {e}"))?;
        text.push('\n');
        if let Err(e) = self.write.write_all(text.as_bytes()).await {
            return Err(format!("{name}: {e}"));
        }
        match tokio::time::timeout(ANSWER_WAIT, self.lines.next_line()).await {
            Ok(Ok(Some(line))) => Ok(line),
            Ok(Ok(None)) => Err(format!("{name}: the virtual Nano closed the socket")),
            Ok(Err(e)) => Err(format!("{name}: {e}")),
            Err(_) => Err(format!(
                "{name}: no answer within {} s",
                ANSWER_WAIT.as_secs()
            )),
        }
    }
}

/// `POST /api/units/{addr}/rig`: one request for the rig (the socket's JSON), its state after.
pub async fn post(
    State(hub): State<Arc<Hub>>,
    State(rig): State<Option<Arc<Rig>>>,
    addr: Result<Path<u8>, PathRejection>,
    body: Result<Json<Value>, JsonRejection>,
) -> Result<Json<RigState>, ApiError> {
    let Path(addr) = addr?;
    hub.view().unit(addr).ok_or(ApiError::NoUnit(addr))?;
    let Json(body) = body?;
    // Read as the socket reads it (a JSON array would make a struct by position).
    let Value::Object(fields) = body else {
        return Err(RigError::NotARequest(format!("not {body}")).into());
    };
    let mut request = RigRequest::from_object(&fields).map_err(RigError::NotARequest)?;
    if hub.read_only {
        return Err(ApiError::ReadOnly);
    }
    let rig = rig.as_ref().ok_or(RigError::NoRig)?;
    if request.nano.is_some() {
        return Err(RigError::NanoGiven.into());
    }
    let view = rig.view();
    if !view.connected {
        return Err(RigError::NotConnected(view.error.unwrap_or_default()).into());
    }
    let nano = view.nano_of(addr).ok_or(RigError::NoNano {
        addr,
        nanos: view.nanos.len(),
    })?;
    if view.nanos.len() > 1 {
        request.nano = Some(nano);
    }
    Ok(Json(rig.ask(request).await?))
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
        assert_eq!((s.nano, s.nanos), (1, 1), "a single Nano's answer");
        let e = answer(r#"{"error":"press: switches are 0..5 (A0..A5), not 9","switches":[]}"#);
        assert!(matches!(e, Err(RigError::Refused(w)) if w.contains("0..5")));
        assert!(matches!(answer("nonsense"), Err(RigError::NotConnected(_))));
        let e = answer(r#"{"error":"no Nano 4 here: nano is 1..3","nanos":3}"#);
        assert!(matches!(e, Err(RigError::Refused(w)) if w.contains("1..3")));
    }

    #[test]
    fn a_card_works_the_only_nano_or_the_one_at_its_address() {
        let of = |n: u8| RigView {
            nanos: (1..=n)
                .map(|k| RigState {
                    nano: k,
                    nanos: n,
                    ..RigState::default()
                })
                .collect(),
            connected: true,
            ..RigView::default()
        };
        assert_eq!(of(0).nano_of(1), None, "no answer yet");
        assert_eq!((of(1).nano_of(1), of(1).nano_of(7)), (Some(1), Some(1)));
        assert_eq!(of(3).nano_of(2), Some(2));
        assert_eq!((of(3).nano_of(0), of(3).nano_of(4)), (None, None));
    }
}
