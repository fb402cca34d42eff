//! RUN mode's Modbus RTU slave (SPEC §13), between scans: judge a frame once its silence has
//! passed, carry the request out on the engine (the core's `PlcMap`), and feed the reply to
//! the transmitter a few bytes per visit, so no visit holds the scan up for long.

use avr_device::interrupt;
use utile_core::board::Board;
use utile_core::engine::Engine;
use utile_core::modbus::plc::{PlcMap, Status, STATUS_OVERRUN, STATUS_RUNNING};
use utile_core::modbus::plc::{STATUS_STORED, STATUS_WATCHDOG};
use utile_core::modbus::slave::Event;
use utile_core::stats::ScanStats;
use utile_core::store;

use crate::hal::scan::RunState;
use crate::hal::{serial, Nano};

/// Reply bytes made per visit at most (a map read and the CRC each), so a visit stays below
/// the 0.5 ms a scan may wait.
const BYTES_PER_VISIT: u8 = 6;
/// Bytes kept queued ahead of the line (6 ms of it): visits come every 16 scans, 2.2 ms apart
/// for a program of 200 lines, and a reply must not pause 1.5 characters.
const AHEAD: u8 = 12;

/// What the RUN loop must do after a visit.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum After {
    /// Nothing.
    Nothing,
    /// A lone `/` came: the break key (KEY takes it from the receive ring).
    BreakKey,
    /// The master wrote presets or set-points: reseal the program kept over a warm reset.
    Written,
}

/// The slave's RUN-mode state.
pub struct Server {
    address: u8,
    /// Input register 0's bits.
    flags: u16,
    status: Status,
    start_ms: u32,
    overruns_at_start: u16,
    /// A reply is being made.
    pending: bool,
    /// Its first byte has gone to the transmitter (the driver enable is up).
    started: bool,
    /// A request came: the warm-reset seal is renewed at the next visit.
    reseal: bool,
}

impl Server {
    /// RUN starts: the address from EEPROM, the status bits (`stored`: EEPROM holds a valid
    /// program, as the editor knows it), the line switched to Modbus.
    pub fn begin(eng: &Engine, board: &mut Nano, mcusr: u8, stored: bool) -> Self {
        let mut flags = STATUS_RUNNING;
        // WDRF: the last reset was the watchdog's (0 after a boot loader that clears MCUSR).
        if mcusr & 0x08 != 0 {
            flags |= STATUS_WATCHDOG;
        }
        if stored {
            flags |= STATUS_STORED;
        }
        let mut status = Status::default();
        status.start(&eng.prog.uf);
        let server = Server {
            address: store::slave_address(board),
            flags,
            status,
            start_ms: board.now_ms(),
            overruns_at_start: board.rx_overruns(),
            pending: false,
            started: false,
            reseal: false,
        };
        serial::serve_modbus(true);
        server
    }

    /// RUN ends: the line goes back to the terminal.
    pub fn end(&mut self) {
        serial::serve_modbus(false);
    }

    /// Whether a master talked to this slave within the last 3 s (the terminal is quiet).
    pub fn master_active(&self, board: &mut Nano) -> bool {
        let now = board.now_ms();
        interrupt::free(|cs| {
            // SAFETY: the closure does not re-enter LINE.
            unsafe { serial::LINE.with(cs, |l| l.slave.master_active(now)) }
        })
    }

    /// One visit between scans, one job per visit so that none holds the scan up for long:
    /// a finished frame judged and carried out, or a few reply bytes made, or (the reply
    /// queued) the warm-reset seal renewed.
    pub fn visit(
        &mut self,
        eng: &mut Engine,
        board: &mut Nano,
        st: &RunState,
        wraps: u16,
    ) -> After {
        let mut after = After::Nothing;
        if serial::take_frame_end() {
            self.refresh(eng, board, st, wraps);
            let now = board.now_ms();
            let (address, status) = (self.address, &self.status);
            let event = interrupt::free(|cs| {
                let mut map = PlcMap {
                    eng: &mut *eng,
                    b: &mut *board,
                    status,
                };

                // SAFETY: the map reaches the ticker, the ADC and EEPROM, never LINE.
                unsafe { serial::LINE.with(cs, |l| l.slave.end(address, &mut map, now)) }
            });
            match event {
                Event::Slash => {
                    serial::inject(b'/');
                    after = After::BreakKey;
                }
                Event::Reply => {
                    self.pending = true;
                    self.started = false;
                    // Any request may have written: the seal is renewed (0.14 ms) anyway.
                    self.reseal = true;
                }
                Event::Broadcast => self.reseal = true,
                Event::None | Event::Dropped => {}
            }
            return after;
        }
        if self.pending {
            self.send(eng, board);
        } else if self.reseal {
            // After the reply is queued: the master waits for the reply, not for the seal.
            self.reseal = false;
            after = After::Written;
        }
        after
    }

    /// Make up to [`BYTES_PER_VISIT`] reply bytes, as the transmit ring has room.
    fn send(&mut self, eng: &mut Engine, board: &mut Nano) {
        // A RUN display still going out must leave the line before the driver enable rises.
        if !self.started {
            if !serial::reply_start() {
                return;
            }
            self.started = true;
        }
        let status = &self.status;
        for _ in 0..BYTES_PER_VISIT {
            if serial::tx_room() <= serial::TX_SIZE as u8 - AHEAD {
                return;
            }
            let byte = interrupt::free(|cs| {
                let mut map = PlcMap {
                    eng: &mut *eng,
                    b: &mut *board,
                    status,
                };

                // SAFETY: the map never reaches LINE.
                unsafe { serial::LINE.with(cs, |l| l.slave.next_byte(&mut map)) }
            });
            match byte {
                Some(b) => serial::tx(b),
                None => {
                    serial::reply_queued();
                    self.pending = false;
                    return;
                }
            }
        }
    }

    /// The figures the input registers report, as they are now, and the snapshot's
    /// registers of this scan (SPEC §17).
    fn refresh(&mut self, eng: &Engine, board: &mut Nano, st: &RunState, wraps: u16) {
        let overruns = board.rx_overruns();
        if overruns != self.overruns_at_start {
            self.flags |= STATUS_OVERRUN;
        }
        let dropped = interrupt::free(|cs| {
            // SAFETY: the closure does not re-enter LINE.
            unsafe { serial::LINE.with(cs, |l| l.slave.dropped()) }
        });
        let stats = ScanStats {
            min: st.min,
            max: st.max,
            count: (u32::from(wraps) << 16) | u32::from(st.scans),
            run_ms: board.now_ms().wrapping_sub(self.start_ms),
        };
        self.status.refresh(self.flags, &stats, overruns, dropped);
        self.status.take_scan(eng, board);
    }
}
