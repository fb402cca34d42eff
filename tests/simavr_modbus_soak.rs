//! Soak (SPEC §13, issue 16): ten simulated minutes of a master polling every table of the
//! REAL image at line rate, with noise frames, other slaves' requests and bad CRCs mixed in.
//! The program's outputs stay right, every valid request is answered correctly, every bad
//! frame is counted as dropped, and EEPROM does not change.
//!
//! Needs `out/m328-nano-utile.elf` (`cargo fw`). About two minutes of CPU (BENCHMARKS.md,
//! "The test loop").

mod support;

use support::chip::{Board, Rig, CYCLES_PER_MS};
use utile_kit::listing;
use utile_kit::modbus;
use utile_kit::rng::Rng;
use utile_kit::simavr::{frame_cycles, RxPacing};

const ADDRESS: u8 = 1;
/// Simulated time of the soak.
const SOAK_MS: u64 = 10 * 60 * 1000;

struct Master {
    nano: Board,
    rng: Rng,
}

impl Master {
    fn char_cycles() -> u64 {
        frame_cycles(19_200)
    }

    /// Send `frame` after 4 characters of silence and run until `expect` reply bytes came
    /// (or 20 ms more passed); the reply.
    fn exchange(&mut self, frame: &[u8], expect: usize) -> Vec<u8> {
        let c = Self::char_cycles();
        self.nano.chip.send_after(4 * c, frame);
        let end = self.nano.chip.cycle() + (4 + frame.len() as u64) * c;
        self.nano.chip.run_for(end - self.nano.chip.cycle());
        let mut got = Vec::new();
        let deadline = self.nano.chip.cycle() + (expect as u64 + 2) * c + 20 * CYCLES_PER_MS;
        while self.nano.chip.cycle() < deadline {
            self.nano.chip.run_for(CYCLES_PER_MS / 4);
            got.extend(self.nano.chip.take_output());
            if expect > 0 && got.len() >= expect {
                // The line is free again after the reply's last byte.
                self.nano.chip.run_for(2 * c);
                break;
            }
        }
        got
    }

    fn request(&mut self, pdu: &[u8], expect: usize) -> Vec<u8> {
        let reply = self.exchange(&modbus::frame(ADDRESS, pdu), expect);
        assert_eq!(reply.len(), expect, "reply to {pdu:02X?}: {reply:02X?}");
        modbus::reply_pdu(ADDRESS, &reply)
            .unwrap_or_else(|e| panic!("{e}: {reply:02X?}"))
            .to_vec()
    }

    /// A broken frame: random noise, another slave's request, or a bad CRC. No answer.
    fn broken(&mut self) {
        let kind = self.rng.below(3);
        let mut frame = match kind {
            0 => {
                let len = 2 + self.rng.below(20) as usize;
                (0..len).map(|_| self.rng.byte()).collect::<Vec<u8>>()
            }
            1 => modbus::frame(2 + self.rng.below(200) as u8, &[0x03, 0, 0, 0, 4]),
            _ => modbus::with_wrong_crc(
                &[ADDRESS, 0x04, 0, 0, 0, 8],
                1 + self.rng.below(0xFFFE) as u16,
            ),
        };
        if kind == 0 && frame.len() > 3 {
            // Random bytes that happen to carry a good CRC would be a real frame: break it.
            if modbus::crc_ok(&frame) {
                let n = frame.len();
                frame[n - 1] ^= 1;
            }
        }
        let reply = self.exchange(&frame, 0);
        assert!(reply.is_empty(), "no answer to {frame:02X?}: {reply:02X?}");
    }
}

#[test]
fn ten_minutes_of_polling_with_noise_keep_the_program_and_the_slave_right() {
    // Y0 follows CLKA (0.4 s period), Y1 is A0 inverted, Y2 is U0 (the master's coil 8).
    let prog = listing::commands(&[
        "CLKA.", ".Y0", "A0.", "!", ".Y1", "U0.", ".Y2", "KEY", "END",
    ]);
    let eeprom = support::chip::stored(&prog);
    let mut nano = Board::boot_with(Rig {
        d8: true,
        d9: false,
        eeprom: Some(eeprom),
    });
    nano.chip.set_rx_pacing(RxPacing::Line { baud: 19_200 });
    nano.run_ms(1_000);
    nano.take_output();
    let ee_before = nano.eeprom();
    let mut m = Master {
        nano,
        rng: Rng(0x50AC),
    };
    let start = m.nano.chip.cycle();
    let (mut answered, mut broken, mut clka_changes) = (0u32, 0u32, 0u32);
    let mut last_y0 = m.nano.outputs() & 1;
    let mut u0 = false;
    let mut pressed = false;
    while m.nano.chip.cycle() - start < SOAK_MS * CYCLES_PER_MS {
        match m.rng.below(8) {
            0 => {
                let r = m.request(&[0x01, 0, 0, 0, 24], 5 + 3);
                let y = m.nano.outputs();
                assert_eq!(r[2] & 0b110, y & 0b110, "coils Y1, Y2 as the pins");
            }
            1 => {
                let r = m.request(&[0x02, 0, 0, 0, 6], 5 + 1);
                assert_eq!(r[2] & 1, u8::from(!pressed), "discrete input A0");
            }
            2 => {
                let r = m.request(&[0x03, 0, 0, 0, 26], 5 + 52);
                assert_eq!(r[1], 52);
            }
            3 => {
                let r = m.request(&[0x04, 0, 0, 0, 8], 5 + 16);
                let dropped = u16::from_be_bytes([r[16], r[17]]);
                assert_eq!(u32::from(dropped), broken, "every broken frame counted");
            }
            4 => {
                u0 = !u0;
                let v = if u0 { 0xFF } else { 0 };
                m.request(&[0x05, 0, 8, v, 0], 8);
            }
            5 => {
                pressed = !pressed;
                m.nano.switch(0, pressed);
                m.broken();
                broken += 1;
                continue;
            }
            _ => {
                m.broken();
                broken += 1;
                continue;
            }
        }
        answered += 1;
        let y = m.nano.outputs();
        assert_eq!(y >> 1 & 1, u8::from(pressed), "Y1 follows A0");
        assert_eq!(y >> 2 & 1, u8::from(u0), "Y2 follows the master's U0");
        if y & 1 != last_y0 {
            clka_changes += 1;
            last_y0 = y & 1;
        }
    }
    println!("soak: {answered} answered, {broken} broken frames, Y0 changed {clka_changes} times");
    assert!(answered > 5_000, "{answered} requests answered");
    assert!(
        clka_changes > 500,
        "Y0 kept following CLKA: {clka_changes} changes"
    );
    assert_eq!(m.nano.eeprom(), ee_before, "EEPROM unchanged");
}
