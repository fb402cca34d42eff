//! The RTU master's side of one transaction on the shared line: how long a reply is (read
//! from its first bytes), where a reply sits in what came in (the terminal's bytes may come
//! before it), and how long things take at 19200 baud. Frames and CRCs are the kit's
//! (`utile_kit::modbus`); this file only adds what a master on a line shared with a terminal
//! needs.

use std::time::Duration;

use utile_kit::modbus;

/// The line's speed (SPEC §13): 19200 baud, 8N1, so 10 bits a byte.
pub const BAUD: u32 = 19_200;

/// Time on the line for `bytes` bytes.
pub fn line_time(bytes: usize) -> Duration {
    Duration::from_micros(bytes as u64 * 10 * 1_000_000 / u64::from(BAUD))
}

/// The silence that ends a frame: 3.5 characters (about 1.8 ms).
pub fn frame_gap() -> Duration {
    Duration::from_micros(35 * 1_000_000 / u64::from(BAUD))
}

/// A uTile starts its reply ≤ 5 ms after the request (SPEC §13); the rest of the wait is for
/// the host: a USB adapter's latency, a simulation that runs behind the wall clock.
pub const ANSWER_SLACK: Duration = Duration::from_millis(120);

/// The longest reply any request can get: address, 253 bytes of PDU, CRC.
pub const MAX_FRAME: usize = 256;

/// How long to wait for the reply to `request` (a whole frame): its own time on the line,
/// the longest reply it can get, and `slack` (usually [`ANSWER_SLACK`]).
pub fn reply_timeout(request: &[u8], slack: Duration) -> Duration {
    line_time(request.len()) + line_time(longest_reply(request)) + slack
}

/// The longest reply `request` (a whole frame) can get.
pub fn longest_reply(request: &[u8]) -> usize {
    let quantity = || {
        request
            .get(4..6)
            .map_or(0, |q| usize::from(u16::from_be_bytes([q[0], q[1]])))
    };
    match request.get(1) {
        Some(1) | Some(2) => 5 + quantity().div_ceil(8).min(250),
        Some(3) | Some(4) => 5 + 2 * quantity().min(125),
        Some(5) | Some(6) | Some(15) | Some(16) => 8,
        Some(8) => request.len(),
        // Report server ID: uTile's text and version are a few bytes.
        Some(17) => 5 + 32,
        _ => MAX_FRAME,
    }
}

/// The length of the reply frame that starts with `head` (address, function code, and for
/// replies that carry a byte count, that count), or `None` until enough has come.
/// `request_len` is the request's length (an echo is as long).
pub fn reply_len(head: &[u8], request_len: usize) -> Option<usize> {
    let function = *head.get(1)?;
    if function & 0x80 != 0 {
        return Some(5);
    }
    match function {
        1 | 2 | 3 | 4 | 17 | 20 | 21 | 23 => Some(5 + usize::from(*head.get(2)?)),
        5 | 6 | 15 | 16 => Some(8),
        8 => Some(request_len),
        22 => Some(10),
        _ => None,
    }
}

/// What the bytes received after a request hold.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Scan {
    /// The reply, at `start..end`; the bytes before `start` are not part of it (the terminal's
    /// output, or noise).
    Reply {
        /// Offset of the reply's address byte.
        start: usize,
        /// Offset just past its CRC.
        end: usize,
    },
    /// No whole reply yet.
    Incomplete,
}

/// Looks for `address`'s reply to `request` in `got`: the first offset where a frame from
/// that address, of the length its head announces, ends in a right CRC. A terminal's text
/// before it (a RUN screen still drawing when the first request went out) is skipped, never
/// taken as a reply.
pub fn find_reply(got: &[u8], address: u8, request: &[u8]) -> Scan {
    for start in 0..got.len() {
        if got[start] != address {
            continue;
        }
        let Some(len) = reply_len(&got[start..], request.len()) else {
            continue;
        };
        let end = start + len;
        if end <= got.len() && modbus::reply_pdu(address, &got[start..end]).is_ok() {
            // An echo or a write's reply must name the request's function (or its exception).
            let f = got[start + 1] & 0x7F;
            if request.get(1) == Some(&f) {
                return Scan::Reply { start, end };
            }
        }
    }
    Scan::Incomplete
}

/// Whether `got` holds a whole frame from `address` for `request`'s function (or its
/// exception), of the length its head announces, whose CRC is wrong: a damaged reply, not
/// one that is late or cut short.
pub fn bad_crc(got: &[u8], address: u8, request: &[u8]) -> bool {
    let f = request.get(1).copied().unwrap_or(0);
    (0..got.len()).any(|start| {
        let head = &got[start..];
        head.len() >= 2
            && head[0] == address
            && head[1] & 0x7F == f
            && reply_len(head, request.len())
                .is_some_and(|len| head.len() >= len && !modbus::crc_ok(&head[..len]))
    })
}

/// A Modbus exception code in words, as the page shows a refusal.
pub fn exception_text(code: u8) -> String {
    let what = match code {
        1 => "illegal function",
        2 => "illegal data address: outside uTile's map",
        3 => "illegal data value: out of range",
        4 => "server device failure",
        6 => "server busy",
        0x0A => "gateway path unavailable",
        0x0B => "the uTile did not answer",
        _ => "unknown exception",
    };
    format!("exception {code:02X} ({what})")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reply_behind_terminal_text_is_found_and_a_wrong_crc_is_not() {
        let request = modbus::frame(1, &[4, 0, 64, 0, 2]);
        let reply = modbus::frame(1, &[4, 4, 0, 1, 0x12, 0x34]);
        let mut got = b"\x1b[5;1H*** Running User File Program ***".to_vec();
        let at = got.len();
        got.extend_from_slice(&reply);
        assert_eq!(
            find_reply(&got, 1, &request),
            Scan::Reply {
                start: at,
                end: got.len()
            }
        );
        assert_eq!(
            find_reply(&got[..got.len() - 1], 1, &request),
            Scan::Incomplete
        );
        let mut bad = got.clone();
        let last = bad.len() - 1;
        bad[last] ^= 0x55;
        assert_eq!(find_reply(&bad, 1, &request), Scan::Incomplete);
        assert!(bad_crc(&bad, 1, &request));
        assert!(!bad_crc(&got[..got.len() - 1], 1, &request));
        // Another function's frame from that address is not this request's reply.
        let other = modbus::frame(1, &[3, 2, 0, 9]);
        assert_eq!(find_reply(&other, 1, &request), Scan::Incomplete);
    }

    #[test]
    fn an_exception_is_a_reply_of_five_bytes() {
        let request = modbus::frame(2, &[6, 0, 24, 0x10, 0]);
        let reply = modbus::frame(2, &[0x86, 3]);
        assert_eq!(reply_len(&reply, request.len()), Some(5));
        assert_eq!(
            find_reply(&reply, 2, &request),
            Scan::Reply { start: 0, end: 5 }
        );
    }

    #[test]
    fn the_snapshot_read_takes_about_53_ms_with_the_gaps() {
        // FC04 of 40 registers: 8 bytes out, 85 back (issue 25's 93 bytes).
        let request = modbus::frame(1, &[4, 0, 64, 0, 40]);
        assert_eq!(longest_reply(&request), 85);
        let t = line_time(8 + 85) + frame_gap() * 2;
        assert!((49..=53).contains(&t.as_millis()), "{t:?}");
    }
}
