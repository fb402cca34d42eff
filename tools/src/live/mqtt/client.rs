//! The connection to the broker: rumqttc's event loop driven in a task of its own, errors
//! told in words (a wrong password, a certificate that does not match, no broker), retries
//! that back off (0.1 s doubling to 1 s while the broker cannot be reached, to 30 s while it
//! refuses us), and after every connect the `set` subscription and every retained message
//! sent again. The publisher never waits on the network: it offers messages to the client's
//! queue and keeps what did not fit for the next turn. It also keeps each uTile's own
//! availability session (`availability.rs`) told, and on a clean stop publishes the line's
//! `offline` and every uTile's, then disconnects.

use std::collections::BTreeMap;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;

use rumqttc::{
    AsyncClient, ConnectReturnCode, ConnectionError, Event, EventLoop, Packet, Publish, QoS,
};
use tokio::sync::{mpsc, oneshot, watch};
use tokio::task::JoinHandle;

use super::availability::Sessions;
use super::options::{Broker, Settings};
use super::outbox::Outbox;
use super::payloads::{OFFLINE, ONLINE};
use super::{commands, discovery, payloads, Counters, Report, WriteRequest};

/// The client's queue of requests.
const QUEUE: usize = 4096;
/// The first wait after a failed connect.
pub const BACKOFF_MIN: Duration = Duration::from_millis(100);
/// The longest wait while the broker cannot be reached (it comes back within 2 s of that).
pub const BACKOFF_MAX: Duration = Duration::from_secs(1);
/// The longest wait while the broker refuses us (login, TLS): no point in hammering it.
pub const BACKOFF_REFUSED: Duration = Duration::from_secs(30);
/// How often the counters are looked at and what could not be sent is tried again.
const TICK: Duration = Duration::from_millis(250);

/// The longest a clean stop waits for the broker to take the `offline` messages.
const STOP_WAIT: Duration = Duration::from_secs(2);

/// The connection's state as the publisher sees it: connects so far, and connected now.
type Link = (u64, bool);

/// The running client, to stop cleanly.
pub struct Handle {
    stop: mpsc::Sender<oneshot::Sender<()>>,
    driver: JoinHandle<()>,
}

impl Handle {
    /// Publishes `offline` on the line's status and every uTile's availability (retained),
    /// and disconnects (so the broker drops the wills, which say the same); waits at most
    /// twice [`STOP_WAIT`] for the broker.
    pub async fn stop(self) {
        let all = async {
            let (done, rx) = oneshot::channel();
            if self.stop.send(done).await.is_ok() {
                let _ = rx.await;
            }
            let _ = self.driver.await;
        };
        if tokio::time::timeout(STOP_WAIT * 2, all).await.is_err() {
            eprintln!(
                "utile live: MQTT: the broker did not take the offline messages in time \
                 (the last wills say the same once it notices)"
            );
        }
    }
}

/// Starts the connection, the publisher and (with `--mqtt-commands`) the commands.
pub fn spawn(
    settings: Settings,
    reports: mpsc::Receiver<Vec<Report>>,
    writes: mpsc::Sender<WriteRequest>,
) -> Handle {
    let counters = Arc::new(Counters::default());
    let (client, events) = AsyncClient::new(settings.client_options(), QUEUE);
    let (link_tx, link_rx) = watch::channel((0, false));
    let (inbox_tx, inbox_rx) = mpsc::channel(64);
    if settings.commands {
        tokio::spawn(commands::serve(
            settings.topics.clone(),
            client.clone(),
            inbox_rx,
            writes,
            counters.clone(),
        ));
    }
    let driver = tokio::spawn(drive(
        events,
        client.clone(),
        settings.clone(),
        link_tx,
        inbox_tx,
        counters.clone(),
    ));
    let (stop, stop_rx) = mpsc::channel(1);
    tokio::spawn(publish(
        settings,
        client,
        (reports, stop_rx),
        link_rx,
        counters,
    ));
    Handle { stop, driver }
}

/// A connection error in words, and whether the broker refused us (rather than not being
/// The wait after `backoff` before the next attempt to connect: doubled, up to
/// [`BACKOFF_REFUSED`] when the broker refused the login or the certificate (asking again
/// soon changes nothing) and [`BACKOFF_MAX`] otherwise.
pub fn next_backoff(backoff: Duration, refused: bool) -> Duration {
    let most = if refused {
        BACKOFF_REFUSED
    } else {
        BACKOFF_MAX
    };
    (backoff * 2).min(most)
}

/// there).
pub fn explain(e: &ConnectionError, b: &Broker) -> (String, bool) {
    let at = format!("{}:{}", b.host, b.port);
    match e {
        ConnectionError::ConnectionRefused(
            ConnectReturnCode::BadUserNamePassword | ConnectReturnCode::NotAuthorized,
        ) => (
            format!(
                "the broker at {at} refused the login: check --mqtt-user and \
                 --mqtt-password-file (and the broker's password file)"
            ),
            true,
        ),
        ConnectionError::ConnectionRefused(code) => (
            format!("the broker at {at} refused the connection ({code:?})"),
            true,
        ),
        ConnectionError::Tls(t) => (
            format!(
                "TLS with {at} failed: {t} (is --mqtt-ca the CA that signed the broker's \
                 certificate, and is the URL's host a name in that certificate?)"
            ),
            true,
        ),
        ConnectionError::Io(io) => (
            format!("cannot reach the broker at {at}: {io} (is it running? is the URL right?)"),
            false,
        ),
        ConnectionError::NetworkTimeout => {
            (format!("no answer from the broker at {at} in time"), false)
        }
        other => (format!("the connection to {at} ended: {other}"), false),
    }
}

