//! Intel HEX for images (SPEC §10, docs/FORMAT.md): the writer's exact text, bit-exact
//! round trips, and every way the streaming reader refuses a file.

use utile_core::engine::Program;
use utile_core::ihex::{write_hex, HexError, HexEvent, HexReader};
use utile_core::image::{self, ImageError, IMAGE_LEN};
use utile_kit::rng::Rng;

fn random_image(rng: &mut Rng) -> [u8; IMAGE_LEN] {
    image::encode(&rng.program())
}

fn hex_text(img: &[u8]) -> String {
    let mut out = Vec::new();
    write_hex(img, &mut |b| out.push(b));
    String::from_utf8(out).expect("hex is ASCII")
}

/// One record with a correct checksum (built independently of the writer).
fn rec(addr: u16, kind: u8, data: &[u8]) -> String {
    let mut bytes = vec![data.len() as u8, (addr >> 8) as u8, addr as u8, kind];
    bytes.extend_from_slice(data);
    let sum = bytes.iter().fold(0u8, |s, &b| s.wrapping_add(b));
    bytes.push(sum.wrapping_neg());
    let mut s = String::from(":");
    for b in bytes {
        s.push_str(&format!("{b:02X}"));
    }
    s.push_str("\r\n");
    s
}

/// The file for `img` built from records of `size` bytes, in order.
fn file_with_records(img: &[u8], size: usize) -> String {
    let mut s = String::new();
    for (k, chunk) in img.chunks(size).enumerate() {
        s.push_str(&rec((k * size) as u16, 0, chunk));
    }
    s.push_str(":00000001FF\r\n");
    s
}

/// Feed all of `text`; the event after the last byte, and the index of the first byte
/// that gave a non-`More` answer.
fn feed_all(reader: &mut HexReader, text: &[u8]) -> (HexEvent, Option<usize>) {
    let mut last = HexEvent::More;
    let mut first_final = None;
    for (i, &b) in text.iter().enumerate() {
        last = reader.feed(b);
        if last != HexEvent::More && first_final.is_none() {
            first_final = Some(i);
        }
    }
    (last, first_final)
}

fn read(text: &str) -> (HexEvent, HexReader) {
    let mut r = HexReader::new();
    let (ev, _) = feed_all(&mut r, text.as_bytes());
    (ev, r)
}

#[test]
fn writer_text_is_exact() {
    let img = image::encode(&Program::blank());
    let text = hex_text(&img);
    let lines: Vec<&str> = text.split_terminator("\r\n").collect();
    assert_eq!(lines.len(), 20, "18 full records, 1 short, EOF");
    assert_eq!(lines[0], ":1000000075540200FFFFFFFFFFFFFFFFFFFFFFFF31");
    for (k, line) in lines[..18].iter().enumerate() {
        assert_eq!(line.len(), 43);
        assert_eq!(&line[..9], format!(":10{:04X}00", k * 16));
    }
    assert!(
        lines[18].starts_with(":0A012000"),
        "last record: 10 bytes at 0x0120"
    );
    assert_eq!(lines[18].len(), 1 + 8 + 20 + 2);
    assert_eq!(lines[19], ":00000001FF");
    assert!(text.ends_with(":00000001FF\r\n"));
    assert!(!text.contains('\n') || text.matches('\n').count() == text.matches("\r\n").count());
    assert!(
        !text.bytes().any(|b| b.is_ascii_lowercase()),
        "upper case only"
    );
    assert_eq!(text.len(), 18 * 45 + 33 + 13, "WRITE sends 856 bytes");
    // Every record sums to zero.
    for line in &lines {
        let bytes: Vec<u8> = (1..line.len())
            .step_by(2)
            .map(|i| u8::from_str_radix(&line[i..i + 2], 16).unwrap())
            .collect();
        assert_eq!(
            bytes.iter().fold(0u8, |s, &b| s.wrapping_add(b)),
            0,
            "{line}"
        );
    }
    // Independent builder agrees with the writer.
    assert_eq!(text, file_with_records(&img, 16));
}

#[test]
fn round_trip_is_bit_exact() {
    let mut rng = Rng(0xC0FFEE);
    for _ in 0..300 {
        let img = random_image(&mut rng);
        let text = hex_text(&img);
        let mut r = HexReader::new();
        let (ev, first) = feed_all(&mut r, text.as_bytes());
        assert_eq!(ev, HexEvent::Done { len: 298 });
        assert_eq!(
            first,
            Some(text.len() - 3),
            "Done exactly at the EOF record's checksum"
        );
        assert_eq!(r.data(), &img[..]);
        assert_eq!(image::decode(r.data()), image::decode(&img));
    }
}

#[test]
fn done_and_errors_are_latched() {
    let img = image::encode(&Program::blank());
    let (ev, mut r) = read(&hex_text(&img));
    assert_eq!(ev, HexEvent::Done { len: 298 });
    assert_eq!(r.feed(b'x'), HexEvent::Done { len: 298 });
    assert_eq!(r.feed(b':'), HexEvent::Done { len: 298 });

    let (ev, mut r) = read(":1G");
    assert_eq!(ev, HexEvent::Error(HexError::BadChar));
    assert_eq!(r.feed(b':'), HexEvent::Error(HexError::BadChar));
}

