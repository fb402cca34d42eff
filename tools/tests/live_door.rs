//! `utile live`'s door (issue 37, item 1; `tools/src/live/origin.rs`), as curl would meet it:
//! on its default loopback bind a request naming another host (DNS rebinding) is refused 421
//! whatever it asks, `--allow-host` lets a name in; on every bind a write, a key or the
//! terminal's WebSocket sent with another page's `Origin` (`null` included) is refused 403,
//! while the page's own origin and scripts without an Origin go through; keys by POST take
//! `application/octet-stream` or JSON only (415 for what a form or a no-cors fetch sends).
//! No uTile is needed (the rules are the server's); the browser's side is `live_browser`'s
//! `a_page_of_another_origin_cannot_touch_the_plant`.

mod support;

use std::net::SocketAddr;
use std::path::Path;

use support::live::{exchange, Answer, Live};

/// `utile live` on a port that does not exist, with `extra`; its page as reached through
/// 127.0.0.1.
fn portless(extra: &[&str]) -> (Live, SocketAddr) {
    let live = Live::start(Path::new("/nonexistent/utile-door-tty"), extra);
    let at = SocketAddr::from(([127, 0, 0, 1], live.http.port()));
    (live, at)
}

/// `method path` with the header lines `headers` and `body`.
fn ask(at: SocketAddr, method: &str, path: &str, headers: &[&str], body: &str) -> Answer {
    exchange(at, method, path, headers, body.as_bytes())
}

/// The refusal's words.
fn words(a: &Answer) -> &str {
    a.body["error"].as_str().unwrap_or_default()
}

