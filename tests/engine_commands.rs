//! Every executable command: its effect on the bit stack and on the ports (SPEC §4).

mod support;
use support::scenario::*;
use utile_core::board::Board;
use utile_core::engine::{Engine, Flow, LINES};
use utile_core::opcodes::{self, lookup, BLANK, END, NOP};
use utile_kit::sim::SimBoard;

fn op(name: &str) -> u8 {
    lookup(name.as_bytes()).unwrap_or_else(|| panic!("{name}"))
}

/// Run `name` on a fresh engine with bit stack `bs`; returns the engine.
fn run1(name: &str, bs: u8) -> (Engine, SimBoard) {
    let mut b = SimBoard::new();
    let mut e = Engine::default();
    e.bs = bs;
    assert_eq!(e.exec(op(name), &mut b), Flow::Next, "{name}");
    (e, b)
}

fn bs_after(name: &str, bs: u8) -> u8 {
    run1(name, bs).0.bs
}

/// Push b: shift toward bit 7 (bit 7 lost), b into bit 0.
fn push(bs: u8, b: bool) -> u8 {
    (bs << 1) | u8::from(b)
}
/// Pop: bit 0 out, shift toward bit 0, 0 into bit 7.
fn pop(bs: u8) -> (bool, u8) {
    (bs & 1 != 0, bs >> 1)
}

#[test]
fn push_and_pop_follow_the_manual() {
    // SET/CLR push; bit 7 is lost; DROP pops with 0 entering bit 7.
    assert_eq!(bs_after("SET", 0b1000_0000), 0b0000_0001);
    assert_eq!(bs_after("SET", 0b0100_0001), 0b1000_0011);
    assert_eq!(bs_after("CLR", 0b1111_1111), 0b1111_1110);
    assert_eq!(bs_after("DROP", 0b1111_1111), 0b0111_1111);
    assert_eq!(bs_after("DROP", 0b1000_0001), 0b0100_0000);
    for bs in 0..=255u8 {
        assert_eq!(bs_after("SET", bs), push(bs, true));
        assert_eq!(bs_after("CLR", bs), push(bs, false));
        assert_eq!(bs_after("DUP", bs), push(bs, bs & 1 != 0));
        assert_eq!(bs_after("DROP", bs), pop(bs).1);
    }
}

#[test]
fn logic_truth_tables_pop_two_push_one() {
    for (name, f) in [
        ("AND", (|a, b| a & b) as fn(bool, bool) -> bool),
        ("OR", |a, b| a | b),
        ("XOR", |a, b| a ^ b),
    ] {
        for bs in 0..=255u8 {
            let (x, rest) = pop(bs);
            let (y, rest) = pop(rest);
            assert_eq!(
                bs_after(name, bs),
                push(rest, f(x, y)),
                "{name} on {bs:08b}"
            );
        }
        // The printed truth table rows.
        for (a, b) in [(false, false), (false, true), (true, false), (true, true)] {
            let bs = 0b1010_1000 | u8::from(b) << 1 | u8::from(a);
            assert_eq!(bs_after(name, bs) & 1 != 0, f(a, b));
            assert_eq!(
                bs_after(name, bs) >> 1,
                0b0010_1010,
                "{name}: rest moves up two, 0s enter bit 7"
            );
        }
    }
}

#[test]
fn complements_fills_swap_and_2dup() {
    for bs in 0..=255u8 {
        assert_eq!(bs_after("!", bs), bs ^ 1);
        assert_eq!(bs_after("!!", bs), !bs);
        assert_eq!(bs_after("F.", bs), 0xFF);
        assert_eq!(bs_after("Z.", bs), 0x00);
        assert_eq!(bs_after("NOP", bs), bs);
        let (b0, b1) = (bs & 1, (bs >> 1) & 1);
        assert_eq!(bs_after("SWAP", bs), (bs & 0xFC) | (b0 << 1) | b1);
        // 2DUP: push TOS+1 then TOS.
        assert_eq!(bs_after("2DUP", bs), push(push(bs, b1 != 0), b0 != 0));
    }
    assert_eq!(bs_after("SWAP", 0b1111_0001), 0b1111_0010);
    assert_eq!(bs_after("2DUP", 0b1100_0010), 0b0000_1010);
}

