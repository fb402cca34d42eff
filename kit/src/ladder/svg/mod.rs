//! The ladder model drawn as SVG: one `<g class="rung" data-rung="N">` per rung or block,
//! each element a `<g>` with `data-rung`, `data-signal` (the listing's name) and
//! `data-lines` (its listing lines), so a page can light it from the lines' values.
//!
//! Every element and every wire also carries `data-power-lines`: the lines whose values,
//! ANDed, are the power it shows (docs/LADDER.md, "Power flow"); empty is the left rail.
//! A network's power from the rail is the value of its last line (the core's engine
//! computes it); deeper in a rung it is the power arriving ANDed with that value.

use std::fmt::Write;
use std::string::String;
use std::vec::Vec;

use utile_core::engine::unit_ms;

use super::model::{op_word, Coil, CoilKind, Contact, ContactKind, Flow, Item, Ladder, Net, Step};

/// A cell's width and height in px.
const W: i32 = 84;
const H: i32 = 58;
/// The left margin (rung numbers) and the row of text for a block's line.
const LEFT: i32 = 44;
const TEXT_ROW: i32 = 16;

mod draw;
use draw::Draw;

/// The SVG picture of a ladder, titled `title`.
pub fn svg(ladder: &Ladder, title: &str) -> String {
    let mut body = String::new();
    let mut y = 40;
    let mut width = 4;
    for (rung_no, item) in ladder.items.iter().enumerate() {
        match item {
            Item::Rung(r) => {
                let (wn, hn) = net_size(&r.net);
                let mut d = Draw {
                    out: String::new(),
                    top: y,
                    rung: rung_no,
                    ladder,
                };
                // A dry run finds the coils' column, then the drawing.
                let power = [net_last(&r.net)];
                let (coil_col, hf) = d.flow(&r.flow, wn, 0, 0, &power);
                d.out.clear();
                let cols = coil_col + 1;
                let rows = hn.max(hf);
                width = width.max(cols);
                d.net(&r.net, 0, 0, &[]);
                d.flow(&r.flow, wn, 0, coil_col, &power);
                let lines = rung_lines(r);
                let _ = write!(
                    body,
                    "<g class=\"rung\" data-rung=\"{rung_no}\" data-lines=\"{}\">\
                     <text class=\"no\" x=\"4\" y=\"{}\">{rung_no}</text>\
                     <line class=\"rail\" x1=\"{LEFT}\" y1=\"{y}\" x2=\"{LEFT}\" y2=\"{}\"/>\
                     <line class=\"rail\" x1=\"{rx}\" y1=\"{y}\" x2=\"{rx}\" y2=\"{}\"/>{}</g>",
                    join(&lines),
                    y + H / 2 + 4,
                    y + rows * H,
                    y + rows * H,
                    d.out,
                    rx = LEFT + cols * W,
                );
                body.push('\n');
                y += rows * H + 12;
            }
            Item::Block(b) => {
                let h = b.lines.len() as i32 * TEXT_ROW + 10;
                let lines: Vec<u8> = b.lines.iter().map(|l| l.0).collect();
                let _ = write!(
                    body,
                    "<g class=\"rung block\" data-rung=\"{rung_no}\" data-lines=\"{}\">\
                     <text class=\"no\" x=\"4\" y=\"{}\">{rung_no}</text>\
                     <rect x=\"{LEFT}\" y=\"{y}\" width=\"{}\" height=\"{h}\"/>",
                    join(&lines),
                    y + 16,
                    W * 2,
                );
                for (k, &(line, op)) in b.lines.iter().enumerate() {
                    let _ = write!(
                        body,
                        "<text class=\"line\" data-lines=\"{line}\" data-power-lines=\"{line}\" data-rung=\"{rung_no}\" data-signal=\"{}\" x=\"{}\" y=\"{}\">{line:03} {}</text>",
                        esc(op_word(op).trim_matches('.')),
                        LEFT + 8,
                        y + 18 + k as i32 * TEXT_ROW,
                        esc(&op_word(op)),
                    );
                }
                body.push_str("</g>\n");
                y += h + 12;
            }
        }
    }
    let total_w = LEFT + width * W + 20;
    format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" class=\"ladder\" width=\"{total_w}\" height=\"{}\" \
         viewBox=\"0 0 {total_w} {}\" font-family=\"monospace\" font-size=\"12\">\n\
         <style>line,path,rect,circle{{stroke:#222;stroke-width:2;fill:none}}\
         .rail{{stroke-width:4}} text{{fill:#222;stroke:none}} .no{{fill:#888}}\
         .block rect{{fill:#f4f4f4;stroke:#888}} .label{{text-anchor:middle}}</style>\n\
         <text x=\"4\" y=\"20\" font-size=\"14\">{}</text>\n{body}</svg>\n",
        y + 10,
        y + 10,
        esc(title),
    )
}

