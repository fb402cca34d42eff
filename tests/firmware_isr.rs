//! A toolchain assumption the hot paths rely on, checked on the real image
//! (docs/RELIABILITY.md, "What the hot paths assume"): the threaded scan (`scan.S`) uses r1
//! for `mul` results with interrupts on, so every interrupt handler that reads r1 must set it
//! to zero first (`eor r1, r1` in its prologue, after saving it), as avr-gcc's and LLVM's
//! AVR backends do. Read with Debian's `avr-objdump` from `out/m328-nano-utile.elf`
//! (`cargo fw`).

use std::path::Path;
use std::process::Command;

/// The disassembly of the firmware image.
fn disassembly() -> String {
    let elf = std::env::var("UTILE_ELF").unwrap_or_else(|_| {
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("out/m328-nano-utile.elf")
            .to_string_lossy()
            .into_owned()
    });
    let out = Command::new("avr-objdump")
        .args(["-d", &elf])
        .output()
        .expect("avr-objdump (binutils-avr) runs");
    assert!(
        out.status.success(),
        "avr-objdump -d {elf}: run `cargo fw` first"
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Each handler's instructions (mnemonic and operands), from its label to its `reti` or
/// its first jump away.
fn handlers(dis: &str) -> Vec<(String, Vec<String>)> {
    let mut all = Vec::new();
    let mut current: Option<(String, Vec<String>)> = None;
    for line in dis.lines() {
        if line.ends_with(">:") {
            if let Some(h) = current.take() {
                all.push(h);
            }
            if let Some(name) = line.split('<').nth(1).map(|n| n.trim_end_matches(">:")) {
                if name.starts_with("__vector_") {
                    current = Some((name.to_string(), Vec::new()));
                }
            }
            continue;
        }
        if let Some((_, body)) = &mut current {
            // "    addr:\tbytes \tmnemonic\toperands\t; comment"
            let fields: Vec<&str> = line.split('\t').collect();
            if fields.len() >= 3 {
                let insn = fields[2..].join(" ");
                let insn = insn.split(';').next().unwrap_or("").trim().to_string();
                body.push(insn);
            }
        }
    }
    all.extend(current);
    all
}

/// Whether the instruction reads register r1 (as an operand other than its own save,
/// restore or clearing).
fn reads_r1(insn: &str) -> bool {
    let mut parts = insn.splitn(2, ' ');
    let mnemonic = parts.next().unwrap_or("");
    let operands = parts.next().unwrap_or("");
    if matches!(mnemonic, "push" | "pop") || insn.replace(' ', "") == "eorr1,r1" {
        return false;
    }
    operands
        .split(',')
        .map(str::trim)
        .enumerate()
        .any(|(i, op)| {
            op == "r1"
                && !(i == 0
                    && matches!(
                        mnemonic,
                        "ldi" | "lds" | "mov" | "in" | "ld" | "pop" | "clr"
                    ))
        })
}

#[test]
fn every_interrupt_handler_that_reads_r1_clears_it_first() {
    let dis = disassembly();
    let handlers = handlers(&dis);
    assert!(
        handlers.len() >= 6,
        "the image's interrupt handlers: {:?}",
        handlers.iter().map(|h| &h.0).collect::<Vec<_>>()
    );
    let mut checked = 0;
    for (name, body) in &handlers {
        let cleared = body.iter().position(|i| i.replace(' ', "") == "eorr1,r1");
        let first_read = body.iter().position(|i| reads_r1(i));
        if let Some(read) = first_read {
            checked += 1;
            assert!(
                cleared.is_some_and(|c| c < read),
                "{name} reads r1 ({}) before clearing it: an interrupt inside the scan's \
                 `mul` would see its product",
                body[read]
            );
        }
    }
    assert!(checked >= 3, "only {checked} handlers read r1");
}

/// The check can fail: a handler that stores r1 before clearing it is seen.
#[test]
fn the_check_sees_a_handler_that_reads_r1_before_clearing_it() {
    let planted = "00000010 <__vector_1>:\n  10:\t0f 92 \tpush\tr0\n  12:\t10 92 6f 00 \tsts\t0x006F, r1\t; TIMSK1\n  16:\t11 24 \teor\tr1, r1\n  18:\t18 95 \treti\n";
    let h = handlers(planted);
    assert_eq!(h.len(), 1);
    let body = &h[0].1;
    assert_eq!(body.iter().position(|i| reads_r1(i)), Some(1));
    assert_eq!(
        body.iter().position(|i| i.replace(' ', "") == "eorr1,r1"),
        Some(2)
    );
}
