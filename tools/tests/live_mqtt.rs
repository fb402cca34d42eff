//! `utile live --mqtt` against a real broker (Debian's mosquitto, started here on free
//! loopback ports with a password file and a TLS listener whose certificates are made here)
//! and a real client (rumqttc): state on a rig press, availability, the last wills (the
//! line's and each uTile's, killed or stopped cleanly), the broker stopped and back, Home
//! Assistant discovery checked against the keys HA documents, `set` commands (with
//! `--mqtt-commands`, refused without it and with `--read-only`, bad payloads), TLS and the
//! login; nothing of a uTile's state before it was first read.

mod support;

use std::path::Path;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use support::live::{tank_with_remote, Live, NanoSpec};
use support::mqtt::{have_mosquitto, Broker, Certs, Subscriber, PASSWORD, USER};
use support::vnano::scratch;

/// The scenarios share two cores: one at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

const T: Duration = Duration::from_secs(30);

fn one_at_a_time() -> std::sync::MutexGuard<'static, ()> {
    ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner())
}

fn json(text: &str) -> Value {
    serde_json::from_str(text).unwrap_or(Value::Null)
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}

/// The tank (with `U0. .Y2`) on a virtual Nano, `utile live` on it publishing to `broker` as
/// line `line` with `extra`; uTile 1 online.
fn tank_live(
    name: &str,
    broker: &Broker,
    line: &str,
    extra: &[&str],
) -> (support::vnano::PtyNano, Live) {
    let spec = NanoSpec::single(name, &tank_with_remote(), false);
    let nano = spec.start();
    let mut args = broker.live_args(line);
    args.extend(extra.iter().map(|s| s.to_string()));
    let live = Live::start(&spec.link, &strs(&args));
    live.wait("uTile 1 online", T, |s| {
        s["units"][0]["state"] == "online" && s["units"][0]["values"]["A6"] == 409
    });
    (nano, live)
}

/// Waits for a console line of `live` containing `needle`; returns it and when it came.
fn console_line(live: &Live, needle: &str, timeout: Duration) -> (String, Instant) {
    let t0 = Instant::now();
    loop {
        let left = timeout.saturating_sub(t0.elapsed());
        match live.console.recv_timeout(left) {
            Ok(line) if line.contains(needle) => return (line, Instant::now()),
            Ok(_) => {}
            Err(_) => panic!("utile live printed no line with {needle:?} within {timeout:?}"),
        }
    }
}

#[test]
fn state_follows_a_rig_press_and_the_last_will_marks_the_line_offline() {
    if !have_mosquitto() {
        return;
    }
    let _one = one_at_a_time();
    let broker = Broker::start("state");
    let sub = Subscriber::connect(broker.port, &["utile/#"]);
    let (mut nano, mut live) = tank_live("mqtt-state", &broker, "plant1", &[]);
    sub.wait("utile/plant1/status", T, |p| p == "online");
    sub.wait("utile/plant1/1/availability", T, |p| p == "online");
    let state = sub.wait("utile/plant1/1/state", T, |p| json(p)["A6"] == 409);
    let s = json(&state.text);
    for name in ["A0", "Y0", "U0", "TQ0", "C0", "A7", "scans", "scans_per_s"] {
        assert!(s.get(name).is_some(), "{name} is in the state: {s}");
    }
    // Each value alone too, as the state has it.
    let a0 = s["A0"].to_string();
    sub.wait("utile/plant1/1/A6", T, |p| p == "409");

    // A rig press (A0 toggles on the virtual Nano) reaches the subscriber.
    let from = sub.count();
    let pressed = Instant::now();
    nano.key("0");
    let m = sub.wait_from(from, "utile/plant1/1/A0", T, |p| p != a0);
    eprintln!(
        "MEASURE rig press -> MQTT message at the subscriber: {:.0} ms",
        (m.at - pressed).as_secs_f64() * 1e3
    );
    let now: u64 = m.text.parse().expect("A0 is 0 or 1");
    sub.wait_from(from, "utile/plant1/1/state", T, |p| json(p)["A0"] == now);

    // On change only: no A0 message while A0 stays, while the state goes on (scans).
    let a0_count = |sub: &Subscriber| {
        sub.all()
            .iter()
            .filter(|x| x.topic == "utile/plant1/1/A0")
            .count()
    };
    let (n_a0, n_all) = (a0_count(&sub), sub.count());
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(a0_count(&sub), n_a0, "A0 sent again without a change");
    assert!(
        sub.count() > n_all,
        "the state goes on while the uTile scans"
    );

    // Retained: a client that comes later gets the state and the availability at once.
    let late = Subscriber::connect(
        broker.port,
        &["utile/plant1/1/state", "utile/plant1/status"],
    );
    let got = late.wait("utile/plant1/1/state", T, |p| json(p)["A6"] == 409);
    assert!(got.retained, "the state is retained");

    // Killed: the broker publishes the last will.
    let from = sub.count();
    live.child.kill().unwrap();
    let _ = live.child.wait();
    sub.wait_from(from, "utile/plant1/status", T, |p| p == "offline");
    sub.wait_from(from, "utile/plant1/1/availability", T, |p| p == "offline");
    let late = Subscriber::connect(broker.port, &["utile/plant1/status"]);
    let kept = late.wait("utile/plant1/status", T, |_| true);
    assert_eq!(kept.text, "offline", "the last will is retained");
}

