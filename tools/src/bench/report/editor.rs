//! The rows of `size` (flash and static RAM, from the ELF), `uart` (bytes the editor's
//! screens send), `store` (STORE's duration) and `stack` (the deepest stack use).

use std::path::Path;

use super::Report;
use crate::bench::{measure_stack, measure_store, measure_uart};

/// Flash and static RAM of the image.
pub fn size_rows(rows: &mut Report, elf: &Path) {
    match crate::elf::sections(elf) {
        Ok(sections) => {
            let (flash, ram) = (sections.flash(), sections.ram());
            rows.row(
                "flash (.text + .data)",
                format!("{flash} bytes"),
                "15,378 bytes",
                "≤ 15.4 KB",
            );
            rows.row(
                "static RAM (.data + .bss + .noinit)",
                format!("{ram} bytes"),
                "614 bytes",
                "—",
            );
        }
        Err(e) => rows.row("flash / RAM", e.to_string(), "15,378 bytes", "≤ 15.4 KB"),
    }
}

/// UART bytes of the power-up screen, a command, a page flip and a redraw.
pub fn uart_rows(rows: &mut Report, elf: &Path) {
    match measure_uart(elf) {
        Ok(u) => {
            for (what, bytes, original, goal) in [
                ("power-up screen", u.power_up, "1238", "≤ 1300"),
                ("one command entry (`A0.` CR)", u.command, "n/a", "≤ 120"),
                ("page flip (ESC [ C)", u.page_flip, "n/a", "≤ 700"),
                ("full redraw (`/` CR)", u.redraw, "1238", "≤ 1300"),
            ] {
                rows.row(
                    format!("UART bytes: {what}"),
                    bytes.to_string(),
                    original,
                    goal,
                );
            }
        }
        Err(e) => rows.row(
            "UART bytes",
            format!("not yet measurable: {e}"),
            "1238",
            "≤ 1300",
        ),
    }
}

/// STORE after a one-line change and into an erased EEPROM.
pub fn store_rows(rows: &mut Report, elf: &Path) {
    match measure_store(elf) {
        Ok((small, full)) => {
            for (name, t) in [
                ("one-line change", small),
                ("full rewrite (erased EEPROM)", full),
            ] {
                rows.row(
                    format!("STORE, {name}"),
                    format!(
                        "{:.0} ms ({} EEPROM byte writes × 3.4 ms modelled)",
                        t.ms, t.writes
                    ),
                    "~1.8 s (528 writes)",
                    "—",
                );
            }
        }
        Err(e) => rows.row("STORE", format!("not yet measurable: {e}"), "~1.8 s", "—"),
    }
}

/// The stack's high-water mark after every screen and Modbus requests in RUN mode.
pub fn stack_rows(rows: &mut Report, elf: &Path) {
    match measure_stack(elf) {
        Ok((used, free, log)) => {
            for l in log {
                eprintln!("    {l}");
            }
            rows.row("stack high-water (after help, LDT, LDC, ADDR, READ/LIST/WRITE of 256 lines, RUN with Modbus requests, STORE)",
                    format!("{used} bytes used, {free} bytes never touched"),
                    "n/a",
                    "—",
                );
        }
        Err(e) => rows.row(
            "stack high-water",
            format!("not yet measurable: {e}"),
            "n/a",
            "—",
        ),
    }
}
