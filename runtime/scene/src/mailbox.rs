//! Messages between scenes and tools: a script publishes `(key, JSON value)` and
//! subscribes to key expressions; every message is delivered at the start of the next
//! tick, in a deterministic order: the scene's own messages in the order they were
//! published, then those inputs brought in (a network subscription, a replay), in the
//! order of the inputs and, within one input and tick, sorted by key then text.
//!
//! The mailbox only holds messages; the script (the Lua director) calls the
//! subscribers' functions, and an observer (`troupe run --zenoh`) sends what was
//! published. Key expressions are Zenoh's (`cue/*`, `cue/**`), so a subscription here
//! matches what the network would deliver.

use crate::error::{Error, Result};

/// A message: a key and a JSON value.
#[derive(Clone, Debug, PartialEq)]
pub struct Message {
    /// Where it was published (`cue/start`), never a wildcard.
    pub key: String,
    /// The value.
    pub value: serde_json::Value,
    /// Whether it came from outside the scene (a network, a replay), so recordings
    /// keep it: the scene's own messages are published again by a replay.
    pub remote: bool,
}

/// The scene's messages: published this tick, to deliver this tick, and subscriptions.
#[derive(Debug, Default)]
pub struct Mailbox {
    /// Published by the script during the current tick.
    published: Vec<Message>,
    /// To deliver in this tick's script phase.
    inbox: Vec<Message>,
    /// Delivered in this tick's script phase (kept for recorders until the next tick).
    delivered: Vec<Message>,
    /// Key expressions subscribed to, in the order of subscription (repeats kept once).
    subscriptions: Vec<String>,
}

impl Mailbox {
    /// Starts a tick: what the script published last tick becomes this tick's inbox, before
    /// any input adds to it.
    pub fn begin_tick(&mut self) {
        self.delivered.clear();
        self.inbox = std::mem::take(&mut self.published);
    }

    /// Publishes a message from the script; delivered at the next tick.
    pub fn publish(&mut self, key: &str, value: serde_json::Value) -> Result<()> {
        check_key(key, false)?;
        self.published.push(Message {
            key: key.to_string(),
            value,
            remote: false,
        });
        Ok(())
    }

    /// Messages the script published during the current tick (an observer sends them).
    pub fn published(&self) -> &[Message] {
        &self.published
    }

    /// Adds messages from an input to this tick's inbox, sorted by key then text so the
    /// order does not depend on how they arrived.
    pub fn deliver(&mut self, mut messages: Vec<Message>) {
        messages.sort_by_cached_key(|m| (m.key.clone(), m.value.to_string()));
        self.inbox
            .extend(messages.into_iter().map(|m| Message { remote: true, ..m }));
    }

    /// Adds messages to this tick's inbox in the order given (a replay, whose order was
    /// sorted when it was recorded).
    pub fn deliver_in_order(&mut self, messages: Vec<Message>) {
        self.inbox
            .extend(messages.into_iter().map(|m| Message { remote: true, ..m }));
    }

    /// Takes this tick's inbox for the script to hand to its subscribers.
    pub fn take_inbox(&mut self) -> Vec<Message> {
        let inbox = std::mem::take(&mut self.inbox);
        self.delivered.extend(inbox.iter().cloned());
        inbox
    }

    /// Messages delivered in this tick's script phase.
    pub fn delivered(&self) -> &[Message] {
        &self.delivered
    }

    /// Subscribes to a key expression (`cue/*`, `cue/**`).
    pub fn subscribe(&mut self, expr: &str) -> Result<()> {
        check_key(expr, true)?;
        if !self.subscriptions.iter().any(|s| s == expr) {
            self.subscriptions.push(expr.to_string());
        }
        Ok(())
    }

    /// Key expressions subscribed to, in order.
    pub fn subscriptions(&self) -> &[String] {
        &self.subscriptions
    }
}