#[test]
fn blank_lines_control_chars_and_lower_case_accepted() {
    let mut rng = Rng(5);
    let img = random_image(&mut rng);
    let text = hex_text(&img);
    // CR LF LF (the original's line end), blank lines, spaces and tabs between records,
    // LF-only and CR-only line ends.
    for sep in ["\r\n\n", "\r\n\r\n   \t\r\n", "\n", "\r", "\r\n\0\x7f\n"] {
        let t = text.replace("\r\n", sep);
        let (ev, r) = read(&t);
        assert_eq!(ev, HexEvent::Done { len: 298 }, "separator {sep:?}");
        assert_eq!(r.data(), &img[..]);
    }
    let (ev, r) = read(&text.to_lowercase());
    assert_eq!(ev, HexEvent::Done { len: 298 });
    assert_eq!(r.data(), &img[..]);
    // Screen output before the first record (a captured session) is skipped.
    let (ev, r) = read(&format!("\x1b[11;1H WRITE junk ;-)\r\n{text}"));
    assert_eq!(ev, HexEvent::Done { len: 298 });
    assert_eq!(r.data(), &img[..]);
}

#[test]
fn other_record_sizes_accepted_when_contiguous() {
    let mut rng = Rng(77);
    let img = random_image(&mut rng);
    for size in [1, 8, 15, 32, 255] {
        let (ev, r) = read(&file_with_records(&img, size));
        assert_eq!(ev, HexEvent::Done { len: 298 }, "records of {size}");
        assert_eq!(r.data(), &img[..]);
    }
}

#[test]
fn bad_checksum() {
    let img = image::encode(&Program::blank());
    let text = hex_text(&img);
    let mut lines: Vec<String> = text.split_inclusive("\r\n").map(String::from).collect();
    for k in [0, 5, 17, 18, 19] {
        let mut l = lines.clone();
        // Change one data digit (or the EOF's checksum) without fixing the checksum.
        let pos = if k == 19 { 10 } else { 12 };
        let c = l[k].as_bytes()[pos];
        let new = if c == b'0' { '1' } else { '0' };
        l[k].replace_range(pos..pos + 1, &new.to_string());
        let (ev, _) = read(&l.concat());
        assert_eq!(ev, HexEvent::Error(HexError::Checksum), "record {k}");
    }
    // Garbled address digits are a checksum error too (checked before the address).
    lines[3].replace_range(4..5, "F");
    assert_eq!(read(&lines.concat()).0, HexEvent::Error(HexError::Checksum));
}

#[test]
fn bad_chars() {
    let img = image::encode(&Program::blank());
    let text = hex_text(&img);
    for (pos, c) in [(1usize, 'G'), (20, ' '), (44, 'z'), (50, '\r'), (60, ':')] {
        let mut t = text.clone();
        t.replace_range(pos..pos + 1, &c.to_string());
        assert_eq!(
            read(&t).0,
            HexEvent::Error(HexError::BadChar),
            "{c:?} at {pos}"
        );
    }
    // A truncated record line (line end inside the record).
    let first_end = format!("FFFF{}\r\n", &text[41..43]);
    let t = text.replacen(&first_end, "FF\r\n", 1);
    assert_eq!(read(&t).0, HexEvent::Error(HexError::BadChar));
    // Printable junk between records.
    let t = text.replacen("\r\n", "\r\nhello\r\n", 1);
    assert_eq!(read(&t).0, HexEvent::Error(HexError::BadChar));
}

#[test]
fn too_long_line() {
    let img = image::encode(&Program::blank());
    let text = hex_text(&img);
    let t = text.replacen("\r\n", "00\r\n", 1);
    assert_eq!(read(&t).0, HexEvent::Error(HexError::TooLong));
}

#[test]
fn wrong_addresses_gaps_and_overlaps() {
    let mut rng = Rng(11);
    let img = random_image(&mut rng);
    let recs: Vec<String> = img
        .chunks(16)
        .enumerate()
        .map(|(k, c)| rec(k as u16 * 16, 0, c))
        .collect();
    let eof = ":00000001FF\r\n".to_string();

    // Not starting at 0.
    let mut t = vec![rec(0x0001, 0, &img[0..16])];
    t.extend_from_slice(&recs[1..]);
    t.push(eof.clone());
    assert_eq!(read(&t.concat()).0, HexEvent::Error(HexError::Address));

    // A gap: record 4 missing.
    let mut t = recs.clone();
    t.remove(4);
    t.push(eof.clone());
    assert_eq!(read(&t.concat()).0, HexEvent::Error(HexError::Address));

    // An overlap: record 4 twice.
    let mut t = recs.clone();
    t.insert(4, recs[4].clone());
    t.push(eof.clone());
    assert_eq!(read(&t.concat()).0, HexEvent::Error(HexError::Address));

    // Out of order.
    let mut t = recs.clone();
    t.swap(2, 3);
    t.push(eof.clone());
    assert_eq!(read(&t.concat()).0, HexEvent::Error(HexError::Address));

    // Past the end of the image: a full 16-byte last record (0x120..0x130).
    let mut t = recs[..18].to_vec();
    let mut last = img[0x120..].to_vec();
    last.resize(16, 0);
    t.push(rec(0x0120, 0, &last));
    t.push(eof.clone());
    assert_eq!(read(&t.concat()).0, HexEvent::Error(HexError::Address));

    // An extra record after the whole image.
    let mut t = recs.clone();
    t.push(rec(0x012A, 0, &[0]));
    t.push(eof.clone());
    assert_eq!(read(&t.concat()).0, HexEvent::Error(HexError::Address));

    // A far address (e.g. a firmware file).
    let t = [rec(0x3C00, 0, &[1, 2, 3]), eof].concat();
    assert_eq!(read(&t).0, HexEvent::Error(HexError::Address));
}

