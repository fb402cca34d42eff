//! The serial port to a uTile: 19200 baud 8N1 through the `serialport` crate, with
//! everything received kept so that the session can look for the firmware's texts.

use std::io::Write;
use std::time::{Duration, Instant};

use serialport::SerialPort;

/// uTile's terminal speed (SPEC §8).
pub const BAUD: u32 = 19_200;

/// How long one read waits for a byte.
pub const POLL: Duration = Duration::from_millis(20);

/// A failure of the port itself; its cause (the system's words) is its source.
#[derive(Debug, thiserror::Error)]
pub enum PortError {
    /// The port cannot be opened (no such device, no permission, in use).
    #[error("cannot open {path}")]
    Open {
        /// The port's path.
        path: String,
        /// Why.
        #[source]
        source: serialport::Error,
    },
    /// Sending failed (the adapter was unplugged?).
    #[error("writing to the port")]
    Write(#[source] std::io::Error),
    /// Receiving failed (the adapter was unplugged?).
    #[error("reading from the port")]
    Read(#[source] std::io::Error),
    /// The port's read time-out cannot be set.
    #[error("setting the port's time-out")]
    Timeout(#[source] serialport::Error),
}

/// An open port and the transcript of what came in.
pub struct Port {
    port: Box<dyn SerialPort>,
    /// Every byte received since the port was opened.
    pub seen: Vec<u8>,
}

impl Port {
    /// Opens `path` at 19200 baud, 8N1, no flow control. On a Nano the open resets the chip
    /// (DTR), so the boot loader runs first.
    pub fn open(path: &str) -> Result<Port, PortError> {
        let port = serialport::new(path, BAUD)
            .data_bits(serialport::DataBits::Eight)
            .parity(serialport::Parity::None)
            .stop_bits(serialport::StopBits::One)
            .flow_control(serialport::FlowControl::None)
            .timeout(POLL)
            .open()
            .map_err(|source| PortError::Open {
                path: path.into(),
                source,
            })?;
        Ok(Port {
            port,
            seen: Vec::new(),
        })
    }

    /// A port another owner opened (`utile live`'s line lends it for a send), read with
    /// the same short polls.
    pub fn wrap(mut port: Box<dyn SerialPort>) -> Result<Port, PortError> {
        port.set_timeout(POLL).map_err(PortError::Timeout)?;
        Ok(Port {
            port,
            seen: Vec::new(),
        })
    }

    /// Sends `bytes` and waits until the system has taken them.
    pub fn send(&mut self, bytes: &[u8]) -> Result<(), PortError> {
        self.port
            .write_all(bytes)
            .and_then(|()| self.port.flush())
            .map_err(PortError::Write)
    }

    /// One read of up to a poll's time; whether anything came.
    fn pump(&mut self) -> Result<bool, PortError> {
        let mut buf = [0u8; 512];
        match self.port.read(&mut buf) {
            Ok(0) => Ok(false),
            Ok(n) => {
                self.seen.extend_from_slice(&buf[..n]);
                Ok(true)
            }
            Err(e) if e.kind() == std::io::ErrorKind::TimedOut => Ok(false),
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => Ok(false),
            Err(e) => Err(PortError::Read(e)),
        }
    }

    /// Reads until one of `needles` appears after offset `from` (at most `timeout`).
    /// Returns which one and the offset just past it.
    pub fn wait_for(
        &mut self,
        from: usize,
        needles: &[&[u8]],
        timeout: Duration,
    ) -> Result<Option<(usize, usize)>, PortError> {
        let deadline = Instant::now() + timeout;
        loop {
            let hay = self.seen.get(from..).unwrap_or(&[]);
            // The earliest match wins: it is what the firmware said first.
            let found = needles
                .iter()
                .enumerate()
                .filter_map(|(i, n)| find(hay, n).map(|at| (at, i, at + n.len())))
                .min();
            if let Some((_, i, end)) = found {
                return Ok(Some((i, from + end)));
            }
            if Instant::now() >= deadline {
                return Ok(None);
            }
            self.pump()?;
        }
    }

    /// Reads until nothing has come for `quiet` (or `max` has passed); whether anything came.
    pub fn settle(&mut self, quiet: Duration, max: Duration) -> Result<bool, PortError> {
        let start = self.seen.len();
        let deadline = Instant::now() + max;
        let mut last = Instant::now();
        while Instant::now() < deadline && last.elapsed() < quiet {
            if self.pump()? {
                last = Instant::now();
            }
        }
        Ok(self.seen.len() > start)
    }
}

/// Position of `needle` in `hay`.
pub fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() {
        return Some(0);
    }
    hay.windows(needle.len()).position(|w| w == needle)
}

/// Position of the last `needle` in `hay`.
pub fn find_last(hay: &[u8], needle: &[u8]) -> Option<usize> {
    if needle.is_empty() || needle.len() > hay.len() {
        return None;
    }
    hay.windows(needle.len()).rposition(|w| w == needle)
}

#[cfg(test)]
mod tests {
    use super::{find, find_last};

    #[test]
    fn find_gives_the_first_position() {
        assert_eq!(find(b"abcabc", b"bc"), Some(1));
        assert_eq!(find(b"abc", b"x"), None);
        assert_eq!(find(b"", b"x"), None);
        assert_eq!(find_last(b"abcabc", b"bc"), Some(4));
        assert_eq!(find_last(b"a", b"abc"), None);
    }
}
