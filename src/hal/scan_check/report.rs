//! The scan check's verdict on the UART: PASS with the coverage counters, or FAIL with the case.

use super::*;

/// Send a text from flash (one function for all the texts, whatever their length).
#[inline(never)]
pub(super) fn tx_flash(text: ProgMem<[u8]>) {
    for b in text.wrapper_iter() {
        serial::tx(b.load());
    }
}

pub(super) fn tx_dec(mut v: u32) {
    let mut digits = [0u8; 10];
    let mut n = 0;
    for d in digits.iter_mut() {
        *d = b'0' + (v % 10) as u8;
        v /= 10;
        n += 1;
        if v == 0 {
            break;
        }
    }
    for &d in digits.iter().take(n).rev() {
        serial::tx(d);
    }
}

pub(super) fn tx_hex(v: u8) {
    for nibble in [v >> 4, v & 0x0F] {
        serial::tx(if nibble < 10 {
            b'0' + nibble
        } else {
            b'A' + nibble - 10
        });
    }
}

pub(super) fn tx_hex_bytes(bytes: &[u8]) {
    for &b in bytes {
        tx_hex(b);
    }
}

/// Print the failing case: the world, the runtime state before, both engines' differing
/// bytes, the edge bits and outputs after, and the program.
pub(super) fn report(
    trial: u16,
    scan: u8,
    w: &World,
    m: &Mismatch,
    eng: &Engine,
    reference: &Engine,
) {
    say!(b"\r\nscan-check FAIL trial ");
    tx_dec(u32::from(trial));
    say!(b" scan ");
    tx_dec(u32::from(scan));
    if m.burst {
        say!(b" (a burst of 16 scans)");
    }
    say!(b"\r\nexit asm ");
    tx_hex(m.exit as u8);
    say!(b" (1 = Scans) core ");
    tx_hex(m.flow as u8);
    say!(b" (1 = End)\r\nworld ms ");
    tx_hex_bytes(&w.ms.to_be_bytes());
    say!(b" level ");
    tx_hex(w.level);
    say!(b" leading ");
    tx_hex(w.leading);
    say!(b" trailing ");
    tx_hex(w.trailing);
    say!(b" toggles ");
    tx_hex(w.toggles);
    say!(b" clocks ");
    tx_hex(w.clocks);
    say!(b" out_py ");
    tx_hex(w.py);
    say!(b" invert ");
    tx_hex(w.invert);
    say!(b"\r\nlayout bs 00 py 01 pu 02 pv 03 set 04 reset 06 q 08 tq 0A swept_ms 0C views 0D port_view 0E bs_view 0F deadline 10 (4 B LE each) cu 50 cu_prev 51 cr 52 cq 53 count 54 (2 B LE each) presets 64 counter_presets 74 set_points 84 uf 88 guard 188");
    say!(b"\r\nbefore ");
    tx_hex_bytes(&m.before);
    say!(b"\r\nasm    ");
    tx_hex_bytes(bytes(eng).get(..RUNTIME).unwrap_or(&[]));
    say!(b"\r\ncore   ");
    tx_hex_bytes(bytes(reference).get(..RUNTIME).unwrap_or(&[]));
    say!(b"\r\ndiff (offset asm core):");
    for (i, (a, c)) in bytes(eng).iter().zip(bytes(reference)).enumerate() {
        if a != c {
            serial::tx(b' ');
            tx_hex((i >> 8) as u8);
            tx_hex(i as u8);
            serial::tx(b'=');
            tx_hex(*a);
            serial::tx(b'/');
            tx_hex(*c);
        }
    }
    say!(b"\r\nafter (leading trailing out_py last_py PORTD PORTB) asm");
    m.asm.send();
    say!(b" core");
    m.core.send();
    say!(b"\r\npresets ");
    tx_hex_bytes(&eng.prog.presets);
    say!(b"\r\nuf ");
    tx_hex_bytes(&eng.prog.uf);
    say!(b"\r\nscan-check END\r\n");
}

pub(super) fn pass(cov: &Coverage) {
    say!(b"\r\nscan-check PASS trials=");
    tx_dec(u32::from(TRIALS));
    say!(b" scans=");
    tx_dec(cov.scans);
    say!(b" py=");
    tx_dec(u32::from(cov.py));
    say!(b" q=");
    tx_dec(u32::from(cov.q));
    say!(b" tk=");
    tx_dec(u32::from(cov.tk));
    say!(b" retired=");
    tx_dec(u32::from(cov.retired));
    say!(b" edges=");
    tx_dec(u32::from(cov.edges));
    say!(b" views=");
    tx_dec(u32::from(cov.views));
    say!(b" guard=");
    tx_dec(u32::from(cov.guard));
    say!(b" wraps=");
    tx_dec(u32::from(cov.wraps));
    say!(b" bursts=");
    tx_dec(u32::from(cov.bursts));
    say!(b" by_line=");
    tx_dec(u32::from(cov.by_line));
    say!(b" counted=");
    tx_dec(u32::from(cov.counted));
    say!(b" counter_resets=");
    tx_dec(u32::from(cov.counter_resets));
    say!(b" saturated=");
    tx_dec(u32::from(cov.saturated));
    say!(b" cq=");
    tx_dec(u32::from(cov.cq));
    say!(b"\r\nscan-check END\r\n");
}
