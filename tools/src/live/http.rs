//! The web server (axum): the page's files, the JSON API, the server-sent events that carry
//! every change, writes by POST, and the terminal's WebSocket. docs/LIVE.md documents the API.
//! Every handler reads the latest published view (never a lock the line waits on); the
//! events carry the state as serialized once per change, the same bytes for every page.

use std::convert::Infallible;
use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::body::Bytes;
use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{Path, State};
use axum::http::{header, HeaderMap, Method, StatusCode, Uri};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use futures_util::stream::{self, Stream};

use super::api::{ApiError, KeysBody, KeysSent, TrendDoc, WriteBody, WriteDone};
use super::assets;
use super::check;
use super::hub::{Hub, Input};
use super::ladder;
use super::origin::{self, Door};
use super::queue::{Done, Job, Origin};
use super::rig;
use super::rtu;
use super::scan_control;
use super::send;
use super::signals::{self, SIGNALS};
use super::unit::TREND_STEP;
use super::view::{View, TREND_SIGNALS};

/// The events are sent at most this often (the line refreshes a uTile about every 53 ms).
const EVENT_GAP: Duration = Duration::from_millis(20);
/// The longest a page's write waits for the line.
const WRITE_WAIT: Duration = Duration::from_secs(5);

/// The routes: one line each (hold and step, a program sent, a rig panel go here too), behind
/// `door`'s rules (`origin.rs`: what another web page could send is refused first).
pub fn router(hub: Arc<Hub>, door: Door) -> Router {
    Router::new()
        .route("/api/state", get(state))
        .route("/api/events", get(events))
        .route("/api/signals", get(signal_table))
        .route("/api/units/{addr}/write", post(write))
        .route("/api/units/{addr}/scan", post(scan_control::post))
        .route("/api/units/{addr}/rig", post(rig::post))
        .route("/api/check", post(check::post))
        .route("/api/units/{addr}/program", get(program).post(send::post))
        .route("/api/units/{addr}/trend", get(trend))
        .route("/api/units/{addr}/ladder", get(ladder::get))
        .route("/api/terminal", get(terminal).post(keys))
        .fallback(file)
        .method_not_allowed_fallback(wrong_method)
        .with_state(hub)
        .layer(axum::middleware::from_fn_with_state(
            Arc::new(door),
            origin::check,
        ))
}

/// Serializes each new view once (at most one per [`EVENT_GAP`]) for every page that
/// follows the events; runs until the line's owner is gone.
pub async fn serialize_views(hub: Arc<Hub>) {
    let mut views = hub.views();
    loop {
        let view = views.borrow_and_update().clone();
        match serde_json::to_vec(&*view) {
            Ok(json) => {
                hub.state_json.send_replace(Bytes::from(json));
            }
            Err(e) => tracing::error!(error = %e, "the state cannot be serialized"),
        }
        let sent = Instant::now();
        if views.changed().await.is_err() {
            return;
        }
        let since = sent.elapsed();
        if since < EVENT_GAP {
            tokio::time::sleep(EVENT_GAP - since).await;
        }
    }
}

