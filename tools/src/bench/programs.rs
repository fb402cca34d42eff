//! The programs the benchmarks run: built from command names, the manual's examples, and
//! the EEPROM or chip that holds one stored for autostart.

use std::path::Path;

use utile_core::engine::{Program, LINES};
use utile_core::opcodes::{self, END, NOP};
use utile_kit::listing;
use utile_kit::setup;
use utile_kit::simavr::{Chip, RigPin};

use super::chip;
use super::error::BenchError;

/// A program from command names, line 0 onwards; the rest of the UF is NOP.
pub fn program(words: &[&str]) -> Program {
    listing::commands(words)
}

/// 255 NOP lines, then END on line 255.
pub fn nops_program() -> Program {
    let mut p = Program::blank();
    p.uf = [NOP; LINES];
    p.uf[LINES - 1] = END;
    p
}

/// Every counter counting (C0..C5 on A0..A5, C6 on CLKA, C7 on CLKB), each with a reset
/// (A5 inverted) and its output on Yn, and both analog thresholds to U0/U1.
pub fn all_counters_program() -> Program {
    let mut words: Vec<String> = Vec::new();
    for m in 0..8 {
        let input = match m {
            0..=5 => format!("A{m}."),
            6 => "CLKA.".into(),
            _ => "CLKB.".into(),
        };
        words.extend([
            input,
            format!(".CU{m}"),
            "A5.".into(),
            "!".into(),
            format!(".CR{m}"),
        ]);
    }
    for m in 0..8 {
        words.extend([format!("CQ{m}."), format!(".Y{m}")]);
    }
    words.extend([
        "H6.".into(),
        ".U0".into(),
        "H7.".into(),
        ".U1".into(),
        "END".into(),
    ]);
    let refs: Vec<&str> = words.iter().map(String::as_str).collect();
    let mut prog = program(&refs);
    prog.counter_presets = [3, 5, 10, 100, 1000, 10_000, 2, 4];
    prog.set_points = [512, 256];
    prog
}

/// Every valid opcode once (END last), presets 10 so the timers run.
pub fn every_opcode_program() -> Program {
    let mut p = Program::blank();
    p.uf = [NOP; LINES];
    let ops: Vec<u8> = (0..=0xFEu8)
        .filter(|&op| op != END && opcodes::is_valid(op))
        .collect();
    for (line, op) in p.uf.iter_mut().zip(&ops) {
        *line = *op;
    }
    p.uf[ops.len().min(LINES - 1)] = END;
    p.presets = [10; 16];
    p
}

/// A `.utl` listing from the repository's examples directory.
pub fn example(name: &str) -> Result<Program, BenchError> {
    let path = setup::workspace_root().join("examples").join(name);
    let text = std::fs::read_to_string(&path).map_err(|source| BenchError::File {
        path: path.clone(),
        source,
    })?;
    Ok(listing::parse(name, &text)?)
}

/// [`utile_kit::sim::stored_eeprom`] with the bench's error text.
pub fn eeprom_with(prog: &Program, stores: usize) -> Result<Vec<u8>, BenchError> {
    utile_kit::sim::stored_eeprom(prog, stores).map_err(BenchError::Store)
}

/// A chip with `prog` stored in EEPROM and D8 grounded: it autostarts at power-up.
pub fn autostarting(elf: &Path, prog: &Program) -> Result<Chip, BenchError> {
    let mut chip = chip::load(elf)?;
    chip.set_eeprom(0, &eeprom_with(prog, 1)?);
    chip.hold_low(RigPin::D8, true);
    Ok(chip)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_opcode_program_has_each_valid_opcode_once_then_end() {
        let p = every_opcode_program();
        let end_at = p.uf.iter().position(|&op| op == END).unwrap();
        let body = &p.uf[..end_at];
        for op in 0..=0xFEu8 {
            let n = body.iter().filter(|&&x| x == op).count();
            let want = usize::from(op != END && opcodes::is_valid(op));
            assert_eq!(n, want, "opcode {op:#04x}");
        }
    }
}
