//! `utile live`'s API and gateway against the real image in the virtual Nano, without a
//! browser (issue 25's bad input and faults): twenty Modbus TCP clients and one sending
//! garbage while the page's polls go on, a dead address that backs off without slowing the
//! others, values out of range refused with the reason and nothing sent (on the page's
//! API, and by the uTile through the gateway), `--read-only`, every failure answered as JSON
//! (axum's rejections too); and on a pty of the test's own, a line that answers with noise or
//! damaged frames: only a damaged frame counts as a CRC error. Holds and their leases are
//! `live_holds.rs`'s.

mod support;

use std::io::Write;
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde_json::json;
use utile_kit::rng::Rng;

use support::live::{mbap, request, tank, Live, NanoSpec};
use utile_kit::modbus;
use utile_tools::vnano::pty::Pty;

/// The scenarios share two cores: one at a time.
static ONE_AT_A_TIME: Mutex<()> = Mutex::new(());

const T: Duration = Duration::from_secs(30);

/// The tank on one virtual Nano and `utile live` on it with `extra`, uTile 1 online.
fn tank_live(name: &str, extra: &[&str]) -> (support::vnano::PtyNano, Live) {
    let spec = NanoSpec::single(name, &tank(), false);
    let nano = spec.start();
    let live = Live::start(&spec.link, extra);
    live.wait("uTile 1 online", T, |s| {
        s["units"][0]["state"] == "online" && s["units"][0]["values"]["A6"] == 409
    });
    (nano, live)
}

/// Pictures of uTile `addr` seen while `busy` runs (its scan count moving on).
fn pictures_during(live: &Live, addr: u64, busy: impl FnOnce()) -> usize {
    let stop = Arc::new(AtomicBool::new(false));
    let seen = Arc::new(AtomicU64::new(0));
    let watcher = {
        let (stop, seen, http) = (stop.clone(), seen.clone(), live.http);
        std::thread::spawn(move || {
            let mut last = None;
            while !stop.load(Ordering::Relaxed) {
                let (_, s) = support::live::request(http, "GET", "/api/state", None);
                let scans = s["units"]
                    .as_array()
                    .and_then(|u| u.iter().find(|u| u["addr"] == addr))
                    .map(|u| u["values"]["scans"].clone());
                if scans.is_some() && scans != last {
                    seen.fetch_add(1, Ordering::Relaxed);
                    last = scans;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
        })
    };
    busy();
    stop.store(true, Ordering::Relaxed);
    watcher.join().unwrap();
    seen.load(Ordering::Relaxed) as usize
}

#[test]
fn twenty_tcp_clients_and_a_garbage_client_never_starve_the_page() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-clients", &[]);
    let tcp = live.tcp;
    let before = live.state()["line"]["tcp_requests"].as_u64().unwrap();
    let answered: Arc<Vec<AtomicU64>> = Arc::new((0..20).map(|_| AtomicU64::new(0)).collect());
    let seen = pictures_during(&live, 1, || {
        let until = Instant::now() + Duration::from_secs(6);
        let mut threads = Vec::new();
        for c in 0..20u16 {
            let answered = answered.clone();
            threads.push(std::thread::spawn(move || {
                let mut s = TcpStream::connect(tcp).expect("a client connects");
                s.set_read_timeout(Some(T)).unwrap();
                let mut id = c << 8;
                while Instant::now() < until {
                    id = id.wrapping_add(1);
                    // Set-points S6, S7 (holding registers 24, 25): the tank's 800 and 300.
                    let pdu = mbap(&mut s, id, 1, &[3, 0, 24, 0, 2]);
                    assert_eq!(pdu, [3, 4, 0x03, 0x20, 0x01, 0x2C], "client {c}");
                    answered[usize::from(c)].fetch_add(1, Ordering::Relaxed);
                }
            }));
        }
        // Garbage: random bytes, a new connection whenever the gateway drops one.
        threads.push(std::thread::spawn(move || {
            let mut rng = Rng::new(25);
            while Instant::now() < until {
                let Ok(mut s) = TcpStream::connect(tcp) else {
                    continue;
                };
                for _ in 0..20 {
                    let junk: Vec<u8> = (0..64).map(|_| rng.below(256) as u8).collect();
                    if s.write_all(&junk).is_err() {
                        break;
                    }
                    std::thread::sleep(Duration::from_millis(5));
                }
            }
        }));
        for t in threads {
            t.join().expect("a client thread");
        }
    });
    // Every client got its answers (each checked above, in its thread), none was starved.
    let counts: Vec<u64> = answered.iter().map(|a| a.load(Ordering::Relaxed)).collect();
    assert!(
        counts.iter().all(|&n| n >= 1),
        "answers per client: {counts:?}"
    );
    // The polls took their turns between the clients' requests all along.
    assert!(seen >= 10, "the page saw {seen} pictures during the load");
    // The gateway counted each of them (and any request the garbage happened to spell); the
    // line publishes its counters with its next view.
    let total: u64 = counts.iter().sum();
    let s = live.wait("the gateway's count published", T, |s| {
        s["line"]["tcp_requests"].as_u64().unwrap() >= before + total
    });
    assert_eq!(s["units"][0]["state"], "online", "{s:#}");
    let counted = s["line"]["tcp_requests"].as_u64().unwrap() - before;
    assert!(
        counted >= total && counted <= total + 5,
        "the gateway counted {counted} requests, the clients got {total} answers: {s:#}"
    );
}

#[test]
fn a_dead_address_backs_off_and_never_slows_the_others() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-dead", &["--units", "1,7"]);
    live.wait("uTile 7 offline", T, |s| {
        s["units"][1]["state"] == "offline"
    });
    let requests =
        |s: &serde_json::Value, i: usize| s["units"][i]["link"]["requests"].as_u64().unwrap();
    let s0 = live.state();
    let seen = pictures_during(&live, 1, || std::thread::sleep(Duration::from_secs(5)));
    let s1 = live.state();
    let after = &s1["units"][1];
    assert_eq!(after["state"], "offline", "{after:#}");
    // Counted in the line's own turns, not the wall clock: the dead address is still tried,
    // at most once for every three polls of the live one (it backs off to one a second while
    // uTile 1 is polled about 18 times a second; three leaves room for a simulation running
    // at a sixth of the clock on a loaded machine).
    let dead = requests(&s1, 1) - requests(&s0, 1);
    let alive = requests(&s1, 0) - requests(&s0, 0);
    assert!(
        dead >= 1 && dead * 3 <= alive,
        "the dead address was polled {dead} times, the live one {alive}"
    );
    assert!(seen >= 10, "uTile 1 gave {seen} snapshots meanwhile");
    // The gateway answers for the dead address at once with 0x0B.
    let mut s = TcpStream::connect(live.tcp).unwrap();
    s.set_read_timeout(Some(T)).unwrap();
    assert_eq!(mbap(&mut s, 1, 7, &[4, 0, 0, 0, 1]), [0x84, 0x0B]);
}

