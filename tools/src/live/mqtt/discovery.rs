//! Home Assistant MQTT discovery (`--ha-discovery`): retained configs under
//! `homeassistant/<component>/<object>/config` that make each uTile a device (name, model,
//! firmware, `via_device` its line) with binary sensors (A0..A5, H6, H7, Q, TQ, CQ), switches
//! (Y, U, V: only with `--mqtt-commands`, else binary sensors), numbers (timer and counter
//! presets, set-points, with their ranges: only with `--mqtt-commands`, else sensors) and
//! sensors (A6/A7 in counts and volts, the counts, scans per second, scan time); the line is a
//! device of its own with one connectivity sensor. Every entity is available when both its
//! line and its uTile are.

use serde::Serialize;

use super::payloads::{OFFLINE, ONLINE};
use super::topics::Topics;
use super::Report;

/// A6/A7 full scale: 1023 counts are 5 V (SPEC §15).
const VOLTS_TEMPLATE: &str = "{{ (value | float * 5 / 1023) | round(3) }}";
/// A bit's payload when set.
const ON: &str = "1";
/// A bit's payload when clear.
const OFF: &str = "0";

/// A device, as HA's `device` key takes it.
#[derive(Clone, Debug, Serialize)]
struct Device {
    identifiers: [String; 1],
    name: String,
    model: &'static str,
    manufacturer: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    via_device: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    sw_version: Option<String>,
}

/// One entry of HA's `availability` list.
#[derive(Clone, Debug, Serialize)]
struct Availability {
    topic: String,
}

/// One entity's config: the keys every component shares, and its component's own.
#[derive(Debug, Serialize)]
struct Config<'a> {
    name: String,
    unique_id: String,
    device: &'a Device,
    state_topic: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    availability: Option<&'a [Availability; 2]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    availability_mode: Option<&'static str>,
    #[serde(flatten)]
    component: Component,
}

/// A component's own keys.
#[derive(Debug, Serialize)]
#[serde(untagged)]
enum Component {
    /// `binary_sensor`.
    Binary {
        payload_on: &'static str,
        payload_off: &'static str,
        #[serde(skip_serializing_if = "Option::is_none")]
        device_class: Option<&'static str>,
    },
    /// `switch`.
    Switch {
        command_topic: String,
        payload_on: &'static str,
        payload_off: &'static str,
        state_on: &'static str,
        state_off: &'static str,
        optimistic: bool,
    },
    /// `number`.
    Number {
        command_topic: String,
        min: u32,
        max: u32,
        step: u32,
        mode: &'static str,
        entity_category: &'static str,
    },
    /// `sensor`.
    Sensor {
        #[serde(skip_serializing_if = "Option::is_none")]
        state_class: Option<&'static str>,
        #[serde(skip_serializing_if = "Option::is_none")]
        unit_of_measurement: Option<&'static str>,
        #[serde(skip_serializing_if = "Option::is_none")]
        device_class: Option<&'static str>,
        #[serde(skip_serializing_if = "Option::is_none")]
        value_template: Option<&'static str>,
        #[serde(skip_serializing_if = "Option::is_none")]
        entity_category: Option<&'static str>,
    },
}

impl Component {
    /// Its name in the discovery topic.
    fn name(&self) -> &'static str {
        match self {
            Component::Binary { .. } => "binary_sensor",
            Component::Switch { .. } => "switch",
            Component::Number { .. } => "number",
            Component::Sensor { .. } => "sensor",
        }
    }

    /// A bit read only.
    fn bit() -> Component {
        Component::Binary {
            payload_on: ON,
            payload_off: OFF,
            device_class: None,
        }
    }

    /// A sensor of measurements in `unit` (none when empty).
    fn measurement(unit: &'static str) -> Component {
        Component::Sensor {
            state_class: Some("measurement"),
            unit_of_measurement: (!unit.is_empty()).then_some(unit),
            device_class: None,
            value_template: None,
            entity_category: None,
        }
    }
}