/// Every listing line of a rung, in order.
fn rung_lines(r: &super::model::Rung) -> Vec<u8> {
    let mut v = Vec::new();
    net_lines(&r.net, &mut v);
    flow_lines(&r.flow, &mut v);
    v.sort_unstable();
    v
}

fn net_lines(n: &Net, v: &mut Vec<u8>) {
    match n {
        Net::Contact(c) => v.extend(&c.lines),
        Net::Series(a, b, l) | Net::Parallel(a, b, l) | Net::Xor(a, b, l) => {
            net_lines(a, v);
            net_lines(b, v);
            v.push(*l);
        }
        Net::Not(a, l) => {
            net_lines(a, v);
            v.push(*l);
        }
    }
}

fn flow_lines(f: &Flow, v: &mut Vec<u8>) {
    match f {
        Flow::Coil(c) => v.extend(&c.lines),
        Flow::Then(s, rest) => {
            step_lines(s, v);
            flow_lines(rest, v);
        }
        Flow::Split(a, b, l) => {
            v.push(*l);
            flow_lines(a, v);
            flow_lines(b, v);
        }
    }
}

fn step_lines(s: &Step, v: &mut Vec<u8>) {
    match s {
        Step::And(n, l) | Step::Or(n, l) | Step::Xor(n, l) => {
            net_lines(n, v);
            v.push(*l);
        }
        Step::Not(l) => v.push(*l),
        Step::Tap(f, l) => {
            v.push(*l);
            flow_lines(f, v);
        }
        Step::Merge(steps, _, dup, join) => {
            v.push(*dup);
            for s in steps {
                step_lines(s, v);
            }
            v.push(*join);
        }
    }
}

/// The line that leaves a network's value on the stack (its last).
fn net_last(n: &Net) -> u8 {
    match n {
        Net::Contact(c) => c.lines.last().copied().unwrap_or(0),
        Net::Series(_, _, l) | Net::Parallel(_, _, l) | Net::Xor(_, _, l) | Net::Not(_, l) => *l,
    }
}

/// The power `power` ANDed with the value of `line`.
fn then(power: &[u8], line: u8) -> Vec<u8> {
    let mut p = power.to_vec();
    p.push(line);
    p
}

/// A network's size in cells (columns, rows).
fn net_size(n: &Net) -> (i32, i32) {
    match n {
        Net::Contact(_) => (1, 1),
        Net::Series(a, b, _) => {
            let (wa, ha) = net_size(a);
            let (wb, hb) = net_size(b);
            (wa + wb, ha.max(hb))
        }
        Net::Parallel(a, b, _) => {
            let (wa, ha) = net_size(a);
            let (wb, hb) = net_size(b);
            (wa.max(wb), ha + hb)
        }
        Net::Xor(a, b, _) => {
            let (wa, ha) = net_size(a);
            let (wb, hb) = net_size(b);
            (wa.max(wb) + 1, ha + hb)
        }
        Net::Not(a, _) => {
            let (wa, ha) = net_size(a);
            (wa + 1, ha)
        }
    }
}

fn join(lines: &[u8]) -> String {
    let v: Vec<String> = lines.iter().map(|l| l.to_string()).collect();
    v.join(",")
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}
