//! Where each element of the body is drawn, and each wire's route, as OpenPLC Editor lays
//! out a ladder: a left power rail with a connection point at each wire it feeds, contacts
//! in columns along their rung's line (a parallel branch in a lane below), function blocks
//! with their inputs 20 apart from 30 down, coils in one column before the right power
//! rail. Every route is its end points (the input first, the output last) and the corners
//! between, each step horizontal or vertical.
//!
//! The order is the picture's: each output (coil or function block) has a band of its own,
//! the bands top to bottom in scan order, so an IEC runtime that runs the outputs top to
//! bottom (then left to right) runs them in the listing's order.

use std::vec::Vec;

use super::graph::{Element, Kind, Src, RAIL};

/// The left rail's x; its connection points are 10 to the right.
const RAIL_X: i32 = 20;
/// Where a wire from the left rail starts.
const RAIL_OUT: i32 = RAIL_X + 10;
/// Columns are this far apart.
const PITCH: i32 = 100;
/// Lanes of a band are this far apart.
const LANE: i32 = 60;
/// A band's first line is this far below its top.
const LINE: i32 = 50;

/// An element's box.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Place {
    /// Left.
    pub(super) x: i32,
    /// Top.
    pub(super) y: i32,
    /// Width.
    pub(super) w: i32,
    /// Height.
    pub(super) h: i32,
}

/// Every element's box, the bands' tops and the right rail's x.
pub(super) struct Layout {
    /// By element, in the graph's order.
    pub(super) at: Vec<Place>,
    /// Each band's top.
    band_top: Vec<i32>,
    /// The right power rail's x.
    pub(super) right_x: i32,
}

/// An element's width and height.
fn size(e: &Element) -> (i32, i32) {
    match &e.kind {
        Kind::Contact { .. } | Kind::Coil { .. } => (21, 20),
        Kind::Const(text) => ((8 * text.len() as i32 + 25) / 10 * 10, 20),
        Kind::Block { .. } => (60, 20 * (e.inputs.len().max(e.outputs.len()) as i32 + 1)),
    }
}

/// Where input `k` of `e` is, relative to its box.
pub(super) fn in_rel(e: &Element, k: usize) -> (i32, i32) {
    match e.kind {
        Kind::Block { .. } => (0, 30 + 20 * k as i32),
        _ => (0, 10),
    }
}

/// Where output `k` of `e` is, relative to its box.
pub(super) fn out_rel(e: &Element, k: usize) -> (i32, i32) {
    let (w, _) = size(e);
    match e.kind {
        Kind::Block { .. } => (w, 30 + 20 * k as i32),
        _ => (w, 10),
    }
}

/// The column of each element: one right of its sources (a function block two, its
/// constants between), coils in one column right of everything.
fn columns(els: &[Element]) -> Vec<i32> {
    let index = |id: u32| (id - RAIL - 1) as usize;
    let mut col = std::vec![0; els.len()];
    for (i, e) in els.iter().enumerate() {
        let from = |srcs: &[Src]| {
            srcs.iter()
                .filter(|(id, _)| *id != RAIL)
                .filter(|(id, _)| !matches!(els[index(*id)].kind, Kind::Const(_)))
                .map(|(id, _)| col[index(*id)])
                .max()
                .unwrap_or(0)
        };
        let inputs = e.inputs.iter().filter(|(f, _)| *f != "EN");
        let left = inputs.map(|(_, s)| from(s)).max().unwrap_or(0);
        col[i] = left
            + if e.is_output() && !matches!(e.kind, Kind::Coil { .. }) {
                2
            } else {
                1
            };
    }
    let last = els
        .iter()
        .zip(&col)
        .filter(|(e, _)| !matches!(e.kind, Kind::Coil { .. }))
        .map(|(_, &c)| c)
        .max()
        .unwrap_or(0);
    for (e, c) in els.iter().zip(col.iter_mut()) {
        if matches!(e.kind, Kind::Coil { .. }) {
            *c = last + 1;
        }
    }
    col
}

