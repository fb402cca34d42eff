//! The real firmware image in simavr: reset state of the pins, out_sense, inputs, autostart
//! from EEPROM, the main screen. Needs `out/m328-nano-utile.elf` (`cargo fw`).

mod support;

use support::chip::{Board, Rig, CYCLES_PER_MS, RAMSTART, STACK_PAINT};
use utile_core::engine::Program;
use utile_core::opcodes::{END, LOAD_PA, NOT_ALL, STORE_PY};

/// An EEPROM holding `uf` (from line 0) as written by STORE.
fn eeprom_with(uf: &[u8]) -> &'static [u8] {
    let mut prog = Program::blank();
    prog.uf[..uf.len()].copy_from_slice(uf);
    support::chip::stored(&prog)
}

/// Step until the pins become outputs and return (PORTD, PORTB) at that instant.
fn ports_when_outputs_appear(rig: Rig) -> (u8, u8) {
    let mut nano = Board::load(rig);
    for _ in 0..100_000 {
        let (portd, ddrd) = nano.port('D');
        let (portb, ddrb) = nano.port('B');
        if ddrd != 0 || ddrb & 0x30 != 0 {
            return (portd, portb);
        }
        nano.step();
    }
    panic!("the output pins never became outputs");
}

#[test]
fn outputs_are_off_before_they_become_outputs() {
    let (portd, portb) = ports_when_outputs_appear(Rig::default());
    assert_eq!(
        portd & 0xFC,
        0,
        "Y0..Y5 must be low when PD2..PD7 turn to outputs"
    );
    assert_eq!(
        portb & 0x30,
        0,
        "Y6/Y7 must be low when PB4/PB5 turn to outputs"
    );
}

#[test]
fn with_d9_grounded_outputs_are_high_before_they_become_outputs() {
    let (portd, portb) = ports_when_outputs_appear(Rig {
        d9: true,
        ..Rig::default()
    });
    assert_eq!(
        portd & 0xFC,
        0xFC,
        "active-low relays: Y0..Y5 high from the start"
    );
    assert_eq!(
        portb & 0x30,
        0x30,
        "active-low relays: Y6/Y7 high from the start"
    );
}

#[test]
fn reset_state_of_every_pin() {
    let mut nano = Board::boot();
    assert_eq!(nano.y_pins(), 0, "all outputs off");
    let (portc, ddrc) = nano.port('C');
    assert_eq!(ddrc & 0x3F, 0, "A0..A5 are inputs");
    assert_eq!(portc & 0x3F, 0x3F, "A0..A5 have their pull-ups on");
    assert_eq!(nano.pin_reg('C') & 0x3F, 0x3F, "open inputs read 1");
    let (portb, ddrb) = nano.port('B');
    assert_eq!(ddrb & 0x03, 0, "D8/D9 are inputs");
    assert_eq!(portb & 0x03, 0x03, "D8/D9 have their pull-ups on");
    assert_eq!(ddrb & 0x30, 0x30);
    nano.run_ms(100);
    assert_eq!(nano.y_pins(), 0, "outputs stay off in the editor");
}

#[test]
fn grounding_d9_while_running_inverts_the_pins_within_2ms() {
    let mut nano = Board::boot();
    assert_eq!(nano.y_pins(), 0);
    nano.jumper_d9(true);
    nano.run_ms(2);
    assert_eq!(nano.y_pins(), 0xFF, "out_sense applies at the pins");
    assert_eq!(nano.outputs(), 0, "the output image itself is unchanged");
    nano.jumper_d9(false);
    nano.run_ms(2);
    assert_eq!(nano.y_pins(), 0);
}

#[test]
fn autostart_runs_the_stored_program_within_100ms_and_maps_every_pin() {
    // PA. !! .PY END: Y0..Y5 = NOT A0..A5 (on while the switch is closed), Y6/Y7 = 1.
    let eeprom = eeprom_with(&[LOAD_PA, NOT_ALL, STORE_PY, END]);
    let mut nano = Board::load(Rig {
        d8: true,
        eeprom: Some(eeprom),
        ..Rig::default()
    });
    let mut ms = 0;
    while ms < 100 {
        nano.run_ms(1);
        ms += 1;
        if nano.y_pins() == 0xC0 {
            break;
        }
    }
    assert_eq!(
        nano.y_pins(),
        0xC0,
        "program not running 100 ms after reset"
    );
    println!("autostart: outputs driven by the program {ms} ms after reset");
    for n in 0..6 {
        nano.switch(n, true);
        // SPEC §7: press to output at most 8 ms.
        nano.run_ms(8);
        assert_eq!(
            nano.y_pins(),
            0xC0 | (1 << n),
            "switch A{n} closed → Y{n} on"
        );
        nano.switch(n, false);
        nano.run_ms(8);
        assert_eq!(nano.y_pins(), 0xC0, "switch A{n} open → Y{n} off");
    }
}

