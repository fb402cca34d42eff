//! `utile live`'s API and gateway against the real image in the virtual Nano, without a
//! browser (issue 25's bad input and faults): twenty Modbus TCP clients and one sending
//! garbage while the page's polls go on, a dead address that backs off without slowing the
//! others, values out of range refused with the reason and nothing written (on the page's
//! API, and by the uTile through the gateway), `--read-only`.

mod support;

use std::io::Write;
use std::net::TcpStream;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use serde_json::json;
use utile_kit::rng::Rng;

use support::live::{mbap, tank, Live, NanoSpec};

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
    let answered = Arc::new(AtomicU64::new(0));
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
                    answered.fetch_add(1, Ordering::Relaxed);
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
    let n = answered.load(Ordering::Relaxed);
    assert!(n >= 20, "the gateway answered {n} requests");
    // The polls took their turns between the clients' requests all along.
    assert!(seen >= 10, "the page saw {seen} pictures during the load");
    let s = live.state();
    assert_eq!(s["units"][0]["state"], "online", "{s:#}");
    assert!(s["line"]["tcp_requests"].as_u64().unwrap() >= n, "{s:#}");
}

#[test]
fn a_dead_address_backs_off_and_never_slows_the_others() {
    let _one = ONE_AT_A_TIME.lock().unwrap_or_else(|e| e.into_inner());
    let (_nano, live) = tank_live("live-dead", &["--units", "1,7"]);
    let before = live.unit(7)["link"]["requests"].as_u64().unwrap();
    let t0 = Instant::now();
    let seen = pictures_during(&live, 1, || std::thread::sleep(Duration::from_secs(5)));
    let after = live.unit(7);
    let polls = after["link"]["requests"].as_u64().unwrap() - before;
    let secs = t0.elapsed().as_secs_f64();
    assert_eq!(after["state"], "offline", "{after:#}");
    assert!(
        polls as f64 <= secs + 1.0,
        "the dead address was polled {polls} times in {secs:.1} s"
    );
    assert!(seen >= 10, "uTile 1 gave {seen} pictures in {secs:.1} s");
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
    let (code, body) = write("S6", json!(2000));
    assert_eq!(code, 400);
    assert_eq!(body["error"], "set-point S6 takes 0..1023, not 2000");
    let (code, body) = write("T3", json!(256));
    assert_eq!(
        (code, body["error"].as_str().unwrap()),
        (400, "timer preset T3 takes 0..255, not 256")
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
    // Nothing was written: the uTile still has the tank's set-point.
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(live.unit(1)["values"]["S6"], 800);
    // A value the uTile itself refuses, through the gateway: exception 03, nothing changes.
    let mut s = TcpStream::connect(live.tcp).unwrap();
    s.set_read_timeout(Some(T)).unwrap();
    assert_eq!(mbap(&mut s, 1, 1, &[6, 0, 24, 0x07, 0xD0]), [0x86, 3]);
    assert_eq!(mbap(&mut s, 2, 1, &[3, 0, 24, 0, 1]), [3, 2, 0x03, 0x20]);
    // A good write is carried out and shown.
    let (code, body) = write("S6", json!("700"));
    assert_eq!(code, 200, "{body}");
    live.wait_value(1, "S6", 700);
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
