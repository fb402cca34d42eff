//! One rung drawn: its wires, contacts, IEC function boxes and coils, each a `<g>` with
//! `data-rung`, `data-signal` and `data-lines` (the page lights them from the lines' values)
//! and `data-power-lines` (the lines whose values, ANDed, are its power).

use super::*;

/// The drawing of one rung.
pub(super) struct Draw<'a> {
    pub(super) out: String,
    pub(super) top: i32,
    pub(super) rung: usize,
    pub(super) ladder: &'a Ladder,
}

impl Draw<'_> {
    pub(super) fn px(&self, col: i32) -> i32 {
        LEFT + col * W
    }
    pub(super) fn py(&self, row: i32) -> i32 {
        self.top + row * H + H / 2
    }

    /// A wire from (`c0`, `row`) to (`c1`, `row`) carrying `power`.
    pub(super) fn wire(&mut self, c0: i32, c1: i32, row: i32, power: &[u8]) {
        if c1 > c0 {
            let (x0, x1, y) = (self.px(c0), self.px(c1), self.py(row));
            self.line(x0, y, x1, y, power);
        }
    }

    /// A wire down column `col` from row `r0` to `r1` carrying `power`.
    pub(super) fn vwire(&mut self, col: i32, r0: i32, r1: i32, power: &[u8]) {
        let (x, y0, y1) = (self.px(col), self.py(r0), self.py(r1));
        self.line(x, y0, x, y1, power);
    }

    pub(super) fn line(&mut self, x0: i32, y0: i32, x1: i32, y1: i32, power: &[u8]) {
        let _ = write!(
            self.out,
            "<line class=\"wire\" data-rung=\"{}\" data-power-lines=\"{}\" \
             x1=\"{x0}\" y1=\"{y0}\" x2=\"{x1}\" y2=\"{y1}\"/>",
            self.rung,
            join(power)
        );
    }

    /// A group's opening tag; `power`: the lines of its power.
    pub(super) fn open(&mut self, class: &str, signal: &str, lines: &[u8], power: &[u8]) {
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
    pub(super) fn contact(&mut self, c: &Contact, col: i32, row: i32, power: &[u8]) -> Vec<u8> {
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
    pub(super) fn function(
        &mut self,
        name: &str,
        line: u8,
        col: i32,
        r0: i32,
        r1: i32,
        power: &[u8],
    ) {
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

    /// Networks `a` above `b` from column `col`, row `row`, both fed `power`, each wired out
    /// to the wider one's right edge: that edge's column offset and `a`'s height in rows.
    fn branches(&mut self, a: &Net, b: &Net, col: i32, row: i32, power: &[u8]) -> (i32, i32) {
        let (wa, ha) = net_size(a);
        let (wb, _) = net_size(b);
        let w = wa.max(wb);
        let pa = self.net(a, col, row, power);
        self.wire(col + wa, col + w, row, &pa);
        let pb = self.net(b, col, row + ha, power);
        self.wire(col + wb, col + w, row + ha, &pb);
        (w, ha)
    }

    /// A network whose power arrives at (`col`, `row`) as `power`: the power leaving it.
    pub(super) fn net(&mut self, n: &Net, col: i32, row: i32, power: &[u8]) -> Vec<u8> {
        match n {
            Net::Contact(c) => self.contact(c, col, row, power),
            Net::Series(a, b, line) => {
                let (wa, _) = net_size(a);
                let pa = self.net(a, col, row, power);
                self.net(b, col + wa, row, &pa);
                then(power, *line)
            }
            Net::Parallel(a, b, line) => {
                let out = then(power, *line);
                let (w, ha) = self.branches(a, b, col, row, power);
                self.vwire(col, row, row + ha, power);
                self.vwire(col + w, row, row + ha, &out);
                out
            }
            Net::Xor(a, b, line) => {
                let out = then(power, *line);
                let (w, ha) = self.branches(a, b, col, row, power);
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
    pub(super) fn flow(
        &mut self,
        f: &Flow,
        col: i32,
        row: i32,
        cc: i32,
        power: &[u8],
    ) -> (i32, i32) {
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
    pub(super) fn step(
        &mut self,
        s: &Step,
        col: i32,
        row: i32,
        cc: i32,
        power: &[u8],
    ) -> (i32, i32, Vec<u8>) {
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
    pub(super) fn steps(
        &mut self,
        steps: &[Step],
        col: i32,
        row: i32,
        cc: i32,
        power: &[u8],
    ) -> (i32, i32) {
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
    pub(super) fn coil(&mut self, c: &Coil, col: i32, row: i32, power: &[u8]) {
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