#[test]
fn autostart_with_out_sense_inverts_only_at_the_pins() {
    // PA. .PY END: Y0..Y5 follow the (open = 1) inputs, Y6/Y7 = 0.
    let eeprom = eeprom_with(&[LOAD_PA, STORE_PY, END]);
    let mut nano = Board::boot_with(Rig {
        d8: true,
        d9: true,
        eeprom: Some(eeprom),
    });
    assert_eq!(nano.outputs(), 0x3F);
    assert_eq!(nano.y_pins(), 0xC0, "pins inverted by D9");
    nano.switch(2, true);
    nano.run_ms(10);
    assert_eq!(nano.outputs(), 0x3B);
    assert_eq!(nano.y_pins(), 0xC4);
}

#[test]
fn without_d8_the_stored_program_does_not_start() {
    let eeprom = eeprom_with(&[LOAD_PA, NOT_ALL, STORE_PY, END]);
    let mut nano = Board::boot_with(Rig {
        eeprom: Some(eeprom),
        ..Rig::default()
    });
    nano.run_ms(100);
    assert_eq!(nano.y_pins(), 0, "EDIT mode: outputs off");
}

#[test]
fn autostart_without_a_valid_image_stays_in_the_editor() {
    let mut nano = Board::boot_with(Rig {
        d8: true,
        ..Rig::default()
    });
    nano.run_ms(100);
    assert_eq!(nano.y_pins(), 0);
}

#[test]
fn reset_button_restarts_the_stored_program() {
    let eeprom = eeprom_with(&[LOAD_PA, NOT_ALL, STORE_PY, END]);
    let mut nano = Board::boot_with(Rig {
        d8: true,
        eeprom: Some(eeprom),
        ..Rig::default()
    });
    assert_eq!(nano.y_pins(), 0xC0);
    nano.reset_button();
    nano.run_ms(100);
    assert_eq!(nano.y_pins(), 0xC0, "running again after the reset");
}

#[test]
fn static_data_plus_stack_stay_within_1536_bytes() {
    let eeprom = eeprom_with(&[LOAD_PA, NOT_ALL, STORE_PY, END]);
    let mut nano = Board::boot_with(Rig {
        d8: true,
        eeprom: Some(eeprom),
        ..Rig::default()
    });
    nano.switch(0, true);
    nano.run_ms(200);
    // Static data ends where the paint begins.
    let mut end = RAMSTART;
    while !(0..16).all(|i| nano.ram(end + i) == STACK_PAINT) {
        end += 1;
    }
    let statics = end - RAMSTART;
    let stack = nano.stack_high_water();
    println!(
        "RAM: static {statics} bytes, stack high-water {stack} bytes, total {}",
        statics + stack
    );
    assert!(stack > 0 && statics > 0);
    assert!(
        statics + stack <= 1536,
        "RAM budget (SPEC §11): {} bytes",
        statics + stack
    );
}

#[test]
fn the_timer_interrupt_runs_at_1khz() {
    // Indirect but exact: Timer0 counts in CTC mode from 0 to 249 at clk/64.
    let mut nano = Board::boot();
    let start = nano.cycles();
    nano.run_cycles(10 * CYCLES_PER_MS);
    assert!(nano.cycles() - start >= 10 * CYCLES_PER_MS);
    // TCCR0A = CTC, OCR0A = 249, TCCR0B = clk/64, TIMSK0 = OCIE0A.
    let reg = |a: u16| nano.data(a);
    assert_eq!(
        (reg(0x44), reg(0x47), reg(0x45), reg(0x6E)),
        (0x02, 249, 0x03, 0x02)
    );
}

// ---- these need the editor (issue 4): they describe the manual's main screen ----

#[test]
fn boots_to_the_main_screen() {
    let mut nano = Board::boot();
    assert!(
        nano.wait_for("*** User File 0 ***", 1500),
        "status line missing"
    );
    let screen = nano.screen();
    assert!(
        screen.contains("<<<< Nano - u T I L E - ATmega328 >>>>"),
        "{screen}"
    );
    assert!(screen.contains("Enter:"), "{screen}");
    assert!(screen.contains("000 "), "{screen}");
}

#[test]
fn typed_characters_echo_at_the_prompt() {
    let mut nano = Board::boot();
    assert!(nano.wait_for("*** User File 0 ***", 1500));
    nano.take_output();
    nano.type_bytes(b"A0.");
    nano.drain_typed();
    nano.run_ms(20);
    let screen = nano.screen();
    let prompt = screen
        .lines()
        .find(|l| l.contains("Enter:"))
        .unwrap_or_default();
    assert!(
        prompt.contains("Enter:A0.") || prompt.contains("Enter: A0."),
        "{prompt:?}"
    );
}

#[test]
fn set_then_pop_into_y7_lights_led_l_at_once() {
    let mut nano = Board::boot();
    assert!(nano.wait_for("*** User File 0 ***", 1500));
    nano.enter("SET", 50);
    nano.enter(".Y7", 50);
    assert_eq!(nano.outputs(), 0x80, "manual §5.4: LED L on");
    nano.enter("CLR", 50);
    nano.enter(".Y7", 50);
    assert_eq!(nano.outputs(), 0);
}
