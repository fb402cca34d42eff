//! Stored-image format (docs/FORMAT.md): encode/decode round trips and every decode error.

use utile_core::engine::Program;
use utile_core::image::{self, ImageError, CRC_OFFSET, IMAGE_LEN, IMAGE_LEN_V1, MAGIC, VERSION};
use utile_kit::rng::Rng;

#[test]
fn crc_check_value() {
    assert_eq!(image::crc16_ccitt(b"123456789"), 0x29B1);
}

#[test]
fn layout_of_a_blank_program() {
    let img = image::encode(&Program::blank());
    assert_eq!(img.len(), 298);
    assert_eq!(&img[0..4], &[b'u', b'T', 2, 0]);
    assert!(
        img[4..260].iter().all(|&b| b == 0xFF),
        "blank lines are 0xFF"
    );
    assert!(img[260..276].iter().all(|&b| b == 0), "presets 0");
    assert!(
        img[276..296].iter().all(|&b| b == 0),
        "counter presets, set-points 0"
    );
    let crc = image::crc16_ccitt(&img[..296]);
    assert_eq!(
        &img[296..298],
        &crc.to_be_bytes(),
        "CRC big-endian over bytes 0..296"
    );
}

#[test]
fn lines_and_presets_land_at_their_offsets() {
    let mut p = Program::blank();
    p.uf[0] = 0x12;
    p.uf[255] = 0x34;
    p.presets[0] = 7;
    p.presets[15] = 255;
    p.counter_presets[0] = 0x1234;
    p.counter_presets[7] = 65535;
    p.set_points = [1023, 1];
    let img = image::encode(&p);
    assert_eq!(img[4], 0x12);
    assert_eq!(img[259], 0x34);
    assert_eq!(img[260], 7);
    assert_eq!(img[275], 255);
    assert_eq!(&img[276..278], &[0x12, 0x34], "C0 high byte first");
    assert_eq!(&img[290..292], &[0xFF, 0xFF], "C7");
    assert_eq!(&img[292..296], &[0x03, 0xFF, 0x00, 0x01], "S6, S7");
}

#[test]
fn round_trip_many_programs() {
    let mut rng = Rng(0x1234_5678);
    for _ in 0..500 {
        let p = rng.program_v2();
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
    assert_eq!(image::decode(&img[..297]), Err(ImageError::Length));
    assert_eq!(
        image::decode(&img[..IMAGE_LEN_V1]),
        Err(ImageError::Length),
        "v2 header, v1 length"
    );
    assert_eq!(image::decode(&[]), Err(ImageError::Length));
    let mut long = img.to_vec();
    long.push(0);
    assert_eq!(image::decode(&long), Err(ImageError::Length));
}

#[test]
fn magic_version_and_crc_errors() {
    let mut rng = Rng(99);
    let img = image::encode(&rng.program_v2());

    for i in 0..2 {
        let mut bad = img;
        bad[i] ^= 0x01;
        assert_eq!(
            image::decode(&bad),
            Err(ImageError::Magic),
            "magic byte {i}"
        );
    }
    for v in [0u8, 3, 0xFF] {
        let mut bad = img;
        bad[2] = v;
        // Even with a CRC that matches, an unknown version is refused as such.
        let crc = image::crc16_ccitt(&bad[..CRC_OFFSET]).to_be_bytes();
        bad[CRC_OFFSET..].copy_from_slice(&crc);
        assert_eq!(image::decode(&bad), Err(ImageError::Version(v)));
    }
    // Every other byte (reserved, lines, presets, counter presets, set-points, the CRC
    // itself) is covered by the CRC.
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
    assert_eq!(VERSION, 2);
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
        bytes[0..4].copy_from_slice(&[b'u', b'T', 2, 0]);
        if image::crc16_ccitt(&bytes[..CRC_OFFSET]).to_be_bytes() != bytes[CRC_OFFSET..] {
            assert_eq!(image::decode(&bytes), Err(ImageError::Crc));
        }
    }
}

/// `prog` as the version-1 firmware wrote it (278 bytes).
fn version_1(prog: &Program) -> Vec<u8> {
    let mut v1 = image::encode(prog)[..image::COUNTER_PRESETS_OFFSET].to_vec();
    v1[image::VERSION_OFFSET] = 1;
    let crc = image::crc16_ccitt(&v1);
    v1.extend_from_slice(&crc.to_be_bytes());
    v1
}

#[test]
fn version_1_images_decode_with_counter_presets_and_set_points_0() {
    let mut rng = Rng(5);
    for _ in 0..200 {
        let p = rng.program();
        assert_eq!(image::decode(&version_1(&p)), Ok(p));
    }
    // The version-1 layout is checked like version 2's: a damaged byte fails the CRC.
    let mut bad = version_1(&rng.program());
    bad[100] ^= 4;
    assert_eq!(image::decode(&bad), Err(ImageError::Crc));
}

#[test]
fn a_set_point_above_1023_is_refused() {
    let mut p = Program::blank();
    p.set_points = [1024, 0];
    assert_eq!(image::decode(&image::encode(&p)), Err(ImageError::Value));
    p.set_points = [1023, 1023];
    assert_eq!(image::decode(&image::encode(&p)), Ok(p));
}
