//! What the core needs from the board it runs on.
//!
//! The firmware implements this on the ATmega328P (`crate::hal`); the host implements it
//! with a simulated clock and pins (tests, `utile sim`). Methods are small and called from
//! the scan, so implementations should be `#[inline]` and cheap.

/// The services of a board (real or simulated) that the engine and the editor use.
pub trait Board {
    /// Debounced input levels A0..A5 in bits 0..5 (bits 6..7 are 0).
    fn inputs(&mut self) -> u8;
    /// Leading-edge (0→1) bits selected by `mask`: returns whether any was set and clears
    /// them, atomically against the input sampling.
    fn take_leading(&mut self, mask: u8) -> bool;
    /// Trailing-edge (1→0) bits selected by `mask`: read and clear, atomically.
    fn take_trailing(&mut self, mask: u8) -> bool;
    /// Double-action (toggle) bits, one per input.
    fn toggles(&mut self) -> u8;
    /// Forget edges and toggles and take the present levels as debounced, with no
    /// phantom edges (EX0).
    fn resync_inputs(&mut self);
    /// Clock square waves: bit 0 CLKA (0.4 s), bit 1 CLKB (1.2 s), bit 2 CLKC (3.6 s).
    fn clocks(&mut self) -> u8;
    /// Milliseconds since reset, wrapping at 2^32.
    fn now_ms(&mut self) -> u32;
    /// Drive the output pins from the output image PY (out_sense is applied by the board).
    fn write_outputs(&mut self, py: u8);
    /// Next byte received from the terminal, if any.
    fn rx(&mut self) -> Option<u8>;
    /// Send one byte to the terminal; waits while the transmit buffer is full.
    fn tx(&mut self, byte: u8);
    /// Free space in the transmit buffer, for output that must never wait (RUN displays).
    fn tx_room(&mut self) -> u8;
    /// Read one EEPROM byte (addresses past the end read 0xFF).
    fn eeprom_read(&mut self, addr: u16) -> u8;
    /// Write one EEPROM byte if it differs; returns once the byte is written.
    fn eeprom_update(&mut self, addr: u16, value: u8);
    /// Received bytes wait to be read (the editor then defers its drawing: input first).
    fn rx_pending(&mut self) -> bool {
        false
    }
    /// Output is being dropped (the editor redraws later): drawing may stop early.
    fn tx_dropped(&mut self) -> bool {
        false
    }
    /// Received bytes lost because the receive buffer was full, since reset (for STAT).
    fn rx_overruns(&mut self) -> u16 {
        0
    }
    /// Restart the watchdog (long editor operations such as STORE call it).
    fn feed_watchdog(&mut self) {}
    /// Analog threshold bits: H6 in bit 6, H7 in bit 7, every other bit 0 (SPEC §15).
    fn analog_bits(&mut self) -> u8;
    /// The last reading of A6 (`channel` 0) or A7 (1), 0..1023 (the LDC screen, Modbus).
    /// One channel a call: a `u16` comes back in registers, where the pair came back through
    /// a stack frame of the caller's.
    fn analog_reading(&mut self, channel: u8) -> u16;
    /// The set-points S6, S7 the thresholds compare with (the program's, given at RUN, EX0
    /// and whenever they change).
    fn set_points(&mut self, sp: [u16; crate::analog::CHANNELS]);
}
