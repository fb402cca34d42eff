//! The Arduino boot loaders of Debian's `arduino-core-avr` on a blank simulated chip: they
//! start in their boot section, answer STK500's sync at their baud rate after an external
//! reset, and run the application after it. Skipped (with a message) when the package is
//! missing, unless `CI` is set.

use utile_kit::setup;
use utile_kit::simavr::{
    ArduinoBoot, BootSection, Chip, FlashImage, Reset, RxPacing, CYCLES_PER_MS,
};

/// STK500 v1: GET_SYNC, CRC_EOP; the answer INSYNC, OK.
const SYNC: [u8; 2] = [0x30, 0x20];
const IN_SYNC_OK: [u8; 2] = [0x14, 0x10];

#[test]
fn each_boot_loader_answers_stk500_sync_after_an_external_reset() {
    for boot in ArduinoBoot::ALL {
        if !setup::boot_loader_installed(boot) {
            continue;
        }
        let mut chip = Chip::blank().expect("blank chip");
        boot.load_into(&mut chip).expect("boot loader");
        assert_eq!(chip.pc(), boot.section().start(), "{boot:?}: BOOTRST");
        chip.reset(Reset::External);
        chip.set_rx_pacing(RxPacing::Line { baud: boot.baud() });
        // Give it time to set up its UART, then sync as avrdude does.
        chip.run_for(5 * CYCLES_PER_MS);
        // 16 MHz divides neither rate exactly: 58,824 and 117,647 baud, within 2.2 %.
        let off = chip.baud().abs_diff(boot.baud()) * 1000 / boot.baud();
        assert!(off < 25, "{boot:?} at {} baud", chip.baud());
        let mut got = Vec::new();
        // Both blink the LED first (the old one for about 200 ms): sync every 50 ms.
        for _ in 0..20 {
            chip.send(&SYNC);
            chip.run_for(50 * CYCLES_PER_MS);
            got.extend(chip.take_output());
            if got.windows(2).any(|w| w == IN_SYNC_OK) {
                break;
            }
        }
        assert!(
            got.windows(2).any(|w| w == IN_SYNC_OK),
            "{boot:?}: no sync in {got:02x?}"
        );
    }
}

#[test]
fn optiboot_is_relinked_into_the_1k_section_with_its_version_word_on_top() {
    let boot = ArduinoBoot::Optiboot;
    if !setup::boot_loader_installed(boot) {
        return;
    }
    let raw = FlashImage::read_hex(&boot.hex_path()).unwrap();
    // Debian's build: linked at 0x7E00 but 532 bytes long, past the end of flash.
    assert_eq!(raw.start(), 0x7E00);
    assert!(raw.end() > 0x8000, "{:#x}", raw.end());
    let image = boot.image().unwrap();
    assert_eq!((image.start(), image.end()), (0x7C00, 0x8000));
    let mut chip = Chip::blank().unwrap();
    boot.load_into(&mut chip).unwrap();
    // Version word 4.4 at the top, as avrdude and Optiboot expect.
    assert_eq!(chip.flash_word(0x7FFE), 0x0404);
}

/// The README's recipe for an Optiboot that fits the Nano's 512-byte section (its
/// "Old boot loader or Optiboot"), run as written: from `src=` to the `avr-objcopy` line.
fn optiboot_built_as_the_readme_says(dir: &std::path::Path) -> std::path::PathBuf {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../README.md"))
        .expect("README.md");
    let from = readme
        .find("src=/usr/share/arduino")
        .expect("the recipe in the README");
    let to = from
        + readme[from..]
            .find("avr-objcopy")
            .expect("its avr-objcopy line");
    let end = to + readme[to..].find('\n').expect("a line end");
    let script = &readme[from..end];
    let out = std::process::Command::new("bash")
        .args(["-euc", script])
        .current_dir(dir)
        .output()
        .expect("bash");
    assert!(
        out.status.success(),
        "the README's recipe failed:\n{script}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir.join("optiboot.hex")
}

#[test]
fn optiboot_built_from_the_package_source_as_the_readme_says_fits_512_bytes_and_works() {
    let boot = ArduinoBoot::Optiboot;
    if !setup::boot_loader_installed(boot) {
        return;
    }
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("optiboot-512");
    std::fs::create_dir_all(&dir).unwrap();
    let image = FlashImage::read_hex(&optiboot_built_as_the_readme_says(&dir)).unwrap();
    // Code at 0x7E00, the version word at 0x7FFE, nothing past the end of flash.
    assert_eq!((image.start(), image.end()), (0x7E00, 0x8000));
    let mut chip = Chip::blank().unwrap();
    chip.load_boot_image(&image, BootSection::B512).unwrap();
    assert_eq!(chip.flash_word(0x7FFE), 0x0404, "version 4.4");
    // Code and version word apart: the code ends before 0x7FFE.
    let code_end = (0x7E00..0x7FFE)
        .step_by(2)
        .rev()
        .find(|&a| chip.flash_word(a) != 0xFFFF);
    assert!(code_end.is_some_and(|a| a < 0x7FFE), "{code_end:x?}");
    // A power-up goes straight to the application (here erased flash below the section).
    chip.run_for(CYCLES_PER_MS);
    assert!(chip.pc() < 0x7E00, "power-up left PC at {:#06x}", chip.pc());
    // An external reset (DTR) stays in it for avrdude, at 115200 baud, with no LED flashes.
    chip.reset(Reset::External);
    chip.set_rx_pacing(RxPacing::Line { baud: boot.baud() });
    chip.run_for(2 * CYCLES_PER_MS);
    chip.send(&SYNC);
    chip.run_for(10 * CYCLES_PER_MS);
    assert_eq!(chip.take_output(), IN_SYNC_OK, "STK500 sync");
}
