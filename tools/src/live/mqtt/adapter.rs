//! The MQTT room's one joint with the live view (the only file here that knows it): reports
//! made from the published view after each change (at most one per [`GAP`]), each uTile's
//! firmware id asked once it answers (Report Server ID through the line's queue), and write
//! requests carried out by the page's own write path (`--read-only`, the uTile on the line,
//! the signal table's name and range, then the line's queue and the uTile's answer).

use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use tokio::sync::mpsc;
use utile_core::modbus::REPORT_SERVER_ID;

use super::{Reading, Report, WriteRequest};
use crate::live::http::write_signal;
use crate::live::hub::Hub;
use crate::live::job::Job;
use crate::live::rtu;
use crate::live::view::{CardState, UnitView, View};

/// Reports are made at most this often (a uTile's picture comes about every 53 ms).
pub const GAP: Duration = Duration::from_millis(20);
/// The longest the firmware id's question waits for the line to take it.
const ASK_WAIT: Duration = Duration::from_secs(5);
/// Where the id's text starts in a Report Server ID reply: function, byte count, server id,
/// run indicator.
const ID_TEXT_AT: usize = 4;

/// Firmware ids by address: `None` while asked, `Some` once known (empty: not given).
type Ids = Arc<Mutex<BTreeMap<u8, Option<String>>>>;

/// Starts both directions: the reports' receiver and the write requests' sender.
pub fn start(hub: Arc<Hub>) -> (mpsc::Receiver<Vec<Report>>, mpsc::Sender<WriteRequest>) {
    let (report_tx, report_rx) = mpsc::channel(16);
    let (write_tx, mut write_rx) = mpsc::channel::<WriteRequest>(16);
    let h = hub.clone();
    tokio::spawn(async move {
        let mut views = h.views();
        let ids: Ids = Arc::default();
        loop {
            let view = views.borrow_and_update().clone();
            let mut units = reports(&view);
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
                        tokio::spawn(ask_id(h.clone(), r.addr, ids.clone()));
                    }
                    None => {}
                }
            }
            // A full channel drops this report: the next change brings the same values.
            if report_tx.try_send(units).is_err() && report_tx.is_closed() {
                return;
            }
            tokio::time::sleep(GAP).await;
            if views.changed().await.is_err() {
                return;
            }
        }
    });
    tokio::spawn(async move {
        while let Some(w) = write_rx.recv().await {
            let outcome = write_signal(&hub, w.addr, &w.signal, w.value)
                .await
                .map(|_| ());
            if w.done.send(outcome).is_err() {
                tracing::debug!(addr = w.addr, "a MQTT write's asker is gone");
            }
        }
    });
    (report_rx, write_tx)
}

/// One report per uTile of `view`.
fn reports(view: &View) -> Vec<Report> {
    view.units.iter().map(report).collect()
}

/// A uTile's report: its values by the API's names (with `scans_per_s` once it has values),
/// online unless its card says offline.
fn report(u: &UnitView) -> Report {
    let mut values: BTreeMap<String, Reading> = u
        .values
        .0
        .iter()
        .map(|(k, v)| ((*k).to_string(), Reading::Whole(*v)))
        .collect();
    if u.values.get("A0").is_some() {
        values.insert("scans_per_s".into(), Reading::Rate(u.scans_per_s));
    }
    Report {
        addr: u.addr,
        online: u.state != CardState::Offline,
        values,
        firmware: None,
    }
}

/// Asks uTile `addr` for its firmware id (Report Server ID); on no answer it is asked again
/// at the next report, after an exception (firmware without it) never.
async fn ask_id(hub: Arc<Hub>, addr: u8, ids: Ids) {
    let text = match hub
        .ask(Job::page(addr, vec![REPORT_SERVER_ID]), ASK_WAIT)
        .await
    {
        Ok(done) if rtu::exception(&done.pdu).is_some() => Some(String::new()),
        Ok(done) if done.pdu.first() == Some(&REPORT_SERVER_ID) => {
            Some(done.pdu.get(ID_TEXT_AT..).map_or_else(String::new, |t| {
                String::from_utf8_lossy(t)
                    .trim_end_matches('\0')
                    .trim()
                    .to_string()
            }))
        }
        Ok(_) => Some(String::new()),
        Err(_) => None,
    };
    let mut ids = ids.lock().unwrap_or_else(|e| e.into_inner());
    match text {
        Some(t) => {
            ids.insert(addr, Some(t));
        }
        None => {
            tracing::debug!(addr, "no firmware id yet: asked again at the next report");
            ids.remove(&addr);
        }
    }
}
