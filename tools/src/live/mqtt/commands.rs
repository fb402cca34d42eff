//! `--mqtt-commands`: a message on `<prefix>/<line>/<addr>/<signal>/set` writes that signal,
//! through the live view's own checks (the signal writable, the value in its range,
//! `--read-only`). A refusal writes nothing and is published on `<prefix>/<line>/<addr>/error`
//! (`{"signal", "payload", "error", "refused"}`, not retained) and counted. Retained `set`
//! messages are refused: a command left on the broker would be carried out again at every
//! reconnect.

use std::sync::atomic::Ordering;
use std::sync::Arc;

use rumqttc::{AsyncClient, Publish, QoS};
use serde::Serialize;
use tokio::sync::{mpsc, oneshot};

use super::topics::Topics;
use super::{Counters, WriteRequest};

/// A refusal as published on the error topic.
#[derive(Debug, Serialize)]
struct Refusal<'a> {
    /// The signal the `set` was for.
    signal: &'a str,
    /// The payload, cut short.
    payload: String,
    /// Why, in words.
    error: &'a str,
    /// Refusals so far.
    refused: u64,
}

/// The longest payload a `set` takes (a number is a few bytes).
pub const MAX_PAYLOAD: usize = 32;

/// A `set` payload that is no value.
#[derive(Debug, PartialEq, Eq, thiserror::Error)]
pub enum BadPayload {
    /// Longer than [`MAX_PAYLOAD`].
    #[error("payload too long ({0} bytes): a set takes a number")]
    TooLong(usize),
    /// Not UTF-8.
    #[error("payload is not text: a set takes a number")]
    NotText,
    /// Text, but no whole number (nor ON/OFF, true/false).
    #[error("'{0}' is not a whole number")]
    NotANumber(String),
}

/// The value of a `set` payload: a whole number, or `ON`/`OFF`, `true`/`false`.
pub fn value(payload: &[u8]) -> Result<i64, BadPayload> {
    if payload.len() > MAX_PAYLOAD {
        return Err(BadPayload::TooLong(payload.len()));
    }
    let text = std::str::from_utf8(payload)
        .map_err(|_| BadPayload::NotText)?
        .trim();
    match text.to_ascii_lowercase().as_str() {
        "on" | "true" => return Ok(1),
        "off" | "false" => return Ok(0),
        _ => {}
    }
    text.parse()
        .map_err(|_| BadPayload::NotANumber(text.to_string()))
}

/// A payload as shown in an error: text, cut short.
fn shown(payload: &[u8]) -> String {
    let text = String::from_utf8_lossy(&payload[..payload.len().min(MAX_PAYLOAD)]);
    if payload.len() > MAX_PAYLOAD {
        format!("{text}…")
    } else {
        text.into_owned()
    }
}

/// Takes `set` messages from `inbox` until the connection's task ends.
pub async fn serve(
    t: Topics,
    client: AsyncClient,
    mut inbox: mpsc::Receiver<Publish>,
    writes: mpsc::Sender<WriteRequest>,
    counters: Arc<Counters>,
) {
    while let Some(p) = inbox.recv().await {
        let Some(set) = t.parse_set(&p.topic) else {
            continue;
        };
        let addr = set
            .addr
            .parse::<u8>()
            .ok()
            .filter(|a| (1..=247).contains(a));
        let outcome = match (addr, value(&p.payload)) {
            _ if p.retain => Err("a retained set is not carried out (publish it without the \
                                  retain flag)"
                .to_string()),
            (None, _) => Err(format!("'{}' is not a slave address (1..247)", set.addr)),
            (_, Err(why)) => Err(format!("{}: {why}", set.signal)),
            (Some(addr), Ok(v)) => write(&writes, addr, &set.signal, v).await,
        };
        match outcome {
            Ok(()) => {
                counters.commands.fetch_add(1, Ordering::Relaxed);
            }
            Err(why) => {
                let n = counters.refused.fetch_add(1, Ordering::Relaxed) + 1;
                let topic = match addr {
                    Some(a) => t.unit(a, "error"),
                    None => t.line_error(),
                };
                let body = Refusal {
                    signal: &set.signal,
                    payload: shown(&p.payload),
                    error: &why,
                    refused: n,
                };
                let body = serde_json::to_string(&body).unwrap_or_default();
                let _ = client.try_publish(topic, QoS::AtMostOnce, false, body);
            }
        }
    }
}

/// Asks the live view to write, and waits for its answer.
async fn write(
    writes: &mpsc::Sender<WriteRequest>,
    addr: u8,
    signal: &str,
    value: i64,
) -> Result<(), String> {
    let (done, rx) = oneshot::channel();
    let req = WriteRequest {
        addr,
        signal: signal.to_string(),
        value,
        done,
    };
    writes
        .send(req)
        .await
        .map_err(|_| "the live view has stopped".to_string())?;
    match rx.await {
        Ok(outcome) => outcome.map_err(|e| e.to_string()),
        Err(_) => Err("the live view has stopped".into()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn payloads_are_numbers_or_on_off() {
        assert_eq!(value(b"1"), Ok(1));
        assert_eq!(value(b" 512\n"), Ok(512));
        assert_eq!(value(b"ON"), Ok(1));
        assert_eq!(value(b"false"), Ok(0));
        assert_eq!(value(b"-3"), Ok(-3));
        assert_eq!(value(b"abc"), Err(BadPayload::NotANumber("abc".into())));
        assert!(value(b"abc")
            .unwrap_err()
            .to_string()
            .contains("not a whole number"));
        assert_eq!(value(&[0xFF, 0xFE]), Err(BadPayload::NotText));
        assert_eq!(value(&[b'1'; 100]), Err(BadPayload::TooLong(100)));
        assert_eq!(shown(&[b'x'; 40]).chars().count(), MAX_PAYLOAD + 1);
    }
}
