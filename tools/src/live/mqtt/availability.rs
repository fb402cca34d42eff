//! Each uTile's `<addr>/availability` on a MQTT session of its own (client id
//! `utile-LINE-ADDR`) whose last will is `offline` on that topic, retained. A broker keeps one
//! will per session, and the line's session spends its will on the line's `status`: with a
//! session per uTile, `utile live` killed (or cut from the network) leaves every uTile's
//! availability `offline` too, with no help from anyone. The session publishes its uTile's
//! availability itself (after every connect, and on every change), so the will and the value
//! travel on one connection and cannot overtake each other. A clean stop publishes `offline`
//! and disconnects (a clean disconnect drops the will).

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

use rumqttc::{AsyncClient, Event, EventLoop, Outgoing, Packet, QoS};
use tokio::task::JoinHandle;

use super::client::{explain, next_backoff, BACKOFF_MIN};
use super::options::{Broker, Settings};
use super::payloads::{availability, OFFLINE};

/// A session's queue of requests (it publishes one topic).
const QUEUE: usize = 16;

/// What one uTile's session shows, shared by its driver and the publisher.
#[derive(Debug, Default)]
struct Shown {
    /// The uTile answers (its card is not offline).
    online: bool,
    /// The session is connected now.
    connected: bool,
    /// A clean stop is under way: no more connects.
    stopping: bool,
}

/// One uTile's session.
struct Session {
    client: AsyncClient,
    topic: String,
    shown: Arc<Mutex<Shown>>,
    task: JoinHandle<()>,
}

/// The shared state, even if a holder panicked (it is two flags and a value).
fn lock(m: &Mutex<Shown>) -> MutexGuard<'_, Shown> {
    m.lock().unwrap_or_else(|e| e.into_inner())
}

impl Session {
    /// Connects (in the background) uTile `addr`'s session.
    fn start(settings: &Settings, addr: u8) -> Session {
        let (client, events) = AsyncClient::new(settings.unit_options(addr), QUEUE);
        let topic = settings.topics.unit(addr, "availability");
        let shown = Arc::new(Mutex::new(Shown::default()));
        let task = tokio::spawn(drive(
            events,
            client.clone(),
            topic.clone(),
            shown.clone(),
            (settings.broker.clone(), addr),
        ));
        Session {
            client,
            topic,
            shown,
            task,
        }
    }

    /// The uTile is `online` (or not): published at once when connected and changed, else
    /// at the next connect. The lock is held while the message is queued, so the driver's
    /// publish after a connect cannot overtake a newer value.
    fn set(&self, online: bool) {
        let mut s = lock(&self.shown);
        if s.online == online {
            return;
        }
        s.online = online;
        if s.connected {
            // A full queue: the next connect publishes the value again.
            let _ = self.client.try_publish(
                self.topic.clone(),
                QoS::AtLeastOnce,
                true,
                availability(online),
            );
        }
    }

    /// Publishes `offline` and disconnects; the driver's task, to wait on.
    fn stop(self) -> JoinHandle<()> {
        let mut s = lock(&self.shown);
        s.stopping = true;
        s.online = false;
        if s.connected {
            let _ = self
                .client
                .try_publish(self.topic.clone(), QoS::AtLeastOnce, true, OFFLINE);
            let _ = self.client.try_disconnect();
        } else {
            // Not connected: the broker has (or will have) the will's `offline`.
            self.task.abort();
        }
        drop(s);
        self.task
    }
}

/// Drives one session: connects, publishes the availability after each connect, backs off
/// as the line's session does. The line's session tells the broker's trouble on the console;
/// here only a refusal that session does not get is told (once).
async fn drive(
    mut events: EventLoop,
    client: AsyncClient,
    topic: String,
    shown: Arc<Mutex<Shown>>,
    (broker, addr): (Broker, u8),
) {
    let mut backoff = BACKOFF_MIN;
    let mut told = false;
    loop {
        match events.poll().await {
            Ok(Event::Incoming(Packet::ConnAck(_))) => {
                backoff = BACKOFF_MIN;
                let mut s = lock(&shown);
                s.connected = true;
                let _ = client.try_publish(
                    topic.clone(),
                    QoS::AtLeastOnce,
                    true,
                    availability(s.online),
                );
            }
            Ok(Event::Outgoing(Outgoing::Disconnect)) => return,
            Ok(_) => {}
            Err(e) => {
                let stopping = {
                    let mut s = lock(&shown);
                    s.connected = false;
                    s.stopping
                };
                if stopping {
                    return;
                }
                let (words, refused) = explain(&e, &broker);
                if refused && !told {
                    eprintln!("utile live: MQTT: uTile {addr}'s availability session: {words}");
                    told = true;
                }
                tokio::time::sleep(backoff).await;
                backoff = next_backoff(backoff, refused);
            }
        }
    }
}

/// The sessions of the line's uTiles, made as each first appears in a report.
pub struct Sessions {
    settings: Settings,
    units: BTreeMap<u8, Session>,
}

impl Sessions {
    /// No session yet.
    pub fn new(settings: Settings) -> Sessions {
        Sessions {
            settings,
            units: BTreeMap::new(),
        }
    }

    /// uTile `addr` is `online` (or not).
    pub fn set(&mut self, addr: u8, online: bool) {
        let settings = &self.settings;
        self.units
            .entry(addr)
            .or_insert_with(|| Session::start(settings, addr))
            .set(online);
    }

    /// Publishes `offline` for every uTile and disconnects, waiting at most `wait`.
    pub async fn stop(&mut self, wait: Duration) {
        let tasks: Vec<JoinHandle<()>> = std::mem::take(&mut self.units)
            .into_values()
            .map(Session::stop)
            .collect();
        let all = async {
            for t in tasks {
                let _ = t.await;
            }
        };
        let _ = tokio::time::timeout(wait, all).await;
    }
}
