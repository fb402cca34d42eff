//! Programs to and from a uTile over a serial port without Kermit (`utile push`, `utile
//! pull`): the port (`port.rs`), the editor session that speaks READ and WRITE
//! (`session.rs`) and how long it waits for each answer (`timeouts.rs`).

pub mod port;
pub mod session;
pub mod timeouts;

pub use port::PortError;
pub use session::{LinkError, Options, Session};
pub use timeouts::Timeouts;