#[test]
fn blank_and_unassigned_bytes_act_as_nop() {
    for code in 0..=255u8 {
        if opcodes::is_valid(code) {
            continue;
        }
        let mut b = SimBoard::new();
        let mut e = Engine::default();
        e.bs = 0x5A;
        e.py = 0x33;
        assert_eq!(e.exec(code, &mut b), Flow::Next);
        assert_eq!(
            (e.bs, e.py, e.pu, e.pv, e.q, e.tq),
            (0x5A, 0x33, 0, 0, 0, 0),
            "{code:#04x}"
        );
        assert!(b.output_log.is_empty());
    }
    assert!(!opcodes::is_valid(BLANK));
}

#[test]
fn byte_commands_load_and_store_without_popping() {
    let mut b = SimBoard::new();
    let mut e = Engine::default();
    b.raw_inputs = 0b0010_1101;
    b.advance_ms(10);
    e.bs = 0xFF;
    e.exec(op("PA."), &mut b);
    assert_eq!(
        e.bs, 0b0010_1101,
        "PA. replaces the stack; bits 6, 7 read 0"
    );
    for (store, load, field) in [(".PY", "PY.", 0), (".PU", "PU.", 1), (".PV", "PV.", 2)] {
        e.bs = 0xA5;
        e.exec(op(store), &mut b);
        assert_eq!(e.bs, 0xA5, "{store} keeps the stack");
        let v = [e.py, e.pu, e.pv][field];
        assert_eq!(v, 0xA5, "{store}");
        e.bs = 0;
        e.exec(op(load), &mut b);
        assert_eq!(e.bs, 0xA5, "{load}");
        e.bs = 0x3C;
        e.exec(op(store), &mut b);
    }
    assert_eq!((e.py, e.pu, e.pv), (0x3C, 0x3C, 0x3C));
}

#[test]
fn port_and_stack_display_requests() {
    let mut b = SimBoard::new();
    let mut e = Engine::default();
    b.raw_inputs = 0x15;
    b.advance_ms(10);
    e.py = 1;
    e.pu = 2;
    e.pv = 3;
    e.bs = 0x81;
    for (name, want) in [("PPA", 0x15), ("PPY", 1), ("PPU", 2), ("PPV", 3)] {
        e.exec(op(name), &mut b);
        assert_eq!(e.port_view(), Some(want), "{name}");
        assert_eq!(e.bs, 0x81, "{name} leaves the stack");
    }
    e.exec(op("PBS"), &mut b);
    assert_eq!(e.bs_view(), Some(0x81));
    assert!(
        b.tx_log.is_empty(),
        "the engine never writes to the UART itself"
    );
}

#[test]
fn bit_reads_and_writes_of_every_port() {
    let mut b = SimBoard::new();
    let mut e = Engine::default();
    for n in 0..8u8 {
        for (w, r) in [(".Y", "Y"), (".U", "U"), (".V", "V")] {
            let (wn, rn) = (format!("{w}{n}"), format!("{r}{n}."));
            e.bs = 0b11;
            e.exec(op(&wn), &mut b);
            assert_eq!(e.bs, 0b01, "{wn} pops");
            e.exec(op(&rn), &mut b);
            assert_eq!(e.bs, 0b11, "{rn} pushes the bit back");
            e.bs = 0b10;
            e.exec(op(&wn), &mut b);
            e.exec(op(&rn), &mut b);
            assert_eq!(e.bs, 0b10, "{wn} then {rn} with 0");
        }
        // Writing bit n touches only bit n.
        e.py = 0;
        e.bs = 1;
        e.exec(op(&format!(".Y{n}")), &mut b);
        assert_eq!(e.py, 1 << n);
    }
    e.pu = 0b0100_0000;
    e.bs = 0;
    e.exec(op("U6."), &mut b);
    e.exec(op("U5."), &mut b);
    assert_eq!(e.bs, 0b10);
}

