//! `utile live` beyond loopback (issue 30, item 4): with `--http 0.0.0.0:PORT` (reached here
//! through 127.0.0.1 only) every write and every read of the API needs the token (401 and a
//! JSON error without it, unless `--public-read` for reads), which comes printed as a URL,
//! from `--token-file`, in the cookie that URL sets, or as a Bearer header; the page itself
//! is served so it can ask, and does in words in a real browser (`live_token.py`: the request,
//! a wrong token refused, the printed URL pasted in taken, the plant and a write). `--tcp`
//! beyond loopback needs `--tcp-allow`; other clients are refused and counted. On loopback
//! nothing changes.

mod support;

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use support::live::{exchange, mbap, tank_with_remote, Answer, Live, NanoSpec, UTILE};
use support::vnano::scratch;

const T: Duration = Duration::from_secs(30);

/// One HTTP/1.1 request (Host, and a JSON body) with extra header lines.
fn http(addr: SocketAddr, method: &str, path: &str, headers: &[&str], body: &str) -> Answer {
    let host = format!("Host: {addr}");
    let mut all = vec![host.as_str(), "Content-Type: application/json"];
    all.extend_from_slice(headers);
    exchange(addr, method, path, &all, body.as_bytes())
}

/// `utile live` on a port that does not exist (no uTile needed: the rules are the server's)
/// with `extra`; the page's address as reached through 127.0.0.1.
fn portless(extra: &[&str]) -> (Live, SocketAddr) {
    let live = Live::start(Path::new("/nonexistent/utile-guard-tty"), extra);
    let at = SocketAddr::from(([127, 0, 0, 1], live.http.port()));
    (live, at)
}

/// The token in the URL `live` printed at its start.
fn printed_token(live: &Live) -> String {
    let t0 = Instant::now();
    loop {
        let line = live
            .console
            .recv_timeout(T.saturating_sub(t0.elapsed()))
            .expect("a line with the token's URL");
        if let Some(rest) = line.split("?token=").nth(1) {
            return rest.trim().to_string();
        }
    }
}

const WRITE: &str = r#"{"signal": "U0", "value": 1}"#;

#[test]
fn beyond_loopback_every_read_and_write_needs_the_token() {
    let (live, at) = portless(&["--http", "0.0.0.0:0"]);
    assert!(live.http.ip().is_unspecified(), "{}", live.http);
    let token = printed_token(&live);
    assert_eq!(token.len(), 32, "{token}");

    // Without it: 401 with a JSON error, for reads and writes alike.
    for (method, path, body) in [
        ("GET", "/api/state", ""),
        ("GET", "/api/units/1/trend", ""),
        ("POST", "/api/units/1/write", WRITE),
        ("POST", "/api/terminal", "/"),
    ] {
        let a = http(at, method, path, &[], body);
        assert_eq!(a.status, 401, "{method} {path}");
        assert!(
            a.body["error"].as_str().unwrap().contains("token"),
            "{}",
            a.body
        );
        assert_eq!(a.body["token_needed"], true);
        let wrong = http(
            at,
            method,
            path,
            &["Authorization: Bearer 0123456789abcdef0123456789abcdef"],
            body,
        );
        assert_eq!(wrong.status, 401, "{method} {path} with a wrong token");
        assert!(wrong.body["error"]
            .as_str()
            .unwrap()
            .contains("wrong token"));
    }
    // The terminal's WebSocket carries keys: refused before the upgrade.
    let ws = http(
        at,
        "GET",
        "/api/terminal",
        &[
            "Upgrade: websocket",
            "Connection: Upgrade",
            "Sec-WebSocket-Version: 13",
            "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==",
        ],
        "",
    );
    assert_eq!(ws.status, 401);
    // The page itself is served, so it can ask.
    assert_eq!(http(at, "GET", "/", &[], "").status, 200);

    // The printed URL: its answer sets the cookie, which then opens the API.
    let page = http(at, "GET", &format!("/?token={token}"), &[], "");
    assert_eq!(page.status, 200);
    let cookie_line = page
        .head
        .lines()
        .find(|l| l.starts_with("set-cookie:"))
        .expect("a cookie");
    assert!(cookie_line.contains("httponly") && cookie_line.contains("samesite=strict"));
    let cookie = format!("Cookie: utile_token={token}");
    let a = http(at, "GET", "/api/state", &[&cookie], "");
    assert_eq!(a.status, 200);
    assert_eq!(a.body["port"], "/nonexistent/utile-guard-tty");
    // A write with the token passes the guard (the line has no port: 503, not 401).
    let bearer = format!("Authorization: Bearer {token}");
    let w = http(at, "POST", "/api/units/1/write", &[&bearer], WRITE);
    assert_ne!(w.status, 401, "{}", w.body);
    assert!(
        w.body["error"].as_str().unwrap().contains("serial port"),
        "{}",
        w.body
    );
    let q = http(at, "GET", &format!("/api/state?token={token}"), &[], "");
    assert_eq!(q.status, 200);

    // The page's check of a token typed in: 401 without or wrong, 200 and the cookie right.
    assert_eq!(http(at, "GET", "/api/token", &[], "").status, 401);
    let wrong = http(at, "GET", "/api/token?token=0123456789abcdef", &[], "");
    assert_eq!(wrong.status, 401);
    assert!(wrong.body["error"]
        .as_str()
        .unwrap()
        .contains("wrong token"));
    let right = http(at, "GET", &format!("/api/token?token={token}"), &[], "");
    assert_eq!(right.status, 200);
    assert_eq!(right.body["ok"], true);
    assert!(
        right
            .head
            .contains(&format!("set-cookie: utile_token={token}")),
        "{}",
        right.head
    );
}

