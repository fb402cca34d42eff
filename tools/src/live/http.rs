//! The web server (axum): the page's files, the JSON API, the server-sent events that carry
//! every change, writes by POST, and the terminal's WebSocket. docs/LIVE.md documents the API.

use std::convert::Infallible;
use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::body::Bytes;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Path, State};
use axum::http::{header, StatusCode, Uri};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use futures_util::stream::{self, Stream};
use serde_json::{json, Value};

use super::assets;
use super::queue::{Failure, Job, Origin};
use super::rtu::exception_text;
use super::signals;
use super::state::{Input, Shared};
use super::unit::TREND_STEP;
use super::view;

/// The events are sent at most this often (the line refreshes a uTile about every 53 ms).
const EVENT_GAP: Duration = Duration::from_millis(20);
/// The longest a page's write waits for the line.
const WRITE_WAIT: Duration = Duration::from_secs(5);

/// The routes.
pub fn router(shared: Arc<Shared>) -> Router {
    Router::new()
        .route("/api/state", get(state))
        .route("/api/events", get(events))
        .route("/api/units/{addr}/write", post(write))
        .route("/api/units/{addr}/program", get(program))
        .route("/api/units/{addr}/trend", get(trend))
        .route("/api/terminal", get(terminal).post(keys))
        .fallback(get(file))
        .with_state(shared)
}

/// A page file, or 404.
async fn file(uri: Uri) -> Response {
    match assets::get(uri.path()) {
        Some((kind, body)) => (
            [
                (header::CONTENT_TYPE, kind),
                (header::CACHE_CONTROL, "no-cache"),
            ],
            body,
        )
            .into_response(),
        None => (StatusCode::NOT_FOUND, "no such page").into_response(),
    }
}

async fn state(State(shared): State<Arc<Shared>>) -> Json<Value> {
    Json(shared.state_json())
}

/// Every change as an event `state` carrying what `/api/state` gives.
async fn events(
    State(shared): State<Arc<Shared>>,
) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let rx = shared.changed.subscribe();
    let stream = stream::unfold(
        (rx, shared, None::<Instant>),
        |(mut rx, shared, last)| async move {
            if let Some(last) = last {
                // One event per change, at most one per EVENT_GAP.
                if rx.changed().await.is_err() {
                    return None;
                }
                let since = last.elapsed();
                if since < EVENT_GAP {
                    tokio::time::sleep(EVENT_GAP - since).await;
                }
                rx.borrow_and_update();
            }
            let data = shared.state_json().to_string();
            let event = Event::default().event("state").data(data);
            Some((Ok(event), (rx, shared, Some(Instant::now()))))
        },
    );
    Sse::new(stream).keep_alive(KeepAlive::default())
}

/// An answer with a status and `{"error": why}`.
fn refuse(code: StatusCode, why: impl Into<String>) -> Response {
    (code, Json(json!({ "error": why.into() }))).into_response()
}

/// The number in a write's `value`: a JSON number, or text as typed in a field.
fn number(v: &Value) -> Option<i64> {
    match v {
        Value::Number(n) => n.as_i64(),
        Value::String(s) => s.trim().parse().ok(),
        Value::Bool(b) => Some(i64::from(*b)),
        _ => None,
    }
}

/// `POST /api/units/{addr}/write` with `{"signal": "U0", "value": 1}`: checked against the
/// map's ranges, then sent ahead of the polls; the uTile's refusal comes back in words.
async fn write(
    State(shared): State<Arc<Shared>>,
    Path(addr): Path<u8>,
    Json(body): Json<Value>,
) -> Response {
    if shared.read_only {
        return refuse(
            StatusCode::FORBIDDEN,
            "read-only: this utile live was started with --read-only, every write is refused",
        );
    }
    if shared.lock().unit_mut(addr).is_none() {
        return refuse(
            StatusCode::NOT_FOUND,
            format!("no uTile {addr} on this line"),
        );
    }
    let signal = body.get("signal").and_then(Value::as_str).unwrap_or("");
    let Some(value) = body.get("value").and_then(number) else {
        return refuse(
            StatusCode::BAD_REQUEST,
            format!("{signal}: the value must be a whole number"),
        );
    };
    let w = match signals::write(signal, value) {
        Ok(w) => w,
        Err(why) => return refuse(StatusCode::BAD_REQUEST, why),
    };
    let (job, rx) = Job::new(addr, w.pdu(), Origin::Page);
    if shared.inputs.send(Input::Job(job)).is_err() {
        return refuse(StatusCode::SERVICE_UNAVAILABLE, "the line has stopped");
    }
    let done = match tokio::time::timeout(WRITE_WAIT, rx).await {
        Ok(Ok(Ok(done))) => done,
        Ok(Ok(Err(f))) => {
            let code = match f {
                Failure::Editing => StatusCode::CONFLICT,
                Failure::NoAnswer => StatusCode::GATEWAY_TIMEOUT,
                _ => StatusCode::SERVICE_UNAVAILABLE,
            };
            return refuse(code, f.text());
        }
        _ => return refuse(StatusCode::GATEWAY_TIMEOUT, "the line did not get to it"),
    };
    if done.pdu.first().is_some_and(|f| f & 0x80 != 0) {
        let code = done.pdu.get(1).copied().unwrap_or(0);
        return refuse(
            StatusCode::UNPROCESSABLE_ENTITY,
            format!(
                "uTile {addr} refused {signal} = {value}: {}",
                exception_text(code)
            ),
        );
    }
    Json(json!({
        "ok": true,
        "waited_ms": done.waited.as_secs_f64() * 1e3,
        "on_line_ms": done.on_line.as_secs_f64() * 1e3,
    }))
    .into_response()
}

