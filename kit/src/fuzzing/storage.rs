//! Harnesses of storage: Intel HEX against an independent reader, hex round trips, image decoding, EEPROM slots.

use super::*;

/// An independent, whole-text Intel HEX parser with the rules of `docs/FORMAT.md`: the
/// image if the text (up to its end-of-file record) is a valid file, else `None`.
pub(super) fn reference_hex(text: &[u8]) -> Option<(Vec<u8>, usize)> {
    let start = text.iter().position(|&c| c == b':')?;
    let mut image = Vec::new();
    let mut i = start;
    loop {
        // At a ':'.
        i += 1;
        let mut rec = Vec::new();
        let mut need = 5usize;
        while rec.len() < need {
            let hi = (*text.get(i)? as char).to_digit(16)? as u8;
            let lo = (*text.get(i + 1)? as char).to_digit(16)? as u8;
            rec.push(hi << 4 | lo);
            i += 2;
            if rec.len() == 1 {
                need = 5 + usize::from(rec[0]);
            }
        }
        if rec.iter().fold(0u8, |s, &b| s.wrapping_add(b)) != 0 {
            return None;
        }
        let addr = usize::from(rec[1]) << 8 | usize::from(rec[2]);
        match rec[3] {
            0 if addr == image.len() && addr + usize::from(rec[0]) <= IMAGE_LEN => {
                image.extend_from_slice(&rec[4..rec.len() - 1]);
            }
            // A whole image of version 2 or of version 1.
            1 if rec[0] == 0 && matches!(image.len(), IMAGE_LEN | image::IMAGE_LEN_V1) => {
                return Some((image, i))
            }
            _ => return None,
        }
        // Between records: control characters and blanks, then ':'.
        loop {
            let c = *text.get(i)?;
            if c == b':' {
                break;
            }
            if c > b' ' && c != 0x7F {
                return None;
            }
            i += 1;
        }
    }
}

/// The Intel HEX reader: it says `Done` exactly when the text is a valid file (checked
/// against an independent parser), then holds exactly that file's bytes; `Done` and
/// `Error` are final. A decoded image re-encodes to the same bytes.
pub fn ihex(data: &[u8]) -> Verdict {
    let mut r = HexReader::new();
    let mut done_at: Option<(usize, u16)> = None;
    let mut error = None;
    for (i, &b) in data.iter().enumerate() {
        let ev = r.feed(b);
        match (done_at, error, ev) {
            (Some((_, l)), _, HexEvent::Done { len }) if l == len => {}
            (Some(_), _, e) => return Err(broken!("after Done the reader said {e:?}")),
            (None, Some(e0), HexEvent::Error(e)) if e == e0 => {}
            (None, Some(e0), e) => {
                return Err(broken!("after Error({e0:?}) the reader said {e:?}"))
            }
            (None, None, HexEvent::Done { len }) => done_at = Some((i + 1, len)),
            (None, None, HexEvent::Error(e)) => error = Some(e),
            (None, None, HexEvent::More) => {}
        }
    }
    let reference = reference_hex(data);
    match (done_at, &reference) {
        (Some((end, len)), Some((img, ref_end))) => {
            if *ref_end != end || r.data().get(..usize::from(len)) != Some(img.as_slice()) {
                return Err("the reader's file differs from the reference parser's".into());
            }
            if let Ok(p) = image::decode(img) {
                // A version-1 image comes back as version 2; a version-2 one exactly but for
                // the reserved byte (written 0, ignored on reading) and the CRC over it.
                if img.len() == IMAGE_LEN && !same_image(&image::encode(&p), img) {
                    return Err("decode then encode changed the image".into());
                }
            }
            Ok(())
        }
        (Some(_), None) => Err("the reader accepted a file the reference parser refuses".into()),
        (None, Some(_)) => Err(broken!("the reader refused a valid file ({error:?})")),
        _ => Ok(()),
    }
}

