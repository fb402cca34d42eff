//! The wires followed from a sink back to the left rail: each element's value computed once
//! (memoised by localId and output, so branches that meet again cost no more than their
//! elements), a wire back to a function block being evaluated read as that block's output
//! of the previous scan (IEC's feedback, lowered as the read by name is), any other loop
//! refused; nesting and expressions bounded ([`MAX_NODES`]) so nothing recurses without
//! limit.

use super::*;

impl<'a, 'i> Reader<'a, 'i> {
    /// The power on a connectionPointIn: the OR of its connections (none: FALSE).
    pub(super) fn input_of(&mut self, n: Node<'a, 'i>, point: Option<Node<'a, 'i>>) -> Res<Expr> {
        let Some(point) = point else {
            return Ok(Expr::Const(false));
        };
        let mut power: Option<Expr> = None;
        let mut failed = false;
        for c in point
            .children()
            .filter(|c| c.tag_name().name() == "connection")
        {
            let Some(id) = c
                .attribute("refLocalId")
                .and_then(|s| s.trim().parse().ok())
            else {
                self.fail(
                    n,
                    DETAIL,
                    "a connection without refLocalId — save the file again from the editor",
                );
                failed = true;
                continue;
            };
            match self.output_of(n, id, c.attribute("formalParameter")) {
                Ok(e) => {
                    power = Some(match power {
                        None => e,
                        Some(p) => Expr::or(p, e),
                    });
                }
                Err(Said) => failed = true,
            }
            if power
                .as_ref()
                .is_some_and(|p| p.nodes_within(MAX_NODES).is_none())
            {
                return Err(self.too_big(n));
            }
        }
        if failed {
            return Err(Said);
        }
        Ok(power.unwrap_or(Expr::Const(false)))
    }

    pub(super) fn too_big(&mut self, n: Node) -> Said {
        self.fail(
            n,
            DETAIL,
            &format!(
                "its power is an expression of more than {MAX_NODES} contacts and functions; uTile reads up to {MAX_NODES} (its 256 lines hold fewer) — split the rung"
            ),
        )
    }

    /// The value leaving element `id` (at its output `formal`), for the element `from`.
    pub(super) fn output_of(&mut self, from: Node, id: u64, formal: Option<&str>) -> Res<Expr> {
        let Some(&n) = self.elems.get(&id) else {
            return Err(self.fail(
                from,
                DETAIL,
                &format!("wired to localId {id}, which is not in the body — redraw the wire"),
            ));
        };
        let key = (id, formal.unwrap_or("").to_ascii_uppercase());
        if self.in_block.contains(&id) {
            return self.fed_back_from(n, id, &key.1);
        }
        if self.visiting.contains(&id) {
            return Err(self.fail(
                n,
                DETAIL,
                "a loop of wires comes back to it through contacts, coils and functions only — IEC starts a loop at a function block's output (read from the previous scan); break it with a coil and a contact",
            ));
        }
        let at = self.stmts.len();
        let r = match self.memo.get(&key).cloned() {
            Some(r) => self.remembered(n, &key, r),
            None => self.follow(n, id, formal, &key),
        };
        // A wire read for a second statement is shared (IEC: one value).
        if let Ok(e) = &r {
            match self.wires.get(&key) {
                None => {
                    self.wires.insert(key, at);
                }
                Some(&first) if first != at && self.shared_wires.insert(key) => {
                    self.shared.push(e.clone());
                }
                Some(_) => {}
            }
        }
        r
    }

    /// A wire to a function block being evaluated: its Q of the previous scan.
    fn fed_back_from(&mut self, n: Node, id: u64, formal: &str) -> Res<Expr> {
        let ty = n.attribute("typeName").unwrap_or("").to_ascii_uppercase();
        let q = if matches!(ty.as_str(), "SR" | "RS") {
            "Q1"
        } else {
            "Q"
        };
        if FB_TYPES.contains(&ty.as_str()) && (formal.is_empty() || formal == q) {
            self.fed_back.push(id);
            return Ok(Expr::Named(id));
        }
        Err(self.fail(
            n,
            DETAIL,
            &format!("a loop of wires comes back to it through {} — only a function block's Q may be fed back; break the loop with a coil and a contact", if formal.is_empty() { "its output" } else { formal }),
        ))
    }

    /// A wire already followed: its value, unless it reads a block fed back and that
    /// block has run since (IEC gives the wire one value, from before the block).
    fn remembered(&mut self, n: Node, key: &(u64, String), r: Res<Expr>) -> Res<Expr> {
        let fed = self.memo_fed.get(key).cloned().unwrap_or_default();
        if let Some(&b) = fed.iter().find(|b| self.emitted.contains_key(b)) {
            let block = self.elems.get(&b).map_or_else(String::new, |&bn| what(bn));
            return Err(self.fail(
                n,
                DETAIL,
                &format!("read below {block}, on the loop that feeds its output back — IEC gives this wire one value a scan, from before the block; drive a coil from it above the block and read that coil below"),
            ));
        }
        self.fed_back.extend(fed);
        r
    }