#[test]
fn values_out_of_range_are_refused_with_the_reason_and_nothing_is_written() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-refused", &[]);
    let write = |signal: &str, value: serde_json::Value| {
        live.post(
            "/api/units/1/write",
            &json!({"signal": signal, "value": value}),
        )
    };
    let writes = || live.state()["line"]["writes"].as_u64().unwrap();
    let before = writes();
    let (code, body) = write("S6", json!(2000));
    assert_eq!(code, 400);
    assert_eq!(body["error"], "set-point S6 takes 0..1023, not 2000");
    let (code, body) = write("T3", json!(256));
    assert_eq!(
        (code, body["error"].as_str().unwrap()),
        (400, "timer preset T3 takes 0..255, not 256")
    );
    // The page shows a preset in its timer's unit: the core's, carried by the state.
    assert_eq!(
        live.state()["timer_unit_ms"],
        json!(utile_core::engine::TIMER_UNIT_MS)
    );
    let (code, body) = write("S6", json!("12ab"));
    assert_eq!(code, 400, "{body}");
    assert!(body["error"].as_str().unwrap().contains("whole number"));
    let (code, body) = write("A0", json!(1));
    assert_eq!(code, 400);
    assert!(body["error"]
        .as_str()
        .unwrap()
        .contains("cannot be written"));
    let (code, _) = live.post("/api/units/5/write", &json!({"signal": "Y0", "value": 1}));
    assert_eq!(code, 404);
    // Nothing went on the line: the tool refused each before the queue (the line's count of
    // writes sent has not moved while the polls went on).
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(writes(), before);
    assert_eq!(live.unit(1)["values"]["S6"], 800);
    // A value the uTile itself refuses, through the gateway: exception 03, nothing changes.
    let mut s = TcpStream::connect(live.tcp).unwrap();
    s.set_read_timeout(Some(T)).unwrap();
    assert_eq!(mbap(&mut s, 1, 1, &[6, 0, 24, 0x07, 0xD0]), [0x86, 3]);
    assert_eq!(mbap(&mut s, 2, 1, &[3, 0, 24, 0, 1]), [3, 2, 0x03, 0x20]);
    // A good write is carried out and shown, and counted (with the gateway's one above).
    let (code, body) = write("S6", json!("700"));
    assert_eq!(code, 200, "{body}");
    live.wait_value(1, "S6", 700);
    assert_eq!(writes(), before + 2);
}

