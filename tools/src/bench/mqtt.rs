//! `bench mqtt`: three lines of three uTiles into one broker (issue 30). Three virtual Nanos
//! with `--bus 3` (the release `vnano` beside this binary), three `utile live` processes (the
//! release `utile` beside it, `--mqtt … --name busN --mqtt-commands`), Debian's mosquitto on a
//! free loopback port, and a subscriber (rumqttc) in this process that keeps every `state`
//! and `Y0` message with its time.
//!
//! Counted in simulated time, as every budget on the virtual Nano: each uTile runs the
//! free-running timer of [`super::live`] (T0 = 25.5 s), so the time left `TL0` in each of its
//! `state` messages is its own clock. A uTile's rate is its state messages over the simulated
//! seconds between its first and last one in the window. Changes: U0 of all nine toggled by
//! `set` messages, a round every 2 simulated seconds, each round waiting until every uTile's
//! state shows its new Y0 (so every toggle is a change the uTile made); a change is lost when
//! a uTile's states show Y0 change without a `Y0` message with that value between that
//! change and the one before. The lines' own refreshes (snapshots per simulated second, from
//! each `utile live`'s API) are read over the same window: what the states can follow.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rumqttc::{Client, Event, MqttOptions, Packet, QoS};
use serde_json::Value;

use super::live::start_nano;
use super::live_pages::{get, spawn_live};
use super::{BenchError, Spread};

/// Lines, and uTiles on each.
const LINES: usize = 3;
/// uTiles on each line's bus.
const UNITS: usize = 3;
/// Simulated seconds between two rounds of toggles.
const ROUND_SECS: f64 = 2.0;
/// The longest wall time anything may take (a loaded machine runs the simulations slowly).
pub(super) const WAIT: Duration = Duration::from_secs(120);

/// What one run measured.
#[derive(Clone, Debug)]
pub struct MqttFigures {
    /// State messages per simulated second at the subscriber, each uTile.
    pub rate: Spread,
    /// The line's own refreshes (snapshots) per simulated second, each uTile, over the same
    /// window (from `utile live`'s API): what the state messages can follow at most.
    pub refresh: Spread,
    /// Simulated seconds per wall second, each uTile.
    pub pace: Spread,
    /// Simulated seconds measured (the shortest uTile's).
    pub sim_secs: f64,
    /// Changes of Y0 the uTiles made (their states show them).
    pub changes: usize,
    /// Of those, without their own `Y0` message.
    pub lost: usize,
    /// Toggles asked (U0 of a uTile by a `set` message).
    pub toggles: usize,
    /// Toggles asked whose change never showed (the write not carried out).
    pub not_done: usize,
}

/// One message as the subscriber got it.
#[derive(Clone, Debug)]
pub(super) struct Msg {
    /// Its topic.
    pub(super) topic: String,
    /// Its payload as text.
    pub(super) text: String,
    /// When it came.
    pub(super) at: Instant,
}

/// The messages the subscriber got so far.
pub(super) type Seen = Arc<Mutex<Vec<Msg>>>;

/// Everything that is stopped when dropped: processes and the scratch folder.
pub(super) struct Rig {
    /// The processes, stopped last first.
    pub(super) children: Vec<Child>,
    /// The scratch folder.
    pub(super) dir: PathBuf,
}

