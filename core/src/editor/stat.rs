//! STAT: the scan-time report of the last run.

use super::*;

impl Editor {
    pub(super) fn stat<B: Board>(&mut self, b: &mut B) {
        let s = self.stats;
        let (min, max) = if s.count == 0 { (0, 0) } else { (s.min, s.max) };
        text::STAT_MIN.send_at(b, ROW_INFO, 1);
        num(b, ScanStats::ticks_to_us(u32::from(min)));
        text::STAT_AVG.send(b);
        // The mean scan period: run time over scans, in µs.
        num(b, stats::per_1000(s.run_ms, s.count));
        text::STAT_MAX.send(b);
        num(b, ScanStats::ticks_to_us(u32::from(max)));
        text::STAT_RATE.send(b);
        num(b, stats::per_1000(s.count, s.run_ms));
        text::STAT_OVERRUNS.send(b);
        let overruns = b.rx_overruns();
        num(b, u32::from(overruns));
        ceol(b);
        self.info = INFO_STAT;
    }
}
