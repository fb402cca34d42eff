//! PLCopen's function blocks and functions read: their inputs (EN, PT, PV from a constant or
//! a variable's initial value), TON/TOF/TP/CTU/R_TRIG/F_TRIG/SR/RS as statements, AND/OR/
//! XOR/NOT as expressions, a block's Q read by its instance name (`TOF0.Q`), and time
//! literals.

use super::*;

/// A time literal (`T#500ms`, `TIME#1m30s`, `t#1.5s`) in ms.
pub fn parse_time(text: &str) -> Option<u32> {
    let t = text.trim().replace('_', "").to_ascii_lowercase();
    let body = t
        .strip_prefix("time#")
        .or_else(|| t.strip_prefix("t#"))
        .unwrap_or(&t);
    if body.is_empty() {
        return None;
    }
    if body.bytes().all(|b| b.is_ascii_digit()) {
        return body.parse().ok();
    }
    let mut ms = 0f64;
    let mut rest = body;
    while !rest.is_empty() {
        let end = rest
            .find(|c: char| !c.is_ascii_digit() && c != '.')
            .unwrap_or(rest.len());
        let num: f64 = rest[..end].parse().ok()?;
        rest = &rest[end..];
        let (scale, len) = if rest.starts_with("ms") {
            (1.0, 2)
        } else if rest.starts_with('d') {
            (86_400_000.0, 1)
        } else if rest.starts_with('h') {
            (3_600_000.0, 1)
        } else if rest.starts_with('m') {
            (60_000.0, 1)
        } else if rest.starts_with('s') {
            (1000.0, 1)
        } else {
            return None;
        };
        ms += num * scale;
        rest = &rest[len..];
    }
    (ms <= f64::from(u32::MAX)).then_some(ms.round() as u32)
}

impl<'a, 'i> Reader<'a, 'i> {
    /// `TOF0.Q`: the Q of the timer or counter block of that instance name, read by name
    /// (above its call: the last call's Q).
    pub(super) fn instance_output(&mut self, n: Node, name: &str) -> Res<Expr> {
        if let Some(op) = self.signals.get(name) {
            return Ok(Expr::Var(op)); // a member given a signal with --map
        }
        let (inst, out) = name.trim().split_once('.').unwrap_or((name, ""));
        let block = self
            .instances
            .iter()
            .find(|(i, _, _)| i.eq_ignore_ascii_case(inst.trim()))
            .map(|(_, id, ty)| (*id, ty.clone()));
        let Some((id, ty)) = block else {
            let key = name.trim().to_ascii_uppercase();
            if !self.said_vars.insert(key) {
                return Err(Said);
            }
            let why = self.member(name).unwrap_or_default();
            return Err(self.fail(n, DETAIL, &why));
        };
        let q = match ty.as_str() {
            "TON" | "TOF" | "TP" | "CTU" => "Q",
            "SR" | "RS" => "Q1",
            // A block uTile cannot import: its own reason says so.
            _ => return Err(Said),
        };
        if !out.trim().eq_ignore_ascii_case(q) {
            return Err(self.fail(n, DETAIL, &format!(
                "{name}: uTile reads only the Q of a TON, TOF, TP or CTU (Q1 of an SR or RS) by name — wire the block's output instead"
            )));
        }
        Ok(Expr::Named(id))
    }

    /// A block's input by formal name (`IN`, `PT`, `IN1`, …).
    pub(super) fn block_input(&self, n: Node<'a, 'i>, formal: &str) -> Option<Node<'a, 'i>> {
        child(n, "inputVariables")?.children().find(|v| {
            v.tag_name().name() == "variable"
                && v.attribute("formalParameter")
                    .is_some_and(|f| f.eq_ignore_ascii_case(formal))
        })
    }

    pub(super) fn bool_input(&mut self, n: Node<'a, 'i>, formal: &str) -> Res<Expr> {
        match self.block_input(n, formal) {
            Some(v) => {
                let e = self.input_of(n, child(v, "connectionPointIn"))?;
                Ok(if v.attribute("negated") == Some("true") {
                    Expr::negate(e)
                } else {
                    e
                })
            }
            None => Ok(Expr::Const(false)),
        }
    }

