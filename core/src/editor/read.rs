//! READ (manual §5.8, SPEC §10): records into the staging buffer, checked whole before
//! anything changes; time-outs and draining.

use super::*;

/// Where a READ is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum ReadPhase {
    /// Taking records.
    Receiving,
    /// Throwing input away until it is quiet; then show the result: `READ_DONE`, or why
    /// the file was refused.
    Draining(Txt),
    /// Result shown; a CR returns.
    Waiting,
}

/// READ's state, with the staging buffer (only while READ is active).
#[derive(Clone, Debug)]
pub(super) struct ReadState {
    pub(super) reader: HexReader,
    pub(super) last_ms: u32,
    pub(super) phase: ReadPhase,
}

pub(super) fn hex_reason(e: HexError) -> Txt {
    match e {
        HexError::BadChar => text::WHY_BAD_CHAR,
        HexError::Checksum => text::WHY_CHECKSUM,
        HexError::Address => text::WHY_ADDRESS,
        HexError::RecordType => text::WHY_RECORD_TYPE,
        HexError::Short => text::WHY_SHORT,
        HexError::TooLong => text::WHY_TOO_LONG,
    }
}

pub(super) fn image_reason(e: ImageError) -> Txt {
    match e {
        ImageError::Length => text::WHY_LENGTH,
        ImageError::Magic => text::WHY_MAGIC,
        ImageError::Version(_) => text::WHY_VERSION,
        ImageError::Crc => text::WHY_CRC,
        ImageError::Value => text::WHY_VALUE,
    }
}

impl Editor {
    /// READ's time-outs while nothing arrives: a file that stops, then the quiet after it.
    pub(super) fn read_idle<B: Board>(&mut self, now: u32, b: &mut B) {
        if let Screen::Read(rs) = &mut self.screen {
            let quiet = now.wrapping_sub(rs.last_ms);
            match rs.phase {
                ReadPhase::Receiving if quiet >= READ_TIMEOUT_MS => {
                    rs.phase = ReadPhase::Draining(text::WHY_TIMEOUT);
                    rs.last_ms = now.wrapping_sub(DRAIN_QUIET_MS);
                }
                ReadPhase::Draining(result) if quiet >= DRAIN_QUIET_MS => {
                    rs.phase = ReadPhase::Waiting;
                    goto(b, ROW_STATUS, COL_STATUS_A);
                    if result != text::READ_DONE {
                        text::READ_ERROR.send(b);
                    }
                    result.send(b);
                    text::FOR_MENU.send(b);
                    ceol(b);
                }
                _ => {}
            }
        }
    }

    /// One byte during READ. Returns `Some` when READ is over.
    // Out of line: inlined into the key path it costs 176 B more (BENCHMARKS "Flash routes").
    #[inline(never)]
    pub(super) fn read_byte(
        rs: &mut ReadState,
        byte: u8,
        now: u32,
        eng: &mut Engine,
    ) -> Option<Mode> {
        match rs.phase {
            ReadPhase::Receiving => {
                rs.last_ms = now;
                if byte == b'/' {
                    rs.phase = ReadPhase::Draining(text::WHY_ABORT);
                    return None;
                }
                match rs.reader.feed(byte) {
                    HexEvent::More => {}
                    HexEvent::Done { len } => {
                        let staged = rs.reader.data();
                        let got = staged.get(..usize::from(len)).unwrap_or(staged);
                        rs.phase = ReadPhase::Draining(match decode_into(got, &mut eng.prog) {
                            Ok(()) => text::READ_DONE,
                            Err(e) => image_reason(e),
                        });
                    }
                    HexEvent::Error(e) => rs.phase = ReadPhase::Draining(hex_reason(e)),
                }
            }
            ReadPhase::Draining(_) => rs.last_ms = now,
            ReadPhase::Waiting => {
                if byte == b'\r' {
                    return Some(Mode::Edit);
                }
            }
        }
        None
    }
}
