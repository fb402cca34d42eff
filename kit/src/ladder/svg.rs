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

/// The drawing of one rung.
struct Draw<'a> {
    out: String,
    top: i32,
    rung: usize,
    ladder: &'a Ladder,
}

impl Draw<'_> {
    fn px(&self, col: i32) -> i32 {
        LEFT + col * W
    }
    fn py(&self, row: i32) -> i32 {
        self.top + row * H + H / 2
    }

    /// A wire from (`c0`, `row`) to (`c1`, `row`) carrying `power`.
    fn wire(&mut self, c0: i32, c1: i32, row: i32, power: &[u8]) {
        if c1 > c0 {
            let (x0, x1, y) = (self.px(c0), self.px(c1), self.py(row));
            self.line(x0, y, x1, y, power);
        }
    }

    /// A wire down column `col` from row `r0` to `r1` carrying `power`.
    fn vwire(&mut self, col: i32, r0: i32, r1: i32, power: &[u8]) {
        let (x, y0, y1) = (self.px(col), self.py(r0), self.py(r1));
        self.line(x, y0, x, y1, power);
    }

    fn line(&mut self, x0: i32, y0: i32, x1: i32, y1: i32, power: &[u8]) {
        let _ = write!(
            self.out,
            "<line class=\"wire\" data-rung=\"{}\" data-power-lines=\"{}\" \
             x1=\"{x0}\" y1=\"{y0}\" x2=\"{x1}\" y2=\"{y1}\"/>",
            self.rung,
            join(power)
        );
    }

    /// A group's opening tag; `power`: the lines of its power.
    fn open(&mut self, class: &str, signal: &str, lines: &[u8], power: &[u8]) {
        let _ = write!(
            self.out,
            "<g class=\"{class}\" data-rung=\"{}\" data-signal=\"{}\" data-lines=\"{}\" \
             data-power-lines=\"{}\">",
            self.rung,
            esc(signal),
            join(lines),
            join(power)
        );
    }

    /// A contact whose left side has `power`: the power on its right side.
    fn contact(&mut self, c: &Contact, col: i32, row: i32, power: &[u8]) -> Vec<u8> {
        let (x, y) = (self.px(col), self.py(row));
        let cx = x + W / 2;
        let out = then(power, c.lines.last().copied().unwrap_or(0));
        self.open("contact", &c.signal(), &c.lines, &out);
        match c.kind() {
            ContactKind::Short => {
                let _ = write!(
                    self.out,
                    "<line x1=\"{x}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\"/>",
                    x + W
                );
            }
            kind => {
                let _ = write!(
                    self.out,
                    "<line x1=\"{x}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\"/>\
                     <line x1=\"{}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\"/>\
                     <line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>\
                     <line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
                    cx - 8,
                    cx + 8,
                    x + W,
                    cx - 8,
                    y - 12,
                    cx - 8,
                    y + 12,
                    cx + 8,
                    y - 12,
                    cx + 8,
                    y + 12
                );
                let mark = match (kind, c.negated) {
                    (ContactKind::Rising, _) => "P",
                    (ContactKind::Falling, _) => "N",
                    (ContactKind::Open, _) => "0",
                    _ => "",
                };
                if c.negated {
                    let _ = write!(
                        self.out,
                        "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
                        cx - 6,
                        y + 10,
                        cx + 6,
                        y - 10
                    );
                }
                if !mark.is_empty() {
                    let _ = write!(
                        self.out,
                        "<text class=\"label\" x=\"{cx}\" y=\"{}\">{mark}</text>",
                        y + 4
                    );
                }
            }
        }
        let _ = write!(
            self.out,
            "<text class=\"label\" x=\"{cx}\" y=\"{}\">{}</text></g>",
            y - 16,
            esc(&c.signal())
        );
        out
    }

    /// A function box (NOT, OR, XOR) in column `col` from row `r0` to `r1`, passing `power`
    /// on.
    fn function(&mut self, name: &str, line: u8, col: i32, r0: i32, r1: i32, power: &[u8]) {
        let (x, y0, y1) = (self.px(col), self.py(r0), self.py(r1));
        self.open("function", name, &[line], power);
        let _ = write!(
            self.out,
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/>\
             <text class=\"label\" x=\"{}\" y=\"{}\">{name}</text>\
             <line x1=\"{}\" y1=\"{y0}\" x2=\"{}\" y2=\"{y0}\"/>\
             <line x1=\"{x}\" y1=\"{y0}\" x2=\"{}\" y2=\"{y0}\"/>\
             <line x1=\"{x}\" y1=\"{y1}\" x2=\"{}\" y2=\"{y1}\"/></g>",
            x + 14,
            y0 - 14,
            W - 28,
            y1 - y0 + 28,
            x + W / 2,
            y0 + 4,
            x + W - 14,
            x + W,
            x + 14,
            x + 14
        );
    }

    /// A network whose power arrives at (`col`, `row`) as `power`: the power leaving it.
    fn net(&mut self, n: &Net, col: i32, row: i32, power: &[u8]) -> Vec<u8> {
        match n {
            Net::Contact(c) => self.contact(c, col, row, power),
            Net::Series(a, b, line) => {
                let (wa, _) = net_size(a);
                let pa = self.net(a, col, row, power);
                self.net(b, col + wa, row, &pa);
                then(power, *line)
            }
            Net::Parallel(a, b, line) => {
                let (wa, ha) = net_size(a);
                let (wb, _) = net_size(b);
                let w = wa.max(wb);
                let out = then(power, *line);
                let pa = self.net(a, col, row, power);
                self.wire(col + wa, col + w, row, &pa);
                let pb = self.net(b, col, row + ha, power);
                self.wire(col + wb, col + w, row + ha, &pb);
                self.vwire(col, row, row + ha, power);
                self.vwire(col + w, row, row + ha, &out);
                out
            }
            Net::Xor(a, b, line) => {
                let (wa, ha) = net_size(a);
                let (wb, _) = net_size(b);
                let w = wa.max(wb);
                let out = then(power, *line);
                let pa = self.net(a, col, row, power);
                self.wire(col + wa, col + w, row, &pa);
                let pb = self.net(b, col, row + ha, power);
                self.wire(col + wb, col + w, row + ha, &pb);
                self.function("XOR", *line, col + w, row, row + ha, &out);
                out
            }
            Net::Not(a, line) => {
                let (wa, _) = net_size(a);
                let out = then(power, *line);
                self.net(a, col, row, power);
                self.function("NOT", *line, col + wa, row, row, &out);
                out
            }
        }
    }

    /// A flow whose power arrives at (`col`, `row`) as `power`, its coils in column `cc`:
    /// the column its coils need at least, and its rows.
    fn flow(&mut self, f: &Flow, col: i32, row: i32, cc: i32, power: &[u8]) -> (i32, i32) {
        match f {
            Flow::Coil(c) => {
                self.wire(col, cc, row, power);
                self.coil(c, cc, row, power);
                (col, 1)
            }
            Flow::Then(Step::Tap(tap, _), rest) => {
                let (n1, h1) = self.flow(rest, col, row, cc, power);
                let (n2, h2) = self.flow(tap, col, row + h1, cc, power);
                self.vwire(col, row, row + h1, power);
                (n1.max(n2), h1 + h2)
            }
            Flow::Then(s, rest) => {
                let (w, h, out) = self.step(s, col, row, cc, power);
                let (n, hr) = self.flow(rest, col + w, row, cc, &out);
                (n, h.max(hr))
            }
            Flow::Split(a, b, _) => {
                let (n1, h1) = self.flow(a, col, row, cc, power);
                let (n2, h2) = self.flow(b, col, row + h1, cc, power);
                self.vwire(col, row, row + h1, power);
                (n1.max(n2), h1 + h2)
            }
        }
    }

    /// One step on the power `power` at (`col`, `row`): its columns and rows, and the power
    /// leaving it.
    fn step(&mut self, s: &Step, col: i32, row: i32, cc: i32, power: &[u8]) -> (i32, i32, Vec<u8>) {
        match s {
            Step::And(n, line) => {
                self.net(n, col, row, power);
                let (w, h) = net_size(n);
                (w, h, vec![*line])
            }
            Step::Not(line) => {
                self.function("NOT", *line, col, row, row, &[*line]);
                (1, 1, vec![*line])
            }
            Step::Or(n, line) | Step::Xor(n, line) => {
                let name = if matches!(s, Step::Or(..)) {
                    "OR"
                } else {
                    "XOR"
                };
                let (wn, hn) = net_size(n);
                self.wire(col, col + wn, row, power);
                // The operand's contacts are powered from the left rail.
                self.out.push_str("<g class=\"operand\">");
                self.wire(0, col, row + 1, &[]);
                self.net(n, col, row + 1, &[]);
                self.out.push_str("</g>");
                self.function(name, *line, col + wn, row, row + 1, &[*line]);
                (wn + 1, 1 + hn, vec![*line])
            }
            Step::Tap(f, _) => {
                let (_, h) = self.flow(f, col, row + 1, cc, power);
                self.vwire(col, row, row + 1, power);
                (0, 1 + h, power.to_vec())
            }
            Step::Merge(steps, op, _, join) => {
                let name = match *op {
                    utile_core::opcodes::AND => "AND",
                    utile_core::opcodes::OR => "OR",
                    _ => "XOR",
                };
                let (wb, hb) = self.steps(steps, col, row + 1, cc, power);
                self.wire(col, col + wb, row, power);
                self.vwire(col, row, row + 1, power);
                self.function(name, *join, col + wb, row, row + 1, &[*join]);
                (wb + 1, 1 + hb, vec![*join])
            }
        }
    }

    /// A chain of steps from (`col`, `row`) on the power `power`, its taps drawn below it:
    /// columns and rows.
    fn steps(&mut self, steps: &[Step], col: i32, row: i32, cc: i32, power: &[u8]) -> (i32, i32) {
        let (mut c, mut h) = (col, 1);
        let mut p = power.to_vec();
        let mut taps = Vec::new();
        for s in steps {
            if let Step::Tap(f, _) = s {
                taps.push((f, c, p.clone()));
                continue;
            }
            let (w, hs, out) = self.step(s, c, row, cc, &p);
            c += w;
            h = h.max(hs);
            p = out;
        }
        if c == col {
            self.wire(col, col + 1, row, &p);
            c += 1;
        }
        for (f, tc, tp) in taps {
            let (_, hf) = self.flow(f, tc, row + h, cc, &tp);
            self.vwire(tc, row, row + h, &tp);
            h += hf;
        }
        (c - col, h)
    }

    /// A coil whose input has `power`.
    fn coil(&mut self, c: &Coil, col: i32, row: i32, power: &[u8]) {
        let (x, y) = (self.px(col), self.py(row));
        let cx = x + W / 2;
        self.open("coil", &c.signal(), &c.lines, power);
        let m = usize::from(c.unit());
        let (mark, note) = match c.kind() {
            CoilKind::Plain => ("", String::new()),
            CoilKind::Set => ("S", format!("Q{m:X}")),
            CoilKind::Reset => ("R", format!("Q{m:X}")),
            CoilKind::TimerTrigger => {
                let p = u32::from(self.ladder.presets[m & 15]) * unit_ms(m as u8);
                ("TOF", format!("TQ{m:X} {}", seconds(p)))
            }
            CoilKind::TimerReset => ("R", format!("TQ{m:X}")),
            CoilKind::CountUp => (
                "CTU",
                format!("CQ{m} PV={}", self.ladder.counter_presets[m & 7]),
            ),
            CoilKind::CounterReset => ("R", format!("CQ{m}")),
        };
        let _ = write!(
            self.out,
            "<line x1=\"{x}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\"/>\
             <path d=\"M{} {} a14 14 0 0 0 0 24 M{} {} a14 14 0 0 1 0 24\"/>\
             <line x1=\"{}\" y1=\"{y}\" x2=\"{}\" y2=\"{y}\"/>",
            cx - 12,
            cx - 6,
            y - 12,
            cx + 6,
            y - 12,
            cx + 12,
            x + W
        );
        if c.negated {
            let _ = write!(
                self.out,
                "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/>",
                cx - 5,
                y + 9,
                cx + 5,
                y - 9
            );
        }
        let _ = write!(
            self.out,
            "<text class=\"label\" x=\"{cx}\" y=\"{}\" font-size=\"9\">{mark}</text>\
             <text class=\"label\" x=\"{cx}\" y=\"{}\">{}</text>\
             <text class=\"label\" x=\"{cx}\" y=\"{}\" font-size=\"10\">{}</text></g>",
            y + 3,
            y - 16,
            esc(&c.signal()),
            y + 24,
            esc(&note)
        );
    }
}

/// A time in ms as the manual writes it (`0.5 s`, `5 s`, `2 min`).
fn seconds(ms: u32) -> String {
    if ms.is_multiple_of(60_000) && ms >= 60_000 {
        format!("{} min", ms / 60_000)
    } else if ms.is_multiple_of(1000) {
        format!("{} s", ms / 1000)
    } else {
        format!("{}.{} s", ms / 1000, (ms % 1000) / 100)
    }
}
