//! Holds and writes that keep their word (issue 37), `utile live` on the real image in the
//! virtual Nano, most of them through a line in between that loses what the test tells it to
//! (`support/between.rs`): an API hold with no page open stays held while the script asks
//! and ends 10 s after its last request; a step of 10 whose reply is lost lands once; a hold
//! whose replies are lost still ends with its lease; a Run lost on its way is sent again until
//! the uTile runs; a write whose asker gave up is never carried out; keys typed while the port
//! is closed are refused, not kept for the next uTile; a page's hold ends 10 s after the page
//! closed; and once `utile live` is killed, the firmware's own lease frees the uTile (in
//! simulated time). The leases' own rules, to the millisecond, are `live::lease`'s unit tests
//! on tokio's paused clock.

mod support;

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use serde_json::{json, Value};
use utile_core::engine::Program;

use support::between::Between;
use support::live::{rig_state, Live, NanoSpec};
use support::vnano::PtyNano;

/// The scenarios share two cores: one at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

const T: Duration = Duration::from_secs(30);

/// The hold (register 32 = 1), the Run (32 = 0) and a step of 10 (33 = 10), as the page
/// sends them.
const HOLD: [u8; 5] = [6, 0, 32, 0, 1];
const RUN: [u8; 5] = [6, 0, 32, 0, 0];
const STEP_10: [u8; 5] = [6, 0, 33, 0, 10];
/// A single-register write's reply: the request echoed (8 bytes with address and CRC).
const ECHO: usize = 8;

/// tests/data/scan_counter.utl: Y0..Y7 count the scans, so the outputs stand still exactly
/// while the scan is held.
fn scan_counter() -> Program {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/scan_counter.utl");
    let text = std::fs::read_to_string(&path).expect("scan_counter.utl");
    utile_kit::listing::parse("scan_counter", &text).expect("the listing")
}

/// The scan counter on a virtual Nano (with its rig's socket), `utile live` on it (through
/// a line in between when `between`), uTile 1 online and known to hold (SPEC §18).
struct Plant {
    live: Live,
    between: Option<Between>,
    socket: PathBuf,
    _nano: PtyNano,
}

impl Plant {
    fn start(name: &str, between: bool) -> Plant {
        let (spec, socket) = NanoSpec::single(name, &scan_counter(), false).with_rig();
        let nano = spec.start();
        let between = between.then(|| Between::start(&spec.link));
        let port = between
            .as_ref()
            .map_or(spec.link.clone(), |b| b.path().into());
        let live = Live::start(&port, &[]);
        live.wait("uTile 1 online, §18 known", T, |s| {
            s["units"][0]["state"] == "online" && s["units"][0]["scan_control"]["supported"] == true
        });
        Plant {
            live,
            between,
            socket,
            _nano: nano,
        }
    }

    fn between(&self) -> &Between {
        self.between.as_ref().expect("a line in between")
    }

    /// `POST /api/units/1/scan` with `body`.
    fn scan(&self, body: Value) -> (u16, Value) {
        self.live.post("/api/units/1/scan", &body)
    }

    /// uTile 1's card state.
    fn state(&self) -> Value {
        self.live.unit(1)["state"].clone()
    }

    /// Holds uTile 1 through the API (no page) and waits until its card says held.
    fn hold(&self) {
        let (code, body) = self.scan(json!({"action": "hold"}));
        assert_eq!(code, 200, "{body}");
        self.live
            .wait("uTile 1 held", T, |s| s["units"][0]["state"] == "held");
    }

    /// Waits until uTile 1 runs freely again, a lease of 10 s after `since` (at most `most`
    /// after it).
    fn runs_after_the_lease(&self, what: &str, since: Instant, most: Duration) {
        self.live
            .wait(what, T * 2, |s| s["units"][0]["state"] == "online");
        let after = since.elapsed();
        eprintln!("{what}: after {after:?}");
        assert!(
            after >= Duration::from_millis(9_500),
            "{what}: after {after:?}"
        );
        assert!(after <= most, "{what}: only after {after:?}");
    }
}

#[test]
fn an_api_hold_with_no_page_open_stays_held_while_asked_and_ends_10_s_after() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let p = Plant::start("holds-api", false);
    // A script holds, and asks again every 4 s: held all along, well past 10 s.
    let mut last = Instant::now();
    for i in 0..4 {
        if i > 0 {
            std::thread::sleep(Duration::from_secs(4));
            assert_eq!(
                p.state(),
                "held",
                "the hold ended {i} × 4 s in, while asked"
            );
        }
        p.hold();
        last = Instant::now();
        p.live.settled_scans(1, 3);
    }
    let outputs = rig_state(&p.socket)["outputs"].clone();
    // The script stops asking: 10 s after its last request, the uTile runs freely again.
    let what = "uTile 1 runs again after the script's last request";
    p.runs_after_the_lease(what, last, Duration::from_secs(15));
    assert_ne!(rig_state(&p.socket)["outputs"], outputs, "the scan runs");
}

