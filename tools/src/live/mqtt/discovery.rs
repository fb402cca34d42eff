//! Home Assistant MQTT discovery (`--ha-discovery`): retained configs under
//! `homeassistant/<component>/<object>/config` that make each uTile a device (name, model,
//! firmware, `via_device` its line) with binary sensors (A0..A5, H6, H7, Q, TQ, CQ), switches
//! (Y, U, V: only with `--mqtt-commands`, else binary sensors), numbers (timer and counter
//! presets, set-points, with their ranges: only with `--mqtt-commands`, else sensors) and
//! sensors (A6/A7 in counts and volts, the counts, scans per second, scan time); the line is a
//! device of its own with one connectivity sensor. Every entity is available when both its
//! line and its uTile are.

use serde_json::{json, Map, Value};

use super::topics::Topics;
use super::Report;

/// A6/A7 full scale: 1023 counts are 5 V (SPEC §15).
const VOLTS_TEMPLATE: &str = "{{ (value | float * 5 / 1023) | round(3) }}";

/// The hex digit of a timer or flip-flop (`0`..`F`), as the listing spells it.
fn digit(m: usize) -> char {
    char::from_digit(m as u32, 16)
        .unwrap_or('0')
        .to_ascii_uppercase()
}

/// The signals of one uTile by kind.
struct Kinds {
    bits: Vec<String>,
    coils: Vec<String>,
    /// Name, largest value.
    presets: Vec<(String, u32)>,
    /// Name, unit of measurement.
    readings: Vec<(String, &'static str)>,
}

fn kinds() -> Kinds {
    let mut bits: Vec<String> = (0..6).map(|n| format!("A{n}")).collect();
    bits.extend(["H6".to_string(), "H7".to_string()]);
    bits.extend((0..16).map(|m| format!("Q{}", digit(m))));
    bits.extend((0..16).map(|m| format!("TQ{}", digit(m))));
    bits.extend((0..8).map(|m| format!("CQ{m}")));
    let mut coils = Vec::new();
    for p in ["Y", "U", "V"] {
        coils.extend((0..8).map(|n| format!("{p}{n}")));
    }
    let mut presets: Vec<(String, u32)> =
        (0..16).map(|m| (format!("T{}", digit(m)), 255)).collect();
    presets.extend((0..8).map(|m| (format!("CP{m}"), 65535)));
    presets.extend([("S6".to_string(), 1023), ("S7".to_string(), 1023)]);
    let mut readings = vec![("A6".to_string(), ""), ("A7".to_string(), "")];
    readings.extend((0..8).map(|m| (format!("C{m}"), "")));
    readings.push(("scans_per_s".into(), "scans/s"));
    readings.push(("scan_mean".into(), "µs"));
    readings.push(("scan_max".into(), "µs"));
    Kinds {
        bits,
        coils,
        presets,
        readings,
    }
}

/// The line's device id.
fn line_id(t: &Topics) -> String {
    format!("utile_{}", t.line())
}

/// A uTile's device id (and its entities' prefix).
fn unit_id(t: &Topics, addr: u8) -> String {
    format!("utile_{}_{addr}", t.line())
}

/// The line's own device and its connectivity sensor.
pub fn line_config(t: &Topics) -> (String, String) {
    let id = line_id(t);
    let object = format!("{id}_status");
    let cfg = json!({
        "name": "Line",
        "unique_id": object,
        "device_class": "connectivity",
        "state_topic": t.status(),
        "payload_on": "online",
        "payload_off": "offline",
        "device": {
            "identifiers": [id],
            "name": format!("uTile line {}", t.line()),
            "model": "utile live",
            "manufacturer": "uTile",
        },
    });
    (Topics::discovery("binary_sensor", &object), cfg.to_string())
}

/// The configs of one uTile's entities: (topic, payload).
pub fn unit_configs(t: &Topics, r: &Report, commands: bool) -> Vec<(String, String)> {
    let id = unit_id(t, r.addr);
    let mut device = json!({
        "identifiers": [id],
        "name": format!("uTile {} ({})", r.addr, t.line()),
        "model": "uTile",
        "manufacturer": "uTile",
        "via_device": line_id(t),
    });
    if let Some(fw) = &r.firmware {
        device["sw_version"] = json!(fw);
    }
    let availability = json!([
        {"topic": t.status()},
        {"topic": t.unit(r.addr, "availability")},
    ]);
    let mut out = Vec::new();
    let mut add = |component: &str, signal: &str, name: &str, extra: Value| {
        let object = format!("{id}_{signal}");
        let mut cfg = Map::new();
        cfg.insert("name".into(), json!(name));
        cfg.insert("unique_id".into(), json!(object));
        cfg.insert("device".into(), device.clone());
        cfg.insert("availability".into(), availability.clone());
        cfg.insert("availability_mode".into(), json!("all"));
        if let Value::Object(m) = extra {
            cfg.extend(m);
        }
        out.push((
            Topics::discovery(component, &object),
            Value::Object(cfg).to_string(),
        ));
    };
    let k = kinds();
    let state = |s: &str| t.unit(r.addr, s);
    let bit = |s: &str| json!({"state_topic": state(s), "payload_on": "1", "payload_off": "0"});
    for s in &k.bits {
        add("binary_sensor", s, s, bit(s));
    }
    for s in &k.coils {
        if commands {
            add(
                "switch",
                s,
                s,
                json!({
                    "state_topic": state(s),
                    "command_topic": t.set(r.addr, s),
                    "payload_on": "1",
                    "payload_off": "0",
                    "state_on": "1",
                    "state_off": "0",
                    "optimistic": false,
                }),
            );
        } else {
            add("binary_sensor", s, s, bit(s));
        }
    }
    for (s, max) in &k.presets {
        if commands {
            add(
                "number",
                s,
                s,
                json!({
                    "state_topic": state(s),
                    "command_topic": t.set(r.addr, s),
                    "min": 0,
                    "max": max,
                    "step": 1,
                    "mode": "box",
                    "entity_category": "config",
                }),
            );
        } else {
            add(
                "sensor",
                s,
                s,
                json!({"state_topic": state(s), "entity_category": "diagnostic"}),
            );
        }
    }
    for (s, unit) in &k.readings {
        let mut cfg = json!({"state_topic": state(s), "state_class": "measurement"});
        if !unit.is_empty() {
            cfg["unit_of_measurement"] = json!(unit);
        }
        add("sensor", s, s, cfg);
    }
    for s in ["A6", "A7"] {
        add(
            "sensor",
            &format!("{s}_volts"),
            &format!("{s} volts"),
            json!({
                "state_topic": state(s),
                "value_template": VOLTS_TEMPLATE,
                "unit_of_measurement": "V",
                "device_class": "voltage",
                "state_class": "measurement",
            }),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn switches_and_numbers_only_with_commands() {
        let t = Topics::new("utile", "l");
        let r = Report {
            addr: 1,
            online: true,
            values: Default::default(),
            firmware: Some("uTile 4".into()),
        };
        let count = |c: &[(String, String)], comp: &str| {
            c.iter()
                .filter(|(k, _)| k.starts_with(&format!("homeassistant/{comp}/")))
                .count()
        };
        let with = unit_configs(&t, &r, true);
        assert_eq!(count(&with, "switch"), 24);
        assert_eq!(count(&with, "number"), 26);
        let without = unit_configs(&t, &r, false);
        assert_eq!(count(&without, "switch") + count(&without, "number"), 0);
        let y0: Value = serde_json::from_str(
            &with
                .iter()
                .find(|(k, _)| k == "homeassistant/switch/utile_l_1_Y0/config")
                .unwrap()
                .1,
        )
        .unwrap();
        assert_eq!(y0["command_topic"], "utile/l/1/Y0/set");
        assert_eq!(y0["device"]["sw_version"], "uTile 4");
        assert_eq!(y0["device"]["via_device"], "utile_l");
    }
}
