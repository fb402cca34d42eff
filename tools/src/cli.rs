//! What the command lines share (clap): the typed values (seconds, volts, socket addresses),
//! `--wait` (parsed here once for `utile push`, `pull` and `live`), and the log every binary
//! starts with (`RUST_LOG` selects, e.g. `RUST_LOG=debug`; warnings by default).
//!
//! A value parser returns the value or a message saying what is expected; clap puts it
//! after the flag's name and exits with status 2.

use std::net::SocketAddr;
use std::time::Duration;

/// A value on the command line that is not what its flag takes: the message says what is.
#[derive(Debug, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct BadValue(pub String);

/// `--wait SECS`: the longest wait for uTile after the port opens.
#[derive(clap::Args, Clone, Copy, Debug, PartialEq)]
pub struct BootWait {
    /// The longest wait for uTile after the port opens, in seconds 0..60 (a Nano's boot
    /// loader waits about 1.4 s after the port-open reset)
    #[arg(long = "wait", value_name = "SECS", default_value = "2.5", value_parser = seconds_0_60)]
    pub boot_wait: Duration,
}

/// Seconds 0..60 (a trailing `s` is allowed).
pub fn seconds_0_60(text: &str) -> Result<Duration, BadValue> {
    text.trim_end_matches('s')
        .parse::<f64>()
        .ok()
        .filter(|s| (0.0..=60.0).contains(s))
        .map(Duration::from_secs_f64)
        .ok_or_else(|| BadValue(format!("takes seconds (0..60), not '{text}'")))
}

/// Seconds of simulated time, more than 0.
pub fn positive_seconds(text: &str) -> Result<f64, BadValue> {
    match text.trim_end_matches('s').parse::<f64>() {
        Ok(secs) if secs > 0.0 && secs.is_finite() => Ok(secs),
        Ok(_) => Err(BadValue(format!("must be more than 0 seconds: {text}"))),
        Err(_) => Err(BadValue(format!("not a number of seconds: {text}"))),
    }
}

/// A level in volts, 0..5 (a trailing `V` is allowed), as whole millivolts.
pub fn volts(text: &str) -> Result<u32, BadValue> {
    let number = text.trim_end_matches(['V', 'v']);
    match number.parse::<f64>() {
        Ok(v) if (0.0..=5.0).contains(&v) => Ok((v * 1000.0).round() as u32),
        _ => Err(BadValue(format!("a level is 0..5 volts, not {text}"))),
    }
}

/// `ADDR:PORT`, or a bare port on 127.0.0.1.
pub fn socket_address(text: &str) -> Result<SocketAddr, BadValue> {
    if let Ok(port) = text.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    text.parse().map_err(|_| {
        BadValue(format!(
            "takes ADDR:PORT (e.g. 127.0.0.1:8080) or a port, not '{text}'"
        ))
    })
}

/// Starts the log on standard error: `RUST_LOG` selects what is shown (default: warnings
/// and errors). Called once, first thing in each binary's `main`.
pub fn start_log() {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn"));
    // A second call (tests calling a `main`) keeps the first subscriber.
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn values_are_checked() {
        let says = |e: BadValue, what: &str| assert!(e.0.contains(what), "{e}");
        assert_eq!(seconds_0_60("1.5s"), Ok(Duration::from_millis(1500)));
        says(seconds_0_60("61").unwrap_err(), "0..60");
        assert_eq!(volts("0.333V"), Ok(333));
        says(volts("5.1").unwrap_err(), "0..5 volts");
        assert!(volts("-1").is_err());
        assert_eq!(positive_seconds("2.5"), Ok(2.5));
        says(positive_seconds("0").unwrap_err(), "more than 0");
        says(positive_seconds("abc").unwrap_err(), "not a number");
        assert_eq!(socket_address("0").unwrap().to_string(), "127.0.0.1:0");
        assert_eq!(socket_address("0.0.0.0:80").unwrap().port(), 80);
        assert!(socket_address("nowhere").is_err());
    }
}
