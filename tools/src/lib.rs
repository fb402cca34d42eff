//! The host tools' own parts: the virtual Nano's terminal, pty and rig (`cargo nano`) and
//! the benchmarks (`./x bench`). What the tools share with the tests is in `utile_kit`.
#![deny(missing_docs)]

/// Benchmarks of the real firmware image in simavr (`bench` binary).
pub mod bench;
/// What the command lines share: typed values, `--wait`, the log (`RUST_LOG`).
pub mod cli;
/// Symbols and section sizes of a firmware ELF (AVR binutils), for `cargo fw` and the bench.
pub mod elf;
/// `utile ladder`, `utile import`: listings as ladder; PLCopen XML and LDmicro as listings.
pub mod ladder_cmd;
/// Programs to and from a uTile over a serial port (`utile push`, `utile pull`).
pub mod link;
/// Every uTile on a line live in the browser, the terminal and a Modbus TCP gateway
/// (`utile live`).
pub mod live;
/// The avr8js cross-check's scenarios and traces, and their runner on simavr (`simtrace`).
pub mod simtrace;
/// The virtual Nano (`cargo nano`): firmware in simavr, UART on a terminal or pty.
pub mod vnano;
