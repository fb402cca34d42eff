//! STAT: the scan-time report of the last run.

use super::*;

impl Editor {
    pub(super) fn stat<B: Board>(&mut self, b: &mut B) {
        let s = self.stats;
        let (min, mean, max) = if s.count == 0 {
            (0, 0, 0)
        } else {
            (u32::from(s.min), s.mean(), u32::from(s.max))
        };
        let rate = if s.run_ms == 0 {
            0
        } else if s.count < u32::MAX / 1000 {
            stats::div(s.count * 1000, s.run_ms)
        } else {
            stats::div(s.count, stats::div(s.run_ms, 1000).max(1))
        };
        goto(b, ROW_INFO, 1);
        text::STAT_MIN.send(b);
        num(b, ScanStats::ticks_to_us(min));
        text::STAT_AVG.send(b);
        num(b, ScanStats::ticks_to_us(mean));
        text::STAT_MAX.send(b);
        num(b, ScanStats::ticks_to_us(max));
        text::STAT_RATE.send(b);
        num(b, rate);
        text::STAT_OVERRUNS.send(b);
        let overruns = b.rx_overruns();
        num(b, u32::from(overruns));
        ceol(b);
        self.info = true;
    }
}
