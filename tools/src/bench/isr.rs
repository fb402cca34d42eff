//! Interrupt tracking for the scan benchmark: from the PC before and after each step, when
//! a handler is entered (the PC lands in the vector table) and when its `reti` ends it.

use super::chip::{RETI, VECTORS_END};

/// Tracks interrupt handlers from the PC before and after each step.
#[derive(Default)]
pub struct IsrTrack {
    vector: Option<u32>,
    start: u64,
    /// Cycles per vector number.
    pub cycles: [u64; 26],
    /// Entries per vector number.
    pub entries: [u64; 26],
}

impl IsrTrack {
    /// Accounts one step; returns the cycles of a handler that just ended.
    pub fn step(&mut self, pc0: u32, op: u16, pc1: u32, c1: u64) -> u64 {
        let mut ended = 0;
        if let Some(v) = self.vector {
            if op == RETI {
                ended = c1 - self.start;
                self.cycles[v as usize] += ended;
                self.vector = None;
            }
        }
        let entered = pc1 < VECTORS_END && (pc0 >= VECTORS_END || op == RETI) && pc1 != 0;
        if self.vector.is_none() && entered {
            let v = pc1 / 4;
            self.vector = Some(v);
            self.entries[v as usize] += 1;
            self.start = c1;
        }
        ended
    }
    /// True while a handler runs.
    pub fn in_isr(&self) -> bool {
        self.vector.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isr_tracking_counts_from_vector_entry_to_reti() {
        let mut t = IsrTrack::default();
        // Main code at 0x200 is interrupted: PC lands on vector 14 (0x38) at cycle 100.
        assert_eq!(t.step(0x200, 0x0000, 0x38, 100), 0);
        assert!(t.in_isr());
        assert_eq!(t.step(0x38, 0x940C, 0x400, 103), 0);
        // reti at cycle 150 ends it.
        assert_eq!(t.step(0x420, RETI, 0x202, 150), 50);
        assert!(!t.in_isr());
        assert_eq!((t.entries[14], t.cycles[14]), (1, 50));
    }
}