/// Drives the event loop: connects, reconnects with back-off, hands `set` messages on.
async fn drive(
    mut events: EventLoop,
    client: AsyncClient,
    settings: Settings,
    link: watch::Sender<Link>,
    inbox: mpsc::Sender<Publish>,
    counters: Arc<Counters>,
) {
    let b = &settings.broker;
    let mut backoff = BACKOFF_MIN;
    let mut failures = 0u32;
    let mut last: Option<String> = None;
    loop {
        match events.poll().await {
            Ok(Event::Incoming(Packet::ConnAck(_))) => {
                let n = counters.connects.fetch_add(1, Ordering::Relaxed) + 1;
                let again = if n > 1 { "again " } else { "" };
                eprintln!(
                    "utile live: MQTT: connected {again}to {}:{}, line '{}'",
                    b.host,
                    b.port,
                    settings.topics.line()
                );
                backoff = BACKOFF_MIN;
                failures = 0;
                last = None;
                if settings.commands {
                    let _ = client.try_subscribe(settings.topics.set_filter(), QoS::AtLeastOnce);
                }
                link.send_replace((n, true));
            }
            // Only a clean stop disconnects.
            Ok(Event::Outgoing(rumqttc::Outgoing::Disconnect)) => return,
            Ok(Event::Incoming(Packet::Publish(p))) => {
                if inbox.try_send(p).is_err() {
                    counters.dropped.fetch_add(1, Ordering::Relaxed);
                }
            }
            Ok(_) => {}
            Err(e) => {
                link.send_modify(|l| l.1 = false);
                let (words, refused) = explain(&e, b);
                failures += 1;
                // Each new trouble is told; the same one again at 1, 2, 4, 8 … failures.
                if last.as_deref() != Some(words.as_str()) || failures.is_power_of_two() {
                    eprintln!(
                        "utile live: MQTT: {words}; trying again in {:.1} s (failure {failures})",
                        backoff.as_secs_f64()
                    );
                }
                last = Some(words);
                tokio::time::sleep(backoff).await;
                backoff = next_backoff(backoff, refused);
            }
        }
    }
}

/// The reports, and the clean stop's requests.
type Inputs = (
    mpsc::Receiver<Vec<Report>>,
    mpsc::Receiver<oneshot::Sender<()>>,
);

/// Keeps the broker's retained messages as the reports say, sending only what changed, and
/// each uTile's availability session told; on a clean stop, `offline` everywhere.
async fn publish(
    settings: Settings,
    client: AsyncClient,
    (mut reports, mut stop): Inputs,
    mut link: watch::Receiver<Link>,
    counters: Arc<Counters>,
) {
    let t = &settings.topics;
    let mut sessions = Sessions::new(settings.clone());
    // Each uTile's availability, given to its session once the line's session has been let in
    // (a broker that refuses the login is not asked once more per uTile).
    let mut online: BTreeMap<u8, bool> = BTreeMap::new();
    let mut out = Outbox::new(vec![t.status()]);
    out.want(t.status(), ONLINE.into());
    if settings.discovery {
        let (k, v) = discovery::line_config(t);
        out.want(k, v);
    }
    // The firmware each uTile's discovery was made for.
    let mut described: BTreeMap<u8, Option<String>> = BTreeMap::new();
    let mut tick = tokio::time::interval(TICK);
    loop {
        tokio::select! {
            r = reports.recv() => {
                let Some(units) = r else { return };
                for r in &units {
                    online.insert(r.addr, r.online);
                    for (k, v) in payloads::retained(t, r) {
                        out.want(k, v);
                    }
                    if settings.discovery && described.get(&r.addr) != Some(&r.firmware) {
                        for (k, v) in discovery::unit_configs(t, r, settings.commands) {
                            out.want(k, v);
                        }
                        described.insert(r.addr, r.firmware.clone());
                    }
                }
            }
            changed = link.changed() => {
                if changed.is_err() {
                    return;
                }
                if link.borrow_and_update().1 {
                    out.reconnected();
                }
            }
            _ = tick.tick() => {
                out.want(t.counters(), counters.payload());
            }
            asked = stop.recv() => {
                let _ = client.try_publish(t.status(), QoS::AtLeastOnce, true, OFFLINE);
                let _ = client.try_disconnect();
                sessions.stop(STOP_WAIT).await;
                if let Some(done) = asked {
                    let _ = done.send(());
                }
                return;
            }
        }
        if link.borrow().0 > 0 {
            for (addr, on) in &online {
                sessions.set(*addr, *on);
            }
        }
        if link.borrow().1 {
            flush(&client, &mut out, &counters);
        }
    }
}

/// Offers what is pending to the client's queue; what does not fit waits for the next turn.
fn flush(client: &AsyncClient, out: &mut Outbox, counters: &Counters) {
    for (topic, payload) in out.pending() {
        match client.try_publish(topic.clone(), QoS::AtMostOnce, true, payload.clone()) {
            Ok(()) => out.sent(topic, payload),
            Err(_) => {
                counters.dropped.fetch_add(1, Ordering::Relaxed);
                return;
            }
        }
    }
}
