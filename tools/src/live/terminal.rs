//! The terminal on the same cable: what uTile's editor sends goes to every terminal open in
//! a page (xterm.js over a WebSocket), with the screen since the last clear kept so a page
//! opened later shows it; keys typed there reach the line through its owner.

use std::sync::Mutex;

use tokio::sync::broadcast;

/// Kept output, at most (a full uTile screen is about 2 KB).
const KEEP: usize = 32 * 1024;
/// VT100 "erase the screen": what comes before it is no longer on the screen.
const CLEAR: &[u8] = b"\x1b[2J";

/// The terminal's output, for the pages that show it.
pub struct Terminal {
    tx: broadcast::Sender<Vec<u8>>,
    kept: Mutex<Vec<u8>>,
}

impl Default for Terminal {
    fn default() -> Self {
        Terminal::new()
    }
}

impl Terminal {
    /// No output yet.
    pub fn new() -> Terminal {
        Terminal {
            tx: broadcast::channel(256).0,
            kept: Mutex::new(Vec::new()),
        }
    }

    /// Output from uTile.
    pub fn output(&self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        if let Ok(mut kept) = self.kept.lock() {
            kept.extend_from_slice(bytes);
            if let Some(at) = crate::link::port::find_last(&kept, CLEAR) {
                kept.drain(..at);
            }
            let excess = kept.len().saturating_sub(KEEP);
            kept.drain(..excess);
        }
        let _ = self.tx.send(bytes.to_vec());
    }

    /// The screen so far and what comes next.
    pub fn subscribe(&self) -> (Vec<u8>, broadcast::Receiver<Vec<u8>>) {
        let kept = self.kept.lock().map(|k| k.clone()).unwrap_or_default();
        (kept, self.tx.subscribe())
    }
}
