//! The simavr harness's own capabilities, each on a tiny fixture built here with avr-gcc
//! (`kit/tests/fixtures/*.c`): a boot loader beside the application, reset flags and the
//! cycle count over resets, the watchdog after a reset and in interrupt-and-system-reset
//! mode, the ADC in millivolts, UART bytes timed at any baud, several chips on one RS-485
//! line; and the datasheet's timings simavr leaves out or gets wrong (docs/SIMULATORS.md):
//! an interrupt's entry, the ADC's conversion time, the CPU's halt after an EEPROM read,
//! the transmitter's data register in front of its shift register.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use utile_kit::simavr::{
    frame_cycles, BootSection, Bus, Chip, Reset, RxPacing, CYCLES_PER_MS, F_CPU,
};

/// Builds a fixture with avr-gcc (once per name, one build at a time: the tests run in
/// parallel) and returns its ELF.
fn fixture(src: &str, name: &str, flags: &[&str]) -> PathBuf {
    static BUILD: Mutex<()> = Mutex::new(());
    let _one_at_a_time = BUILD.lock().unwrap_or_else(|e| e.into_inner());
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("simavr-harness");
    std::fs::create_dir_all(&dir).expect("fixture dir");
    let elf = dir.join(format!("{name}-{}.elf", std::process::id()));
    if elf.is_file() {
        return elf;
    }
    let src = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(src);
    utile_kit::setup::avr_gcc(&src, &elf, flags);
    elf
}

fn app() -> PathBuf {
    fixture("app.c", "app", &[])
}

fn boot_loader(section: BootSection) -> PathBuf {
    let start = format!("-Wl,--section-start=.text={:#x}", section.start());
    fixture("boot.c", &format!("boot-{:x}", section.start()), &[&start])
}

/// Runs until the output holds `n` lines; returns them (with the cycle each line's last
/// byte ends).
fn lines(chip: &mut Chip, n: usize, max_ms: u64) -> Vec<(String, u64)> {
    let mut text = Vec::new();
    let mut out = Vec::new();
    for _ in 0..max_ms {
        for (b, at) in chip.take_output_timed() {
            if b == b'\n' {
                let line = String::from_utf8_lossy(&text).trim_end().to_string();
                out.push((line, at));
                text.clear();
            } else {
                text.push(b);
            }
        }
        if out.len() >= n {
            return out;
        }
        chip.run_for(CYCLES_PER_MS);
    }
    panic!("only {out:?} (and {text:?}) within {max_ms} ms");
}

fn texts(lines: &[(String, u64)]) -> Vec<&str> {
    lines.iter().map(|(l, _)| l.as_str()).collect()
}

#[test]
fn a_boot_loader_in_the_boot_section_runs_first_and_sees_the_reset_flags() {
    for section in [BootSection::B512, BootSection::K2] {
        let mut chip = Chip::load(&app()).expect("load");
        chip.load_boot(&boot_loader(section), section)
            .expect("load the boot loader");
        assert_eq!(
            chip.pc(),
            section.start(),
            "BOOTRST: execution starts there"
        );
        assert_eq!(
            section.start(),
            if section == BootSection::B512 {
                0x7E00
            } else {
                0x7800
            }
        );
        assert_eq!(chip.mcusr(), 0x01, "power-on");
        let got = lines(&mut chip, 2, 100);
        assert_eq!(texts(&got), ["BOOT mcusr=01", "APP mcusr=01"]);

        // The reset button: the boot loader again, with EXTRF (the app cleared PORF).
        chip.reset(Reset::External);
        assert_eq!(chip.pc(), section.start());
        let got = lines(&mut chip, 2, 100);
        assert_eq!(texts(&got), ["BOOT mcusr=02", "APP mcusr=02"]);

        // A watchdog reset done by simavr itself also starts in the boot section.
        chip.send(b"w");
        let got = lines(&mut chip, 2, 100);
        assert_eq!(texts(&got), ["BOOT mcusr=08", "APP mcusr=08"]);

        // Power off and on: PORF alone.
        chip.reset(Reset::PowerOn);
        let got = lines(&mut chip, 2, 100);
        assert_eq!(texts(&got), ["BOOT mcusr=01", "APP mcusr=01"]);
    }
}

