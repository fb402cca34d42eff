//! Listing → ladder: a program's lines read as rungs where they have a ladder form.
//!
//! A rung is the postfix form of a network followed by its outputs:
//!
//! ```text
//! rung  := net flow
//! net   := push [!] | net net AND | net net OR | net net XOR | net !
//! flow  := [!] pop | DUP flow flow | step flow
//! step  := ! | net AND | net OR | net XOR | DUP flow | DUP step* (AND | OR | XOR)
//! ```
//!
//! Whatever does not read so (SWAP, 2DUP, byte moves, a stack left non-empty, more than the
//! stack's 8 bits deep) becomes an instruction block of its lines, as do END, KEY and NOP.
//! Compiling the model ([`super::to_listing`]) gives the same bytes back.

use std::vec::Vec;

use utile_core::engine::{Program, LINES};
use utile_core::opcodes::{self, AND, BLANK, DUP, END, KEY, NOP, NOT, OR, XOR};

use super::model::{is_pop, is_push, Block, Coil, Contact, Flow, Item, Ladder, Net, Rung, Step};

/// The stack's depth: a rung deeper than this would lose bits.
const STACK_BITS: usize = 8;

/// The ladder form of a program.
pub fn from_program(prog: &Program) -> Ladder {
    let uf = &prog.uf;
    let last = uf[LINES - 1];
    let (fill, end) = if last == NOP || last == BLANK {
        let n = uf.iter().rev().take_while(|&&op| op == last).count();
        (last, LINES - n)
    } else {
        (BLANK, LINES)
    };
    let ops = &uf[..end];
    let mut items: Vec<Item> = Vec::new();
    let mut i = 0;
    while i < ops.len() {
        if let Some((rung, next)) = rung_at(ops, i) {
            items.push(Item::Rung(rung));
            i = next;
            continue;
        }
        let start = i;
        let mut block = Block { lines: Vec::new() };
        if matches!(ops[i], END | KEY) {
            block.lines.push((i as u8, ops[i]));
            i += 1;
        } else {
            // The block runs until its own pushes are used up and a rung (or END/KEY) starts.
            let mut depth: i32 = 0;
            while i < ops.len() {
                if i > start
                    && (matches!(ops[i], END | KEY) || depth <= 0 && rung_at(ops, i).is_some())
                {
                    break;
                }
                depth += stack_effect(ops[i]);
                block.lines.push((i as u8, ops[i]));
                i += 1;
            }
        }
        items.push(Item::Block(block));
    }
    Ladder {
        items,
        fill,
        presets: prog.presets,
        counter_presets: prog.counter_presets,
        set_points: prog.set_points,
    }
}

/// How many bits an opcode leaves on the stack more than it found (byte moves count 0).
fn stack_effect(op: u8) -> i32 {
    match op {
        op if is_push(op) => 1,
        op if is_pop(op) => -1,
        AND | OR | XOR | opcodes::DROP => -1,
        DUP => 1,
        opcodes::DUP2 => 2,
        _ => 0,
    }
}

/// The rung that starts at `i`, and the line after it.
fn rung_at(ops: &[u8], i: usize) -> Option<(Rung, usize)> {
    let (net, at, end) = expr(ops, i, false)?;
    if end != End::Done {
        return None;
    }
    let mut r = Reader {
        ops,
        at,
        depth: 1,
        max: 1,
    };
    r.max = depth_of(&net);
    let flow = r.flow()?;
    (r.max <= STACK_BITS).then_some((Rung { net, flow }, r.at))
}

/// How deep the stack gets while a network is pushed.
fn depth_of(net: &Net) -> usize {
    match net {
        Net::Contact(_) => 1,
        Net::Not(a, _) => depth_of(a),
        Net::Series(a, b, _) | Net::Parallel(a, b, _) | Net::Xor(a, b, _) => {
            depth_of(a).max(1 + depth_of(b))
        }
    }
}

/// How a network's text ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum End {
    /// One network is on the stack and the next line uses it (a DUP or a pop).
    Done,
    /// A binary function (`AND`, `OR`, `XOR`, on the line after the network) takes the
    /// network and the power beneath it.
    Binary(u8),
}

