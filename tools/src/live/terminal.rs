//! The terminal on the same cable: what uTile's editor sends goes to every terminal open in
//! a page (xterm.js over a WebSocket), with the screen since the last clear kept so a page
//! opened later shows it; keys typed there reach the line through its owner.

use std::sync::Mutex;

use tokio::sync::broadcast;

/// Kept output, at most (a full uTile screen is about 2 KB).
const KEEP: usize = 32 * 1024;
/// VT100 "erase the screen": what comes before it is no longer on the screen.
const CLEAR: &[u8] = b"\x1b[2J";

/// The terminal's output, for the pages that show it. The kept screen and the channel
/// change together, under one lock: a page that opens while output flows gets every byte
/// once, in order (the screen so far, then each chunk after it).
pub struct Terminal {
    inner: Mutex<Inner>,
}

/// What the lock guards.
struct Inner {
    tx: broadcast::Sender<Vec<u8>>,
    kept: Vec<u8>,
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
            inner: Mutex::new(Inner {
                tx: broadcast::channel(256).0,
                kept: Vec::new(),
            }),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Inner> {
        // A panic elsewhere while it was held leaves bytes, never a broken invariant.
        self.inner.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Output from uTile.
    pub fn output(&self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let mut inner = self.lock();
        let kept = &mut inner.kept;
        kept.extend_from_slice(bytes);
        if let Some(at) = crate::link::port::find_last(kept, CLEAR) {
            kept.drain(..at);
        }
        let excess = kept.len().saturating_sub(KEEP);
        kept.drain(..excess);
        // No page open: nobody to send to (the kept screen has it).
        let _no_page = inner.tx.send(bytes.to_vec()).is_err();
    }

    /// The screen so far and what comes next.
    pub fn subscribe(&self) -> (Vec<u8>, broadcast::Receiver<Vec<u8>>) {
        let inner = self.lock();
        (inner.kept.clone(), inner.tx.subscribe())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;

    /// The screen's clear as text.
    const CLEAR_TEXT: &str = "\x1b[2J";

    /// The numbers in `text` ("17,18,19,") after the first comma (a page may open mid-number,
    /// once the kept screen is trimmed), or the place where one is not the last plus one.
    fn in_order(text: &str) -> Result<usize, String> {
        let mut numbers = text.split(',').skip(1).filter(|s| !s.is_empty());
        let Some(first) = numbers.next() else {
            return Ok(0);
        };
        let first = first.trim_start_matches(CLEAR_TEXT);
        let mut last: u64 = first
            .parse()
            .map_err(|_| format!("not a number: {first}"))?;
        let mut n = 1;
        for s in numbers {
            let s = s.trim_start_matches(CLEAR_TEXT);
            let x: u64 = s.parse().map_err(|_| format!("not a number: {s}"))?;
            if x != last + 1 {
                return Err(format!("{x} came after {last}"));
            }
            last = x;
            n += 1;
        }
        Ok(n)
    }

    #[test]
    fn a_page_opened_while_output_flows_gets_every_byte_once_in_order() {
        let t = Arc::new(Terminal::new());
        let done = Arc::new(AtomicBool::new(false));
        let writer = {
            let (t, done) = (t.clone(), done.clone());
            std::thread::spawn(move || {
                for i in 0..200_000u64 {
                    // A clear now and then, as the editor's screens have: the kept screen
                    // starts there.
                    let clear = if i % 64 == 0 { CLEAR_TEXT } else { "" };
                    t.output(format!("{clear}{i},").as_bytes());
                }
                done.store(true, Ordering::Relaxed);
            })
        };
        let pages: Vec<_> = (0..2)
            .map(|_| {
                let (t, done) = (t.clone(), done.clone());
                std::thread::spawn(move || {
                    let mut opened = 0u32;
                    while !done.load(Ordering::Relaxed) {
                        // A page opens: the kept screen, then the next chunks as they come.
                        let (kept, mut rx) = t.subscribe();
                        let mut seen = kept;
                        let mut whole = true;
                        let mut got = 0;
                        while got < 8 && !done.load(Ordering::Relaxed) {
                            match rx.try_recv() {
                                Ok(chunk) => {
                                    seen.extend_from_slice(&chunk);
                                    got += 1;
                                }
                                Err(broadcast::error::TryRecvError::Empty) => {
                                    std::thread::sleep(std::time::Duration::from_micros(50))
                                }
                                // Fell behind the channel: nothing to judge.
                                Err(_) => {
                                    whole = false;
                                    break;
                                }
                            }
                        }
                        if whole {
                            let text = String::from_utf8(seen).expect("text");
                            if let Err(why) = in_order(&text) {
                                return Err(format!("page {opened}: {why}"));
                            }
                            opened += 1;
                        }
                    }
                    Ok(opened)
                })
            })
            .collect();
        writer.join().expect("the writer");
        let mut opened = 0;
        for p in pages {
            opened += p
                .join()
                .expect("a page")
                .expect("every byte once, in order");
        }
        assert!(opened >= 100, "only {opened} pages were opened");
    }
}