#[test]
fn without_a_boot_loader_the_chip_starts_at_0_with_power_on_flags() {
    let mut chip = Chip::load(&app()).expect("load");
    assert_eq!(chip.pc(), 0);
    assert_eq!(texts(&lines(&mut chip, 1, 50)), ["APP mcusr=01"]);
    chip.reset(Reset::Watchdog);
    assert_eq!(texts(&lines(&mut chip, 1, 50)), ["APP mcusr=08"]);
}

#[test]
fn the_cycle_count_goes_on_over_resets() {
    let mut chip = Chip::load(&app()).expect("load");
    lines(&mut chip, 1, 50);
    chip.run_for(10 * CYCLES_PER_MS);
    let before = chip.cycle();
    assert!(before >= 10 * CYCLES_PER_MS);
    chip.reset(Reset::External);
    assert!(
        chip.cycles_since_reset() < 10,
        "simavr restarts its own count"
    );
    assert!(chip.cycle() >= before, "ours goes on");
    chip.run_for(CYCLES_PER_MS);
    assert!(chip.cycle() >= before + CYCLES_PER_MS);
    assert_eq!(texts(&lines(&mut chip, 1, 50)), ["APP mcusr=02"]);

    // Over a watchdog reset simavr does by itself, inside a step.
    chip.send(b"w");
    let sent = chip.cycle();
    let got = lines(&mut chip, 1, 100);
    assert_eq!(texts(&got), ["APP mcusr=08"]);
    let after = got[0].1;
    let ms = (after - sent) as f64 / CYCLES_PER_MS as f64;
    // The byte (0.6 ms), the 16 ms timeout, the boot line (14 bytes, 7.3 ms).
    assert!(
        (20.0..30.0).contains(&ms),
        "watchdog reset and boot line in {ms} ms"
    );
}

#[test]
fn after_a_reset_the_watchdog_fires_on_time() {
    // EEPROM byte 1 set: the app leaves the watchdog enabled after a watchdog reset (WDRF
    // forces WDE at the shortest timeout), so the chip resets every 16 ms and some.
    let mut chip = Chip::load(&app()).expect("load");
    chip.set_eeprom(1, &[1]);
    lines(&mut chip, 1, 50);
    chip.reset(Reset::Watchdog);
    let got = lines(&mut chip, 4, 200);
    // The app keeps MCUSR too: PORF from power-up, WDRF from each timeout.
    assert!(texts(&got).iter().all(|l| *l == "APP mcusr=09"), "{got:?}");
    for w in got.windows(2) {
        let ms = (w[1].1 - w[0].1) as f64 / CYCLES_PER_MS as f64;
        // 16.4 ms of timeout (2048 cycles of the 128 kHz oscillator; simavr says 16 ms).
        assert!((15.5..17.5).contains(&ms), "resets {ms} ms apart: {got:?}");
    }
}

/// Sends `cmd` to the app (after its boot line), runs until the next boot line, and returns
/// the lines after the command and the ms from the command to that boot line.
fn hang_until_reset(cmd: u8, max_ms: u64) -> (Vec<String>, f64) {
    let mut chip = Chip::load(&app()).expect("load");
    chip.set_rx_pacing(RxPacing::Line { baud: 19_200 });
    lines(&mut chip, 1, 50);
    chip.send(&[cmd]);
    // The byte's frame ends when the app can take it.
    let sent = chip.cycle() + frame_cycles(19_200);
    let mut got = Vec::new();
    loop {
        let (line, at) = lines(&mut chip, 1, max_ms).remove(0);
        got.push(line.clone());
        if line.starts_with("APP") {
            let ms = (at - sent) as f64 / CYCLES_PER_MS as f64;
            return (got, ms);
        }
    }
}