#[test]
fn public_read_opens_reads_only_and_a_token_file_gives_the_token() {
    let dir = scratch("guard-token-file");
    let file = dir.join("token");
    let token = "a-token-kept-in-a-file-42";
    std::fs::write(&file, format!("{token}\n")).unwrap();
    let (live, at) = portless(&[
        "--http",
        "0.0.0.0:0",
        "--public-read",
        "--token-file",
        file.to_str().unwrap(),
    ]);
    assert_eq!(printed_token(&live), token);
    assert_eq!(http(at, "GET", "/api/state", &[], "").status, 200);
    // Reads are open, but the page's check of a token still needs the right one.
    assert_eq!(http(at, "GET", "/api/token", &[], "").status, 401);
    assert_eq!(
        http(at, "POST", "/api/units/1/write", &[], WRITE).status,
        401
    );
    assert_eq!(http(at, "POST", "/api/terminal", &[], "/").status, 401);
    let bearer = format!("Authorization: Bearer {token}");
    assert_ne!(
        http(at, "POST", "/api/units/1/write", &[&bearer], WRITE).status,
        401
    );
    drop(live);

    // On loopback nothing is asked.
    let (live, at) = portless(&[]);
    assert_eq!(http(at, "GET", "/api/state", &[], "").status, 200);
    assert_ne!(
        http(at, "POST", "/api/units/1/write", &[], WRITE).status,
        401
    );
    drop(live);

    // A token file with too short a token is refused at start.
    let (started, said) = start_with_token(&dir, "short");
    assert!(!started && said.contains("at least 16"), "{said}");
}

/// `utile live` beyond loopback with `token` in its `--token-file`: whether it started (it
/// is stopped at once), and its console.
fn start_with_token(dir: &Path, token: &str) -> (bool, String) {
    let file = dir.join("token");
    std::fs::write(&file, format!("{token}\n")).unwrap();
    let mut child = Command::new(UTILE)
        .args([
            "live",
            "--port",
            "/nonexistent/x",
            "--http",
            "0.0.0.0:0",
            "--no-tcp",
        ])
        .arg("--token-file")
        .arg(&file)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = child.stderr.take().unwrap();
    // It ends at once when it refuses; started, it prints its page's URL with the token.
    let mut said = String::new();
    let mut buf = [0u8; 4096];
    let t0 = Instant::now();
    while !said.contains("?token=") && t0.elapsed() < T {
        match err.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => said.push_str(&String::from_utf8_lossy(&buf[..n])),
        }
    }
    let started = said.contains("?token=");
    let _ = child.kill();
    let status = child.wait().unwrap();
    assert!(
        started || !status.success(),
        "refused, yet it ended well: {said}"
    );
    (started, said)
}

