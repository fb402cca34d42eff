//! The virtual test rig (manual §2.4) as seen from the keyboard: the hot-key prefix, the
//! rig keys, the one-line status display, and a tracker of the firmware's VT100 output so
//! the status line is only drawn between escape sequences.

use utile_kit::simavr::{Chip, RigPin};

/// The hot-key prefix in terminal mode: Ctrl-] (as telnet's escape key; uTile has no use
/// for it). Press it twice to send one Ctrl-] to the firmware.
pub const PREFIX: u8 = 0x1D;

/// What a rig key asks for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RigAction {
    /// Toggle a switch (pressed/released) or a jumper (fitted/open).
    Toggle(RigPin),
    /// Step the level on A6 or A7 (the pin number) by [`ANALOG_STEP_MV`]: up if true.
    Analog(u8, bool),
    /// Warm reset of the chip (the reset button).
    Reset,
    /// Leave the virtual Nano.
    Quit,
    /// Show the rig keys.
    Help,
}

/// One press of an analog rig key moves A6 or A7 by this many millivolts.
pub const ANALOG_STEP_MV: u32 = 100;

/// Maps a rig key (after the prefix in terminal mode, bare in pty mode) to its action.
/// `6`/`7` raise A6/A7; `^`/`&` (the same keys with Shift on a US keyboard) lower them.
pub fn rig_key(byte: u8) -> Option<RigAction> {
    match byte {
        b'0'..=b'5' => Some(RigAction::Toggle(RigPin::Switch(byte - b'0'))),
        b'6' => Some(RigAction::Analog(6, true)),
        b'7' => Some(RigAction::Analog(7, true)),
        b'^' => Some(RigAction::Analog(6, false)),
        b'&' => Some(RigAction::Analog(7, false)),
        b'8' => Some(RigAction::Toggle(RigPin::D8)),
        b'9' => Some(RigAction::Toggle(RigPin::D9)),
        b'r' | b'R' => Some(RigAction::Reset),
        b'q' | b'Q' => Some(RigAction::Quit),
        b'?' | b'h' | b'H' => Some(RigAction::Help),
        _ => None,
    }
}

/// One decoded keyboard byte in terminal mode.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    /// Goes to the firmware's UART.
    Uart(u8),
    /// Drives the rig.
    Rig(RigAction),
    /// Swallowed (the prefix itself, or an unknown key after it).
    None,
}

/// Splits the terminal's key stream into UART bytes and rig commands.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeyParser {
    armed: bool,
}

impl KeyParser {
    /// Decodes one byte.
    pub fn feed(&mut self, byte: u8) -> Key {
        if !self.armed {
            if byte == PREFIX {
                self.armed = true;
                return Key::None;
            }
            return Key::Uart(byte);
        }
        self.armed = false;
        if byte == PREFIX || byte == b']' {
            return Key::Uart(PREFIX);
        }
        match rig_key(byte) {
            Some(action) => Key::Rig(action),
            None => Key::None,
        }
    }

    /// True after the prefix, while waiting for the rig key.
    pub fn is_armed(&self) -> bool {
        self.armed
    }
}

/// One line of help for terminal mode.
pub const HELP_TERMINAL: &str =
    "Ctrl-] then: 0-5 A0-A5, 8/9 D8/D9, 6/7 A6/A7 +0.1V, ^/& -0.1V, r reset, q quit";

/// One line of help for pty mode (keys on the console, no prefix needed).
pub const HELP_PTY: &str =
    "keys: 0-5 A0-A5, 8/9 D8/D9, 6/7 A6/A7 +0.1V, ^/& -0.1V, r reset, q quit, ? help";

/// What the status line shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct RigView {
    /// Switches A0..A5 held pressed, bits 0..5.
    pub switches: u8,
    /// D8 autostart jumper fitted (pin held low).
    pub d8_low: bool,
    /// D9 out_sense jumper fitted (pin held low).
    pub d9_low: bool,
    /// Output pin levels Y0..Y7, bits 0..7 (1 = high, LED lit).
    pub outputs: u8,
    /// Levels on A6 and A7 in millivolts (0..5000).
    pub analog_mv: [u32; 2],
}

impl RigView {
    /// The rig of `chip` as it is now, with `analog_mv` on A6 and A7.
    pub fn of(chip: &Chip, analog_mv: [u32; 2]) -> RigView {
        RigView {
            switches: (0..6u8)
                .filter(|&n| chip.is_held_low(RigPin::Switch(n)))
                .fold(0, |m, n| m | 1 << n),
            d8_low: chip.is_held_low(RigPin::D8),
            d9_low: chip.is_held_low(RigPin::D9),
            outputs: chip.outputs(),
            analog_mv,
        }
    }
}