/// A config as its (topic, payload).
fn message(object: &str, cfg: &Config) -> (String, String) {
    (
        Topics::discovery(cfg.component.name(), object),
        serde_json::to_string(cfg).unwrap_or_default(),
    )
}

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
    let device = Device {
        identifiers: [id],
        name: format!("uTile line {}", t.line()),
        model: "utile live",
        manufacturer: "uTile",
        via_device: None,
        sw_version: None,
    };
    let cfg = Config {
        name: "Line".into(),
        unique_id: object.clone(),
        device: &device,
        state_topic: t.status(),
        availability: None,
        availability_mode: None,
        component: Component::Binary {
            payload_on: ONLINE,
            payload_off: OFFLINE,
            device_class: Some("connectivity"),
        },
    };
    message(&object, &cfg)
}

/// The configs of one uTile's entities: (topic, payload).
pub fn unit_configs(t: &Topics, r: &Report, commands: bool) -> Vec<(String, String)> {
    let id = unit_id(t, r.addr);
    let device = Device {
        identifiers: [id.clone()],
        name: format!("uTile {} ({})", r.addr, t.line()),
        model: "uTile",
        manufacturer: "uTile",
        via_device: Some(line_id(t)),
        sw_version: r.firmware.clone(),
    };
    let availability = [
        Availability { topic: t.status() },
        Availability {
            topic: t.unit(r.addr, "availability"),
        },
    ];
    let mut out = Vec::new();
    // The entity `{id}_{object}` named `name`, reading `signal`'s topic.
    let mut add = |object: &str, name: &str, signal: &str, component: Component| {
        let object = format!("{id}_{object}");
        let cfg = Config {
            name: name.to_string(),
            unique_id: object.clone(),
            device: &device,
            state_topic: t.unit(r.addr, signal),
            availability: Some(&availability),
            availability_mode: Some("all"),
            component,
        };
        out.push(message(&object, &cfg));
    };
    let k = kinds();
    for s in &k.bits {
        add(s, s, s, Component::bit());
    }
    for s in &k.coils {
        let c = if commands {
            Component::Switch {
                command_topic: t.set(r.addr, s),
                payload_on: ON,
                payload_off: OFF,
                state_on: ON,
                state_off: OFF,
                optimistic: false,
            }
        } else {
            Component::bit()
        };
        add(s, s, s, c);
    }
    for (s, max) in &k.presets {
        let c = if commands {
            Component::Number {
                command_topic: t.set(r.addr, s),
                min: 0,
                max: *max,
                step: 1,
                mode: "box",
                entity_category: "config",
            }
        } else {
            Component::Sensor {
                state_class: None,
                unit_of_measurement: None,
                device_class: None,
                value_template: None,
                entity_category: Some("diagnostic"),
            }
        };
        add(s, s, s, c);
    }
    for (s, unit) in &k.readings {
        add(s, s, s, Component::measurement(unit));
    }
    for s in ["A6", "A7"] {
        add(
            &format!("{s}_volts"),
            &format!("{s} volts"),
            s,
            Component::Sensor {
                state_class: Some("measurement"),
                unit_of_measurement: Some("V"),
                device_class: Some("voltage"),
                value_template: Some(VOLTS_TEMPLATE),
                entity_category: None,
            },
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::Value;

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
        assert_eq!(y0["availability"][1]["topic"], "utile/l/1/availability");
        let get = |topic: &str| -> Value {
            let (_, p) = with.iter().find(|(k, _)| k == topic).unwrap();
            serde_json::from_str(p).unwrap()
        };
        let volts = get("homeassistant/sensor/utile_l_1_A6_volts/config");
        assert_eq!(
            volts["state_topic"], "utile/l/1/A6",
            "the volts read the counts"
        );
        assert_eq!(volts["unit_of_measurement"], "V");
        let cp0 = get("homeassistant/number/utile_l_1_CP0/config");
        assert_eq!(
            (cp0["min"].as_u64(), cp0["max"].as_u64()),
            (Some(0), Some(65535))
        );
        let c0 = get("homeassistant/sensor/utile_l_1_C0/config");
        assert!(c0.get("unit_of_measurement").is_none(), "{c0}");
        let (topic, line) = line_config(&t);
        let line: Value = serde_json::from_str(&line).unwrap();
        assert_eq!(topic, "homeassistant/binary_sensor/utile_l_status/config");
        assert_eq!(line["device_class"], "connectivity");
        assert!(line.get("availability").is_none());
    }
}
