//! The real image in simavr under faults: a reset in the middle of STORE, the deepest
//! editor paths against the RAM budget, and ten simulated minutes of random inputs and UART
//! noise. Needs `out/m328-nano-utile.elf` (`cargo fw`).

mod support;
use support::chip::{contains, stored, Board, Rig, RAMSTART, STACK_PAINT};
use utile_core::engine::Program;
use utile_core::opcodes::{self, NOP};
use utile_core::{ihex, image, store};
use utile_kit::rng::Rng;
use utile_kit::sim::SimBoard;

/// The program every fault test starts from: stored in EEPROM, different from FILL's.
fn old_program() -> Program {
    let mut prog = Program::blank();
    for (line, word) in ["A0.", "!", ".Y0", "SET", ".Y7", "END"].iter().enumerate() {
        prog.uf[line] = opcodes::lookup(word.as_bytes()).expect("a command");
    }
    prog.presets[0] = 42;
    prog
}

/// FILL's program: every line NOP, the presets and set-points of the program it replaced.
fn filled(from: &Program) -> Program {
    Program {
        uf: [NOP; 256],
        ..from.clone()
    }
}

/// What LOAD would find in an EEPROM dump (the core's LOAD over the chip's bytes).
fn stored_program(eeprom: &[u8]) -> Option<Program> {
    let mut board = SimBoard::new();
    board.eeprom = eeprom.to_vec();
    store::load(&mut board).ok()
}

/// Boot with `eeprom`, LOAD it, FILL, and type STORE; returns once the CR is received.
fn start_store(eeprom: &'static [u8]) -> Board {
    let mut nano = Board::boot_with(Rig {
        eeprom: Some(eeprom),
        ..Rig::default()
    });
    assert!(
        nano.wait_for("*** User File 0 ***", 2000),
        "the editor came up"
    );
    nano.enter("LOAD", 400);
    assert!(contains(&nano.take_output(), b"loaded from EEPROM"));
    nano.enter("fill", 400);
    nano.take_output();
    nano.type_bytes(b"STORE\r");
    nano.drain_typed();
    nano
}

/// READ `file` through the UART and return to the editor.
fn read_file(nano: &mut Board, file: &[u8]) {
    nano.enter("READ", 300);
    nano.type_bytes(file);
    nano.drain_typed();
    assert!(
        nano.wait_for("File read completed", 3000),
        "READ took the file"
    );
    nano.enter("", 800);
}

/// WRITE: everything the firmware sends from the CR to the end-of-file record's CR LF.
fn write_file(nano: &mut Board) -> Vec<u8> {
    nano.enter("WRITE", 300);
    nano.take_output();
    nano.type_bytes(b"\r");
    nano.drain_typed();
    assert!(nano.wait_for(":00000001FF", 2000), "WRITE sent the file");
    nano.run_ms(20); // the record's CR LF
    nano.take_output()
}

/// The Intel HEX file WRITE sends for `prog`.
fn hex_of(prog: &Program) -> Vec<u8> {
    let mut file = Vec::new();
    ihex::write_hex(&image::encode(prog), &mut |c| file.push(c));
    file
}

#[test]
fn a_reset_in_the_middle_of_store_never_loses_the_stored_program() {
    let old = old_program();
    let new = filled(&old);
    let eeprom = stored(&old);

    // How long STORE takes on this image, from the CR to its message.
    let mut nano = start_store(eeprom);
    let c0 = nano.cycles();
    assert!(nano.wait_for("stored in EEPROM", 5000), "STORE finished");
    let duration = nano.cycles() - c0;
    assert_eq!(stored_program(&nano.eeprom()).as_ref(), Some(&new));

    // Reset at 24 points spread over STORE, then power-cycle and look at what LOAD gets.
    let (mut saw_old, mut saw_new) = (0, 0);
    for k in 0..24u64 {
        let mut nano = start_store(eeprom);
        nano.run_cycles(duration * k / 24);
        nano.power_cycle();
        nano.run_ms(50);
        match stored_program(&nano.eeprom()) {
            Some(p) if p == old => saw_old += 1,
            Some(p) if p == new => saw_new += 1,
            other => panic!("reset {k}/24 into STORE left {other:?}"),
        }
        // And the firmware's own LOAD finds a program.
        assert!(nano.wait_for("*** User File 0 ***", 2000));
        nano.enter("LOAD", 400);
        assert!(
            contains(&nano.take_output(), b"loaded from EEPROM"),
            "reset {k}/24"
        );
    }
    // The points really fell before and after the moment the new copy became valid.
    assert!(saw_old > 0 && saw_new > 0, "old {saw_old}, new {saw_new}");
}

