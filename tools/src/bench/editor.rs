//! The editor on the real image: the bytes its screens send, the deepest stack any screen
//! or a Modbus request in RUN mode reaches, and how long STORE takes.

use std::path::Path;

use utile_core::engine::LINES;
use utile_core::modbus::{
    READ_DISCRETE_INPUTS, READ_HOLDING_REGISTERS, READ_INPUT_REGISTERS, REPORT_SERVER_ID,
    WRITE_MULTIPLE_COILS, WRITE_MULTIPLE_REGISTERS,
};
use utile_core::opcodes::{self, END, NOP};
use utile_kit::modbus;
use utile_kit::simavr::Chip;

use super::chip::{self, BenchRun, CYCLES_PER_MS};
use super::error::BenchError;
use super::programs::{eeprom_with, every_opcode_program, example};

/// Byte painted over free RAM at boot by the HAL (`utile::hal::STACK_PAINT`, AVR-only).
pub const STACK_PAINT: u8 = 0xC5;

/// UART output of the editor, in bytes: power-up screen, one command entry, page flip,
/// full redraw (`/`).
#[derive(Clone, Debug, Default)]
pub struct UartBytes {
    /// Power-up screen.
    pub power_up: usize,
    /// `A0.` + CR.
    pub command: usize,
    /// ESC [ C.
    pub page_flip: usize,
    /// `/` + CR.
    pub redraw: usize,
}

/// Sends `input`, waits until the firmware has been quiet for `quiet_ms`, returns the
/// number of bytes it sent meanwhile.
fn exchange_q(chip: &mut Chip, input: &[u8], quiet_ms: u64) -> usize {
    chip.take_output();
    chip.send(input);
    chip.run_until_quiet(quiet_ms, 10_000);
    chip.take_output().len()
}

fn exchange(chip: &mut Chip, input: &[u8]) -> usize {
    exchange_q(chip, input, 40)
}

/// Counts the editor's UART bytes (D8 open, erased EEPROM).
pub fn measure_uart(elf: &Path) -> Result<UartBytes, BenchError> {
    let mut chip = chip::load(elf)?;
    chip.run_until_quiet(40, 5000);
    let power_up = chip.take_output().len();
    if power_up == 0 {
        return Err("no power-up screen".into());
    }
    Ok(UartBytes {
        power_up,
        command: exchange(&mut chip, b"A0.\r"),
        page_flip: exchange(&mut chip, b"\x1b[C"),
        redraw: exchange(&mut chip, b"/\r"),
    })
}

