//! `GET /api/units/{addr}/ladder`: the program a uTile runs (its listing read over SPEC §17)
//! drawn as ladder by the kit's drawer ([`utile_kit::ladder`]), with its presets. The page
//! fetches it once per program (and again when a preset changes) and lights it from the line
//! values every picture already brings (`program.values`): each element's and wire's
//! `data-power-lines` names the lines whose values, ANDed, are its power (docs/LADDER.md,
//! "Power flow"), so a refresh costs the server nothing.

use std::sync::Arc;

use axum::extract::rejection::PathRejection;
use axum::extract::{Path, State};
use axum::Json;
use serde::Serialize;

use utile_core::engine::{Program, LINES};
use utile_core::opcodes::BLANK;
use utile_kit::ladder;

use super::api::ApiError;
use super::hub::Hub;
use super::signals::Values;
use super::view::Listing;

/// `GET /api/units/{addr}/ladder`'s answer.
#[derive(Clone, Debug, Serialize)]
pub struct LadderDoc {
    /// The fingerprint of the program drawn (SPEC §17), as its listing was read.
    pub fingerprint: u16,
    /// The lines read give that fingerprint.
    pub consistent: bool,
    /// The timer presets T0..TF drawn (on the TOF coils), as last read.
    pub presets: Vec<u8>,
    /// The counter presets C0..C7 drawn (on the CTU coils), as last read.
    pub counter_presets: Vec<u16>,
    /// The drawing: `utile ladder`'s SVG of the program.
    pub svg: String,
}

/// The program of `listing` with the presets and set-points of `values` (0 where not read).
pub fn program(listing: &Listing, values: &Values) -> Program {
    let mut prog = Program::blank();
    prog.uf = [BLANK; LINES];
    for line in &listing.lines {
        prog.uf[usize::from(line.n)] = line.op;
    }
    let hex = |m: usize| char::from_digit(m as u32, 16).map_or('0', |c| c.to_ascii_uppercase());
    for (m, p) in prog.presets.iter_mut().enumerate() {
        *p = values.get(&format!("T{}", hex(m))).unwrap_or(0).min(255) as u8;
    }
    for (m, p) in prog.counter_presets.iter_mut().enumerate() {
        *p = values.get(&format!("CP{m}")).unwrap_or(0) as u16;
    }
    for (k, p) in prog.set_points.iter_mut().enumerate() {
        *p = values.get(&format!("S{}", 6 + k)).unwrap_or(0) as u16;
    }
    prog
}

/// The drawing of uTile `addr`'s program.
pub fn drawing(addr: u8, listing: &Listing, values: &Values) -> LadderDoc {
    let prog = program(listing, values);
    let model = ladder::from_program(&prog);
    let title = format!(
        "uTile {addr}: program {:04X}{}",
        listing.fingerprint,
        if listing.consistent {
            ""
        } else {
            " (read again: the lines do not give it)"
        }
    );
    LadderDoc {
        fingerprint: listing.fingerprint,
        consistent: listing.consistent,
        presets: prog.presets.to_vec(),
        counter_presets: prog.counter_presets.to_vec(),
        svg: ladder::svg(&model, &title),
    }
}

