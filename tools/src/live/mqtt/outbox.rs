//! What should be retained on the broker, and what was sent on this connection: a message
//! goes out when it differs from what was sent, so a value is published on change only, a
//! message the client's queue could not take is tried again, and after a reconnect
//! everything is sent again (the broker may have lost its retained messages).

use std::collections::BTreeMap;

/// The retained messages, wanted and sent.
#[derive(Debug, Default)]
pub struct Outbox {
    /// First of all after a connect (the line's status).
    first: Vec<String>,
    wanted: BTreeMap<String, String>,
    sent: BTreeMap<String, String>,
}

impl Outbox {
    /// An outbox that sends `first` (topics) before any other.
    pub fn new(first: Vec<String>) -> Outbox {
        Outbox {
            first,
            ..Outbox::default()
        }
    }

    /// `topic` should hold `payload`.
    pub fn want(&mut self, topic: String, payload: String) {
        match self.wanted.get_mut(&topic) {
            Some(p) if *p == payload => {}
            Some(p) => *p = payload,
            None => {
                self.wanted.insert(topic, payload);
            }
        }
    }

    /// Whether `topic` is wanted (with any payload).
    pub fn wants(&self, topic: &str) -> bool {
        self.wanted.contains_key(topic)
    }

    /// A new connection: nothing is sent on it yet.
    pub fn reconnected(&mut self) {
        self.sent.clear();
    }

    /// Messages not sent as they are wanted, in order (the `first` ones first).
    pub fn pending(&self) -> Vec<(String, String)> {
        let differs = |t: &String, p: &String| self.sent.get(t) != Some(p);
        let mut out: Vec<(String, String)> = self
            .first
            .iter()
            .filter_map(|t| self.wanted.get(t).map(|p| (t.clone(), p.clone())))
            .filter(|(t, p)| differs(t, p))
            .collect();
        out.extend(
            self.wanted
                .iter()
                .filter(|(t, p)| !self.first.contains(t) && differs(t, p))
                .map(|(t, p)| (t.clone(), p.clone())),
        );
        out
    }

    /// `topic` went out with `payload`.
    pub fn sent(&mut self, topic: String, payload: String) {
        self.sent.insert(topic, payload);
    }

    /// Messages wanted.
    pub fn len(&self) -> usize {
        self.wanted.len()
    }

    /// Nothing is wanted.
    pub fn is_empty(&self) -> bool {
        self.wanted.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_changes_go_out_until_a_reconnect_sends_all_again() {
        let mut o = Outbox::new(vec!["s".into()]);
        o.want("b".into(), "1".into());
        o.want("s".into(), "online".into());
        let p = o.pending();
        assert_eq!(p[0].0, "s", "the status goes first");
        for (t, v) in p {
            o.sent(t, v);
        }
        assert!(o.pending().is_empty());
        o.want("b".into(), "1".into());
        assert!(o.pending().is_empty(), "no change, nothing sent");
        o.want("b".into(), "0".into());
        assert_eq!(o.pending(), [("b".into(), "0".into())]);
        o.sent("b".into(), "0".into());
        o.reconnected();
        assert_eq!(o.pending().len(), 2);
    }
}
