//! `utile live`'s MQTT flags (`--mqtt URL`, `--mqtt-ca`, `--mqtt-user`,
//! `--mqtt-password-file`, `--name`, `--mqtt-prefix`, `--mqtt-commands`, `--ha-discovery`),
//! the broker's URL, the line's name, and the client's options (credentials, TLS, last will).

use std::time::Duration;

use rumqttc::{LastWill, MqttOptions, QoS, TlsConfiguration, Transport};

use super::payloads::OFFLINE;
use super::topics::Topics;

/// The CA bundle used for `mqtts://` without `--mqtt-ca` (Debian's ca-certificates).
const SYSTEM_CAS: &str = "/etc/ssl/certs/ca-certificates.crt";

/// The MQTT flags as given (clap; flattened into `utile live`'s arguments). Every one but
/// `--mqtt` needs `--mqtt`.
#[derive(clap::Args, Clone, Debug, Default, PartialEq)]
#[command(next_help_heading = "MQTT (docs/LIVE.md)")]
pub struct Flags {
    /// Publish every uTile to this broker: mqtt://HOST[:PORT] or mqtts://HOST[:PORT]
    #[arg(long = "mqtt", value_name = "URL")]
    pub url: Option<String>,
    /// The CA that signed the broker's certificate (mqtts://; default: the system's)
    #[arg(long = "mqtt-ca", value_name = "FILE", requires = "url")]
    pub ca: Option<String>,
    /// The broker's login name
    #[arg(long = "mqtt-user", value_name = "NAME", requires = "url")]
    pub user: Option<String>,
    /// The broker's password, read from this file
    #[arg(long = "mqtt-password-file", value_name = "FILE", requires = "user")]
    pub password_file: Option<String>,
    /// The line's name, one topic level (default: host name and port, e.g. pi-ttyUSB0)
    #[arg(long = "name", value_name = "LINE", requires = "url")]
    pub name: Option<String>,
    /// The topics' prefix (default utile)
    #[arg(long = "mqtt-prefix", value_name = "P", requires = "url")]
    pub prefix: Option<String>,
    /// Take `set` commands from the broker (writes, as the page's)
    #[arg(long = "mqtt-commands", requires = "url")]
    pub commands: bool,
    /// Publish Home Assistant's discovery messages
    #[arg(long = "ha-discovery", requires = "url")]
    pub discovery: bool,
}

/// A MQTT flag's value that cannot be used: the message says what the flag takes.
#[derive(Debug, thiserror::Error)]
pub enum MqttFlagError {
    /// `--mqtt`'s URL.
    #[error(
        "--mqtt takes mqtt://HOST[:PORT] or mqtts://HOST[:PORT] (e.g. mqtt://127.0.0.1:1883), \
         not '{0}'"
    )]
    Url(String),
    /// `--name`.
    #[error("--name takes letters, digits, '-' and '_' (one topic level), not '{0}'")]
    Name(String),
    /// `--mqtt-prefix`.
    #[error("--mqtt-prefix takes topic levels without '+', '#' or a leading '/', not '{0}'")]
    Prefix(String),
    /// `--mqtt-password-file` cannot be read.
    #[error("--mqtt-password-file {file}: {source}")]
    PasswordFile {
        /// The path given.
        file: String,
        /// Why.
        source: std::io::Error,
    },
    /// `--mqtt-ca` (or the system's bundle) cannot be read.
    #[error(
        "--mqtt-ca {file}: {source} (mqtts:// needs the CA that signed the broker's certificate)"
    )]
    CaFile {
        /// The path.
        file: String,
        /// Why.
        source: std::io::Error,
    },
    /// `--mqtt-ca` holds no certificate.
    #[error("--mqtt-ca {0}: no PEM certificate in it")]
    NoPem(String),
    /// `--mqtt-ca` with `mqtt://`.
    #[error("--mqtt-ca is for mqtts:// (TLS); the URL says mqtt://")]
    CaWithoutTls,
}