#[test]
fn with_interrupts_off_the_watchdog_interrupt_becomes_a_reset_at_the_next_time_out() {
    // simavr alone would raise the pending interrupt again for ever; a real chip resets.
    let (got, ms) = hang_until_reset(b'i', 200);
    assert_eq!(got, ["APP mcusr=08"], "WDRF after the reset");
    // Two time-outs of 16 ms (2048 cycles of simavr's 128 kHz), then the 7.3 ms boot line.
    assert!(
        (38.0..41.0).contains(&ms),
        "reset and boot line {ms} ms after the hang"
    );
}

#[test]
fn with_interrupts_on_the_watchdog_interrupt_runs_first_then_the_reset() {
    let (got, ms) = hang_until_reset(b'j', 200);
    assert_eq!(got, ["WDT", "APP mcusr=08"]);
    // The handler ran at the first time-out (clearing WDIE); the reset came at the second.
    assert!(
        (38.0..41.0).contains(&ms),
        "reset and boot line {ms} ms after the hang"
    );
}

#[test]
fn a_wdr_while_the_interrupt_waits_puts_the_reset_off() {
    // Pending at 16 ms; wdr at 20, 30, 40 and 50 ms; the reset 16 ms after the last (66 ms),
    // the boot line 7.3 ms later.
    let (got, ms) = hang_until_reset(b'k', 300);
    assert_eq!(got, ["APP mcusr=08"]);
    assert!(
        (70.0..77.0).contains(&ms),
        "reset and boot line {ms} ms after the hang"
    );
}

#[test]
fn the_adc_reads_millivolts_against_avcc() {
    let mut chip = Chip::load(&app()).expect("load");
    lines(&mut chip, 1, 50);
    for (mv, reading) in [(2500, "0511"), (0, "0000"), (5000, "1023"), (1000, "0204")] {
        chip.set_analog_mv(6, mv);
        chip.send(b"a");
        let got = lines(&mut chip, 1, 20);
        assert_eq!(got[0].0, format!("A6={reading}"), "{mv} mV");
    }
    // Another channel does not leak into ADC6.
    chip.set_analog_mv(7, 4000);
    chip.set_analog_mv(6, 1250);
    chip.send(b"a");
    assert_eq!(lines(&mut chip, 1, 20)[0].0, "A6=0255");
}

/// Echo test at `baud` with the app built for `ubrr`: back-to-back bytes every frame, a
/// gap where the sender made one, each echo timed at its stop bit.
fn echo_timing(baud: u32, ubrr: u32) {
    let flag = format!("-DUBRRV={ubrr}");
    let mut chip = Chip::load(&fixture("app.c", &format!("app-{ubrr}"), &[&flag])).unwrap();
    chip.set_rx_pacing(RxPacing::Line { baud });
    chip.run_for(20 * CYCLES_PER_MS);
    chip.take_output();
    assert_eq!(chip.baud(), (F_CPU / (16 * (u64::from(ubrr) + 1))) as u32);
    let frame = frame_cycles(baud);
    let gap = 35 * frame / 10; // Modbus's 3.5 characters of silence
    chip.send(b"ABCD");
    chip.send_after(gap, b"EF");
    let start = chip.cycle();
    chip.run_for(12 * frame);
    assert_eq!(chip.pending_input(), 0);
    chip.run_for(2 * frame);
    let echo = chip.take_output_timed();
    let bytes: Vec<u8> = echo.iter().map(|&(b, _)| b).collect();
    assert_eq!(bytes, b"ABCDEF");
    // The first byte is in after one frame; the echo leaves at the firmware's own rate.
    let tx_frame = 10 * 16 * (u64::from(ubrr) + 1);
    let first = echo[0].1 - start;
    assert!(
        (frame + tx_frame..frame + tx_frame + 200).contains(&first),
        "first echo ends {first} cycles after sending (frame {frame}, tx {tx_frame})"
    );
    let gaps: Vec<u64> = echo.windows(2).map(|w| w[1].1 - w[0].1).collect();
    for (i, g) in gaps.iter().enumerate() {
        let want = if i == 3 { frame + gap } else { frame };
        assert!(
            want.abs_diff(*g) <= 60,
            "gap {i}: {g} cycles, want {want} (all {gaps:?})"
        );
    }
}

