//! A scenario on the kit's simavr harness: the image from its Intel HEX file (as avrdude
//! writes it, no boot loader), the line timed as a wire at 19200 baud both ways, every
//! output pin's change seen after the instruction that made it.

use std::path::Path;

use utile_kit::simavr::{frame_cycles, Chip, Reset, RigPin, RxPacing, CYCLES_PER_MS, VCC_MV};
use utile_kit::{listing, modbus};

use super::{PinChange, Scenario, Sent, Step, Trace, TraceError};

/// The line's speed.
const BAUD: u32 = 19_200;
/// Modbus requests go after a silence of 4 characters (more than t3.5).
const REQUEST_SILENCE_CHARS: u64 = 4;
/// The slave's address when EEPROM holds none.
const SLAVE: u8 = 1;

/// The output pins by name and their bit in the harness's log word (port B high, D low):
/// Y0..Y5 = PD2..PD7, Y6 = PB4, Y7 = PB5, D10 = PB2.
const OUTPUTS: [(&str, u16); 9] = [
    ("Y0", 1 << 2),
    ("Y1", 1 << 3),
    ("Y2", 1 << 4),
    ("Y3", 1 << 5),
    ("Y4", 1 << 6),
    ("Y5", 1 << 7),
    ("Y6", 1 << 12),
    ("Y7", 1 << 13),
    ("D10", 1 << 10),
];

/// Runs `scenario` with paths relative to `root`.
pub fn run(scenario: &Scenario, root: &Path) -> Result<Trace, TraceError> {
    let mut chip = Chip::load_hex(&root.join(&scenario.image))?;
    chip.set_rx_pacing(RxPacing::Line { baud: BAUD });
    // The chip takes its time for each EEPROM write, as avr8js and the datasheet do.
    chip.set_eeprom_write_time(true);
    let mut run = Run {
        chip,
        log: Vec::new(),
        sent: Vec::new(),
        line_free: 0,
    };
    for (i, step) in scenario.steps.iter().enumerate() {
        run.step(i, step, root)
            .map_err(|why| TraceError::Step { step: i, why })?;
    }
    Ok(run.trace())
}

/// A scenario being run.
struct Run {
    chip: Chip,
    /// The driven levels of ports B and D at each change.
    log: Vec<(u64, u16)>,
    sent: Vec<Sent>,
    /// The cycle the line into the chip is free (the last queued stop bit).
    line_free: u64,
}

impl Run {
    fn step(&mut self, i: usize, step: &Step, root: &Path) -> Result<(), String> {
        match step {
            Step::RunMs(ms) => self.run_to(self.chip.cycle() + ms_cycles(*ms)?),
            Step::UntilMs(ms) => self.run_to(ms_cycles(*ms)?),
            Step::Type(text) => self.send(i, 0, text.as_bytes()),
            Step::Bytes(bytes) => self.send(i, 0, bytes),
            Step::Modbus(hex) => {
                let pdu = hex_bytes(hex)?;
                let silence = REQUEST_SILENCE_CHARS * frame_cycles(BAUD);
                self.send(i, silence, &modbus::frame(SLAVE, &pdu));
            }
            Step::Read(path) => {
                let text = std::fs::read_to_string(root.join(path))
                    .map_err(|e| format!("cannot read {}: {e}", path.display()))?;
                let prog = listing::parse(&path.display().to_string(), &text)
                    .map_err(|e| e.to_string())?;
                self.send(i, 0, &listing::to_hex(&prog));
            }
            Step::Press(name) => self.chip.hold_low(rig_pin(name)?, true),
            Step::Release(name) => self.chip.hold_low(rig_pin(name)?, false),
            Step::Volts(name, volts) => {
                let channel = match name.as_str() {
                    "A6" => 6,
                    "A7" => 7,
                    _ => return Err(format!("no analog input {name}: A6 or A7")),
                };
                self.chip.set_analog_mv(channel, datasheet_mv(*volts)?);
            }
            Step::Reset => self.chip.reset(Reset::External),
            Step::PowerCycle => self.chip.reset(Reset::PowerOn),
        }
        Ok(())
    }

