//! SPEC §18: the scan held and stepped from a Modbus master. Holding register 32 holds (1)
//! or releases (0) the scan, holding register 33 asks for n more scans (1..1000) and then a
//! hold; a hold ends by itself 10 s after the last valid frame for this slave (the lease).
//! Status bits 4 (held) and 5 (a hold ended by itself since RUN) are kept here in their
//! places, so the status register ORs them in.
//!
//! This is the decision only: the firmware's RUN loop asks [`Hold::next`] between two scans
//! whether the next scan may run ([`Next`]); nothing here runs in the scan.

use crate::board::Board;

/// Holding register 32 [40033]: 1 while the scan is held, 0 while it runs freely.
pub const HR_SCAN_CONTROL: u16 = 32;
/// Holding register 33 [40034]: the steps not yet run; writing n asks for n more scans.
pub const HR_STEPS: u16 = 33;
/// Most steps one write may ask for.
pub const MAX_STEPS: u16 = 1000;
/// A hold ends by itself this long after the last valid frame for this slave.
pub const LEASE_MS: u32 = 10_000;
/// Status bit 4 (input registers 0 and 64): the scan is held.
pub const STATUS_HELD: u16 = HELD as u16;
/// Status bit 5: a hold has ended by itself since RUN.
pub const STATUS_LAPSED: u16 = LAPSED as u16;
/// [`STATUS_HELD`] in [`Hold::bits`].
const HELD: u8 = 1 << 4;
/// [`STATUS_LAPSED`] in [`Hold::bits`].
const LAPSED: u8 = 1 << 5;

/// What the RUN loop does next, between two scans.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub enum Next {
    /// Scan freely, as many scans as the scan runs before it comes back.
    Free,
    /// Run exactly one scan (a step), then ask again.
    Step,
    /// Run no scan: serve the line, feed the watchdog, and ask again.
    Held,
}

/// The scan's hold: RUN starts it free (all zeros).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Hold {
    /// [`STATUS_HELD`] and [`STATUS_LAPSED`], in their status places (the low byte).
    pub bits: u8,
    /// Steps not yet run (holding register 33).
    pub steps: u16,
    /// The ms clock's low 16 bits at the last valid frame for this slave (the lease runs
    /// from it). 16 bits are enough: [`Hold::next`] looks at it many times a second.
    pub heard_ms: u16,
}

impl Hold {
    /// Whether the scan is held (register 32, status bit 4): a hold asked for, by itself
    /// or after steps still to run.
    pub fn held(&self) -> bool {
        self.bits & HELD != 0
    }

    /// Whether a hold has ended by itself since RUN (status bit 5).
    pub fn lapsed(&self) -> bool {
        self.bits & LAPSED != 0
    }

    /// Holding register 32 or 33 as a master reads it.
    pub fn read(&self, addr: u16) -> u16 {
        if addr == HR_SCAN_CONTROL {
            u16::from(self.held())
        } else {
            self.steps
        }
    }

    /// Whether register 32 (0 or 1) or 33 (1..[`MAX_STEPS`]) takes `value`; else the codec
    /// answers exception 03 and nothing changes.
    pub fn accepts(addr: u16, value: u16) -> bool {
        // 32 is even and takes 0..=1; 33 is odd and takes 1..=1000, that is 0..=999 less 1.
        let odd = addr & 1;
        let max = if odd != 0 { MAX_STEPS - 1 } else { 1 };
        value.wrapping_sub(odd) <= max
    }

    /// A write the codec has checked with [`Hold::accepts`]: 1 to register 32 holds at the
    /// next END (steps still to run are dropped), 0 releases; n to register 33 runs n more
    /// scans and then holds.
    pub fn write(&mut self, addr: u16, value: u16) {
        // Steps only from 33 (odd); a hold from any value but 32's 0 (33 takes no 0).
        self.steps = value & 0u16.wrapping_sub(addr & 1);
        self.bits &= LAPSED;
        if value != 0 {
            self.bits |= HELD;
        }
    }

    /// A valid request for this slave's own address came at `now_ms`: the lease starts
    /// again (a broadcast does not renew it, SPEC §18).
    pub fn heard(&mut self, now_ms: u32) {
        self.heard_ms = now_ms as u16;
    }

    /// Between two scans: whether the next scan runs. A hold whose lease ran out ends here
    /// (status bit 5); a step is counted as it is given. The clock is read only while held.
    pub fn next<B: Board>(&mut self, b: &mut B) -> Next {
        if !self.held() {
            return Next::Free;
        }
        if (b.now_ms() as u16).wrapping_sub(self.heard_ms) >= LEASE_MS as u16 {
            self.bits = LAPSED;
            self.steps = 0;
            return Next::Free;
        }
        if self.steps == 0 {
            return Next::Held;
        }
        self.steps -= 1;
        Next::Step
    }
}
