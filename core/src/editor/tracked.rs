//! [`Tracked`]: a board that notes whether anything was sent, so each entry point knows
//! whether to put the terminal cursor back at the prompt, and that puts input first
//! (SPEC §8 type-ahead): once the transmit ring is full while received bytes wait, it drops
//! the rest of the call's output instead of waiting, and the editor redraws later.

use super::*;

/// Room for the longest escape sequence the editor sends (`ESC [ 2 4 ; 4 7 H` and a few
/// digits after it), so starting one never waits.
const SEQ_ROOM: u8 = 16;

/// A board that notes whether anything was sent (so the cursor is put back at the prompt)
/// and mutes its output rather than keep received bytes waiting.
pub(super) struct Tracked<'a, B: Board> {
    pub(super) b: &'a mut B,
    /// [`SENT`], [`MAY_MUTE`], [`MUTE`], [`DROPPED`]: one byte, so each entry point sets up
    /// its `Tracked` with two stores.
    flags: u8,
    /// The last byte sent (muting never cuts an `ESC [ n ; n X` sequence in half).
    last: u8,
}

/// Something went out.
const SENT: u8 = 1;
/// Muting is allowed (not while LIST or WRITE send their text).
const MAY_MUTE: u8 = 2;
/// Output is dropped from now on.
const MUTE: u8 = 4;
/// Something was dropped: the screen is behind.
const DROPPED: u8 = 8;

impl<'a, B: Board> Tracked<'a, B> {
    pub(super) fn new(b: &'a mut B, may_mute: bool) -> Self {
        Self {
            b,
            flags: if may_mute { MAY_MUTE } else { 0 },
            last: 0,
        }
    }

    /// Something went out.
    pub(super) fn sent(&self) -> bool {
        self.flags & SENT != 0
    }

    /// Output is dropped from now on.
    pub(super) fn mute(&self) -> bool {
        self.flags & MUTE != 0
    }

    /// Something was dropped: the screen is behind.
    pub(super) fn dropped(&self) -> bool {
        self.flags & DROPPED != 0
    }
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
    // One copy: every byte the editor sends comes through here.
    #[inline(never)]
    fn tx(&mut self, byte: u8) {
        // Sending would wait while input is pending: input wins.
        // Room this byte needs to go out without waiting. A sequence `ESC [ n ; n X` is
        // started only with room for all of it and never cut: the terminal sees no half
        // sequence (after a digit of plain text the cut just comes a byte later).
        let need: u8 = match (byte, self.last) {
            (0x1B, _) => SEQ_ROOM,
            (_, 0x1B | b'[' | b'0'..=b'9' | b';') => 0,
            _ => 1,
        };
        if self.flags & (MAY_MUTE | MUTE) == MAY_MUTE
            && self.b.tx_room() < need
            && self.b.rx_pending()
        {
            self.flags |= MUTE;
        }
        if self.mute() {
            self.flags |= DROPPED;
            return;
        }
        self.flags |= SENT;
        self.last = byte;
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
    fn tx_dropped(&mut self) -> bool {
        self.mute()
    }
    fn rx_pending(&mut self) -> bool {
        self.b.rx_pending()
    }
    fn rx_overruns(&mut self) -> u16 {
        self.b.rx_overruns()
    }
    fn feed_watchdog(&mut self) {
        self.b.feed_watchdog()
    }
    fn analog_bits(&mut self) -> u8 {
        self.b.analog_bits()
    }
    fn analog_reading(&mut self, channel: u8) -> u16 {
        self.b.analog_reading(channel)
    }
    fn set_points(&mut self, sp: [u16; crate::analog::CHANNELS]) {
        self.b.set_points(sp)
    }
}
