//! One Modbus RTU slave on a serial line: frames in, the request handled against a map, the
//! reply out one byte at a time, the drops counted, and whether a master is active (the
//! terminal stays quiet while one is).
//!
//! The board reports the line's silences ([`Slave::push`] with `after_gap`, [`Slave::close`]
//! after 3.5 character times, both measured as [`super::frame`] says) as they happen, from
//! its interrupts; the main program carries a closed frame out later ([`Slave::judge`]).
//! A frame is closed at its silence whatever the main program is doing, so a byte that
//! comes after it starts a new frame: a frame for another slave (or a broken one) is counted
//! and forgotten at once, and one this slave must carry out (a request for it, a broadcast,
//! the lone `/`) keeps the line until it has been, as its reply does (RS-485 is half duplex).
//! The slave never waits and never holds a reply buffer.

use super::frame::{Receiver, Verdict};
use super::map::Map;
use super::reply::Reply;
use super::request::{handle, Answer};
use super::BROADCAST;

/// A master counts as active this long after its last valid frame for this slave (SPEC §13:
/// the terminal's RUN displays resume after 3 s of silence).
pub const ACTIVE_MS: u32 = 3000;

/// What the end of a frame meant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// Nothing (no frame closed, or it was counted when it closed: [`Slave::close`]).
    None,
    /// The single byte `/`: the terminal's break key.
    Slash,
    /// A frame was thrown away and counted ([`Slave::dropped`]).
    Dropped,
    /// A broadcast was carried out (no reply).
    Broadcast,
    /// A request for this slave: the reply waits in [`Slave::next_byte`].
    Reply,
}

/// The slave's state between frames.
#[derive(Clone, Debug)]
pub struct Slave {
    rx: Receiver,
    /// The reply being sent, while `replying`.
    reply: Reply,
    replying: bool,
    /// A frame closed by [`Slave::close`] waits for [`Slave::judge`]: a request for this
    /// slave or a broadcast (its bytes in `rx`'s last frame), or the lone `/` (none).
    closed: bool,
    /// Frames dropped (CRC, length, gap, another address), saturating.
    dropped: u16,
    /// The ms clock at the last valid frame for this slave.
    last_ms: u32,
    /// Whether a valid frame for this slave ever came (`last_ms` means something).
    heard: bool,
}

impl Default for Slave {
    fn default() -> Self {
        Self::new()
    }
}

impl Slave {
    /// A slave that has heard nothing.
    pub const fn new() -> Self {
        Self {
            rx: Receiver::new(),
            reply: Reply::none(),
            replying: false,
            closed: false,
            dropped: 0,
            last_ms: 0,
            heard: false,
        }
    }

    /// A received byte; `after_gap`: the line was silent for more than 1.5 character times
    /// since the previous byte's stop bit (see [`super::frame::pause_limit`]).
    /// From a closed frame this slave carries out until its reply has gone, the line is
    /// ours (RS-485 is half duplex): bytes are ignored.
    pub fn push(&mut self, byte: u8, after_gap: bool) {
        if !self.replying && !self.closed {
            self.rx.push(byte, after_gap);
        }
    }

    /// Whether a frame closed by [`Slave::close`] waits for [`Slave::judge`].
    pub fn closed(&self) -> bool {
        self.closed
    }

    /// Whether bytes of an unfinished frame wait for their silence.
    pub fn receiving(&self) -> bool {
        !self.rx.is_empty()
    }

    /// 3.5 character times of silence (the board's timer interrupt): the frame is closed.
    /// A broken frame or one for another address than `address` (1..247) is counted
    /// ([`Slave::dropped`]) and forgotten; a request for `address`, a broadcast or the lone
    /// `/` waits for [`Slave::judge`] (returns true), and bytes are ignored until then.
    ///
    /// While a closed frame waits or a reply is being made nothing closes: the bytes were
    /// ignored, and the request the reply is built from stays.
    pub fn close(&mut self, address: u8) -> bool {
        if self.replying || self.closed {
            return self.closed;
        }
        self.closed = match self.rx.end() {
            Verdict::Empty => return false,
            Verdict::Slash => true,
            Verdict::Dropped(_) => false,
            Verdict::Frame { .. } => {
                let to = self.rx.frame().first().copied().unwrap_or(0);
                to == address || to == BROADCAST
            }
        };
        if !self.closed {
            self.dropped = self.dropped.saturating_add(1);
        }
        self.closed
    }

    /// Carry out the frame [`Slave::close`] kept: a request for this slave on `map` (its
    /// reply then waits in [`Slave::next_byte`]), a broadcast on `map` (no reply), or the
    /// break key. [`Event::None`] when no frame waits.
    pub fn judge<M: Map + ?Sized>(&mut self, map: &mut M, now_ms: u32) -> Event {
        if !core::mem::take(&mut self.closed) {
            return Event::None;
        }
        let frame = self.rx.frame();
        let Some(&to) = frame.first() else {
            return Event::Slash;
        };
        let pdu = frame.get(1..frame.len() - 2).unwrap_or(&[]);
        let answer: Answer = handle(pdu, map);
        if to == BROADCAST {
            // Carried out, never answered: only a write changes anything.
            return Event::Broadcast;
        }
        self.last_ms = now_ms;
        self.heard = true;
        self.reply = Reply::new(to, answer, map);
        self.replying = true;
        Event::Reply
    }

    /// [`Slave::close`] and [`Slave::judge`] at once, for a board that does both between
    /// two scans; a frame counted as dropped is [`Event::Dropped`].
    pub fn end<M: Map + ?Sized>(&mut self, address: u8, map: &mut M, now_ms: u32) -> Event {
        let dropped = self.dropped;
        if !self.close(address) {
            return if self.dropped != dropped {
                Event::Dropped
            } else {
                Event::None
            };
        }
        self.judge(map, now_ms)
    }

    /// Whether a reply is being sent.
    pub fn replying(&self) -> bool {
        self.replying
    }

    /// The next byte of the reply (read from `map` now), or `None` when it is complete.
    pub fn next_byte<M: Map + ?Sized>(&mut self, map: &mut M) -> Option<u8> {
        if !self.replying {
            return None;
        }
        let frame = self.rx.frame();
        let pdu = frame.get(1..frame.len().saturating_sub(2)).unwrap_or(&[]);
        let byte = self.reply.next_byte(map, pdu);
        if byte.is_none() {
            self.replying = false;
        }
        byte
    }

    /// Frames dropped since [`Slave::new`] (or [`Slave::clear_counts`]).
    pub fn dropped(&self) -> u16 {
        self.dropped
    }

    /// Start counting drops from 0 (RUN).
    pub fn clear_counts(&mut self) {
        self.dropped = 0;
    }

    /// Whether a master sent this slave a valid frame within the last [`ACTIVE_MS`].
    pub fn master_active(&self, now_ms: u32) -> bool {
        self.heard && now_ms.wrapping_sub(self.last_ms) < ACTIVE_MS
    }

    /// Whether the terminal must wait: a frame is coming in or waits to be judged, its reply
    /// is being sent, or a master is active (SPEC §13: nothing but replies meanwhile).
    pub fn line_busy(&self, now_ms: u32) -> bool {
        self.receiving() || self.closed || self.replying || self.master_active(now_ms)
    }
}
