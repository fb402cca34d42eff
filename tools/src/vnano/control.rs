//! `--control PATH`: the rig worked from another program over a Unix socket, one JSON
//! object a line in each direction. A request names what to change —
//! `{"press": 0}` / `{"release": 0}` (switch A0..A5), `{"a6": 2.5}` / `{"a7": 1.0}` (volts,
//! 0..5), `{"d8": true}` / `{"d9": false}` (jumper fitted), `{"reset": true}`, or `{}` to
//! ask — and every request is answered with the rig's state after it:
//! `{"switches": [..6], "pins": [..6], "d8": .., "d9": .., "a6": V, "a7": V, "outputs":
//! [..8]}` (switches and jumpers `true` when pressed or fitted, the chip's A0..A5 pins as it
//! reads them, a pressed switch pulling its pin low; outputs Y0..Y7 as the pins show them), with
//! `"error"` naming what was refused. The Nano of a single run only: `"nano"` other than 1
//! is refused.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};
use utile_kit::simavr::{Chip, RigPin, VCC_MV};

/// Longest request line kept (a longer one is refused whole).
const MAX_LINE: usize = 1024;

/// The control socket and its clients.
pub struct Control {
    listener: UnixListener,
    path: PathBuf,
    clients: Vec<Client>,
}

/// One connected client and its unfinished line.
struct Client {
    stream: UnixStream,
    line: Vec<u8>,
}

/// What a request asks of the session besides the chip itself.
#[derive(Debug, Default, PartialEq, Eq)]
pub struct Asked {
    /// Reset the chip (warm reset, as the rig's `r` key).
    pub reset: bool,
    /// A request came (the status line shows the change).
    pub handled: bool,
}

impl Control {
    /// Listen at `path` (a stale socket file there is replaced).
    pub fn bind(path: &Path) -> Result<Control, String> {
        let _ = std::fs::remove_file(path);
        let listener =
            UnixListener::bind(path).map_err(|e| format!("--control {}: {e}", path.display()))?;
        listener
            .set_nonblocking(true)
            .map_err(|e| format!("--control {}: {e}", path.display()))?;
        Ok(Control {
            listener,
            path: path.to_path_buf(),
            clients: Vec::new(),
        })
    }

    /// Take new clients and their complete lines, carry each request out on `nano` and the
    /// session's analog levels `analog_mv` (A6, A7), and answer it. Never waits.
    pub fn poll(&mut self, nano: &mut Chip, analog_mv: &mut [u32; 2]) -> Asked {
        while let Ok((stream, _)) = self.listener.accept() {
            if stream.set_nonblocking(true).is_ok() {
                self.clients.push(Client {
                    stream,
                    line: Vec::new(),
                });
            }
        }
        let mut asked = Asked::default();
        self.clients.retain_mut(|c| {
            let mut buf = [0u8; 512];
            loop {
                match c.stream.read(&mut buf) {
                    Ok(0) => return false,
                    Ok(n) => c.line.extend_from_slice(&buf[..n]),
                    Err(e) if e.kind() == ErrorKind::WouldBlock => break,
                    Err(e) if e.kind() == ErrorKind::Interrupted => {}
                    Err(_) => return false,
                }
            }
            while let Some(end) = c.line.iter().position(|&b| b == b'\n') {
                let line: Vec<u8> = c.line.drain(..=end).collect();
                asked.handled = true;
                let answer = request(&line, nano, analog_mv, &mut asked);
                let mut text = answer.to_string();
                text.push('\n');
                // The socket is non-blocking: a client that reads nothing loses answers.
                if c.stream.write_all(text.as_bytes()).is_err() {
                    return false;
                }
            }
            if c.line.len() > MAX_LINE {
                c.line.clear();
            }
            true
        });
        asked
    }
}

