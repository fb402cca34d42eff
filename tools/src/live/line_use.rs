//! Line time over a sliding window: the share of the last seconds the line, or one uTile's
//! transactions on it, kept busy.

use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// Line time used, by when, over the last `window`.
#[derive(Clone, Debug)]
pub struct LineUse {
    window: Duration,
    spans: VecDeque<(Instant, Duration)>,
}

impl LineUse {
    /// Nothing used yet, counted over `window`.
    pub fn new(window: Duration) -> Self {
        LineUse {
            window,
            spans: VecDeque::new(),
        }
    }

    /// Notes `time` on the line at `now`, forgets what is older than the window, and returns
    /// the share of the window used (0..1).
    pub fn add(&mut self, now: Instant, time: Duration) -> f64 {
        self.spans.push_back((now, time));
        while self
            .spans
            .front()
            .is_some_and(|(at, _)| now.duration_since(*at) > self.window)
        {
            self.spans.pop_front();
        }
        let used: Duration = self.spans.iter().map(|(_, d)| *d).sum();
        (used.as_secs_f64() / self.window.as_secs_f64()).min(1.0)
    }

    /// The line time noted last (zero before any).
    pub fn last(&self) -> Duration {
        self.spans.back().map(|(_, d)| *d).unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_share_counts_only_the_window() {
        let t0 = Instant::now();
        let mut u = LineUse::new(Duration::from_secs(2));
        assert_eq!(u.last(), Duration::ZERO);
        assert!((u.add(t0, Duration::from_millis(500)) - 0.25).abs() < 1e-9);
        let later = t0 + Duration::from_millis(1500);
        assert!((u.add(later, Duration::from_millis(500)) - 0.5).abs() < 1e-9);
        // Past the window the first span is forgotten.
        let much_later = t0 + Duration::from_millis(2600);
        assert!((u.add(much_later, Duration::from_millis(100)) - 0.3).abs() < 1e-9);
        assert_eq!(u.last(), Duration::from_millis(100));
        assert_eq!(u.add(much_later, Duration::from_secs(9)), 1.0);
    }
}