#[test]
fn every_failure_is_answered_as_json_with_its_status() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-errors", &[]);
    let error = |method: &str, path: &str, body: Option<&[u8]>| {
        let (code, json) = request(live.http, method, path, body);
        let why = json["error"]
            .as_str()
            .unwrap_or_else(|| panic!("{method} {path}: {code} without a JSON error: {json}"))
            .to_string();
        (code, why)
    };
    // axum's own rejections: a path with no address, a body that is not JSON.
    let (code, why) = error("GET", "/api/units/300/program", None);
    assert_eq!(code, 400, "{why}");
    assert!(why.contains("\"300\"") && why.contains("1..247"), "{why}");
    let (code, why) = error(
        "POST",
        "/api/units/1/write",
        Some(b"{\"signal\": \"U0\", \"value\":"),
    );
    assert_eq!(code, 400, "{why}");
    assert!(why.starts_with("the body must be JSON"), "{why}");
    let (code, why) = error("POST", "/api/units/1/write", Some(b"[1, 2]"));
    assert_eq!(code, 422, "{why}");
    assert!(why.starts_with("the body must be JSON"), "{why}");
    // The tool's own.
    let (code, why) = error("GET", "/api/units/9/program", None);
    assert_eq!((code, why.as_str()), (404, "no uTile 9 on this line"));
    let (code, why) = error("GET", "/api/units/9/trend", None);
    assert_eq!((code, why.as_str()), (404, "no uTile 9 on this line"));
    let (code, why) = error("GET", "/api/nothing", None);
    assert_eq!(code, 404, "{why}");
    let (code, why) = error("DELETE", "/api/state", None);
    assert_eq!(code, 405, "{why}");
    // What works still answers JSON of its own shape.
    let (code, trend) = live.get("/api/units/1/trend");
    assert_eq!(code, 200);
    assert_eq!(trend["step_ms"], 250);
    assert_eq!(trend["names"][0], "A6");
    let (code, signals) = live.get("/api/signals");
    assert_eq!(code, 200);
    let s6 = signals
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["name"] == "S6")
        .cloned()
        .unwrap();
    assert_eq!(
        (s6["max"].as_u64(), s6["writes"]["register"].as_u64()),
        (Some(1023), Some(24))
    );
    let s = live.state();
    assert_eq!(s["units"][0]["online"], true, "{s:#}");
    assert!(s["units"][0]["values"].get("online").is_none(), "{s:#}");
}

/// What the test's own slave on a pty answers to each request.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Answer {
    /// Text that holds the address and the function side by side, but no reply.
    Noise,
    /// The reply, whole, with its CRC damaged.
    BadCrc,
}

#[test]
fn only_a_damaged_reply_counts_as_a_crc_error() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let mut pty = Pty::open(None).expect("a pty");
    let path = pty.path().to_path_buf();
    let answer = Arc::new(Mutex::new(Answer::Noise));
    let stop = Arc::new(AtomicBool::new(false));
    let slave = {
        let (answer, stop) = (answer.clone(), stop.clone());
        std::thread::spawn(move || {
            let mut got = Vec::new();
            while !stop.load(Ordering::Relaxed) {
                pty.read_into(&mut got);
                // Each request: the snapshot read of uTile 1 (8 bytes with a right CRC).
                while let Some(at) = got.windows(2).position(|w| w == [1, 4]) {
                    if got.len() < at + 8 {
                        break;
                    }
                    let frame: Vec<u8> = got.drain(..at + 8).skip(at).collect();
                    if !modbus::crc_ok(&frame) {
                        continue;
                    }
                    let reply = match *answer.lock().unwrap() {
                        Answer::Noise => b"..\x01\x04..noise..".to_vec(),
                        Answer::BadCrc => {
                            let mut pdu = vec![4, 80];
                            pdu.resize(82, 0);
                            let mut r = modbus::frame(1, &pdu);
                            let last = r.len() - 1;
                            r[last] ^= 0x5A;
                            r
                        }
                    };
                    pty.write(&reply);
                }
                std::thread::sleep(Duration::from_millis(1));
            }
        })
    };
    let live = Live::start(&path, &["--units", "1", "--wait", "0.2"]);
    let link = |live: &Live| live.unit(1)["link"].clone();
    // Noise after three requests: three time-outs, their bytes counted as no reply, and no
    // CRC error.
    live.wait("three answers of noise", T, |s| {
        s["units"][0]["link"]["timeouts"].as_u64() >= Some(3)
    });
    let l = link(&live);
    assert_eq!(l["crc_errors"], 0, "{l:#}");
    assert!(l["not_reply_bytes"].as_u64() >= Some(3 * 13), "{l:#}");
    *answer.lock().unwrap() = Answer::BadCrc;
    let timeouts = l["timeouts"].as_u64().unwrap();
    live.wait("a damaged reply", T, |s| {
        s["units"][0]["link"]["timeouts"].as_u64() > Some(timeouts + 1)
    });
    let l = link(&live);
    assert!(l["crc_errors"].as_u64() >= Some(1), "{l:#}");
    // Each CRC error is one of the time-outs since the noise.
    assert!(
        l["crc_errors"].as_u64() <= l["timeouts"].as_u64().map(|t| t - 3),
        "{l:#}"
    );
    drop(live);
    stop.store(true, Ordering::Relaxed);
    slave.join().expect("the pty's slave");
}

