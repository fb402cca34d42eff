//! The command line of `utile live` (clap): [`LiveArgs`] as typed, then [`Options`], what
//! the rest of `live` consumes.

use std::net::SocketAddr;
use std::time::Duration;

use clap::Parser;

use super::allow::Cidr;
use super::mqtt::options::Flags;
use super::origin::host_name;
use crate::cli::{socket_address, BootWait};

/// The examples under `utile live --help`.
const EXAMPLES: &str = "\
Examples:
  utile live --port /dev/ttyUSB0                   uTile 1 on the page at http://127.0.0.1:8080/
  utile live --port /dev/ttyUSB0 --units 1,2,3     three uTiles on one RS-485 line
  utile live --port /dev/ttyUSB0 --scan            look for every uTile on the line
  utile live --port /tmp/utile-tty --http 8081 --program examples/tank-fill.utl
  utile live --port /dev/ttyUSB0 --http 0.0.0.0:8080 --read-only --no-tcp
  utile live --port /dev/ttyUSB0 --http 0.0.0.0:8080 --tcp 0.0.0.0:1502 --tcp-allow 192.168.1.0/24
  utile live --port /dev/ttyUSB0 --mqtt mqtt://127.0.0.1 --ha-discovery --mqtt-commands

Security (docs/LIVE.md): no other web page can act here (its Host and Origin are checked;
--allow-host NAME lets a reverse proxy's name in). Beyond loopback the page needs a token
(printed at start, or --token-file FILE) for every write, and for reads unless --public-read;
the gateway needs --tcp-allow with its clients' networks.";

/// The help's heading for the security flags.
const SECURITY: &str = "Security (docs/LIVE.md)";

/// `utile live`: every uTile on the line live in the browser, the terminal beside it, a
/// Modbus TCP gateway.
#[derive(clap::Args, Clone, Debug, PartialEq)]
#[command(after_help = EXAMPLES)]
pub struct LiveArgs {
    /// The serial port (e.g. /dev/ttyUSB0)
    #[arg(long, value_name = "PATH")]
    pub port: String,
    /// The slave addresses on the line, 1..247 (default 1)
    #[arg(long, value_name = "1,2,3", value_delimiter = ',', num_args = 1,
          value_parser = clap::value_parser!(u8).range(1..=247), conflicts_with = "scan")]
    pub units: Vec<u8>,
    /// Look for the uTiles on the line
    #[arg(long)]
    pub scan: bool,
    /// Where the page is served: ADDR:PORT, or a port on 127.0.0.1
    #[arg(long, value_name = "ADDR:PORT", default_value = "127.0.0.1:8080", value_parser = socket_address)]
    pub http: SocketAddr,
    /// The Modbus TCP gateway (unit id = slave address): ADDR:PORT, or a port on 127.0.0.1
    #[arg(long, value_name = "ADDR:PORT", default_value = "127.0.0.1:1502",
          value_parser = socket_address, conflicts_with = "no_tcp")]
    pub tcp: SocketAddr,
    /// No Modbus TCP gateway
    #[arg(long)]
    pub no_tcp: bool,
    /// Refuse every write (page, terminal keys and TCP)
    #[arg(long)]
    pub read_only: bool,
    /// Check that this listing is the program that runs (its fingerprint)
    #[arg(long, value_name = "PROG.utl")]
    pub program: Option<String>,
    /// `--wait SECS`.
    #[command(flatten)]
    pub wait: BootWait,
    /// The virtual Nano's control socket (cargo nano --control SOCKET): a rig panel on each
    /// card (switches A0..A5, A6/A7 in volts, D8/D9, reset)
    #[arg(long, value_name = "SOCKET")]
    pub rig: Option<std::path::PathBuf>,
    /// The MQTT flags (`--mqtt URL` …).
    #[command(flatten)]
    pub mqtt: Flags,
    /// The page's token beyond loopback, read from this file (default: a new one, printed)
    #[arg(long, value_name = "FILE", help_heading = SECURITY)]
    pub token_file: Option<String>,
    /// Beyond loopback, reads need no token (writes still do)
    #[arg(long, help_heading = SECURITY)]
    pub public_read: bool,
    /// The networks the gateway takes clients from (needed for --tcp beyond loopback)
    #[arg(long, value_name = "CIDR,...", value_delimiter = ',', num_args = 1,
          value_parser = Cidr::parse, conflicts_with = "no_tcp", help_heading = SECURITY)]
    pub tcp_allow: Vec<Cidr>,
    /// Answer to this host name too (a reverse proxy's), besides localhost, 127.0.0.1, [::1]
    #[arg(long, value_name = "NAME,...", value_delimiter = ',', num_args = 1,
          value_parser = host_name, help_heading = SECURITY)]
    pub allow_host: Vec<String>,
}

