//! RUN mode's Modbus RTU slave (SPEC §13, §17, §18), between scans: carry out a frame closed
//! at its silence on the engine (the core's `PlcMap`) and start its reply at once, then feed
//! the reply to the transmitter a few bytes per visit; and whether the next scan may run
//! (§18's hold, the core's `Hold`, kept in the status). The line's timing and the slave
//! itself are the hardware layer's (`hal/line.rs`); this file has no `unsafe`.
//!
//! The scan comes back for this after the very scan in which the work arose (a frame closed,
//! the transmitter took a byte of the reply), so a reply starts within a scan of its
//! request's silence, whatever the program's length; no visit holds the scan up long.

use utile_core::board::Board;
use utile_core::engine::Engine;
use utile_core::modbus::hold::{Next, HR_SCAN_CONTROL};
use utile_core::modbus::plc::{PlcMap, Status, STATUS_OVERRUN, STATUS_RUNNING};
use utile_core::modbus::plc::{STATUS_STORED, STATUS_WATCHDOG};
use utile_core::modbus::slave::Event;
use utile_core::stats::ScanStats;
use utile_core::store;

use crate::hal::scan::RunState;
use crate::hal::{clock, line, serial, Nano};

/// Timer1 counts (0.5 µs) a visit may go on making reply bytes (0.2 ms): a byte costs a map
/// read and the CRC, a timer's time left or the mean scan time a division (0.13 ms). With
/// the judging before them, no visit holds the scan up 0.45 ms.
const VISIT_TICKS: u16 = clock::t1_us(200);
/// Reply bytes a visit makes whatever it costs: a reply's first three (address, function,
/// byte count or echo) read nothing from the map, and three bytes keep the line busy
/// 1.5 ms, longer than the slowest scan before the next visit.
const MIN_BYTES: u8 = 3;
/// Bytes kept queued ahead of the line (6 ms of it), so that a program whose scans are long
/// never leaves a pause of 1.5 characters inside a reply.
const AHEAD: u8 = 12;

/// The slave's RUN-mode state. `repr(C)`, the count's high word first: the simavr tests
/// find it at `SERVER`'s address to bring a run to its 2³²nd scan.
#[repr(C)]
pub struct Server {
    /// The scan count's high word: how many times its low 16 bits (`RunState::scans`) have
    /// wrapped. It wraps too, at 2³² scans (registers 4–5 and 70–71 count modulo 2³²).
    wraps: u16,
    /// Input register 0's bits.
    flags: u16,
    status: Status,
    /// The ms clock when the mean's run time starts: at RUN, and again each time the scan
    /// count wraps to 0, so the mean is always that run time over the scans it counted.
    start_ms: u32,
    overruns_at_start: u16,
    /// A reply is being made.
    pending: bool,
    /// Its first byte has gone to the transmitter (the driver enable is up).
    started: bool,
}

impl Server {
    /// RUN starts: the address from EEPROM, the status bits (`by_watchdog`: the last reset
    /// was the watchdog's; `stored`: EEPROM holds a valid program, as the editor knows it),
    /// the program's fingerprint, the line switched to Modbus.
    #[inline(never)]
    pub fn begin(&mut self, eng: &Engine, board: &mut Nano, by_watchdog: bool, stored: bool) {
        let mut flags = STATUS_RUNNING;
        if by_watchdog {
            flags |= STATUS_WATCHDOG;
        }
        if stored {
            flags |= STATUS_STORED;
        }
        // Field by field, in place: the rest of the status is written at every request
        // before it is read.
        self.wraps = 0;
        self.flags = flags;
        self.status.start(&eng.prog.uf);
        // Free, bit 5 clear. No steps are left: a RUN ends only at a `/`, which ends any
        // hold (`visit`), or at a reset, which clears static RAM; the lease starts with the
        // frame that holds.
        self.status.hold.bits = 0;
        self.start_ms = board.now_ms();
        self.overruns_at_start = board.rx_overruns();
        // No reply (`started` is set with each reply).
        self.pending = false;
        line::serve(store::slave_address(board));
    }

    /// RUN ends: the line goes back to the terminal.
    pub fn end(&mut self) {
        line::serve(0);
    }

    /// Whether the terminal must wait: a master talked to this slave within the last 3 s,
    /// or a frame is on its way (its reply must not queue behind a display).
    pub fn quiet(&self, board: &mut Nano) -> bool {
        line::busy(board.now_ms())
    }

