//! The `modbus` harness's oracle of what a request does, worked out from the request and the
//! map alone (never from the codec): a read's reply carries the map's values as they were,
//! a write changes exactly the coils or registers it names to the values it names, and
//! anything else (diagnostics, report server ID, an exception) changes nothing.

use std::vec::Vec;

use utile_core::modbus::map::{Map, Table};

use super::Verdict;
use crate::modbus::map::TestMap;

/// Big-endian word at `i` of `b` (0 past the end).
fn word(b: &[u8], i: usize) -> u16 {
    match (b.get(i), b.get(i + 1)) {
        (Some(&h), Some(&l)) => u16::from_be_bytes([h, l]),
        _ => 0,
    }
}

/// The map as `before` with every `(table, addr, value)` of `writes` done.
fn written(before: &TestMap, writes: &[(Table, u16, u16)]) -> TestMap {
    let mut m = before.clone();
    for &(table, addr, value) in writes {
        m.write(table, addr, value);
    }
    m
}

/// Checks the reply PDU `reply` (function first, no address or CRC) to the request PDU `pdu`,
/// and the map `after` it, against the map `before` it.
pub fn check_effect(pdu: &[u8], reply: &[u8], before: &TestMap, after: &TestMap) -> Verdict {
    let function = pdu.first().copied().unwrap_or(0);
    if reply.first().is_some_and(|f| f & 0x80 != 0) {
        if after != before {
            return Err(broken!(
                "exception {reply:02X?} to {pdu:02X?} changed the map"
            ));
        }
        return Ok(());
    }
    let (start, qty) = (word(pdu, 1), word(pdu, 3));
    let mut map = before.clone();
    let expected_after = match function {
        0x01 | 0x02 => {
            let table = if function == 1 {
                Table::Coils
            } else {
                Table::DiscreteInputs
            };
            let mut bytes = std::vec![0u8; usize::from(qty).div_ceil(8)];
            for i in 0..qty {
                if map.read(table, start.wrapping_add(i)) != 0 {
                    bytes[usize::from(i / 8)] |= 1 << (i % 8);
                }
            }
            let mut want = std::vec![function, bytes.len() as u8];
            want.extend(bytes);
            if reply != want.as_slice() {
                return Err(broken!(
                    "read {pdu:02X?} got {reply:02X?}, the map holds {want:02X?}"
                ));
            }
            before.clone()
        }
        0x03 | 0x04 => {
            let table = if function == 3 {
                Table::HoldingRegisters
            } else {
                Table::InputRegisters
            };
            let mut want = std::vec![function, (2 * qty) as u8];
            for i in 0..qty {
                want.extend(map.read(table, start.wrapping_add(i)).to_be_bytes());
            }
            if reply != want.as_slice() {
                return Err(broken!(
                    "read {pdu:02X?} got {reply:02X?}, the map holds {want:02X?}"
                ));
            }
            before.clone()
        }
        0x05 => written(before, &[(Table::Coils, start, u16::from(qty == 0xFF00))]),
        0x06 => written(before, &[(Table::HoldingRegisters, start, qty)]),
        0x0F => {
            let writes: Vec<(Table, u16, u16)> = (0..qty)
                .map(|i| {
                    let byte = pdu.get(6 + usize::from(i / 8)).copied().unwrap_or(0);
                    let bit = u16::from(byte >> (i % 8) & 1);
                    (Table::Coils, start.wrapping_add(i), bit)
                })
                .collect();
            written(before, &writes)
        }
        0x10 => {
            let writes: Vec<(Table, u16, u16)> = (0..qty)
                .map(|i| {
                    let value = word(pdu, 6 + 2 * usize::from(i));
                    (Table::HoldingRegisters, start.wrapping_add(i), value)
                })
                .collect();
            written(before, &writes)
        }
        _ => before.clone(),
    };
    if matches!(function, 0x05 | 0x06) && reply != pdu {
        return Err(broken!("write {pdu:02X?} not echoed: {reply:02X?}"));
    }
    if matches!(function, 0x0F | 0x10) && reply.get(..5) != pdu.get(..5) {
        return Err(broken!("write {pdu:02X?} answered {reply:02X?}"));
    }
    if *after != expected_after {
        return Err(broken!(
            "{pdu:02X?} changed the map otherwise than it names"
        ));
    }
    Ok(())
}

/// Whether `after` is `before` with exactly the writes the request frame `request` names
/// (worked out here from §13's map, not by the codec): coils 0..23 are PY, PU, PV bit by bit,
/// holding registers 0..15 the timer presets, 16..23 the counter presets (their counters'
/// outputs may follow), 24..25 the set-points. A request that writes nothing changes nothing.
pub fn named_writes(
    request: &[u8],
    before: &utile_core::engine::Engine,
    after: &utile_core::engine::Engine,
) -> Verdict {
    let word = |i: usize| match (request.get(i), request.get(i + 1)) {
        (Some(&h), Some(&l)) => u16::from_be_bytes([h, l]),
        _ => 0,
    };
    let (start, qty) = (word(2), word(4));
    let mut want = before.clone();
    let mut coil = |a: u16, on: bool| {
        let port = match a >> 3 {
            0 => &mut want.py,
            1 => &mut want.pu,
            _ => &mut want.pv,
        };
        let mask = 1u8 << (a & 7);
        *port = if on { *port | mask } else { *port & !mask };
    };
    let mut registers = Vec::new();
    match request.get(1).copied().unwrap_or(0) {
        0x05 => coil(start, qty == 0xFF00),
        0x0F => {
            for i in 0..qty {
                let byte = request.get(7 + usize::from(i / 8)).copied().unwrap_or(0);
                coil(start.wrapping_add(i), byte >> (i % 8) & 1 != 0);
            }
        }
        0x06 => registers.push((start, qty)),
        0x10 => {
            for i in 0..qty {
                registers.push((start.wrapping_add(i), word(7 + 2 * usize::from(i))));
            }
        }
        _ => {}
    }
    // Counter outputs may follow the presets written.
    let mut cq_free = 0u8;
    for (a, v) in registers {
        let a = usize::from(a);
        match a {
            0..=15 => want.prog.presets[a] = v as u8,
            16..=23 => {
                want.prog.counter_presets[a - 16] = v;
                cq_free |= 1 << (a - 16);
            }
            24..=25 => want.prog.set_points[a - 24] = v,
            // SPEC §18's scan control and steps move the hold, not the engine (the hold's
            // own model checks them: `super::hold`).
            _ => {}
        }
    }
    if (after.cq ^ before.cq) & !cq_free != 0 {
        return Err(broken!(
            "{request:02X?} moved the outputs of counters whose preset it did not write"
        ));
    }
    want.cq = after.cq;
    if *after != want {
        return Err(broken!("{request:02X?} changed otherwise than it names"));
    }
    Ok(())
}
