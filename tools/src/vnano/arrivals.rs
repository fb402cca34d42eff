//! A client's bytes at the simulated time they came. The virtual Nano reads its pty between
//! steps of the simulation; when the simulation runs behind the wall clock, bytes that came
//! apart (a Modbus request 2 ms after the last reply, the next request after its own reply)
//! would reach the chip back to back and the silences between frames would collapse. So
//! each chunk is stamped with its wall-clock arrival and goes to the chip at the simulated
//! time that keeps its distance from the last thing on the link (a chunk the client sent,
//! or bytes the chip sent it): the master's gaps survive a slow simulation, and a master
//! need not stretch them. A gap is kept up to [`MAX_GAP`], beyond every silence the firmware
//! tells apart (3.5 characters end a frame, 1.5 break one): a longer pause means nothing
//! more to it, and kept whole it would be replayed at the simulation's slower pace, holding
//! the next request back while its master's time-out runs. When the simulation keeps up,
//! the time a chunk is due has already come and it goes at once.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

use utile_kit::simavr::F_CPU;

/// The longest gap kept: beyond Modbus's 3.5 characters at 19200 baud (1.8 ms) with room.
pub const MAX_GAP: Duration = Duration::from_millis(5);

/// Chunks from the client waiting for their simulated time.
#[derive(Debug, Default)]
pub struct Arrivals {
    /// (cycle due, bytes), in the order they came.
    waiting: VecDeque<(u64, Vec<u8>)>,
    /// The last thing on the link on both clocks: wall time and cycle.
    anchor: Option<(Instant, u64)>,
}

/// Cycles in `d` of simulated time.
fn cycles(d: Duration) -> u64 {
    (d.as_nanos() * u128::from(F_CPU) / 1_000_000_000) as u64
}

impl Arrivals {
    /// `bytes` came from the client at wall time `at`, the simulation being at cycle `now`.
    pub fn came(&mut self, bytes: Vec<u8>, at: Instant, now: u64) {
        if bytes.is_empty() {
            return;
        }
        let after_anchor = self.anchor.map_or(now, |(wall, cycle)| {
            cycle + cycles(at.saturating_duration_since(wall).min(MAX_GAP))
        });
        let after_queue = self.waiting.back().map_or(0, |&(c, _)| c);
        let due = after_anchor.max(now).max(after_queue);
        self.anchor = Some((at, due));
        self.waiting.push_back((due, bytes));
    }

    /// Bytes went to the client at wall time `at`, the last one's stop bit ending at `cycle`.
    pub fn sent(&mut self, at: Instant, cycle: u64) {
        self.anchor = Some((at, cycle));
    }

    /// The bytes whose time has come at cycle `now`, in order.
    pub fn due(&mut self, now: u64) -> Vec<u8> {
        let mut out = Vec::new();
        while let Some((at, _)) = self.waiting.front() {
            if *at > now {
                break;
            }
            if let Some((_, bytes)) = self.waiting.pop_front() {
                out.extend(bytes);
            }
        }
        out
    }

    /// How many cycles after `now` the next waiting chunk is due (a step ends there), if one
    /// waits.
    pub fn next_in(&self, now: u64) -> Option<u64> {
        self.waiting.front().map(|&(at, _)| at.saturating_sub(now))
    }

    /// Drops what waits (the chip was reset by the client's open: it was the old run's).
    pub fn clear(&mut self) {
        self.waiting.clear();
        self.anchor = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const MS: u64 = F_CPU / 1000;

    #[test]
    fn a_gap_after_the_chips_reply_is_kept_when_the_simulation_lags() {
        let t0 = Instant::now();
        let mut a = Arrivals::default();
        // The reply's last byte ended at 100 ms; the client wrote back 2 ms (wall) later,
        // when the simulation was still at 100.5 ms.
        a.sent(t0, 100 * MS);
        a.came(vec![1, 4], t0 + Duration::from_millis(2), 100 * MS + MS / 2);
        assert_eq!(a.next_in(100 * MS + MS / 2), Some(MS + MS / 2));
        assert!(a.due(101 * MS).is_empty());
        assert_eq!(a.due(102 * MS), [1, 4]);
        assert_eq!(a.next_in(102 * MS), None);
    }

    #[test]
    fn when_the_simulation_keeps_up_bytes_go_at_once() {
        let t0 = Instant::now();
        let mut a = Arrivals::default();
        a.sent(t0, 100 * MS);
        a.came(vec![9], t0 + Duration::from_millis(2), 103 * MS);
        assert_eq!(a.due(103 * MS), [9]);
    }

    #[test]
    fn chunks_keep_their_order_and_distance_and_a_long_pause_is_cut_short() {
        let t0 = Instant::now();
        let mut a = Arrivals::default();
        a.came(vec![1], t0, 0);
        a.came(vec![2], t0 + Duration::from_millis(3), MS);
        a.came(vec![3], t0 + Duration::from_secs(10), 2 * MS);
        assert_eq!(a.due(0), [1]);
        assert!(a.due(2 * MS).is_empty());
        assert_eq!(a.due(3 * MS), [2]);
        assert!(a.due(7 * MS).is_empty());
        assert_eq!(a.due(8 * MS), [3]);
        a.came(vec![4], t0, 0);
        a.clear();
        assert_eq!(a.next_in(0), None);
    }
}
