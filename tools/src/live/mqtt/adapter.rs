//! The MQTT room's one joint with the live view (the only file here that knows it): reports
//! made from the API's own JSON after each change (at most one per [`GAP`]), each uTile's
//! firmware id asked once it answers (Report Server ID through the line's queue), and write
//! requests carried out as the page's writes are (`--read-only`, the uTile on the line, the
//! signal and its range, then the line's queue and the uTile's answer).

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use serde_json::Value;
use tokio::sync::mpsc;

use super::{Report, WriteRequest};
use crate::live::queue::{Job, Origin};
use crate::live::rtu::exception_text;
use crate::live::signals;
use crate::live::state::{Input, Shared};

/// Reports are made at most this often (a uTile's picture comes about every 53 ms).
pub const GAP: Duration = Duration::from_millis(20);
/// The longest a write waits for the line.
const WRITE_WAIT: Duration = Duration::from_secs(5);

/// Starts both directions: the reports' receiver and the write requests' sender.
pub fn start(shared: Arc<Shared>) -> (mpsc::Receiver<Vec<Report>>, mpsc::Sender<WriteRequest>) {
    let (report_tx, report_rx) = mpsc::channel(16);
    let (write_tx, mut write_rx) = mpsc::channel::<WriteRequest>(16);
    let s = shared.clone();
    tokio::spawn(async move {
        let mut changed = s.changed.subscribe();
        // Firmware ids by address: `None` while asked, `Some` once known.
        let ids = Arc::new(Mutex::new(BTreeMap::<u8, Option<String>>::new()));
        loop {
            let mut units = reports(&s);
            for r in &mut units {
                let known = ids
                    .lock()
                    .unwrap_or_else(|e| e.into_inner())
                    .get(&r.addr)
                    .cloned();
                match known {
                    Some(id) => r.firmware = id.filter(|t| !t.is_empty()),
                    None if r.online => {
                        ids.lock()
                            .unwrap_or_else(|e| e.into_inner())
                            .insert(r.addr, None);
                        tokio::spawn(ask_id(s.clone(), r.addr, ids.clone()));
                    }
                    None => {}
                }
            }
            // A full channel drops this report: the next change brings the same values.
            if report_tx.try_send(units).is_err() && report_tx.is_closed() {
                return;
            }
            tokio::time::sleep(GAP).await;
            if changed.changed().await.is_err() {
                return;
            }
        }
    });
    tokio::spawn(async move {
        while let Some(w) = write_rx.recv().await {
            let outcome = write(&shared, w.addr, &w.signal, w.value).await;
            let _ = w.done.send(outcome);
        }
    });
    (report_rx, write_tx)
}

/// One report per uTile, from `GET /api/state`'s JSON.
fn reports(shared: &Shared) -> Vec<Report> {
    let state = shared.state_json();
    let units = state["units"].as_array().cloned().unwrap_or_default();
    units
        .iter()
        .filter_map(|u| {
            let addr = u["addr"].as_u64().and_then(|a| u8::try_from(a).ok())?;
            let mut values: BTreeMap<String, Value> = u["values"]
                .as_object()
                .map(|m| m.iter().map(|(k, v)| (k.clone(), v.clone())).collect())
                .unwrap_or_default();
            if u["values"].get("A0").is_some() {
                values.insert("scans_per_s".into(), u["scans_per_s"].clone());
            }
            Some(Report {
                addr,
                online: u["state"] != "offline",
                values,
                firmware: None,
            })
        })
        .collect()
}

/// Asks uTile `addr` for its firmware id (Report Server ID: address, run indicator, the id
/// text); on no answer it is asked again at the next report, after an exception (firmware
/// without it) never.
async fn ask_id(shared: Arc<Shared>, addr: u8, ids: Arc<Mutex<BTreeMap<u8, Option<String>>>>) {
    let (job, rx) = Job::new(addr, vec![0x11], Origin::Page);
    let text = if shared.inputs.send(Input::Job(job)).is_ok() {
        match tokio::time::timeout(WRITE_WAIT, rx).await {
            Ok(Ok(Ok(done))) if done.pdu.first() == Some(&0x11) => done.pdu.get(4..).map(|t| {
                String::from_utf8_lossy(t)
                    .trim_end_matches('\0')
                    .trim()
                    .to_string()
            }),
            Ok(Ok(Ok(_))) => Some(String::new()),
            _ => None,
        }
    } else {
        None
    };
    let mut ids = ids.lock().unwrap_or_else(|e| e.into_inner());
    match text {
        Some(t) => {
            ids.insert(addr, Some(t));
        }
        None => {
            ids.remove(&addr);
        }
    }
}

/// Writes `signal = value` to uTile `addr`, or says why not (nothing written).
async fn write(shared: &Shared, addr: u8, signal: &str, value: i64) -> Result<(), String> {
    if shared.read_only {
        return Err("read-only: this utile live was started with --read-only".into());
    }
    if shared.lock().unit_mut(addr).is_none() {
        return Err(format!("no uTile {addr} on this line"));
    }
    let w = signals::write(signal, value)?;
    let (job, rx) = Job::new(addr, w.pdu(), Origin::Page);
    if shared.inputs.send(Input::Job(job)).is_err() {
        return Err("the line has stopped".into());
    }
    let done = match tokio::time::timeout(WRITE_WAIT, rx).await {
        Ok(Ok(Ok(done))) => done,
        Ok(Ok(Err(f))) => return Err(f.text().into()),
        _ => return Err("the line did not get to it".into()),
    };
    if done.pdu.first().is_some_and(|f| f & 0x80 != 0) {
        let code = done.pdu.get(1).copied().unwrap_or(0);
        return Err(format!(
            "uTile {addr} refused {signal} = {value}: {}",
            exception_text(code)
        ));
    }
    Ok(())
}