impl Rig {
    /// A scratch folder `name`-PID and a broker on a free port: the rig and the port.
    pub(super) fn with_broker(name: &str) -> Result<(Rig, u16), String> {
        let dir = std::env::temp_dir().join(format!("{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let mut rig = Rig {
            children: Vec::new(),
            dir: dir.clone(),
        };
        let (broker, port) = start_broker(&dir)?;
        rig.children.push(broker);
        Ok((rig, port))
    }
}

impl Drop for Rig {
    fn drop(&mut self) {
        // The lines first (they publish `offline`), then the Nanos and the broker.
        for c in self.children.iter_mut().rev() {
            let _ = c.kill();
            let _ = c.wait();
        }
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// A free TCP port on 127.0.0.1.
fn free_port() -> Result<u16, String> {
    std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .map_err(|e| format!("a free port: {e}"))
}

/// mosquitto on a free loopback port, anonymous clients let in, nothing kept on disk.
fn start_broker(dir: &Path) -> Result<(Child, u16), String> {
    let mosquitto = Path::new("/usr/sbin/mosquitto");
    if !mosquitto.is_file() {
        return Err("/usr/sbin/mosquitto is missing: ./x setup installs it".into());
    }
    let port = free_port()?;
    let mut conf = format!("listener {port} 127.0.0.1\nallow_anonymous true\npersistence false\n");
    // SAFETY: geteuid only reads the process's effective user id.
    if unsafe { libc::geteuid() } == 0 {
        conf.push_str("user root\n");
    }
    let file = dir.join("mosquitto.conf");
    std::fs::write(&file, conf).map_err(|e| format!("{}: {e}", file.display()))?;
    let child = Command::new(mosquitto)
        .arg("-c")
        .arg(&file)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("mosquitto: {e}"))?;
    let t0 = Instant::now();
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        if t0.elapsed() > Duration::from_secs(10) {
            return Err("mosquitto did not start".into());
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    Ok((child, port))
}

/// `utile live` on `link` publishing as line `name` to the broker at `port`; its page's
/// address.
fn start_line(link: &Path, port: u16, name: &str) -> Result<(Child, SocketAddr), String> {
    let units: Vec<String> = (1..=UNITS).map(|u| u.to_string()).collect();
    start_line_units(link, port, name, &units.join(","))
}

/// `utile live --units UNITS` on `link` publishing as line `name`; its page's address.
pub(super) fn start_line_units(
    link: &Path,
    port: u16,
    name: &str,
    units: &str,
) -> Result<(Child, SocketAddr), String> {
    let utile = std::env::current_exe()
        .map_err(|e| e.to_string())?
        .with_file_name("utile");
    if !utile.is_file() {
        return Err(format!(
            "{} is missing: cargo build --release --bin utile",
            utile.display()
        ));
    }
    let mut cmd = Command::new(&utile);
    cmd.arg("live")
        .arg("--port")
        .arg(link)
        .args(["--units", units, "--http", "127.0.0.1:0"])
        .args(["--no-tcp", "--mqtt-commands", "--name", name])
        .arg("--mqtt")
        .arg(format!("mqtt://127.0.0.1:{port}"));
    spawn_live(cmd)
}

/// Each uTile's (snapshots, TL0) in a line's API.
fn refreshes(addr: SocketAddr) -> Result<Vec<(u64, u64)>, String> {
    let s = get(addr, "/api/state")?;
    let units = s["units"].as_array().ok_or("no units in /api/state")?;
    units
        .iter()
        .map(|u| {
            let snaps = u["snapshots"].as_u64().ok_or("no snapshots")?;
            let tl0 = u["values"]["TL0"].as_u64().ok_or("no TL0")?;
            Ok((snaps, tl0))
        })
        .collect()
}

/// A subscriber to `filters`; the messages so far, and its client to publish.
pub(super) fn subscribe(port: u16, filters: &[&str]) -> Result<(Client, Seen), String> {
    let mut o = MqttOptions::new(format!("bench-{port}"), "127.0.0.1", port);
    o.set_keep_alive(Duration::from_secs(10));
    o.set_max_packet_size(1 << 20, 1 << 20);
    let (client, mut conn) = Client::new(o, 1024);
    for f in filters {
        client
            .subscribe(*f, QoS::AtLeastOnce)
            .map_err(|e| format!("subscribe: {e}"))?;
    }
    let seen = Arc::new(Mutex::new(Vec::new()));
    let kept = seen.clone();
    std::thread::spawn(move || {
        for ev in conn.iter() {
            match ev {
                Ok(Event::Incoming(Packet::Publish(p))) => {
                    let m = Msg {
                        topic: p.topic.clone(),
                        text: String::from_utf8_lossy(&p.payload).into_owned(),
                        at: Instant::now(),
                    };
                    kept.lock().unwrap_or_else(|e| e.into_inner()).push(m);
                }
                Ok(_) => {}
                Err(_) => std::thread::sleep(Duration::from_millis(100)),
            }
        }
    });
    Ok((client, seen))
}

/// The topic of uTile `a` of line `l`.
fn topic(l: usize, a: usize, leaf: &str) -> String {
    format!("utile/bus{l}/{a}/{leaf}")
}

/// The states of one uTile since `from`, parsed.
fn states(all: &[Msg], l: usize, a: usize, from: Instant) -> Vec<(Instant, Value)> {
    let t = topic(l, a, "state");
    all.iter()
        .filter(|m| m.topic == t && m.at >= from)
        .map(|m| (m.at, serde_json::from_str(&m.text).unwrap_or(Value::Null)))
        .collect()
}

/// Simulated seconds over consecutive states (T0's time left falls 10 a second and starts
/// again from 255).
pub(super) fn simulated(states: &[(Instant, Value)]) -> f64 {
    let tl: Vec<u64> = states.iter().filter_map(|s| s.1["TL0"].as_u64()).collect();
    let tenths: u64 = tl.windows(2).map(|w| (w[0] + 255 - w[1]) % 255).sum();
    tenths as f64 / 10.0
}

/// Waits until `ok` holds, checked every 20 ms; false after `limit`.
pub(super) fn until(limit: Duration, mut ok: impl FnMut() -> bool) -> bool {
    let t0 = Instant::now();
    while t0.elapsed() < limit {
        if ok() {
            return true;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    false
}

/// Three lines of three for at least `secs` simulated seconds.
pub fn measure_mqtt(secs: u32) -> Result<MqttFigures, BenchError> {
    run(secs).map_err(BenchError::Live)
}

fn run(secs: u32) -> Result<MqttFigures, String> {
    let (mut rig, port) = Rig::with_broker("utile-mqtt-bench")?;
    let dir = rig.dir.clone();
    let mut links = Vec::new();
    for l in 0..LINES {
        let d = dir.join(format!("bus{l}"));
        std::fs::create_dir_all(&d).map_err(|e| format!("{}: {e}", d.display()))?;
        let link = d.join("tty");
        rig.children
            .push(start_nano(&d, &link, UNITS).map_err(|e| e.to_string())?);
        links.push(link);
    }
    std::thread::sleep(Duration::from_millis(500));
    let (client, seen) = subscribe(port, &["utile/+/+/state", "utile/+/+/Y0"])?;
    let mut pages = Vec::new();
    for (l, link) in links.iter().enumerate() {
        let (child, page) = start_line(link, port, &format!("bus{l}"))?;
        rig.children.push(child);
        pages.push(page);
    }
    let all = || seen.lock().unwrap_or_else(|e| e.into_inner()).clone();
    let every = || (0..LINES).flat_map(|l| (1..=UNITS).map(move |a| (l, a)));
    let t0 = Instant::now();
    let ready = until(WAIT, || {
        let m = all();
        every().all(|(l, a)| states(&m, l, a, t0).iter().any(|s| s.1["Y0"] == 0))
    });
    if !ready {
        return Err("not every uTile's state came within 120 s".into());
    }

    // Rounds of toggles until the first uTile has run `secs` simulated seconds.
    // Each uTile's (snapshots, TL0) in the lines' APIs, read at every round: snapshots and
    // simulated tenths summed round by round (a round is far shorter than T0's 25.5 s).
    let api = || -> Result<Vec<(u64, u64)>, String> {
        let mut all = Vec::new();
        for &p in &pages {
            all.extend(refreshes(p)?);
        }
        Ok(all)
    };
    let mut last = api()?;
    let mut counted = vec![(0u64, 0u64); last.len()];
    let from = Instant::now();
    let mut on = false;
    let mut asked = 0;
    let mut not_done = 0;
    loop {
        on = !on;
        let round = Instant::now();
        for (l, a) in every() {
            client
                .publish(
                    topic(l, a, "U0/set"),
                    QoS::AtLeastOnce,
                    false,
                    u8::from(on).to_string(),
                )
                .map_err(|e| format!("publish: {e}"))?;
            asked += 1;
        }
        until(WAIT, || {
            let m = all();
            every().all(|(l, a)| {
                states(&m, l, a, round)
                    .iter()
                    .any(|s| s.1["Y0"] == u8::from(on))
            })
        });
        let m = all();
        not_done += every()
            .filter(|&(l, a)| {
                !states(&m, l, a, round)
                    .iter()
                    .any(|s| s.1["Y0"] == u8::from(on))
            })
            .count();
        // A round every 2 simulated seconds: each uTile's output changes that often.
        until(WAIT, || {
            simulated(&states(&all(), 0, 1, round)) >= ROUND_SECS
        });
        let now = api()?;
        for ((c, (s0, t0)), (s1, t1)) in counted.iter_mut().zip(&last).zip(&now) {
            c.0 += s1 - s0;
            c.1 += (t0 + 255 - t1) % 255;
        }
        last = now;
        if simulated(&states(&m, 0, 1, from)) >= f64::from(secs) || from.elapsed() > WAIT * 5 {
            break;
        }
    }
    let to = Instant::now();
    let refresh: Vec<f64> = counted
        .iter()
        .filter(|c| c.1 > 0)
        .map(|&(snaps, tenths)| snaps as f64 * 10.0 / tenths as f64)
        .collect();
    // The last messages on their way.
    std::thread::sleep(Duration::from_secs(2));
    let m = all();
    let (mut rate, mut pace, mut sims) = (Vec::new(), Vec::new(), Vec::new());
    let (mut changes, mut lost) = (0, 0);
    for (l, a) in every() {
        let st: Vec<(Instant, Value)> = states(&m, l, a, from)
            .into_iter()
            .filter(|s| s.0 <= to)
            .collect();
        let sim = simulated(&st);
        let (Some(first), Some(last)) = (st.first(), st.last()) else {
            return Err(format!("bus{l} uTile {a}: no state in the window"));
        };
        if sim <= 0.0 {
            return Err(format!("bus{l} uTile {a}: its clock did not move"));
        }
        rate.push((st.len() - 1) as f64 / sim);
        pace.push(sim / (last.0 - first.0).as_secs_f64().max(1e-3));
        sims.push(sim);
        // Y0's changes in the states (from the Y0 before the window) against Y0's messages.
        let mut y = states(&m, l, a, t0)
            .iter()
            .rev()
            .find(|s| s.0 < from)
            .and_then(|s| s.1["Y0"].as_u64());
        let mut made = Vec::new();
        for s in &st {
            let now = s.1["Y0"].as_u64();
            if let Some(v) = now.filter(|_| now != y) {
                made.push((s.0, v));
                y = now;
            }
        }
        changes += made.len();
        // Each change needs its own Y0 message, sent before the state that shows it (the
        // outbox sends a report's topics in order: `Y0` before `state`) and after the change
        // before it.
        let y0 = topic(l, a, "Y0");
        let mut after = from;
        for (at, v) in made {
            let text = v.to_string();
            let came = m
                .iter()
                .any(|x| x.topic == y0 && x.at >= after && x.at <= at && x.text == text);
            if !came {
                lost += 1;
            }
            after = at;
        }
    }
    Ok(MqttFigures {
        rate: Spread::of(&rate).ok_or("no uTile")?,
        refresh: Spread::of(&refresh).ok_or("no clock in the API")?,
        pace: Spread::of(&pace).ok_or("no uTile")?,
        sim_secs: sims.iter().copied().fold(f64::INFINITY, f64::min),
        changes,
        lost,
        toggles: asked,
        not_done,
    })
}
