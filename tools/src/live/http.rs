//! The web server (axum): the page's files, the JSON API, the server-sent events that carry
//! every change, writes by POST, and the terminal's WebSocket. docs/LIVE.md documents the API.
//! Every handler reads the latest published view (never a lock the line waits on); the
//! events carry the state as serialized once per change, the same bytes for every page. The
//! state is the line's view with the figures of the parts that publish their own beside it
//! (the gateway's counters, the rig's state), each from its owner's `watch`.

use std::convert::Infallible;
use std::sync::Arc;
use std::time::{Duration, Instant};

use axum::body::Bytes;
use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{FromRef, Path, Query, State};
use axum::http::{header, HeaderMap, Method, StatusCode, Uri};
use axum::response::sse::{Event, KeepAlive, Sse};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use futures_util::stream::{self, Stream};
use serde::{Deserialize, Serialize};
use tokio::sync::mpsc;

use super::api::{ApiError, KeysBody, KeysSent, TrendDoc, WriteBody, WriteDone};
use super::assets;
use super::check;
use super::gateway::{Counters, Figures};
use super::hub::Hub;
use super::job::{Done, Job, TAKEN_WAIT};
use super::ladder;
use super::lease::PageId;
use super::origin::{self, Door};
use super::rig::{self, Rig, RigView};
use super::rtu;
use super::scan_control;
use super::send;
use super::signals::{self, SIGNALS};
use super::unit::TREND_STEP;
use super::view::{LineFigures, View, TREND_SIGNALS};

/// The events are sent at most this often (the line refreshes a uTile about every 53 ms).
const EVENT_GAP: Duration = Duration::from_millis(20);
/// The longest a page's write (or keys) waits for the line to take it.
const WRITE_WAIT: Duration = Duration::from_secs(5);

/// What the web server's handlers share: the hub, and the parts that publish their own
/// state beside the line's (the rig's client, the gateway's counters).
#[derive(Clone)]
pub struct App {
    /// Where the parts meet.
    pub hub: Arc<Hub>,
    /// `--rig`'s client.
    pub rig: Option<Arc<Rig>>,
    /// The gateway's counters (all zero without a gateway).
    pub gateway: Arc<Counters>,
}

impl FromRef<App> for Arc<Hub> {
    fn from_ref(app: &App) -> Arc<Hub> {
        app.hub.clone()
    }
}

impl FromRef<App> for Option<Arc<Rig>> {
    fn from_ref(app: &App) -> Option<Arc<Rig>> {
        app.rig.clone()
    }
}

/// `/api/state`: the line's view, its figures with the gateway's, the rig's state.
#[derive(Serialize)]
struct StateDoc<'a> {
    #[serde(flatten)]
    view: &'a View,
    line: LineDoc<'a>,
    rig: Option<&'a RigView>,
}

/// The state's `line`: the line's figures and the gateway's.
#[derive(Serialize)]
struct LineDoc<'a> {
    #[serde(flatten)]
    line: &'a LineFigures,
    #[serde(flatten)]
    gateway: &'a Figures,
}

impl App {
    /// The state as of now, as JSON.
    fn state_json(&self) -> Result<Bytes, ApiError> {
        let view = self.hub.view();
        let gateway = self.gateway.now();
        let rig = self.rig.as_ref().map(|r| r.view());
        let doc = StateDoc {
            view: &view,
            line: LineDoc {
                line: &view.line,
                gateway: &gateway,
            },
            rig: rig.as_ref(),
        };
        serde_json::to_vec(&doc)
            .map(Bytes::from)
            .map_err(|e| ApiError::Unserializable(e.to_string()))
    }
}

/// The routes: one line each (hold and step, a program sent, a rig panel go here too), behind
/// `door`'s rules (`origin.rs`: what another web page could send is refused first).
pub fn router(app: App, door: Door) -> Router {
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
        .with_state(app)
        .layer(axum::middleware::from_fn_with_state(
            Arc::new(door),
            origin::check,
        ))
}

