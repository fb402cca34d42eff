//! The outputs written: coils, flip-flops (set/reset coils on `Qm`, or memory coils and
//! END's update as a last rung), timers (a TOF block; `.TRm` through `TOFm_R`), counters (a
//! CTU at its rungs, or memory coils and the CTU called last, where uTile counts) — each
//! function block with EN from the left rail and ENO, as OpenPLC Editor draws a block on a
//! rung.

use std::vec::Vec;

use utile_core::engine::unit_ms;
use utile_core::opcodes::{POP_CR, POP_CU, POP_R};

use super::super::iec::time_text;
use super::super::model::{Coil, CoilKind};
use super::graph::{Kind, Src};
use super::plan::Form;
use super::rungs::{rail, Writer};
use super::{coil_push, counter_count_name, counter_reset_name, reset_name, variable, STARTED};

impl Writer<'_> {
    /// A function block instance: EN from the left rail, then `inputs`; ENO, then `outputs`.
    fn block(
        &mut self,
        ty: &'static str,
        instance: String,
        inputs: Vec<(&'static str, Vec<Src>)>,
        outputs: &[&'static str],
    ) -> u32 {
        let mut ins = std::vec![("EN", rail())];
        ins.extend(inputs);
        let mut outs = std::vec!["ENO"];
        outs.extend_from_slice(outputs);
        let kind = Kind::Block {
            ty,
            instance: Some(instance),
        };
        self.g.add(kind, ins, outs)
    }

    /// An output of the listing, `power` arriving.
    pub(super) fn output(&mut self, k: &Coil, power: Vec<Src>) {
        let m = k.unit();
        match k.kind() {
            CoilKind::TimerTrigger => self.timer(k, power),
            CoilKind::TimerReset => {
                // `.TRm`: TQm off at once until the next trigger: TOFm_R set.
                let power = self.maybe_not(k.negated, power);
                self.coil(&reset_name(m), false, "set", power);
            }
            CoilKind::CountUp | CoilKind::CounterReset => self.counter(k, power),
            CoilKind::Set | CoilKind::Reset => self.flip_flop(k, power),
            CoilKind::Plain => {
                let push = coil_push(k.op).unwrap_or(0);
                let (var, _) = variable(push).unwrap_or_default();
                self.coil(&var, k.negated, "none", power);
            }
        }
    }

    /// `.TKm`: a TOF block `TOFm` with its PT; a trigger clears `TOFm_R` (on the same wire,
    /// so it is read once).
    fn timer(&mut self, k: &Coil, power: Vec<Src>) {
        let m = k.unit();
        let preset = u32::from(self.ladder.presets[usize::from(m)]);
        let pt = self.constant(&time_text(preset * unit_ms(m)));
        let power = self.maybe_not(k.negated, power);
        let inputs = std::vec![("IN", power.clone()), ("PT", pt)];
        self.block("TOF", format!("TOF{m}"), inputs, &["Q", "ET"]);
        if self.plan.resets[usize::from(m)] {
            self.coil(&reset_name(m), false, "reset", power);
        }
    }

    /// `.Sm` / `.Rm`: a set or reset coil on `Qm` in place, or a coil on `Qm_S` / `Qm_R`
    /// that END's last rung reads.
    fn flip_flop(&mut self, k: &Coil, power: Vec<Src>) {
        let m = k.unit();
        let set = k.op < POP_R;
        if self.plan.flip_flops[usize::from(m)] == Form::AtEnd {
            let var = format!("Q{m}_{}", if set { "S" } else { "R" });
            self.coil(&var, k.negated, "none", power);
        } else {
            let power = self.maybe_not(k.negated, power);
            self.coil(
                &format!("Q{m}"),
                false,
                if set { "set" } else { "reset" },
                power,
            );
        }
    }

    /// `.CUm` / `.CRm`: in place, the CTU written at the counter's later rung; at END, a
    /// coil on `CTUm_CU` / `CTUm_R`.
    fn counter(&mut self, k: &Coil, power: Vec<Src>) {
        let m = (k.op - POP_CU) % 8;
        let reset = k.op >= POP_CR;
        if self.plan.counters[usize::from(m)] == Form::AtEnd {
            let var = if reset {
                self.reset_written[usize::from(m)] = true;
                counter_reset_name(m)
            } else {
                counter_count_name(m)
            };
            self.coil(&var, k.negated, "none", power);
            return;
        }
        let power = self.maybe_not(k.negated, power);
        self.pending[usize::from(m)][usize::from(reset)] = Some(power);
        let has_reset = self.parts.coils.iter().any(|o| o.op == POP_CR + m);
        let [cu, r] = &self.pending[usize::from(m)];
        if cu.is_some() && (r.is_some() || !has_reset) {
            self.ctu(m);
        }
    }

    /// The CTU block of counter m from its pending CU and R, PV its preset.
    fn ctu(&mut self, m: u8) {
        let [cu, r] = std::mem::take(&mut self.pending[usize::from(m)]);
        let preset = self.ladder.counter_presets[usize::from(m)];
        let pv = self.constant(&preset.to_string());
        // uTile counts no edge at the first END (its count inputs start as on); IEC's CTU
        // would count a CU already on: R in the first scan (NOT STARTED) takes that edge.
        let mut r = r.unwrap_or_default();
        r.extend(self.below(|w| w.contact(STARTED, true, "none", rail())));
        let inputs = std::vec![("CU", cu.unwrap_or_default()), ("R", r), ("PV", pv)];
        self.block("CTU", format!("CTU{m}"), inputs, &["Q", "CV"]);
    }

    /// What uTile does at END, as last rungs: each flip-flop at END, `Qm := (Qm_S OR Qm)
    /// AND NOT Qm_R`; then each counter at END, its CTU on `CTUm_CU` and `CTUm_R`; then
    /// `STARTED := TRUE`.
    pub(super) fn end_rungs(&mut self) {
        let pops = |w: &Self, op: u8| w.parts.coils.iter().any(|k| k.op == op);
        for m in 0..16u8 {
            if self.plan.flip_flops[usize::from(m)] != Form::AtEnd {
                continue;
            }
            self.g.start_rung();
            let mut p = self.contact(&format!("Q{m}"), false, "none", rail());
            if pops(self, utile_core::opcodes::POP_S + m) {
                let s = self.below(|w| w.contact(&format!("Q{m}_S"), false, "none", rail()));
                p.extend(s);
            }
            if pops(self, POP_R + m) {
                p = self.contact(&format!("Q{m}_R"), true, "none", p);
            }
            self.coil(&format!("Q{m}"), false, "none", p);
        }
        for m in 0..8u8 {
            if self.plan.counters[usize::from(m)] != Form::AtEnd {
                continue;
            }
            self.g.start_rung();
            let cu = self.contact(&counter_count_name(m), false, "none", rail());
            self.pending[usize::from(m)][0] = Some(cu);
            if pops(self, POP_CR + m) {
                let r = self.below(|w| w.contact(&counter_reset_name(m), false, "none", rail()));
                self.pending[usize::from(m)][1] = Some(r);
            }
            self.ctu(m);
        }
        if self.plan.started {
            self.g.start_rung();
            self.coil(STARTED, false, "none", rail());
        }
    }
}
