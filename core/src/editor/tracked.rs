//! [`Tracked`]: a board that notes whether anything was sent, so each entry point knows
//! whether to put the terminal cursor back at the prompt.

use super::*;

/// A board that notes whether anything was sent (so the cursor is put back at the prompt).
pub(super) struct Tracked<'a, B: Board> {
    pub(super) b: &'a mut B,
    pub(super) sent: bool,
}

impl<B: Board> Board for Tracked<'_, B> {
    fn inputs(&mut self) -> u8 {
        self.b.inputs()
    }
    fn take_leading(&mut self, mask: u8) -> bool {
        self.b.take_leading(mask)
    }
    fn take_trailing(&mut self, mask: u8) -> bool {
        self.b.take_trailing(mask)
    }
    fn toggles(&mut self) -> u8 {
        self.b.toggles()
    }
    fn resync_inputs(&mut self) {
        self.b.resync_inputs()
    }
    fn clocks(&mut self) -> u8 {
        self.b.clocks()
    }
    fn now_ms(&mut self) -> u32 {
        self.b.now_ms()
    }
    fn write_outputs(&mut self, py: u8) {
        self.b.write_outputs(py)
    }
    fn rx(&mut self) -> Option<u8> {
        self.b.rx()
    }
    fn tx(&mut self, byte: u8) {
        self.sent = true;
        self.b.tx(byte)
    }
    fn tx_room(&mut self) -> u8 {
        self.b.tx_room()
    }
    fn eeprom_read(&mut self, addr: u16) -> u8 {
        self.b.eeprom_read(addr)
    }
    fn eeprom_update(&mut self, addr: u16, value: u8) {
        self.b.eeprom_update(addr, value)
    }
    fn rx_overruns(&mut self) -> u16 {
        self.b.rx_overruns()
    }
    fn feed_watchdog(&mut self) {
        self.b.feed_watchdog()
    }
}
