//! uTile's resources chosen for an imported program before its rungs are written: which
//! SR/RS are uTile's own flip-flops, the edge memories (an input's own edge bit, one reader
//! each), the memory bits counted against the 16 free, the timers (by unit), the counters,
//! and each block's Q known before its call (a read above it, or fed back, is the last
//! call's).

use super::*;

/// Which SR/RS are uTile's own flip-flops: those whose Q1 nothing reads below them (in
/// the scan after their call), so Q changing at END is what every read sees, as IEC's
/// last call's Q. uTile has 16; past them, memory bits.
pub(super) fn own_flip_flops(prog: &IecProgram) -> Vec<bool> {
    let mut own = 0;
    (0..prog.stmts.len())
        .map(|i| {
            let yes = own < 16
                && matches!(prog.stmts[i], Stmt::FlipFlop { .. })
                && !prog.stmts[i + 1..].iter().any(|s| {
                    let mut reads = false;
                    stmt_exprs(s, &mut |e| reads |= reads_out(e, i));
                    reads
                });
            own += usize::from(yes);
            yes
        })
        .collect()
}

/// Each edge's variable and direction, and the rungs (groups) that read it.
pub(super) fn edge_readers(
    prog: &IecProgram,
    pieces: &[pieces::Piece],
    block_group: &[Option<usize>],
) -> (Vec<(u8, bool)>, Vec<Vec<usize>>) {
    let mut edge_vars = std::vec![(0u8, true); prog.edges];
    let mut edge_groups: Vec<Vec<usize>> = std::vec![Vec::new(); prog.edges];
    let mut read_in = |e: &Expr, g: usize| {
        edges_of(e, &mut |id, var, rising| {
            if let (Some(v), Some(groups)) = (edge_vars.get_mut(id), edge_groups.get_mut(id)) {
                *v = (var, rising);
                if !groups.contains(&g) {
                    groups.push(g);
                }
            }
        })
    };
    for p in pieces {
        read_in(&p.expr, p.group);
    }
    for (i, s) in prog.stmts.iter().enumerate() {
        if let Some(g) = block_group[i] {
            stmt_exprs(s, &mut |e| read_in(e, g));
        }
    }
    (edge_vars, edge_groups)
}

/// Whether a push opcode reads one of the inputs A0..A5.
pub(super) fn is_input(var: u8) -> bool {
    (PUSH_A..PUSH_A + 6).contains(&var)
}

impl Lowering {
    /// An edge on an input is uTile's own edge bit (ALn, ATn): one reader each.
    pub(super) fn input_edges(
        &mut self,
        prog: &IecProgram,
        edge_vars: &[(u8, bool)],
        edge_groups: &[Vec<usize>],
    ) {
        let mut seen: Vec<(u8, bool)> = Vec::new();
        for (id, &(var, rising)) in edge_vars.iter().enumerate() {
            if !is_input(var) {
                continue;
            }
            let name = crate::ladder::import::signal_name(var);
            let pn = if rising { "P" } else { "N" };
            if seen.contains(&(var, rising)) || edge_groups[id].len() > 1 {
                let what = prog.edge_what.get(id).cloned().unwrap_or_default();
                self.problems.push(format!(
                    "{what}: a {pn} contact on {name}: uTile keeps one {} edge bit per input, read by one contact in one rung — use one {pn} contact driving a memory coil, and read that coil",
                    if rising { "rising" } else { "falling" }
                ));
            }
            seen.push((var, rising));
        }
    }