/// The listing of the program that runs (read over Modbus, SPEC §17).
async fn program(State(shared): State<Arc<Shared>>, Path(addr): Path<u8>) -> Response {
    let mut live = shared.lock();
    let Some(u) = live.unit_mut(addr) else {
        return refuse(
            StatusCode::NOT_FOUND,
            format!("no uTile {addr} on this line"),
        );
    };
    let Some((fp, uf, same)) = &u.program else {
        return refuse(StatusCode::NOT_FOUND, "the program has not been read yet");
    };
    let lines: Vec<Value> = view::listing(uf)
        .into_iter()
        .map(|l| json!({"n": l.n, "name": l.name, "pops": view::pops(l.op)}))
        .collect();
    Json(json!({"fingerprint": fp, "consistent": same, "lines": lines})).into_response()
}

/// The trend: A6, A7 and the counts, one point per [`TREND_STEP`], seconds before now.
async fn trend(State(shared): State<Arc<Shared>>, Path(addr): Path<u8>) -> Response {
    let now = Instant::now();
    let mut live = shared.lock();
    let Some(u) = live.unit_mut(addr) else {
        return refuse(
            StatusCode::NOT_FOUND,
            format!("no uTile {addr} on this line"),
        );
    };
    let t: Vec<f64> = u
        .trend
        .iter()
        .map(|(at, _)| -now.duration_since(*at).as_secs_f64())
        .collect();
    let series: Vec<Vec<u16>> = (0..10)
        .map(|i| u.trend.iter().map(|(_, p)| p[i]).collect())
        .collect();
    Json(json!({"step_ms": TREND_STEP.as_millis() as u64, "t": t, "series": series}))
        .into_response()
}

/// `POST /api/terminal`: the body's bytes typed into the terminal (for scripts).
async fn keys(State(shared): State<Arc<Shared>>, body: Bytes) -> Response {
    if shared.read_only {
        return refuse(StatusCode::FORBIDDEN, "read-only: keys are refused");
    }
    if shared.inputs.send(Input::Keys(body.to_vec())).is_err() {
        return refuse(StatusCode::SERVICE_UNAVAILABLE, "the line has stopped");
    }
    Json(json!({"ok": true})).into_response()
}

/// The terminal's WebSocket: uTile's output as binary messages, keys back.
async fn terminal(State(shared): State<Arc<Shared>>, ws: WebSocketUpgrade) -> Response {
    ws.on_upgrade(move |socket| terminal_session(socket, shared))
}

async fn terminal_session(mut socket: WebSocket, shared: Arc<Shared>) {
    let (kept, mut rx) = shared.terminal.subscribe();
    if socket
        .send(Message::Binary(Bytes::from(kept)))
        .await
        .is_err()
    {
        return;
    }
    loop {
        tokio::select! {
            out = rx.recv() => match out {
                Ok(bytes) => {
                    if socket.send(Message::Binary(Bytes::from(bytes))).await.is_err() {
                        return;
                    }
                }
                Err(tokio::sync::broadcast::error::RecvError::Lagged(_)) => {}
                Err(_) => return,
            },
            msg = socket.recv() => {
                let keys = match msg {
                    Some(Ok(Message::Text(t))) => t.as_str().as_bytes().to_vec(),
                    Some(Ok(Message::Binary(b))) => b.to_vec(),
                    Some(Ok(_)) => continue,
                    _ => return,
                };
                if shared.read_only {
                    // Keys can stop a program (`/`): a read-only view takes none.
                    continue;
                }
                if shared.inputs.send(Input::Keys(keys)).is_err() {
                    return;
                }
            }
        }
    }
}