#[test]
fn input_bits_levels_edges_and_toggles() {
    let mut b = SimBoard::new();
    let mut e = Engine::default();
    let bit = |e: &mut Engine, b: &mut SimBoard, name: &str| {
        e.bs = 0;
        e.exec(op(name), b);
        e.bs & 1 != 0
    };
    for n in 0..6u8 {
        assert!(bit(&mut e, &mut b, &format!("A{n}.")), "open input reads 1");
        b.press(n);
        b.advance_ms(10);
        assert!(!bit(&mut e, &mut b, &format!("A{n}.")));
        assert!(
            bit(&mut e, &mut b, &format!("AT{n}.")),
            "trailing edge on press"
        );
        assert!(!bit(&mut e, &mut b, &format!("AT{n}.")), "read clears it");
        assert!(!bit(&mut e, &mut b, &format!("AL{n}.")));
        assert!(!bit(&mut e, &mut b, &format!("AD{n}.")));
        b.release(n);
        b.advance_ms(10);
        b.advance_ms(1000);
        assert!(
            bit(&mut e, &mut b, &format!("AL{n}.")),
            "leading edge kept until read"
        );
        assert!(!bit(&mut e, &mut b, &format!("AL{n}.")));
        assert!(
            bit(&mut e, &mut b, &format!("AD{n}.")),
            "toggle on the leading edge"
        );
        assert!(
            bit(&mut e, &mut b, &format!("AD{n}.")),
            "AD is not cleared by reading"
        );
    }
    // Only the addressed input's edge bit is consumed.
    b.press(0);
    b.press(1);
    b.advance_ms(10);
    assert!(bit(&mut e, &mut b, "AT1."));
    assert!(bit(&mut e, &mut b, "AT0."));
}

#[test]
fn flip_flops_update_only_at_end_and_reset_wins_in_both_orders() {
    let mut b = SimBoard::new();
    for order in [[".S3", ".R3"], [".R3", ".S3"]] {
        let mut e = Engine::default();
        // Set only.
        for (s, r, q_before, q_after) in [
            (true, false, false, true),
            (false, false, true, true), // no change
            (true, true, true, false),  // both: reset wins
            (true, false, false, true),
            (false, true, true, false),
            (false, false, false, false),
        ] {
            for name in order {
                e.bs = u8::from(if name == ".S3" { s } else { r });
                e.exec(op(name), &mut b);
            }
            e.bs = 0;
            e.exec(op("Q3."), &mut b);
            assert_eq!(
                e.bs & 1 != 0,
                q_before,
                "{order:?} s={s} r={r}: Q before END"
            );
            e.exec(END, &mut b);
            e.exec(op("Q3."), &mut b);
            assert_eq!(e.bs & 1 != 0, q_after, "{order:?} s={s} r={r}: Q after END");
            assert_eq!(e.q & !(1 << 3), 0, "other flip-flops untouched");
        }
    }
}

#[test]
fn set_and_reset_latches_are_levels_that_persist() {
    let mut b = SimBoard::new();
    let mut e = Engine::default();
    e.bs = 1;
    e.exec(op(".SF"), &mut b);
    e.exec(END, &mut b);
    e.q = 0; // something else cleared Q: the persisting S sets it again at the next END
    e.exec(END, &mut b);
    assert_eq!(e.q, 1 << 15);
    e.bs = 1;
    e.exec(op(".RF"), &mut b);
    for _ in 0..3 {
        e.exec(END, &mut b);
        assert_eq!(e.q, 0, "R stays 1 until overwritten");
    }
    e.bs = 0;
    e.exec(op(".RF"), &mut b);
    e.exec(END, &mut b);
    assert_eq!(e.q, 1 << 15, "S still 1");
}

