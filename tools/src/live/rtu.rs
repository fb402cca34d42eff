//! The RTU master's side of one transaction on the shared line: how long a reply is (read
//! from its first bytes), where a reply sits in what came in (the terminal's bytes may come
//! before it), and how long things take at 19200 baud. Frames and CRCs are the kit's
//! (`utile_kit::modbus`); this file only adds what a master on a line shared with a terminal
//! needs.

use std::time::Duration;

use tokio_modbus::ExceptionCode;
use utile_core::modbus::{
    Exception, DIAGNOSTICS, READ_COILS, READ_DISCRETE_INPUTS, READ_HOLDING_REGISTERS,
    READ_INPUT_REGISTERS, REPORT_SERVER_ID, WRITE_MULTIPLE_COILS, WRITE_MULTIPLE_REGISTERS,
    WRITE_SINGLE_COIL, WRITE_SINGLE_REGISTER,
};
use utile_kit::modbus;

/// The bit of a reply's function code that makes it an exception (Modbus application
/// protocol, section 7).
pub const EXCEPTION_BIT: u8 = 0x80;
/// Function code 20: read file record (a reply with a byte count).
const READ_FILE_RECORD: u8 = 0x14;
/// Function code 21: write file record.
const WRITE_FILE_RECORD: u8 = 0x15;
/// Function code 22: mask write register.
pub const MASK_WRITE_REGISTER: u8 = 0x16;
/// Function code 23: read/write multiple registers.
pub const READ_WRITE_MULTIPLE_REGISTERS: u8 = 0x17;

/// Whether a reply's function code is an exception's.
pub fn is_exception(function: u8) -> bool {
    function & EXCEPTION_BIT != 0
}

/// The function a reply answers (its exception bit cleared).
pub fn answers(function: u8) -> u8 {
    function & !EXCEPTION_BIT
}

/// The exception code of a reply's PDU, if it is an exception.
pub fn exception(pdu: &[u8]) -> Option<u8> {
    let (&f, rest) = pdu.split_first()?;
    is_exception(f).then(|| {
        rest.first()
            .copied()
            .unwrap_or(u8::from(ExceptionCode::ServerDeviceFailure))
    })
}

/// Whether a request of this function changes something in the slave.
pub fn is_write(function: u8) -> bool {
    matches!(
        function,
        WRITE_SINGLE_COIL
            | WRITE_SINGLE_REGISTER
            | WRITE_MULTIPLE_COILS
            | WRITE_MULTIPLE_REGISTERS
            | MASK_WRITE_REGISTER
            | READ_WRITE_MULTIPLE_REGISTERS
    )
}

/// Whether a write of this function only writes bits (the presets need no new read).
pub fn writes_coils(function: u8) -> bool {
    matches!(function, WRITE_SINGLE_COIL | WRITE_MULTIPLE_COILS)
}

/// Whether a request of this function can be sent again when it got no answer: reads, and
/// writes that set a value (sending one twice leaves what sending it once does).
pub fn repeatable(function: u8) -> bool {
    matches!(
        function,
        READ_COILS
            | READ_DISCRETE_INPUTS
            | READ_HOLDING_REGISTERS
            | READ_INPUT_REGISTERS
            | WRITE_SINGLE_COIL
            | WRITE_SINGLE_REGISTER
            | WRITE_MULTIPLE_COILS
            | WRITE_MULTIPLE_REGISTERS
    )
}

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

/// The most a reply may be late before it counts as missing (the line's learnt slack never
/// passes it; a reply whose bytes are still coming is waited for twice as long).
pub const SLACK_MAX: Duration = Duration::from_millis(1500);

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
    let Some(&function) = request.get(1) else {
        return MAX_FRAME;
    };
    match function {
        READ_COILS | READ_DISCRETE_INPUTS => 5 + quantity().div_ceil(8).min(250),
        READ_HOLDING_REGISTERS | READ_INPUT_REGISTERS => 5 + 2 * quantity().min(125),
        WRITE_SINGLE_COIL
        | WRITE_SINGLE_REGISTER
        | WRITE_MULTIPLE_COILS
        | WRITE_MULTIPLE_REGISTERS => 8,
        DIAGNOSTICS => request.len(),
        // Report server ID: uTile's text and version are a few bytes.
        REPORT_SERVER_ID => 5 + 32,
        _ => MAX_FRAME,
    }
}