/// The x of a column's elements.
fn column_x(col: i32) -> i32 {
    PITCH * col - 40
}

impl Layout {
    /// The boxes of `els`.
    pub(super) fn new(els: &[Element]) -> Layout {
        let col = columns(els);
        // Each element's box with y relative to its band's top; constants beside the input
        // they feed.
        let mut at: Vec<Place> = els
            .iter()
            .zip(&col)
            .map(|(e, &c)| {
                let (w, h) = size(e);
                let line = LINE + LANE * e.lane as i32;
                let y = match e.kind {
                    Kind::Block { .. } => line - in_rel(e, usize::from(e.is_output())).1,
                    _ => line - 10,
                };
                Place {
                    x: column_x(c),
                    y,
                    w,
                    h,
                }
            })
            .collect();
        for (i, e) in els.iter().enumerate() {
            for (k, (_, srcs)) in e.inputs.iter().enumerate() {
                for &(id, _) in srcs {
                    let j = (id.wrapping_sub(RAIL + 1)) as usize;
                    if id != RAIL && matches!(els[j].kind, Kind::Const(_)) {
                        let (rx, ry) = in_rel(e, k);
                        at[j].x = at[i].x + rx - 20 - at[j].w;
                        at[j].y = at[i].y + ry - 10;
                    }
                }
            }
        }
        let bands = els.last().map_or(0, |e| e.band as usize + 1);
        let mut bottom = std::vec![0; bands];
        for (e, p) in els.iter().zip(&at) {
            let b = &mut bottom[e.band as usize];
            *b = (*b).max(p.y + p.h);
        }
        let mut band_top = Vec::with_capacity(bands);
        let mut top = 20;
        for b in bottom {
            band_top.push(top);
            top += (b + 39) / 10 * 10;
        }
        for (e, p) in els.iter().zip(at.iter_mut()) {
            p.y += band_top[e.band as usize];
        }
        let right_x = at.iter().map(|p| p.x + p.w).max().unwrap_or(RAIL_OUT) + 40;
        Layout {
            at,
            band_top,
            right_x,
        }
    }

    /// Where input `k` of element `i` is.
    pub(super) fn in_point(&self, els: &[Element], i: usize, k: usize) -> (i32, i32) {
        let (rx, ry) = in_rel(&els[i], k);
        (self.at[i].x + rx, self.at[i].y + ry)
    }

    /// Where the output a wire leaves is (`src`), with the input it goes to at `to`.
    fn out_point(&self, els: &[Element], src: Src, to: (i32, i32)) -> (i32, i32) {
        if src.0 == RAIL {
            return (RAIL_OUT, to.1);
        }
        let j = (src.0 - RAIL - 1) as usize;
        let e = &els[j];
        let k = e
            .outputs
            .iter()
            .position(|f| Some(*f) == src.1 || (src.1.is_none() && f.is_empty()))
            .unwrap_or(0);
        let (rx, ry) = out_rel(e, k);
        (self.at[j].x + rx, self.at[j].y + ry)
    }

    /// The route of the wire from `src` into input `k` of element `i`: its end points (the
    /// input first) and corners. EN comes from the left rail along the band's top.
    pub(super) fn route(&self, els: &[Element], i: usize, k: usize, src: Src) -> Vec<(i32, i32)> {
        let to = self.in_point(els, i, k);
        let from = self.out_point(els, src, to);
        if src.0 == RAIL && els[i].inputs[k].0 == "EN" {
            let y = self.band_top[els[i].band as usize] + 10;
            return std::vec![to, (to.0 - 10, to.1), (to.0 - 10, y), (RAIL_OUT, y)];
        }
        if from.1 == to.1 {
            return std::vec![to, from];
        }
        // Down from a branch point: the corner by the source; up into a join: by the input.
        let x = if from.1 < to.1 {
            from.0 + 10
        } else {
            to.0 - 10
        };
        std::vec![to, (x, to.1), (x, from.1), from]
    }
}