    /// The scan count's low 16 bits wrapped: 65,536 more scans. At 2³² the count wraps to
    /// 0, and the mean's run time starts again with it.
    pub fn wrapped(&mut self, board: &mut Nano) {
        self.wraps = self.wraps.wrapping_add(1);
        if self.wraps == 0 {
            self.start_ms = board.now_ms();
        }
    }

    /// STAT's figures as they are now (run time and scans since RUN, or since the scan
    /// count last wrapped).
    pub fn stats(&self, st: &RunState, now_ms: u32) -> ScanStats {
        ScanStats {
            min: st.min,
            max: st.max,
            count: (u32::from(self.wraps) << 16) | u32::from(st.scans),
            run_ms: now_ms.wrapping_sub(self.start_ms),
        }
    }

    /// One visit between scans: a frame closed at its silence carried out and its reply
    /// started, or the reply fed as the transmit ring has room. Whatever is left wants the
    /// scan back after the next scan. Returns true when a request for this slave was carried
    /// out: the terminal's screen is to be redrawn whole once the master is quiet (SPEC §13).
    pub fn visit(&mut self, eng: &mut Engine, board: &mut Nano, st: &RunState) -> bool {
        let start = board.stats_ticks();
        let mut replied = false;
        if line::take_frame_end() {
            let now = board.now_ms();
            self.refresh(eng, board, st, now);
            let mut map = PlcMap {
                eng: &mut *eng,
                b: &mut *board,
                status: &mut self.status,
            };
            match line::judge(&mut map, now) {
                Event::Slash => {
                    serial::inject(b'/');
                    // The terminal's break key ends a hold of a program with KEY, which then
                    // stops at its next KEY; of any other it changes nothing (SPEC §18).
                    if eng.prog.stops_at_key() {
                        self.status.hold.write(HR_SCAN_CONTROL, 0);
                    }
                }
                Event::Reply => {
                    self.pending = true;
                    self.started = false;
                    replied = true;
                    // A valid request for this slave: a hold's lease starts again (SPEC §18;
                    // a broadcast does not renew it).
                    self.status.hold.heard(now);
                }
                Event::Broadcast | Event::None | Event::Dropped => {}
            }
        }
        if self.pending {
            self.send(eng, board, start);
        }
        // A reply waiting for the line: at the next END. A reply being fed comes back by
        // itself each time the transmitter takes a byte.
        if self.pending && !self.started {
            line::again();
        }
        replied
    }

    /// Make reply bytes while the transmit ring has room, at least [`MIN_BYTES`] and then
    /// until the visit that began at Timer1 count `start` has lasted [`VISIT_TICKS`].
    fn send(&mut self, eng: &mut Engine, board: &mut Nano, start: u16) {
        // The terminal's bytes not yet sent are dropped; the ones already in the USART must
        // leave the line before the driver enable rises.
        if !self.started {
            if !line::reply_start() {
                return;
            }
            self.started = true;
        }
        let mut map = PlcMap {
            eng: &mut *eng,
            b: &mut *board,
            status: &mut self.status,
        };
        let mut made = 0u8;
        while made < MIN_BYTES || map.b.stats_ticks().wrapping_sub(start) < VISIT_TICKS {
            made += 1;
            if serial::tx_room() <= serial::TX_SIZE as u8 - AHEAD {
                return;
            }
            match line::reply_byte(&mut map) {
                Some(b) => serial::tx(b),
                None => {
                    line::reply_queued();
                    self.pending = false;
                    return;
                }
            }
        }
    }

    /// Between two scans: whether the next scan runs (SPEC §18, the core's `Hold::next`).
    pub fn next_scan(&mut self, board: &mut Nano) -> Next {
        self.status.hold.next(board)
    }

    /// The figures the input registers report, as they are now, and the snapshot's
    /// registers of this scan (SPEC §17).
    fn refresh(&mut self, eng: &Engine, board: &mut Nano, st: &RunState, now: u32) {
        let overruns = board.rx_overruns();
        if overruns != self.overruns_at_start {
            self.flags |= STATUS_OVERRUN;
        }
        let stats = self.stats(st, now);
        self.status
            .refresh(self.flags, &stats, overruns, line::dropped());
        self.status.take_scan(eng, board);
    }
}
