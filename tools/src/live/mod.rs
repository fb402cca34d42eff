//! `utile live --port PATH`: one program owns the serial port and serves every uTile on the
//! line live in the browser, with the terminal beside it on the same cable and a Modbus TCP
//! gateway (docs/LIVE.md). The rooms:
//!
//! | file | job |
//! |---|---|
//! | `args.rs` | the command line |
//! | `port.rs` | opening the port, an adapter's latency timer |
//! | `line/` | the line's owner: open/reopen, the boot wait, EDIT or RUN, one transaction at a time |
//! | `line_use.rs` | line time over a sliding window (the line's busy figure, a uTile's share) |
//! | `rtu.rs` | the RTU master's side of a transaction: reply lengths, finding a reply, timing |
//! | `queue.rs` | the queue in front of the line: writes first, reads and polls in turn |
//! | `screen.rs` | EDIT or RUN, told from the terminal's output |
//! | `unit.rs` | one uTile: its picture, presets, program, back-off, link health, trend |
//! | `signals.rs` | the listing's names for values and writes, with their ranges |
//! | `view.rs` | the program, live: listing and each line's value from the core's engine |
//! | `terminal.rs` | the terminal's output for the pages (xterm.js) |
//! | `state.rs` | what the threads share; the API's JSON |
//! | `http.rs` | the web server: page, API, events, writes, terminal WebSocket |
//! | `gateway.rs` | the Modbus TCP gateway |
//! | `guard.rs`, `allow.rs` | beyond loopback: the page's token; the gateway's networks |
//! | `mqtt/` | the MQTT publisher, Home Assistant discovery, `set` commands |
//! | `assets.rs`, `page/` | the page's files, built into the binary |

pub mod allow;
pub mod args;
pub mod assets;
pub mod gateway;
pub mod guard;
pub mod http;
pub mod line;
pub mod line_use;
pub mod mqtt;
pub mod port;
pub mod queue;
pub mod rtu;
pub mod screen;
pub mod signals;
pub mod state;
pub mod terminal;
pub mod unit;
pub mod view;

use std::net::SocketAddr;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

use utile_core::modbus::snapshot;
use utile_kit::listing;

use screen::Mode;
use state::{Live, ProgramFile, Shared};
use unit::Unit;

/// A running live view: its shared state and where it listens.
pub struct Running {
    /// The shared state (the API's source).
    pub shared: Arc<Shared>,
    /// The page's address.
    pub http: SocketAddr,
    /// The gateway's address.
    pub tcp: Option<SocketAddr>,
    line: Option<std::thread::JoinHandle<()>>,
}

impl Running {
    /// Ends the line's owner (the port is closed).
    pub fn stop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.line.take() {
            let _ = h.join();
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Starts the line's owner, the web server and the gateway on the current tokio runtime.
/// `say` gets the lines a console shows.
pub async fn start(opts: &args::Options, say: &mut dyn FnMut(&str)) -> Result<Running, String> {
    assets::check()?;
    let mqtt = mqtt::options::Settings::new(&opts.mqtt, &opts.port).map_err(|e| e.to_string())?;
    args::check_tcp(opts).map_err(|e| e.to_string())?;
    let file = match &opts.program {
        Some(path) => {
            let text =
                std::fs::read_to_string(path).map_err(|e| format!("--program {path}: {e}"))?;
            let prog = listing::parse(path, &text).map_err(|e| e.to_string())?;
            Some(ProgramFile {
                name: path.clone(),
                fingerprint: snapshot::fingerprint(&prog.uf),
            })
        }
        None => None,
    };
    let now = Instant::now();
    let mut notes = Vec::new();
    if let Some(note) = port::low_latency(&opts.port) {
        say(&note);
        notes.push(note);
    }
    let live = Live {
        port: opts.port.clone(),
        open: false,
        mode: Mode::Unknown,
        message: "opening the port".into(),
        notes,
        units: opts.units.iter().map(|&a| Unit::new(a, now)).collect(),
        busy: 0.0,
        stray: 0,
        line_bytes: 0,
        file,
        slack: rtu::ANSWER_SLACK,
    };
    let (shared, inputs) = Shared::new(live, opts.read_only);
    let http = tokio::net::TcpListener::bind(opts.http)
        .await
        .map_err(|e| format!("--http {}: {e}", opts.http))?;
    let http_addr = http.local_addr().map_err(|e| e.to_string())?;
    let guard = guard::Guard::new(&http_addr, opts.token_file.as_deref(), opts.public_read)?;
    let tcp_addr = match opts.tcp {
        Some(a) => {
            let l = tokio::net::TcpListener::bind(a)
                .await
                .map_err(|e| format!("--tcp {a}: {e}"))?;
            let bound = l.local_addr().map_err(|e| e.to_string())?;
            tokio::spawn(gateway::serve(l, shared.clone(), opts.tcp_allow.clone()));
            Some(bound)
        }
        None => None,
    };
    let token_url = guard.url(&http_addr, &mqtt::options::host_name());
    let router = guard::layer(http::router(shared.clone()), guard);
    tokio::spawn(async move {
        let _ = axum::serve(http, router).await;
    });
    let line = line::spawn(
        line::Options {
            path: opts.port.clone(),
            boot_wait: opts.boot_wait,
            scan: opts.scan,
        },
        shared.clone(),
        inputs,
    )
    .map_err(|e| format!("cannot start the line's thread: {e}"))?;
    say(&format!("the page is at http://{http_addr}/"));
    if let Some(t) = tcp_addr {
        say(&format!(
            "Modbus TCP gateway on {t} (unit id = slave address)"
        ));
        if let Some(w) = args::exposed("the Modbus TCP gateway", &t) {
            say(&w);
        }
    }
    if let Some(url) = token_url {
        let reads = if opts.public_read {
            "every write"
        } else {
            "every read and write"
        };
        say(&format!(
            "the page listens beyond this computer: {reads} needs its token; open {url}"
        ));
    }
    if opts.read_only {
        say("read-only: every write is refused");
    }
    if let Some(m) = mqtt {
        say(&format!(
            "MQTT: line '{}' to {}:{} (topics {})",
            m.topics.line(),
            m.broker.host,
            m.broker.port,
            m.topics.status().trim_end_matches("/status")
        ));
        let (reports, writes) = mqtt::adapter::start(shared.clone());
        mqtt::start(m, reports, writes);
    }
    Ok(Running {
        shared,
        http: http_addr,
        tcp: tcp_addr,
        line: Some(line),
    })
}

/// `utile live ...`: runs until Ctrl-C or SIGTERM.
pub fn main(opts: &args::Options) -> Result<(), String> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| format!("cannot start the runtime: {e}"))?;
    rt.block_on(async {
        let mut say = |line: &str| eprintln!("utile live: {line}");
        let mut running = start(opts, &mut say).await?;
        let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())
            .map_err(|e| e.to_string())?;
        tokio::select! {
            _ = tokio::signal::ctrl_c() => {}
            _ = term.recv() => {}
        }
        running.stop();
        Ok(())
    })
}