/// Every request that acts, with a body it would take.
const WRITES: [(&str, &str, &str); 6] = [
    (
        "POST",
        "/api/units/1/write",
        r#"{"signal": "U0", "value": 1}"#,
    ),
    ("POST", "/api/units/1/scan", r#"{"action": "hold"}"#),
    ("POST", "/api/units/1/rig", r#"{"press": 0}"#),
    (
        "POST",
        "/api/units/1/program",
        r#"{"listing": "END", "run": true}"#,
    ),
    ("POST", "/api/check", r#"{"listing": "END"}"#),
    ("POST", "/api/terminal", r#"{"keys": "EX0\r"}"#),
];

/// The terminal's WebSocket handshake from `origin`.
fn websocket(at: SocketAddr, host: &str, origin: Option<&str>) -> Answer {
    let host = format!("Host: {host}");
    let origin = origin.map(|o| format!("Origin: {o}"));
    let mut h = vec![
        host.as_str(),
        "Upgrade: websocket",
        "Connection: Upgrade",
        "Sec-WebSocket-Version: 13",
        "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==",
    ];
    h.extend(origin.as_deref());
    ask(at, "GET", "/api/terminal", &h, "")
}

#[test]
fn on_loopback_a_request_naming_another_host_is_refused() {
    let (live, at) = portless(&[]);
    let port = live.http.port();
    let foreign = format!("Host: evil.example:{port}");
    for (method, path, body) in [("GET", "/api/state", ""), ("GET", "/", "")]
        .into_iter()
        .chain(WRITES)
    {
        let json = "Content-Type: application/json";
        let a = ask(at, method, path, &[&foreign, json], body);
        assert_eq!(a.status, 421, "{method} {path}: {}", a.body);
        assert!(words(&a).contains("DNS rebinding"), "{}", a.body);
        assert!(words(&a).contains("--allow-host"), "{}", a.body);
    }
    assert_eq!(
        websocket(at, &format!("evil.example:{port}"), None).status,
        421
    );
    assert_eq!(
        ask(at, "GET", "/api/state", &["Host: plc.example"], "").status,
        421
    );
    // This computer's own names, with the port or without.
    for host in [
        format!("127.0.0.1:{port}"),
        format!("localhost:{port}"),
        format!("[::1]:{port}"),
        "localhost".to_string(),
    ] {
        let a = ask(at, "GET", "/api/state", &[&format!("Host: {host}")], "");
        assert_eq!(a.status, 200, "{host}: {}", a.body);
    }
    // No Host at all is no browser's request.
    assert_eq!(ask(at, "GET", "/api/state", &[], "").status, 200);
    drop(live);

    // --allow-host lets a reverse proxy's name in, and no other.
    let (_live, at) = portless(&["--allow-host", "plc.example"]);
    assert_eq!(
        ask(at, "GET", "/api/state", &["Host: plc.example"], "").status,
        200
    );
    let a = ask(at, "GET", "/api/state", &["Host: plc.example.evil"], "");
    assert_eq!(a.status, 421, "{}", a.body);
}

#[test]
fn another_pages_origin_is_refused_on_every_write_and_the_websocket() {
    let (live, at) = portless(&[]);
    let own_host = format!("Host: {at}");
    let json = "Content-Type: application/json";
    for origin in [
        "http://localhost:9999",
        &format!("http://localhost:{}", at.port()),
        "http://evil.example",
        "null",
    ] {
        let o = format!("Origin: {origin}");
        for (method, path, body) in WRITES {
            let a = ask(at, method, path, &[&own_host, json, &o], body);
            assert_eq!(a.status, 403, "{origin} {method} {path}: {}", a.body);
            assert!(
                words(&a).contains("only utile live's own page"),
                "{}",
                a.body
            );
        }
        assert_eq!(websocket(at, &at.to_string(), Some(origin)).status, 403);
        // A read is the browser's to keep from the other page.
        assert_eq!(
            ask(at, "GET", "/api/state", &[&own_host, &o], "").status,
            200
        );
    }
    // The page's own origin, and scripts without one, go through the door (the line has no
    // port here: what they get is the line's answer, never a refusal at the door).
    let own = format!("Origin: http://{at}");
    for headers in [
        vec![own_host.as_str(), json, &own],
        vec![own_host.as_str(), json],
    ] {
        for (method, path, body) in WRITES {
            let a = ask(at, method, path, &headers, body);
            assert!(
                ![403, 415, 421].contains(&a.status),
                "{method} {path}: {}",
                a.body
            );
        }
        let a = ask(at, "POST", "/api/check", &headers, r#"{"listing": "END"}"#);
        assert_eq!(a.status, 200, "{}", a.body);
    }
    assert_eq!(
        websocket(at, &at.to_string(), Some(&format!("http://{at}"))).status,
        101
    );
    assert_eq!(websocket(at, &at.to_string(), None).status, 101);
    drop(live);

    // Beyond loopback too, the token notwithstanding.
    let (live, at) = portless(&["--http", "0.0.0.0:0"]);
    let token = loop {
        let line = live
            .console
            .recv_timeout(std::time::Duration::from_secs(30))
            .expect("the token's URL");
        if let Some(t) = line.split("?token=").nth(1) {
            break t.trim().to_string();
        }
    };
    let bearer = format!("Authorization: Bearer {token}");
    let host = format!("Host: pi.local:{}", at.port());
    let (_, path, body) = WRITES[0];
    let foreign = ask(
        at,
        "POST",
        path,
        &[&host, json, &bearer, "Origin: http://evil.example"],
        body,
    );
    assert_eq!(foreign.status, 403, "{}", foreign.body);
    let own = format!("Origin: http://pi.local:{}", at.port());
    let a = ask(at, "POST", path, &[&host, json, &bearer, &own], body);
    assert!(![401, 403, 421].contains(&a.status), "{}", a.body);
}

#[test]
fn keys_by_post_take_bytes_or_json_only() {
    let (_live, at) = portless(&[]);
    let host = format!("Host: {at}");
    for kind in [
        Some("text/plain;charset=UTF-8"),
        Some("application/x-www-form-urlencoded"),
        Some("multipart/form-data; boundary=x"),
        None,
    ] {
        let ct = kind.map(|k| format!("Content-Type: {k}"));
        let mut h = vec![host.as_str()];
        h.extend(ct.as_deref());
        let a = ask(at, "POST", "/api/terminal", &h, "/");
        assert_eq!(a.status, 415, "{kind:?}: {}", a.body);
        assert!(words(&a).contains("application/octet-stream"), "{}", a.body);
    }
    // The door lets bytes and JSON through to the line; with no port open the
    // line itself refuses them (keys never pile up for a freshly reset Nano).
    let bytes = "Content-Type: application/octet-stream";
    let a = ask(at, "POST", "/api/terminal", &[&host, bytes], "EX0\r");
    assert_eq!(a.status, 503, "{}", a.body);
    assert!(words(&a).contains("serial port is closed"), "{}", a.body);
    let json = "Content-Type: application/json";
    let a = ask(
        at,
        "POST",
        "/api/terminal",
        &[&host, json],
        r#"{"keys": "EX0\r"}"#,
    );
    assert_eq!(a.status, 503, "{}", a.body);
    assert!(words(&a).contains("serial port is closed"), "{}", a.body);
    let a = ask(at, "POST", "/api/terminal", &[&host, json], "EX0");
    assert_eq!(a.status, 400, "{}", a.body);
    assert!(words(&a).contains(r#"{"keys""#), "{}", a.body);
}