#[test]
fn read_only_refuses_every_write() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-read-only", &["--read-only"]);
    assert_eq!(live.state()["read_only"], true);
    let (code, body) = live.post("/api/units/1/write", &json!({"signal": "U0", "value": 1}));
    assert_eq!(code, 403, "{body}");
    let (code, _) = support::live::request(live.http, "POST", "/api/terminal", Some(b"/"));
    assert_eq!(code, 403);
    let mut s = TcpStream::connect(live.tcp).unwrap();
    s.set_read_timeout(Some(T)).unwrap();
    assert_eq!(mbap(&mut s, 1, 1, &[5, 0, 8, 0xFF, 0]), [0x85, 1]);
    assert_eq!(mbap(&mut s, 2, 1, &[16, 0, 24, 0, 1, 2, 0, 1]), [0x90, 1]);
    // Reads still go through.
    assert_eq!(mbap(&mut s, 3, 1, &[1, 0, 8, 0, 1]), [1, 1, 0]);
    assert_eq!(live.unit(1)["values"]["U0"], 0);
}

#[test]
fn scan_finds_the_utile_on_the_line() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let spec = NanoSpec::single("live-scan", &tank(), false);
    let _nano = spec.start();
    let live = Live::start(&spec.link, &["--scan"]);
    // Report server ID on 1..247: address 1 answers first, and is polled from then on.
    let s = live.wait("uTile 1 found and online", T, |s| {
        s["units"][0]["addr"] == 1 && s["units"][0]["state"] == "online"
    });
    assert_eq!(s["units"].as_array().unwrap().len(), 1, "{s:#}");
    live.wait_value(1, "A6", 409);
}

#[test]
fn hold_run_and_step_through_the_api() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-hold", &[]);
    // A page that follows the events and names itself: its hold lives while it follows them.
    let _page = live.open_page(Some("hold-test"));
    let scan = |mut body: serde_json::Value| {
        body["page"] = json!("hold-test");
        live.post("/api/units/1/scan", &body)
    };
    // The line asked the firmware once whether it holds (SPEC §18): it does.
    live.wait("§18 known", T, |s| {
        s["units"][0]["scan_control"]["supported"] == true
    });
    let (code, body) = scan(json!({"action": "hold"}));
    assert_eq!(code, 200, "{body}");
    let s = live.wait("uTile 1 held", T, |s| s["units"][0]["state"] == "held");
    assert!(
        s["units"][0]["advice"]
            .as_str()
            .unwrap()
            .starts_with("Held"),
        "{s:#}"
    );
    assert_eq!(s["units"][0]["online"], true);
    // Held: the scan count stops (a few snapshots later it has not moved).
    let held = live.settled_scans(1, 3);
    // The gateway passes registers 32-33 like any other: 32 reads 1, 33 no steps left.
    let mut s = TcpStream::connect(live.tcp).unwrap();
    s.set_read_timeout(Some(T)).unwrap();
    assert_eq!(mbap(&mut s, 1, 1, &[3, 0, 32, 0, 2]), [3, 4, 0, 1, 0, 0]);
    // Step 1 and step 10: the count rises by exactly that, and stays.
    let (code, body) = scan(json!({"action": "step", "n": 1}));
    assert_eq!((code, body["n"].as_u64()), (200, Some(1)), "{body}");
    live.wait_value(1, "scans", held + 1);
    assert_eq!(live.settled_scans(1, 3), held + 1);
    let (code, body) = scan(json!({"action": "step", "n": 10}));
    assert_eq!(code, 200, "{body}");
    live.wait_value(1, "scans", held + 11);
    assert_eq!(live.settled_scans(1, 3), held + 11);
    assert_eq!(live.unit(1)["state"], "held");
    // Bad requests are refused with the reason, nothing sent.
    let writes = live.state()["line"]["writes"].as_u64().unwrap();
    let (code, body) = scan(json!({"action": "step", "n": 0}));
    assert_eq!(
        (code, body["error"].as_str().unwrap()),
        (400, "step takes n = 1..1000 scans, not 0")
    );
    let (code, body) = scan(json!({"action": "step", "n": 1001}));
    assert_eq!(code, 400, "{body}");
    let (code, body) = scan(json!({"action": "pause"}));
    assert_eq!(code, 400, "{body}");
    assert!(body["error"]
        .as_str()
        .unwrap()
        .contains("\"pause\" is no action"));
    let (code, _) = live.post("/api/units/9/scan", &json!({"action": "hold"}));
    assert_eq!(code, 404);
    assert_eq!(live.state()["line"]["writes"].as_u64().unwrap(), writes);
    // Run: free again, the count moves on.
    let (code, body) = scan(json!({"action": "run"}));
    assert_eq!(code, 200, "{body}");
    live.wait("uTile 1 running freely", T, |s| {
        s["units"][0]["state"] == "online"
            && s["units"][0]["values"]["scans"].as_u64() > Some(held + 11)
    });
    assert_eq!(mbap(&mut s, 2, 1, &[3, 0, 32, 0, 1]), [3, 2, 0, 0]);
}

