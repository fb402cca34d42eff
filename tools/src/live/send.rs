//! Send a program from the page: `POST /api/units/{addr}/program` with
//! `{"listing": "…", "store": bool, "run": bool}`. The listing is checked whole first (the
//! kit's parser, `utile asm`'s messages): one with mistakes sends nothing. Then the send is a
//! job of the line's owner (`line/send.rs`), like the terminal's editor session: polling
//! pauses while the editor has the line. On the line it is `utile push --stop`'s steps
//! ([`crate::link::Session`], on a clone of the line's port): `/` stops the program (a program
//! without KEY is refused), READ takes the image (only a whole, checked file replaces the
//! program), STORE if asked, EX0 if asked; then the line reads it back: the §17 program block
//! and the snapshot's fingerprint must be the image's (without EX0, WRITE reads it back).
//!
//! The request waits as long as the send can take on the line (its longest, from the
//! session's own time-outs, [`crate::link::Timeouts`]), so a send it reports failed has
//! failed; a send the line has not taken within [`WAIT`] is not carried out.

use std::sync::Arc;
use std::time::Duration;

use axum::extract::rejection::{JsonRejection, PathRejection};
use axum::extract::{Path, State};
use axum::Json;
use serde::Deserialize;

use super::api::ApiError;
use super::check;
use super::hub::{Hub, Input};
use super::job::{question, SendJob, Sent};
use super::line::longest_send;

/// The longest the request waits for the line to take the send (it does between two
/// transactions).
const WAIT: Duration = Duration::from_secs(5);

/// `POST /api/units/{addr}/program`'s body.
#[derive(Debug, Deserialize)]
pub struct SendBody {
    /// The listing's text, as a `.utl` file holds it.
    #[serde(default)]
    pub listing: String,
    /// STORE it into EEPROM (autostart with D8) after it is loaded.
    #[serde(default)]
    pub store: bool,
    /// Start it (EX0) after it is loaded.
    #[serde(default)]
    pub run: bool,
}

/// `POST /api/units/{addr}/program`: check, then send through the line's owner.
pub async fn post(
    State(hub): State<Arc<Hub>>,
    addr: Result<Path<u8>, PathRejection>,
    body: Result<Json<SendBody>, JsonRejection>,
) -> Result<Json<Sent>, ApiError> {
    let Path(addr) = addr?;
    let Json(body) = body?;
    if let Some(p) = check::problems(&body.listing).into_iter().next() {
        return Err(ApiError::Listing {
            line: p.line,
            message: p.message,
        });
    }
    let prog =
        utile_kit::listing::parse("listing", &body.listing).map_err(|e| ApiError::Listing {
            line: 1,
            message: e.to_string(),
        })?;
    if hub.read_only {
        return Err(ApiError::ReadOnly);
    }
    hub.view().unit(addr).ok_or(ApiError::NoUnit(addr))?;
    let (reply, asked) = question();
    hub.submit(Input::Send(Box::new(SendJob {
        addr,
        prog,
        store: body.store,
        run: body.run,
        reply,
    })))?;
    let sent = asked
        .outcome(WAIT, longest_send(body.store, body.run))
        .await??;
    Ok(Json(sent))
}