impl Drop for Control {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// One request line carried out; the rig's state (with `"error"` when refused).
fn request(line: &[u8], nano: &mut Chip, analog_mv: &mut [u32; 2], asked: &mut Asked) -> Value {
    let error = match serde_json::from_slice::<Value>(line) {
        Ok(Value::Object(fields)) => apply(&fields, nano, analog_mv, asked).err(),
        Ok(_) => Some("a request is one JSON object, e.g. {\"press\": 0}".to_string()),
        Err(e) => Some(format!("not JSON: {e}")),
    };
    let mut state = state(nano, analog_mv);
    if let (Some(why), Value::Object(m)) = (error, &mut state) {
        m.insert("error".into(), Value::String(why));
    }
    state
}

/// One checked change of a request, made once every field has been checked.
type Change = Box<dyn FnOnce(&mut Chip, &mut [u32; 2], &mut Asked)>;

/// The request's fields on the rig, checked first: nothing changes when one is wrong.
fn apply(
    fields: &Map<String, Value>,
    nano: &mut Chip,
    analog_mv: &mut [u32; 2],
    asked: &mut Asked,
) -> Result<(), String> {
    let mut changes: Vec<Change> = Vec::new();
    for (key, value) in fields {
        match key.as_str() {
            "nano" => {
                if value.as_u64() != Some(1) {
                    return Err(format!("one Nano runs here (nano 1), not {value}"));
                }
            }
            "press" | "release" => {
                let n = value
                    .as_u64()
                    .filter(|&n| n <= 5)
                    .ok_or_else(|| format!("{key}: switches are 0..5 (A0..A5), not {value}"))?
                    as u8;
                let low = key == "press";
                changes.push(Box::new(move |c, _, _| c.hold_low(RigPin::Switch(n), low)));
            }
            "a6" | "a7" => {
                let volts = value
                    .as_f64()
                    .filter(|v| (0.0..=f64::from(VCC_MV) / 1000.0).contains(v))
                    .ok_or_else(|| format!("{key}: a level is 0..5 volts, not {value}"))?;
                let (pin, i) = if key == "a6" { (6u8, 0) } else { (7u8, 1) };
                let mv = (volts * 1000.0).round() as u32;
                changes.push(Box::new(move |c, a, _| {
                    a[i] = mv;
                    c.set_analog_mv(pin, mv);
                }));
            }
            "d8" | "d9" => {
                let fitted = value
                    .as_bool()
                    .ok_or_else(|| format!("{key}: true (fitted) or false, not {value}"))?;
                let pin = if key == "d8" { RigPin::D8 } else { RigPin::D9 };
                changes.push(Box::new(move |c, _, _| c.hold_low(pin, fitted)));
            }
            "reset" => {
                if value.as_bool() == Some(true) {
                    changes.push(Box::new(|_, _, asked| asked.reset = true));
                }
            }
            other => {
                return Err(format!(
                    "unknown field {other}: press, release, a6, a7, d8, d9, reset, nano"
                ))
            }
        }
    }
    for change in changes {
        change(nano, analog_mv, asked);
    }
    Ok(())
}

/// The rig's state as the answers give it.
pub fn state(nano: &Chip, analog_mv: &[u32; 2]) -> Value {
    let switches: Vec<bool> = (0..6)
        .map(|n| nano.is_held_low(RigPin::Switch(n)))
        .collect();
    let outputs = nano.outputs();
    let leds: Vec<bool> = (0..8).map(|n| outputs & (1 << n) != 0).collect();
    let levels = nano.input_levels();
    let pins: Vec<bool> = (0..6).map(|n| levels & (1 << n) != 0).collect();
    json!({
        "switches": switches,
        "pins": pins,
        "d8": nano.is_held_low(RigPin::D8),
        "d9": nano.is_held_low(RigPin::D9),
        "a6": f64::from(analog_mv[0]) / 1000.0,
        "a7": f64::from(analog_mv[1]) / 1000.0,
        "outputs": leds,
    })
}
