//! The topics of one line (docs/LIVE.md, "MQTT"): `<prefix>/<line>/status`,
//! `<prefix>/<line>/<addr>/{state,availability,error,<signal>,<signal>/set}` and Home
//! Assistant's `homeassistant/<component>/<object>/config`.

/// Home Assistant's discovery prefix.
pub const DISCOVERY_PREFIX: &str = "homeassistant";

/// The topics of one line.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Topics {
    /// `<prefix>/<line>`.
    base: String,
    line: String,
}

/// A `set` topic taken apart.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SetTopic {
    /// The address as written in the topic (may not be a number).
    pub addr: String,
    /// The signal's name.
    pub signal: String,
}

impl Topics {
    /// The topics under `prefix` for the line `line`.
    pub fn new(prefix: &str, line: &str) -> Topics {
        Topics {
            base: format!("{}/{line}", prefix.trim_end_matches('/')),
            line: line.to_string(),
        }
    }

    /// The line's name.
    pub fn line(&self) -> &str {
        &self.line
    }

    /// `<prefix>/<line>/status`: `online`, and `offline` as the last will.
    pub fn status(&self) -> String {
        format!("{}/status", self.base)
    }

    /// `<prefix>/<line>/counters`: the line's MQTT counters as JSON.
    pub fn counters(&self) -> String {
        format!("{}/counters", self.base)
    }

    /// `<prefix>/<line>/error`: a refused `set` whose address is not a number.
    pub fn line_error(&self) -> String {
        format!("{}/error", self.base)
    }

    /// `<prefix>/<line>/<addr>/<leaf>` (`state`, `availability`, `error`, or a signal).
    pub fn unit(&self, addr: u8, leaf: &str) -> String {
        format!("{}/{addr}/{leaf}", self.base)
    }

    /// `<prefix>/<line>/<addr>/<signal>/set`.
    pub fn set(&self, addr: u8, signal: &str) -> String {
        format!("{}/{addr}/{signal}/set", self.base)
    }

    /// The filter that takes every `set` of this line.
    pub fn set_filter(&self) -> String {
        format!("{}/+/+/set", self.base)
    }

    /// The address and signal of a `set` topic of this line, or `None`.
    pub fn parse_set(&self, topic: &str) -> Option<SetTopic> {
        let rest = topic.strip_prefix(&self.base)?.strip_prefix('/')?;
        let rest = rest.strip_suffix("/set")?;
        let (addr, signal) = rest.split_once('/')?;
        (!signal.contains('/')).then(|| SetTopic {
            addr: addr.to_string(),
            signal: signal.to_string(),
        })
    }

    /// `homeassistant/<component>/<object>/config`.
    pub fn discovery(component: &str, object: &str) -> String {
        format!("{DISCOVERY_PREFIX}/{component}/{object}/config")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn topics_of_a_line() {
        let t = Topics::new("utile", "pi-ttyUSB0");
        assert_eq!(t.status(), "utile/pi-ttyUSB0/status");
        assert_eq!(t.unit(3, "state"), "utile/pi-ttyUSB0/3/state");
        assert_eq!(t.set(3, "Y0"), "utile/pi-ttyUSB0/3/Y0/set");
        assert_eq!(
            t.parse_set("utile/pi-ttyUSB0/3/Y0/set"),
            Some(SetTopic {
                addr: "3".into(),
                signal: "Y0".into()
            })
        );
        assert_eq!(t.parse_set("utile/other/3/Y0/set"), None);
        assert_eq!(t.parse_set("utile/pi-ttyUSB0/3/Y0"), None);
        assert_eq!(
            Topics::discovery("switch", "utile_l_1_Y0"),
            "homeassistant/switch/utile_l_1_Y0/config"
        );
    }
}
