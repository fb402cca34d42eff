//! The host tools' own parts: the virtual Nano's terminal, pty and rig (`cargo nano`) and
//! the benchmarks (`./x bench`). What the tools share with the tests is in `utile_kit`.
#![deny(missing_docs)]

/// Benchmarks of the real firmware image in simavr (`bench` binary).
pub mod bench;
/// What the command lines share: typed values, `--wait`, the log (`RUST_LOG`).
pub mod cli;
/// Symbols and section sizes of a firmware ELF (AVR binutils), for `cargo fw` and the bench.
pub mod elf;
/// Programs to and from a uTile over a serial port (`utile push`, `utile pull`).
pub mod link;
/// Every uTile on a line live in the browser, the terminal and a Modbus TCP gateway
/// (`utile live`).
pub mod live;
/// The virtual Nano (`cargo nano`): firmware in simavr, UART on a terminal or pty.
pub mod vnano;