/// Millivolts as volts with two decimals (`2.50V`).
pub fn volts(mv: u32) -> String {
    format!("{}.{:02}V", mv / 1000, mv % 1000 / 10)
}

impl RigView {
    /// The status line: a pressed switch shows its number, a lit LED its number,
    /// `-` otherwise; jumpers show `GND` when fitted; the levels on A6 and A7 once either is
    /// above 0 V. Under 80 columns: the hint is left out when it does not fit.
    pub fn status_line(&self, hint: &str) -> String {
        let mut s = String::with_capacity(80);
        s.push_str("SW A0-A5: ");
        for i in 0..6u8 {
            s.push(if self.switches & (1 << i) != 0 {
                char::from(b'0' + i)
            } else {
                '-'
            });
        }
        s.push_str("  D8:");
        s.push_str(if self.d8_low { "GND " } else { "open" });
        s.push_str(" D9:");
        s.push_str(if self.d9_low { "GND " } else { "open" });
        s.push_str("  LED Y0-Y7: ");
        for i in 0..8u8 {
            s.push(if self.outputs & (1 << i) != 0 {
                char::from(b'0' + i)
            } else {
                '-'
            });
        }
        // A bare Nano reads 0 V: the levels appear once the rig has set one.
        if self.analog_mv != [0, 0] {
            s.push_str(&format!(
                "  A6 {} A7 {}",
                volts(self.analog_mv[0]),
                volts(self.analog_mv[1])
            ));
        }
        if !hint.is_empty() && s.len() + 2 + hint.len() < 80 {
            s.push_str("  ");
            s.push_str(hint);
        }
        s
    }
}

/// Follows the firmware's output through VT100 escape sequences, so the virtual Nano can
/// tell when it is safe to slip its own status line in.
#[derive(Clone, Copy, Debug, Default)]
pub struct OutputTracker {
    state: EscState,
    /// The firmware saved the cursor (`ESC 7`) and has not restored it yet: our own
    /// save/restore would overwrite its saved position.
    cursor_saved: bool,
    /// The firmware erased (part of) the display since the last `take_cleared`.
    cleared: bool,
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
enum EscState {
    #[default]
    Ground,
    Esc,
    Csi,
    /// `ESC (`, `ESC )`, `ESC #`: one more byte follows.
    OneMore,
}

impl OutputTracker {
    /// Follows a chunk of firmware output.
    pub fn feed(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.state = match self.state {
                EscState::Ground => {
                    if b == 0x1B {
                        EscState::Esc
                    } else {
                        EscState::Ground
                    }
                }
                EscState::Esc => match b {
                    b'[' => EscState::Csi,
                    b'(' | b')' | b'#' => EscState::OneMore,
                    b'7' => {
                        self.cursor_saved = true;
                        EscState::Ground
                    }
                    b'8' => {
                        self.cursor_saved = false;
                        EscState::Ground
                    }
                    b'c' => {
                        self.cleared = true;
                        self.cursor_saved = false;
                        EscState::Ground
                    }
                    0x1B => EscState::Esc,
                    _ => EscState::Ground,
                },
                EscState::Csi => match b {
                    0x20..=0x3F => EscState::Csi,
                    0x1B => EscState::Esc,
                    _ => {
                        match b {
                            b'J' => self.cleared = true,
                            b's' => self.cursor_saved = true,
                            b'u' => self.cursor_saved = false,
                            _ => {}
                        }
                        EscState::Ground
                    }
                },
                EscState::OneMore => EscState::Ground,
            };
        }
    }

    /// True when our own escape sequences would not break one of the firmware's.
    pub fn can_interject(&self) -> bool {
        self.state == EscState::Ground && !self.cursor_saved
    }

    /// True once after the firmware erased the display (the status line must be redrawn).
    pub fn take_cleared(&mut self) -> bool {
        std::mem::take(&mut self.cleared)
    }
}

/// The bytes that draw `text` on screen row `row` (1-based) without disturbing the
/// firmware's cursor or attributes: save cursor, plain attributes, go, erase, write, restore.
pub fn draw_on_row(row: u16, text: &str) -> Vec<u8> {
    format!("\x1b7\x1b[0m\x1b[{row};1H\x1b[2K{text}\x1b8").into_bytes()
}

