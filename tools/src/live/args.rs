//! The command line of `utile live`.

use std::net::SocketAddr;
use std::time::Duration;

/// The usage text.
pub const USAGE: &str = "\
  utile live --port PATH [--units 1,2,3 | --scan] [--http ADDR:PORT] [--tcp ADDR:PORT]
             [--no-tcp] [--read-only] [--program PROG.utl] [--wait SECS] [--rig SOCKET]
                                       every uTile on the line live in the browser, the
                                       terminal beside it, a Modbus TCP gateway
    --units  the slave addresses on the line (default 1); --scan looks for them
    --http   where the page is served (default 127.0.0.1:8080)
    --tcp    the Modbus TCP gateway (default 127.0.0.1:1502; unit id = slave address)
    --read-only  refuse every write (page, terminal keys and TCP)
    --program    check that the listing is the program that runs (its fingerprint)
    --rig    the virtual Nano's control socket (cargo nano --control SOCKET): a rig panel
             on each card (switches A0..A5, A6/A7 in volts, D8/D9, reset)";

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
}

/// `ADDR:PORT`, or a bare port on 127.0.0.1.
fn address(flag: &str, v: &str) -> Result<SocketAddr, String> {
    if let Ok(port) = v.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    v.parse()
        .map_err(|_| format!("{flag} takes ADDR:PORT (e.g. 127.0.0.1:8080), not '{v}'"))
}

/// Parses the words after `live`.
pub fn parse(words: &[String]) -> Result<Options, String> {
    let mut o = Options {
        port: String::new(),
        units: Vec::new(),
        scan: false,
        http: SocketAddr::from(([127, 0, 0, 1], 8080)),
        tcp: Some(SocketAddr::from(([127, 0, 0, 1], 1502))),
        read_only: false,
        program: None,
        boot_wait: Duration::from_millis(2500),
        rig: None,
    };
    let mut it = words.iter();
    while let Some(w) = it.next() {
        let mut value = || {
            it.next()
                .cloned()
                .ok_or_else(|| format!("option '{w}' needs a value"))
        };
        match w.as_str() {
            "--port" => o.port = value()?,
            "--units" => {
                let list = value()?;
                for a in list.split(',') {
                    let n: u8 = a
                        .trim()
                        .parse()
                        .ok()
                        .filter(|n| (1..=247).contains(n))
                        .ok_or_else(|| {
                            format!("--units takes slave addresses 1..247, not '{a}'")
                        })?;
                    if !o.units.contains(&n) {
                        o.units.push(n);
                    }
                }
            }
            "--scan" => o.scan = true,
            "--http" => o.http = address(w, &value()?)?,
            "--tcp" => o.tcp = Some(address(w, &value()?)?),
            "--no-tcp" => o.tcp = None,
            "--read-only" => o.read_only = true,
            "--program" => o.program = Some(value()?),
            "--rig" => o.rig = Some(value()?.into()),
            "--wait" => {
                let v = value()?;
                let secs: f64 = v
                    .trim_end_matches('s')
                    .parse()
                    .ok()
                    .filter(|s: &f64| (0.0..=60.0).contains(s))
                    .ok_or_else(|| format!("--wait takes seconds (0..60), not '{v}'"))?;
                o.boot_wait = Duration::from_secs_f64(secs);
            }
            other => return Err(format!("unknown option '{other}'\nusage:\n{USAGE}")),
        }
    }
    if o.port.is_empty() {
        return Err(format!(
            "--port PATH is needed (e.g. /dev/ttyUSB0)\nusage:\n{USAGE}"
        ));
    }
    if o.scan && !o.units.is_empty() {
        return Err("--units and --scan exclude each other".into());
    }
    if !o.scan && o.units.is_empty() {
        o.units.push(1);
    }
    Ok(o)
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
        assert_eq!(o.rig, None);
        let o = parse(&words("--port p --rig out/live-rig.sock")).unwrap();
        assert_eq!(o.rig.unwrap().to_str(), Some("out/live-rig.sock"));
        assert!(parse(&words("--port p --rig"))
            .unwrap_err()
            .contains("needs a value"));
    }

    #[test]
    fn mistakes_are_refused() {
        assert!(parse(&words("--units 1")).unwrap_err().contains("--port"));
        assert!(parse(&words("--port p --units 0")).is_err());
        assert!(parse(&words("--port p --units 248")).is_err());
        assert!(parse(&words("--port p --scan --units 2")).is_err());
        assert!(parse(&words("--port p --http nowhere")).is_err());
        assert!(parse(&words("--port p --bogus")).is_err());
    }
}