/// Waits until a new subscriber gets `offline`, retained, on the line's status and on each
/// of `units`' availability.
fn all_offline_retained(broker: &Broker, line: &str, units: &[u8]) {
    let late = Subscriber::connect(broker.port, &[&format!("utile/{line}/#")]);
    let mut topics = vec![format!("utile/{line}/status")];
    topics.extend(
        units
            .iter()
            .map(|a| format!("utile/{line}/{a}/availability")),
    );
    for topic in &topics {
        let m = late.wait(topic, T, |_| true);
        assert!(m.retained, "{topic} is retained");
        assert_eq!(m.text, "offline", "{topic}, as a new subscriber sees it");
    }
}

#[test]
fn killed_or_stopped_utile_live_leaves_the_line_and_each_utile_offline() {
    if !have_mosquitto() {
        return;
    }
    let _one = one_at_a_time();
    let broker = Broker::start("wills");
    let sub = Subscriber::connect(broker.port, &["utile/#"]);
    let spec = NanoSpec::bus("mqtt-wills", 3, &tank_with_remote());
    let _nano = spec.start();
    let mut args = broker.live_args("wills");
    args.extend(["--units", "1,2,3"].map(String::from));
    let units = [1u8, 2, 3];
    let all_online = |from: usize| {
        sub.wait_from(from, "utile/wills/status", T, |p| p == "online");
        for a in units {
            sub.wait_from(from, &format!("utile/wills/{a}/availability"), T, |p| {
                p == "online"
            });
        }
    };

    // Killed (SIGKILL: nothing of it runs): the broker's wills, one per session.
    let mut live = Live::start(&spec.link, &strs(&args));
    all_online(0);
    let from = sub.count();
    live.child.kill().unwrap();
    let _ = live.child.wait();
    for a in units {
        sub.wait_from(from, &format!("utile/wills/{a}/availability"), T, |p| {
            p == "offline"
        });
    }
    sub.wait_from(from, "utile/wills/status", T, |p| p == "offline");
    all_offline_retained(&broker, "wills", &units);

    // Started again: online again; then stopped cleanly (SIGTERM): it publishes `offline`
    // itself and disconnects (the broker logs a clean disconnect, not a lost connection).
    let from = sub.count();
    let mut live = Live::start(&spec.link, &strs(&args));
    all_online(from);
    let from = sub.count();
    // SAFETY: kill only sends a signal to the child this test started.
    let r = unsafe { libc::kill(live.child.id() as libc::pid_t, libc::SIGTERM) };
    assert_eq!(r, 0, "SIGTERM sent");
    let status = live.child.wait().unwrap();
    assert!(status.success(), "utile live ended {status} on SIGTERM");
    for a in units {
        sub.wait_from(from, &format!("utile/wills/{a}/availability"), T, |p| {
            p == "offline"
        });
    }
    sub.wait_from(from, "utile/wills/status", T, |p| p == "offline");
    all_offline_retained(&broker, "wills", &units);
    let log = broker.log_text();
    for id in [
        "utile-wills",
        "utile-wills-1",
        "utile-wills-2",
        "utile-wills-3",
    ] {
        assert!(
            log.contains(&format!("Client {id} disconnected")),
            "{id} disconnected cleanly:\n{log}"
        );
    }
}