#[test]
fn flipped_bytes_in_the_newest_slot_fall_back_to_the_other() {
    let old = old_program();
    let new = filled(&old);
    let mut nano = start_store(stored(&old));
    assert!(nano.wait_for("stored in EEPROM", 5000));
    let mut bytes = nano.eeprom();
    // The newest slot is the one holding `new`: damage one of its UF bytes.
    let (addr, _) = {
        let mut board = SimBoard::new();
        board.eeprom = bytes.clone();
        store::newest_slot(&mut board).expect("a valid slot")
    };
    let victim = usize::from(addr) + usize::from(store::SEQ_LEN) + image::UF_OFFSET + 10;
    bytes[victim] ^= 0x5A;
    nano.set_eeprom(0, &bytes);
    nano.enter("LOAD", 400);
    assert!(contains(&nano.take_output(), b"loaded from EEPROM"));
    // WRITE shows what is in RAM now: the old program.
    let expected = hex_of(&old);
    let out = write_file(&mut nano);
    assert!(
        contains(&out, &expected),
        "LOAD took the intact older copy:\n{}\nexpected\n{}",
        String::from_utf8_lossy(&out),
        String::from_utf8_lossy(&expected)
    );
    // The damaged newer copy (FILL's program) was not taken.
    assert!(!contains(&out, &hex_of(&new)));
}

/// Static data (up to the stack paint) plus the deepest stack since boot.
fn ram_in_use(nano: &Board) -> (u16, u16) {
    let mut end = RAMSTART;
    while !(0..16).all(|i| nano.ram(end + i) == STACK_PAINT) {
        end += 1;
    }
    (end - RAMSTART, nano.stack_high_water())
}

#[test]
fn the_deepest_editor_paths_stay_within_the_ram_budget() {
    // A program with every assigned opcode once (KEY last but one, then END), via READ.
    let mut prog = Program::blank();
    let ops: Vec<u8> = (0..=255u8)
        .filter(|&op| opcodes::is_valid(op) && op != opcodes::END && op != opcodes::KEY)
        .collect();
    prog.uf[..ops.len()].copy_from_slice(&ops);
    prog.uf[ops.len()] = opcodes::KEY;
    prog.uf[ops.len() + 1] = opcodes::END;
    prog.presets = [3; 16];
    let file = hex_of(&prog);

    let mut nano = Board::boot();
    assert!(nano.wait_for("*** User File 0 ***", 2000));
    nano.enter("?", 800);
    nano.type_bytes(b" ");
    nano.drain_typed();
    nano.run_ms(800);
    nano.enter("ldt", 800);
    nano.enter("300", 100);
    nano.type_bytes(b"\x1b[C");
    nano.enter("Z", 300);
    nano.enter("", 800);
    read_file(&mut nano, &file);
    for cmd in ["LIST", "WRITE"] {
        nano.enter(cmd, 300);
        nano.enter("", 3000);
        nano.enter("", 800);
    }
    nano.enter("STORE", 1500);
    nano.enter("LOAD", 800);
    nano.type_bytes(b"\x1b[2~\x1b[3~\x1b[C\x1b[D99999\r\x1b[H");
    nano.drain_typed();
    nano.run_ms(800);
    nano.enter("EX0", 1000);
    nano.type_bytes(b"/");
    nano.drain_typed();
    nano.run_ms(300);
    nano.type_bytes(b" ");
    nano.drain_typed();
    nano.run_ms(800);
    nano.enter("STAT", 300);
    assert!(
        contains(&nano.take_output(), b"scans/s"),
        "the run happened"
    );
    let (statics, stack) = ram_in_use(&nano);
    println!("RAM after the deep paths: static {statics} + stack {stack} bytes");
    assert!(
        statics + stack <= 1536,
        "SPEC §11: {} bytes",
        statics + stack
    );
}

