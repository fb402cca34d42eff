//! Several chips on one serial line, as on an RS-485 bus: the master's bytes reach every
//! chip, every chip's bytes reach the master and the other chips, and an optional
//! driver-enable pin per chip decides which bytes reach the line at all, judged over each
//! byte's whole time on the wire, and shows when two drive the line at once.

use super::chip::{Chip, CpuState};
use super::frame_cycles;
use super::uart::RxPacing;

/// Driver-enable pin of the RS-485 transceiver: D10 = PB2.
const DE_PORT: char = 'B';
const DE_BIT: u8 = 2;

/// One byte a chip sent on the line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BusByte {
    /// The byte.
    pub byte: u8,
    /// Cycle its stop bit ends.
    pub cycle: u64,
    /// Index of the chip that sent it.
    pub from: usize,
}

/// A byte a chip sent while its driver enable changed: part of it went onto the line, part
/// did not. A real bus carries a damaged character then (a receiver misses its start bit,
/// or reads the bits after the enable fell as the idle level); the bus gives it to nobody.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HalfOn {
    /// The byte the chip sent.
    pub byte: u8,
    /// Cycle its start bit begins.
    pub start: u64,
    /// Cycle its stop bit ends.
    pub stop: u64,
    /// Index of the chip that sent it.
    pub from: usize,
}

/// A time when two or more chips had their driver enabled at once.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Collision {
    /// Cycle the overlap began.
    pub start: u64,
    /// Cycle it ended (`None` while it lasts).
    pub end: Option<u64>,
    /// The chips with their driver enabled when it began.
    pub chips: Vec<usize>,
}

/// A byte on its way: sent, its stop bit not yet reached by its chip, so the driver
/// enable over its wire time is not known whole yet.
#[derive(Clone, Copy, Debug)]
struct OnWire {
    byte: u8,
    start: u64,
    stop: u64,
    from: usize,
}

/// Chips sharing one serial line at one baud rate, with the test as the bus master.
///
/// The chip furthest behind runs next, a stretch at a time: up to half a frame time past
/// the next chip (a byte another chip starts later cannot end sooner than a frame after its
/// start), never past the stop bit of a byte another chip still has on the wire (it is
/// judged when its own chip gets there, and then reaches the others on time), and no
/// further than the end of the run, where every chip stops at its first instruction
/// boundary at or past the end, as in instruction lockstep. A stretch also ends when the
/// chip sends a byte or changes its driver-enable pin; the pins' changes are merged in time
/// order into the [`Collision`]s.
///
/// With the driver enable watched ([`Bus::with_driver_enable`]), a byte reaches the line
/// only if its chip's D10 was high for the byte's whole wire time, from the start of its
/// start bit to the end of its stop bit; one sent with D10 low throughout reaches nobody
/// (the transceiver is not driving), and one during which D10 changed is a [`HalfOn`].
pub struct Bus {
    chips: Vec<Chip>,
    baud: u32,
    /// Driver-enable pins watched (D10 per chip).
    de: bool,
    /// Each chip's driver-enable pin as of its own cycle.
    de_on: Vec<bool>,
    /// Each chip's driver-enable changes (cycle, level), from the last one at or before the
    /// start of its oldest byte still on the wire (the first entry is the level then).
    de_seen: Vec<Vec<(u64, bool)>>,
    /// Driver-enable changes (cycle, chip, level) not yet merged into `collisions`.
    de_changes: Vec<(u64, usize, bool)>,
    /// The pins as of the last merged change.
    de_merged: Vec<bool>,
    /// Bytes sent and not yet judged.
    on_wire: Vec<OnWire>,
    /// Cycle the master's transmitter is free again.
    master_free: u64,
    master_rx: Vec<BusByte>,
    collisions: Vec<Collision>,
    half_on: Vec<HalfOn>,
}

impl Bus {
    /// Puts `chips` on one line at `baud` 8N1 (each chip's input becomes
    /// [`RxPacing::Line`]).
    pub fn new(mut chips: Vec<Chip>, baud: u32) -> Bus {
        for c in &mut chips {
            c.set_rx_pacing(RxPacing::Line { baud });
        }
        let n = chips.len();
        Bus {
            chips,
            baud,
            de: false,
            de_on: vec![false; n],
            de_seen: vec![vec![(0, false)]; n],
            de_changes: Vec::new(),
            de_merged: vec![false; n],
            on_wire: Vec::new(),
            master_free: 0,
            master_rx: Vec::new(),
            collisions: Vec::new(),
            half_on: Vec::new(),
        }
    }

