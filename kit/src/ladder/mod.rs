//! uTile speaks ladder (IEC 61131-3 LD): a listing drawn as rungs, rungs compiled back to a
//! listing, PLCopen XML (OpenPLC Editor) and LDmicro programs imported (docs/LADDER.md).
//!
//! One room a job: [`model`] (rungs, contacts, coils, blocks), [`from_listing`] and
//! [`to_listing`] (the two directions between a program and its rungs), [`svg`] (the
//! drawing), [`import`] (what the importers share, and the importers: [`import::plcopen`],
//! [`import::ldmicro`]) and [`iec`] (IEC's timers, edges and flip-flops built from uTile's
//! own), and [`plcopen_export`] (a program as OpenPLC Editor's PLCopen XML).

pub mod from_listing;
pub mod iec;
pub mod import;
pub mod model;
pub mod plcopen_export;
pub mod svg;
pub mod to_listing;

pub use from_listing::from_program;
pub use model::{Block, Coil, Contact, Flow, Item, Ladder, Net, Rung, Step};
pub use svg::svg;
pub use to_listing::{code, to_program, TooLong};

/// Every reason a program cannot be imported, lowered or exported, one a line, each with
/// what to do.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{}", .0.join("\n"))]
pub struct Reasons(pub std::vec::Vec<std::string::String>);