#[test]
fn the_broker_stopped_and_back_gets_everything_again_while_the_page_goes_on() {
    if !have_mosquitto() {
        return;
    }
    let _one = one_at_a_time();
    let mut broker = Broker::start("restart");
    let (_nano, live) = tank_live("mqtt-restart", &broker, "plant2", &["--ha-discovery"]);
    console_line(&live, "MQTT: connected to", T);
    let sub = Subscriber::connect(broker.port, &["utile/#"]);
    sub.wait("utile/plant2/1/Y2", T, |p| p == "0");

    // The broker goes away (and its retained messages with it: no persistence).
    broker.down();
    console_line(&live, "cannot reach the broker", T);
    // The page and the line go on: a write through the API, read back.
    let (code, body) = live.post("/api/units/1/write", &json!({"signal": "U0", "value": 1}));
    assert_eq!(code, 200, "{body}");
    live.wait_value(1, "Y2", 1);

    let back = Instant::now();
    broker.up();
    let (_, connected) = console_line(&live, "MQTT: connected again", T);
    eprintln!(
        "MEASURE broker back -> reconnected: {:.0} ms",
        (connected - back).as_secs_f64() * 1e3
    );
    // Retained state (with the change made while away) and discovery are there again.
    // (A first client sees them come; one after it gets them from the broker, retained.)
    let sub = Subscriber::connect(broker.port, &["utile/#", "homeassistant/#"]);
    let a0 = "homeassistant/binary_sensor/utile_plant2_1_A0/config";
    sub.wait("utile/plant2/1/state", T, |p| json(p)["Y2"] == 1);
    sub.wait(a0, T, |_| true);
    let late = Subscriber::connect(broker.port, &["utile/#", "homeassistant/#"]);
    let st = late.wait("utile/plant2/1/state", T, |p| json(p)["Y2"] == 1);
    assert!(st.retained);
    assert!(
        late.wait("utile/plant2/status", T, |p| p == "online")
            .retained
    );
    assert!(late.wait(a0, T, |_| true).retained);
    // The uTile's own session connected again and published its availability again.
    assert!(
        late.wait("utile/plant2/1/availability", T, |p| p == "online")
            .retained
    );
}

/// The keys every MQTT entity of Home Assistant takes (home-assistant.io/integrations/
/// <component>.mqtt/, "Configuration Variables"), written here from those pages.
const HA_COMMON: &[&str] = &[
    "availability",
    "availability_mode",
    "availability_template",
    "availability_topic",
    "default_entity_id",
    "device",
    "enabled_by_default",
    "encoding",
    "entity_category",
    "entity_picture",
    "icon",
    "json_attributes_template",
    "json_attributes_topic",
    "name",
    "object_id",
    "payload_available",
    "payload_not_available",
    "platform",
    "qos",
    "unique_id",
];

/// Each component's own keys, and the ones it requires.
fn ha_keys(component: &str) -> (&'static [&'static str], &'static [&'static str]) {
    match component {
        "binary_sensor" => (
            &[
                "device_class",
                "expire_after",
                "force_update",
                "off_delay",
                "payload_off",
                "payload_on",
                "state_topic",
                "value_template",
            ],
            &["state_topic"],
        ),
        "switch" => (
            &[
                "command_template",
                "command_topic",
                "device_class",
                "optimistic",
                "payload_off",
                "payload_on",
                "retain",
                "state_off",
                "state_on",
                "state_topic",
                "value_template",
            ],
            &["command_topic"],
        ),
        "number" => (
            &[
                "command_template",
                "command_topic",
                "device_class",
                "max",
                "min",
                "mode",
                "optimistic",
                "payload_reset",
                "retain",
                "state_topic",
                "step",
                "unit_of_measurement",
                "value_template",
            ],
            &["command_topic"],
        ),
        "sensor" => (
            &[
                "device_class",
                "expire_after",
                "force_update",
                "last_reset_value_template",
                "options",
                "state_class",
                "state_topic",
                "suggested_display_precision",
                "unit_of_measurement",
                "value_template",
            ],
            &["state_topic"],
        ),
        other => panic!("a component HA's MQTT discovery has no page for here: {other}"),
    }
}

/// The keys of `device` (all components' pages).
const HA_DEVICE: &[&str] = &[
    "configuration_url",
    "connections",
    "hw_version",
    "identifiers",
    "manufacturer",
    "model",
    "model_id",
    "name",
    "serial_number",
    "suggested_area",
    "sw_version",
    "via_device",
];

/// The keys of one `availability` entry.
const HA_AVAILABILITY: &[&str] = &[
    "payload_available",
    "payload_not_available",
    "topic",
    "value_template",
];