#[test]
fn uart_bytes_are_received_and_timed_at_19200_baud() {
    echo_timing(19_200, 51);
    // One 8N1 frame at 19200 baud is 521 µs.
    assert_eq!(frame_cycles(19_200) * 1_000_000 / F_CPU, 520);
}

#[test]
fn uart_bytes_are_received_and_timed_at_9600_and_38400_baud() {
    echo_timing(9_600, 103);
    echo_timing(38_400, 25);
}

/// `n` chips running the fixture at bus addresses 0..n, on one line whose driver enables
/// are watched.
fn bus_of_apps(n: u8) -> Bus {
    let chips: Vec<Chip> = (0..n)
        .map(|addr| {
            let mut c = Chip::load(&app()).expect("load");
            c.set_eeprom(0, &[addr]);
            c
        })
        .collect();
    Bus::new(chips, 19_200).with_driver_enable()
}

#[test]
fn three_chips_share_one_rs485_line() {
    let mut bus = bus_of_apps(3);
    assert_eq!(bus.len(), 3);
    bus.run_for(20 * CYCLES_PER_MS);
    assert!(bus.take_master().is_empty(), "silent until addressed");

    let reply = |bus: &mut Bus| -> (String, Vec<usize>) {
        let got = bus.take_master();
        let text =
            String::from_utf8_lossy(&got.iter().map(|b| b.byte).collect::<Vec<_>>()).into_owned();
        assert!(got.windows(2).all(|w| w[0].cycle <= w[1].cycle));
        (text, got.iter().map(|b| b.from).collect())
    };

    // Chip 0 heard one byte.
    bus.send(b"x");
    bus.run_for(10 * CYCLES_PER_MS);
    let (text, from) = reply(&mut bus);
    assert_eq!(text, "R0=01\r\n");
    assert!(from.iter().all(|&f| f == 0));

    // Chip 1 heard "x", chip 0's reply (7 bytes: the line is shared) and "y".
    bus.send(b"y");
    bus.run_for(10 * CYCLES_PER_MS);
    assert_eq!(reply(&mut bus).0, "R1=09\r\n");
    // Chip 2 heard both replies too.
    bus.send(b"z");
    bus.run_for(10 * CYCLES_PER_MS);
    assert_eq!(reply(&mut bus).0, "R2=11\r\n");
    assert!(bus.collisions().is_empty(), "one driver at a time");

    // Everyone at once: the drivers overlap.
    bus.send(b"*");
    bus.run_for(10 * CYCLES_PER_MS);
    let (text, from) = reply(&mut bus);
    assert_eq!(text.len(), 21, "{text:?}");
    for chip in 0..3 {
        assert_eq!(from.iter().filter(|&&f| f == chip).count(), 7);
    }
    let collisions = bus.collisions();
    assert_eq!(collisions.len(), 1, "{collisions:?}");
    let c = &collisions[0];
    assert!(c.chips.len() >= 2);
    let end = c.end.expect("the overlap ended");
    let ms = (end - c.start) as f64 / CYCLES_PER_MS as f64;
    // 7 bytes (3.6 ms) plus the 1.5 ms wait, each chip about as long.
    assert!((4.0..6.0).contains(&ms), "overlap {ms} ms");
}

