//! The Arduino boot loaders of Debian's `arduino-core-avr` on a blank simulated chip: they
//! start in their boot section, answer STK500's sync at their baud rate after an external
//! reset, and run the application after it. Skipped (with a message) when the package is
//! missing, unless `CI` is set.

use utile_kit::simavr::{ArduinoBoot, Chip, FlashImage, Reset, RxPacing, CYCLES_PER_MS};

/// STK500 v1: GET_SYNC, CRC_EOP; the answer INSYNC, OK.
const SYNC: [u8; 2] = [0x30, 0x20];
const IN_SYNC_OK: [u8; 2] = [0x14, 0x10];

fn installed(boot: ArduinoBoot) -> bool {
    if boot.hex_path().is_file() {
        return true;
    }
    assert!(
        std::env::var_os("CI").is_none(),
        "{} missing in CI: `./x setup` installs arduino-core-avr",
        boot.hex_path().display()
    );
    eprintln!(
        "SKIPPED: {} missing (install arduino-core-avr: `./x setup`)",
        boot.hex_path().display()
    );
    false
}

#[test]
fn each_boot_loader_answers_stk500_sync_after_an_external_reset() {
    for boot in ArduinoBoot::ALL {
        if !installed(boot) {
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
    if !installed(boot) {
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