    /// Watches each chip's driver-enable pin (D10 = PB2, high = driving): a chip's byte
    /// reaches the line only if it was high over the byte's whole wire time, a byte during
    /// which it changed is a [`HalfOn`], and two high at once is a [`Collision`].
    pub fn with_driver_enable(mut self) -> Bus {
        self.de = true;
        self
    }

    /// Number of chips.
    pub fn len(&self) -> usize {
        self.chips.len()
    }

    /// No chip on the line.
    pub fn is_empty(&self) -> bool {
        self.chips.is_empty()
    }

    /// Chip `i`.
    pub fn chip(&self, i: usize) -> &Chip {
        &self.chips[i]
    }

    /// Chip `i`, to drive its pins or reset it.
    pub fn chip_mut(&mut self, i: usize) -> &mut Chip {
        &mut self.chips[i]
    }

    /// The bus time: the cycle of the chip furthest behind.
    pub fn cycle(&self) -> u64 {
        self.chips.iter().map(Chip::cycle).min().unwrap_or(0)
    }

    /// The master sends `bytes` back to back after what it sent before: every chip
    /// receives each byte when its stop bit ends.
    pub fn send(&mut self, bytes: &[u8]) {
        self.send_after(0, bytes);
    }

    /// The master sends `bytes` after `idle` cycles of silence (e.g. Modbus's 3.5
    /// character times between frames).
    pub fn send_after(&mut self, idle: u64, bytes: &[u8]) {
        let frame = frame_cycles(self.baud);
        let mut start = self.master_free.max(self.cycle()) + idle;
        for &b in bytes {
            let stop = start + frame;
            for c in &mut self.chips {
                c.receive_at(stop, b);
            }
            start = stop;
        }
        self.master_free = start;
    }

    /// Runs every chip `cycles` further; returns the first chip that stopped, if any.
    pub fn run_for(&mut self, cycles: u64) -> Option<(usize, CpuState)> {
        let end = self.cycle().saturating_add(cycles);
        let stopped = self.run_to(end);
        self.merge_de_changes();
        stopped
    }

    /// Runs the chips in stretches (see [`Bus`]) until each is at or past cycle `end`.
    fn run_to(&mut self, end: u64) -> Option<(usize, CpuState)> {
        loop {
            self.judge();
            // The chip furthest behind (the first of equals), and the next one's cycle.
            let (mut i, mut now, mut next) = (0, u64::MAX, u64::MAX);
            for (j, c) in self.chips.iter().enumerate() {
                let at = c.cycle();
                if at < now {
                    (i, now, next) = (j, at, now);
                } else if at < next {
                    next = at;
                }
            }
            if now >= end {
                return None;
            }
            // Not past a byte of another chip whose wire time is still being watched.
            let unjudged = self
                .on_wire
                .iter()
                .filter(|b| b.from != i)
                .map(|b| b.stop)
                .min()
                .unwrap_or(u64::MAX);
            let horizon = end.min(next.saturating_add(self.lookahead())).min(unjudged);
            let (de, de_on) = (self.de, self.de_on[i]);
            let state = self.chips[i].run_while(horizon, |c| {
                c.output_len() > 0 || (de && c.drives_high(DE_PORT, DE_BIT) != de_on)
            });
            if state != CpuState::Running {
                return Some((i, state));
            }
            if self.de {
                self.watch_de(i);
            }
            if self.chips[i].output_len() > 0 {
                self.put_on_wire(i);
            }
        }
    }

    /// How far a chip may run past the next one: half the shortest frame on the line (the
    /// bus's baud rate, or a chip's faster setting), so every byte another chip may still
    /// send ends after it.
    fn lookahead(&self) -> u64 {
        let fastest = self.chips.iter().map(Chip::baud).fold(self.baud, u32::max);
        frame_cycles(fastest) / 2
    }

    /// Chip `i`'s new bytes go on its wire, to be judged at their stop bits.
    fn put_on_wire(&mut self, i: usize) {
        let frame = self.chips[i].frame_cycles_set();
        for (byte, stop) in self.chips[i].take_output_timed() {
            self.on_wire.push(OnWire {
                byte,
                start: stop.saturating_sub(frame),
                stop,
                from: i,
            });
        }
    }