/// Serializes the state once per change of the line's view, the gateway's figures or the
/// rig's state (at most once per [`EVENT_GAP`]) for every page that follows the events;
/// runs until the line's owner is gone.
pub async fn serialize_views(app: App) {
    let mut views = app.hub.views();
    let mut gateway = app.gateway.figures();
    let mut rig = app.rig.as_ref().map(|r| r.views());
    loop {
        views.mark_unchanged();
        gateway.mark_unchanged();
        if let Some(r) = rig.as_mut() {
            r.mark_unchanged();
        }
        match app.state_json() {
            Ok(json) => {
                app.hub.state_json.send_replace(json);
            }
            Err(e) => tracing::error!(error = %e, "the state cannot be serialized"),
        }
        let sent = Instant::now();
        // A rig's client that has stopped changes nothing more.
        let rig_changed = async {
            let moved = match rig.as_mut() {
                Some(r) => r.changed().await.is_ok(),
                None => false,
            };
            if !moved {
                std::future::pending::<()>().await;
            }
        };
        // The counters live as long as `app`: they always can change.
        let gone = tokio::select! {
            r = views.changed() => r.is_err(),
            _ = gateway.changed() => false,
            () = rig_changed => false,
        };
        if gone {
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

/// `GET /api/state`: the state as of now.
async fn state(State(app): State<App>) -> Result<Response, ApiError> {
    app.state_json().map(json_bytes)
}

/// `GET /api/signals`: the signal table (name, what, how written, range, unit).
async fn signal_table() -> Json<&'static [signals::Signal]> {
    Json(SIGNALS.as_slice())
}

/// `GET /api/events`'s query: the page that follows them (`?page=ID`, made by the page).
#[derive(Debug, Deserialize)]
struct EventsQuery {
    page: Option<String>,
}

/// A page following the events: while its stream lives its holds do; dropped with the
/// stream, it tells the hub when the page closed.
struct Following {
    hub: Arc<Hub>,
    page: PageId,
}

impl Following {
    /// Page `page` follows the events from now on (refused when too many do).
    fn start(hub: Arc<Hub>, page: PageId) -> Result<Following, ApiError> {
        let mut opened = Ok(());
        hub.pages
            .send_modify(|p| opened = p.opened(&page, Instant::now()));
        opened?;
        Ok(Following { hub, page })
    }
}

impl Drop for Following {
    fn drop(&mut self) {
        let page = &self.page;
        self.hub
            .pages
            .send_modify(|p| p.closed(page, Instant::now()));
    }
}

/// Every change as an event `state` carrying what `/api/state` gives, as serialized once.
/// A page that names itself (`?page=ID`) holds what it holds while it follows them.
async fn events(
    State(hub): State<Arc<Hub>>,
    Query(query): Query<EventsQuery>,
) -> Result<Sse<impl Stream<Item = Result<Event, Infallible>>>, ApiError> {
    let following = match query.page.as_deref() {
        Some(name) => Some(Following::start(hub.clone(), PageId::parse(name)?)?),
        None => None,
    };
    let rx = hub.state_json.subscribe();
    let stream = stream::unfold(
        (rx, true, following),
        |(mut rx, first, following)| async move {
            if !first && rx.changed().await.is_err() {
                return None;
            }
            loop {
                let json = rx.borrow_and_update().clone();
                if !json.is_empty() {
                    let event = Event::default()
                        .event("state")
                        .data(String::from_utf8_lossy(&json));
                    return Some((Ok(event), (rx, false, following)));
                }
                // Nothing serialized yet: the first comes at once.
                if rx.changed().await.is_err() {
                    return None;
                }
            }
        },
    );
    Ok(Sse::new(stream).keep_alive(KeepAlive::default()))
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
    let done = hub.ask(Job::page(addr, w.pdu()), WRITE_WAIT).await?;
    if let Some(code) = rtu::exception(&done.pdu) {
        return Err(ApiError::Exception {
            addr,
            what: format!("{signal} = {value}"),
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
/// through), once they went; refused while the port is closed (never kept for later).
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
    hub.keys(keys)?.answer(WRITE_WAIT, TAKEN_WAIT).await?;
    Ok(Json(KeysSent { ok: true }))
}

/// The terminal's WebSocket: uTile's output as binary messages, keys back; keys the line
/// refused are answered with a text message saying why (the page shows it by the terminal).
async fn terminal(State(hub): State<Arc<Hub>>, ws: WebSocketUpgrade) -> Response {
    ws.on_upgrade(move |socket| terminal_session(socket, hub))
}

/// At most this many refusals wait to be told to one terminal (more say the same).
const REFUSALS: usize = 4;

async fn terminal_session(mut socket: WebSocket, hub: Arc<Hub>) {
    let (kept, mut rx) = hub.terminal.subscribe();
    if socket
        .send(Message::Binary(Bytes::from(kept)))
        .await
        .is_err()
    {
        return;
    }
    let (refused_tx, mut refused) = mpsc::channel::<String>(REFUSALS);
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
            Some(why) = refused.recv() => {
                if socket.send(Message::Text(why.into())).await.is_err() {
                    return;
                }
            }
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
                // Handed over now, in the order typed; whether they went comes later.
                let went = hub.keys(keys);
                let tell = refused_tx.clone();
                tokio::spawn(async move {
                    let outcome = match went {
                        Ok(asked) => asked.answer(WRITE_WAIT, TAKEN_WAIT).await,
                        Err(why) => Err(why),
                    };
                    if let Err(why) = outcome {
                        // A full channel: the terminal is being told the same already.
                        let _ = tell.try_send(format!("keys not typed: {why}"));
                    }
                });
            }
        }
    }
}