#[test]
fn a_step_of_10_whose_reply_is_lost_lands_exactly_once() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let p = Plant::start("holds-step-lost", true);
    p.hold();
    let held = p.live.settled_scans(1, 3);
    // The step reaches the uTile, which runs its 10 scans; its answer is lost on the way back.
    p.between().lose_replies_to(1, &STEP_10, ECHO, 1);
    let (code, body) = p.scan(json!({"action": "step", "n": 10}));
    assert!(p.between().all_lost(T), "the reply was not lost");
    assert_eq!(code, 504, "{body}");
    let error = body["error"].as_str().unwrap();
    assert!(
        error.contains("did not answer step 10") && error.contains("never sent twice"),
        "{error}"
    );
    assert_eq!(p.between().passed(1, &STEP_10), 1, "the step went twice");
    p.live.wait_value(1, "scans", held + 10);
    assert_eq!(p.live.settled_scans(1, 5), held + 10, "10 scans, once");
    assert_eq!(p.state(), "held");
}

#[test]
fn a_hold_whose_replies_are_lost_still_ends_with_its_lease() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let p = Plant::start("holds-hold-lost", true);
    // The hold lands, both its answers are lost (it is harmless twice, so it goes twice).
    p.between().lose_replies_to(1, &HOLD, ECHO, 2);
    let asked = Instant::now();
    let (code, body) = p.scan(json!({"action": "hold"}));
    assert!(p.between().all_lost(T), "the replies were not lost");
    assert_eq!(code, 504, "{body}");
    p.live
        .wait("uTile 1 held", T, |s| s["units"][0]["state"] == "held");
    // utile live's polls renew the firmware's lease without end: utile live's own lease
    // must end the hold it recorded before the write went.
    let what = "uTile 1 runs again after the lost hold's lease";
    p.runs_after_the_lease(what, asked, Duration::from_secs(16));
}

#[test]
fn a_run_lost_on_its_way_is_sent_again_until_the_utile_runs() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let p = Plant::start("holds-run-lost", true);
    p.hold();
    let asked = Instant::now();
    // The lease's Run never reaches the uTile, twice.
    p.between().lose_requests(1, &RUN, 2);
    let what = "uTile 1 runs again after its Run was lost twice";
    p.runs_after_the_lease(what, asked, Duration::from_secs(18));
    assert!(
        p.between().all_lost(Duration::ZERO),
        "the Runs were not lost"
    );
    let writes: Vec<_> = p
        .between()
        .requests()
        .into_iter()
        .filter(|f| f.get(1) == Some(&6))
        .collect();
    assert_eq!(
        p.between().passed(1, &RUN),
        1,
        "the third Run landed: {writes:?}"
    );
}

/// The writes of [`a_write_whose_asker_gave_up_is_never_carried_out`]: every preset and
/// set-point to 7 (the scan counter's timers have 50, its counters and set-points 0; its
/// coils are the program's own, written every scan).
fn preset_writes() -> Vec<(String, i64)> {
    (0..16)
        .map(|i| format!("T{i:X}"))
        .chain((0..8).map(|i| format!("CP{i}")))
        .chain(["S6".to_string(), "S7".to_string()])
        .map(|p| (p, 7))
        .collect()
}

#[test]
fn a_write_whose_asker_gave_up_is_never_carried_out() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let p = Plant::start("holds-asker-gone", true);
    // No reply comes back: each write is tried (twice) and waits out its time-outs, so the
    // line gets to the later ones only after their askers' 5 s.
    p.between().lose_every_reply(true);
    let writes = preset_writes();
    let http = p.live.http;
    let answers: Vec<(String, i64, u16, String)> = std::thread::scope(|s| {
        let asking: Vec<_> = writes
            .iter()
            .map(|(signal, value)| {
                s.spawn(move || {
                    let body = json!({ "signal": signal, "value": value }).to_string();
                    let (code, answer) = support::live::request(
                        http,
                        "POST",
                        "/api/units/1/write",
                        Some(body.as_bytes()),
                    );
                    let error = answer["error"].as_str().unwrap_or_default().to_string();
                    (signal.clone(), *value, code, error)
                })
            })
            .collect();
        asking.into_iter().map(|a| a.join().unwrap()).collect()
    });
    // Replies again: whatever the line still had queued would be carried out now.
    p.between().lose_every_reply(false);
    p.live
        .wait("uTile 1 online", T, |s| s["units"][0]["state"] == "online");
    let (seen, _) = p.live.scans(1);
    p.live.wait("newer snapshots and presets", T, |s| {
        s["units"][0]["snapshots"].as_u64().unwrap_or(0) >= seen + 60
    });
    let values = p.live.unit(1)["values"].clone();
    let given_up: Vec<_> = answers
        .iter()
        .filter(|(_, _, _, e)| e.contains("did not get to it"))
        .collect();
    assert!(
        given_up.len() >= 3,
        "only {} of {} askers gave up: {answers:?}",
        given_up.len(),
        answers.len()
    );
    for (signal, value, code, error) in given_up {
        assert_ne!(
            values[signal.as_str()],
            json!(value),
            "{signal} = {value} was carried out after its asker gave up ({code}: {error}): \
             {values:#}"
        );
        assert_eq!(*code, 503, "{signal}: {error}");
        assert!(error.contains("nothing was sent"), "{signal}: {error}");
    }
}

