//! `--control PATH`: the rig worked from another program over a Unix socket, one JSON
//! object a line in each direction. A request names what to change —
//! `{"press": 0}` / `{"release": 0}` (switch A0..A5), `{"a6": 2.5}` / `{"a7": 1.0}` (volts,
//! 0..5), `{"d8": true}` / `{"d9": false}` (jumper fitted), `{"reset": true}`, or `{}` to
//! ask — and every request is answered with the rig's state after it:
//! `{"switches": [..6], "pins": [..6], "d8": .., "d9": .., "a6": V, "a7": V, "outputs":
//! [..8], "seconds": S}` (switches and jumpers `true` when pressed or fitted, the chip's A0..A5
//! pins as it reads them, a pressed switch pulling its pin low; outputs Y0..Y7 as the pins
//! show them; the simulated time since power-up, so a client can time what it sees), with
//! `"error"` naming what was refused, and `"nano"` (which Nano) and `"nanos"` (how many).
//!
//! On a bus (`--bus N`) a request may name its Nano: `{"nano": 2, "press": 0}`. Nanos are
//! numbered 1..N, as their slave addresses (Nano 2 answers Modbus at address 2); without
//! `"nano"` a request works Nano 1 (the only one of a single run). A Nano that is not there
//! is answered `{"error": "no Nano 5 here: …", "nanos": N}` and nothing changes.
//!
//! A request is a [`RigRequest`], the one struct `utile live --rig`'s client (`live/rig.rs`)
//! sends too. A line longer than [`MAX_LINE`] is discarded to its newline, none of it carried
//! out, and answered with an error. PATH is taken only when nothing is there or a socket no
//! program listens on (left by an earlier run): any other file is refused, never deleted.

use std::io::{ErrorKind, Read, Write};
use std::os::unix::fs::FileTypeExt;
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use utile_kit::simavr::{Chip, Reset, RigPin, VCC_MV};

use super::error::VnanoError;

/// Longest request line kept, newline left out (a longer one is refused whole).
pub const MAX_LINE: usize = 1024;

/// One request on the control socket: what to change, each field left out when unchanged;
/// `{}` asks. Sent by `utile live --rig` (`live/rig.rs`) and read here, so both ends have one
/// list of fields.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigRequest {
    /// The Nano of a bus, 1..N (its slave address); left out: Nano 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nano: Option<u8>,
    /// Press switch 0..5 (A0..A5).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub press: Option<u8>,
    /// Release switch 0..5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub release: Option<u8>,
    /// A6's level, volts 0..5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a6: Option<f64>,
    /// A7's level, volts 0..5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub a7: Option<f64>,
    /// Jumper D8 fitted (`true`) or removed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d8: Option<bool>,
    /// Jumper D9 fitted (`true`) or removed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub d9: Option<bool>,
    /// `true`: a warm reset, as the rig's `r` key.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reset: Option<bool>,
}

impl RigRequest {
    /// The request a JSON object makes, or why not in words, naming the field at fault.
    /// Always read from an object: serde would take a JSON array as the fields by position.
    pub fn from_object(fields: &serde_json::Map<String, Value>) -> Result<RigRequest, String> {
        RigRequest::deserialize(Value::Object(fields.clone())).map_err(|e| {
            // serde names no field for a wrong value: try each alone to say which.
            let field = fields.iter().find(|(k, v)| {
                let alone = serde_json::Map::from_iter([((*k).clone(), (*v).clone())]);
                RigRequest::deserialize(Value::Object(alone)).is_err()
            });
            match field {
                Some((k, _)) if !e.to_string().starts_with("unknown field") => format!("{k}: {e}"),
                _ => e.to_string(),
            }
        })
    }
}

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
    /// The line under way grew past [`MAX_LINE`]: its bytes are dropped to its newline.
    discarding: bool,
}

/// The Nanos a control socket works: the one of a single run, or each of a bus.
pub trait Nanos {
    /// How many (1 without a bus).
    fn count(&self) -> usize;
    /// Nano `i` (0-based) and its levels on A6 and A7, mV.
    fn nano(&mut self, i: usize) -> (&mut Chip, &mut [u32; 2]);
}