#[test]
fn read_only_refuses_hold_and_step() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-hold-read-only", &["--read-only"]);
    for body in [json!({"action": "hold"}), json!({"action": "step", "n": 1})] {
        let (code, answer) = live.post("/api/units/1/scan", &body);
        assert_eq!(code, 403, "{answer}");
        assert!(answer["error"].as_str().unwrap().starts_with("read-only"));
    }
    let (seen, _) = live.scans(1);
    live.wait("newer snapshots", T, |s| {
        s["units"][0]["snapshots"].as_u64().unwrap() >= seen + 3
    });
    assert_eq!(live.unit(1)["state"], "online");
    // Checking a listing sends nothing and works read-only: the messages `utile asm` gives.
    let text = "A0.\n.Y0\nBLAH\n300 END\nT0 = 999\n";
    let file = std::env::temp_dir().join(format!("live-check-{}.utl", std::process::id()));
    std::fs::write(&file, text).unwrap();
    let asm = std::process::Command::new(support::live::UTILE)
        .arg("asm")
        .arg(&file)
        .arg("-o")
        .arg(file.with_extension("hex"))
        .output()
        .expect("utile asm");
    assert!(!asm.status.success());
    let said = String::from_utf8_lossy(&asm.stderr);
    let (code, problems) = live.post("/api/check", &json!({ "listing": text }));
    assert_eq!(code, 200, "{problems}");
    let problems = problems.as_array().unwrap();
    assert_eq!(
        problems.len(),
        said.lines().count(),
        "{problems:?} against {said}"
    );
    for (p, line) in problems.iter().zip(said.lines()) {
        let want = format!(
            "{}:{}: {}",
            file.display(),
            p["line"],
            p["message"].as_str().unwrap()
        );
        assert_eq!(want, line);
    }
    assert_eq!(problems[0]["line"], 3);
    let (code, problems) = live.post("/api/check", &json!({"listing": "A0.\n.Y0\nEND\n"}));
    assert_eq!((code, problems), (200, json!([])));
}

/// The fingerprint of the image `utile asm` makes of `text` (SPEC §17, on the host).
fn asm_fingerprint(name: &str, text: &str) -> u16 {
    let file = std::env::temp_dir().join(format!("{name}-{}.utl", std::process::id()));
    std::fs::write(&file, text).unwrap();
    let hex = file.with_extension("hex");
    let asm = std::process::Command::new(support::live::UTILE)
        .arg("asm")
        .arg(&file)
        .arg("-o")
        .arg(&hex)
        .output()
        .expect("utile asm");
    assert!(asm.status.success(), "{asm:?}");
    let prog = utile_kit::listing::from_hex(&std::fs::read(&hex).unwrap()).unwrap();
    utile_core::modbus::snapshot::fingerprint(&prog.uf)
}

#[test]
fn a_program_without_key_running_is_refused_and_nothing_is_sent() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-send-no-key", &[]);
    // The running program's fingerprint, once the line has read it (null until then).
    let s = live.wait("the tank's program read", T, |s| {
        !s["units"][0]["program"]["fingerprint"].is_null()
    });
    let fp = s["units"][0]["program"]["fingerprint"].clone();
    let (code, body) = live.post(
        "/api/units/1/program",
        &json!({"listing": "A0.\n.Y0\nKEY\nEND\n", "store": false, "run": true}),
    );
    assert_eq!(code, 409, "{body}");
    assert!(body["error"]
        .as_str()
        .unwrap()
        .contains("stop it at the uTile — remove D8 and reset — or add KEY"));
    // The tank still runs its own program, polled again.
    live.wait("the tank polled again", T, |s| {
        s["units"][0]["state"] == "online" && s["units"][0]["program"]["fingerprint"] == fp
    });
}