/// Stack use: (bytes of stack used at the deepest point, free bytes never touched).
pub fn measure_stack(elf: &Path) -> Result<(usize, usize, Vec<String>), BenchError> {
    let syms = crate::elf::symbols(elf)?;
    let heap = crate::elf::address(&syms, "__heap_start").ok_or("no __heap_start symbol")?;
    // A data-space address: without the ELF's offset of the data space.
    let heap = (heap - crate::elf::DATA_SPACE) as usize;
    let mut chip = chip::load(elf)?;
    chip.run_until_quiet(40, 5000);
    let mut big = every_opcode_program();
    for (i, line) in big.uf.iter_mut().enumerate().skip(200) {
        *line = opcodes::lookup(b"A0.").unwrap_or(NOP) + (i % 6) as u8;
    }
    big.uf[LINES - 1] = END;
    let hex = utile_kit::listing::to_hex(&big);
    let mut log = Vec::new();
    let steps: Vec<(&str, Vec<u8>)> = vec![
        ("help", b"?\r".to_vec()),
        ("help key", b" ".to_vec()),
        ("LDT", b"LDT\r5\r\x1b[C300\rZ\r\r".to_vec()),
        ("READ", b"READ\r".to_vec()),
        ("READ file of 256 lines", hex),
        ("READ done", b"\r".to_vec()),
        ("LIST", b"LIST\r\r".to_vec()),
        ("LIST back", b"\r".to_vec()),
        ("WRITE", b"WRITE\r\r".to_vec()),
        ("WRITE back", b"\r".to_vec()),
        (
            "keys",
            b"\x1b[C\x1b[D\x1b[A\x1b[B\x1b[1~\x1b[2~\x1b[3~40\r\x1bH".to_vec(),
        ),
        ("entry", b"A0.\r!\r.Y0\rINS\rDEL\rVER\r99999\r".to_vec()),
        ("LDC", b"LDC\r5\r\x1b[C70000\r1023\rZ\r\r".to_vec()),
        ("ADDR", b"7\rADDR\r".to_vec()),
        ("STORE", b"STORE\r".to_vec()),
        ("LOAD", b"LOAD\r".to_vec()),
        ("RUN", b"EX0\r".to_vec()),
        // Modbus requests to slave 7 while the program runs: the deepest map paths.
        (
            "Modbus FC03 x 26",
            modbus::frame(7, &[READ_HOLDING_REGISTERS, 0, 0, 0, 26]),
        ),
        (
            "Modbus FC16",
            modbus::frame(
                7,
                &[
                    WRITE_MULTIPLE_REGISTERS,
                    0,
                    14,
                    0,
                    4,
                    8,
                    0,
                    9,
                    0,
                    10,
                    0x12,
                    0x34,
                    0x01,
                    0x00,
                ],
            ),
        ),
        (
            "Modbus FC04 time left",
            modbus::frame(7, &[READ_INPUT_REGISTERS, 0, 32, 0, 16]),
        ),
        (
            "Modbus FC02",
            modbus::frame(7, &[READ_DISCRETE_INPUTS, 0, 8, 0, 42]),
        ),
        (
            "Modbus FC15",
            modbus::frame(7, &[WRITE_MULTIPLE_COILS, 0, 0, 0, 24, 3, 0xFF, 0, 0xFF]),
        ),
        ("Modbus FC17", modbus::frame(7, &[REPORT_SERVER_ID])),
        ("break", b"/".to_vec()),
        ("strike", b" ".to_vec()),
        ("STAT", b"STAT\r".to_vec()),
        ("FILL", b"FILL\r/\r".to_vec()),
    ];
    for (name, bytes) in steps {
        // READ ignores input for 200 ms after the file; RUN needs time to scan.
        let quiet = match name {
            "READ file of 256 lines" | "RUN" => 400,
            // A reply starts 1.8 ms after the request and takes up to 60 ms.
            n if n.starts_with("Modbus") => 100,
            // STORE writes for up to a second without a word.
            "STORE" => 2000,
            _ => 40,
        };
        let n = exchange_q(&mut chip, &bytes, quiet);
        log.push(format!("{name}: {n} bytes"));
    }
    let ramend = chip.ramend();
    let lowest = (heap..=ramend)
        .find(|&a| chip.peek(a) != STACK_PAINT)
        .unwrap_or(ramend);
    Ok((ramend + 1 - lowest, lowest - heap, log))
}

/// STORE timing.
#[derive(Clone, Copy, Debug)]
pub struct StoreTiming {
    /// EEPROM bytes written.
    pub writes: u64,
    /// From the end of the CR of STORE to the last byte of its final message, in simavr
    /// with the 3.4 ms EEPROM write time modelled (see `chip::load`).
    pub ms: f64,
}

fn timed_store(chip: &mut Chip) -> StoreTiming {
    let w0 = chip.ee_writes();
    chip.send(b"STORE\r");
    chip.run_until(1000 * CYCLES_PER_MS, |c| c.pending_input() == 0);
    // The CR is complete one frame after it starts.
    let start = chip.last_input_cycle() + chip::RX_CYCLES_PER_BYTE;
    // STORE sends nothing while it writes (up to about 1 s): wait for its final message.
    let end = chip.run_until_quiet(2000, 10_000);
    let writes = chip.ee_writes() - w0;
    let ms = end.saturating_sub(start) as f64 / CYCLES_PER_MS as f64;
    StoreTiming { writes, ms }
}

/// STORE after a one-line change (both slots hold the loaded program) and STORE into an
/// erased EEPROM (every byte written).
pub fn measure_store(elf: &Path) -> Result<(StoreTiming, StoreTiming), BenchError> {
    let prog = example("11.2b-intrusion-alarm.utl")?;
    let mut chip = chip::load(elf)?;
    chip.set_eeprom(0, &eeprom_with(&prog, 2)?);
    chip.run_until_quiet(40, 5000);
    exchange(&mut chip, b"LOAD\r");
    exchange(&mut chip, b"A1.\r");
    let small = timed_store(&mut chip);

    let mut chip = chip::load(elf)?;
    chip.run_until_quiet(40, 5000);
    exchange(&mut chip, b"FILL\r");
    let full = timed_store(&mut chip);
    if full.writes == 0 {
        return Err("STORE wrote nothing".into());
    }
    Ok((small, full))
}
