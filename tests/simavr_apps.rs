//! The application programs of manual ch. 11 on the REAL firmware image in simavr (issue 3):
//! each program is put into the chip the way a user would, started with EX0, fed an input
//! timeline on the pins A0..A5 (a pressed push-button pulls its pin low) and its output pins
//! Y0..Y7 (PD2..PD7, PB4, PB5) are checked over time against the manual's description (the
//! same expectations as the host scenarios in `tests/scenarios_apps.rs`).
//!
//! Two ways in:
//! - typed through the editor, one command + CR at a time after FILL, presets with LDT
//!   (push-button timer, continuous timers, intrusion alarm); WRITE then sends the image back
//!   and it must equal the listing, so the typing path is checked as well as the behaviour;
//! - through READ, the hex image as `utile asm` would write it (the other programs).
//!
//! Time: `t` counts ms from the program start. The chip's 1 ms tick runs from boot (Timer0
//! start, found by watching TCCR0B), so EX0 falls in tick interval `k`; chip time `t` is the
//! interval between ticks `k + t` and `k + t + 1`, and the free-running clocks CLKA/B/C are
//! at their phase for `k + t` (the host scenarios start them at 0 with the program). Inputs
//! change a quarter of a millisecond into their interval, as a real switch lands at some
//! random point between two samples.
//!
//! Needs `out/m328-nano-utile.elf` (`cargo fw`). About 90 s of simulated time in all.

mod support;

use support::chip::{Board, Rig, CYCLES_PER_MS};
use support::scenario::{changes, clock, listing, parse_timeline, Act, DEBOUNCE_MS};
use utile_core::engine::Program;
use utile_core::ihex::{HexEvent, HexReader};
use utile_core::image;
use utile_core::opcodes::{self, END};

const D: u32 = DEBOUNCE_MS;
/// TCCR0B in the data space: Timer0's clock select, written once at boot.
const TCCR0B: u16 = 0x45;
/// How often the pins are looked at: 1/16 ms.
const STEP: u64 = CYCLES_PER_MS / 16;

/// The real image running one program.
struct Chip {
    nano: Board,
    /// Cycle at which the 1 ms tick started (tick 0).
    epoch: u64,
    /// Tick interval in which EX0 started the program.
    k: u32,
    /// Cycle of tick `k`: chip time 0.
    origin: u64,
    /// Output changes: (ms from the program start, Y image).
    log: Vec<(u32, u8)>,
}

impl Chip {
    /// Power up and wait for the editor's page.
    fn boot() -> Chip {
        let mut nano = Board::load(Rig::default());
        while nano.data(TCCR0B) == 0 {
            nano.step();
            assert!(nano.cycles() < 50 * CYCLES_PER_MS, "Timer0 never started");
        }
        let epoch = nano.cycles();
        assert!(nano.wait_for("*** User File 0 ***", 2_000), "no page");
        nano.take_output();
        Chip {
            nano,
            epoch,
            k: 0,
            origin: 0,
            log: Vec::new(),
        }
    }

    /// Type a line and CR, then wait until the firmware has answered and gone quiet.
    fn line(&mut self, text: &str) {
        self.nano.take_output();
        self.nano.enter(text, 0);
        let mut quiet = 0;
        for _ in 0..3_000 {
            self.nano.run_ms(1);
            if self.nano.take_output().is_empty() {
                quiet += 1;
                if quiet >= 5 {
                    return;
                }
            } else {
                quiet = 0;
            }
        }
        panic!("the firmware keeps talking after {text:?}");
    }

    /// Type the program in: FILL, every command up to END, the presets with LDT.
    fn type_in(&mut self, prog: &Program) {
        self.line("fill");
        for &op in prog.uf.iter() {
            let name = opcodes::name(op).expect("a named command");
            self.line(name.as_str());
            if op == END {
                break;
            }
        }
        let last = prog.presets.iter().rposition(|&v| v != 0);
        if let Some(last) = last {
            self.line("ldt");
            for v in &prog.presets[..=last] {
                self.line(&v.to_string());
            }
            self.line("");
        }
    }