    /// Follow element `n` once: its value remembered, with the blocks it reads fed back.
    fn follow(
        &mut self,
        n: Node<'a, 'i>,
        id: u64,
        formal: Option<&str>,
        key: &(u64, String),
    ) -> Res<Expr> {
        if self.visiting.len() >= MAX_NODES {
            // Said once: every wire past the limit has the same problem.
            if std::mem::replace(&mut self.said_deep, true) {
                return Err(Said);
            }
            return Err(self.fail(
                n,
                DETAIL,
                &format!("wires nested more than {MAX_NODES} elements deep; uTile reads up to {MAX_NODES} — split the rung"),
            ));
        }
        let mark = self.fed_back.len();
        self.reached.insert(id);
        self.visiting.push(id);
        let r = self.output_inner(n, formal);
        self.visiting.pop();
        let mut fed: Vec<u64> = self.fed_back.drain(mark..).collect();
        fed.sort_unstable();
        fed.dedup();
        self.fed_back.extend(&fed);
        if !fed.is_empty() {
            self.memo_fed.insert(key.clone(), fed);
        }
        self.memo.insert(key.clone(), r.clone());
        r
    }

    fn output_inner(&mut self, n: Node<'a, 'i>, formal: Option<&str>) -> Res<Expr> {
        match n.tag_name().name() {
            "leftPowerRail" => Ok(Expr::Const(true)),
            "contact" => self.contact(n),
            "coil" | "connector" => self.input_of(n, child(n, "connectionPointIn")),
            "inVariable" | "inOutVariable" => {
                let name = child_text(n, "expression").unwrap_or_default();
                let value = match name.to_ascii_uppercase().as_str() {
                    "TRUE" | "1" => Expr::Const(true),
                    "FALSE" | "0" => Expr::Const(false),
                    _ if name.contains('.') => self.instance_output(n, &name)?,
                    _ => Expr::Var(self.var(n, &name)?),
                };
                Ok(if n.attribute("negated") == Some("true") {
                    Expr::negate(value)
                } else {
                    value
                })
            }
            "continuation" => {
                let name = n.attribute("name").unwrap_or("").to_ascii_uppercase();
                let Some(&c) = self.connectors.get(&name) else {
                    return Err(self.fail(
                        n,
                        DETAIL,
                        &format!("no connector named {name} — draw the connector or the wire"),
                    ));
                };
                self.output_of(n, local_id(c).unwrap_or(0), None)
            }
            "block" => self.block_output(n, formal.unwrap_or("")),
            _ => Err(self.fail(n, DETAIL, "nothing flows out of it — redraw the wire")),
        }
    }

    /// A contact: the power arriving AND its variable (negated, or an edge of it).
    fn contact(&mut self, n: Node<'a, 'i>) -> Res<Expr> {
        let power = self.input_of(n, child(n, "connectionPointIn"));
        let name = child_text(n, "variable").unwrap_or_default();
        let negated = n.attribute("negated") == Some("true");
        let edge = n.attribute("edge").unwrap_or("none");
        let value = if name.contains('.') && self.signals.get(&name).is_none() {
            let value = self.instance_output(n, &name);
            if edge != "none" && value.is_ok() {
                return Err(self.fail(n, DETAIL, &format!(
                    "an edge contact on {name} — uTile's edges are on bits; drive a coil from {name} and put the edge contact on that coil's variable"
                )));
            }
            value
        } else {
            let push = self.var(n, &name);
            push.and_then(|push| self.edge_of(n, push, edge))
        };
        let (power, value) = (power?, value?);
        let value = if negated { Expr::negate(value) } else { value };
        Ok(Expr::and(power, value))
    }

    /// A variable read through a contact's `edge`.
    fn edge_of(&mut self, n: Node, push: u8, edge: &str) -> Res<Expr> {
        match edge {
            "none" => Ok(Expr::Var(push)),
            e @ ("rising" | "falling") => {
                let id = local_id(n).unwrap_or(0);
                let next = self.edges.len();
                let eid = *self.edges.entry(id).or_insert(next);
                if eid == next {
                    self.edge_what.push(what(n));
                }
                Ok(Expr::Edge {
                    var: push,
                    rising: e == "rising",
                    id: eid,
                })
            }
            other => Err(self.fail(
                n,
                DETAIL,
                &format!("edge=\"{other}\" is not rising or falling"),
            )),
        }
    }
}