#[test]
fn clocks_push_square_waves_of_0_4_1_2_and_3_6_s() {
    let mut r = Run::start(
        program(&["CLKA.", ".Y0", "CLKB.", ".Y1", "CLKC.", ".Y2", "END"]),
        0x3F,
    );
    r.wait(7_201);
    for (n, period) in [(0u8, 400u32), (1, 1200), (2, 3600)] {
        let ch = r.changes(n);
        assert_eq!(ch.first(), Some(&(period / 2, true)), "Y{n}");
        assert!(ch
            .windows(2)
            .all(|w| w[1].0 - w[0].0 == period / 2 && w[1].1 != w[0].1));
        assert_eq!(ch.len() as u32, 7200 / (period / 2));
    }
}

#[test]
fn end_writes_the_outputs_once_per_scan_not_mid_scan() {
    let mut b = SimBoard::new();
    let mut e = Engine::new(program(&["SET", ".Y0", "CLR", ".Y0", "SET", ".Y1", "END"]));
    e.scan(&mut b);
    e.scan(&mut b);
    // Y0 went 1 then 0 inside the scan: the pins only ever saw Y1.
    assert_eq!(b.output_log, vec![(0, 0b10)]);
}

#[test]
fn running_past_line_255_acts_as_end() {
    let mut b = SimBoard::new();
    let mut p = program(&[]);
    p.uf = [NOP; LINES];
    p.uf[255] = op(".Y4"); // last line pops a 1 (pushed on line 0)
    p.uf[0] = op("SET");
    let mut e = Engine::new(p);
    assert_eq!(e.scan(&mut b), Flow::End);
    assert_eq!(b.outputs, 0x10, "outputs written at the implied END");
    e.bs = 1;
    e.exec(op(".S0"), &mut b);
    e.scan(&mut b);
    assert_eq!(e.q, 1, "flip-flops updated at the implied END");
    // A never-programmed UF (all blank) scans as NOPs + END.
    let mut blank = Engine::default();
    blank.bs = 0x42;
    assert_eq!(blank.scan(&mut b), Flow::End);
    assert_eq!(blank.bs, 0x42);
}

#[test]
fn end_stops_the_scan_and_later_lines_do_not_run() {
    let mut b = SimBoard::new();
    let mut e = Engine::new(program(&["SET", ".Y0", "END", "SET", ".Y1"]));
    e.scan(&mut b);
    assert_eq!(b.outputs, 1);
}

#[test]
fn key_breaks_only_on_slash_and_discards_other_characters() {
    let mut b = SimBoard::new();
    let mut e = Engine::new(program(&["KEY", "SET", ".Y0", "END"]));
    b.type_bytes(b"ab");
    assert_eq!(e.scan(&mut b), Flow::End);
    assert_eq!(e.scan(&mut b), Flow::End);
    assert!(b.rx_queue.is_empty(), "other characters are discarded");
    b.type_bytes(b"/x");
    assert_eq!(e.scan(&mut b), Flow::Break);
    assert_eq!(b.rx_queue.len(), 1, "KEY reads one character per execution");
    assert_eq!(b.rx(), Some(b'x'));
}

#[test]
fn ex0_clears_runtime_state_but_keeps_the_program_and_presets() {
    let mut b = SimBoard::new();
    let mut p = program(&["SET", ".TK4", "END"]);
    p.presets[4] = 9;
    let mut e = Engine::new(p.clone());
    e.scan(&mut b);
    e.bs = 0xAA;
    e.py = 1;
    e.pu = 2;
    e.pv = 3;
    e.set = 4;
    e.reset = 5;
    e.q = 6;
    e.request_port_view(1);
    e.request_bs_view(2);
    b.press(0);
    b.advance_ms(10);
    e.clear_runtime(&mut b);
    assert_eq!(
        (e.bs, e.py, e.pu, e.pv, e.set, e.reset, e.q, e.tq),
        (0, 0, 0, 0, 0, 0, 0, 0)
    );
    assert_eq!((e.port_view(), e.bs_view()), (None, None));
    assert_eq!(e.prog, p);
    assert_eq!(b.outputs, 0, "outputs driven off");
    assert!(!b.take_trailing(1), "no edge left over");
}
