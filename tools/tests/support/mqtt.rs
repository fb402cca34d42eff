//! The MQTT tests' rig: Debian's `mosquitto` started on free loopback ports with a password
//! file and a TLS listener (certificates made here with the openssl CLI), and a real MQTT
//! client (rumqttc) that subscribes, keeps every message with its time, and publishes.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{channel, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use rumqttc::{Client, Event, MqttOptions, Packet, QoS, Transport};

use super::vnano::scratch;

/// The user and password the brokers take.
pub const USER: &str = "plant";
/// The password of [`USER`].
pub const PASSWORD: &str = "s3cret pass";

/// Whether mosquitto is installed (`./x setup` installs it); prints SKIPPED when not.
pub fn have_mosquitto() -> bool {
    utile_kit::setup::installed(
        "mosquitto",
        Path::new("/usr/sbin/mosquitto").is_file()
            && Path::new("/usr/bin/mosquitto_passwd").is_file(),
    )
}

/// A free TCP port on 127.0.0.1.
pub fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .expect("a free port")
        .port()
}

/// Runs a command that must succeed.
fn run(cmd: &mut Command) {
    let out = cmd.output().expect("run a setup command");
    assert!(
        out.status.success(),
        "{cmd:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A CA and a server certificate it signed for 127.0.0.1 (or `name`), made with openssl.
pub struct Certs {
    /// The CA's certificate (PEM): what `--mqtt-ca` takes.
    pub ca: PathBuf,
    /// The server's certificate.
    pub cert: PathBuf,
    /// The server's key.
    pub key: PathBuf,
}

impl Certs {
    /// A new CA in `dir`, and a server certificate whose subjectAltName is `san`
    /// (`IP:127.0.0.1`).
    pub fn make(dir: &Path, san: &str) -> Certs {
        let p = |f: &str| dir.join(f);
        let ec = [
            "-newkey",
            "ec",
            "-pkeyopt",
            "ec_paramgen_curve:prime256v1",
            "-nodes",
        ];
        run(Command::new("openssl")
            .args(["req", "-x509"])
            .args(ec)
            .arg("-keyout")
            .arg(p("ca.key"))
            .arg("-out")
            .arg(p("ca.crt"))
            .args(["-days", "2", "-subj", "/CN=utile test CA"])
            .args(["-addext", "basicConstraints=critical,CA:TRUE"])
            .args(["-addext", "keyUsage=critical,keyCertSign,cRLSign"]));
        run(Command::new("openssl")
            .arg("req")
            .args(ec)
            .arg("-keyout")
            .arg(p("server.key"))
            .arg("-out")
            .arg(p("server.csr"))
            .args(["-subj", "/CN=utile test broker"]));
        std::fs::write(
            p("server.ext"),
            format!(
                "subjectAltName={san}\nbasicConstraints=CA:FALSE\n\
                 keyUsage=critical,digitalSignature\nextendedKeyUsage=serverAuth\n"
            ),
        )
        .unwrap();
        run(Command::new("openssl")
            .args(["x509", "-req", "-in"])
            .arg(p("server.csr"))
            .arg("-CA")
            .arg(p("ca.crt"))
            .arg("-CAkey")
            .arg(p("ca.key"))
            .args(["-CAcreateserial", "-days", "2", "-out"])
            .arg(p("server.crt"))
            .arg("-extfile")
            .arg(p("server.ext")));
        Certs {
            ca: p("ca.crt"),
            cert: p("server.crt"),
            key: p("server.key"),
        }
    }
}

/// A running mosquitto: a plain listener and, with certificates, a TLS one; a password file
/// (anonymous clients refused). Killed when dropped.
pub struct Broker {
    child: Option<Child>,
    conf: PathBuf,
    /// The plain listener's port.
    pub port: u16,
    /// The TLS listeners' ports, one for each certificate given.
    pub tls_ports: Vec<u16>,
    /// The broker's log file.
    pub log: PathBuf,
    /// The scratch directory.
    pub dir: PathBuf,
}

impl Broker {
    /// Starts a broker named `name` with a plain listener only.
    pub fn start(name: &str) -> Broker {
        let dir = scratch(&format!("broker-{name}"));
        Self::start_in(dir, &[])
    }

    /// Starts a broker whose files go in `dir`, with a TLS listener for each of `certs`.
    pub fn start_in(dir: PathBuf, certs: &[&Certs]) -> Broker {
        let passwd = dir.join("passwd");
        run(Command::new("mosquitto_passwd")
            .args(["-b", "-c"])
            .arg(&passwd)
            .args([USER, PASSWORD]));
        let port = free_port();
        let log = dir.join("mosquitto.log");
        let mut conf = format!(
            "per_listener_settings false\nallow_anonymous false\npassword_file {}\n\
             persistence false\nlog_dest file {}\nlog_type all\n\
             log_timestamp_format %H:%M:%S\nlistener {port} 127.0.0.1\n",
            passwd.display(),
            log.display()
        );
        let mut tls_ports = Vec::new();
        for c in certs {
            let tls_port = free_port();
            tls_ports.push(tls_port);
            conf.push_str(&format!(
                "listener {tls_port} 127.0.0.1\ncafile {}\ncertfile {}\nkeyfile {}\n",
                c.ca.display(),
                c.cert.display(),
                c.key.display()
            ));
        }
        // SAFETY: geteuid only reads the process's effective user id.
        if unsafe { libc::geteuid() } == 0 {
            // As root mosquitto would become the user `mosquitto`, who cannot write here.
            conf.push_str("user root\n");
        }
        let conf_path = dir.join("mosquitto.conf");
        std::fs::write(&conf_path, conf).unwrap();
        let mut b = Broker {
            child: None,
            conf: conf_path,
            port,
            tls_ports,
            log,
            dir,
        };
        b.up();
        b
    }

    /// Starts (again) the broker process and waits until it takes connections.
    pub fn up(&mut self) {
        assert!(self.child.is_none(), "the broker runs already");
        let child = Command::new("/usr/sbin/mosquitto")
            .arg("-c")
            .arg(&self.conf)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("start mosquitto");
        self.child = Some(child);
        let t0 = Instant::now();
        while std::net::TcpStream::connect(("127.0.0.1", self.port)).is_err() {
            assert!(
                t0.elapsed() < Duration::from_secs(10),
                "mosquitto did not start"
            );
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Kills the broker (its retained messages are lost: no persistence).
    pub fn down(&mut self) {
        if let Some(mut c) = self.child.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }

    /// The broker's log.
    pub fn log_text(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }

    /// `mqtt://127.0.0.1:PORT`.
    pub fn url(&self) -> String {
        format!("mqtt://127.0.0.1:{}", self.port)
    }

    /// A password file for `--mqtt-password-file` holding `password`.
    pub fn password_file(&self, password: &str) -> PathBuf {
        let f = self.dir.join(format!("pw-{}", password.len()));
        std::fs::write(&f, format!("{password}\n")).unwrap();
        f
    }

    /// `utile live`'s MQTT arguments with the right login, `--name line`.
    pub fn live_args(&self, line: &str) -> Vec<String> {
        let pw = self.password_file(PASSWORD);
        [
            "--mqtt",
            &self.url(),
            "--mqtt-user",
            USER,
            "--mqtt-password-file",
            pw.to_str().unwrap(),
            "--name",
            line,
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    }
}

impl Drop for Broker {
    fn drop(&mut self) {
        self.down();
    }
}

/// One message as a subscriber got it.
#[derive(Clone, Debug)]
pub struct Message {
    /// Its topic.
    pub topic: String,
    /// Its payload as text.
    pub text: String,
    /// The broker sent it as retained (it was there before the subscription).
    pub retained: bool,
    /// When it arrived.
    pub at: Instant,
}

/// A real MQTT client (rumqttc) subscribed to some topics: every message is kept.
pub struct Subscriber {
    /// For publishing.
    pub client: Client,
    seen: Arc<Mutex<Vec<Message>>>,
    rx: Receiver<()>,
}

impl Subscriber {
    /// Connects to `port` with the right login and subscribes to `filters`.
    pub fn connect(port: u16, filters: &[&str]) -> Subscriber {
        let mut o = MqttOptions::new(format!("test-{}", free_port()), "127.0.0.1", port);
        o.set_credentials(USER, PASSWORD);
        o.set_keep_alive(Duration::from_secs(5));
        o.set_max_packet_size(1 << 20, 1 << 20);
        o.set_transport(Transport::Tcp);
        let (client, mut conn) = Client::new(o, 1024);
        for f in filters {
            client.subscribe(*f, QoS::AtLeastOnce).unwrap();
        }
        let seen = Arc::new(Mutex::new(Vec::new()));
        let (tx, rx): (Sender<()>, Receiver<()>) = channel();
        let kept = seen.clone();
        std::thread::spawn(move || {
            for ev in conn.iter() {
                match ev {
                    Ok(Event::Incoming(Packet::Publish(p))) => {
                        kept.lock().unwrap().push(Message {
                            topic: p.topic.clone(),
                            text: String::from_utf8_lossy(&p.payload).into_owned(),
                            retained: p.retain,
                            at: Instant::now(),
                        });
                        if tx.send(()).is_err() {
                            return;
                        }
                    }
                    Ok(_) => {}
                    Err(_) => std::thread::sleep(Duration::from_millis(100)),
                }
            }
        });
        Subscriber { client, seen, rx }
    }

    /// Every message so far.
    pub fn all(&self) -> Vec<Message> {
        self.seen.lock().unwrap().clone()
    }

    /// The last payload on `topic`, if any.
    pub fn last(&self, topic: &str) -> Option<String> {
        self.all()
            .into_iter()
            .rev()
            .find(|m| m.topic == topic)
            .map(|m| m.text)
    }

    /// Waits for a message on `topic` (after the first `from` messages) whose text passes
    /// `ok`; panics after `timeout` with what came.
    pub fn wait_from(
        &self,
        from: usize,
        topic: &str,
        timeout: Duration,
        ok: impl Fn(&str) -> bool,
    ) -> Message {
        let t0 = Instant::now();
        loop {
            if let Some(m) = self
                .all()
                .into_iter()
                .skip(from)
                .find(|m| m.topic == topic && ok(&m.text))
            {
                return m;
            }
            let left = timeout.saturating_sub(t0.elapsed());
            if left.is_zero() {
                let on: Vec<String> = self
                    .all()
                    .into_iter()
                    .filter(|m| m.topic == topic)
                    .map(|m| m.text)
                    .collect();
                panic!("no fitting message on {topic} within {timeout:?}; it had {on:?}");
            }
            let _ = self.rx.recv_timeout(left.min(Duration::from_millis(100)));
        }
    }

    /// Waits for a message on `topic` whose text passes `ok`.
    pub fn wait(&self, topic: &str, timeout: Duration, ok: impl Fn(&str) -> bool) -> Message {
        self.wait_from(0, topic, timeout, ok)
    }

    /// How many messages came so far.
    pub fn count(&self) -> usize {
        self.seen.lock().unwrap().len()
    }

    /// Publishes `payload` on `topic` (`retain` as given).
    pub fn publish(&self, topic: &str, payload: &[u8], retain: bool) {
        self.client
            .publish(topic, QoS::AtLeastOnce, retain, payload.to_vec())
            .unwrap();
    }
}