#[test]
fn wrong_record_types() {
    let img = image::encode(&Program::blank());
    let text = hex_text(&img);
    for kind in [2u8, 3, 4, 5, 0xFF] {
        let t = format!("{}{text}", rec(0, kind, &[0, 0]));
        assert_eq!(
            read(&t).0,
            HexEvent::Error(HexError::RecordType),
            "type {kind:02X}"
        );
    }
    // An end-of-file record carrying data.
    let t = text.replace(":00000001FF\r\n", &rec(0, 1, &[0]));
    assert_eq!(read(&t).0, HexEvent::Error(HexError::RecordType));
}

#[test]
fn truncated_files() {
    let img = image::encode(&Program::blank());
    let text = hex_text(&img);
    let lines: Vec<&str> = text.split_inclusive("\r\n").collect();
    // EOF after some records: Short.
    for n in [0, 1, 10, 17] {
        let t = [lines[..n].concat(), ":00000001FF\r\n".into()].concat();
        assert_eq!(read(&t).0, HexEvent::Error(HexError::Short), "{n} records");
    }
    // No EOF record: the reader keeps waiting (the editor's 3 s silence timeout ends it).
    let mut r = HexReader::new();
    let (ev, first) = feed_all(&mut r, lines[..18].concat().as_bytes());
    assert_eq!((ev, first), (HexEvent::More, None));
    // Cut in the middle of a record: still waiting, never Done.
    for cut in [1, 100, 400, 790] {
        let mut r = HexReader::new();
        assert_eq!(
            feed_all(&mut r, &text.as_bytes()[..cut]),
            (HexEvent::More, None),
            "cut {cut}"
        );
    }
}

#[test]
fn random_bytes_never_give_an_image() {
    let mut rng = Rng(0xDEAD_BEEF);
    for round in 0..3000 {
        let len = 1 + (rng.next_u32() % 1500) as usize;
        let mut r = HexReader::new();
        let mut errors = 0;
        for i in 0..len {
            // Mostly hex-ish text with colons, sometimes any byte.
            let b = match rng.next_u32() % 8 {
                0 => b':',
                1 => rng.byte(),
                2 => b'\n',
                _ => b"0123456789ABCDEFabcdef"[(rng.next_u32() % 22) as usize],
            };
            let b = if round % 2 == 0 && i == 0 { b':' } else { b };
            match r.feed(b) {
                HexEvent::Done { .. } => panic!("random input accepted (round {round})"),
                HexEvent::Error(_) => errors += 1,
                HexEvent::More => assert_eq!(errors, 0, "errors are latched"),
            }
        }
    }
}

#[test]
fn valid_hex_with_a_bad_image_is_caught_by_decode() {
    let mut img = image::encode(&Program::blank());
    img[2] = 3; // a future version
    let (ev, r) = read(&hex_text(&img));
    assert_eq!(ev, HexEvent::Done { len: 298 });
    assert_eq!(image::decode(r.data()), Err(ImageError::Version(3)));

    let mut img = image::encode(&Program::blank());
    img[100] ^= 1; // damaged in a text editor, checksums recomputed
    let (ev, r) = read(&hex_text(&img));
    assert_eq!(ev, HexEvent::Done { len: 298 });
    assert_eq!(image::decode(r.data()), Err(ImageError::Crc));

    // A hex file of some other 298 bytes (not a uTile image).
    let (ev, r) = read(&hex_text(&[0x55; IMAGE_LEN]));
    assert_eq!(ev, HexEvent::Done { len: 298 });
    assert_eq!(image::decode(r.data()), Err(ImageError::Magic));
}

#[test]
fn a_version_1_file_is_whole_at_278_bytes_and_decodes() {
    let mut prog = Program::blank();
    prog.uf[0] = 0x20;
    prog.presets[1] = 3;
    let mut v1 = image::encode(&prog)[..image::COUNTER_PRESETS_OFFSET].to_vec();
    v1[image::VERSION_OFFSET] = image::VERSION_1;
    let crc = image::crc16_ccitt(&v1);
    v1.extend_from_slice(&crc.to_be_bytes());
    let (ev, r) = read(&hex_text(&v1));
    assert_eq!(ev, HexEvent::Done { len: 278 });
    assert_eq!(image::decode(r.data()), Ok(prog));
}