#[test]
fn keys_typed_while_the_port_is_closed_are_refused_and_never_reach_the_utile() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    // A program with KEY: a `/` that reached it would stop it.
    let prog = utile_kit::listing::parse("key", "A1.\n.Y1\nKEY\nEND\n").unwrap();
    let spec = NanoSpec::single("holds-keys", &prog, false);
    let nano = spec.start();
    let live = Live::start(&spec.link, &[]);
    live.wait("uTile 1 online", T, |s| s["units"][0]["state"] == "online");
    drop(nano);
    live.wait("the port closed", T, |s| s["open"] == false);
    let (code, body) = support::live::post_keys(live.http, b"/");
    // The Nano is back: its program runs, and nothing typed before stops it.
    let _nano = spec.start();
    let back = "uTile 1 back and running (a `/` typed while the port was closed would stop it)";
    live.wait(back, Duration::from_secs(60), |s| {
        s["mode"] == "run" && s["units"][0]["state"] == "online"
    });
    let (seen, _) = live.scans(1);
    let s = live.wait("newer snapshots, or the editor", T, |s| {
        s["mode"] != "run" || s["units"][0]["snapshots"].as_u64().unwrap_or(0) >= seen + 40
    });
    assert_eq!(
        s["mode"], "run",
        "the keys typed while the port was closed came: {s:#}"
    );
    assert_eq!(s["units"][0]["state"], "online", "{s:#}");
    // And the script was told, in words.
    assert_eq!(code, 503, "{body}");
    let error = body["error"].as_str().unwrap();
    assert!(
        error.contains("serial port is closed") && error.contains("nothing was sent"),
        "{error}"
    );
}

#[test]
fn a_pages_hold_ends_10_s_after_the_page_closed() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let p = Plant::start("holds-page", false);
    let page = p.live.open_page(Some("page-a"));
    let (code, body) = p.scan(json!({"action": "hold", "page": "page-a"}));
    assert_eq!(code, 200, "{body}");
    p.live
        .wait("uTile 1 held", T, |s| s["units"][0]["state"] == "held");
    let held = rig_state(&p.socket)["outputs"].clone();
    drop(page);
    let closed = Instant::now();
    assert_eq!(
        rig_state(&p.socket)["outputs"],
        held,
        "held as the page closes"
    );
    let what = "uTile 1 runs again after its page closed";
    p.runs_after_the_lease(what, closed, Duration::from_secs(15));
    assert_ne!(rig_state(&p.socket)["outputs"], held, "the scan runs");
}

#[test]
fn utile_live_killed_while_held_the_lease_frees_the_utile_within_10_s() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut p = Plant::start("holds-killed", false);
    p.hold();
    let socket = p.socket.clone();
    let held = rig_state(&socket)["outputs"].clone();
    // Held for 2 s while utile live polls (and so keeps the lease).
    let t = rig_state(&socket)["seconds"].as_f64().unwrap();
    while rig_state(&socket)["seconds"].as_f64().unwrap() < t + 2.0 {
        std::thread::sleep(Duration::from_millis(100));
    }
    assert_eq!(
        rig_state(&socket)["outputs"],
        held,
        "held while utile live polls"
    );

    // utile live killed (SIGKILL: no goodbye on the line).
    let before = rig_state(&socket)["seconds"].as_f64().unwrap();
    p.live.child.kill().expect("kill utile live");
    p.live.child.wait().expect("utile live ended");
    let after = rig_state(&socket)["seconds"].as_f64().unwrap();
    // Its last frame came before `after`: the lease ends the hold at most 10 s later.
    let start = Instant::now();
    let mut last_held = after;
    let freed_at = loop {
        let s = rig_state(&socket);
        let now = s["seconds"].as_f64().unwrap();
        if s["outputs"] != held {
            break now;
        }
        last_held = now;
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "still held {:.1} s (simulated) after utile live was killed",
            now - after
        );
        std::thread::sleep(Duration::from_millis(50));
    };
    eprintln!(
        "killed at {before:.2}..{after:.2} s, last seen held at {last_held:.2} s, \
         running at {freed_at:.2} s (simulated)"
    );
    assert!(
        last_held >= before + 9.0,
        "the hold ended {:.2} s after the kill, before its 10 s lease",
        last_held - before
    );
    assert!(
        freed_at <= after + 10.5,
        "the hold outlived its lease: still held at {last_held:.2} s, {:.2} s after the kill",
        last_held - after
    );
}
