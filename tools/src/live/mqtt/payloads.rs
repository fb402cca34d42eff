//! The retained messages one uTile's report gives on the line's session: `<addr>/state`
//! (every value as one JSON object, the API's names) and `<addr>/<signal>` (each value alone:
//! `0`/`1`, a number); the outbox sends only those that changed. `<addr>/availability`
//! (`online`/`offline`) goes on the uTile's own session (`availability.rs`).

use super::topics::Topics;
use super::{Reading, Report};

/// The payload of a line's status and a uTile's availability while it is there.
pub const ONLINE: &str = "online";
/// The payload of a line's status and a uTile's availability once it is not (the last wills).
pub const OFFLINE: &str = "offline";

/// [`ONLINE`] or [`OFFLINE`].
pub fn availability(online: bool) -> &'static str {
    if online {
        ONLINE
    } else {
        OFFLINE
    }
}

/// A value alone, as text: `1`, `512`, `18.5` (a whole rate without a trailing `.0`).
pub fn value_text(v: &Reading) -> String {
    match *v {
        Reading::Whole(n) => n.to_string(),
        Reading::Rate(f) if f.fract() == 0.0 && f.abs() < 1e15 => format!("{}", f as i64),
        Reading::Rate(f) => f.to_string(),
    }
}

/// The retained (topic, payload) pairs of `r` on the line's session (its availability is not
/// among them); none before the uTile's first read (no values): a retained `{}` would stand
/// on the broker as the uTile's state.
pub fn retained(t: &Topics, r: &Report) -> Vec<(String, String)> {
    if r.values.is_empty() {
        return Vec::new();
    }
    let mut out = Vec::with_capacity(r.values.len() + 1);
    let state = serde_json::to_string(&r.values).unwrap_or_else(|_| "{}".into());
    out.push((t.unit(r.addr, "state"), state));
    for (name, v) in &r.values {
        out.push((t.unit(r.addr, name), value_text(v)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_report_gives_state_and_each_value() {
        let t = Topics::new("utile", "l");
        let r = Report {
            addr: 2,
            online: true,
            values: [
                ("A0", Reading::Whole(1)),
                ("A6", Reading::Whole(409)),
                ("scans_per_s", Reading::Rate(18.0)),
            ]
            .into_iter()
            .map(|(k, v)| (k.to_string(), v))
            .collect(),
            firmware: None,
        };
        let m = retained(&t, &r);
        let get = |topic: &str| m.iter().find(|(k, _)| k == topic).map(|(_, v)| v.as_str());
        assert_eq!(
            get("utile/l/2/availability"),
            None,
            "on the uTile's own session"
        );
        assert_eq!(
            get("utile/l/2/state"),
            Some(r#"{"A0":1,"A6":409,"scans_per_s":18.0}"#)
        );
        assert_eq!(get("utile/l/2/A6"), Some("409"));
        assert_eq!(get("utile/l/2/scans_per_s"), Some("18"));
        assert_eq!(value_text(&Reading::Rate(18.5)), "18.5");
    }

    #[test]
    fn nothing_before_the_first_read() {
        let t = Topics::new("utile", "l");
        let unread = Report {
            addr: 1,
            online: false,
            values: Default::default(),
            firmware: None,
        };
        assert_eq!(retained(&t, &unread), Vec::new());
    }
}
