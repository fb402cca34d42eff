//! What `utile sim` writes from a result: the table of output changes and a Value Change
//! Dump for GTKWave (the SVG diagram is [`crate::diagram`]), and the edges of one output.

use std::fmt::Write as _;
use std::string::String;
use std::vec::Vec;

use super::run::SimResult;
use super::signal::Signal;
use super::timeline::format_time;

/// The table of output changes: a header, then one row per change with the time and Y0..Y7.
pub fn output_table(log: &[(u32, u8)]) -> String {
    let mut out = String::from("     time  Y0 Y1 Y2 Y3 Y4 Y5 Y6 Y7\n");
    for &(ms, py) in log {
        let _ = write!(out, "{:>9}", format_time(ms));
        for n in 0..8 {
            let _ = write!(out, "  {}", (py >> n) & 1);
        }
        out.push('\n');
    }
    out
}

/// The edges of output Yn in an output log of (ms, Y0..Y7 image) changes, as the host
/// run and the chip record them: (ms, new level) each time bit `n` changes, from low.
pub fn edges(log: &[(u32, u8)], n: u8) -> Vec<(u32, bool)> {
    let mut last = false;
    let mut out = Vec::new();
    for &(ms, py) in log {
        let level = py & (1 << n) != 0;
        if level != last {
            out.push((ms, level));
            last = level;
        }
    }
    out
}

/// A Value Change Dump of the traces (timescale 1 ms), for GTKWave.
pub fn vcd(result: &SimResult, program_name: &str) -> String {
    let id = |i: usize| {
        // Identifiers from the printable range, two characters past 94 signals.
        let (hi, lo) = (i / 94, i % 94);
        let mut s = String::new();
        if hi > 0 {
            s.push(char::from(b'!' + (hi - 1) as u8));
        }
        s.push(char::from(b'!' + lo as u8));
        s
    };
    let mut out = String::new();
    let _ = writeln!(out, "$comment utile sim {program_name} $end");
    out.push_str("$version utile-tools $end\n$timescale 1ms $end\n$scope module utile $end\n");
    for (i, tr) in result.traces.iter().enumerate() {
        let _ = writeln!(
            out,
            "$var wire {} {} {} $end",
            tr.signal.width(),
            id(i),
            tr.signal.name()
        );
    }
    // A bit is `0!`; a vector (counts, analog levels) is `b1010 !`.
    let value = |signal: Signal, v: u16, i: usize| {
        if signal.is_bit() {
            format!("{v}{}", id(i))
        } else {
            format!("b{v:b} {}", id(i))
        }
    };
    out.push_str("$upscope $end\n$enddefinitions $end\n#0\n$dumpvars\n");
    for (i, tr) in result.traces.iter().enumerate() {
        let _ = writeln!(out, "{}", value(tr.signal, tr.initial, i));
    }
    out.push_str("$end\n");
    let mut changes: Vec<(u32, usize, u16)> = result
        .traces
        .iter()
        .enumerate()
        .flat_map(|(i, tr)| tr.changes.iter().map(move |&(ms, v)| (ms, i, v)))
        .collect();
    changes.sort();
    let mut last = None;
    for (ms, i, v) in changes {
        if last != Some(ms) {
            let _ = writeln!(out, "#{ms}");
            last = Some(ms);
        }
        let _ = writeln!(out, "{}", value(result.traces[i].signal, v, i));
    }
    let _ = writeln!(out, "#{}", result.until_ms);
    out
}