#[test]
fn send_checks_stops_loads_verifies_stores_and_starts() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let first = "A1.\n.Y1\nKEY\nEND\n";
    let prog = utile_kit::listing::parse("first", first).unwrap();
    let spec = NanoSpec::single("live-send", &prog, false);
    let mut nano = spec.start();
    let live = Live::start(&spec.link, &[]);
    let old = u64::from(asm_fingerprint("live-send-first", first));
    live.wait("uTile 1 runs the first program", T, |s| {
        s["units"][0]["state"] == "online" && s["units"][0]["program"]["fingerprint"] == old
    });
    let send = |listing: &str, store: bool| {
        live.post(
            "/api/units/1/program",
            &json!({"listing": listing, "store": store, "run": true}),
        )
    };
    // A listing with a mistake: 400 with its line, and nothing goes on the line.
    let before = live.state()["line"].clone();
    let bad = "A0.\n.Y0\nBLAH\nKEY\nEND\n";
    let (code, body) = send(bad, false);
    assert_eq!((code, body["line"].as_u64()), (400, Some(3)), "{body}");
    let said = utile_kit::listing::parse("x", bad).unwrap_err();
    assert!(body["error"]
        .as_str()
        .unwrap()
        .contains(&said.problems[0].message));
    let after = live.state()["line"].clone();
    assert_eq!(after["writes"], before["writes"]);
    assert_eq!(live.unit(1)["program"]["fingerprint"], old);
    // The corrected listing: running, with `utile asm`'s fingerprint.
    let good = "A0.\n.Y0\nKEY\nEND\n";
    let want = asm_fingerprint("live-send-good", good);
    assert_ne!(u64::from(want), old);
    let (code, body) = send(good, true);
    assert_eq!(code, 200, "{body}");
    assert_eq!(body["fingerprint"].as_u64(), Some(u64::from(want)));
    eprintln!("send: {} ms on the line", body["ms"]);
    let s = live.wait("uTile 1 runs the new program", T, |s| {
        s["units"][0]["state"] == "online"
            && s["units"][0]["program"]["fingerprint"] == u64::from(want)
            && s["units"][0]["program"]["consistent"] == true
    });
    assert_eq!(s["mode"], "run", "{s:#}");
    // STOREd: another program sent without STORE runs until a reset; then (D8 fitted) the
    // stored one autostarts from EEPROM.
    let third = "A2.\n.Y2\nKEY\nEND\n";
    let third_fp = asm_fingerprint("live-send-third", third);
    let (code, body) = send(third, false);
    assert_eq!(code, 200, "{body}");
    live.wait("uTile 1 runs the third program", T, |s| {
        s["units"][0]["program"]["fingerprint"] == u64::from(third_fp)
    });
    live.wait("a million scans", T, |s| {
        s["units"][0]["values"]["scans"].as_u64() > Some(1_000_000)
    });
    nano.key("r");
    live.wait("the stored program autostarted after the reset", T, |s| {
        s["units"][0]["state"] == "online"
            && s["units"][0]["values"]["scans"].as_u64() < Some(1_000_000)
            && s["units"][0]["program"]["fingerprint"] == u64::from(want)
    });
    // A whole 256-line program (a free-running clock first: T0 = 25.5 s, its time left in
    // the snapshot), not stored.
    let mut long = String::from("TQ0.\n!\n.TK0\n");
    for i in 0..252 {
        long.push_str(&match i % 2 {
            0 => format!("A{}.\n", i / 2 % 6),
            _ => format!(".V{}\n", i / 2 % 8),
        });
    }
    long.push_str("END\nT0 = 255\n");
    assert_eq!(
        utile_kit::listing::parse("long", &long).unwrap().uf[255],
        utile_core::opcodes::END
    );
    let long_fp = asm_fingerprint("live-send-long", &long);
    let (code, body) = send(&long, false);
    assert_eq!(code, 200, "{body}");
    assert_eq!(body["fingerprint"].as_u64(), Some(u64::from(long_fp)));
    let s = live.wait("uTile 1 runs the 256-line program", T, |s| {
        s["units"][0]["program"]["fingerprint"] == u64::from(long_fp)
            && s["units"][0]["program"]["consistent"] == true
    });
    // The simulation's pace (its clock against the wall's), for the figure's meaning.
    let (tl0, w0) = (
        s["units"][0]["values"]["TL0"].as_u64().unwrap(),
        Instant::now(),
    );
    std::thread::sleep(Duration::from_secs(3));
    let tl1 = live.unit(1)["values"]["TL0"].as_u64().unwrap();
    // T0's time left counts down from 255 tenths and restarts.
    let pace = ((tl0 + 255 - tl1) % 255) as f64 / 10.0 / w0.elapsed().as_secs_f64();
    eprintln!(
        "send of 256 lines: {} ms on the line; the simulation then ran at {pace:.2}× the clock",
        body["ms"]
    );
    // Read-only refuses a send.
    drop(live);
    let live = Live::start(&spec.link, &["--read-only"]);
    live.wait("online read-only", T, |s| {
        s["units"][0]["state"] == "online"
    });
    let (code, body) = live.post(
        "/api/units/1/program",
        &json!({"listing": good, "store": false, "run": true}),
    );
    assert_eq!(code, 403, "{body}");
}