/// The WRITE/READ round trip of the image `data` (as a program) through the Intel HEX text.
pub fn hex_roundtrip(data: &[u8]) -> Verdict {
    let mut prog = Program::blank();
    for (dst, &src) in prog
        .uf
        .iter_mut()
        .chain(prog.presets.iter_mut())
        .zip(data.iter())
    {
        *dst = src;
    }
    let img = image::encode(&prog);
    let mut text = Vec::new();
    ihex::write_hex(&img, &mut |c| text.push(c));
    let mut r = HexReader::new();
    let mut last = HexEvent::More;
    for &c in &text {
        last = r.feed(c);
    }
    match last {
        HexEvent::Done { len } if usize::from(len) == IMAGE_LEN => {}
        e => return Err(broken!("WRITE's own text read back as {e:?}")),
    }
    if image::decode(r.data()) != Ok(prog) {
        return Err("WRITE then READ changed the program".into());
    }
    Ok(())
}

/// Whether `data` is a valid image by the rules of `docs/FORMAT.md`, checked here
/// independently of the decoder: 298 bytes of version 2 or 278 of version 1, the magic, a
/// good CRC, and (version 2) set-points of at most 1023.
pub(super) fn reference_image_valid(data: &[u8]) -> bool {
    let len = match data.get(image::VERSION_OFFSET) {
        Some(2) => 298,
        Some(1) => 278,
        _ => return false,
    };
    if data.len() != len {
        return false;
    }
    let set_points_ok = len == 278
        || [292, 294]
            .iter()
            .all(|&at| u16::from_be_bytes([data[at], data[at + 1]]) <= 1023);
    data[..2] == *b"uT"
        && image::crc16_ccitt(&data[..len - 2]).to_be_bytes() == data[len - 2..]
        && set_points_ok
}

/// Whether `encoded` (the encoder's image) holds what the valid image `read` holds: a
/// valid image itself, equal byte for byte over the first `read.len() - 2` bytes (a
/// version-1 image's version byte read as 2) except the reserved byte, which the encoder
/// writes 0 and readers ignore (docs/FORMAT.md); the CRC then differs only if that byte did.
pub fn same_image(encoded: &[u8], read: &[u8]) -> bool {
    let body = read.len().saturating_sub(2).min(encoded.len());
    reference_image_valid(encoded)
        && encoded.get(image::RESERVED_OFFSET) == Some(&0)
        && (0..body).all(|i| {
            let want = if i == image::VERSION_OFFSET {
                image::VERSION
            } else {
                read[i]
            };
            i == image::RESERVED_OFFSET || encoded[i] == want
        })
}

/// The stored-image decoder: accepts exactly the valid images of either version
/// ([`reference_image_valid`]); a version-2 image re-encodes to the same bytes but for the
/// reserved byte ([`same_image`]), a version-1 image to a version-2 image of the same
/// program with counter presets and set-points 0.
pub fn image_decode(data: &[u8]) -> Verdict {
    let res = image::decode(data);
    let valid = reference_image_valid(data);
    match res {
        Ok(p) if valid => {
            let again = image::encode(&p);
            // A version-1 image's body ends where the counter presets begin.
            let same = same_image(&again, data)
                && (data.len() == IMAGE_LEN
                    || (p.counter_presets == [0; 8] && p.set_points == [0; 2]));
            if same {
                Ok(())
            } else {
                Err("a decoded image re-encodes differently".into())
            }
        }
        Ok(_) => Err("decode accepted an invalid image".into()),
        Err(e) if valid => Err(broken!("decode refused a valid image: {e:?}")),
        Err(_) => Ok(()),
    }
}

