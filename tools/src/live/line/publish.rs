//! The view the owner publishes after each change: the line's figures, every uTile's part
//! (values by name from the signal table, the program's values, the trend). Built on the
//! line's thread in microseconds; read by everyone else.

use std::sync::Arc;
use std::time::Instant;

use utile_core::engine::TIMER_UNIT_MS;

use super::super::view::{LineFigures, View};
use super::Owner;

impl Owner {
    /// Publishes the line's state as a new immutable view.
    pub(super) fn publish(&mut self) {
        let now = Instant::now();
        self.published += 1;
        let view = View {
            port: self.opts.path.clone(),
            open: self.open,
            mode: self.mode,
            message: self.message.clone(),
            notes: self.opts.notes.clone(),
            read_only: self.hub.read_only,
            timer_unit_ms: TIMER_UNIT_MS,
            line: LineFigures {
                busy: self.busy_share,
                stray_bytes: self.stray,
                bytes: self.line_bytes,
                requests: self.requests,
                writes: self.writes,
                reply_slack_ms: self.slack.as_millis() as u64,
            },
            units: self
                .units
                .iter()
                .map(|u| u.view(self.open, self.mode, self.opts.file.as_ref(), now))
                .collect(),
            seq: self.published,
        };
        self.publish.send_replace(Arc::new(view));
    }

    /// Sets the line's message (and publishes when it changed).
    pub(super) fn say(&mut self, message: impl Into<String>) {
        let message = message.into();
        if message != self.message {
            self.message = message;
            self.publish();
        }
    }

    /// The uTile at `addr`.
    pub(super) fn unit_mut(&mut self, addr: u8) -> Option<&mut super::super::unit::Unit> {
        self.units.iter_mut().find(|u| u.addr == addr)
    }
}
