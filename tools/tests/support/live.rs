//! The `utile live` tests' rig: the virtual Nano with a stored program on a pty link,
//! `utile live` on it, a small HTTP client for the API and a raw Modbus TCP client.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver};
use std::time::{Duration, Instant};

use serde_json::Value;
use utile_core::engine::Program;
use utile_core::opcodes;
use utile_kit::listing;

use super::vnano::{eeprom_file, firmware_elf, scratch, PtyNano};

/// The `utile` binary under test.
pub const UTILE: &str = env!("CARGO_BIN_EXE_utile");

/// The tank example (examples/tank-fill.utl), never a copy.
pub fn tank_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/tank-fill.utl")
}

/// The tank example's program.
pub fn tank() -> Program {
    let text = std::fs::read_to_string(tank_path()).expect("the tank example");
    listing::parse("tank-fill", &text).expect("the tank listing")
}

/// The tank example with `U0. .Y2` before its END: a remote command through the program.
pub fn tank_with_remote() -> Program {
    tank_with(&["U0.", ".Y2"])
}

/// The tank example with `words` before its END.
pub fn tank_with(words: &[&str]) -> Program {
    let mut p = tank();
    let end =
        p.uf.iter()
            .position(|&op| op == opcodes::END)
            .expect("the tank's END");
    for (i, word) in words.iter().chain(&["END"]).enumerate() {
        p.uf[end + i] = opcodes::lookup(word.as_bytes()).expect("a command");
    }
    p
}

/// How a virtual Nano is started (again, after a kill).
pub struct NanoSpec {
    /// Its arguments after `--pty`.
    pub args: Vec<String>,
    /// The pty link `utile live` opens.
    pub link: PathBuf,
}

impl NanoSpec {
    /// The Nano (or the `extra`-described bus) running `prog` from its EEPROM, A6 = A7 =
    /// 2.0 V, on a pty link of its own.
    fn with(name: &str, prog: &Program, extra: &[&str]) -> NanoSpec {
        let ee = eeprom_file(name, prog);
        let link = scratch(&format!("{name}-link")).join("tty");
        let elf = firmware_elf();
        let mut args: Vec<String> = ["--elf", elf.to_str().unwrap(), "--eeprom"]
            .iter()
            .map(|s| s.to_string())
            .collect();
        args.push(ee.to_str().unwrap().to_string());
        args.extend(extra.iter().map(|s| s.to_string()));
        args.extend(["--a6", "2.0", "--a7", "2.0", "--link"].map(String::from));
        args.push(link.to_str().unwrap().to_string());
        NanoSpec { args, link }
    }

    /// One Nano autostarting `prog` (D8 fitted), A6 = A7 = 2.0 V; `dtr`: opening the port
    /// resets it, as a Nano's DTR does.
    pub fn single(name: &str, prog: &Program, dtr: bool) -> NanoSpec {
        let mut spec = Self::with(name, prog, &["--d8-low"]);
        if dtr {
            spec.args.push("--dtr-reset".into());
        }
        spec
    }

    /// `n` Nanos on one RS-485 line, each running `prog`, A6 = A7 = 2.0 V.
    pub fn bus(name: &str, n: usize, prog: &Program) -> NanoSpec {
        Self::with(name, prog, &["--bus", &n.to_string()])
    }

    /// Opens its rig's control socket (`--control`, beside the link): the path for
    /// `utile live --rig`.
    pub fn with_rig(mut self) -> (NanoSpec, PathBuf) {
        let socket = self.link.with_file_name("rig.sock");
        self.args.extend([
            "--control".to_string(),
            socket.to_str().unwrap().to_string(),
        ]);
        (self, socket)
    }

    /// Starts it.
    pub fn start(&self) -> PtyNano {
        let args: Vec<&str> = self.args.iter().map(String::as_str).collect();
        PtyNano::start(&args)
    }
}

/// A running `utile live`.
pub struct Live {
    /// The process (killed on drop).
    pub child: Child,
    /// The page's base URL, `http://127.0.0.1:PORT`.
    pub url: String,
    /// The page's address.
    pub http: SocketAddr,
    /// The gateway's address.
    pub tcp: SocketAddr,
    /// Its console lines.
    pub console: Receiver<String>,
}

