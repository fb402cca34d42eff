//! `utile ladder` and listing ⇄ ladder: every example draws (each element names its signal
//! and lines truly, every line drawn once), compiles back to the same bytes, and runs the
//! same on the core's engine; lines without a ladder form become blocks of their lines.

mod support;

use support::ladder::{elements, random_events, run};
use support::utile::*;
use utile_core::engine::{Program, LINES};
use utile_core::opcodes::{self, BLANK, NOP, NOT};
use utile_kit::ladder::{self, Item};
use utile_kit::listing;
use utile_kit::rng::Rng;

fn load(stem: &str) -> Program {
    let path = example(&format!("{stem}.utl"));
    listing::parse(&path, &std::fs::read_to_string(&path).unwrap()).unwrap()
}

/// The lines of a program that are not the fill after its last command.
fn code_lines(prog: &Program) -> usize {
    let last = prog.uf[LINES - 1];
    if last == NOP || last == BLANK {
        LINES - prog.uf.iter().rev().take_while(|&&o| o == last).count()
    } else {
        LINES
    }
}

/// Each contact and coil in the SVG names the signal its lines push or pop, a negated
/// one has its `!`, and every code line of the program is drawn in exactly one rung.
fn check_drawing(prog: &Program, svg: &str) {
    let els = elements(svg);
    let mut seen = vec![0u32; LINES];
    for e in &els {
        let word = |l: u8| opcodes::name(prog.uf[usize::from(l)]).map(|n| n.as_str().to_string());
        match e.class.as_str() {
            "contact" => {
                let w = word(e.lines[0]).unwrap();
                let sig = e.signal.clone().unwrap();
                assert!(
                    w.trim_end_matches('.') == sig
                        || (sig == "1" && w == "SET")
                        || (sig == "0" && w == "CLR"),
                    "contact {sig} on line {} which holds {w}",
                    e.lines[0]
                );
                if e.lines.len() == 2 {
                    assert_eq!(prog.uf[usize::from(e.lines[1])], NOT);
                }
            }
            "coil" => {
                let pop = *e.lines.last().unwrap();
                let w = word(pop).unwrap();
                assert_eq!(w.trim_start_matches('.'), e.signal.clone().unwrap());
                if e.lines.len() == 2 {
                    assert_eq!(prog.uf[usize::from(e.lines[0])], NOT);
                }
            }
            "rung" | "rung block" => {
                for &l in &e.lines {
                    seen[usize::from(l)] += 1;
                }
            }
            _ => {}
        }
    }
    for (l, &n) in seen.iter().enumerate().take(code_lines(prog)) {
        assert_eq!(n, 1, "line {l:03} is drawn {n} times");
    }
    assert_eq!(svg.matches("<g").count(), svg.matches("</g>").count());
}

#[test]
fn every_example_draws_with_its_signals_and_lines() {
    let stems = example_stems();
    assert!(stems.len() >= 9);
    for stem in stems {
        let out = scratch(&format!("{stem}.svg"));
        let input = example(&format!("{stem}.utl"));
        utile_ok(&["ladder", &input, "-o", out.to_str().unwrap()]);
        let svg = std::fs::read_to_string(&out).unwrap();
        assert!(
            svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""),
            "{stem}"
        );
        let prog = load(&stem);
        check_drawing(&prog, &svg);
        // The examples are ladder all through: no blocks but KEY and END.
        let model = ladder::from_program(&prog);
        for item in &model.items {
            if let Item::Block(b) = item {
                for &(_, op) in &b.lines {
                    assert!(
                        op == opcodes::KEY || op == opcodes::END,
                        "{stem}: line {:?} drawn as a block",
                        b.lines
                    );
                }
            }
        }
        assert!(svg.contains("class=\"coil\""), "{stem}");
    }
}

#[test]
fn every_example_round_trips_byte_for_byte_and_runs_the_same() {
    let mut rng = Rng::new(29);
    for stem in example_stems() {
        let prog = load(&stem);
        let back = ladder::to_program(&ladder::from_program(&prog)).unwrap();
        // The canonical listing (`utile fmt`) is the same text.
        assert_eq!(listing::print(&back), listing::print(&prog), "{stem}");
        assert_eq!(back, prog, "{stem}");
        for _ in 0..20 {
            let events = random_events(&mut rng, 0x3F, 4000, 30);
            assert_eq!(
                run(&prog, &events, 4000, 2),
                run(&back, &events, 4000, 2),
                "{stem}"
            );
        }
    }
}