/// The bytes that put `text` in the terminal's window title (for terminals under 25 rows).
pub fn draw_in_title(text: &str) -> Vec<u8> {
    format!("\x1b]0;vnano {text}\x07").into_bytes()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prefix_then_digit_toggles_a_switch_and_plain_keys_go_to_the_uart() {
        let mut p = KeyParser::default();
        assert_eq!(p.feed(b'f'), Key::Uart(b'f'));
        assert_eq!(p.feed(PREFIX), Key::None);
        assert!(p.is_armed());
        assert_eq!(p.feed(b'3'), Key::Rig(RigAction::Toggle(RigPin::Switch(3))));
        assert!(!p.is_armed());
        assert_eq!(p.feed(b'3'), Key::Uart(b'3'));
    }

    #[test]
    fn every_rig_key_after_the_prefix() {
        let cases = [
            (b'0', Key::Rig(RigAction::Toggle(RigPin::Switch(0)))),
            (b'5', Key::Rig(RigAction::Toggle(RigPin::Switch(5)))),
            (b'8', Key::Rig(RigAction::Toggle(RigPin::D8))),
            (b'9', Key::Rig(RigAction::Toggle(RigPin::D9))),
            (b'r', Key::Rig(RigAction::Reset)),
            (b'q', Key::Rig(RigAction::Quit)),
            (b'?', Key::Rig(RigAction::Help)),
            (b'6', Key::Rig(RigAction::Analog(6, true))),
            (b'7', Key::Rig(RigAction::Analog(7, true))),
            (b'^', Key::Rig(RigAction::Analog(6, false))),
            (b'&', Key::Rig(RigAction::Analog(7, false))),
            (b'x', Key::None),
            (PREFIX, Key::Uart(PREFIX)),
            (b']', Key::Uart(PREFIX)),
        ];
        for (byte, want) in cases {
            let mut p = KeyParser::default();
            p.feed(PREFIX);
            assert_eq!(p.feed(byte), want, "key {byte:#04x}");
        }
    }

    #[test]
    fn status_line_shows_pressed_switches_jumpers_and_lit_leds() {
        let view = RigView {
            switches: 0b10_0001,
            d8_low: false,
            d9_low: true,
            outputs: 0x81,
            analog_mv: [0, 0],
        };
        let line = view.status_line("");
        assert_eq!(
            line,
            "SW A0-A5: 0----5  D8:open D9:GND   LED Y0-Y7: 0------7"
        );
        let idle = RigView::default().status_line(HELP_TERMINAL);
        assert!(idle.starts_with("SW A0-A5: ------  D8:open D9:open  LED Y0-Y7: --------"));
        assert!(RigView::default().status_line("Ctrl-] ? help").len() < 80);
        assert!(HELP_TERMINAL.len() < 80 && HELP_PTY.len() < 80);
    }

    #[test]
    fn status_line_shows_the_analog_levels_once_set() {
        let view = RigView {
            analog_mv: [2500, 0],
            ..RigView::default()
        };
        let line = view.status_line("Ctrl-] ? help");
        assert_eq!(
            line,
            "SW A0-A5: ------  D8:open D9:open  LED Y0-Y7: --------  A6 2.50V A7 0.00V"
        );
        assert!(line.len() < 80);
        assert_eq!(volts(5000), "5.00V");
        assert_eq!(volts(1234), "1.23V");
    }

    #[test]
    fn tracker_waits_for_the_end_of_an_escape_sequence() {
        let mut t = OutputTracker::default();
        t.feed(b"abc");
        assert!(t.can_interject());
        t.feed(b"\x1b[1");
        assert!(!t.can_interject());
        t.feed(b"2;4");
        assert!(!t.can_interject());
        t.feed(b"H");
        assert!(t.can_interject());
        t.feed(b"\x1b");
        assert!(!t.can_interject());
        t.feed(b"(B");
        assert!(t.can_interject());
    }

    #[test]
    fn tracker_sees_clears_and_the_firmwares_own_cursor_save() {
        let mut t = OutputTracker::default();
        t.feed(b"\x1b[2J\x1b[H");
        assert!(t.take_cleared());
        assert!(!t.take_cleared());
        t.feed(b"\x1b7\x1b[24;1H");
        assert!(!t.can_interject());
        t.feed(b"x\x1b8");
        assert!(t.can_interject());
        t.feed(b"\x1bc");
        assert!(t.take_cleared());
    }

    #[test]
    fn draw_on_row_saves_and_restores_the_cursor() {
        let bytes = draw_on_row(25, "hi");
        assert_eq!(bytes, b"\x1b7\x1b[0m\x1b[25;1H\x1b[2Khi\x1b8");
    }
}
