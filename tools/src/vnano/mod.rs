//! The virtual Nano: the real firmware image running in simavr, its UART on the user's
//! terminal (or a pseudo-terminal), and a virtual test rig driven from the keyboard.
//! The `vnano` binary (`cargo nano`) parses the options and runs a [`session`].
//!
//! The rooms: [`args`] (the command line), [`start`] (the chip and the pty a run starts
//! from), [`session`] (the loop: chip, keys, UART, pacing), [`status`] (the line below the
//! screen), [`rig`] (the rig's keys and its view), [`load`] (`--load` through READ),
//! [`term`] (the user's terminal), [`pty`] (the pseudo-terminal), [`io`] (waiting and
//! reading on descriptors) and [`bus`] (`--bus N`).

pub mod args;
pub mod bus;
pub mod io;
pub mod load;
pub mod pty;
pub mod rig;
pub mod session;
pub mod start;
pub mod status;
pub mod term;

pub use utile_kit::simavr::{Chip, CpuState, RigPin};
