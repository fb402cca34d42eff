//! A reference evaluator of LDmicro's rungs (`.ld`, 0.1 and 0.2), written from what LDmicro
//! does with each element (its manual and its file format), not from the importer: it runs
//! a file's rungs scan by scan and gives the outputs, so `ladder_ldmicro` can compare the
//! imported program on the core's engine with LDmicro.
//!
//! Its rules: each scan the master control relay is on; every rung runs top to bottom from
//! the relay's power (a rung that begins with a COMMENT runs nothing); a series passes the
//! power element by element, a parallel gives each branch the power it receives, runs them
//! in order and passes on their OR; a coil writes at once and passes its power on. Timers
//! run on time (LDmicro counts cycles of its CYCLE; the comparison allows a tick). Where
//! uTile documents a difference (docs/LADDER.md) the evaluator does as uTile: a CTU's count
//! input and an OSF's power start as on (no edge in the first scan).

use std::collections::HashMap;

use super::ladder::Sample;

/// A rung's node.
#[derive(Clone, Debug)]
enum El {
    Series(Vec<El>),
    Parallel(Vec<El>),
    /// A leaf: its number (for its edge memory) and its words.
    Leaf(usize, Vec<String>),
}

/// An LDmicro file's rungs, ready to run scan by scan.
#[derive(Clone, Debug)]
pub struct LdReference {
    rungs: Vec<El>,
    inputs: Vec<String>,
    outputs: Vec<String>,
    bits: HashMap<String, bool>,
    /// Each edge element's memory (OSR, OSF, ODR, a T-trigger coil, a CTU's input).
    memory: HashMap<usize, bool>,
    counts: HashMap<String, u32>,
    /// TON: since when its input is on; TOF: when its input was last on.
    times: HashMap<String, u32>,
    mcr: bool,
    now: u32,
}

fn parse(
    lines: &mut std::iter::Peekable<std::slice::Iter<'_, Vec<String>>>,
    n: &mut usize,
) -> Vec<El> {
    let mut items = Vec::new();
    while let Some(w) = lines.next() {
        match w[0].as_str() {
            "END" => break,
            "SERIES" => items.push(El::Series(parse(lines, n))),
            "PARALLEL" => items.push(El::Parallel(parse(lines, n))),
            _ => {
                *n += 1;
                items.push(El::Leaf(*n, w.clone()));
            }
        }
    }
    items
}

impl LdReference {
    /// The file's rungs; its X names are inputs A0.. and its Y names outputs Y0.. in the IO
    /// LIST's order (the fixtures name every one there).
    pub fn new(text: &str) -> LdReference {
        let words: Vec<Vec<String>> = text
            .lines()
            .map(|l| l.split_whitespace().map(String::from).collect::<Vec<_>>())
            .filter(|w| !w.is_empty())
            .collect();
        let list = words.iter().position(|w| w.join(" ") == "IO LIST").unwrap();
        let (mut inputs, mut outputs) = (Vec::new(), Vec::new());
        for w in words[list + 1..].iter().take_while(|w| w[0] != "END") {
            match w[0].as_bytes()[0] {
                b'X' => inputs.push(w[0].clone()),
                b'Y' => outputs.push(w[0].clone()),
                _ => {}
            }
        }
        let program = words.iter().position(|w| w[0] == "PROGRAM").unwrap();
        let mut it = words[program + 1..].iter().peekable();
        let (mut rungs, mut n) = (Vec::new(), 0);
        while let Some(w) = it.next() {
            assert_eq!(w[0], "RUNG");
            rungs.push(El::Series(parse(&mut it, &mut n)));
        }
        LdReference {
            rungs,
            inputs,
            outputs,
            bits: HashMap::new(),
            memory: HashMap::new(),
            counts: HashMap::new(),
            times: HashMap::new(),
            mcr: true,
            now: 0,
        }
    }

