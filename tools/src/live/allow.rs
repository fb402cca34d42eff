//! `--tcp-allow CIDR[,CIDR…]`: the networks whose clients the Modbus TCP gateway takes when
//! it listens beyond loopback (`192.168.1.0/24`, `10.0.0.7`, `fd00::/8`); other clients are
//! refused (the connection closed at once) and counted.

use std::net::IpAddr;

/// One network.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Cidr {
    net: IpAddr,
    bits: u8,
}

/// Not a network: the message says what `--tcp-allow` takes.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
#[error("--tcp-allow takes networks as ADDR/BITS or ADDR (e.g. 192.168.1.0/24), not '{0}'")]
pub struct BadCidr(pub String);

impl Cidr {
    /// `ADDR/BITS` or a bare address (all its bits).
    pub fn parse(s: &str) -> Result<Cidr, BadCidr> {
        let bad = || BadCidr(s.to_string());
        let (a, bits) = match s.trim().split_once('/') {
            Some((a, b)) => (a, Some(b)),
            None => (s.trim(), None),
        };
        let net: IpAddr = a.parse().map_err(|_| bad())?;
        let most = if net.is_ipv4() { 32 } else { 128 };
        let bits = match bits {
            Some(b) => b
                .parse::<u8>()
                .ok()
                .filter(|b| *b <= most)
                .ok_or_else(bad)?,
            None => most,
        };
        Ok(Cidr { net, bits })
    }

    /// Whether `ip` is in this network (an IPv4 client seen as `::ffff:a.b.c.d` counts as
    /// IPv4).
    pub fn contains(&self, ip: IpAddr) -> bool {
        let ip = match ip {
            IpAddr::V6(v6) => v6.to_ipv4_mapped().map_or(ip, IpAddr::V4),
            v4 => v4,
        };
        match (self.net, ip) {
            (IpAddr::V4(n), IpAddr::V4(a)) => {
                let mask = u32::MAX.checked_shl(32 - u32::from(self.bits)).unwrap_or(0);
                u32::from(n) & mask == u32::from(a) & mask
            }
            (IpAddr::V6(n), IpAddr::V6(a)) => {
                let mask = u128::MAX
                    .checked_shl(128 - u32::from(self.bits))
                    .unwrap_or(0);
                u128::from(n) & mask == u128::from(a) & mask
            }
            _ => false,
        }
    }
}

/// A comma-separated list.
pub fn parse_list(s: &str) -> Result<Vec<Cidr>, BadCidr> {
    s.split(',').map(Cidr::parse).collect()
}

/// Whether `ip` may connect: `allow` empty means every client (the gateway on loopback).
pub fn allowed(allow: &[Cidr], ip: IpAddr) -> bool {
    allow.is_empty() || allow.iter().any(|c| c.contains(ip))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ip(s: &str) -> IpAddr {
        s.parse().unwrap()
    }

    #[test]
    fn networks_take_their_addresses_only() {
        let l = parse_list("192.168.1.0/24,10.0.0.7,fd00::/8").unwrap();
        assert!(allowed(&l, ip("192.168.1.200")));
        assert!(!allowed(&l, ip("192.168.2.1")));
        assert!(allowed(&l, ip("10.0.0.7")));
        assert!(!allowed(&l, ip("10.0.0.8")));
        assert!(allowed(&l, ip("fd12::1")));
        assert!(allowed(&l, ip("::ffff:192.168.1.3")));
        assert!(!allowed(&l, ip("127.0.0.1")));
        assert!(allowed(&parse_list("0.0.0.0/0").unwrap(), ip("8.8.8.8")));
        assert!(allowed(&[], ip("8.8.8.8")));
        for bad in ["", "1.2.3.4/33", "x/8", "1.2.3/8", "::/129"] {
            assert!(parse_list(bad).is_err(), "{bad}");
        }
    }
}