/// A program of random commands, weighted toward those a rung is made of.
fn random_program(rng: &mut Rng) -> Program {
    let mut p = Program::blank();
    let n = rng.range(1, 255) as usize;
    for l in 0..n {
        p.uf[l] = match rng.below(10) {
            0..=3 => opcodes::PUSH_A + rng.below(0x60) as u8,
            4 => opcodes::POP_Y + rng.below(0x68) as u8,
            5 => [opcodes::AND, opcodes::OR, opcodes::XOR][rng.below(3) as usize],
            6 => NOT,
            7 => opcodes::DUP,
            8 => rng.byte(),
            _ => [
                opcodes::SET,
                opcodes::CLR,
                opcodes::SWAP,
                opcodes::DUP2,
                opcodes::END,
            ][rng.below(5) as usize],
        };
    }
    let fill = [NOP, BLANK][rng.below(2) as usize];
    for l in n..LINES {
        p.uf[l] = fill;
    }
    p.presets[rng.below(16) as usize] = rng.byte();
    p
}

#[test]
fn any_program_round_trips_and_draws_every_line_once() {
    let mut rng = Rng::new(0x1adde7);
    for _ in 0..3000 {
        let prog = random_program(&mut rng);
        let model = ladder::from_program(&prog);
        assert_eq!(ladder::to_program(&model).unwrap(), prog);
        check_drawing(&prog, &ladder::svg(&model, "random"));
    }
    for _ in 0..300 {
        let prog = rng.program_v2();
        let model = ladder::from_program(&prog);
        assert_eq!(ladder::to_program(&model).unwrap(), prog);
    }
}

#[test]
fn what_has_no_ladder_form_is_a_block_of_its_lines() {
    let text = "FILL\nA0.\nA1.\nSWAP\n.Y0\n.Y1\nPA.\n.PY\nA2.\nDUP\n.Y2\n.Y3\nA3.\nKEY\nEND\n";
    let prog = listing::parse("t.utl", text).unwrap();
    let model = ladder::from_program(&prog);
    let kinds: Vec<String> = model
        .items
        .iter()
        .map(|i| match i {
            Item::Rung(_) => "rung".to_string(),
            Item::Block(b) => format!("block{:?}", b.lines.iter().map(|l| l.0).collect::<Vec<_>>()),
        })
        .collect();
    // SWAP with its pushes and pops, then the byte moves; A2 split to two coils is a rung;
    // A3 left on the stack; KEY; END.
    assert_eq!(
        kinds,
        [
            "block[0, 1, 2, 3, 4, 5, 6]",
            "rung",
            "block[11]",
            "block[12]",
            "block[13]"
        ]
    );
    let svg = ladder::svg(&model, "t");
    assert!(svg.contains(">002 SWAP</text>"));
    assert!(svg.contains(">006 .PY</text>"));
    assert_eq!(ladder::to_program(&model).unwrap(), prog);
}

#[test]
fn a_stack_deeper_than_eight_bits_is_not_a_rung() {
    // Nine contacts pushed before the first AND: the ninth push loses the first bit.
    let mut text = String::from("FILL\n");
    for _ in 0..9 {
        text.push_str("A0.\n");
    }
    for _ in 0..8 {
        text.push_str("AND\n");
    }
    text.push_str(".Y0\nEND\n");
    let prog = listing::parse("deep.utl", &text).unwrap();
    let model = ladder::from_program(&prog);
    assert!(matches!(model.items[0], Item::Block(_)));
    assert_eq!(ladder::to_program(&model).unwrap(), prog);
}

#[test]
fn bad_listing_draws_nothing() {
    let path = write_scratch("bad.utl", "000 A0.\nFOO\n");
    let out = scratch("bad.svg");
    let err = utile_err(&["ladder", &path, "-o", out.to_str().unwrap()]);
    assert!(err.contains("unknown word 'FOO'"), "{err}");
    assert!(!out.exists());
}
