//! uTile: a programmable logic controller for the ATmega328P of an Arduino Nano.
//!
//! [`core`] holds everything that is not hardware: the engine, the editor, the image
//! formats. It builds for the AVR (linked into the firmware by `src/main.rs`) and for the
//! host, where `cargo test` and the `utile` tool use it. [`hal`] is the thin hardware layer
//! and exists only on the AVR.
#![cfg_attr(not(test), no_std)]
#![deny(unsafe_code)]
// The HAL's threaded scan is `global_asm!`, still unstable on the AVR.
#![cfg_attr(target_arch = "avr", feature(asm_experimental_arch))]

#[cfg(not(target_arch = "avr"))]
extern crate std;

pub mod core;

#[cfg(target_arch = "avr")]
#[allow(unsafe_code)]
pub mod hal;

#[cfg(not(target_arch = "avr"))]
pub mod sim;

#[cfg(not(target_arch = "avr"))]
pub mod fuzzing;