/// Checks one config against HA's keys; returns its component.
fn check_config(topic: &str, cfg: &Value) -> String {
    let parts: Vec<&str> = topic.split('/').collect();
    assert_eq!(parts.len(), 4, "{topic}");
    assert_eq!((parts[0], parts[3]), ("homeassistant", "config"), "{topic}");
    let component = parts[1];
    assert!(
        parts[2]
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-'),
        "object id {topic}"
    );
    let (own, required) = ha_keys(component);
    let obj = cfg
        .as_object()
        .unwrap_or_else(|| panic!("{topic}: not an object"));
    for k in obj.keys() {
        assert!(
            HA_COMMON.contains(&k.as_str()) || own.contains(&k.as_str()),
            "{topic}: '{k}' is not a key of HA's MQTT {component}"
        );
    }
    for k in required {
        assert!(obj.contains_key(*k), "{topic}: '{k}' is required");
    }
    let dev = cfg["device"].as_object().expect("a device");
    for k in dev.keys() {
        assert!(HA_DEVICE.contains(&k.as_str()), "{topic}: device key '{k}'");
    }
    assert!(
        dev.contains_key("identifiers"),
        "{topic}: device identifiers"
    );
    if let Some(list) = cfg["availability"].as_array() {
        for a in list {
            for k in a.as_object().unwrap().keys() {
                assert!(
                    HA_AVAILABILITY.contains(&k.as_str()),
                    "{topic}: availability '{k}'"
                );
            }
            assert!(a["topic"].is_string());
        }
        assert!(
            ["all", "any", "latest"]
                .contains(&cfg["availability_mode"].as_str().unwrap_or("latest")),
            "{topic}"
        );
    }
    if let Some(c) = cfg.get("entity_category") {
        assert!(
            c == "config" || c == "diagnostic",
            "{topic}: entity_category {c}"
        );
    }
    if component == "number" {
        assert!(["auto", "box", "slider"].contains(&cfg["mode"].as_str().unwrap_or("auto")));
    }
    if let Some(c) = cfg.get("state_class") {
        assert!(["measurement", "total", "total_increasing"].contains(&c.as_str().unwrap()));
    }
    component.to_string()
}

#[test]
fn home_assistant_discovery_configs_use_the_keys_ha_documents() {
    if !have_mosquitto() {
        return;
    }
    let _one = one_at_a_time();
    let broker = Broker::start("discovery");
    let (_nano, live) = tank_live(
        "mqtt-discovery",
        &broker,
        "plant3",
        &["--ha-discovery", "--mqtt-commands"],
    );
    console_line(&live, "MQTT: connected to", T);
    let sub = Subscriber::connect(broker.port, &["homeassistant/#", "utile/plant3/#"]);
    let y0 = "homeassistant/switch/utile_plant3_1_Y0/config";
    // The configs are sent again once the firmware's id (Report Server ID) is known.
    sub.wait(y0, T, |p| json(p)["device"]["sw_version"].is_string());
    // Wait a little for the last of them; the last of each topic counts.
    std::thread::sleep(Duration::from_millis(500));
    let mut configs = std::collections::BTreeMap::new();
    for m in sub
        .all()
        .into_iter()
        .filter(|m| m.topic.starts_with("homeassistant/"))
    {
        configs.insert(m.topic.clone(), json(&m.text));
    }
    let mut by_component = std::collections::BTreeMap::<String, usize>::new();
    for (topic, cfg) in &configs {
        *by_component.entry(check_config(topic, cfg)).or_default() += 1;
    }
    // Retained: a client that comes now gets them all from the broker.
    let late = Subscriber::connect(broker.port, &["homeassistant/#"]);
    late.wait(y0, T, |p| json(p)["device"]["sw_version"].is_string());
    std::thread::sleep(Duration::from_millis(300));
    let kept = late.all();
    assert!(kept.iter().all(|m| m.retained));
    let topics: std::collections::BTreeSet<&String> = kept.iter().map(|m| &m.topic).collect();
    assert_eq!(topics.len(), configs.len());
    // One uTile: 48 bits + the line's connectivity, 24 switches, 26 numbers, 15 sensors.
    assert_eq!(by_component["binary_sensor"], 49, "{by_component:?}");
    assert_eq!(by_component["switch"], 24);
    assert_eq!(by_component["number"], 26);
    assert_eq!(by_component["sensor"], 15);

    let y0 = &configs[y0];
    assert_eq!(y0["command_topic"], "utile/plant3/1/Y0/set");
    assert_eq!(y0["state_topic"], "utile/plant3/1/Y0");
    assert_eq!(y0["device"]["model"], "uTile");
    assert_eq!(y0["device"]["via_device"], "utile_plant3");
    assert!(
        y0["device"]["sw_version"]
            .as_str()
            .unwrap()
            .starts_with("uTile "),
        "the firmware's id (Report Server ID): {y0}"
    );
    assert!(y0["device"]["name"].as_str().unwrap().contains("plant3"));
    let topics: Vec<&str> = y0["availability"]
        .as_array()
        .unwrap()
        .iter()
        .map(|a| a["topic"].as_str().unwrap())
        .collect();
    assert_eq!(
        topics,
        ["utile/plant3/status", "utile/plant3/1/availability"]
    );
    // The line's device, which the uTiles' via_device names.
    let line = &configs["homeassistant/binary_sensor/utile_plant3_status/config"];
    assert_eq!(line["device"]["identifiers"][0], "utile_plant3");
    // Ranges of the numbers are the map's (SPEC §13).
    let s6 = &configs["homeassistant/number/utile_plant3_1_S6/config"];
    assert_eq!(
        (s6["min"].clone(), s6["max"].clone()),
        (json!(0), json!(1023))
    );
    assert_eq!(
        configs["homeassistant/number/utile_plant3_1_TF/config"]["max"],
        255
    );
    assert_eq!(
        configs["homeassistant/number/utile_plant3_1_CP7/config"]["max"],
        65535
    );
    // Every state topic a config names is published (the values HA will show).
    for cfg in configs.values() {
        let st = cfg["state_topic"].as_str().unwrap_or_default();
        if !st.is_empty() {
            sub.wait(st, T, |_| true);
        }
    }
    let volts = &configs["homeassistant/sensor/utile_plant3_1_A6_volts/config"];
    assert_eq!(volts["unit_of_measurement"], "V");
    assert_eq!(sub.last("utile/plant3/1/A6").as_deref(), Some("409"));
}