    /// Load the program through READ, as `utile asm` writes it.
    fn read(&mut self, prog: &Program) {
        let mut hex = Vec::new();
        utile_core::ihex::write_hex(&image::encode(prog), &mut |b| hex.push(b));
        self.nano.enter("READ", 0);
        assert!(self.nano.wait_for("Reading file", 1_000));
        self.nano.type_bytes(&hex);
        assert!(self.nano.wait_for("File read completed", 10_000));
        self.nano.take_output();
        self.nano.enter("", 0);
        assert!(self.nano.wait_for("*** User File 0 ***", 1_000));
    }

    /// The program in the chip's RAM, as WRITE sends it.
    fn write(&mut self) -> Program {
        self.line("WRITE");
        self.nano.enter("", 0);
        assert!(
            self.nano.wait_for(":00000001FF", 5_000),
            "WRITE sent no file"
        );
        let out = self.nano.take_output();
        let start = out.iter().position(|&b| b == b':').expect("a record");
        let mut reader = HexReader::new();
        for &b in &out[start..] {
            match reader.feed(b) {
                HexEvent::More => {}
                HexEvent::Done { len } => {
                    let data = &reader.data()[..usize::from(len)];
                    self.line("");
                    return image::decode(data).expect("WRITE's image decodes");
                }
                HexEvent::Error(e) => panic!("WRITE's hex: {e:?}"),
            }
        }
        panic!("WRITE's file has no end record");
    }

    /// Set the input pins to `raw` (bit n = An high), then EX0; chip time 0 is the tick
    /// interval in which the program started.
    fn start(&mut self, raw: u8) {
        for n in 0..6 {
            self.nano.switch(n, raw & (1 << n) == 0);
        }
        self.nano.run_ms(20);
        self.nano.type_bytes(b"EX0");
        self.nano.drain_typed();
        self.nano.run_ms(5);
        self.nano.take_output();
        self.nano.type_bytes(b"\r");
        let limit = self.nano.cycles() + 20 * CYCLES_PER_MS;
        while self.nano.take_output().is_empty() {
            assert!(self.nano.cycles() < limit, "no answer to EX0");
            self.nano.run_cycles(64);
        }
        self.k = ((self.nano.cycles() - self.epoch) / CYCLES_PER_MS) as u32;
        self.origin = self.epoch + u64::from(self.k) * CYCLES_PER_MS;
        self.log = vec![(0, self.nano.outputs())];
    }

    /// Chip time now, in whole ms.
    fn now(&self) -> u32 {
        ((self.nano.cycles() - self.origin) / CYCLES_PER_MS) as u32
    }

    /// Run until chip time `until`, applying the timeline's actions at their times.
    fn run(&mut self, timeline: &[(u32, Act)], until: u32) {
        let from = self.now();
        let mut next = timeline.iter().filter(|a| a.0 >= from).peekable();
        let end = self.origin + u64::from(until) * CYCLES_PER_MS;
        let origin = self.origin;
        let at = |t: u32| origin + u64::from(t) * CYCLES_PER_MS + CYCLES_PER_MS / 4;
        while self.nano.cycles() < end {
            let now = self.nano.cycles();
            while let Some(&(_, act)) = next.next_if(|a| at(a.0) <= now) {
                match act {
                    Act::Press(n) => self.nano.switch(n, true),
                    Act::Release(n) => self.nano.switch(n, false),
                }
            }
            self.nano.run_cycles(STEP);
            self.nano.take_output();
            let y = self.nano.outputs();
            if self.log.last().map(|l| l.1) != Some(y) {
                let t = self.now();
                self.log.push((t, y));
            }
        }
    }

    /// Changes of output `n`: (ms, level).
    fn changes(&self, n: u8) -> Vec<(u32, bool)> {
        changes(&self.log, n)
    }

