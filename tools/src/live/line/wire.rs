//! The bytes on the wire: the terminal's share, writes after the 3.5-character gap, one
//! request and its reply, and what the replies teach about how late they may come.

use std::io::{Read as _, Write as _};
use std::time::{Duration, Instant};

use serialport::SerialPort;
use utile_kit::modbus;

use super::super::job::Failure;
use super::super::rtu::{self, Scan};
use super::{Miss, Owner, INTER_BYTE};

impl Owner {
    /// Reads whatever comes within `wait`: the editor's screen.
    pub(super) fn listen(&mut self, wait: Duration) {
        let mut buf = [0u8; 1024];
        let Some(p) = self.port.as_mut() else {
            return;
        };
        if let Err(e) = p.set_timeout(wait) {
            self.close(&format!("setting its time-out: {e}"));
            return;
        }
        match p.read(&mut buf) {
            Ok(0) => {}
            Ok(n) => {
                self.quiet_since = Instant::now();
                self.terminal(&buf[..n]);
            }
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => {}
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e) => self.close(&format!("reading: {e}")),
        }
    }

    /// Bytes for the terminal (and the screen tracker).
    pub(super) fn terminal(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        self.hub.terminal.output(bytes);
        if let Some(m) = self.screen.feed(bytes, Instant::now()) {
            self.set_mode(m);
        }
    }

    /// Writes `bytes` after the 3.5-character gap.
    pub(super) fn write(&mut self, bytes: &[u8]) -> bool {
        let gap = rtu::frame_gap();
        let since = self.quiet_since.elapsed();
        if since < gap {
            std::thread::sleep(gap - since);
        }
        let Some(p) = self.port.as_mut() else {
            return false;
        };
        match p.write_all(bytes) {
            Ok(()) => {
                self.quiet_since = Instant::now() + rtu::line_time(bytes.len());
                true
            }
            Err(e) => {
                self.close(&format!("writing: {e}"));
                false
            }
        }
    }

    /// Keys from a page's terminal, as their own frame (between two transactions); whoever
    /// typed them hears whether they went.
    pub(super) fn send_keys(&mut self) {
        if self.keys.is_empty() {
            return;
        }
        let keys = std::mem::take(&mut self.keys);
        let outcome = if self.write(&keys) {
            Ok(())
        } else {
            Err(Failure::PortClosed)
        };
        for reply in self.keys_for.drain(..) {
            reply.send(outcome.clone());
        }
    }

    /// Counts `bytes` of a transaction on the line (the busy figure); their line time.
    pub(super) fn count_line_time(&mut self, bytes: usize) -> Duration {
        let t = rtu::line_time(bytes);
        self.busy_share = self.busy.add(Instant::now(), t);
        self.line_bytes += bytes as u64;
        t
    }

    /// One request and its reply: the reply's PDU and the round trip, or why not. Bytes
    /// around the reply go to the terminal.
    pub(super) fn transact(
        &mut self,
        addr: u8,
        pdu: &[u8],
        slack: Duration,
    ) -> Result<(Vec<u8>, Duration), Miss> {
        // What came before the request is the editor's (or the RUN screen's).
        while self
            .port
            .as_ref()
            .is_some_and(|p| p.bytes_to_read().unwrap_or(0) > 0)
        {
            self.listen(Duration::from_millis(1));
        }
        let frame = modbus::frame(addr, pdu);
        if !self.write(&frame) {
            return Err(Miss::Port);
        }
        self.requests += 1;
        if pdu.first().copied().is_some_and(rtu::is_write) {
            self.writes += 1;
        }
        let t0 = Instant::now();
        let mut deadline = t0 + rtu::reply_timeout(&frame, slack);
        // A reply on its way is waited for while its bytes keep coming (a slow adapter or
        // simulation), never longer than this: a request sent into it would collide.
        let last_chance = t0 + rtu::reply_timeout(&frame, rtu::SLACK_MAX * 2);
        let mut got = Vec::new();
        let mut buf = [0u8; 512];
        loop {
            let now = Instant::now();
            if let Scan::Reply { start, end } = rtu::find_reply(&got, addr, &frame) {
                self.quiet_since = now;
                let reply = got[start + 1..end - 2].to_vec();
                self.stray(&got[..start]);
                self.stray(&got[end..]);
                let on_line = self.count_line_time(frame.len() + end - start);
                self.learn_slack(now - t0, on_line, now);
                return Ok((reply, now - t0));
            }
            if now >= deadline {
                break;
            }
            let Some(p) = self.port.as_mut() else {
                return Err(Miss::Port);
            };
            if let Err(e) = p.set_timeout((deadline - now).min(Duration::from_millis(20))) {
                self.close(&format!("setting its time-out: {e}"));
                return Err(Miss::Port);
            }
            match p.read(&mut buf) {
                Ok(n) => {
                    got.extend_from_slice(&buf[..n]);
                    if n > 0 {
                        deadline = deadline.max(Instant::now() + INTER_BYTE).min(last_chance);
                    }
                }
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted
                    ) => {}
                Err(e) => {
                    self.close(&format!("reading: {e}"));
                    return Err(Miss::Port);
                }
            }
            if got.len() > 4 * rtu::MAX_FRAME {
                break;
            }
        }
        self.count_line_time(frame.len());
        let missed = rtu::missed_reply(&got, addr, &frame);
        self.stray(&got);
        if !got.is_empty() {
            self.quiet_since = Instant::now();
        }
        Err(Miss::Timeout {
            crc: missed.bad_crc,
            not_reply: missed.not_reply,
        })
    }

    /// A reply came `rtt` after the request went out, for `on_line` of bytes on the line:
    /// the slack follows the latest replies' lateness (three times the recent worst, at least
    /// [`rtu::ANSWER_SLACK`]).
    pub(super) fn learn_slack(&mut self, rtt: Duration, on_line: Duration, now: Instant) {
        self.answered = Some(now);
        let late = rtt.saturating_sub(on_line);
        self.late = late.max(self.late.mul_f64(0.98));
        self.slack =
            (self.late * 3 + Duration::from_millis(30)).clamp(rtu::ANSWER_SLACK, rtu::SLACK_MAX);
    }

    /// Bytes that were not a reply: the editor's screen when they carry its text, else
    /// noise (counted); the terminal shows them either way.
    pub(super) fn stray(&mut self, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        self.stray += bytes.len() as u64;
        self.terminal(bytes);
    }
}