/// Waits for an error on uTile 1 of `line` after message `from` whose text has `words`.
fn refused(sub: &Subscriber, from: usize, line: &str, words: &str) -> Value {
    let m = sub.wait_from(from, &format!("utile/{line}/1/error"), T, |p| {
        json(p)["error"].as_str().is_some_and(|e| e.contains(words))
    });
    assert!(!m.retained, "errors are not retained");
    json(&m.text)
}

#[test]
fn set_topics_write_with_mqtt_commands_only_and_refuse_bad_payloads() {
    if !have_mosquitto() {
        return;
    }
    let _one = one_at_a_time();
    let broker = Broker::start("commands");
    let sub = Subscriber::connect(broker.port, &["utile/#"]);

    // Without --mqtt-commands a set does nothing.
    let (_nano, live) = tank_live("mqtt-no-commands", &broker, "plant4", &[]);
    sub.wait("utile/plant4/1/U0", T, |p| p == "0");
    sub.publish("utile/plant4/1/U0/set", b"1", false);
    std::thread::sleep(Duration::from_millis(1500));
    assert_eq!(
        live.unit(1)["values"]["U0"],
        0,
        "written without --mqtt-commands"
    );
    assert!(sub.last("utile/plant4/1/error").is_none());
    drop(live);

    // With it. A set left retained on the broker is not carried out at the subscription
    // (then the retained message is cleared: an empty payload, refused too).
    sub.publish("utile/plant5/1/U0/set", b"1", true);
    // On the broker before utile live subscribes (its own copy comes back to the test's
    // client): a slow machine must not turn it into a live command.
    sub.wait("utile/plant5/1/U0/set", T, |p| p == "1");
    let (_nano, live) = tank_live("mqtt-commands", &broker, "plant5", &["--mqtt-commands"]);
    console_line(&live, "MQTT: connected to", T);
    refused(&sub, 0, "plant5", "retained");
    sub.publish("utile/plant5/1/U0/set", b"", true);
    refused(&sub, 0, "plant5", "'' is not a whole number");
    assert_eq!(
        live.unit(1)["values"]["U0"],
        0,
        "a retained set was written"
    );
    // U0 (the program copies it to Y2) on and off, through the line.
    sub.wait("utile/plant5/1/Y2", T, |p| p == "0");
    let from = sub.count();
    let sent = Instant::now();
    sub.publish("utile/plant5/1/U0/set", b"1", false);
    let m = sub.wait_from(from, "utile/plant5/1/Y2", T, |p| p == "1");
    eprintln!(
        "MEASURE set U0 -> Y2 at the subscriber: {:.0} ms",
        (m.at - sent).as_secs_f64() * 1e3
    );
    assert_eq!(live.unit(1)["values"]["U0"], 1);
    sub.publish("utile/plant5/1/S6/set", b"700", false);
    sub.wait_from(from, "utile/plant5/1/S6", T, |p| p == "700");

    // Bad payloads: refused on the error topic with the reason, counted, nothing written.
    let from = sub.count();
    sub.publish("utile/plant5/1/U0/set", b"abc", false);
    let e = refused(&sub, from, "plant5", "not a whole number");
    assert_eq!(e["signal"], "U0");
    sub.publish("utile/plant5/1/U0/set", b"2", false);
    refused(&sub, from, "plant5", "a bit: 0 or 1");
    sub.publish("utile/plant5/1/S6/set", b"1024", false);
    refused(&sub, from, "plant5", "0..1023");
    sub.publish("utile/plant5/1/A0/set", b"1", false);
    refused(&sub, from, "plant5", "cannot be written");
    sub.publish("utile/plant5/1/U0/set", &vec![b'0'; 100_000], false);
    refused(&sub, from, "plant5", "too long");
    sub.publish("utile/plant5/9/U0/set", b"0", false);
    let last = sub.wait_from(from, "utile/plant5/9/error", T, |p| {
        p.contains("no uTile 9")
    });
    assert_eq!(
        json(&last.text)["refused"],
        8,
        "every refusal counted: {}",
        last.text
    );
    let unit = live.unit(1);
    assert_eq!(unit["values"]["U0"], 1, "nothing written: {unit}");
    assert_eq!(unit["values"]["S6"], 700);
    // Still connected and taking commands after the huge payload.
    sub.publish("utile/plant5/1/U0/set", b"OFF", false);
    live.wait_value(1, "Y2", 0);
    let c = sub.wait("utile/plant5/counters", T, |p| json(p)["refused"] == 8);
    assert_eq!(json(&c.text)["connects"], 1, "no reconnect: {}", c.text);
    drop(live);

    // --read-only refuses them all.
    let (_nano, live) = tank_live(
        "mqtt-read-only",
        &broker,
        "plant6",
        &["--mqtt-commands", "--read-only"],
    );
    console_line(&live, "MQTT: connected to", T);
    let from = sub.count();
    sub.publish("utile/plant6/1/U0/set", b"1", false);
    refused(&sub, from, "plant6", "read-only");
    assert_eq!(live.unit(1)["values"]["U0"], 0);
}