    /// A constant input (PT, PV): an inVariable's literal, or a variable's initial value.
    pub(super) fn constant_input(&mut self, n: Node, formal: &str) -> Res<String> {
        let src = self
            .block_input(n, formal)
            .and_then(|v| child(v, "connectionPointIn"))
            .and_then(|p| p.children().find(|c| c.tag_name().name() == "connection"))
            .and_then(|c| c.attribute("refLocalId"))
            .and_then(|s| s.trim().parse::<u64>().ok());
        let src = src.map(|id| (id, self.elems.get(&id).copied()));
        match src {
            Some((id, Some(src))) if src.tag_name().name() == "inVariable" => {
                self.reached.insert(id);
                let text = child_text(src, "expression").unwrap_or_default();
                Ok(self
                    .vars
                    .constants
                    .get(&text.to_ascii_uppercase())
                    .cloned()
                    .unwrap_or(text))
            }
            Some((id, None)) => Err(self.fail(
                n,
                DETAIL,
                &format!("wired to localId {id}, which is not in the body — redraw the wire"),
            )),
            _ => Err(self.fail(
                n,
                DETAIL,
                &format!("{formal} must come from a constant or a variable with an initial value"),
            )),
        }
    }

    pub(super) fn enable_ok(&mut self, n: Node<'a, 'i>) -> Res<()> {
        if self.block_input(n, "EN").is_some() {
            let en = self.bool_input(n, "EN")?;
            if en != Expr::Const(true) {
                return Err(self.fail(n, DETAIL, "EN from a condition — uTile runs every block every scan; wire the condition into the block's input instead and EN to the left rail"));
            }
        }
        Ok(())
    }

    pub(super) fn block_output(&mut self, n: Node<'a, 'i>, formal: &str) -> Res<Expr> {
        let ty = n.attribute("typeName").unwrap_or("").to_ascii_uppercase();
        if formal.eq_ignore_ascii_case("ENO") {
            self.enable_ok(n)?;
            return Ok(Expr::Const(true));
        }
        if FUNCTIONS.contains(&ty.as_str()) {
            return self.function(n, &ty);
        }
        if FB_TYPES.contains(&ty.as_str()) {
            let q = if matches!(ty.as_str(), "SR" | "RS") {
                "Q1"
            } else {
                "Q"
            };
            if !formal.is_empty() && !formal.eq_ignore_ascii_case(q) {
                return Err(self.fail(
                    n,
                    DETAIL,
                    &format!(
                    "its output {formal} has no uTile form (only {q} and ENO) — leave it unwired"
                ),
                ));
            }
            let s = self.block_stmt(n)?;
            return Ok(Expr::Out(s));
        }
        Err(self.unknown_block(n, &ty))
    }

    /// AND, OR, XOR, NOT of the block's inputs in their order.
    fn function(&mut self, n: Node<'a, 'i>, ty: &str) -> Res<Expr> {
        self.enable_ok(n)?;
        let names: Vec<String> = child(n, "inputVariables")
            .map(|iv| {
                iv.children()
                    .filter(|v| v.tag_name().name() == "variable")
                    .filter_map(|v| v.attribute("formalParameter").map(str::to_string))
                    .filter(|f| !f.eq_ignore_ascii_case("EN"))
                    .collect()
            })
            .unwrap_or_default();
        let mut ins: Vec<Expr> = Vec::new();
        let mut failed = false;
        for f in &names {
            match self.bool_input(n, f) {
                Ok(e) => ins.push(e),
                Err(Said) => failed = true,
            }
        }
        if failed {
            return Err(Said);
        }
        let mut it = ins.into_iter();
        let Some(first) = it.next() else {
            return Err(self.fail(n, DETAIL, "no inputs"));
        };
        let e = match ty {
            "NOT" => Expr::negate(first),
            "AND" => it.fold(first, |a, b| Expr::And(Box::new(a), Box::new(b))),
            "OR" => it.fold(first, Expr::or),
            _ => it.fold(first, |a, b| Expr::Xor(Box::new(a), Box::new(b))),
        };
        if e.nodes_within(MAX_NODES).is_none() {
            return Err(self.too_big(n));
        }
        Ok(e)
    }

