//! A hold from the page ends with the page. SPEC §18's lease ends a hold 10 s after its
//! master's last frame, but `utile live` polls without end, so a uTile held from the page
//! would stay held once the page is closed. This task keeps the lease's promise for the
//! page: when no page has followed the events (`GET /api/events`) for [`LEASE`], each uTile
//! held through the API (`POST /api/units/{addr}/scan` hold or step) is sent Run (holding
//! register 32 = 0). Holds made by other masters through the gateway are theirs to end.

use std::collections::BTreeSet;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use utile_core::modbus::hold::HR_SCAN_CONTROL;
use utile_core::modbus::WRITE_SINGLE_REGISTER;

use super::hub::{Hub, Input};
use super::queue::{Job, Origin};

/// How long the uTiles held from the page stay held with no page open.
pub const LEASE: Duration = Duration::from_secs(10);
/// How often the pages are counted.
const CHECK: Duration = Duration::from_millis(250);

/// The uTiles held through the API (and not run since).
#[derive(Debug, Default)]
pub struct Holds(Mutex<BTreeSet<u8>>);

impl Holds {
    /// uTile `addr` was held (or stepped, which leaves it held) through the API.
    pub fn held(&self, addr: u8) {
        self.set().insert(addr);
    }

    /// uTile `addr` was run through the API.
    pub fn ran(&self, addr: u8) {
        self.set().remove(&addr);
    }

    /// Every uTile held through the API, forgotten.
    fn take(&self) -> BTreeSet<u8> {
        std::mem::take(&mut *self.set())
    }

    fn set(&self) -> std::sync::MutexGuard<'_, BTreeSet<u8>> {
        // A panic while holding the lock leaves a set of addresses, still whole.
        self.0.lock().unwrap_or_else(|e| e.into_inner())
    }
}

/// Counts the pages; once none has been open for [`LEASE`], runs the uTiles held from them.
pub async fn watch(hub: Arc<Hub>) {
    let mut unwatched_since: Option<Instant> = None;
    let mut tick = tokio::time::interval(CHECK);
    loop {
        tick.tick().await;
        if hub.stopping() {
            return;
        }
        if hub.state_json.receiver_count() > 0 {
            unwatched_since = None;
            continue;
        }
        let since = *unwatched_since.get_or_insert_with(Instant::now);
        if since.elapsed() < LEASE {
            continue;
        }
        for addr in hub.holds.take() {
            let [r0, r1] = HR_SCAN_CONTROL.to_be_bytes();
            let (job, done) = Job::new(
                addr,
                vec![WRITE_SINGLE_REGISTER, r0, r1, 0, 0],
                Origin::Page,
            );
            if hub.inputs.send(Input::Job(job)).is_err() {
                return;
            }
            tracing::info!(
                addr,
                "no page open for 10 s: the hold made from the page ended (Run)"
            );
            // Its outcome is the card's: a uTile that did not answer runs free by the
            // firmware's own lease.
            let _ = done.await;
        }
    }
}