/// A line with no uTile behind it (the port does not exist: the line keeps trying), publishing
/// with the MQTT arguments `mqtt`.
fn portless_live(mqtt: &[&str]) -> Live {
    Live::start(Path::new("/nonexistent/utile-mqtt-tty"), mqtt)
}

#[test]
fn no_state_is_published_before_the_utile_was_read() {
    if !have_mosquitto() {
        return;
    }
    let _one = one_at_a_time();
    let broker = Broker::start("unread");
    let sub = Subscriber::connect(broker.port, &["utile/#"]);
    let mut args = broker.live_args("unread1");
    args.push("--mqtt-commands".into());
    // No uTile behind the line: it is never read.
    let _live = portless_live(&strs(&args));
    sub.wait("utile/unread1/status", T, |p| p == "online");
    sub.wait("utile/unread1/1/availability", T, |p| p == "offline");
    // A refusal goes on the line's session after its first reports, which any state of the
    // uTile would have come before.
    sub.publish("utile/unread1/1/U0/set", b"abc", false);
    refused(&sub, 0, "unread1", "not a whole number");
    let published: Vec<String> = sub
        .all()
        .into_iter()
        .map(|m| m.topic)
        .filter(|t| t.starts_with("utile/unread1/1/"))
        .filter(|t| !t.ends_with("/availability") && !t.ends_with("/error") && !t.ends_with("/set"))
        .collect();
    assert!(
        published.is_empty(),
        "published before the first read: {published:?}"
    );
}