    /// Every byte whose chip has run past its stop bit: on the line (to the master and the
    /// other chips, received at its stop bit) if the driver enable was high all along,
    /// nowhere if it was low all along, a [`HalfOn`] if it changed on the way.
    fn judge(&mut self) {
        let mut k = 0;
        while k < self.on_wire.len() {
            let b = self.on_wire[k];
            if self.chips[b.from].cycle() < b.stop {
                k += 1;
                continue;
            }
            self.on_wire.remove(k);
            match self.driven(b.from, b.start, b.stop) {
                Some(true) => {
                    self.master_rx.push(BusByte {
                        byte: b.byte,
                        cycle: b.stop,
                        from: b.from,
                    });
                    for (j, c) in self.chips.iter_mut().enumerate() {
                        if j != b.from {
                            c.receive_at(b.stop, b.byte);
                        }
                    }
                }
                Some(false) => {}
                None => self.half_on.push(HalfOn {
                    byte: b.byte,
                    start: b.start,
                    stop: b.stop,
                    from: b.from,
                }),
            }
        }
        self.forget_de();
    }

    /// Chip `i`'s driver enable from `start` to `stop`: `Some(level)` if it held one level
    /// all along (a change exactly at either end counts as outside), `None` if it changed in
    /// between. Without the pins watched, every byte is driven.
    fn driven(&self, i: usize, start: u64, stop: u64) -> Option<bool> {
        if !self.de {
            return Some(true);
        }
        let seen = &self.de_seen[i];
        let at_start = seen
            .iter()
            .take_while(|&&(at, _)| at <= start)
            .last()
            .map_or(seen[0].1, |&(_, on)| on);
        let changed = seen.iter().any(|&(at, _)| start < at && at < stop);
        (!changed).then_some(at_start)
    }

    /// Drops the driver-enable changes no byte still on a wire needs: each chip keeps the
    /// last change at or before its oldest byte's start (or its cycle now).
    fn forget_de(&mut self) {
        for (i, seen) in self.de_seen.iter_mut().enumerate() {
            let keep_from = self
                .on_wire
                .iter()
                .filter(|b| b.from == i)
                .map(|b| b.start)
                .min()
                .unwrap_or_else(|| self.chips[i].cycle());
            let first_needed = seen
                .iter()
                .rposition(|&(at, _)| at <= keep_from)
                .unwrap_or(0);
            seen.drain(..first_needed);
        }
    }

    /// Follows chip `i`'s driver-enable pin: a change is noted with its cycle.
    fn watch_de(&mut self, i: usize) {
        let on = self.chips[i].drives_high(DE_PORT, DE_BIT);
        if on != self.de_on[i] {
            let at = self.chips[i].cycle();
            self.de_on[i] = on;
            self.de_seen[i].push((at, on));
            self.de_changes.push((at, i, on));
        }
    }

    /// Opens and closes collisions from the driver-enable changes up to the bus time (every
    /// chip has run that far), in the order they happened.
    fn merge_de_changes(&mut self) {
        let upto = self.cycle();
        self.de_changes.sort_by_key(|&(at, i, _)| (at, i));
        let due = self.de_changes.partition_point(|&(at, _, _)| at <= upto);
        for (now, i, on) in self.de_changes.drain(..due) {
            self.de_merged[i] = on;
            let driving: Vec<usize> = (0..self.chips.len())
                .filter(|&j| self.de_merged[j])
                .collect();
            let open = self.collisions.last().is_some_and(|c| c.end.is_none());
            if driving.len() >= 2 && !open {
                self.collisions.push(Collision {
                    start: now,
                    end: None,
                    chips: driving,
                });
            } else if driving.len() < 2 && open {
                if let Some(c) = self.collisions.last_mut() {
                    c.end = Some(now);
                }
            }
        }
    }

    /// Takes the bytes that reached the line since the last call (each judged once its chip
    /// has run past its stop bit), in the order they ended.
    pub fn take_master(&mut self) -> Vec<BusByte> {
        let mut v = std::mem::take(&mut self.master_rx);
        v.sort_by_key(|b| b.cycle);
        v
    }

    /// The bytes sent so far while their chip's driver enable changed (see [`HalfOn`]).
    pub fn half_on(&self) -> &[HalfOn] {
        &self.half_on
    }

    /// The overlaps of driver-enable pins seen so far.
    pub fn collisions(&self) -> &[Collision] {
        &self.collisions
    }
}