    /// One scan at `now` ms with the inputs (bit n: the IO LIST's n-th X), giving the
    /// outputs (bit n: its n-th Y).
    pub fn scan(&mut self, now: u32, inputs: u8) -> u8 {
        self.now = now;
        for (k, x) in self.inputs.iter().enumerate() {
            self.bits.insert(x.clone(), inputs & (1 << k) != 0);
        }
        self.mcr = true;
        let rungs = self.rungs.clone();
        for r in &rungs {
            if let El::Series(items) = r {
                if matches!(items.first(), Some(El::Leaf(_, w)) if w[0] == "COMMENT") {
                    continue;
                }
            }
            let power = self.mcr;
            self.eval(r, power);
        }
        let mut out = 0;
        for (k, y) in self.outputs.iter().enumerate() {
            if self.bit(y) {
                out |= 1 << k;
            }
        }
        out
    }

    /// The outputs of a fresh run, one scan a ms on the inputs the engine's scans saw.
    pub fn outputs(&self, samples: &[Sample]) -> Vec<u8> {
        let mut r = self.clone();
        samples
            .iter()
            .enumerate()
            .map(|(t, s)| r.scan(t as u32, s.inputs))
            .collect()
    }

    fn bit(&self, name: &str) -> bool {
        self.bits.get(name).copied().unwrap_or(false)
    }

    fn eval(&mut self, el: &El, p: bool) -> bool {
        match el {
            El::Series(items) => items.iter().fold(p, |p, e| self.eval(e, p)),
            El::Parallel(items) => {
                let mut any = false;
                for e in items {
                    any |= self.eval(e, p);
                }
                any
            }
            El::Leaf(id, w) => self.leaf(*id, w, p),
        }
    }

    /// The edge memory `id` (starting at `start`): its value before, set to `p`.
    fn edge(&mut self, id: usize, start: bool, p: bool) -> bool {
        let before = *self.memory.get(&id).unwrap_or(&start);
        self.memory.insert(id, p);
        before
    }

    fn leaf(&mut self, id: usize, w: &[String], p: bool) -> bool {
        let flag = |k: usize| w.get(k).is_some_and(|f| f != "0");
        let now = self.now;
        match w[0].as_str() {
            "CONTACTS" => p && (self.bit(&w[1]) != flag(2)),
            "COIL" => {
                let name = w[1].clone();
                let old = self.bit(&name);
                let new = if flag(2) {
                    !p
                } else if flag(3) {
                    old || p
                } else if flag(4) {
                    old && !p
                } else if flag(5) {
                    let before = self.edge(id, false, p);
                    old != (p && !before)
                } else {
                    p
                };
                self.bits.insert(name, new);
                p
            }
            "TON" => {
                let ms: u32 = w[2].parse::<u32>().unwrap() / 1000;
                if !p {
                    self.times.remove(&w[1]);
                    return false;
                }
                let since = *self.times.entry(w[1].clone()).or_insert(now);
                now - since >= ms
            }
            "TOF" => {
                let ms: u32 = w[2].parse::<u32>().unwrap() / 1000;
                if p {
                    self.times.insert(w[1].clone(), now);
                    return true;
                }
                self.times.get(&w[1]).is_some_and(|&t| now - t < ms)
            }
            "CTU" => {
                let max: u32 = w[2].parse().unwrap();
                let before = self.edge(id, true, p);
                let count = self.counts.entry(w[1].clone()).or_insert(0);
                if p && !before && *count < max {
                    *count += 1;
                }
                *count >= max
            }
            "RES" => {
                if p {
                    self.counts.insert(w[1].clone(), 0);
                }
                p
            }
            "OSR" => {
                let before = self.edge(id, false, p);
                p && !before
            }
            "OSF" => {
                let before = self.edge(id, true, p);
                !p && before
            }
            "ODR" => {
                let before = self.edge(id, false, p);
                !(p && !before)
            }
            "OPEN" => false,
            "SHORT" | "COMMENT" => p,
            "MASTER_RELAY" => {
                self.mcr = !self.mcr || p;
                p
            }
            other => panic!("the reference does not run {other}"),
        }
    }
}