    fn changes_in(&self, n: u8, from: u32, to: u32) -> Vec<(u32, bool)> {
        self.changes(n)
            .into_iter()
            .filter(|&(t, _)| t >= from && t < to)
            .collect()
    }

    /// Output `n` during ms `t`.
    fn y_at(&self, n: u8, t: u32) -> bool {
        self.log
            .iter()
            .take_while(|&&(at, _)| at <= t)
            .last()
            .is_some_and(|&(_, v)| v & (1 << n) != 0)
    }

    /// A clock with half-period `half` at chip time `t` (running since boot).
    fn clk(&self, t: u32, half: u32) -> bool {
        clock(self.k + t, half)
    }
}

#[track_caller]
fn expect_changes(chip: &Chip, n: u8, expected: &[(u32, bool)], tol: u32) {
    let got = chip.changes(n);
    let ok = got.len() == expected.len()
        && got
            .iter()
            .zip(expected)
            .all(|(&(gt, gl), &(et, el))| gl == el && gt.abs_diff(et) <= tol);
    assert!(
        ok,
        "Y{n}: changes {got:?}, expected {expected:?} (±{tol} ms)"
    );
}

/// Output `n` equals `model(t)` at every ms of `[from, to)` not within `slack` ms of a change
/// of the model.
#[track_caller]
fn expect_model(chip: &Chip, n: u8, from: u32, to: u32, slack: u32, model: impl Fn(u32) -> bool) {
    let mut checked = 0;
    for t in from..to {
        let want = model(t);
        if (t.saturating_sub(slack)..=t + slack).any(|u| model(u) != want) {
            continue;
        }
        assert_eq!(
            chip.y_at(n, t),
            want,
            "Y{n} at {t} ms: {:?}",
            chip.changes(n)
        );
        checked += 1;
    }
    assert!(checked > 0, "Y{n}: nothing checked");
}

/// Boot, type the program in, check it with WRITE.
fn typed(name: &str) -> (Chip, Program) {
    let prog = listing(name);
    let mut chip = Chip::boot();
    chip.type_in(&prog);
    assert_eq!(chip.write(), prog, "{name}: the typed program differs");
    (chip, prog)
}

/// Boot and READ the program.
fn read(name: &str) -> Chip {
    let mut chip = Chip::boot();
    chip.read(&listing(name));
    chip
}

// ---------------------------------------------------------------------------------------

#[test]
fn pushbutton_timer_typed_in_runs_5_s_and_stops_early_on_a_second_press() {
    let (mut chip, _) = typed("app_11_1_pushbutton_timer");
    chip.start(0x3F);
    let tl = parse_timeline(
        "100: press A0; 200: release A0
         2000: press A0; 2100: release A0
         7000: press A0; 7100: release A0",
    );
    chip.run(&tl, 12_300);
    expect_changes(
        &chip,
        0,
        &[
            (200 + D, true),
            (2100 + D, false),
            (7100 + D, true),
            (7100 + D + 5000, false),
        ],
        2,
    );
    assert!(chip.log.iter().all(|&(_, y)| y & !1 == 0), "only Y0");
}

#[test]
fn n_switches_read_in_each_switch_changes_the_output() {
    let mut chip = read("app_11_2_n_switches");
    chip.start(0x3F);
    let tl = parse_timeline(
        "100: low A0; 300: low A2; 500: low A3; 700: high A0; 900: low A1; 1100: high A3;
         1300: high A2; 1500: high A1",
    );
    chip.run(&tl, 1700);
    let expected: Vec<(u32, bool)> = [100, 300, 500, 700, 900, 1100, 1300, 1500]
        .iter()
        .enumerate()
        .map(|(i, &t)| (t + D, i % 2 == 0))
        .collect();
    expect_changes(&chip, 0, &expected, 2);
}