#[test]
fn the_bus_takes_a_byte_only_if_its_driver_enable_was_up_over_its_whole_wire_time() {
    let mut bus = bus_of_apps(2);
    bus.run_for(20 * CYCLES_PER_MS);
    // Chip 1 raises D10, writes "H\r\n" and drops D10 at once: 'H' has left whole, '\r'
    // is on the wire (half on), '\n' waits in UDR0 and goes out with D10 low (off the line).
    bus.send(b"\"");
    bus.run_for(10 * CYCLES_PER_MS);
    let got = bus.take_master();
    assert_eq!(
        got.iter().map(|b| (b.byte, b.from)).collect::<Vec<_>>(),
        vec![(b'H', 1)],
        "only the byte sent whole under D10"
    );
    let half = bus.half_on();
    assert_eq!(half.len(), 1, "{half:?}");
    assert_eq!((half[0].byte, half[0].from), (b'\r', 1));
    // 10 bits of 16 × (UBRR0 51 + 1) cycles.
    assert_eq!(half[0].stop - half[0].start, 10 * 16 * 52, "{half:?}");
    assert_eq!(
        half[0].start, got[0].cycle,
        "'\\r' right after 'H': double-buffered"
    );
    // Chip 0 heard 'H' (and the master's bytes), not the half byte: its count shows it.
    bus.send(b"x");
    bus.run_for(10 * CYCLES_PER_MS);
    let text: Vec<u8> = bus.take_master().iter().map(|b| b.byte).collect();
    assert_eq!(text, b"R0=03\r\n", "'\"', 'H', 'x'");
    assert!(bus.collisions().is_empty());
}

#[test]
fn dropping_chips_frees_simavr() {
    // Each chip's simulator (its avr_t, 32 KB of flash, RAM, I/O modules) is freed on
    // drop. simavr keeps about 10 KB per chip of its own (IRQ tables and names it never
    // frees); a leaked chip would add its whole MCU.
    const LOADS: u64 = 1000;
    let rss = || {
        let s = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
        s.split_whitespace()
            .nth(1)
            .and_then(|p| p.parse::<u64>().ok())
            .unwrap_or(0)
            * 4096
    };
    let elf = app();
    drop(Chip::load(&elf).unwrap());
    let before = rss();
    for _ in 0..LOADS {
        let mut c = Chip::load(&elf).unwrap();
        c.run_for(1000);
    }
    let per_chip = rss().saturating_sub(before) / LOADS;
    // Leaking the MCU alone (its avr_t, 16.8 KB, and its I/O modules) would exceed this.
    let avr_t = std::mem::size_of::<simavr_ffi::avr_t>() as u64;
    assert!(per_chip < avr_t, "each chip left {per_chip} bytes behind");
}

#[test]
fn eeprom_reads_and_writes_through_one_path() {
    let mut chip = Chip::load(&app()).expect("load");
    assert!(chip.eeprom().iter().all(|&b| b == 0xFF));
    chip.set_eeprom(1020, &[1, 2, 3, 4, 5, 6]);
    let ee = chip.eeprom();
    assert_eq!(&ee[1018..], &[0xFF, 0xFF, 1, 2, 3, 4]);
    chip.set_eeprom(0, &[7]);
    assert_eq!(chip.eeprom()[0], 7);
}

/// Steps until `done` holds after a step, at most `max` cycles; the cycle before and after
/// that step.
fn step_until(chip: &mut Chip, max: u64, mut done: impl FnMut(&Chip) -> bool) -> (u64, u64) {
    let end = chip.cycle() + max;
    while chip.cycle() < end {
        let before = chip.cycle();
        chip.step();
        if done(chip) {
            return (before, chip.cycle());
        }
    }
    panic!("not within {max} cycles (PC {:#06x})", chip.pc());
}

#[test]
fn an_interrupts_entry_takes_four_cycles() {
    // 'j': the watchdog's interrupt with interrupts on, main in `for (;;) {}` (an rjmp to
    // itself, 2 cycles); the vector (6, at 0x18) is reached 2 + 4 cycles after the last
    // rjmp began: "the interrupt execution response … is four clock cycles minimum".
    let mut chip = Chip::load(&app()).expect("load");
    lines(&mut chip, 1, 50);
    chip.send(b"j");
    let (before, at) = step_until(&mut chip, 40 * CYCLES_PER_MS, |c| c.pc() == 0x18);
    assert_eq!(at - before, 2 + 4, "an rjmp, then the interrupt's entry");
}

