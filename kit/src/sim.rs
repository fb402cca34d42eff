//! A simulated board for the host: the same [`Ticker`] as the firmware's 1 ms interrupt,
//! pins you set by hand, a terminal you read as bytes, and a 1 KiB EEPROM.
//!
//! Tests, `utile sim` and scenario checks drive it with simulated time:
//! `board.advance_ms(n)` runs the 1 ms tick n times, `run_for(engine, ms)` also scans.

use std::collections::VecDeque;
use std::vec::Vec;

use utile_core::analog::{Analog, CHANNELS};
use utile_core::board::Board;
use utile_core::engine::{Engine, Flow, Program};
use utile_core::store::{self, StoreError};
use utile_core::ticker::Ticker;

/// Size of the simulated EEPROM.
pub const EEPROM_SIZE: usize = 1024;

/// How the byte being written is left when the power fails in the middle of its write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Tear {
    /// The write never started: the old value stays.
    Old,
    /// Erased (0xFF) but not yet programmed.
    Erased,
    /// Some bits programmed: old AND new.
    Partial,
}

/// EEPROM faults for storage tests (the chip's EEPROM when things go wrong).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EepromFault {
    /// Every write works.
    #[default]
    None,
    /// The power fails after `writes` more byte writes; the write under way then is left
    /// as `tear` says, and every later write is lost.
    PowerFail {
        /// Byte writes that still complete.
        writes: u32,
        /// What the interrupted write leaves.
        tear: Tear,
    },
    /// The power is off: writes are lost.
    PoweredOff,
    /// Writes to this address are lost (a worn-out cell).
    Stuck(u16),
}

/// A host board with simulated time.
#[derive(Clone, Debug)]
pub struct SimBoard {
    /// The 1 ms tick state (time, debouncer, clocks), exactly as on the chip.
    pub ticker: Ticker,
    /// Raw levels on A0..A5 (1 = open / high, as with the pull-ups).
    pub raw_inputs: u8,
    /// Output image last written to the pins (before out_sense).
    pub outputs: u8,
    /// Every change of the output pins: (ms, new image).
    pub output_log: Vec<(u32, u8)>,
    /// Bytes waiting to be received by the firmware.
    pub rx_queue: VecDeque<u8>,
    /// Everything sent to the terminal.
    pub tx_log: Vec<u8>,
    /// Received bytes reported lost (`rx_overruns`, the firmware's overrun count).
    pub rx_lost: u16,
    /// Free room reported by `tx_room` (the real buffer drains at 19200 baud).
    pub tx_room_value: u8,
    /// EEPROM contents (erased = 0xFF).
    pub eeprom: Vec<u8>,
    /// Count of EEPROM bytes actually written (wear).
    pub eeprom_writes: u32,
    /// Injected EEPROM faults.
    pub eeprom_fault: EepromFault,
    /// Times the watchdog was fed.
    pub watchdog_feeds: u32,
    /// EEPROM byte writes since the last watchdog feed.
    pub writes_since_feed: u32,
    /// The most EEPROM byte writes seen between two watchdog feeds.
    pub max_writes_between_feeds: u32,
    /// Raw levels on A6 and A7, 0..1023 (the ADC's counts).
    pub analog_levels: [u16; CHANNELS],
    /// The analog sampler, fed one conversion per ms as the chip's ADC interrupt does.
    pub analog: Analog,
}

/// The EEPROM of a Nano that ran STORE of `prog` `times` times from an erased EEPROM (the
/// core's own STORE, so the slots, CRC and sequence numbers are the firmware's): what tests,
/// the bench and the virtual Nano start a chip with.
pub fn stored_eeprom(prog: &Program, times: usize) -> Result<Vec<u8>, StoreError> {
    let mut board = SimBoard::new();
    for _ in 0..times {
        store::store(prog, &mut board)?;
    }
    Ok(board.eeprom)
}

impl Default for SimBoard {
    fn default() -> Self {
        Self::new()
    }
}

impl SimBoard {
    /// All inputs open (high), outputs off, erased EEPROM, time 0.
    pub fn new() -> Self {
        Self {
            ticker: Ticker::new(0x3F),
            raw_inputs: 0x3F,
            outputs: 0,
            output_log: Vec::new(),
            rx_queue: VecDeque::new(),
            tx_log: Vec::new(),
            rx_lost: 0,
            tx_room_value: 255,
            eeprom: std::vec![0xFF; EEPROM_SIZE],
            eeprom_writes: 0,
            eeprom_fault: EepromFault::None,
            watchdog_feeds: 0,
            writes_since_feed: 0,
            max_writes_between_feeds: 0,
            analog_levels: [0; CHANNELS],
            analog: Analog::new(),
        }
    }

    /// One ms of the board: the tick, and one ADC conversion.
    fn tick(&mut self) {
        self.ticker.tick(self.raw_inputs);
        let c = usize::from(self.analog.channel() - utile_core::analog::FIRST_CHANNEL);
        self.analog.sample(self.analog_levels[c & 1]);
    }

