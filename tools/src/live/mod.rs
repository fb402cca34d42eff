//! `utile live --port PATH`: one program owns the serial port and serves every uTile on the
//! line live in the browser, with the terminal beside it on the same cable and a Modbus TCP
//! gateway (docs/LIVE.md). The rooms:
//!
//! | file | what it holds |
//! |---|---|
//! | `args.rs` | the command line |
//! | `port.rs` | opening the port, an adapter's latency timer |
//! | `line/` | the line's owner: the port and everything about the line (open/reopen, the boot wait, EDIT or RUN, one transaction at a time, every uTile's poller, a send's turn on the line); it publishes the view |
//! | `line_use.rs` | line time over a sliding window (the line's busy figure, a uTile's share) |
//! | `rtu.rs` | the RTU master's side of a transaction and the Modbus vocabulary: reply lengths, finding a reply, a missed one's bytes, timing |
//! | `check.rs` | a listing checked by the kit's parser for the page's editor (`POST /api/check`) |
//! | `send.rs` | a program sent from the page (`POST /api/units/{addr}/program`): checked, then `utile push --stop`'s steps as a job of the line |
//! | `rig.rs` | `--rig`: the virtual Nano's rig over its control socket, the API's route for the page's rig panel |
//! | `hold.rs` | SPEC §18 as the tool speaks it: hold, run and step as register writes, whether a uTile's firmware has them |
//! | `scan_control.rs` | hold, run and step: the API's route |
//! | `lease.rs` | holds that keep their word: a lease per holder (a page while it follows the events, a script 10 s past its last request), Run when the last one ran out |
//! | `job.rs` | what the line is asked (a Modbus request, keys, a send) and how its answer comes back: once or not at all |
//! | `queue.rs` | the queue in front of the line: writes first, reads and polls in turn, bounded |
//! | `screen.rs` | EDIT or RUN, told from the terminal's output |
//! | `unit.rs` | one uTile as the line's owner keeps it: snapshot, presets, program, back-off, link health, trend |
//! | `signals.rs` | the signal table: each name, where it is read, how it is written, its range and unit |
//! | `program.rs` | the program, live: listing and each line's value from the core's engine |
//! | `ladder.rs` | the program drawn as ladder for the page's Ladder tab (`GET /api/units/{addr}/ladder`), lit from the line values |
//! | `view.rs` | the immutable view the line publishes after each transaction (the API's state) |
//! | `hub.rs` | where the parts meet: the one way to ask the line, the published view, the state's JSON, the terminal, the pages following |
//! | `api.rs` | the API's documents and its one error type (JSON `{"error": …}`) |
//! | `terminal.rs` | the terminal's output for the pages (xterm.js) |
//! | `http.rs` | the web server: its routes, the events, the terminal WebSocket |
//! | `gateway.rs` | the Modbus TCP gateway |
//! | `origin.rs` | on every bind: what another web page could send is refused (Host, Origin, the keys' type) |
//! | `guard.rs`, `allow.rs` | beyond loopback: the page's token; the gateway's networks |
//! | `mqtt/` | the MQTT publisher, Home Assistant discovery, `set` commands |
//! | `assets.rs`, `page/` | the page's files, built into the binary |

pub mod allow;
pub mod api;
pub mod args;
pub mod assets;
pub mod check;
pub mod gateway;
pub mod guard;
pub mod hold;
pub mod http;
pub mod hub;
pub mod job;
pub mod ladder;
pub mod lease;
pub mod line;
pub mod line_use;
pub mod mqtt;
pub mod origin;
pub mod port;
pub mod program;
pub mod queue;
pub mod rig;
pub mod rtu;
pub mod scan_control;
pub mod screen;
pub mod send;
pub mod signals;
pub mod terminal;
pub mod unit;
pub mod view;

use std::net::SocketAddr;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use utile_core::modbus::snapshot;
use utile_kit::listing;

use hub::Hub;
use program::ProgramFile;
use view::View;

