//! The hardware layer (AVR only): the ATmega328P adapted to the core's `Board` trait, one
//! peripheral per file, as thin as it can be; all logic lives in `utile_core`.
//!
//! | file | owns |
//! |---|---|
//! | `board.rs` | bring-up order (`init`) and `Board` for [`Nano`] |
//! | `pins.rs` | Y0..Y7 with out_sense, A0..A5, the D8/D9 jumpers |
//! | `tick.rs` | Timer0's 1 ms tick (the core's `Ticker`), Timer1 for STAT |
//! | `adc.rs` | A6/A7 in the background (the core's `Analog`: H6, H7) |
//! | `watchdog.rs` | the watchdog (software restart first) and the reset flags |
//! | `eeprom.rs` | EEPROM bytes |
//! | `serial.rs`, `ring.rs` | USART0 and its receive/transmit rings (the terminal's side) |
//! | `line.rs` | the line as a Modbus slave's in RUN mode: frame timing, D10, the replies |
//! | `want.rs` | when the scan gives the CPU back (every 16th scan, or now for Modbus) |
//! | `kept.rs` | the program kept over a warm reset (`.noinit`) |
//! | `scan.rs`, `scan.S` | the threaded RUN-mode scan |
//! | `scan_check/` | the `scan-check` build: `scan.S` against `Engine::scan` on the chip |
//! | `hang_test.rs` | the `hang-test` build: hangs on purpose, with interrupts on or off |
//! | `stack.rs` | stack painting for the high-water mark |
//! | `regs.rs`, `isr_cell.rs` | register access and bit names, state shared with interrupts |
//!
//! The interrupt vectors themselves are declared in `src/main.rs` (they need a crate
//! feature) and call [`on_tick`], [`adc::on_conversion`], [`serial::on_rx`],
//! [`serial::on_udre`], [`line::on_silence`] and [`line::on_tx_complete`]; the watchdog's,
//! which never returns, is assembly in `watchdog.rs`.

pub mod adc;
mod board;
mod eeprom;
#[cfg(feature = "hang-test")]
mod hang_test;
mod isr_cell;
pub mod kept;
pub mod line;
mod pins;
mod regs;
mod ring;
pub mod scan;
#[cfg(feature = "scan-check")]
pub mod scan_check;
pub mod serial;
mod stack;
mod tick;
mod want;
mod watchdog;

pub(crate) use adc::BITS as ANALOG_BITS;
pub use board::{init, Nano};
pub(crate) use isr_cell::IsrCell;
#[cfg(feature = "scan-check")]
pub(crate) use pins::drive_pins;
pub(crate) use pins::{LAST_PY, OUTPUTS, OUTPUTS_INVERT_AT, OUTPUTS_PY_AT};
#[cfg(feature = "scan-check")]
pub(crate) use regs::{regs, wr};
pub use tick::on_tick;
#[cfg(feature = "scan-check")]
pub(crate) use tick::publish;
pub(crate) use tick::{CLOCKS, LEVEL, TICKER, TOGGLES};
pub(crate) use want::now_from_main as want_next_end;
