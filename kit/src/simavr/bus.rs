//! Several chips on one serial line, as on an RS-485 bus: the master's bytes reach every
//! chip, every chip's bytes reach the master and the other chips, and an optional
//! driver-enable pin per chip shows when two drive the line at once.

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

/// Chips sharing one serial line at one baud rate, run in lockstep (the one furthest behind
/// steps next), with the test as the bus master.
pub struct Bus {
    chips: Vec<Chip>,
    baud: u32,
    /// Driver-enable pins watched (D10 per chip).
    de: bool,
    de_on: Vec<bool>,
    /// Cycle the master's transmitter is free again.
    master_free: u64,
    master_rx: Vec<BusByte>,
    collisions: Vec<Collision>,
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
            master_free: 0,
            master_rx: Vec::new(),
            collisions: Vec::new(),
        }
    }

    /// Watches each chip's driver-enable pin (D10 = PB2, high = driving): a chip's bytes
    /// reach the line only while it is high, and two high at once is a [`Collision`].
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
        loop {
            let (i, now) = self
                .chips
                .iter()
                .enumerate()
                .map(|(i, c)| (i, c.cycle()))
                .min_by_key(|&(_, c)| c)?;
            if now >= end {
                return None;
            }
            let state = self.chips[i].step();
            if state != CpuState::Running {
                return Some((i, state));
            }
            if self.de {
                self.watch_de(i);
            }
            if self.chips[i].output_len() > 0 {
                self.route(i);
            }
        }
    }

    /// Chip `i`'s new bytes go to the master and the other chips.
    fn route(&mut self, i: usize) {
        let sent = self.chips[i].take_output_timed();
        if self.de && !self.de_on[i] {
            return; // its transceiver is not driving: nothing reaches the line
        }
        for (byte, cycle) in sent {
            self.master_rx.push(BusByte {
                byte,
                cycle,
                from: i,
            });
            for (j, c) in self.chips.iter_mut().enumerate() {
                if j != i {
                    c.receive_at(cycle, byte);
                }
            }
        }
    }

    /// Follows chip `i`'s driver-enable pin and opens or closes collisions.
    fn watch_de(&mut self, i: usize) {
        let on = self.chips[i].drives_high(DE_PORT, DE_BIT);
        if on == self.de_on[i] {
            return;
        }
        self.de_on[i] = on;
        let now = self.chips[i].cycle();
        let driving: Vec<usize> = (0..self.chips.len()).filter(|&j| self.de_on[j]).collect();
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

    /// Takes the bytes the chips sent since the last call, in the order they ended.
    pub fn take_master(&mut self) -> Vec<BusByte> {
        let mut v = std::mem::take(&mut self.master_rx);
        v.sort_by_key(|b| b.cycle);
        v
    }

    /// The overlaps of driver-enable pins seen so far.
    pub fn collisions(&self) -> &[Collision] {
        &self.collisions
    }
}