/// The one Nano of a single run and its levels on A6 and A7 (mV).
pub struct One<'a>(pub &'a mut Chip, pub &'a mut [u32; 2]);

impl Nanos for One<'_> {
    fn count(&self) -> usize {
        1
    }

    fn nano(&mut self, _: usize) -> (&mut Chip, &mut [u32; 2]) {
        (self.0, self.1)
    }
}

impl Control {
    /// Listen at `path`: nothing there, or a socket no program listens on (left by an earlier
    /// run, replaced). Any other file there is refused and left as it is.
    pub fn bind(path: &Path) -> Result<Control, VnanoError> {
        let failed = VnanoError::file("--control", path);
        match std::fs::symlink_metadata(path) {
            Ok(m) if m.file_type().is_socket() => {
                if UnixStream::connect(path).is_ok() {
                    return Err(VnanoError::ControlInUse(path.to_path_buf()));
                }
                std::fs::remove_file(path).map_err(VnanoError::file("--control", path))?;
            }
            Ok(_) => return Err(VnanoError::ControlNotSocket(path.to_path_buf())),
            Err(e) if e.kind() == ErrorKind::NotFound => {}
            Err(e) => return Err(failed(e)),
        }
        let failed = VnanoError::file("--control", path);
        let listener = UnixListener::bind(path).map_err(failed)?;
        listener
            .set_nonblocking(true)
            .map_err(VnanoError::file("--control", path))?;
        Ok(Control {
            listener,
            path: path.to_path_buf(),
            clients: Vec::new(),
        })
    }

    /// Take new clients and their complete lines, carry each request out on the Nano of
    /// `nanos` it names, and answer it. Never waits; true when a request came (the status
    /// line shows the change).
    pub fn poll(&mut self, nanos: &mut dyn Nanos) -> bool {
        while let Ok((stream, _)) = self.listener.accept() {
            if stream.set_nonblocking(true).is_ok() {
                self.clients.push(Client {
                    stream,
                    line: Vec::new(),
                    discarding: false,
                });
            }
        }
        let mut handled = false;
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
                handled = true;
                let too_long = std::mem::take(&mut c.discarding) || end > MAX_LINE;
                let answer = if too_long {
                    json!({
                        "error": format!(
                            "a request line is at most {MAX_LINE} bytes: this one was \
                             discarded whole, nothing changed"
                        ),
                        "nanos": nanos.count(),
                    })
                } else {
                    request(&line, nanos)
                };
                let mut text = answer.to_string();
                text.push('\n');
                // The socket is non-blocking: a client that reads nothing loses answers.
                if c.stream.write_all(text.as_bytes()).is_err() {
                    return false;
                }
            }
            if c.line.len() > MAX_LINE {
                // Dropped to its newline, which is answered with the error.
                c.line.clear();
                c.discarding = true;
            }
            true
        });
        handled
    }
}

