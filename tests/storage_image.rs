//! Stored-image format (docs/FORMAT.md): encode/decode round trips and every decode error.

use utile_core::engine::Program;
use utile_core::image::{self, ImageError, IMAGE_LEN, MAGIC, VERSION};
use utile_kit::rng::Rng;

#[test]
fn crc_check_value() {
    assert_eq!(image::crc16(b"123456789"), 0x29B1);
}

#[test]
fn layout_of_a_blank_program() {
    let img = image::encode(&Program::blank());
    assert_eq!(img.len(), 278);
    assert_eq!(&img[0..4], &[b'u', b'T', 1, 0]);
    assert!(
        img[4..260].iter().all(|&b| b == 0xFF),
        "blank lines are 0xFF"
    );
    assert!(img[260..276].iter().all(|&b| b == 0), "presets 0");
    let crc = image::crc16(&img[..276]);
    assert_eq!(
        &img[276..278],
        &crc.to_be_bytes(),
        "CRC big-endian over bytes 0..276"
    );
}

#[test]
fn lines_and_presets_land_at_their_offsets() {
    let mut p = Program::blank();
    p.uf[0] = 0x12;
    p.uf[255] = 0x34;
    p.presets[0] = 7;
    p.presets[15] = 255;
    let img = image::encode(&p);
    assert_eq!(img[4], 0x12);
    assert_eq!(img[259], 0x34);
    assert_eq!(img[260], 7);
    assert_eq!(img[275], 255);
}

#[test]
fn round_trip_many_programs() {
    let mut rng = Rng(0x1234_5678);
    for _ in 0..500 {
        let p = rng.program();
        let img = image::encode(&p);
        assert_eq!(image::decode(&img), Ok(p));
    }
    assert_eq!(
        image::decode(&image::encode(&Program::blank())),
        Ok(Program::blank())
    );
}

#[test]
fn length_errors() {
    let img = image::encode(&Program::blank());
    assert_eq!(image::decode(&img[..277]), Err(ImageError::Length));
    assert_eq!(image::decode(&[]), Err(ImageError::Length));
    let mut long = img.to_vec();
    long.push(0);
    assert_eq!(image::decode(&long), Err(ImageError::Length));
}

#[test]
fn magic_version_and_crc_errors() {
    let mut rng = Rng(99);
    let img = image::encode(&rng.program());

    for i in 0..2 {
        let mut bad = img;
        bad[i] ^= 0x01;
        assert_eq!(
            image::decode(&bad),
            Err(ImageError::Magic),
            "magic byte {i}"
        );
    }
    for v in [0u8, 2, 0xFF] {
        let mut bad = img;
        bad[2] = v;
        // Even with a CRC that matches, an unknown version is refused as such.
        let crc = image::crc16(&bad[..276]).to_be_bytes();
        bad[276..].copy_from_slice(&crc);
        assert_eq!(image::decode(&bad), Err(ImageError::Version(v)));
    }
    // Every other byte (reserved, lines, presets, the CRC itself) is covered by the CRC.
    for i in 3..IMAGE_LEN {
        for flip in [0x01u8, 0x80, 0xFF] {
            let mut bad = img;
            bad[i] ^= flip;
            assert_eq!(
                image::decode(&bad),
                Err(ImageError::Crc),
                "byte {i} ^ {flip:#x}"
            );
        }
    }
    assert_eq!(MAGIC, *b"uT");
    assert_eq!(VERSION, 1);
}

#[test]
fn erased_and_random_bytes_are_refused() {
    assert_eq!(image::decode(&[0xFF; IMAGE_LEN]), Err(ImageError::Magic));
    assert_eq!(image::decode(&[0x00; IMAGE_LEN]), Err(ImageError::Magic));
    let mut rng = Rng(7);
    for _ in 0..2000 {
        let mut bytes = [0u8; IMAGE_LEN];
        bytes.iter_mut().for_each(|b| *b = rng.byte());
        assert!(image::decode(&bytes).is_err());
        // Even with the right header, random contents fail the CRC.
        bytes[0..4].copy_from_slice(&[b'u', b'T', 1, 0]);
        if image::crc16(&bytes[..276]).to_be_bytes() != bytes[276..] {
            assert_eq!(image::decode(&bytes), Err(ImageError::Crc));
        }
    }
}
