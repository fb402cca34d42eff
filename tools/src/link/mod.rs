//! Programs to and from a uTile over a serial port without Kermit (`utile push`, `utile
//! pull`): the port (`port.rs`) and the editor session that speaks READ and WRITE
//! (`session.rs`).

pub mod port;
pub mod session;

pub use port::PortError;
pub use session::{LinkError, Options, Session};