/// Whether `key` is matched by `expr`: chunks separated by `/`, where `*` matches one
/// chunk and `**` any number of chunks (none included), as Zenoh's key expressions.
pub fn key_matches(expr: &str, key: &str) -> bool {
    fn go(e: &[&str], k: &[&str]) -> bool {
        match (e.first(), k.first()) {
            (None, None) => true,
            (Some(&"**"), _) => go(&e[1..], k) || (!k.is_empty() && go(e, &k[1..])),
            (Some(&"*"), Some(_)) => go(&e[1..], &k[1..]),
            (Some(a), Some(b)) => a == b && go(&e[1..], &k[1..]),
            _ => false,
        }
    }
    let e: Vec<&str> = expr.split('/').collect();
    let k: Vec<&str> = key.split('/').collect();
    go(&e, &k)
}

/// Refuses keys Zenoh would refuse: empty chunks, spaces, `$ ? #`; wildcards (`*`, `**`
/// as whole chunks) only in a subscription.
fn check_key(key: &str, wildcards: bool) -> Result<()> {
    let what = if wildcards {
        "subscription"
    } else {
        "message key"
    };
    let bad = |why: &str| Err(Error::Invalid(format!("{what} {key:?}: {why}")));
    if key.is_empty() || key.split('/').any(str::is_empty) {
        return bad("chunks between '/' must not be empty");
    }
    if key.contains(['$', '?', '#']) || key.contains(char::is_whitespace) {
        return bad("no '$', '?', '#' or spaces");
    }
    for chunk in key.split('/') {
        if chunk.contains('*') && !(wildcards && (chunk == "*" || chunk == "**")) {
            return bad(if wildcards {
                "'*' and '**' stand alone between '/'"
            } else {
                "a message is published on one key, without '*'"
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn wildcards_match_as_in_zenoh() {
        assert!(key_matches("cue/start", "cue/start"));
        assert!(!key_matches("cue/start", "cue/stop"));
        assert!(key_matches("cue/*", "cue/start"));
        assert!(!key_matches("cue/*", "cue/a/b"));
        assert!(!key_matches("cue/*", "cue"));
        assert!(key_matches("cue/**", "cue"));
        assert!(key_matches("cue/**", "cue/a/b"));
        assert!(key_matches("**/b", "cue/a/b"));
        assert!(!key_matches("**/b", "cue/a/c"));
    }

    #[test]
    fn bad_keys_are_refused_with_the_key() {
        let mut m = Mailbox::default();
        for bad in ["", "a//b", "/a", "a/", "a b", "a/*", "a$b"] {
            let err = m.publish(bad, json!(1)).unwrap_err().to_string();
            assert!(err.contains(&format!("{bad:?}")), "{err}");
        }
        assert!(m.subscribe("a/*/b/**").is_ok());
        assert!(m.subscribe("a/b*").is_err());
    }

    #[test]
    fn messages_arrive_next_tick_own_first_then_inputs_sorted() {
        let mut m = Mailbox::default();
        m.publish("z/own", json!("first")).unwrap();
        m.publish("a/own", json!("second")).unwrap();
        assert_eq!(m.published().len(), 2);
        m.begin_tick();
        m.deliver(vec![
            Message {
                key: "b".into(),
                value: json!(2),
                remote: true,
            },
            Message {
                key: "a".into(),
                value: json!(9),
                remote: true,
            },
            Message {
                key: "a".into(),
                value: json!(1),
                remote: true,
            },
        ]);
        let keys: Vec<(String, String)> = m
            .take_inbox()
            .into_iter()
            .map(|m| (m.key, m.value.to_string()))
            .collect();
        let want = [
            ("z/own", "\"first\""),
            ("a/own", "\"second\""),
            ("a", "1"),
            ("a", "9"),
            ("b", "2"),
        ];
        assert_eq!(
            keys,
            want.map(|(k, v)| (k.to_string(), v.to_string())).to_vec()
        );
        assert_eq!(m.delivered().len(), 5);
        assert!(m.take_inbox().is_empty(), "delivered once");
        m.begin_tick();
        assert!(m.delivered().is_empty());
    }
}