    /// The memory bits the patterns need, against those free after the variables.
    pub(super) fn bits_needed(
        &self,
        prog: &IecProgram,
        own: &[bool],
        edge_vars: &[(u8, bool)],
    ) -> Result<(), Vec<String>> {
        let memory_edges = edge_vars.iter().filter(|(v, _)| !is_input(*v)).count();
        let per_stmt: usize = prog
            .stmts
            .iter()
            .map(|s| match s {
                Stmt::Timer {
                    kind: TimerKind::Tp,
                    ..
                }
                | Stmt::FlipFlop { .. } => 1,
                Stmt::Trig { .. } => 2,
                _ => 0,
            })
            .sum();
        let primed = prog.stmts.iter().any(|s| {
            matches!(
                s,
                Stmt::Timer {
                    kind: TimerKind::Ton,
                    ..
                } | Stmt::FirstScan { .. }
            )
        });
        let needed =
            memory_edges + per_stmt - own.iter().filter(|&&o| o).count() + usize::from(primed);
        let free = 16 - prog.used_uv.count_ones() as usize;
        if needed > free {
            return Err(std::vec![format!(
                "program: edges, pulses, R_TRIG/F_TRIG, flip-flops and initial values need {needed} memory bits and {free} of uTile's 16 (U0..U7, V0..V7) are free after the variables — drop some, or map variables to outputs with --map"
            )]);
        }
        Ok(())
    }

    /// Timers: the PTs only one unit holds first, then the finest unit free.
    pub(super) fn choose_timers(&mut self, prog: &IecProgram) {
        let mut order: Vec<(usize, u32)> = prog
            .stmts
            .iter()
            .enumerate()
            .filter_map(|(i, s)| match s {
                Stmt::Timer { pt_ms, .. } => Some((i, *pt_ms)),
                _ => None,
            })
            .collect();
        order.sort_by_key(|&(_, pt)| UNIT_GROUPS.iter().filter(|g| holds(g.0, pt)).count());
        for (i, pt) in order {
            match timer_for(pt, self.timers_used) {
                Ok((m, preset)) => {
                    self.timers_used |= 1 << m;
                    self.presets[usize::from(m)] = preset;
                    self.timer_of[i] = Some(m);
                }
                Err(why) => {
                    if let Stmt::Timer { what, .. } = &prog.stmts[i] {
                        self.problems.push(format!("{what}: {why}"));
                    }
                }
            }
        }
    }

    /// Each block's Q before its call (a read above it, or fed back, is the last call's):
    /// counters in statement order, timers, flip-flops, R_TRIG/F_TRIG's memory bits.
    pub(super) fn choose_units(&mut self, prog: &IecProgram, own: &[bool]) {
        for (i, s) in prog.stmts.iter().enumerate() {
            match s {
                Stmt::Counter { pv, what, .. } => {
                    let Some(m) = (0..COUNTERS as u8).find(|m| self.counters_used & (1 << m) == 0)
                    else {
                        self.problems.push(format!(
                            "{what}: more counters than uTile's {COUNTERS} (C0..C7) — use fewer CTU blocks"
                        ));
                        continue;
                    };
                    self.counters_used |= 1 << m;
                    self.counter_presets[usize::from(m)] = *pv;
                    self.made[i] = Made::Q(PUSH_CQ + m, false);
                }
                Stmt::Timer { kind, .. } => {
                    if let Some(m) = self.timer_of[i] {
                        self.made[i] = Made::Q(PUSH_TQ + m, *kind == TimerKind::Ton);
                    }
                }
                Stmt::FlipFlop { .. } if own[i] => {
                    // uTile has 16 flip-flops: one each.
                    let m = (0..16u8)
                        .find(|m| self.flip_flops_used & (1 << m) == 0)
                        .unwrap_or(15);
                    self.flip_flops_used |= 1 << m;
                    self.made[i] = Made::Q(PUSH_Q + m, false);
                }
                Stmt::FlipFlop { .. } => {
                    let mem = self.bit();
                    self.made[i] = Made::Q(mem, false);
                }
                Stmt::Trig { .. } => {
                    // M holds CLK, E the Q: E read above the call is the last call's Q.
                    let (mem, out) = (self.bit(), self.bit());
                    self.trig_mem[i] = mem;
                    self.made[i] = Made::Q(out, false);
                }
                _ => {}
            }
        }
    }

    /// The memory bit set at the end of the first scan (`SET .P`): TON's and the initial
    /// values' first-scan test.
    pub(super) fn primed_bit(&mut self) -> u8 {
        match self.primed {
            Some(p) => p,
            None => {
                let p = self.bit();
                self.primed = Some(p);
                p
            }
        }
    }
}