/// The length of the reply frame that starts with `head` (address, function code, and for
/// replies that carry a byte count, that count), or `None` until enough has come.
/// `request_len` is the request's length (an echo is as long).
pub fn reply_len(head: &[u8], request_len: usize) -> Option<usize> {
    let function = *head.get(1)?;
    if is_exception(function) {
        return Some(5);
    }
    match function {
        READ_COILS
        | READ_DISCRETE_INPUTS
        | READ_HOLDING_REGISTERS
        | READ_INPUT_REGISTERS
        | REPORT_SERVER_ID
        | READ_FILE_RECORD
        | WRITE_FILE_RECORD
        | READ_WRITE_MULTIPLE_REGISTERS => Some(5 + usize::from(*head.get(2)?)),
        WRITE_SINGLE_COIL
        | WRITE_SINGLE_REGISTER
        | WRITE_MULTIPLE_COILS
        | WRITE_MULTIPLE_REGISTERS => Some(8),
        DIAGNOSTICS => Some(request_len),
        MASK_WRITE_REGISTER => Some(10),
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
            let f = answers(got[start + 1]);
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
            && answers(head[1]) == f
            && reply_len(head, request.len())
                .is_some_and(|len| head.len() >= len && !modbus::crc_ok(&head[..len]))
    })
}

/// A Modbus exception code in words, as the page shows a refusal.
pub fn exception_text(code: u8) -> String {
    const FUNCTION: u8 = Exception::IllegalFunction as u8;
    const ADDRESS: u8 = Exception::IllegalDataAddress as u8;
    const VALUE: u8 = Exception::IllegalDataValue as u8;
    let what = match code {
        FUNCTION => "illegal function",
        ADDRESS => "illegal data address: outside uTile's map",
        VALUE => "illegal data value: out of range",
        _ => match ExceptionCode::new(code) {
            ExceptionCode::ServerDeviceFailure => "server device failure",
            ExceptionCode::ServerDeviceBusy => "server busy",
            ExceptionCode::GatewayPathUnavailable => "gateway path unavailable",
            ExceptionCode::GatewayTargetDevice => "the uTile did not answer",
            _ => "unknown exception",
        },
    };
    format!("exception {code:02X} ({what})")
}

/// What came after a request that got no whole reply in time.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MissedReply {
    /// A frame from the address, for the request's function, came whole with a wrong CRC.
    pub bad_crc: bool,
    /// Bytes that were no reply (noise, the terminal's text, a reply cut short).
    pub not_reply: usize,
}

/// Tells what `got` (all that came after `request`, no reply found in it) holds.
pub fn missed_reply(got: &[u8], address: u8, request: &[u8]) -> MissedReply {
    MissedReply {
        bad_crc: bad_crc(got, address, request),
        not_reply: got.len(),
    }
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
    fn only_a_whole_frame_with_a_wrong_crc_counts_as_a_crc_error() {
        let request = modbus::frame(1, &[4, 0, 64, 0, 40]);
        // Text that holds the address and the function code side by side ("\x01\x04") is
        // no reply, and no damaged one either.
        let noise = b"AB\x01\x04CD".to_vec();
        let m = missed_reply(&noise, 1, &request);
        assert!(!m.bad_crc);
        assert_eq!(m.not_reply, 6);
        // A reply cut short is none either.
        let reply = modbus::frame(1, &[4, 2, 0, 7]);
        assert!(!missed_reply(&reply[..4], 1, &request).bad_crc);
        let mut bad = reply.clone();
        bad[4] ^= 1;
        assert!(missed_reply(&bad, 1, &request).bad_crc);
        // An exception with a wrong CRC is a damaged reply too.
        let mut ex = modbus::frame(1, &[0x84, 2]);
        ex[3] ^= 0xFF;
        assert!(missed_reply(&ex, 1, &request).bad_crc);
    }

    #[test]
    fn the_vocabulary_names_the_functions() {
        assert!(is_exception(0x86) && !is_exception(6));
        assert_eq!(exception(&[0x86, 3]), Some(3));
        assert_eq!(exception(&[6, 0, 24, 0, 1]), None);
        assert!(is_write(WRITE_SINGLE_COIL) && is_write(WRITE_MULTIPLE_REGISTERS));
        assert!(!is_write(READ_INPUT_REGISTERS) && !is_write(REPORT_SERVER_ID));
        assert!(repeatable(READ_HOLDING_REGISTERS) && !repeatable(DIAGNOSTICS));
        assert_eq!(
            exception_text(2),
            "exception 02 (illegal data address: outside uTile's map)"
        );
        assert_eq!(
            exception_text(0x0B),
            "exception 0B (the uTile did not answer)"
        );
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