/// A network from line `i` on: the network, the line after it, how it ended. With `under`,
/// a binary function may take the power beneath (a flow's step).
fn expr(ops: &[u8], mut i: usize, under: bool) -> Option<(Net, usize, End)> {
    let mut stack: Vec<Net> = Vec::new();
    while let Some(&op) = ops.get(i) {
        let line = i as u8;
        if is_push(op) {
            let mut c = Contact {
                op,
                negated: false,
                lines: std::vec![line],
            };
            if ops.get(i + 1) == Some(&NOT) {
                c.negated = true;
                c.lines.push(line + 1);
                i += 1;
            }
            stack.push(Net::Contact(c));
        } else if op == NOT {
            let top = stack.pop()?;
            stack.push(Net::Not(Box::new(top), line));
        } else if matches!(op, AND | OR | XOR) {
            if stack.len() == 1 && under {
                let net = stack.pop()?;
                return Some((net, i + 1, End::Binary(op)));
            }
            let b = Box::new(stack.pop()?);
            let a = Box::new(stack.pop()?);
            stack.push(match op {
                AND => Net::Series(a, b, line),
                OR => Net::Parallel(a, b, line),
                _ => Net::Xor(a, b, line),
            });
        } else if stack.len() == 1 && !under && (op == DUP || is_pop(op)) {
            return Some((stack.pop()?, i, End::Done));
        } else {
            return None;
        }
        i += 1;
    }
    None
}

/// Reads a flow, tracking the stack's depth.
struct Reader<'a> {
    ops: &'a [u8],
    at: usize,
    depth: usize,
    max: usize,
}

impl Reader<'_> {
    fn flow(&mut self) -> Option<Flow> {
        let op = *self.ops.get(self.at)?;
        let line = self.at as u8;
        if is_pop(op) {
            self.at += 1;
            self.depth -= 1;
            return Some(Flow::Coil(Coil {
                op,
                negated: false,
                lines: std::vec![line],
            }));
        }
        if op == NOT {
            self.at += 1;
            if let Some(&pop) = self.ops.get(self.at).filter(|&&p| is_pop(p)) {
                self.at += 1;
                self.depth -= 1;
                return Some(Flow::Coil(Coil {
                    op: pop,
                    negated: true,
                    lines: std::vec![line, line + 1],
                }));
            }
            let rest = self.flow()?;
            return Some(Flow::Then(Step::Not(line), Box::new(rest)));
        }
        if op == DUP {
            let save = (self.at, self.depth, self.max);
            self.at += 1;
            self.depth += 1;
            self.max = self.max.max(self.depth);
            if let Some(first) = self.flow() {
                if let Some(second) = self.flow() {
                    return Some(Flow::Split(Box::new(first), Box::new(second), line));
                }
            }
            (self.at, self.depth, self.max) = save;
        }
        let step = self.step()?;
        let rest = self.flow()?;
        Some(Flow::Then(step, Box::new(rest)))
    }

    /// A step on the power at the top (no coil): a function, a tap or a merge.
    fn step(&mut self) -> Option<Step> {
        let op = *self.ops.get(self.at)?;
        let line = self.at as u8;
        if op == NOT {
            self.at += 1;
            return Some(Step::Not(line));
        }
        if op == DUP {
            let save = (self.at, self.depth, self.max);
            self.at += 1;
            self.depth += 1;
            self.max = self.max.max(self.depth);
            if let Some(f) = self.flow() {
                return Some(Step::Tap(Box::new(f), line));
            }
            // The copy's steps, until a function joins it with the power beneath.
            (self.at, self.depth, self.max) = save;
            self.at += 1;
            self.depth += 1;
            self.max = self.max.max(self.depth);
            let mut steps = Vec::new();
            loop {
                let next = *self.ops.get(self.at)?;
                if matches!(next, AND | OR | XOR) {
                    let join = self.at as u8;
                    self.at += 1;
                    self.depth -= 1;
                    return Some(Step::Merge(steps, next, line, join));
                }
                steps.push(self.step()?);
            }
        }
        let (net, next, end) = expr(self.ops, self.at, true)?;
        let End::Binary(f) = end else { return None };
        self.max = self.max.max(self.depth + depth_of(&net));
        self.at = next;
        let fline = (next - 1) as u8;
        Some(match f {
            AND => Step::And(net, fline),
            OR => Step::Or(net, fline),
            _ => Step::Xor(net, fline),
        })
    }
}