/// Why `utile live` cannot start or go on.
#[derive(Debug, thiserror::Error)]
pub enum LiveError {
    /// The page's files are missing from the build.
    #[error(transparent)]
    Assets(#[from] assets::LibrariesMissing),
    /// `--program`'s file cannot be read.
    #[error("--program {path}: {source}")]
    ProgramFile {
        /// The path given.
        path: String,
        /// Why.
        source: std::io::Error,
    },
    /// `--program`'s listing does not parse.
    #[error("--program {path}: {why}")]
    Listing {
        /// The path given.
        path: String,
        /// The parser's words.
        why: String,
    },
    /// An address cannot be listened on.
    #[error("{flag} {addr}: {source} (is another program listening there? pick another port)")]
    Listen {
        /// `--http` or `--tcp`.
        flag: &'static str,
        /// The address.
        addr: SocketAddr,
        /// Why.
        source: std::io::Error,
    },
    /// A MQTT flag's value cannot be used.
    #[error(transparent)]
    Mqtt(#[from] mqtt::options::MqttFlagError),
    /// `--tcp` beyond loopback without `--tcp-allow`.
    #[error(transparent)]
    TcpAllow(#[from] args::TcpNeedsAllow),
    /// The page's token beyond loopback.
    #[error(transparent)]
    Token(#[from] guard::GuardError),
    /// The line's thread or the runtime cannot start.
    #[error("cannot start {what}: {source}")]
    Start {
        /// What.
        what: &'static str,
        /// Why.
        source: std::io::Error,
    },
}

/// A running live view: its hub and where it listens.
pub struct Running {
    /// Where the parts meet (the published view, the line's inputs).
    pub hub: Arc<Hub>,
    /// What the web server's handlers share (the hub, the rig, the gateway's counters).
    pub app: http::App,
    /// The page's address.
    pub http: SocketAddr,
    /// The gateway's address.
    pub tcp: Option<SocketAddr>,
    line: Option<std::thread::JoinHandle<()>>,
    /// The MQTT client (`--mqtt`), stopped before the line so its last messages say
    /// `offline`.
    mqtt: Option<mqtt::client::Handle>,
}

impl Running {
    /// Publishes `offline` for the line and each uTile (with `--mqtt`) and disconnects from
    /// the broker.
    pub async fn stop_mqtt(&mut self) {
        if let Some(m) = self.mqtt.take() {
            m.stop().await;
        }
    }

    /// Ends the line's owner (the port is closed).
    pub fn stop(&mut self) {
        self.hub.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.line.take() {
            if h.join().is_err() {
                tracing::error!("the line's owner panicked");
            }
        }
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        self.stop();
    }
}

/// Binds `addr` for `flag`.
async fn listen(
    flag: &'static str,
    addr: SocketAddr,
) -> Result<(tokio::net::TcpListener, SocketAddr), LiveError> {
    let err = |source| LiveError::Listen { flag, addr, source };
    let l = tokio::net::TcpListener::bind(addr).await.map_err(err)?;
    let bound = l.local_addr().map_err(err)?;
    Ok((l, bound))
}

/// Starts the line's owner, the web server and the gateway on the current tokio runtime.
/// `say` gets the lines a console shows.
pub async fn start(opts: &args::Options, say: &mut dyn FnMut(&str)) -> Result<Running, LiveError> {
    assets::check()?;
    let mqtt = mqtt::options::Settings::new(&opts.mqtt, &opts.port)?;
    args::check_tcp(opts)?;
    let file = match &opts.program {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|source| LiveError::ProgramFile {
                path: path.clone(),
                source,
            })?;
            let prog = listing::parse(path, &text).map_err(|e| LiveError::Listing {
                path: path.clone(),
                why: e.to_string(),
            })?;
            Some(ProgramFile {
                name: path.clone(),
                fingerprint: snapshot::fingerprint(&prog.uf),
            })
        }
        None => None,
    };
    let mut notes = Vec::new();
    if let Some(note) = port::low_latency(&opts.port) {
        say(&note);
        notes.push(note);
    }
    let (hub, ends) = Hub::new(View::starting(&opts.port, opts.read_only, notes.clone()));
    let app = http::App {
        hub: hub.clone(),
        rig: opts.rig.clone().map(|p| Arc::new(rig::Rig::spawn(p))),
        gateway: Arc::default(),
    };
    let (http, http_addr) = listen("--http", opts.http).await?;
    let guard = guard::Guard::new(&http_addr, opts.token_file.as_deref(), opts.public_read)?;
    let tcp_addr = match opts.tcp {
        Some(a) => {
            let (l, bound) = listen("--tcp", a).await?;
            let (hub, counters) = (hub.clone(), app.gateway.clone());
            let allow = opts.tcp_allow.clone();
            tokio::spawn(async move {
                if let Err(e) = gateway::serve(l, hub, allow, counters).await {
                    tracing::error!(error = %e, "the Modbus TCP gateway stopped");
                }
            });
            Some(bound)
        }
        None => None,
    };
    tokio::spawn(http::serialize_views(app.clone()));
    let token_url = guard.url(&http_addr, &mqtt::options::host_name());
    let door = origin::Door::new(http_addr, &opts.allow_host);
    let router = guard::layer(http::router(app.clone(), door), guard);
    tokio::spawn(async move {
        if let Err(e) = axum::serve(http, router).await {
            tracing::error!(error = %e, "the web server stopped");
        }
    });
    let line = line::spawn(
        line::Options {
            path: opts.port.clone(),
            boot_wait: opts.boot_wait,
            scan: opts.scan,
            units: opts.units.clone(),
            file,
            notes,
        },
        hub.clone(),
        ends,
    )
    .map_err(|source| LiveError::Start {
        what: "the line's thread",
        source,
    })?;
    tracing::info!(
        port = %opts.port,
        page = %format!("http://{http_addr}/"),
        gateway = ?tcp_addr,
        read_only = opts.read_only,
        "utile live listens"
    );
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
    if let Some(r) = &opts.rig {
        say(&format!(
            "the rig panel works the virtual Nano's rig at {}",
            r.display()
        ));
    }
    if opts.read_only {
        say("read-only: every write is refused");
    }
    let mut mqtt_handle = None;
    if let Some(m) = mqtt {
        say(&format!(
            "MQTT: line '{}' to {}:{} (topics {})",
            m.topics.line(),
            m.broker.host,
            m.broker.port,
            m.topics.status().trim_end_matches("/status")
        ));
        let (reports, writes) = mqtt::adapter::start(hub.clone());
        mqtt_handle = Some(mqtt::start(m, reports, writes));
    }
    Ok(Running {
        hub,
        app,
        http: http_addr,
        tcp: tcp_addr,
        line: Some(line),
        mqtt: mqtt_handle,
    })
}

/// `utile live ...`: runs until Ctrl-C or SIGTERM.
/// Runs the live view of `opts` until Ctrl-C or SIGTERM.
pub fn run(opts: &args::Options) -> Result<(), LiveError> {
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|source| LiveError::Start {
            what: "the runtime",
            source,
        })?;
    rt.block_on(async {
        let mut say = |line: &str| eprintln!("utile live: {line}");
        let mut running = start(opts, &mut say).await?;
        let mut term = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate())
            .map_err(|source| LiveError::Start {
                what: "the SIGTERM handler",
                source,
            })?;
        tokio::select! {
            _ = tokio::signal::ctrl_c() => {}
            _ = term.recv() => {}
        }
        tracing::info!("stopping");
        running.stop_mqtt().await;
        running.stop();
        Ok(())
    })
}
