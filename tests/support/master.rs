//! A Modbus master on the real image's line (`simavr_modbus`, `simavr_hold`): the line timed
//! as a wire at 19200 8N1 in both directions (`RxPacing::Line`), requests sent with the
//! silences a test chooses, replies read with the cycle of each stop bit, and D10 (the RS-485
//! driver enable) sampled all along.

use super::chip::{Board, Rig, CYCLES_PER_MS};
use utile_core::engine::Program;
use utile_core::store;
use utile_kit::modbus;
use utile_kit::sim::SimBoard;
use utile_kit::simavr::{frame_cycles, RxPacing};

/// One character at 19200 8N1, in CPU cycles.
pub fn char_cycles() -> u64 {
    frame_cycles(19_200)
}

/// The slave's address when EEPROM holds none.
pub const ADDRESS: u8 = 1;

/// The board with `prog` stored in EEPROM, booted; `d8`: the autostart jumper fitted.
pub fn stored(prog: &Program, d8: bool) -> Board {
    let mut b = SimBoard::new();
    store::store(prog, &mut b).expect("STORE");
    let eeprom: &'static [u8] = Box::leak(b.eeprom.into_boxed_slice());
    Board::boot_with(Rig {
        d8,
        d9: false,
        eeprom: Some(eeprom),
    })
}

/// A chip running `prog` (autostarted from EEPROM), its line timed as a wire.
pub struct Line {
    pub nano: Board,
    /// (cycle, D10 level) at every change seen.
    pub de: Vec<(u64, bool)>,
}

impl Line {
    pub fn new(prog: &Program) -> Self {
        let mut nano = stored(prog, true);
        nano.chip.set_rx_pacing(RxPacing::Line { baud: 19_200 });
        // The RUN screen is drawn first (about 0.4 s of line time): a master talks after it.
        nano.run_ms(1_000);
        nano.take_output();
        Line {
            nano,
            de: Vec::new(),
        }
    }

    pub fn de_level(&self) -> bool {
        self.nano.chip.drives_high('B', 2)
    }

    /// Run `cycles`, sampling D10 every 1/32 ms.
    pub fn run(&mut self, cycles: u64) {
        let step = CYCLES_PER_MS / 32;
        let end = self.nano.chip.cycle() + cycles;
        while self.nano.chip.cycle() < end {
            // The chip itself: the board helper would take the UART's output.
            self.nano.chip.run_for(step);
            let level = self.de_level();
            if self.de.last().map(|&(_, l)| l) != Some(level) {
                self.de.push((self.nano.chip.cycle(), level));
            }
        }
    }

    /// Send `frame` after `idle` cycles of silence; returns the cycle its last stop bit ends
    /// (the request goes down the line while the chip runs).
    pub fn send(&mut self, idle: u64, frame: &[u8]) -> u64 {
        self.nano.chip.send_after(idle, frame);
        let now = self.nano.chip.cycle();
        now + idle + frame.len() as u64 * char_cycles()
    }

    /// A request (CRC appended) and the reply, with the cycle of each reply byte's stop bit.
    pub fn transact(&mut self, pdu: &[u8]) -> (u64, Vec<(u8, u64)>) {
        let frame = modbus::frame(ADDRESS, pdu);
        self.nano.chip.take_output_timed();
        let end = self.send(4 * char_cycles(), &frame);
        // The request goes out first (a long one takes several ms).
        let now = self.nano.chip.cycle();
        self.run(end.saturating_sub(now));
        (end, self.collect())
    }

    /// Everything the slave sends until the line has been quiet for 10 ms.
    pub fn collect(&mut self) -> Vec<(u8, u64)> {
        let mut got = Vec::new();
        let mut quiet = 0;
        while quiet < 10 {
            self.run(CYCLES_PER_MS);
            let more = self.nano.chip.take_output_timed();
            if more.is_empty() {
                quiet += 1;
            } else {
                quiet = 0;
                got.extend(more);
            }
        }
        got
    }
}

/// A reply's bytes without their cycles.
pub fn bytes(reply: &[(u8, u64)]) -> Vec<u8> {
    reply.iter().map(|&(b, _)| b).collect()
}

/// The reply's PDU after checking address and CRC.
pub fn pdu(reply: &[(u8, u64)]) -> Vec<u8> {
    let r = bytes(reply);
    modbus::reply_pdu(ADDRESS, &r)
        .unwrap_or_else(|e| panic!("{e}: {r:02X?}"))
        .to_vec()
}

/// FC04 of `qty` input registers from `start` through the real image.
pub fn read_input(line: &mut Line, start: u16, qty: u16) -> Vec<u16> {
    let [s0, s1] = start.to_be_bytes();
    let [q0, q1] = qty.to_be_bytes();
    let (_, reply) = line.transact(&[0x04, s0, s1, q0, q1]);
    let pdu = pdu(&reply);
    assert_eq!(pdu[0], 0x04, "FC04 {start} x {qty}: {pdu:02X?}");
    modbus::registers(&pdu)
}
