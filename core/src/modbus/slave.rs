//! One Modbus RTU slave on a serial line: frames in, the request handled against a map, the
//! reply out one byte at a time, the drops counted, and whether a master is active (the
//! terminal stays quiet while one is).
//!
//! The board reports the line's silences ([`Slave::push`] with `after_gap`, [`Slave::end`]
//! after 3.5 character times, both measured as [`super::frame`] says); the slave never waits
//! and never holds a reply buffer.

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
    /// Nothing (an empty frame, or bytes that arrived while a reply was going out).
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
            dropped: 0,
            last_ms: 0,
            heard: false,
        }
    }

    /// A received byte; `after_gap`: the line was silent for more than 1.5 character times
    /// since the previous byte's stop bit (see [`super::frame::pause_limit`]).
    /// While a reply goes out the line is ours (RS-485 is half duplex): bytes are ignored.
    pub fn push(&mut self, byte: u8, after_gap: bool) {
        if !self.replying {
            self.rx.push(byte, after_gap);
        }
    }

    /// Whether bytes of an unfinished frame wait for their silence.
    pub fn receiving(&self) -> bool {
        !self.rx.is_empty()
    }

    /// 3.5 character times of silence: judge the frame, and for a valid request to
    /// `address` (1..247) or a broadcast, carry it out on `map`.
    ///
    /// While a reply is being made nothing ends: the bytes were ignored, and the request the
    /// reply is built from stays.
    pub fn end<M: Map + ?Sized>(&mut self, address: u8, map: &mut M, now_ms: u32) -> Event {
        if self.replying {
            return Event::None;
        }
        let len = match self.rx.end() {
            Verdict::Empty => return Event::None,
            Verdict::Slash => return Event::Slash,
            Verdict::Dropped(_) => return self.drop(),
            Verdict::Frame { len } => usize::from(len),
        };
        let frame = self.rx.frame();
        let to = frame.first().copied().unwrap_or(0);
        let pdu = frame.get(1..len - 2).unwrap_or(&[]);
        if to == BROADCAST {
            // Carried out, never answered: only a write changes anything.
            handle(pdu, map);
            return Event::Broadcast;
        }
        if to != address {
            return self.drop();
        }
        self.last_ms = now_ms;
        self.heard = true;
        let answer: Answer = handle(pdu, map);
        self.reply = Reply::new(address, answer, map);
        self.replying = true;
        Event::Reply
    }

    fn drop(&mut self) -> Event {
        self.dropped = self.dropped.saturating_add(1);
        Event::Dropped
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
        self.receiving() || self.replying || self.master_active(now_ms)
    }
}