/// `GET /api/units/{addr}/ladder`: the drawing, or why not (no such uTile, its program not
/// read yet).
pub async fn get(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
) -> Result<Json<LadderDoc>, ApiError> {
    let Path(addr) = addr?;
    let view = hub.view();
    let unit = view.unit(addr).ok_or(ApiError::NoUnit(addr))?;
    let listing = unit.listing.as_ref().ok_or(ApiError::NoProgram)?;
    Ok(Json(drawing(addr, listing, &unit.values)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::live::program::{listing, values};
    use utile_core::modbus::snapshot::Snapshot;
    use utile_kit::listing as kit_listing;
    use utile_kit::rng::Rng;

    /// A listing as the live view reads it.
    fn read(prog: &Program) -> Listing {
        Listing {
            fingerprint: 0x1234,
            consistent: true,
            lines: listing(&prog.uf),
        }
    }

    /// `name="…"` of an element's tag.
    fn attr<'a>(tag: &'a str, name: &str) -> Option<&'a str> {
        let at = tag.find(&format!(" {name}=\""))? + name.len() + 3;
        Some(&tag[at..at + tag[at..].find('"')?])
    }

    fn numbers(list: &str) -> Vec<usize> {
        list.split(',')
            .filter(|s| !s.is_empty())
            .map(|s| s.parse().unwrap())
            .collect()
    }

    /// The page's rule: the values of the lines ANDed (`0` wins, then `?`; none: the rail).
    fn powered(lines: &[usize], v: &[u8]) -> u8 {
        let mut p = b'1';
        for &l in lines {
            match v[l] {
                b'0' => return b'0',
                b'1' => {}
                _ => p = b'?',
            }
        }
        p
    }

    /// Every tag with `data-power-lines`: (class, its lines, its power lines).
    fn powered_tags(svg: &str) -> Vec<(String, Vec<usize>, Vec<usize>)> {
        svg.split('<')
            .filter(|t| t.contains("data-power-lines="))
            .map(|t| {
                (
                    attr(t, "class").unwrap_or("").to_string(),
                    numbers(attr(t, "data-lines").unwrap_or("")),
                    numbers(attr(t, "data-power-lines").unwrap()),
                )
            })
            .collect()
    }

    fn random_snapshot(rng: &mut Rng) -> Snapshot {
        Snapshot {
            inputs: rng.below(64) as u8,
            outputs: rng.below(256) as u8,
            u: rng.below(256) as u8,
            v: rng.below(256) as u8,
            q: rng.below(65536) as u16,
            tq: rng.below(65536) as u16,
            cq: rng.below(256) as u8,
            thresholds: rng.below(4) as u8,
            ..Snapshot::default()
        }
    }

    const CONTACTS: [&str; 12] = [
        "A0.", "A1.", "A2.", "U0.", "U1.", "V2.", "Y0.", "Q1.", "TQ0.", "CQ0.", "AL0.", "CLKA.",
    ];
    const COILS: [&str; 8] = [".Y0", ".Y1", ".U1", ".V2", ".S1", ".R1", ".TK0", ".CU0"];

    /// A random network in postfix words.
    fn net(rng: &mut Rng, depth: u32, out: &mut Vec<&'static str>) {
        if depth == 0 || rng.below(5) < 2 {
            out.push(CONTACTS[rng.below(12) as usize]);
            if rng.below(4) == 0 {
                out.push("!");
            }
            return;
        }
        net(rng, depth - 1, out);
        if rng.below(6) == 0 {
            out.push("!");
            return;
        }
        net(rng, depth - 1, out);
        out.push(["AND", "OR", "XOR"][rng.below(3) as usize]);
    }

    /// A random flow of a rung's power in postfix words.
    fn flow(rng: &mut Rng, depth: u32, out: &mut Vec<&'static str>) {
        match if depth == 0 { 0 } else { rng.below(5) } {
            0 | 1 => {
                if rng.below(4) == 0 {
                    out.push("!");
                }
                out.push(COILS[rng.below(8) as usize]);
            }
            2 => {
                out.push("DUP");
                flow(rng, depth - 1, out);
                flow(rng, depth - 1, out);
            }
            3 => {
                net(rng, 2, out);
                out.push(["AND", "OR", "XOR"][rng.below(3) as usize]);
                flow(rng, depth - 1, out);
            }
            _ => {
                out.push("DUP");
                net(rng, 1, out);
                out.push("AND");
                out.push(["AND", "OR", "XOR"][rng.below(3) as usize]);
                flow(rng, depth - 1, out);
            }
        }
    }

    /// A program of random rungs, then END.
    fn random_rungs(rng: &mut Rng) -> Program {
        let mut words = Vec::new();
        loop {
            let mut rung = Vec::new();
            net(rng, 3, &mut rung);
            flow(rng, 3, &mut rung);
            if words.len() + rung.len() > 250 {
                break;
            }
            words.extend(rung);
        }
        words.push("END");
        kit_listing::commands(&words)
    }

    /// The power at every coil, lit by the page's rule from the engine's line values, is
    /// the bit its pop takes (negated: the other); a contact with power on its right side
    /// is closed.
    fn check_power_flow(prog: &Program, rng: &mut Rng, what: &str) -> usize {
        let doc = drawing(1, &read(prog), &Values(Vec::new()));
        let tags = powered_tags(&doc.svg);
        let mut coils = 0;
        for _ in 0..20 {
            let v = values(&prog.uf, None, &random_snapshot(rng));
            let v = v.as_bytes();
            for (class, lines, power) in &tags {
                let p = powered(power, v);
                match class.as_str() {
                    "coil" => {
                        let pop = *lines.last().unwrap();
                        let negated = lines.len() == 2;
                        let took = match (v[pop], negated) {
                            (b'1', false) | (b'0', true) => b'1',
                            (b'0', false) | (b'1', true) => b'0',
                            (c, _) => c,
                        };
                        assert_eq!(p, took, "{what}: coil on line {pop}: {power:?}");
                        coils += 1;
                    }
                    "contact" if p == b'1' => {
                        assert_eq!(v[*lines.last().unwrap()], b'1', "{what}: {lines:?}");
                    }
                    _ => {}
                }
            }
        }
        coils
    }

    #[test]
    fn the_power_flow_agrees_with_the_engine_on_every_example_and_random_rungs() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples");
        let mut rng = Rng::new(29);
        let mut coils = 0;
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "utl") {
                continue;
            }
            let text = std::fs::read_to_string(&path).unwrap();
            let prog = kit_listing::parse("example", &text).unwrap();
            coils += check_power_flow(&prog, &mut rng, &path.display().to_string());
        }
        assert!(coils > 300, "{coils} coils checked in the examples");
        let mut coils = 0;
        for n in 0..200 {
            let prog = random_rungs(&mut rng);
            coils += check_power_flow(&prog, &mut rng, &format!("random program {n}"));
        }
        assert!(coils > 50_000, "{coils} coils checked in random programs");
    }

    /// A rung's first contact has the power of its own value (from the rail); the one after
    /// it in series, both; a parallel branch's, its own; an instruction block's line, its own.
    #[test]
    fn each_element_names_the_lines_of_its_power() {
        let prog = kit_listing::commands(&[
            "A0.", ".Y0", "A1.", "A2.", "!", "AND", "U0.", "OR", ".Y1", "SWAP", "END",
        ]);
        let svg = drawing(1, &read(&prog), &Values(Vec::new())).svg;
        let tags = powered_tags(&svg);
        let find = |class: &str, line: usize| {
            tags.iter()
                .find(|(c, l, _)| c == class && l.contains(&line))
                .map(|t| t.2.clone())
                .unwrap_or_else(|| panic!("no {class} on line {line} in {svg}"))
        };
        assert_eq!(find("contact", 0), [0]);
        assert_eq!(find("coil", 1), [0]);
        assert_eq!(find("contact", 2), [2]);
        assert_eq!(find("contact", 4), [2, 4]);
        assert_eq!(find("contact", 6), [6]);
        assert_eq!(find("coil", 8), [7]);
        assert_eq!(find("line", 9), [9]);
        // Every wire of rung 1 carries a power too.
        assert!(tags.iter().any(|(c, _, p)| c == "wire" && p == &[7]));
    }

    #[test]
    fn the_presets_read_are_drawn() {
        let prog = kit_listing::commands(&["A0.", ".TK4", "END"]);
        let vals = Values(vec![("T4", 90), ("CP0", 7)]);
        let doc = drawing(3, &read(&prog), &vals);
        assert_eq!(doc.presets[4], 90);
        assert_eq!(doc.counter_presets[0], 7);
        assert!(doc.svg.contains("TQ4 90 s"), "{}", doc.svg);
        assert!(doc.svg.contains("uTile 3: program 1234"));
    }
}