/// Where the broker is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Broker {
    /// Host name or address.
    pub host: String,
    /// TCP port.
    pub port: u16,
    /// `mqtts://`.
    pub tls: bool,
}

/// `mqtt://HOST[:PORT]` (1883) or `mqtts://HOST[:PORT]` (8883).
pub fn broker(url: &str) -> Result<Broker, MqttFlagError> {
    let bad = || MqttFlagError::Url(url.to_string());
    let (tls, rest) = if let Some(r) = url.strip_prefix("mqtts://") {
        (true, r)
    } else if let Some(r) = url.strip_prefix("mqtt://") {
        (false, r)
    } else {
        return Err(bad());
    };
    let rest = rest.trim_end_matches('/');
    if rest.is_empty() || rest.contains('/') || rest.contains('@') {
        return Err(bad());
    }
    let default = if tls { 8883 } else { 1883 };
    let (host, port) = if let Some(v6) = rest.strip_prefix('[') {
        let (h, p) = v6.split_once(']').ok_or_else(bad)?;
        (h.to_string(), p.strip_prefix(':'))
    } else {
        match rest.rsplit_once(':') {
            Some((h, p)) => (h.to_string(), Some(p)),
            None => (rest.to_string(), None),
        }
    };
    let port = match port {
        Some(p) => p.parse().ok().filter(|p| *p != 0).ok_or_else(bad)?,
        None => default,
    };
    if host.is_empty() {
        return Err(bad());
    }
    Ok(Broker { host, port, tls })
}

