//! `bench mqtt`'s second figure (issue 30): one uTile's rig switch, pressed on the virtual
//! Nano's console, to its `A0` message at a subscriber, in simulated time. Built on
//! [`super::mqtt`]'s broker, line and subscriber.

use std::io::Write;
use std::time::{Duration, Instant};

use serde_json::Value;

use super::live::start_nano;
use super::mqtt::{simulated, start_line_units, subscribe, until, Rig, WAIT};
use super::{BenchError, Spread};

/// One uTile (`vnano --pty`), its line publishing as `one`: `presses` rig switches pressed on
/// the virtual Nano's console (A0 toggles), each to its `A0` message at a subscriber, ms of
/// simulated time (the wall time scaled by the simulation's pace over the run, from T0's time
/// left in the states).
pub fn measure_rig(presses: u32) -> Result<Spread, BenchError> {
    rig_run(presses).map_err(BenchError::Live)
}

fn rig_run(presses: u32) -> Result<Spread, String> {
    let (mut rig, port) = Rig::with_broker("utile-mqtt-rig")?;
    let dir = rig.dir.clone();
    let link = dir.join("tty");
    let mut nano = start_nano(&dir, &link, 1).map_err(|e| e.to_string())?;
    let keys = nano.stdin.take().ok_or("vnano's console")?;
    rig.children.push(nano);
    std::thread::sleep(Duration::from_millis(500));
    let (_client, seen) = subscribe(port, &["utile/one/1/state", "utile/one/1/A0"])?;
    let (line, _) = start_line_units(&link, port, "one", "1")?;
    rig.children.push(line);
    let all = || seen.lock().unwrap_or_else(|e| e.into_inner()).clone();
    let a0 = |from: Instant| -> Option<(Instant, String)> {
        all()
            .into_iter()
            .rev()
            .find(|m| m.topic == "utile/one/1/A0" && m.at >= from)
            .map(|m| (m.at, m.text))
    };
    let t0 = Instant::now();
    if !until(WAIT, || a0(t0).is_some()) {
        return Err("no A0 message within 120 s".into());
    }
    let mut keys = keys;
    let mut wall = Vec::new();
    let from = Instant::now();
    for i in 0..presses {
        // Varied phases of the polling.
        std::thread::sleep(Duration::from_millis(300 + u64::from(i * 37 % 100)));
        let before = a0(t0).map(|m| m.1).unwrap_or_default();
        let pressed = Instant::now();
        keys.write_all(b"0")
            .and_then(|()| keys.flush())
            .map_err(|e| e.to_string())?;
        if until(Duration::from_secs(30), || {
            a0(pressed).is_some_and(|m| m.1 != before)
        }) {
            if let Some((at, _)) = a0(pressed) {
                wall.push((at - pressed).as_secs_f64() * 1e3);
            }
        }
    }
    let st: Vec<(Instant, Value)> = all()
        .iter()
        .filter(|m| m.topic == "utile/one/1/state" && m.at >= from)
        .map(|m| (m.at, serde_json::from_str(&m.text).unwrap_or(Value::Null)))
        .collect();
    let pace = match (st.first(), st.last()) {
        (Some(a), Some(b)) if b.0 > a.0 => simulated(&st) / (b.0 - a.0).as_secs_f64(),
        _ => return Err("no states to time the simulation by".into()),
    };
    let sim: Vec<f64> = wall.iter().map(|w| w * pace).collect();
    Spread::of(&sim).ok_or_else(|| "no press reached the subscriber".to_string())
}
