//! The rungs' order: where the export computes each flip-flop and counter so that an IEC
//! runtime, running the rungs top to bottom, computes each value where uTile does.
//!
//! uTile updates its flip-flops and counts its counters at END. IEC's set/reset coils act
//! at once and a CTU counts at its call; where the two agree the export writes them in
//! place, otherwise it keeps the inputs in memory bits and does END's work in last rungs.

use std::vec::Vec;

use utile_core::opcodes::{
    POP_CR, POP_CU, POP_R, POP_S, POP_U, POP_V, PUSH_CQ, PUSH_Q, PUSH_U, PUSH_V,
};

use super::super::model::{CoilKind, ContactKind};

use super::{coil_line, first_line, Parts};

/// Where a flip-flop's or a counter's value is computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) enum Form {
    /// Not driven by the program.
    #[default]
    Unused,
    /// In place: set/reset coils on `Qm`; a CTU at its rungs.
    Direct,
    /// At END: the inputs in memory bits (`Qm_S`, `Qm_R`; `CTUm_CU`, `CTUm_R`), the update
    /// in a last rung.
    AtEnd,
}

/// The form of every flip-flop and counter, and the memory bits IEC needs for them.
pub(super) struct Plan {
    /// Flip-flops 0..F.
    pub(super) flip_flops: [Form; 16],
    /// Counters 0..7.
    pub(super) counters: [Form; 8],
    /// The timers reset by `.TRm` (a memory bit `TOFm_R` each).
    pub(super) resets: [bool; 16],
    /// Whether the program reads an edge or counts: a memory bit `STARTED`, set by a last
    /// rung, keeps the first scan from seeing an edge or a count (IEC's edge memories
    /// start FALSE, uTile reads its inputs at RUN).
    pub(super) started: bool,
    /// The memory bits the flip-flops, counters, resets, `STARTED` and the program's own U/V
    /// take.
    pub(super) bits: usize,
}

impl Plan {
    /// The plan for a program's contacts and coils.
    pub(super) fn new(parts: &Parts) -> Plan {
        let mut plan = Plan {
            flip_flops: [Form::Unused; 16],
            counters: [Form::Unused; 8],
            resets: [false; 16],
            started: false,
            bits: 0,
        };
        for m in 0..16u8 {
            plan.flip_flop(parts, m);
        }
        for m in 0..8u8 {
            plan.counter(parts, m);
        }
        for k in &parts.coils {
            if k.kind() == CoilKind::TimerReset {
                plan.resets[usize::from(k.unit())] = true;
            }
        }
        let edges = parts
            .contacts
            .iter()
            .any(|c| matches!(c.kind(), ContactKind::Rising | ContactKind::Falling));
        plan.started = edges || plan.counters.iter().any(|&f| f != Form::Unused);
        plan.bits += plan.resets.iter().filter(|&&r| r).count()
            + usize::from(plan.started)
            + own_bits(parts);
        plan
    }

    /// Flip-flop m: set/reset coils on `Qm` where IEC's agree with uTile's END update (one
    /// `.Sm` above one `.Rm`, `Qm.` read only above them), else at END.
    fn flip_flop(&mut self, parts: &Parts, m: u8) {
        let (sets, resets) = (pop_lines(parts, POP_S + m), pop_lines(parts, POP_R + m));
        let mut reads = parts
            .contacts
            .iter()
            .filter(|c| c.op == PUSH_Q + m)
            .map(|c| first_line(c));
        if sets.is_empty() && resets.is_empty() {
            // Read and never set: a BOOL that stays FALSE.
            self.bits += usize::from(reads.next().is_some());
            return;
        }
        let top = sets.iter().chain(&resets).copied().min().unwrap_or(0);
        let direct = sets.len() <= 1
            && resets.len() <= 1
            && sets.iter().zip(&resets).all(|(s, r)| s < r)
            && reads.all(|l| l < top);
        self.flip_flops[usize::from(m)] = if direct { Form::Direct } else { Form::AtEnd };
        self.bits += 1 + if direct {
            0
        } else {
            usize::from(!sets.is_empty()) + usize::from(!resets.is_empty())
        };
    }

    /// Counter m: a CTU at its rungs where it counts where uTile does (one `.CUm`, at most
    /// one `.CRm` right after or before it with nothing written or `CQm.` read between,
    /// `CQm.` read only above them), else at END.
    fn counter(&mut self, parts: &Parts, m: u8) {
        let (counts, resets) = (pop_lines(parts, POP_CU + m), pop_lines(parts, POP_CR + m));
        if counts.is_empty() {
            return;
        }
        let (lo, hi) = counts
            .iter()
            .chain(&resets)
            .fold((u8::MAX, 0), |(lo, hi), &l| (lo.min(l), hi.max(l)));
        let reads: Vec<u8> = parts
            .contacts
            .iter()
            .filter(|c| c.op == PUSH_CQ + m)
            .map(|c| first_line(c))
            .collect();
        let written_between = parts
            .coils
            .iter()
            .map(|k| coil_line(k))
            .any(|l| lo < l && l < hi);
        let direct = counts.len() == 1
            && resets.len() <= 1
            && !written_between
            && reads.iter().all(|&l| l < lo);
        self.counters[usize::from(m)] = if direct { Form::Direct } else { Form::AtEnd };
        if !direct {
            self.bits += 1 + usize::from(!resets.is_empty());
        }
    }
}

/// The lines of the coils that pop `op`.
fn pop_lines(parts: &Parts, op: u8) -> Vec<u8> {
    parts
        .coils
        .iter()
        .filter(|k| k.op == op)
        .map(|k| coil_line(k))
        .collect()
}

/// The program's own U and V bits (contacts and coils on them).
fn own_bits(parts: &Parts) -> usize {
    let mut own: Vec<u8> = parts
        .contacts
        .iter()
        .map(|c| c.op)
        .filter(|&p| (PUSH_U..PUSH_V + 8).contains(&p))
        .map(|p| p - PUSH_U)
        .chain(
            parts
                .coils
                .iter()
                .map(|k| k.op)
                .filter(|&p| (POP_U..POP_V + 8).contains(&p))
                .map(|p| p - POP_U),
        )
        .collect();
    own.sort_unstable();
    own.dedup();
    own.len()
}