/// Options of one run.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// The serial port.
    pub port: String,
    /// Slave addresses to poll (empty with `scan`).
    pub units: Vec<u8>,
    /// Look for the uTiles on the line.
    pub scan: bool,
    /// Where the page is served.
    pub http: SocketAddr,
    /// Where the gateway listens (`None`: `--no-tcp`).
    pub tcp: Option<SocketAddr>,
    /// Refuse every write.
    pub read_only: bool,
    /// A listing to check against the running program.
    pub program: Option<String>,
    /// The longest wait for uTile after the port opens.
    pub boot_wait: Duration,
    /// The virtual Nano's control socket (`--rig`).
    pub rig: Option<std::path::PathBuf>,
    /// The MQTT flags (`--mqtt URL` …).
    pub mqtt: Flags,
    /// `--token-file`: the page's token beyond loopback.
    pub token_file: Option<String>,
    /// `--public-read`: reads need no token.
    pub public_read: bool,
    /// `--tcp-allow`: the networks the gateway takes clients from.
    pub tcp_allow: Vec<Cidr>,
    /// `--allow-host`: names the page answers to besides this computer's own.
    pub allow_host: Vec<String>,
}

impl From<LiveArgs> for Options {
    fn from(a: LiveArgs) -> Options {
        let mut units = Vec::new();
        for u in a.units {
            if !units.contains(&u) {
                units.push(u);
            }
        }
        if !a.scan && units.is_empty() {
            units.push(1);
        }
        Options {
            port: a.port,
            units,
            scan: a.scan,
            http: a.http,
            tcp: (!a.no_tcp).then_some(a.tcp),
            read_only: a.read_only,
            program: a.program,
            boot_wait: a.wait.boot_wait,
            rig: a.rig,
            mqtt: a.mqtt,
            token_file: a.token_file,
            public_read: a.public_read,
            tcp_allow: a.tcp_allow,
            allow_host: a.allow_host,
        }
    }
}

/// `utile live`'s words alone, as a command of their own (the benchmarks start `live` so).
#[derive(Parser)]
#[command(name = "utile live")]
struct Alone {
    #[command(flatten)]
    args: LiveArgs,
}

/// Parses the words after `live`.
pub fn parse(words: &[String]) -> Result<Options, clap::Error> {
    let alone =
        Alone::try_parse_from(std::iter::once("live").chain(words.iter().map(String::as_str)))?;
    Ok(alone.args.into())
}

/// `--tcp` beyond loopback without `--tcp-allow`.
#[derive(Debug, thiserror::Error)]
#[error(
    "--tcp {0} listens beyond this computer: give --tcp-allow CIDR[,CIDR…] with the networks \
     its clients come from (e.g. --tcp-allow 192.168.1.0/24)"
)]
pub struct TcpNeedsAllow(pub SocketAddr);

/// The gateway beyond loopback needs `--tcp-allow` (a value clap cannot weigh: the address).
pub fn check_tcp(o: &Options) -> Result<(), TcpNeedsAllow> {
    match o.tcp {
        Some(a) if !a.ip().is_loopback() && o.tcp_allow.is_empty() => Err(TcpNeedsAllow(a)),
        _ => Ok(()),
    }
}