/// The slot the rules of docs/FORMAT.md make the newest, worked out here without the code
/// under test: the slots whose image is valid ([`reference_image_valid`], by the length its
/// version byte names), the one with the newer sequence number (serial-number arithmetic;
/// equal or exactly opposite numbers: slot 0). Its index, if any slot is valid.
pub fn reference_newest(eeprom: &[u8]) -> Option<usize> {
    let seq_and_valid = |k: usize| {
        let at = usize::from(SLOT_ADDR[k]);
        let seq = u16::from_le_bytes([eeprom[at], eeprom[at + 1]]);
        let img = &eeprom[at + 2..];
        let len = match img[image::VERSION_OFFSET] {
            1 => image::IMAGE_LEN_V1,
            _ => IMAGE_LEN,
        };
        reference_image_valid(&img[..len]).then_some(seq)
    };
    match (seq_and_valid(0), seq_and_valid(1)) {
        (Some(s0), Some(s1)) => {
            let d = s1.wrapping_sub(s0);
            Some(usize::from(d != 0 && d < 0x8000))
        }
        (Some(_), None) => Some(0),
        (None, Some(_)) => Some(1),
        (None, None) => None,
    }
}

/// EEPROM `load` on random contents: input bytes 0..300 are slot 0, 300..600 slot 1 (the
/// rest erased). LOAD returns the program of the slot [`reference_newest`] names, or nothing
/// when no slot is valid; STORE then works from any contents; and a STORE cut by a power
/// failure after any number of writes, torn any of the three ways a byte write can be
/// (`Tear`: not started, erased, half programmed), leaves LOAD with the old or the new
/// program, never anything else.
pub fn eeprom(data: &[u8]) -> Verdict {
    let mut board = SimBoard::new();
    let slot = usize::from(SLOT_LEN);
    for (k, chunk) in data.chunks(slot).take(2).enumerate() {
        let at = usize::from(SLOT_ADDR[k]);
        board.eeprom[at..at + chunk.len()].copy_from_slice(chunk);
    }
    let old = store::load(&mut board);
    let newest = reference_newest(&board.eeprom);
    match (&old, newest) {
        (Ok(p), Some(k)) => {
            let at = usize::from(SLOT_ADDR[k]) + 2;
            let len = match board.eeprom[at + image::VERSION_OFFSET] {
                1 => image::IMAGE_LEN_V1,
                _ => IMAGE_LEN,
            };
            // The program is the slot's image: encoded again it is the same bytes.
            if !same_image(&image::encode(p), &board.eeprom[at..at + len]) {
                return Err(broken!(
                    "LOAD did not return the program of slot {k}, the newest valid one"
                ));
            }
        }
        (Ok(_), None) => return Err("LOAD returned a program though no slot is valid".into()),
        (Err(_), Some(k)) => {
            return Err(broken!(
                "LOAD found nothing although slot {k} holds a valid image"
            ))
        }
        (Err(_), None) => {}
    }
    // A new program from the input itself, stored with a power failure after `cut` writes.
    let mut new = Program::blank();
    for (dst, &src) in new.uf.iter_mut().zip(data.iter().rev()) {
        *dst = src;
    }
    new.presets[0] = data.len() as u8;
    let cut = data.first().map_or(0, |&c| u32::from(c) * 3);
    let tear = match data.get(1).map_or(0, |&t| t % 3) {
        0 => Tear::Old,
        1 => Tear::Erased,
        _ => Tear::Partial,
    };
    let mut failing = board.clone();
    failing.eeprom_fault = EepromFault::PowerFail { writes: cut, tear };
    let _ = store::store(&new, &mut failing);
    let after_cut = store::load(&mut failing);
    let ok = after_cut.as_ref() == Ok(&new) || after_cut == old;
    if !ok {
        return Err(broken!(
            "a STORE cut after {cut} writes ({tear:?}) lost the stored program"
        ));
    }
    // A whole STORE works from any contents, and a second one too (the other slot).
    store::store(&new, &mut board).map_err(|e| format!("STORE failed: {e:?}"))?;
    if store::load(&mut board).as_ref() != Ok(&new) {
        return Err("LOAD after STORE does not give the stored program".into());
    }
    let mut newer = new.clone();
    newer.presets[1] = newer.presets[1].wrapping_add(1);
    store::store(&newer, &mut board).map_err(|e| format!("second STORE failed: {e:?}"))?;
    if store::load(&mut board).as_ref() != Ok(&newer) {
        return Err("LOAD after a second STORE does not give the newer program".into());
    }
    Ok(())
}