impl Drop for Control {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// One request line carried out; the state of the Nano it named (with `"error"` when
/// refused).
fn request(line: &[u8], nanos: &mut dyn Nanos) -> Value {
    let fields = match serde_json::from_slice::<Value>(line) {
        Ok(Value::Object(fields)) => Ok(fields),
        Ok(_) => Err("a request is one JSON object, e.g. {\"press\": 0}".to_string()),
        Err(e) => Err(format!("not JSON: {e}")),
    };
    // Which Nano first (a Nano that is not there is answered without a state), then the
    // request's fields as the typed struct.
    let count = nanos.count();
    let i = match fields.as_ref().map(|f| which(f.get("nano"), count)) {
        Ok(Ok(i)) => i,
        Ok(Err(why)) => return json!({"error": why, "nanos": count}),
        Err(_) => 0,
    };
    let (chip, analog_mv) = nanos.nano(i);
    let error = match fields.and_then(|f| RigRequest::from_object(&f)) {
        Ok(r) => apply(&r, chip, analog_mv).err(),
        Err(why) => Some(why),
    };
    let mut state = state(chip, analog_mv);
    if let Value::Object(m) = &mut state {
        m.insert("nano".into(), json!(i + 1));
        m.insert("nanos".into(), json!(count));
        if let Some(why) = error {
            m.insert("error".into(), Value::String(why));
        }
    }
    state
}

/// The Nano (0-based) a request's `"nano"` names among `count`: the first when left out.
fn which(nano: Option<&Value>, count: usize) -> Result<usize, String> {
    let Some(value) = nano else {
        return Ok(0);
    };
    match value.as_u64() {
        Some(n @ 1..) if n as usize <= count => Ok(n as usize - 1),
        _ if count == 1 => Err(format!(
            "one Nano runs here (nano 1, or leave nano out), not {value}"
        )),
        _ => Err(format!(
            "no Nano {value} here: nano is 1..{count}, as their slave addresses on the bus"
        )),
    }
}

/// A switch's number checked: 0..5.
fn switch(key: &str, n: Option<u8>) -> Result<Option<u8>, String> {
    match n {
        Some(n) if n > 5 => Err(format!("{key}: switches are 0..5 (A0..A5), not {n}")),
        n => Ok(n),
    }
}

/// A level checked, in mV: 0..5 V.
fn level(key: &str, volts: Option<f64>) -> Result<Option<u32>, String> {
    match volts {
        Some(v) if !(0.0..=f64::from(VCC_MV) / 1000.0).contains(&v) => {
            Err(format!("{key}: a level is 0..5 volts, not {v}"))
        }
        v => Ok(v.map(|v| (v * 1000.0).round() as u32)),
    }
}

/// The request on the rig, every field checked first: nothing changes when one is wrong.
fn apply(r: &RigRequest, nano: &mut Chip, analog_mv: &mut [u32; 2]) -> Result<(), String> {
    let levels = [level("a6", r.a6)?, level("a7", r.a7)?];
    let press = switch("press", r.press)?;
    let release = switch("release", r.release)?;
    for (i, mv) in levels.into_iter().enumerate() {
        if let Some(mv) = mv {
            analog_mv[i] = mv;
            nano.set_analog_mv(6 + i as u8, mv);
        }
    }
    for (pin, fitted) in [(RigPin::D8, r.d8), (RigPin::D9, r.d9)] {
        if let Some(fitted) = fitted {
            nano.hold_low(pin, fitted);
        }
    }
    if let Some(n) = press {
        nano.hold_low(RigPin::Switch(n), true);
    }
    if let Some(n) = release {
        nano.hold_low(RigPin::Switch(n), false);
    }
    if r.reset == Some(true) {
        nano.reset(Reset::External);
    }
    Ok(())
}

/// The rig's state of one Nano as the answers give it.
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
        "seconds": nano.seconds(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn object(text: &str) -> serde_json::Map<String, Value> {
        match serde_json::from_str(text).unwrap() {
            Value::Object(m) => m,
            other => panic!("{other}"),
        }
    }

    #[test]
    fn a_request_is_written_and_read_by_its_field_names() {
        assert_eq!(serde_json::to_string(&RigRequest::default()).unwrap(), "{}");
        let press = RigRequest {
            nano: Some(2),
            press: Some(0),
            ..RigRequest::default()
        };
        let text = serde_json::to_string(&press).unwrap();
        assert_eq!(text, r#"{"nano":2,"press":0}"#);
        assert_eq!(RigRequest::from_object(&object(&text)).unwrap(), press);
        let e = RigRequest::from_object(&object(r#"{"a6": 1.0, "press": 300}"#)).unwrap_err();
        assert!(e.starts_with("press: "), "{e}");
        let e = RigRequest::from_object(&object(r#"{"d8": 1}"#)).unwrap_err();
        assert!(e.starts_with("d8: "), "{e}");
        let e = RigRequest::from_object(&object(r#"{"prss": 1}"#)).unwrap_err();
        assert!(e.starts_with("unknown field `prss`"), "{e}");
    }
}
