//! What the tests in this folder share, one file a job; a test takes what it needs with
//! `mod support;` and `use support::vnano::...`:
//!
//! - [`vnano`]: starting the virtual Nano, its console and pty with timeouts, the stand-in
//!   firmware (`vnano_*`, `terminals`, `utile_push_pull`, `kermit_roundtrip`, the
//!   cross-checks);
//! - [`utile`]: running the `utile` tool, scratch files, examples, its table, SVG and VCD
//!   (`utile_*`, `crosscheck_examples`);
//! - [`ladder`]: random timelines, runs sampled every ms and a ladder SVG's elements
//!   (`ladder_*`);
//! - [`iec`]: a reference evaluator of IEC 61131-3 ladder in PLCopen XML, scan by scan
//!   (`ladder_equivalence`, `ladder_export`);
//! - [`ldmicro`]: a reference evaluator of LDmicro's rungs, scan by scan (`ladder_ldmicro`);
//! - [`scans`]: a program on the engine one scan at a time beside the reference, the
//!   outputs compared after every scan (`ladder_export`);
//! - [`openplc`]: what OpenPLC Editor and its compiler need of an exported LD body: each
//!   connection's route, one modifier a contact or coil (`ladder_export`);
//! - [`live`]: `utile live` on the virtual Nano, an HTTP client for its API, a raw Modbus
//!   TCP client (`live_*`);
//! - [`between`]: a line between `utile live` and the virtual Nano that loses the replies or
//!   requests a test tells it to (`live_holds`);
//! - [`mqtt`]: mosquitto on loopback (password file, TLS listener, certificates), an MQTT
//!   client that subscribes and publishes (`live_mqtt`).
//!
//! Each test binary uses only part of it.
#![allow(dead_code, unused_imports)]

pub mod between;
pub mod iec;
pub mod ladder;
pub mod ldmicro;
pub mod live;
pub mod mqtt;
pub mod openplc;
pub mod scans;
pub mod utile;
pub mod vnano;