#[test]
fn pushbutton_lighting_read_in_toggles_and_flashes_the_locator() {
    let mut chip = read("app_11_3_pushbutton_lighting");
    chip.start(0x3F);
    let tl = parse_timeline("2000: press A0; 2100: release A0; 5000: press A0; 5150: release A0");
    chip.run(&tl, 8_000);
    let (on, off) = (2100 + D, 5150 + D);
    expect_changes(&chip, 0, &[(on, true), (off, false)], 2);
    let light = |t: u32| (on..off).contains(&t);
    expect_model(&chip, 3, 3, 8_000, 2, |t| light(t) || chip.clk(t, 600));
    assert!(
        chip.changes_in(3, on + 2, off).is_empty(),
        "steady while on"
    );
    assert!(chip.changes_in(3, 0, on).len() >= 3, "flashes while off");
}

#[test]
fn continuous_timers_typed_in_give_a_steady_pulse_train() {
    let (mut chip, _) = typed("app_continuous_timers");
    chip.start(0x3F);
    chip.run(&[], 4_050);
    let ch = chip.changes(0);
    let rises: Vec<u32> = ch.iter().filter(|c| c.1).map(|c| c.0).collect();
    let falls: Vec<u32> = ch.iter().filter(|c| !c.1).map(|c| c.0).collect();
    // Period T0 = 0.4 s, pulse T1 = 0.1 s, from the start.
    assert_eq!(rises.len(), 11, "{ch:?}");
    for (k, &t) in rises.iter().enumerate() {
        assert!(t.abs_diff(400 * k as u32) <= 10, "pulse {k} at {t}: {ch:?}");
    }
    for (&up, &down) in rises.iter().zip(&falls) {
        assert!((down - up).abs_diff(100) <= 10, "pulse {up}..{down}");
    }
}

#[test]
fn intrusion_alarm_typed_in_arms_holds_off_sounds_and_resets() {
    let (mut chip, prog) = typed("app_intrusion_alarm");
    assert_eq!(&prog.presets[..3], &[5, 3, 30]);
    let unit = 100;
    let (arm_delay, holdoff, alarm) = (5 * unit, 3 * unit, 30 * unit);
    chip.start(0x3F);
    let mut tl = parse_timeline("500: press A3; 560: release A3; 1000: press A0; 1200: release A0");
    let armed = 1200 + D + arm_delay;
    let intr = armed + 1000;
    tl.push((intr, Act::Press(3)));
    tl.push((intr + 50, Act::Release(3)));
    let intr_rel = intr + 50 + D;
    let (holdoff_end, alarm_end) = (intr_rel + holdoff, intr_rel + alarm);
    let reset = alarm_end + 1000;
    tl.push((reset, Act::Press(1)));
    tl.push((reset + 100, Act::Release(1)));
    let end = reset + 2000;
    chip.run(&tl, end);

    let arming = |t: u32| t >= 1000 + D && t < armed;
    let armed_at = |t: u32| t >= 1000 + D && t < reset + D;
    let clka = |t: u32| chip.clk(t, 200);
    let clkb = |t: u32| chip.clk(t, 600);
    let clkc = |t: u32| chip.clk(t, 1800);
    expect_model(&chip, 0, 3, end, 2, |t| {
        armed_at(t) && !(arming(t) && clkb(t))
    });
    expect_model(&chip, 1, 3, end, 2, |t| {
        (intr + D..holdoff_end).contains(&t) && clkb(t)
    });
    assert!(chip.changes_in(1, 0, intr).is_empty(), "no hold-off before");
    expect_model(&chip, 3, 3, end, 2, |t| {
        (holdoff_end..alarm_end).contains(&t) && clka(t) && clkc(t)
    });
    assert!(
        !chip.changes_in(3, holdoff_end, alarm_end).is_empty(),
        "the alarm sounded"
    );
    assert!(chip.y_at(0, alarm_end + 500) && !chip.y_at(0, reset + D + 2));
}