#[test]
fn the_port_lost_mid_send_is_answered_with_what_happened() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let first = "A1.\n.Y1\nKEY\nEND\n";
    let prog = utile_kit::listing::parse("first", first).unwrap();
    let spec = NanoSpec::single("live-send-lost", &prog, false);
    let nano = spec.start();
    let live = Live::start(&spec.link, &[]);
    let old = u64::from(asm_fingerprint("live-send-lost-first", first));
    live.wait("uTile 1 runs the first program", T, |s| {
        s["units"][0]["state"] == "online" && s["units"][0]["program"]["fingerprint"] == old
    });
    // A long listing: READ takes a good part of the send.
    let mut long = String::new();
    for i in 0..60 {
        long.push_str(&format!("A{}.\n.Y{}\n", i % 6, i % 8));
    }
    long.push_str("KEY\nEND\n");
    let (url, body) = (
        live.url.clone(),
        json!({"listing": long, "store": false, "run": true}),
    );
    let started = Instant::now();
    let send = std::thread::spawn(move || {
        let addr = url.trim_start_matches("http://").parse().unwrap();
        let bytes = body.to_string();
        request(addr, "POST", "/api/units/1/program", Some(bytes.as_bytes()))
    });
    live.wait("the send under way", T, |s| {
        s["message"]
            .as_str()
            .unwrap_or("")
            .starts_with("sending a program")
    });
    // The stop and READ's screen take about 0.2 s: then the records are on their way (0.45 s
    // of them at 19200 baud). Wherever the port goes, the answer says so (504).
    std::thread::sleep(Duration::from_millis(400));
    drop(nano);
    let (code, answer) = send.join().unwrap();
    assert_eq!(code, 504, "{answer}");
    let error = answer["error"].as_str().unwrap();
    assert!(
        error.contains("serial port was lost") && error.contains("whole program"),
        "{error}"
    );
    assert!(started.elapsed() < Duration::from_secs(20));
    // Back: the uTile runs a whole program (its lines give the fingerprint it shows).
    let _nano = spec.start();
    let s = live.wait("uTile 1 back", Duration::from_secs(60), |s| {
        s["units"][0]["state"] == "online" && s["units"][0]["program"]["consistent"] == true
    });
    assert_eq!(s["units"][0]["program"]["fingerprint"], old, "{s:#}");
}

/// The tank on one virtual Nano with its rig's control socket, and `utile live --rig` on it
/// with `extra`: uTile 1 online, the rig connected.
fn tank_live_with_rig(name: &str, extra: &[&str]) -> (support::vnano::PtyNano, Live) {
    let (spec, socket) = NanoSpec::single(name, &tank(), false).with_rig();
    let nano = spec.start();
    let mut args = vec!["--rig", socket.to_str().unwrap()];
    args.extend_from_slice(extra);
    let live = Live::start(&spec.link, &args);
    let s = live.wait("uTile 1 online, the rig connected", T, |s| {
        s["units"][0]["state"] == "online"
            && s["units"][0]["values"]["A6"] == 409
            && s["rig"]["connected"] == true
    });
    assert_eq!(s["rig"]["path"], socket.to_str().unwrap());
    (nano, live)
}

