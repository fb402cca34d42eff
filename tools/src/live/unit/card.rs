//! A uTile's card: its state (offline, EDIT, stopped, held, online) with the advice in
//! words, and its part of the published view.

use std::time::Instant;

use utile_core::modbus::hold::{STATUS_HELD, STATUS_LAPSED};
use utile_core::modbus::plc::STATUS_RUNNING;

use super::super::program::ProgramFile;
use super::super::screen::Mode;
use super::super::signals;
use super::super::view::{CardState, FileMatch, ProgramView, UnitView, EDIT_ADVICE};
use super::Unit;

/// A held card's advice (SPEC §18).
const HELD_ADVICE: &str = "Held: the scan stopped at its END, the outputs stay as they are. Run \
                           lets it run freely, Step runs 1 or 10 scans. Without a Modbus frame \
                           for 10 s the hold ends by itself.";
/// A running card's advice after a hold ended by itself.
const LAPSED_ADVICE: &str = "A hold ended by itself since RUN (no Modbus frame came for 10 s).";

impl Unit {
    /// A card's state: offline, edit (the editor has the line), stopped (answers, but its
    /// status says the program is not running) or online.
    pub fn card_state(&self, open: bool, mode: Mode) -> CardState {
        if !open || !self.online && mode != Mode::Edit {
            return CardState::Offline;
        }
        if mode == Mode::Edit {
            return CardState::Edit;
        }
        match &self.snap {
            Some((s, _)) if s.status & STATUS_RUNNING == 0 => CardState::Stopped,
            Some((s, _)) if s.status & STATUS_HELD != 0 => CardState::Held,
            _ => CardState::Online,
        }
    }

    /// When the latest snapshot came, if it shows the scan not held (running freely, or not
    /// running at all).
    pub fn not_held_since(&self) -> Option<Instant> {
        match &self.snap {
            Some((s, at)) if s.status & STATUS_HELD == 0 => Some(*at),
            _ => None,
        }
    }

    /// Its part of the view published at `now`.
    pub fn view(
        &self,
        open: bool,
        mode: Mode,
        file: Option<&ProgramFile>,
        now: Instant,
    ) -> UnitView {
        let state = self.card_state(open, mode);
        let advice = match state {
            CardState::Offline => format!(
                "No answer{}: check the cable, the power and the uTile's address (ADDR {}). \
                 The values shown are the last ones read.",
                self.reason
                    .as_ref()
                    .map(|r| format!(" ({r})"))
                    .unwrap_or_default(),
                self.addr
            ),
            CardState::Edit => format!("{EDIT_ADVICE}."),
            CardState::Stopped => {
                "uTile answers, but its program is not running: start it with RUN or EX0."
                    .to_string()
            }
            CardState::Held => HELD_ADVICE.to_string(),
            CardState::Online => match (&self.reason, &self.snap) {
                (Some(r), _) => r.clone(),
                (None, Some((s, _))) if s.status & STATUS_LAPSED != 0 => LAPSED_ADVICE.into(),
                _ => String::new(),
            },
        };
        let snap = self.snap.as_ref();
        let program = match (&self.program, snap) {
            (Some((fp, _, same)), Some((s, _))) => Some(ProgramView {
                fingerprint: *fp,
                consistent: *same,
                values: self.program_values.clone(),
                file: file.map(|f| FileMatch {
                    name: f.name.clone(),
                    fingerprint: f.fingerprint,
                    matches: f.fingerprint == s.fingerprint,
                }),
            }),
            _ => None,
        };
        UnitView {
            addr: self.addr,
            state,
            online: state != CardState::Offline,
            advice,
            reason: self.reason.clone(),
            legacy: self.legacy,
            scan_control: self.scan_control.clone(),
            age_ms: snap.map(|(_, t)| now.duration_since(*t).as_millis() as u64),
            values: snap
                .map(|(s, _)| signals::values(s, self.holdings.as_ref()))
                .unwrap_or_default(),
            refresh_per_s: self.refresh_rate(now),
            scans_per_s: self.scans_per_s.round(),
            link: self.link.clone(),
            program,
            snapshots: self.snapshots,
            listing: self.listing.clone(),
            trend: self.trend.clone(),
        }
    }
}
