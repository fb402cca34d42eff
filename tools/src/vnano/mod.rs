//! The virtual Nano: the real firmware image running in simavr, its UART on the user's
//! terminal (or a pseudo-terminal), and a virtual test rig driven from the keyboard.
//! The `vnano` binary (`cargo nano`) parses the options and runs a [`session`].
//!
//! The rooms: [`args`] (the command line), [`start`] (the chip and the pty a run starts
//! from), [`session`] (the loop: chip, keys, UART, pacing), [`arrivals`] (the pty client's
//! bytes at the simulated time they came), [`status`] (the line below the
//! screen), [`rig`] (the rig's keys and its view), [`load`] (`--load` through READ),
//! [`term`] (the user's terminal), [`pty`] (the pseudo-terminal), [`io`] (waiting and
//! reading on descriptors), [`bus`] (`--bus N`), [`plant`] (`--plant tank`) and [`control`]
//! (`--control PATH`, the rig over a socket).

pub mod args;
pub mod arrivals;
pub mod bus;
pub mod control;
pub mod io;
pub mod load;
pub mod plant;
pub mod pty;
pub mod rig;
pub mod session;
pub mod start;
pub mod status;
pub mod term;

pub use utile_kit::simavr::{Chip, CpuState, RigPin};