#[test]
fn motor_starter_read_in_starts_stops_and_locks_out_after_an_overload() {
    // The listing adapted to pulled-up inputs: the buttons pull low when pressed; the O/L
    // contact is closed (low) in normal running and opens (high) when it trips.
    let mut chip = read("app_motor_start_stop_pullup");
    chip.start(0x3F & !(1 << 3));
    let tl = parse_timeline(
        "1000: press A0; 1100: release A0      # start
         2000: press A1; 2100: release A1      # stop
         3000: press A0; 3100: release A0      # start
         4000: high A3                         # O/L trips while running
         5000: low A3                          # O/L clears: still locked out
         6000: press A0; 6100: release A0      # start refused
         7000: high A3                         # trip while stopped
         7500: press A0; 7600: release A0      # refused
         8000: press A1; 8100: release A1      # stop with the O/L still tripped
         8500: low A3                          # O/L clears
         9000: press A1; 9100: release A1      # stop resets the lock-out
         10000: press A0; 10100: release A0    # start works again",
    );
    chip.run(&tl, 11_000);
    let run = [
        (1000 + D, true),
        (2000 + D, false),
        (3000 + D, true),
        (4000 + D, false),
        (10000 + D, true),
    ];
    expect_changes(&chip, 3, &run, 2);
    expect_changes(&chip, 0, &run, 2);
    expect_changes(
        &chip,
        1,
        &[
            (4000 + D, true),
            (8000 + D, false),
            (8100 + D, true),
            (9000 + D, false),
        ],
        2,
    );
}

#[test]
fn sump_pump_read_in_alternates_and_the_high_high_alarm_starts_the_other_pump() {
    let mut chip = read("app_sump_pump");
    // Sump below the low level: LSL (A1) active (low).
    chip.start(0x3F & !(1 << 1));
    // Level 0 below LSL, 1 between, 2 above LSH (A0), 3 above LSHH (A2).
    let mut tl = Vec::new();
    let mut level = |t: u32, l: u8| {
        let set = |n: u8, active: bool| {
            (
                t,
                if active {
                    Act::Press(n)
                } else {
                    Act::Release(n)
                },
            )
        };
        tl.push(set(1, l == 0));
        tl.push(set(0, l >= 2));
        tl.push(set(2, l >= 3));
    };
    let mut cycles = Vec::new();
    for c in 0..2u32 {
        let t = 500 + 2500 * c;
        level(t, 1);
        level(t + 400, 2);
        level(t + 800, 1);
        level(t + 1600, 0);
        cycles.push((t + 400 + D, t + 1600 + D));
    }
    // The lead pump (pump 1 again) fails: the level reaches LSHH.
    let f = 5_500;
    level(f, 1);
    level(f + 400, 2);
    level(f + 800, 3);
    level(f + 1200, 2);
    level(f + 1600, 1);
    level(f + 2400, 0);
    tl.push((9_000, Act::Press(3)));
    tl.push((9_100, Act::Release(3)));
    tl.sort_by_key(|e| e.0);
    chip.run(&tl, 10_000);

    for (k, &(on, off)) in cycles.iter().enumerate() {
        let (p, other) = if k % 2 == 0 { (0, 1) } else { (1, 0) };
        assert_eq!(
            chip.changes_in(p, on - 300, off + 300),
            vec![(on, true), (off, false)],
            "cycle {k}: pump {p}"
        );
        assert!(
            chip.changes_in(other, on - 300, off + 300).is_empty(),
            "cycle {k}"
        );
    }
    assert!(
        chip.y_at(0, f + 500) && !chip.y_at(1, f + 500),
        "lead pump commanded"
    );
    assert!(
        chip.y_at(0, f + 900) && chip.y_at(1, f + 900),
        "both at LSHH"
    );
    assert!(!chip.y_at(0, f + 2400 + D + 1) && !chip.y_at(1, f + 2400 + D + 1));
    assert!(
        chip.changes_in(3, 0, f + 800).is_empty(),
        "no alarm before LSHH"
    );
    let alarm = |t: u32| (f + 800 + D..9_000 + D).contains(&t);
    expect_model(&chip, 3, 3, 10_000, 2, |t| {
        alarm(t) && chip.clk(t, 200) && chip.clk(t, 1800)
    });
}