impl Live {
    /// `utile live --port LINK --http 127.0.0.1:0 --tcp 127.0.0.1:0` plus `extra` (whose own
    /// `--http` or `--tcp` replaces the default: a flag is given once); waits for the
    /// addresses it prints.
    pub fn start(link: &Path, extra: &[&str]) -> Live {
        let mut defaults = Vec::new();
        for flag in ["--http", "--tcp"] {
            if !extra.contains(&flag) {
                defaults.extend([flag, "127.0.0.1:0"]);
            }
        }
        let mut child = Command::new(UTILE)
            .arg("live")
            .arg("--port")
            .arg(link)
            .args(defaults)
            .args(extra)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start utile live");
        let err = BufReader::new(child.stderr.take().expect("stderr"));
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            for line in err.lines().map_while(Result::ok) {
                eprintln!("[utile live] {line}");
                if tx.send(line).is_err() {
                    return;
                }
            }
        });
        let mut http = None;
        let mut tcp = None;
        let deadline = Instant::now() + Duration::from_secs(30);
        while http.is_none() || tcp.is_none() {
            let left = deadline.saturating_duration_since(Instant::now());
            let line = rx
                .recv_timeout(left)
                .unwrap_or_else(|_| panic!("utile live printed no addresses"));
            if let Some(rest) = line.split("http://").nth(1) {
                http = rest.trim_end_matches('/').parse::<SocketAddr>().ok();
            }
            if let Some(rest) = line.split("gateway on ").nth(1) {
                tcp = rest.split_whitespace().next().and_then(|a| a.parse().ok());
            }
        }
        let http = http.unwrap();
        Live {
            child,
            url: format!("http://{http}"),
            http,
            tcp: tcp.unwrap(),
            console: rx,
        }
    }

    /// `GET path`: the status and the JSON body.
    pub fn get(&self, path: &str) -> (u16, Value) {
        request(self.http, "GET", path, None)
    }

    /// `POST path` with a JSON body.
    pub fn post(&self, path: &str, body: &Value) -> (u16, Value) {
        request(self.http, "POST", path, Some(body.to_string().as_bytes()))
    }

    /// `/api/state`.
    pub fn state(&self) -> Value {
        self.get("/api/state").1
    }

    /// The unit `addr` of the state.
    pub fn unit(&self, addr: u64) -> Value {
        let s = self.state();
        s["units"]
            .as_array()
            .and_then(|u| u.iter().find(|u| u["addr"] == addr).cloned())
            .unwrap_or(Value::Null)
    }

    /// Waits until `ok(state)` holds; panics with the state after `timeout`.
    pub fn wait(&self, what: &str, timeout: Duration, ok: impl Fn(&Value) -> bool) -> Value {
        let t0 = Instant::now();
        loop {
            let s = self.state();
            if ok(&s) {
                return s;
            }
            assert!(
                t0.elapsed() < timeout,
                "no {what} within {timeout:?}: {s:#}"
            );
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    /// Snapshots of uTile `addr` taken so far, and the scan count in the latest.
    pub fn scans(&self, addr: u64) -> (u64, u64) {
        let u = self.unit(addr);
        (
            u["snapshots"].as_u64().unwrap_or(0),
            u["values"]["scans"].as_u64().unwrap_or(0),
        )
    }

    /// The scan count of uTile `addr` once `pictures` newer snapshots have come, each
    /// showing the same count (asserted: the scan is held).
    pub fn settled_scans(&self, addr: u64, pictures: u64) -> u64 {
        let (seen, scans) = self.scans(addr);
        self.wait("newer snapshots", Duration::from_secs(30), |s| {
            s["units"].as_array().is_some_and(|u| {
                u.iter().any(|u| {
                    u["addr"] == addr && u["snapshots"].as_u64().unwrap_or(0) >= seen + pictures
                })
            })
        });
        let (_, now) = self.scans(addr);
        assert_eq!(now, scans, "the scan count moved while held");
        now
    }

    /// A page following the events (`GET /api/events`, `?page=NAME` when named), open while
    /// the stream lives.
    pub fn open_page(&self, page: Option<&str>) -> TcpStream {
        let mut s = TcpStream::connect(self.http).expect("connect to the page's server");
        let query = page.map(|p| format!("?page={p}")).unwrap_or_default();
        write!(
            s,
            "GET /api/events{query} HTTP/1.1\r\nHost: {}\r\nAccept: text/event-stream\r\n\r\n",
            self.http
        )
        .expect("ask for the events");
        let mut head = [0u8; 512];
        let n = s.read(&mut head).expect("the events' head");
        assert!(
            head[..n].starts_with(b"HTTP/1.1 200"),
            "{}",
            String::from_utf8_lossy(&head[..n])
        );
        s
    }

    /// Waits until uTile `addr` shows `signal` = `value`.
    pub fn wait_value(&self, addr: u64, signal: &str, value: u64) -> Value {
        self.wait(
            &format!("uTile {addr} {signal} = {value}"),
            Duration::from_secs(30),
            |s| {
                s["units"].as_array().is_some_and(|u| {
                    u.iter()
                        .any(|u| u["addr"] == addr && u["values"][signal] == value)
                })
            },
        )
    }
}

impl Drop for Live {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// The rig's state from the virtual Nano's control socket: no Modbus frame (which would
/// renew a hold's lease).
pub fn rig_state(socket: &Path) -> Value {
    let mut stream = std::os::unix::net::UnixStream::connect(socket).expect("the rig's socket");
    stream.write_all(b"{}\n").expect("ask the rig");
    let mut line = String::new();
    BufReader::new(stream)
        .read_line(&mut line)
        .expect("the rig's answer");
    serde_json::from_str(&line).unwrap_or_else(|e| panic!("{e}: {line}"))
}

/// One HTTP/1.1 request, `Connection: close`: the status and the body as JSON (`Null` if the
/// body is not JSON).
pub fn request(addr: SocketAddr, method: &str, path: &str, body: Option<&[u8]>) -> (u16, Value) {
    let host = format!("Host: {addr}");
    let a = exchange(
        addr,
        method,
        path,
        &[&host, "Content-Type: application/json"],
        body.unwrap_or_default(),
    );
    (a.status, a.body)
}

/// Keys typed by a script: `POST /api/terminal` with the bytes as they are.
pub fn post_keys(addr: SocketAddr, keys: &[u8]) -> (u16, Value) {
    let host = format!("Host: {addr}");
    let a = exchange(
        addr,
        "POST",
        "/api/terminal",
        &[&host, "Content-Type: application/octet-stream"],
        keys,
    );
    (a.status, a.body)
}

/// An answer: status, head (lower case), body as JSON (`Null` if not).
pub struct Answer {
    /// The status code (0 when none came).
    pub status: u16,
    /// The status line and headers, lower case.
    pub head: String,
    /// The body as JSON.
    pub body: Value,
}

/// One HTTP/1.1 request with exactly the header lines `headers` (Host included, or left out)
/// besides `Connection` (`close`, unless a header asks for an upgrade) and `Content-Length`.
/// An upgrade answered 101 is returned at the end of its head.
pub fn exchange(
    addr: SocketAddr,
    method: &str,
    path: &str,
    headers: &[&str],
    body: &[u8],
) -> Answer {
    let mut s = TcpStream::connect(addr).expect("connect to utile live");
    s.set_read_timeout(Some(Duration::from_secs(15))).unwrap();
    let upgrade = headers
        .iter()
        .any(|h| h.to_ascii_lowercase().starts_with("upgrade:"));
    let mut head = format!("{method} {path} HTTP/1.1\r\n");
    for h in headers {
        head.push_str(h);
        head.push_str("\r\n");
    }
    if !upgrade {
        head.push_str("Connection: close\r\n");
    }
    head.push_str(&format!("Content-Length: {}\r\n\r\n", body.len()));
    s.write_all(head.as_bytes()).unwrap();
    s.write_all(body).unwrap();
    let mut got = Vec::new();
    let mut buf = [0u8; 4096];
    loop {
        let upgraded = upgrade && got.windows(4).any(|w| w == b"\r\n\r\n");
        if upgraded {
            break;
        }
        match s.read(&mut buf) {
            Ok(0) | Err(_) => break,
            Ok(n) => got.extend_from_slice(&buf[..n]),
        }
    }
    let text = String::from_utf8_lossy(&got).into_owned();
    let (head, body) = text.split_once("\r\n\r\n").unwrap_or((&text, ""));
    Answer {
        status: head
            .split_whitespace()
            .nth(1)
            .and_then(|c| c.parse().ok())
            .unwrap_or(0),
        head: head.to_ascii_lowercase(),
        body: serde_json::from_str(body).unwrap_or(Value::Null),
    }
}

/// One Modbus TCP request (unit `unit`, PDU `pdu`) on `s`: the reply's PDU.
pub fn mbap(s: &mut TcpStream, id: u16, unit: u8, pdu: &[u8]) -> Vec<u8> {
    let mut frame = Vec::new();
    frame.extend_from_slice(&id.to_be_bytes());
    frame.extend_from_slice(&[0, 0]);
    frame.extend_from_slice(&(pdu.len() as u16 + 1).to_be_bytes());
    frame.push(unit);
    frame.extend_from_slice(pdu);
    s.write_all(&frame).expect("send a Modbus TCP request");
    let mut head = [0u8; 7];
    s.read_exact(&mut head).expect("a Modbus TCP reply");
    assert_eq!(&head[..2], &id.to_be_bytes(), "the reply's transaction id");
    assert_eq!(head[6], unit, "the reply's unit id");
    let len = usize::from(u16::from_be_bytes([head[4], head[5]])) - 1;
    let mut pdu = vec![0u8; len];
    s.read_exact(&mut pdu).expect("the reply's PDU");
    pdu
}
