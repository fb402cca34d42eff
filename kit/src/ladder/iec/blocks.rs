//! The function blocks lowered to rungs of their own: TON and TP on uTile's timers,
//! R_TRIG/F_TRIG on memory bits, SR/RS whose Q1 is read below them on a memory bit
//! (docs/LADDER.md's patterns), a TRUE initial value set at the first scan. TOF, CTU and the
//! SR/RS that are uTile's own flip-flops are pieces of rungs (pieces.rs).

use super::*;

impl Lowering {
    pub(super) fn block(&mut self, i: usize, s: &Stmt) {
        match s {
            // Coils, TOF, counters and uTile's own flip-flops are pieces (pieces.rs).
            Stmt::Coil { .. } | Stmt::Counter { .. } | Stmt::CounterReset { .. } => {}
            Stmt::Timer { kind, input, .. } => self.timer(i, *kind, input),
            Stmt::Trig { clk, rising } => self.trig(i, clk, *rising),
            Stmt::FlipFlop {
                set,
                reset,
                set_dominant,
            } => self.flip_flop(i, set, reset, *set_dominant),
            Stmt::FirstScan { pop, push } => {
                // TRUE at the first scan until written: set while the first-scan bit is
                // still clear.
                let p = self.primed_bit();
                let flow = Flow::Then(
                    Step::Or(contact(*push, false), 0),
                    Box::new(Flow::Coil(coil(*pop, false))),
                );
                self.rung(contact(p, true), flow);
            }
        }
    }

    /// TON: `IN ! P. ! OR .TKm`; TP: `IN DUP M. ! AND TQm. ! AND .TKm .M` (a TOF is a
    /// piece).
    fn timer(&mut self, i: usize, kind: TimerKind, input: &Expr) {
        let Some(m) = self.timer_of[i] else { return };
        let tk = Flow::Coil(coil(POP_TK + m, false));
        let net = self.net(input);
        match kind {
            TimerKind::Tof => {}
            TimerKind::Ton => {
                let p = self.primed_bit();
                let flow = Flow::Then(
                    Step::Not(0),
                    Box::new(Flow::Then(Step::Or(contact(p, true), 0), Box::new(tk))),
                );
                self.rung(net, flow);
            }
            TimerKind::Tp => {
                let mem = self.bit();
                let trigger = Flow::Then(
                    Step::And(contact(mem, true), 0),
                    Box::new(Flow::Then(
                        Step::And(contact(PUSH_TQ + m, true), 0),
                        Box::new(tk),
                    )),
                );
                let flow = split(std::vec![
                    trigger,
                    Flow::Coil(coil(mem - PUSH_U + POP_U, false))
                ]);
                self.rung(net, flow);
            }
        }
    }

    /// R_TRIG: `CLK DUP M. ! AND .E .M`, F_TRIG the same on `CLK !`. Its bits were chosen
    /// before the call (resources.rs): E read above it is the last call's Q.
    fn trig(&mut self, i: usize, clk: &Expr, rising: bool) {
        let Some(&Made::Q(out, _)) = self.made.get(i) else {
            return;
        };
        let mem = self.trig_mem[i];
        let edge = split(std::vec![
            Flow::Then(
                Step::And(contact(mem, true), 0),
                Box::new(Flow::Coil(coil(out - PUSH_U + POP_U, false))),
            ),
            Flow::Coil(coil(mem - PUSH_U + POP_U, false)),
        ]);
        let flow = if rising {
            edge
        } else {
            Flow::Then(Step::Not(0), Box::new(edge))
        };
        let net = self.net(clk);
        self.rung(net, flow);
    }

    /// An SR or RS whose Q1 is read below it, on a memory bit: SR `S M. R ! AND OR .M`, RS
    /// `R ! S M. OR AND .M` (uTile's own flip-flops are pieces).
    fn flip_flop(&mut self, i: usize, set: &Expr, reset: &Expr, set_dominant: bool) {
        let Some(&Made::Q(q, _)) = self.made.get(i) else {
            return;
        };
        if (PUSH_Q..PUSH_Q + 16).contains(&q) {
            return; // uTile's own flip-flop: pieces (pieces.rs).
        }
        let mem = q;
        let (s, r) = (self.net(set), self.net(reset));
        let not_r = match r {
            Net::Contact(mut c) if !c.negated => {
                c.negated = true;
                Net::Contact(c)
            }
            r => Net::Not(Box::new(r), 0),
        };
        let held = contact(mem, false);
        let net = if set_dominant {
            Net::Parallel(
                Box::new(s),
                Box::new(Net::Series(Box::new(held), Box::new(not_r), 0)),
                0,
            )
        } else {
            Net::Series(
                Box::new(not_r),
                Box::new(Net::Parallel(Box::new(s), Box::new(held), 0)),
                0,
            )
        };
        self.rung(net, Flow::Coil(coil(mem - PUSH_U + POP_U, false)));
    }
}