#[test]
fn ten_minutes_of_input_and_uart_noise_change_nothing_and_hang_nothing() {
    // Y0 follows A0, Y1 follows A1; KEY is reachable.
    let mut prog = Program::blank();
    for (line, word) in ["A0.", ".Y0", "A1.", ".Y1", "KEY", "END"]
        .iter()
        .enumerate()
    {
        prog.uf[line] = opcodes::lookup(word.as_bytes()).expect("a command");
    }
    prog.presets = [7; 16];
    let file = hex_of(&prog);

    let mut nano = Board::boot();
    assert!(nano.wait_for("*** User File 0 ***", 2000));
    read_file(&mut nano, &file);
    nano.enter("EX0", 500);

    let mut noise = Rng(0x2545_F491);
    let mut switches = [false; 6];
    // 10 simulated minutes in 100 ms steps: switches change at random, and the UART gets
    // random bytes at the full rate simavr's UART takes (170 per step) except `/`, which would stop
    // the program by design. Every 10 s the outputs are checked against the inputs.
    for step in 0..6000u32 {
        // simavr's UART takes a byte every 11 bit times: about 174 bytes per 100 ms.
        let burst: Vec<u8> = (0..170)
            .map(|_| (noise.next_u32() >> 7) as u8)
            .filter(|&c| c != b'/')
            .collect();
        nano.type_bytes(&burst);
        if noise.next_u32().is_multiple_of(4) {
            let n = (noise.next_u32() % 6) as u8;
            switches[usize::from(n)] ^= true;
            nano.switch(n, switches[usize::from(n)]);
        }
        nano.run_ms(100);
        if step % 100 == 99 {
            let y = nano.outputs();
            assert_eq!(
                y & 1 != 0,
                !switches[0],
                "Y0 follows A0 at {} s",
                (step + 1) / 10
            );
            assert_eq!(
                y & 2 != 0,
                !switches[1],
                "Y1 follows A1 at {} s",
                (step + 1) / 10
            );
        }
    }
    // Still running and still listening: `/` stops it.
    nano.drain_typed();
    nano.run_ms(50);
    nano.take_output();
    nano.type_bytes(b"/");
    nano.drain_typed();
    assert!(nano.wait_for("Strike any key", 500), "KEY still breaks out");
    nano.type_bytes(b" ");
    nano.drain_typed();
    nano.run_ms(800);
    // The program and presets are unchanged: WRITE sends the very file READ took.
    assert!(
        contains(&write_file(&mut nano), &file),
        "UF and presets unchanged"
    );
    nano.enter("", 800);
    nano.enter("STAT", 300);
    let out = nano.take_output();
    assert!(
        contains(&out, b"rx overruns "),
        "STAT reports receive overruns"
    );
}

#[test]
fn write_read_store_power_cycle_load_write_is_bit_exact() {
    let prog = old_program();
    let file = hex_of(&prog);
    let mut nano = Board::boot();
    assert!(nano.wait_for("*** User File 0 ***", 2000));
    read_file(&mut nano, &file);
    nano.enter("STORE", 1500);
    assert!(contains(&nano.take_output(), b"stored in EEPROM"));
    nano.power_cycle();
    assert!(nano.wait_for("*** User File 0 ***", 2000));
    nano.run_ms(300);
    // A power-on starts blank; LOAD brings the program back.
    assert!(nano.screen().contains("000 ....."), "{}", nano.screen());
    nano.enter("LOAD", 800);
    assert!(contains(&nano.take_output(), b"loaded from EEPROM"));
    assert!(
        contains(&write_file(&mut nano), &file),
        "the same file, byte for byte"
    );
}