    /// Runs to cycle `end`, logging the output pins.
    fn run_to(&mut self, end: u64) {
        let cycles = end.saturating_sub(self.chip.cycle());
        self.chip.run_logging_outputs(cycles, &mut self.log);
    }

    /// Puts `bytes` on the line after `silence` cycles, back to back, each received when its
    /// stop bit ends (the same cycles as the avr8js adapter's line).
    fn send(&mut self, step: usize, silence: u64, bytes: &[u8]) {
        let start = self.line_free.max(self.chip.cycle()) + silence;
        let frame = frame_cycles(BAUD);
        let mut stop = start;
        for &b in bytes {
            stop += frame;
            self.chip.receive_at(stop, b);
        }
        self.line_free = stop;
        self.sent.push(Sent {
            step,
            start,
            bytes: bytes.to_vec(),
        });
    }

    fn trace(mut self) -> Trace {
        let mut pins = Vec::new();
        let mut last = 0u16;
        for &(cycle, levels) in &self.log {
            for (name, bit) in OUTPUTS {
                if (levels ^ last) & bit != 0 {
                    pins.push(PinChange {
                        pin: name.to_owned(),
                        level: u8::from(levels & bit != 0),
                        cycle,
                    });
                }
            }
            last = levels;
        }
        Trace {
            simulator: "simavr".to_owned(),
            sent: self.sent,
            uart: self.chip.take_output_timed(),
            pins,
            end: self.chip.cycle(),
        }
    }
}

/// Milliseconds as cycles.
fn ms_cycles(ms: f64) -> Result<u64, String> {
    if !(ms.is_finite() && ms >= 0.0) {
        return Err(format!("not a time: {ms} ms"));
    }
    Ok((ms * CYCLES_PER_MS as f64).round() as u64)
}

/// A rig input by name.
fn rig_pin(name: &str) -> Result<RigPin, String> {
    match name {
        "D8" => Ok(RigPin::D8),
        "D9" => Ok(RigPin::D9),
        _ => name
            .strip_prefix('A')
            .and_then(|n| n.parse::<u8>().ok())
            .filter(|&n| n < 6)
            .map(RigPin::Switch)
            .ok_or_else(|| format!("no rig input {name}: A0..A5, D8 or D9")),
    }
}

/// The millivolts simavr must be given for the datasheet's conversion of `volts`:
/// ADC = Vin × 1024 / Vref (at most 1023), as avr8js converts. simavr scales by 1023
/// (`mv × 1023 / VCC`), a count low for most levels; the least millivolts that give the
/// datasheet's count under its scale are passed instead.
fn datasheet_mv(volts: f64) -> Result<u32, String> {
    if !(0.0..=5.0).contains(&volts) {
        return Err(format!("a level is 0..5 volts, not {volts}"));
    }
    let count = ((volts * 1024.0 / f64::from(VCC_MV) * 1000.0).floor() as u32).min(1023);
    Ok((count * VCC_MV).div_ceil(1023))
}

/// Hex digits (spaces allowed) as bytes.
fn hex_bytes(text: &str) -> Result<Vec<u8>, String> {
    let digits: String = text.chars().filter(|c| !c.is_whitespace()).collect();
    if !digits.len().is_multiple_of(2) || !digits.chars().all(|c| c.is_ascii_hexdigit()) {
        return Err(format!("not hex bytes: {text:?}"));
    }
    Ok((0..digits.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&digits[i..i + 2], 16).expect("hex digits checked"))
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_level_gives_the_datasheet_count_under_simavrs_scale() {
        for mv in (0..=5000).step_by(7) {
            let v = f64::from(mv) / 1000.0;
            let want = ((v * 1024.0 / 5.0).floor() as u32).min(1023);
            let got = datasheet_mv(v).unwrap() * 1023 / VCC_MV;
            assert_eq!(got, want, "{v} V");
        }
    }

    #[test]
    fn pdu_digits_are_read_with_spaces() {
        assert_eq!(hex_bytes("04 0100 0028").unwrap(), vec![4, 1, 0, 0, 0x28]);
        assert!(hex_bytes("0").is_err());
        assert!(hex_bytes("zz").is_err());
    }
}