/// A page file; outside the API's routes, 404.
async fn file(method: Method, uri: Uri) -> Response {
    let path = uri.path();
    if path.starts_with("/api/") {
        return ApiError::NoRoute(path.to_string()).into_response();
    }
    if method != Method::GET && method != Method::HEAD {
        return ApiError::Method(format!("{method} {path}")).into_response();
    }
    match assets::get(path) {
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

/// A route asked with a method it does not take.
async fn wrong_method(method: Method, uri: Uri) -> ApiError {
    ApiError::Method(format!("{method} {}", uri.path()))
}

/// `{"content-type": "application/json"}` and `json`.
fn json_bytes(json: Bytes) -> Response {
    ([(header::CONTENT_TYPE, "application/json")], json).into_response()
}

/// `GET /api/state`: the latest view.
async fn state(State(hub): State<Arc<Hub>>) -> Result<Response, ApiError> {
    let view = hub.view();
    match serde_json::to_vec(&*view) {
        Ok(json) => Ok(json_bytes(Bytes::from(json))),
        Err(e) => {
            tracing::error!(error = %e, "the state cannot be serialized");
            Err(ApiError::LineStopped)
        }
    }
}

/// `GET /api/signals`: the signal table (name, what, how written, range, unit).
async fn signal_table() -> Json<&'static [signals::Signal]> {
    Json(SIGNALS.as_slice())
}

/// Every change as an event `state` carrying what `/api/state` gives, as serialized once.
async fn events(State(hub): State<Arc<Hub>>) -> Sse<impl Stream<Item = Result<Event, Infallible>>> {
    let rx = hub.state_json.subscribe();
    let stream = stream::unfold((rx, true), |(mut rx, first)| async move {
        if !first && rx.changed().await.is_err() {
            return None;
        }
        loop {
            let json = rx.borrow_and_update().clone();
            if !json.is_empty() {
                let event = Event::default()
                    .event("state")
                    .data(String::from_utf8_lossy(&json));
                return Some((Ok(event), (rx, false)));
            }
            // Nothing serialized yet: the first comes at once.
            if rx.changed().await.is_err() {
                return None;
            }
        }
    });
    Sse::new(stream).keep_alive(KeepAlive::default())
}

/// The uTile at the path's address in `view`, or why not.
fn unit_in(view: &View, addr: Result<Path<u8>, PathRejection>) -> Result<u8, ApiError> {
    let Path(addr) = addr?;
    view.unit(addr)
        .map(|u| u.addr)
        .ok_or(ApiError::NoUnit(addr))
}

/// `POST /api/units/{addr}/write` with `{"signal": "U0", "value": 1}`: checked against the
/// signal table, then sent ahead of the polls; the uTile's refusal comes back in words.
async fn write(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
    body: Result<Json<WriteBody>, JsonRejection>,
) -> Result<Json<WriteDone>, ApiError> {
    if hub.read_only {
        return Err(ApiError::ReadOnly);
    }
    let addr = unit_in(&hub.view(), addr)?;
    let Json(body) = body?;
    let value = body.number()?;
    let done = write_signal(&hub, addr, &body.signal, value).await?;
    Ok(Json(WriteDone {
        ok: true,
        waited_ms: done.waited.as_secs_f64() * 1e3,
        on_line_ms: done.on_line.as_secs_f64() * 1e3,
    }))
}

/// Writes `signal = value` to uTile `addr` as every write by name goes (the page's, and
/// MQTT's `set` topics): `--read-only`, the uTile on the line, the signal table's name and
/// range, then ahead of the polls in the line's queue, and the uTile's answer.
pub async fn write_signal(hub: &Hub, addr: u8, signal: &str, value: i64) -> Result<Done, ApiError> {
    if hub.read_only {
        return Err(ApiError::ReadOnly);
    }
    if hub.view().unit(addr).is_none() {
        return Err(ApiError::NoUnit(addr));
    }
    let w = signals::write(signal, value)?;
    let (job, rx) = Job::new(addr, w.pdu(), Origin::Page);
    hub.inputs
        .send(Input::Job(job))
        .map_err(|_| ApiError::LineStopped)?;
    let done = match tokio::time::timeout(WRITE_WAIT, rx).await {
        Ok(Ok(Ok(done))) => done,
        Ok(Ok(Err(f))) => return Err(ApiError::Line(f)),
        Ok(Err(_)) => return Err(ApiError::LineStopped),
        Err(_) => return Err(ApiError::LineTimeout),
    };
    if let Some(code) = rtu::exception(&done.pdu) {
        return Err(ApiError::Exception {
            addr,
            signal: signal.to_string(),
            value,
            code,
        });
    }
    Ok(done)
}

/// The listing of the program that runs (read over Modbus, SPEC §17).
async fn program(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
) -> Result<Response, ApiError> {
    let view = hub.view();
    let addr = unit_in(&view, addr)?;
    let listing = view
        .unit(addr)
        .and_then(|u| u.listing.clone())
        .ok_or(ApiError::NoProgram)?;
    Ok(Json(&*listing).into_response())
}

/// The trend: A6, A7 and the counts, one point per [`TREND_STEP`], seconds before now.
async fn trend(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
) -> Result<Json<TrendDoc>, ApiError> {
    let now = Instant::now();
    let view = hub.view();
    let addr = unit_in(&view, addr)?;
    let trend = view
        .unit(addr)
        .map(|u| u.trend.clone())
        .ok_or(ApiError::NoUnit(addr))?;
    let t = trend
        .points
        .iter()
        .map(|(at, _)| -now.duration_since(*at).as_secs_f64())
        .collect();
    let series = (0..TREND_SIGNALS.len())
        .map(|i| trend.points.iter().map(|(_, p)| p[i]).collect())
        .collect();
    Ok(Json(TrendDoc {
        step_ms: TREND_STEP.as_millis() as u64,
        names: &TREND_SIGNALS,
        t,
        series,
    }))
}

/// `POST /api/terminal`: the body's bytes typed into the terminal (for scripts), or with
/// `Content-Type: application/json` the text of `{"keys": "…"}` (the door lets no other type
/// through).
async fn keys(
    State(hub): State<Arc<Hub>>,
    headers: HeaderMap,
    body: Bytes,
) -> Result<Json<KeysSent>, ApiError> {
    if hub.read_only {
        return Err(ApiError::ReadOnlyKeys);
    }
    let keys = if origin::keys_as_json(&headers) {
        serde_json::from_slice::<KeysBody>(&body)
            .map_err(|e| ApiError::KeysBody(e.to_string()))?
            .keys
            .into_bytes()
    } else {
        body.to_vec()
    };
    hub.inputs
        .send(Input::Keys(keys))
        .map_err(|_| ApiError::LineStopped)?;
    Ok(Json(KeysSent { ok: true }))
}

/// The terminal's WebSocket: uTile's output as binary messages, keys back.
async fn terminal(State(hub): State<Arc<Hub>>, ws: WebSocketUpgrade) -> Response {
    ws.on_upgrade(move |socket| terminal_session(socket, hub))
}

async fn terminal_session(mut socket: WebSocket, hub: Arc<Hub>) {
    let (kept, mut rx) = hub.terminal.subscribe();
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
                Err(tokio::sync::broadcast::error::RecvError::Lagged(n)) => {
                    tracing::warn!(chunks = n, "a terminal page fell behind: output lost");
                }
                Err(_) => return,
            },
            msg = socket.recv() => {
                let keys = match msg {
                    Some(Ok(Message::Text(t))) => t.as_str().as_bytes().to_vec(),
                    Some(Ok(Message::Binary(b))) => b.to_vec(),
                    Some(Ok(_)) => continue,
                    _ => return,
                };
                if hub.read_only {
                    // Keys can stop a program (`/`): a read-only view takes none.
                    continue;
                }
                if hub.inputs.send(Input::Keys(keys)).is_err() {
                    return;
                }
            }
        }
    }
}
