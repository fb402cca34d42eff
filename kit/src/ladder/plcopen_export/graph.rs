//! The LD body as a graph: each contact, coil, constant and block with its localId, its
//! inputs' wires, and its place in the picture's order — the band of the output it leads to
//! (one output a band, top to bottom in the listing's order, which is the order an IEC
//! runtime runs them in) and its lane in that band (parallel branches below one another).
//! [`super::layout`] turns bands and lanes into positions.

use std::string::String;
use std::vec::Vec;

/// The left power rail's localId.
pub(super) const RAIL: u32 = 1;

/// A wire's source: an element's localId and, for a block, the output's formal name.
pub(super) type Src = (u32, Option<&'static str>);

/// What an element is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    /// A contact on a variable (`edge`: `none`, `rising`, `falling`).
    Contact {
        var: String,
        negated: bool,
        edge: &'static str,
    },
    /// A coil on a variable (`storage`: `none`, `set`, `reset`).
    Coil {
        var: String,
        negated: bool,
        storage: &'static str,
    },
    /// A constant (an `inVariable`: `T#5s`, `5`, `FALSE`).
    Const(String),
    /// A function (`AND`, `NOT`, …) or a function block instance (`TOF0`).
    Block {
        ty: &'static str,
        instance: Option<String>,
    },
}

/// One element of the body.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(super) struct Element {
    /// Its localId.
    pub(super) id: u32,
    /// What it is.
    pub(super) kind: Kind,
    /// Its inputs in order, each with its formal name (`""` for a contact's or coil's).
    pub(super) inputs: Vec<(&'static str, Vec<Src>)>,
    /// Its outputs' formal names in order (`""` for a contact's, coil's or constant's).
    pub(super) outputs: Vec<&'static str>,
    /// The band: one output (coil or function block) each, in scan order.
    pub(super) band: u32,
    /// The lane in its band (0: the output's line).
    pub(super) lane: u32,
}

impl Element {
    /// Whether it is an output: a coil or a function block, which IEC runs in the order of
    /// their positions.
    pub(super) fn is_output(&self) -> bool {
        match &self.kind {
            Kind::Coil { .. } => true,
            Kind::Block { instance, .. } => instance.is_some(),
            _ => false,
        }
    }
}

/// The elements as they are written, and where the next one goes.
#[derive(Default)]
pub(super) struct Graph {
    /// Every element in the order written (localIds ascending from 2).
    pub(super) els: Vec<Element>,
    band: u32,
    lane: u32,
    lane_max: u32,
}

impl Graph {
    /// A new element in the current band and lane (an output: lane 0, and the next element
    /// starts the next band); its localId.
    pub(super) fn add(
        &mut self,
        kind: Kind,
        inputs: Vec<(&'static str, Vec<Src>)>,
        outputs: Vec<&'static str>,
    ) -> u32 {
        let id = RAIL + 1 + self.els.len() as u32;
        let mut el = Element {
            id,
            kind,
            inputs,
            outputs,
            band: self.band,
            lane: self.lane,
        };
        if el.is_output() {
            el.lane = 0;
        }
        self.lane_max = self.lane_max.max(el.lane);
        let output = el.is_output();
        self.els.push(el);
        if output {
            self.band += 1;
            self.lane = 0;
            self.lane_max = 0;
        }
        id
    }

    /// Whether the current band holds elements already.
    fn band_used(&self) -> bool {
        self.els.last().is_some_and(|e| e.band == self.band)
    }

    /// Go to a lane below everything the band holds, and below its current line (which
    /// stays free for the wire going on): for a parallel branch, a function's other operand,
    /// the steps one copy of the power goes through. The lane left.
    pub(super) fn enter_below(&mut self) -> u32 {
        let lane = self.lane;
        self.lane = self.lane_max.max(lane) + 1;
        self.lane_max = self.lane;
        lane
    }

    /// A new network from the rail: below what the band holds already.
    pub(super) fn start_rung(&mut self) {
        if self.band_used() {
            self.lane = self.lane_max + 1;
            self.lane_max = self.lane;
        }
    }

    /// Back to `lane` (from [`Graph::enter_below`]).
    pub(super) fn leave(&mut self, lane: u32) {
        self.lane = lane;
    }
}
