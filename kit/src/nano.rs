//! The Nano's fixed figures, which every simulation of it shares (the simavr harness, the
//! plants, the playground's module): its clock and its supply.

/// CPU clock of the Nano (16 MHz crystal).
pub const F_CPU: u64 = 16_000_000;

/// Supply, analog supply and ADC reference of the simulated board, in millivolts.
pub const VCC_MV: u32 = 5000;