    /// Set the level on A6 (`n` = 6) or A7 (`n` = 7) in ADC counts, 0..1023.
    pub fn set_analog(&mut self, n: u8, counts: u16) {
        self.analog_levels[usize::from(n.wrapping_sub(6) & 1)] = counts.min(1023);
    }

    /// Let `ms` milliseconds pass without scanning.
    pub fn advance_ms(&mut self, ms: u32) {
        for _ in 0..ms {
            self.tick();
        }
    }

    /// Set the raw level of input `n` (true = high/open, false = pressed to ground).
    pub fn set_input(&mut self, n: u8, high: bool) {
        if high {
            self.raw_inputs |= 1 << n;
        } else {
            self.raw_inputs &= !(1 << n);
        }
    }

    /// Press a normally-open push-button on input n (pulls it low).
    pub fn press(&mut self, n: u8) {
        self.set_input(n, false);
    }

    /// Release the push-button on input n.
    pub fn release(&mut self, n: u8) {
        self.set_input(n, true);
    }

    /// Queue bytes as if typed on the terminal.
    pub fn type_bytes(&mut self, bytes: &[u8]) {
        self.rx_queue.extend(bytes.iter().copied());
    }

    /// Run the program for `ms` milliseconds, `scans_per_ms` scans each millisecond.
    /// Returns `Flow::Break` early if KEY saw `/`.
    pub fn run_for(&mut self, engine: &mut Engine, ms: u32, scans_per_ms: u32) -> Flow {
        for _ in 0..ms {
            for _ in 0..scans_per_ms {
                if engine.scan(self) == Flow::Break {
                    return Flow::Break;
                }
            }
            self.tick();
        }
        Flow::End
    }

    /// Output bit n as last written to the pins.
    pub fn output(&self, n: u8) -> bool {
        self.outputs & (1 << n) != 0
    }
}

impl Board for SimBoard {
    fn inputs(&mut self) -> u8 {
        self.ticker.inputs.level()
    }
    fn take_leading(&mut self, mask: u8) -> bool {
        self.ticker.inputs.take_leading(mask)
    }
    fn take_trailing(&mut self, mask: u8) -> bool {
        self.ticker.inputs.take_trailing(mask)
    }
    fn toggles(&mut self) -> u8 {
        self.ticker.inputs.toggles()
    }
    fn resync_inputs(&mut self) {
        let raw = self.raw_inputs;
        self.ticker.inputs.resync(raw);
    }
    fn clocks(&mut self) -> u8 {
        self.ticker.clocks()
    }
    fn now_ms(&mut self) -> u32 {
        self.ticker.now_ms()
    }
    fn write_outputs(&mut self, py: u8) {
        if py != self.outputs || self.output_log.is_empty() {
            self.output_log.push((self.ticker.now_ms(), py));
        }
        self.outputs = py;
    }
    fn rx(&mut self) -> Option<u8> {
        self.rx_queue.pop_front()
    }
    fn tx(&mut self, byte: u8) {
        self.tx_log.push(byte);
    }
    fn tx_room(&mut self) -> u8 {
        self.tx_room_value
    }
    fn rx_pending(&mut self) -> bool {
        !self.rx_queue.is_empty()
    }
    fn rx_overruns(&mut self) -> u16 {
        self.rx_lost
    }
    fn eeprom_read(&mut self, addr: u16) -> u8 {
        self.eeprom.get(usize::from(addr)).copied().unwrap_or(0xFF)
    }
    fn eeprom_update(&mut self, addr: u16, value: u8) {
        let Some(cell) = self.eeprom.get_mut(usize::from(addr)) else {
            return;
        };
        let old = *cell;
        if old == value {
            return;
        }
        match &mut self.eeprom_fault {
            EepromFault::None => {}
            EepromFault::Stuck(a) if *a == addr => return,
            EepromFault::Stuck(_) => {}
            EepromFault::PoweredOff => return,
            EepromFault::PowerFail { writes, tear } => {
                if *writes > 0 {
                    *writes -= 1;
                } else {
                    *cell = match tear {
                        Tear::Old => old,
                        Tear::Erased => 0xFF,
                        Tear::Partial => old & value,
                    };
                    self.eeprom_fault = EepromFault::PoweredOff;
                    return;
                }
            }
        }
        *cell = value;
        self.eeprom_writes += 1;
        self.writes_since_feed += 1;
        self.max_writes_between_feeds = self.max_writes_between_feeds.max(self.writes_since_feed);
    }
    fn feed_watchdog(&mut self) {
        self.watchdog_feeds += 1;
        self.writes_since_feed = 0;
    }
    fn analog_bits(&mut self) -> u8 {
        self.analog.bits()
    }
    fn analog_reading(&mut self, channel: u8) -> u16 {
        self.analog.reading(channel)
    }
    fn set_points(&mut self, sp: [u16; CHANNELS]) {
        self.analog.set_points(sp);
    }
}