/// Cycles from the write of ADSC to ADSC reading 0 again for one 'a' of the app.
fn conversion_cycles(chip: &mut Chip) -> u64 {
    const ADCSRA: usize = 0x7A;
    const ADSC: u8 = 1 << 6;
    chip.send(b"a");
    let (_, start) = step_until(chip, 10 * CYCLES_PER_MS, |c| c.peek(ADCSRA) & ADSC != 0);
    let (_, end) = step_until(chip, 10 * CYCLES_PER_MS, |c| c.peek(ADCSRA) & ADSC == 0);
    lines(chip, 1, 20);
    end - start
}

#[test]
fn an_adc_conversion_takes_25_adc_clocks_first_then_13() {
    // The app enables the ADC at boot with clk/128 and converts on each 'a' (ADSC polled).
    let mut chip = Chip::load(&app()).expect("load");
    lines(&mut chip, 1, 50);
    for (clocks, what) in [
        (25, "the first conversion"),
        (13, "the next"),
        (13, "the next"),
    ] {
        let took = conversion_cycles(&mut chip);
        // Within the few cycles of the polling loop around the end.
        // ADSC is seen set after the instruction that wrote it and clear after the one that
        // read it: a few cycles either way.
        assert!(
            (clocks * 128 - 4..clocks * 128 + 8).contains(&took),
            "{what}: {took} cycles, {clocks} ADC clocks are {}",
            clocks * 128
        );
    }
}

#[test]
fn an_eeprom_read_halts_the_cpu_four_cycles() {
    // The app reads EEPROM bytes at boot: `sbi EECR, EERE` (2 cycles) halts the CPU for 4
    // more before the next instruction.
    const SBI_EECR_EERE: u16 = 0x9AF8;
    let mut chip = Chip::load(&app()).expect("load");
    step_until(&mut chip, CYCLES_PER_MS, |c| {
        c.flash_word(c.pc()) == SBI_EECR_EERE
    });
    let from = chip.cycle();
    chip.step();
    assert_eq!(chip.cycle() - from, 2 + 4);
}

#[test]
fn the_transmitter_takes_a_byte_at_once_on_an_idle_line_and_the_next_after_it() {
    // UDR0 is a buffer in front of the shift register: on an idle line a byte written moves
    // on at once and UDRE0 rises again; the byte written behind it waits in UDR0 (UDRE0 0)
    // until the first has left; TXC0 rises once the last stop bit has ended. The app writes
    // its boot line polling UDRE0.
    const UCSR0A: usize = 0xC0;
    const UDRE0: u8 = 1 << 5;
    const TXC0: u8 = 1 << 6;
    let mut chip = Chip::load(&app()).expect("load");
    let (_, first) = step_until(&mut chip, CYCLES_PER_MS, |c| c.output_len() == 1);
    step_until(&mut chip, 20, |c| c.peek(UCSR0A) & UDRE0 != 0);
    assert!(
        chip.cycle() - first < 20,
        "UDRE0 rises at once on an idle line"
    );
    step_until(&mut chip, 100, |c| c.output_len() == 2);
    assert_eq!(
        chip.peek(UCSR0A) & UDRE0,
        0,
        "the second byte waits in UDR0"
    );
    assert_eq!(chip.peek(UCSR0A) & TXC0, 0, "the first is still being sent");
    step_until(&mut chip, 10 * CYCLES_PER_MS, |c| {
        c.peek(UCSR0A) & TXC0 != 0
    });
    let out = chip.take_output_timed();
    let text: Vec<u8> = out.iter().map(|&(b, _)| b).collect();
    assert!(text.starts_with(b"APP mcusr="), "{text:?}");
    let frame = 10 * 16 * 52;
    assert!(
        out.windows(2).all(|w| w[1].1 - w[0].1 == frame),
        "back to back"
    );
    let last_stop = out.last().expect("bytes").1;
    assert!(
        chip.cycle() >= last_stop && chip.cycle() - last_stop < 8,
        "TXC0 at the last stop bit ({last_stop}), not at {}",
        chip.cycle()
    );
}