#[test]
fn a_token_with_characters_the_url_paste_or_cookie_would_change_is_refused_at_start() {
    let dir = scratch("guard-token-characters");
    let (started, said) = start_with_token(&dir, "A-Token_of.its~own-42");
    assert!(started, "{said}");
    assert!(said.contains("?token=A-Token_of.its~own-42"), "{said}");
    for bad in [
        "token+with+plus+signs",
        "token&with=a&query-x",
        "token%41percent-xxxx",
        "token#with-a-hash-xx",
        "token\"quoted\"-xxxxx",
        "token,with,commas-xx",
        "token\\backslash-xxxx",
    ] {
        let (started, said) = start_with_token(&dir, bad);
        assert!(!started, "{bad} was taken: {said}");
        assert!(
            said.contains("a letter (A-Z, a-z), a digit, '-', '.', '_' or '~'"),
            "{bad}: {said}"
        );
    }
}

#[test]
fn the_gateway_beyond_loopback_takes_only_the_allowed_networks() {
    // Without --tcp-allow it does not start.
    let out = Command::new(UTILE)
        .args(["live", "--port", "/nonexistent/x", "--http", "127.0.0.1:0"])
        .args(["--tcp", "0.0.0.0:0"])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--tcp-allow CIDR"), "{err}");

    // 127.0.0.1 is not in 10.0.0.0/8: refused (the connection closed) and counted.
    let (live, _) = portless(&[
        "--tcp",
        "0.0.0.0:0",
        "--tcp-allow",
        "10.0.0.0/8,192.168.0.0/16",
    ]);
    let gw = SocketAddr::from(([127, 0, 0, 1], live.tcp.port()));
    for _ in 0..2 {
        let mut s = TcpStream::connect(gw).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(5))).unwrap();
        let _ = s.write_all(&[0, 1, 0, 0, 0, 6, 1, 3, 0, 0, 0, 1]);
        let mut buf = [0u8; 16];
        assert!(
            matches!(s.read(&mut buf), Ok(0) | Err(_)),
            "no answer to a refused client"
        );
    }
    live.wait("two clients refused", T, |s| {
        s["line"]["tcp_refused_clients"] == 2
    });
    drop(live);

    // 127.0.0.1/32 is allowed: the request gets the gateway's answer (no uTile: exception 0x0B).
    let (live, _) = portless(&["--tcp", "0.0.0.0:0", "--tcp-allow", "127.0.0.1/32"]);
    let gw = SocketAddr::from(([127, 0, 0, 1], live.tcp.port()));
    let mut s = TcpStream::connect(gw).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(15))).unwrap();
    let pdu = mbap(&mut s, 7, 1, &[3, 0, 0, 0, 1]);
    assert_eq!(pdu, [0x83, 0x0B]);
    assert_eq!(live.state()["line"]["tcp_refused_clients"], 0);
}

#[test]
fn the_page_asks_for_the_token_in_words_and_takes_it() {
    assert!(
        Path::new("/usr/bin/chromium").is_file(),
        "/usr/bin/chromium is missing: ./x setup installs Debian's chromium"
    );
    let spec = NanoSpec::single("guard-page", &tank_with_remote(), false);
    let _nano = spec.start();
    let live = Live::start(&spec.link, &["--http", "0.0.0.0:0"]);
    let printed = loop {
        let line = live
            .console
            .recv_timeout(T)
            .expect("a line with the token's URL");
        if let Some(url) = line.split_whitespace().find(|w| w.contains("?token=")) {
            break url.to_string();
        }
    };
    let url = format!("http://127.0.0.1:{}", live.http.port());
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/live_token.py");
    let out = Command::new("python3")
        .arg(&script)
        .args(["--url", &url, "--printed", &printed])
        .stdin(Stdio::null())
        .stderr(Stdio::inherit())
        .output()
        .expect("run python3 live_token.py");
    let said = String::from_utf8_lossy(&out.stdout);
    eprintln!("{said}");
    assert!(
        out.status.success() && said.contains("ALL OK"),
        "live_token.py failed:\n{said}"
    );
}
