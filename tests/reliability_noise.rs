//! UART noise on the host editor (SPEC §12, issue 8): random bytes at the full 19200 baud
//! (1.92 bytes per simulated ms) for minutes, in the editor and while a program with KEY
//! runs. The harness (`utile_kit::fuzzing::MainLoop`) checks after every byte that the UF and presets
//! changed only through an accepted command and that the screen output stays on 80×24;
//! afterwards a clean FILL must work (no lock-up).

use utile_core::editor::Mode;
use utile_core::engine::Program;
use utile_core::opcodes::{lookup, END, KEY};
use utile_kit::fuzzing::{sample_program, MainLoop};
use utile_kit::rng::Rng;

/// Bytes per second at 19200 baud, 8N1.
const BYTES_PER_S: u32 = 1920;

/// Noise: half uniform bytes, half pieces of what a user types (command words with CR,
/// numbers, escape sequences, hex records), so that it really reaches every screen.
struct Noise {
    rng: Rng,
    slash: bool,
    pending: Vec<u8>,
}

impl Noise {
    fn new(seed: u64, slash: bool) -> Self {
        Self {
            rng: Rng::new(seed),
            slash,
            pending: Vec::new(),
        }
    }

    fn byte(&mut self) -> u8 {
        const WORDS: &[&[u8]] = &[
            b"a0.\r",
            b".y0\r",
            b"set\r",
            b"ins\r",
            b"del\r",
            b"fill\r",
            b"ldt\r",
            b"5\r",
            b"300\r",
            b"z\r",
            b"\r",
            b"?\r",
            b"list\r",
            b"write\r",
            b"read\r",
            b"run\r",
            b"ex0\r",
            b"key\r",
            b"end\r",
            b"store\r",
            b"load\r",
            b"stat\r",
            b"ver\r",
            b"\x1b[A",
            b"\x1b[B",
            b"\x1b[C",
            b"\x1b[2~",
            b"\x1b[3~",
            b"\x1b[1~",
            b"/",
            b":100000007554010002",
            b":00000001FF\r\n",
            b"\x18",
            b"99999\r",
            b"abcdefghij\r",
        ];
        loop {
            let b = match self.pending.pop() {
                Some(b) => b,
                None if self.rng.below(2) == 0 => self.rng.byte(),
                None => {
                    let w = WORDS[self.rng.below(WORDS.len() as u32) as usize];
                    self.pending.extend(w.iter().rev());
                    continue;
                }
            };
            if self.slash || b != b'/' {
                return b;
            }
        }
    }
}

/// Feed `seconds` of noise at the full rate; returns (ms in EDIT, ms in RUN).
fn run_noise(main_loop: &mut MainLoop, noise: &mut Noise, seconds: u32) -> (u32, u32) {
    let (mut edit, mut run) = (0, 0);
    let mut acc = 0u32;
    for _ in 0..seconds * 1000 {
        acc += BYTES_PER_S;
        while acc >= 1000 {
            acc -= 1000;
            let b = noise.byte();
            main_loop.receive(b).unwrap_or_else(|e| panic!("{e}"));
        }
        if main_loop.mode == Mode::Edit {
            edit += 1;
        } else {
            run += 1;
        }
        main_loop.tick().unwrap_or_else(|e| panic!("{e}"));
    }
    (edit, run)
}

/// Whether a scan from line 0 reaches KEY before END.
fn key_before_end(p: &Program) -> bool {
    p.uf.iter()
        .take_while(|&&op| op != END)
        .any(|&op| op == KEY)
}

