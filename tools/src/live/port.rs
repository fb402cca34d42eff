//! The serial port the live view owns: 19200 baud 8N1 without flow control (the `serialport`
//! crate, as `utile push`), and on a USB serial adapter a request for low latency. An FTDI
//! chip holds received bytes up to its latency timer (16 ms by default) before it sends them
//! to the PC, which would add up to 16 ms to every reply; Linux lets root (or a udev rule)
//! set it to 1 ms in sysfs.

use std::path::{Path, PathBuf};
use std::time::Duration;

use serialport::TTYPort;

use super::rtu::BAUD;

/// The port cannot be opened.
#[derive(Debug, thiserror::Error)]
#[error("cannot open {path}: {source} (is the cable in? is another program using the port?)")]
pub struct OpenError {
    /// The port's path.
    pub path: String,
    /// The serial driver's reason.
    #[source]
    pub source: serialport::Error,
}

/// Opens `path` at 19200 baud, 8N1, no flow control. On a Nano the open resets the chip
/// (DTR): its boot loader runs first, then uTile starts.
pub fn open(path: &str) -> Result<TTYPort, OpenError> {
    serialport::new(path, BAUD)
        .data_bits(serialport::DataBits::Eight)
        .parity(serialport::Parity::None)
        .stop_bits(serialport::StopBits::One)
        .flow_control(serialport::FlowControl::None)
        .timeout(Duration::from_millis(1))
        .open_native()
        .map_err(|source| OpenError {
            path: path.to_string(),
            source,
        })
}

/// The sysfs file of a USB serial adapter's latency timer for the device `path` (following
/// symlinks such as /dev/serial/by-id/...), when it has one.
fn latency_file(path: &str) -> Option<PathBuf> {
    let real = std::fs::canonicalize(path).ok()?;
    let name = real.file_name()?.to_str()?.to_string();
    let file = Path::new("/sys/bus/usb-serial/devices")
        .join(name)
        .join("latency_timer");
    file.is_file().then_some(file)
}

/// Asks a USB serial adapter for its lowest latency (1 ms); what happened, in words, for the
/// console (`None`: the port has no latency timer, such as a pty or a CH340).
pub fn low_latency(path: &str) -> Option<String> {
    let file = latency_file(path)?;
    let now: u32 = std::fs::read_to_string(&file).ok()?.trim().parse().ok()?;
    if now <= 1 {
        return Some(format!("{path}: the adapter's latency timer is {now} ms"));
    }
    Some(match std::fs::write(&file, "1") {
        Ok(()) => format!("{path}: the adapter's latency timer set from {now} ms to 1 ms"),
        Err(e) => format!(
            "{path}: the adapter's latency timer stays at {now} ms ({e}); every reply may \
             wait that long. As root: echo 1 > {}",
            file.display()
        ),
    })
}