    /// A block uTile has no form for, named as what it is (a user function block, with its
    /// body's language).
    pub(super) fn unknown_block(&mut self, n: Node, ty: &str) -> Said {
        let user = self.pous.get(ty).cloned();
        let is_user = user.is_some() && !FUNCTIONS.contains(&ty) && !ty.contains("_TO_");
        let why = match ty {
            "CTD" | "CTUD" => "uTile's counters count up only (CTU)".into(),
            "GT" | "GE" | "EQ" | "NE" | "LE" | "LT" => "uTile has no comparisons of numbers".into(),
            "ADD" | "SUB" | "MUL" | "DIV" | "MOD" | "MOVE" | "SEL" | "MUX" | "MAX" | "MIN"
            | "LIMIT" => "uTile has no arithmetic or moves of numbers".into(),
            t if t.contains("_TO_") => "uTile has no conversions of numbers".into(),
            _ => match user {
                Some((kind, lang)) => format!(
                    "a user {} of this project (its body {lang}); uTile imports only the program, with TON, TOF, TP, CTU, R_TRIG, F_TRIG, SR, RS, AND, OR, XOR, NOT (user function blocks cannot be imported) — draw its logic in the program",
                    if kind == "function" { "function" } else { "function block" }
                ),
                None => "uTile knows only TON, TOF, TP, CTU, R_TRIG, F_TRIG, SR, RS, AND, OR, XOR, NOT (user function blocks cannot be imported)".into(),
            },
        };
        let id = local_id(n).unwrap_or(0);
        self.failed_blocks.insert(id);
        let what_to_do = if is_user {
            ""
        } else {
            " — redraw it with those"
        };
        self.fail(n, CAUSE, &format!("{ty}: {why}{what_to_do}"))
    }

    /// The statement of a function block, emitted once (its inputs first).
    pub(super) fn block_stmt(&mut self, n: Node<'a, 'i>) -> Res<usize> {
        let id = local_id(n).unwrap_or(0);
        if let Some(&s) = self.emitted.get(&id) {
            return Ok(s);
        }
        if self.failed_blocks.contains(&id) {
            return Err(Said);
        }
        let mark = self.fed_back.len();
        self.in_block.insert(id);
        let stmt = self.block_inputs(n);
        self.in_block.remove(&id);
        // What the block's inputs read fed back is theirs: its Q is this scan's.
        self.fed_back.truncate(mark);
        let Ok(stmt) = stmt else {
            self.failed_blocks.insert(id);
            return Err(Said);
        };
        self.stmts.push(stmt);
        let s = self.stmts.len() - 1;
        self.emitted.insert(id, s);
        Ok(s)
    }

    /// A function block's statement from its inputs.
    fn block_inputs(&mut self, n: Node<'a, 'i>) -> Res<Stmt> {
        let ty = n.attribute("typeName").unwrap_or("").to_ascii_uppercase();
        if !FB_TYPES.contains(&ty.as_str()) {
            return Err(self.unknown_block(n, &ty));
        }
        self.enable_ok(n)?;
        let w = what(n);
        Ok(match ty.as_str() {
            "TON" | "TOF" | "TP" => {
                let input = self.bool_input(n, "IN");
                let pt_text = self.constant_input(n, "PT")?;
                let Some(pt_ms) = parse_time(&pt_text) else {
                    return Err(self.fail(
                        n,
                        DETAIL,
                        &format!("PT '{pt_text}' is not a time (T#500ms, T#2s, T#1m30s)"),
                    ));
                };
                let kind = match ty.as_str() {
                    "TON" => TimerKind::Ton,
                    "TOF" => TimerKind::Tof,
                    _ => TimerKind::Tp,
                };
                Stmt::Timer {
                    kind,
                    input: input?,
                    pt_ms,
                    what: w,
                }
            }
            "CTU" => {
                let (cu, reset) = (self.bool_input(n, "CU"), self.bool_input(n, "R"));
                let pv_text = self.constant_input(n, "PV")?;
                let Some(pv) = pv_text.trim().parse::<u16>().ok().filter(|&v| v >= 1) else {
                    return Err(self.fail(
                        n,
                        DETAIL,
                        &format!("PV '{pv_text}' is not a preset uTile's counters hold (1..65535)"),
                    ));
                };
                Stmt::Counter {
                    cu: cu?,
                    reset: reset?,
                    pv,
                    what: w,
                }
            }
            "R_TRIG" | "F_TRIG" => Stmt::Trig {
                clk: self.bool_input(n, "CLK")?,
                rising: ty == "R_TRIG",
            },
            _ => {
                let sr = ty == "SR";
                let set = self.bool_input(n, if sr { "S1" } else { "S" });
                let reset = self.bool_input(n, if sr { "R" } else { "R1" });
                Stmt::FlipFlop {
                    set: set?,
                    reset: reset?,
                    set_dominant: sr,
                }
            }
        })
    }
}