#[test]
fn tls_and_the_login_are_checked_and_refusals_back_off_without_a_crash() {
    if !have_mosquitto() {
        return;
    }
    let _one = one_at_a_time();
    let dir = scratch("mqtt-tls");
    let sub_dir = |name: &str| {
        let d = dir.join(name);
        std::fs::create_dir_all(&d).unwrap();
        d
    };
    let good = Certs::make(&sub_dir("good"), "IP:127.0.0.1");
    let elsewhere = Certs::make(&sub_dir("name"), "DNS:broker.invalid");
    let stranger = Certs::make(&sub_dir("other"), "IP:127.0.0.1");
    let broker = Broker::start_in(dir.clone(), &[&good, &elsewhere]);
    let sub = Subscriber::connect(broker.port, &["utile/#"]);
    let pw = broker.password_file(PASSWORD);
    let pw = pw.to_str().unwrap();
    let tls = |port: u16, ca: &Path, line: &str| -> Vec<String> {
        [
            "--mqtt",
            &format!("mqtts://127.0.0.1:{port}"),
            "--mqtt-ca",
            ca.to_str().unwrap(),
            "--mqtt-user",
            USER,
            "--mqtt-password-file",
            pw,
            "--name",
            line,
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    };

    // The right CA and login: online over TLS; the uTile (no port) offline.
    let live = portless_live(&strs(&tls(broker.tls_ports[0], &good.ca, "tls1")));
    sub.wait("utile/tls1/status", T, |p| p == "online");
    sub.wait("utile/tls1/1/availability", T, |p| p == "offline");
    drop(live);

    // A CA that did not sign the broker's certificate, and a certificate for another name:
    // the trouble in words, retries, the live view goes on.
    for (port, ca, line) in [
        (broker.tls_ports[0], &stranger.ca, "tls2"),
        (broker.tls_ports[1], &elsewhere.ca, "tls3"),
    ] {
        let live = portless_live(&strs(&tls(port, ca, line)));
        let (said, _) = console_line(&live, "TLS with", T);
        assert!(said.contains("--mqtt-ca"), "{said}");
        eprintln!("{line}: {said}");
        std::thread::sleep(Duration::from_millis(500));
        let mut live = live;
        assert!(live.child.try_wait().unwrap().is_none(), "utile live ended");
        assert_eq!(live.state()["port"], "/nonexistent/utile-mqtt-tty");
        assert!(sub.last(&format!("utile/{line}/status")).is_none());
    }

    // A wrong password: said at once, tried again less and less often, no crash.
    let wrong = broker.password_file("not the password");
    let url = broker.url();
    let live = portless_live(&[
        "--mqtt",
        &url,
        "--mqtt-user",
        USER,
        "--mqtt-password-file",
        wrong.to_str().unwrap(),
        "--name",
        "pw1",
    ]);
    let (said, t0) = console_line(&live, "refused the login", T);
    assert!(said.contains("--mqtt-password-file"), "{said}");
    std::thread::sleep(Duration::from_secs(6).saturating_sub(t0.elapsed()));
    let mut live = live;
    assert!(live.child.try_wait().unwrap().is_none(), "utile live ended");
    let log = broker.log_text();
    let tries = log.lines().filter(|l| l.contains("not authorised")).count();
    eprintln!("MEASURE login refused: {tries} tries in 6 s");
    assert!((3..=10).contains(&tries), "{tries} tries in 6 s:\n{log}");
    assert!(sub.last("utile/pw1/status").is_none());
}

/// The bench program of `bench live`: T0 (preset 255, 0.1 s units) runs free, so its time left
/// in each state tells the simulation's pace; U0 drives Y0.
fn bench_program() -> utile_core::engine::Program {
    let mut p = utile_kit::listing::commands(&["TQ0.", "!", ".TK0", "U0.", ".Y0", "END"]);
    p.presets[0] = 255;
    p
}

/// Simulated seconds over a uTile's state messages (T0's time left falls 10 a second and
/// starts again from 255).
fn simulated_secs(states: &[Value]) -> f64 {
    let tl: Vec<i64> = states.iter().filter_map(|s| s["TL0"].as_i64()).collect();
    let fell: i64 = tl
        .windows(2)
        .map(|w| {
            if w[1] <= w[0] {
                w[0] - w[1]
            } else {
                w[0] + 256 - w[1]
            }
        })
        .sum();
    fell as f64 / 10.0
}

/// min / median / max.
fn spread(mut v: Vec<f64>) -> String {
    v.sort_by(f64::total_cmp);
    format!(
        "{:.1} / {:.1} / {:.1}",
        v[0],
        v[v.len() / 2],
        v[v.len() - 1]
    )
}

#[test]
#[ignore = "a benchmark for BENCHMARKS.md: cargo nextest run --release -p utile-tools --test live_mqtt --run-ignored only --no-capture"]
fn bench_one_utile_rig_to_subscriber_and_broker_back() {
    let _one = one_at_a_time();
    let mut broker = Broker::start("bench-one");
    let sub = Subscriber::connect(broker.port, &["utile/#"]);
    let spec = NanoSpec::single("mqtt-bench-one", &bench_program(), false);
    let mut nano = spec.start();
    let args = broker.live_args("bench1");
    let live = Live::start(&spec.link, &strs(&args));
    sub.wait("utile/bench1/1/A0", T, |_| true);
    let mut rig = Vec::new();
    for i in 0..20 {
        // Varied phases of the polling.
        std::thread::sleep(Duration::from_millis(300 + (i * 37) % 100));
        let before = sub.last("utile/bench1/1/A0").unwrap();
        let from = sub.count();
        let t0 = Instant::now();
        nano.key("0");
        let m = sub.wait_from(from, "utile/bench1/1/A0", T, |p| p != before);
        rig.push((m.at - t0).as_secs_f64() * 1e3);
    }
    eprintln!(
        "BENCH rig switch -> subscriber (min / median / max): {} ms",
        spread(rig)
    );
    let mut back = Vec::new();
    for _ in 0..5 {
        broker.down();
        console_line(&live, "cannot reach the broker", T);
        // The client's back-off has reached its longest wait.
        std::thread::sleep(Duration::from_secs(3));
        let t0 = Instant::now();
        broker.up();
        let (_, at) = console_line(&live, "connected again", T);
        back.push((at - t0).as_secs_f64() * 1e3);
    }
    eprintln!(
        "BENCH broker back -> reconnected (min / median / max): {} ms",
        spread(back)
    );
}

#[test]
#[ignore = "a benchmark for BENCHMARKS.md: cargo nextest run --release -p utile-tools --test live_mqtt --run-ignored only --no-capture"]
fn bench_three_lines_of_three_into_one_broker() {
    let _one = one_at_a_time();
    let broker = Broker::start("bench-three");
    let sub = Subscriber::connect(broker.port, &["utile/#"]);
    let mut rigs = Vec::new();
    for l in 0..3 {
        let spec = NanoSpec::bus(&format!("mqtt-bench-bus{l}"), 3, &bench_program());
        let nano = spec.start();
        let mut args = broker.live_args(&format!("bus{l}"));
        args.extend(["--units", "1,2,3"].map(String::from));
        let live = Live::start(&spec.link, &strs(&args));
        rigs.push((nano, live));
    }
    for l in 0..3 {
        for a in 1..=3 {
            sub.wait(&format!("utile/bus{l}/{a}/availability"), T, |p| {
                p == "online"
            });
            sub.wait(&format!("utile/bus{l}/{a}/Y0"), T, |p| p == "0");
        }
    }
    // 10 s: every 0.5 s one uTile's U0 toggled through the page's API, in turn.
    let from = sub.count();
    let t0 = Instant::now();
    let mut toggles = [0u32; 9];
    let mut on = [false; 9];
    let mut k = 0;
    while t0.elapsed() < Duration::from_secs(10) {
        let (l, a) = (k % 3, k / 3 % 3 + 1);
        let i = l * 3 + a - 1;
        on[i] = !on[i];
        let (code, body) = rigs[l].1.post(
            &format!("/api/units/{a}/write"),
            &json!({"signal": "U0", "value": u8::from(on[i])}),
        );
        assert_eq!(code, 200, "{body}");
        toggles[i] += 1;
        k += 1;
        std::thread::sleep(Duration::from_millis(500));
    }
    let wall = t0.elapsed().as_secs_f64();
    std::thread::sleep(Duration::from_secs(2));
    let all = sub.all();
    let mut rates = Vec::new();
    let mut sim_rates = Vec::new();
    for l in 0..3 {
        for a in 1..=3 {
            let i = l * 3 + a - 1;
            let state_topic = format!("utile/bus{l}/{a}/state");
            let states: Vec<Value> = all[from..]
                .iter()
                .filter(|m| m.topic == state_topic && m.at - t0 <= Duration::from_secs_f64(wall))
                .map(|m| json(&m.text))
                .collect();
            let sim = simulated_secs(&states);
            rates.push(states.len() as f64 / wall);
            sim_rates.push(states.len() as f64 / sim.max(0.1));
            // None lost on change: a Y0 message for each change of Y0 between one state
            // and the next (a toggle undone before the uTile was read again is no change).
            let mut last = Some(0);
            let mut changes = Vec::new();
            for st in &states {
                if let Some(y) = st["Y0"].as_u64() {
                    if last != Some(y) {
                        changes.push(y.to_string());
                        last = Some(y);
                    }
                }
            }
            let y0: Vec<String> = all[from..]
                .iter()
                .filter(|m| m.topic == format!("utile/bus{l}/{a}/Y0"))
                .filter(|m| m.at - t0 <= Duration::from_secs_f64(wall))
                .map(|m| m.text.clone())
                .collect();
            assert_eq!(
                y0, changes,
                "bus{l} uTile {a}: Y0 messages against the states' changes"
            );
            eprintln!(
                "bus{l} uTile {a}: {} states in {wall:.1} s ({sim:.1} simulated s), {} toggles, {} Y0 changes",
                states.len(),
                toggles[i],
                y0.len()
            );
        }
    }
    eprintln!(
        "BENCH state updates per second, each uTile (min / median / max): {}",
        spread(rates)
    );
    eprintln!(
        "BENCH state updates per simulated second, each uTile (min / median / max): {}",
        spread(sim_rates)
    );
}