#[test]
fn five_minutes_of_noise_in_the_editor_lose_nothing_and_typing_works_afterwards() {
    let (mut total_edit, mut total_run, mut resets, mut changed) = (0, 0, 0, 0);
    for seed in 1..=5u64 {
        let mut main_loop = MainLoop::boot(sample_program());
        main_loop.scans_per_ms = 4;
        let mut noise = Noise::new(seed, true);
        // 60 s of noise at the full rate, with a 300 ms pause every 5 s (a READ that noise
        // started drains until 200 ms of silence, by design).
        for second in 0..60 {
            let (edit, run) = run_noise(&mut main_loop, &mut noise, 1);
            total_edit += edit;
            total_run += run;
            if second % 5 == 4 {
                main_loop.run_ms(300).unwrap_or_else(|e| panic!("{e}"));
            }
            if main_loop.mode == Mode::Run && !key_before_end(&main_loop.eng.prog) {
                // Noise typed RUN over a UF whose scan never reaches KEY: that program
                // runs until a reset, which keeps the UF (warm reset).
                resets += 1;
                main_loop = MainLoop::boot(main_loop.eng.prog.clone());
                main_loop.scans_per_ms = 4;
            }
        }
        if main_loop.eng.prog != sample_program() {
            changed += 1;
        }
        match main_loop.recover_and_fill() {
            Ok(true) => {}
            Ok(false) => {
                assert!(
                    !key_before_end(&main_loop.eng.prog),
                    "seed {seed}: '/' did not stop RUN"
                );
                let mut after_reset = MainLoop::boot(main_loop.eng.prog.clone());
                assert_eq!(after_reset.recover_and_fill(), Ok(true), "seed {seed}");
            }
            Err(e) => panic!("seed {seed}: {e}"),
        }
    }
    eprintln!(
        "noise: {total_edit} ms in EDIT, {total_run} ms in RUN, {resets} resets, {changed}/5 programs changed by accepted commands"
    );
    assert!(
        total_edit > 100_000,
        "the noise must mostly reach the editor"
    );
    assert!(changed > 0, "the noise must type some accepted commands");
}

#[test]
fn noise_while_running_is_discarded_and_the_program_keeps_working() {
    let words: [&[u8]; 6] = [b"KEY", b"A0.", b".Y0", b"CLKA.", b".Y7", b"END"];
    let mut prog = Program::blank();
    for (line, w) in prog.uf.iter_mut().zip(words) {
        *line = lookup(w).expect("a command of the manual");
    }
    let mut main_loop = MainLoop::autostart(&prog).expect("autostart");
    main_loop.scans_per_ms = 4;
    let mut rng = Rng::new(7);
    let mut typing = Noise::new(7, false);
    let mut acc = 0u32;
    // Three minutes of noise without '/', A0 switched at random, Y0 must follow it.
    for ms in 0..180_000u32 {
        acc += BYTES_PER_S;
        while acc >= 1000 {
            acc -= 1000;
            let b = typing.byte();
            main_loop.receive(b).unwrap_or_else(|e| panic!("{e}"));
        }
        if rng.below(500) == 0 {
            let high = rng.below(2) == 0;
            main_loop.board.set_input(0, high);
        }
        // The scan of this ms sees the debounced A0 as it is now.
        let a0 = main_loop.board.ticker.inputs.level() & 1 != 0;
        main_loop.tick().unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(main_loop.mode, Mode::Run, "stopped at {ms} ms without '/'");
        assert_eq!(main_loop.board.output(0), a0, "Y0 follows A0 at {ms} ms");
    }
    assert_eq!(
        main_loop.eng.prog, prog,
        "noise while running never changes the UF"
    );
    assert!(main_loop.overruns == 0, "4 scans per ms read every byte");
    // A clean '/' stops it; a key returns to the editor; FILL works.
    assert_eq!(main_loop.recover_and_fill(), Ok(true));
}

#[test]
fn a_full_receive_ring_loses_bytes_but_not_the_editor() {
    // A program without KEY: bytes pile up and the ring overflows; after a reset the
    // editor (a fresh main_loop with the same UF, as a warm reset keeps it) works.
    let mut prog = Program::blank();
    prog.uf[0] = END;
    let mut main_loop = MainLoop::autostart(&prog).expect("autostart");
    run_noise(&mut main_loop, &mut Noise::new(3, true), 2);
    assert_eq!(main_loop.mode, Mode::Run);
    assert!(
        main_loop.overruns > 3000,
        "{} bytes lost",
        main_loop.overruns
    );
    assert_eq!(main_loop.recover_and_fill(), Ok(false));
    let mut after_reset = MainLoop::boot(main_loop.eng.prog.clone());
    assert_eq!(after_reset.recover_and_fill(), Ok(true));
}