/// A name safe as one topic level: letters, digits, `-` and `_`; anything else becomes `_`.
pub fn level(s: &str) -> String {
    s.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

/// This computer's host name.
pub fn host_name() -> String {
    let mut buf = [0u8; 256];
    // SAFETY: gethostname writes at most `buf.len()` bytes into the buffer it is given.
    let r = unsafe { libc::gethostname(buf.as_mut_ptr().cast(), buf.len()) };
    let end = buf.iter().position(|&b| b == 0).unwrap_or(buf.len());
    match std::str::from_utf8(&buf[..end]) {
        Ok(s) if r == 0 && !s.is_empty() => s.to_string(),
        _ => "host".to_string(),
    }
}

/// The line's default name: the host name and the port's file name (`pi-ttyUSB0`).
pub fn default_name(port: &str) -> String {
    let file = std::path::Path::new(port)
        .file_name()
        .map(|f| f.to_string_lossy().into_owned())
        .unwrap_or_else(|| port.to_string());
    level(&format!("{}-{file}", host_name()))
}

/// Everything the client needs, checked at start.
#[derive(Clone, Debug)]
pub struct Settings {
    /// The broker.
    pub broker: Broker,
    /// The topics.
    pub topics: Topics,
    /// `--mqtt-commands`.
    pub commands: bool,
    /// `--ha-discovery`.
    pub discovery: bool,
    /// The login.
    pub login: Option<(String, String)>,
    /// The CA's PEM (mqtts).
    pub ca: Option<Vec<u8>>,
}

impl Settings {
    /// From the flags (`None` without `--mqtt`); `port` is the serial port (the default name).
    /// (Clap has refused the other flags without `--mqtt`.)
    pub fn new(f: &Flags, port: &str) -> Result<Option<Settings>, MqttFlagError> {
        let Some(url) = &f.url else {
            return Ok(None);
        };
        let broker = broker(url)?;
        let name = match &f.name {
            Some(n) if !n.is_empty() && level(n) == *n => n.clone(),
            Some(n) => return Err(MqttFlagError::Name(n.clone())),
            None => default_name(port),
        };
        let prefix = f.prefix.clone().unwrap_or_else(|| "utile".into());
        if prefix.is_empty() || prefix.contains(['+', '#']) || prefix.starts_with('/') {
            return Err(MqttFlagError::Prefix(prefix));
        }
        let login = match (&f.user, &f.password_file) {
            (Some(u), Some(file)) => {
                let text = std::fs::read_to_string(file).map_err(|source| {
                    MqttFlagError::PasswordFile {
                        file: file.clone(),
                        source,
                    }
                })?;
                Some((u.clone(), text.trim_end_matches(['\r', '\n']).to_string()))
            }
            (Some(u), None) => Some((u.clone(), String::new())),
            // Clap has refused --mqtt-password-file without --mqtt-user.
            (None, _) => None,
        };
        let ca = if broker.tls {
            let file = f.ca.clone().unwrap_or_else(|| SYSTEM_CAS.into());
            let pem = match std::fs::read(&file) {
                Ok(pem) => pem,
                Err(source) => return Err(MqttFlagError::CaFile { file, source }),
            };
            if !String::from_utf8_lossy(&pem).contains("BEGIN CERTIFICATE") {
                return Err(MqttFlagError::NoPem(file));
            }
            Some(pem)
        } else {
            if f.ca.is_some() {
                return Err(MqttFlagError::CaWithoutTls);
            }
            None
        };
        Ok(Some(Settings {
            broker,
            topics: Topics::new(&prefix, &name),
            commands: f.commands,
            discovery: f.discovery,
            login,
            ca,
        }))
    }

    /// The line's client's options: its id (`utile-LINE`), the login, TLS, the last will
    /// (`offline` on the line's status, retained), keep-alive, packet sizes.
    pub fn client_options(&self) -> MqttOptions {
        let id = format!("utile-{}", self.topics.line());
        self.options(id, self.topics.status())
    }

    /// The options of uTile `addr`'s own session (`utile-LINE-ADDR`), whose last will is
    /// `offline` on that uTile's availability, retained.
    pub fn unit_options(&self, addr: u8) -> MqttOptions {
        let id = format!("utile-{}-{addr}", self.topics.line());
        self.options(id, self.topics.unit(addr, "availability"))
    }

    /// A session's options: `id`, the login, TLS, `offline` retained on `will` as the last
    /// will, keep-alive, packet sizes.
    fn options(&self, id: String, will: String) -> MqttOptions {
        let mut o = MqttOptions::new(id, self.broker.host.clone(), self.broker.port);
        o.set_keep_alive(Duration::from_secs(10));
        // Big enough that a huge `set` payload is refused by us, not a reason to disconnect.
        o.set_max_packet_size(256 * 1024, 256 * 1024);
        o.set_last_will(LastWill::new(will, OFFLINE, QoS::AtLeastOnce, true));
        if let Some((u, p)) = &self.login {
            o.set_credentials(u.clone(), p.clone());
        }
        if let Some(ca) = &self.ca {
            o.set_transport(Transport::tls_with_config(TlsConfiguration::Simple {
                ca: ca.clone(),
                alpn: None,
                client_auth: None,
            }));
        }
        o
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn urls_give_host_port_and_tls() {
        let b = broker("mqtt://127.0.0.1").unwrap();
        assert_eq!((b.host.as_str(), b.port, b.tls), ("127.0.0.1", 1883, false));
        let b = broker("mqtts://broker.lan:8884/").unwrap();
        assert_eq!((b.host.as_str(), b.port, b.tls), ("broker.lan", 8884, true));
        let b = broker("mqtt://[::1]:1884").unwrap();
        assert_eq!((b.host.as_str(), b.port), ("::1", 1884));
        for bad in [
            "127.0.0.1",
            "http://x",
            "mqtt://",
            "mqtt://h:0",
            "mqtt://h:x",
            "mqtt://u@h",
        ] {
            assert!(broker(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn names_are_one_topic_level() {
        assert_eq!(level("pi/tty USB0+#"), "pi_tty_USB0__");
        assert!(default_name("/dev/ttyUSB0").ends_with("-ttyUSB0"));
        let f = Flags {
            url: Some("mqtt://h".into()),
            name: Some("a/b".into()),
            ..Flags::default()
        };
        let e = Settings::new(&f, "p").unwrap_err();
        assert!(matches!(e, MqttFlagError::Name(_)), "{e}");
        assert!(Settings::new(&Flags::default(), "p").unwrap().is_none());
    }
}