#[test]
fn the_rig_through_the_api_presses_a0_and_moves_a6() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live_with_rig("live-rig", &[]);
    assert_eq!(live.state()["rig"]["nanos"][0]["switches"][0], false);
    assert_eq!(live.unit(1)["values"]["A0"], 1);
    let (code, body) = live.post("/api/units/1/rig", &json!({"press": 0}));
    assert_eq!(code, 200, "{body}");
    assert_eq!(body["switches"][0], true, "{body}");
    assert_eq!(
        body["pins"][0], false,
        "a pressed switch pulls its pin low: {body}"
    );
    live.wait_value(1, "A0", 0);
    live.wait("the state's rig with A0 pressed", T, |s| {
        s["rig"]["nanos"][0]["switches"][0] == true
    });
    let (code, body) = live.post("/api/units/1/rig", &json!({"release": 0}));
    assert_eq!((code, &body["switches"][0]), (200, &json!(false)), "{body}");
    live.wait_value(1, "A0", 1);
    // The level below the low mark (1.47 V; the example wires one sensor to A6 and A7): the
    // tank's alarm Y1 and its pump Y0 come on.
    let (code, body) = live.post("/api/units/1/rig", &json!({"a6": 1.0, "a7": 1.0}));
    assert_eq!(
        (code, &body["a6"], &body["a7"]),
        (200, &json!(1.0), &json!(1.0)),
        "{body}"
    );
    let s = live.wait("A6 at 1.0 V and the alarm on", T, |s| {
        let u = &s["units"][0]["values"];
        u["A6"].as_u64().is_some_and(|a| (200..=210).contains(&a)) && u["Y1"] == 1
    });
    assert_eq!(
        s["units"][0]["values"]["Y0"], 1,
        "the pump starts below the low mark"
    );
    // Refused whole, with the rig's reason; nothing changes.
    let (code, body) = live.post("/api/units/1/rig", &json!({"a6": 3.0, "press": 9}));
    assert_eq!(code, 400, "{body}");
    assert!(body["error"].as_str().unwrap().contains("0..5"), "{body}");
    assert_eq!(live.post("/api/units/1/rig", &json!({})).1["a6"], 1.0);
    let (code, body) = live.post("/api/units/1/rig", &json!([1, 2]));
    assert_eq!(code, 400, "{body}");
    assert!(
        body["error"].as_str().unwrap().contains("one JSON object"),
        "{body}"
    );
    let (code, body) = live.post("/api/units/7/rig", &json!({"press": 0}));
    assert_eq!(code, 404, "{body}");
    assert_eq!(body["error"], "no uTile 7 on this line");
}

#[test]
fn read_only_refuses_the_rig_and_without_rig_there_is_none() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    {
        let (_nano, live) = tank_live_with_rig("live-rig-read-only", &["--read-only"]);
        let (code, body) = live.post("/api/units/1/rig", &json!({"press": 0}));
        assert_eq!(code, 403, "{body}");
        assert!(body["error"].as_str().unwrap().starts_with("read-only"));
        assert_eq!(live.state()["rig"]["nanos"][0]["switches"][0], false);
        assert_eq!(live.unit(1)["values"]["A0"], 1);
    }
    let (_nano, live) = tank_live("live-no-rig", &[]);
    assert_eq!(live.state()["rig"], serde_json::Value::Null);
    let (code, body) = live.post("/api/units/1/rig", &json!({"press": 0}));
    assert_eq!(code, 404, "{body}");
    assert!(body["error"].as_str().unwrap().contains("--rig"), "{body}");
}

/// `GET /api/units/{addr}/ladder` (the Ladder tab's drawing): the running tank's rungs by the
/// kit's drawer, its fingerprint the state's, each element with the lines of its power; the
/// tank's `Q0. .Y0` coil lit from the state's line values shows the bit its pop takes; an
/// address with no uTile or none at all is answered as JSON.
#[test]
fn the_ladder_of_the_running_program() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-ladder-api", &[]);
    let s = live.wait("the tank's program read", T, |s| {
        s["units"][0]["program"]["values"]
            .as_str()
            .is_some_and(|v| !v.is_empty())
    });
    let (code, doc) = live.get("/api/units/1/ladder");
    assert_eq!(code, 200, "{doc}");
    assert_eq!(doc["fingerprint"], s["units"][0]["program"]["fingerprint"]);
    assert_eq!(doc["consistent"], true);
    assert_eq!(doc["counter_presets"].as_array().map(Vec::len), Some(8));
    let svg = doc["svg"].as_str().unwrap();
    assert!(svg.starts_with("<svg"), "{svg}");
    for signal in ["H6", "R0", "H7", "S0", "Q0", "Y0", "Y1"] {
        assert!(
            svg.contains(&format!("data-signal=\"{signal}\"")),
            "{signal}: {svg}"
        );
    }
    // The tank's lines 005 Q0. 006 .Y0: the coil's power is line 5's value, the bit the pop
    // on line 6 takes, in every picture.
    assert!(
        svg.contains("<g class=\"coil\" data-rung=\"2\" data-signal=\"Y0\" data-lines=\"6\" data-power-lines=\"5\">"),
        "{svg}"
    );
    let values = live.state()["units"][0]["program"]["values"]
        .as_str()
        .unwrap()
        .to_string();
    assert_eq!(values.as_bytes()[5], values.as_bytes()[6], "{values}");
    let error = |path: &str| {
        let (code, json) = request(live.http, "GET", path, None);
        (code, json["error"].as_str().unwrap_or_default().to_string())
    };
    assert_eq!(
        error("/api/units/9/ladder"),
        (404, "no uTile 9 on this line".to_string())
    );
    let (code, why) = error("/api/units/300/ladder");
    assert_eq!(code, 400, "{why}");
    assert!(why.contains("\"300\""), "{why}");
}
