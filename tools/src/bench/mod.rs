//! Benchmarks of the real firmware image in simavr (`cargo run -p utile-tools --release
//! --bin bench`, `./x bench`): scan cycles, press-to-output latency, timer error,
//! reset-to-running, flash/RAM/stack, UART bytes of the editor, STORE duration, Modbus, the
//! live view.
//! Results are reported, never asserted; BENCHMARKS.md explains each row.
//!
//! One job a file: [`chip`] (the harness as the benchmarks run it), [`error`] (why a
//! measurement has no figure), [`programs`] (what they
//! run), [`stats`] (the spread of a sample), [`isr`] (interrupt handlers' cycles), then the
//! measurements — [`scan`], [`timing`], [`editor`], [`modbus`], [`live`] (`utile live` on
//! the virtual Nano), [`live_pages`] (with twenty pages open), [`live_door`] (requests
//! another web page could send, refused), [`mqtt`] (three lines into one
//! broker), [`mqtt_rig`] (a rig switch to its MQTT message) — and [`report`], the rows
//! of the `bench` binary's table with the original's figures beside them. Section sizes and
//! symbols come from [`crate::elf`].

pub mod chip;
pub mod editor;
pub mod error;
pub mod isr;
pub mod live;
pub mod live_door;
pub mod live_pages;
pub mod modbus;
pub mod mqtt;
pub mod mqtt_rig;
pub mod programs;
pub mod report;
pub mod scan;
pub mod stats;
pub mod timing;

pub use editor::{measure_stack, measure_store, measure_uart, StoreTiming, UartBytes, STACK_PAINT};
pub use error::BenchError;
pub use programs::{
    all_counters_program, autostarting, eeprom_with, every_opcode_program, example, nops_program,
    program,
};
pub use scan::{measure_scans, ScanResult, TICK_VECTOR};
pub use stats::Spread;
pub use timing::{
    measure_autostart, measure_autostart_boot, measure_latency, measure_run_gap,
    measure_timer_host, measure_timer_simavr, timer_program, BootStart,
};