/// The warning for an address other than loopback, or `None`.
pub fn exposed(what: &str, a: &SocketAddr) -> Option<String> {
    (!a.ip().is_loopback()).then(|| {
        format!(
            "warning: {what} listens on {a}, not only on this computer: anyone who reaches \
             it can switch outputs (--read-only refuses every write)"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(s: &str) -> Vec<String> {
        s.split_whitespace().map(String::from).collect()
    }

    #[test]
    fn defaults_are_loopback_and_unit_1() {
        let o = parse(&words("--port /dev/ttyUSB0")).unwrap();
        assert_eq!(o.units, [1]);
        assert_eq!(o.http.to_string(), "127.0.0.1:8080");
        assert_eq!(o.tcp.unwrap().to_string(), "127.0.0.1:1502");
        assert!(exposed("the page", &o.http).is_none());
        let o = parse(&words("--port p --units 1,2,3 --http 0.0.0.0:80 --tcp 0")).unwrap();
        assert_eq!(o.units, [1, 2, 3]);
        assert!(exposed("the page", &o.http)
            .unwrap()
            .contains("switch outputs"));
        assert_eq!(o.tcp.unwrap().port(), 0);
    }

    #[test]
    fn mistakes_are_refused() {
        let e = parse(&words("--units 1")).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::MissingRequiredArgument);
        assert!(e.to_string().contains("--port"), "{e}");
        assert!(parse(&words("--port p --units 0")).is_err());
        assert!(parse(&words("--port p --units 248")).is_err());
        assert!(parse(&words("--port p --scan --units 2")).is_err());
        assert!(parse(&words("--port p --http nowhere")).is_err());
        assert!(parse(&words("--port p --bogus")).is_err());
        let e = parse(&words("--port p --port q")).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::ArgumentConflict, "{e}");
        let e = parse(&words("--port p --scan --scan")).unwrap_err();
        assert_eq!(e.kind(), clap::error::ErrorKind::ArgumentConflict, "{e}");
        assert!(parse(&words("--port p --tcp 1 --no-tcp")).is_err());
        let o = parse(&words("--port p --tcp 0.0.0.0:1502")).unwrap();
        assert!(check_tcp(&o)
            .unwrap_err()
            .to_string()
            .contains("--tcp-allow"));
        let o = parse(&words("--port p --tcp 0.0.0.0:1502 --tcp-allow 10.0.0.0/8")).unwrap();
        assert!(check_tcp(&o).is_ok());
        assert!(parse(&words("--port p --tcp-allow 10.0.0.0/40")).is_err());
        let o = parse(&words("--port p --tcp-allow 10.0.0.0/8,192.168.1.7")).unwrap();
        assert_eq!(o.tcp_allow.len(), 2);
        assert!(parse(&words("--port p --no-tcp --tcp-allow 10.0.0.0/8")).is_err());
        let o = parse(&words(
            "--port p --allow-host plc.example,PLC2.lan --allow-host 10.0.0.7",
        ))
        .unwrap();
        assert_eq!(o.allow_host, ["plc.example", "plc2.lan", "10.0.0.7"]);
        let e = parse(&words("--port p --allow-host plc.example:443")).unwrap_err();
        assert!(e.to_string().contains("without a port"), "{e}");
        for stray in [
            "--mqtt-commands",
            "--ha-discovery",
            "--mqtt-ca c.pem",
            "--mqtt-user u",
            "--mqtt-prefix p",
            "--name n",
        ] {
            let e = parse(&words(&format!("--port p {stray}"))).unwrap_err();
            assert_eq!(
                e.kind(),
                clap::error::ErrorKind::MissingRequiredArgument,
                "{stray}: {e}"
            );
            assert!(e.to_string().contains("--mqtt <URL>"), "{stray}: {e}");
        }
        let e = parse(&words("--port p --mqtt mqtt://h --mqtt-password-file f")).unwrap_err();
        assert!(e.to_string().contains("--mqtt-user"), "{e}");
        let o = parse(&words(
            "--port p --mqtt mqtt://h --mqtt-commands --ha-discovery",
        ))
        .unwrap();
        assert!(o.mqtt.commands && o.mqtt.discovery);
    }

    #[test]
    fn units_and_wait() {
        let o = parse(&words(
            "--port p --units 3,1,3 --wait 1s --no-tcp --read-only",
        ))
        .unwrap();
        assert_eq!(o.units, [3, 1]);
        assert_eq!(o.boot_wait, Duration::from_secs(1));
        assert_eq!(o.tcp, None);
        assert!(o.read_only);
        let o = parse(&words("--port p --scan")).unwrap();
        assert!(o.scan && o.units.is_empty());
        assert!(parse(&words("--port p --wait 61")).is_err());
    }
}
