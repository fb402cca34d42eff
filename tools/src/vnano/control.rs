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

use std::io::{ErrorKind, Read, Write};
use std::os::unix::net::{UnixListener, UnixStream};
use std::path::{Path, PathBuf};

use serde_json::{json, Map, Value};
use utile_kit::simavr::{Chip, Reset, RigPin, VCC_MV};

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
    /// Listen at `path` (a stale socket file there is replaced).
    pub fn bind(path: &Path) -> Result<Control, super::error::VnanoError> {
        let failed = |source| super::error::VnanoError::File {
            flag: "--control",
            path: path.to_path_buf(),
            source,
        };
        // A socket file left by an earlier run would make the bind fail; none is fine too.
        let _ = std::fs::remove_file(path);
        let listener = UnixListener::bind(path).map_err(failed)?;
        listener.set_nonblocking(true).map_err(failed)?;
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
                let answer = request(&line, nanos);
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
    let count = nanos.count();
    let i = match fields.as_ref().map(|f| which(f.get("nano"), count)) {
        Ok(Ok(i)) => i,
        Ok(Err(why)) => return json!({"error": why, "nanos": count}),
        Err(_) => 0,
    };
    let (chip, analog_mv) = nanos.nano(i);
    let error = match fields {
        Ok(fields) => apply(&fields, chip, analog_mv).err(),
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

/// One checked change of a request, made once every field has been checked.
type Change = Box<dyn FnOnce(&mut Chip, &mut [u32; 2])>;

/// The request's fields on the rig, checked first: nothing changes when one is wrong.
fn apply(
    fields: &Map<String, Value>,
    nano: &mut Chip,
    analog_mv: &mut [u32; 2],
) -> Result<(), String> {
    let mut changes: Vec<Change> = Vec::new();
    for (key, value) in fields {
        match key.as_str() {
            // Checked by `which`.
            "nano" => {}
            "press" | "release" => {
                let n = value
                    .as_u64()
                    .filter(|&n| n <= 5)
                    .ok_or_else(|| format!("{key}: switches are 0..5 (A0..A5), not {value}"))?
                    as u8;
                let low = key == "press";
                changes.push(Box::new(move |c, _| c.hold_low(RigPin::Switch(n), low)));
            }
            "a6" | "a7" => {
                let volts = value
                    .as_f64()
                    .filter(|v| (0.0..=f64::from(VCC_MV) / 1000.0).contains(v))
                    .ok_or_else(|| format!("{key}: a level is 0..5 volts, not {value}"))?;
                let (pin, i) = if key == "a6" { (6u8, 0) } else { (7u8, 1) };
                let mv = (volts * 1000.0).round() as u32;
                changes.push(Box::new(move |c, a| {
                    a[i] = mv;
                    c.set_analog_mv(pin, mv);
                }));
            }
            "d8" | "d9" => {
                let fitted = value
                    .as_bool()
                    .ok_or_else(|| format!("{key}: true (fitted) or false, not {value}"))?;
                let pin = if key == "d8" { RigPin::D8 } else { RigPin::D9 };
                changes.push(Box::new(move |c, _| c.hold_low(pin, fitted)));
            }
            "reset" => {
                if value.as_bool() == Some(true) {
                    // A warm reset, as the rig's `r` key.
                    changes.push(Box::new(|c, _| c.reset(Reset::External)));
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
        change(nano, analog_mv);
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
