//! Recording the messages a scene received from outside, and replaying them at the same
//! ticks: `troupe run --record-messages FILE.jsonl` and `--replay-messages FILE.jsonl`.
//!
//! One JSON document per line, in delivery order: `{"tick":N,"key":"…","value":…}`, where
//! `tick` is the tick whose script phase saw the message. The scene's own messages are not
//! recorded: a replay publishes them again.

use crate::action::Event;
use crate::error::{Error, Result};
use crate::mailbox::Message;
use crate::scene::Scene;
use crate::session::{Input, Observer};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Records the messages from outside as they are delivered (an observer).
pub struct MessageRecorder {
    path: PathBuf,
    lines: Vec<String>,
}

impl MessageRecorder {
    /// Records to `path`, written when the run finishes.
    pub fn new(path: &Path) -> Self {
        MessageRecorder {
            path: path.to_path_buf(),
            lines: Vec::new(),
        }
    }
}

impl Observer for MessageRecorder {
    fn name(&self) -> String {
        format!("--record-messages {}", self.path.display())
    }

    fn publish(&mut self, scene: &Scene, _events: &[Event]) -> Result<()> {
        for m in scene.mailbox().delivered().iter().filter(|m| m.remote) {
            let line = json!({"tick": scene.tick(), "key": m.key, "value": m.value});
            self.lines.push(line.to_string());
        }
        Ok(())
    }

    fn finish(&mut self, _scene: &Scene) -> Result<Option<String>> {
        let mut text = self.lines.join("\n");
        if !text.is_empty() {
            text.push('\n');
        }
        std::fs::write(&self.path, text)
            .map_err(|e| Error::Invalid(format!("writing {}: {e}", self.path.display())))?;
        Ok(Some(format!(
            "recorded {} message(s) to {}",
            self.lines.len(),
            self.path.display()
        )))
    }
}

/// Delivers recorded messages at the ticks they were delivered in the recorded run (an
/// input).
pub struct MessageReplay {
    name: String,
    /// (tick, message), in file order.
    messages: Vec<(u64, Message)>,
    next: usize,
}

impl MessageReplay {
    /// Reads a recording; a malformed line is refused with its file and line number.
    pub fn read(path: &Path) -> Result<MessageReplay> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| Error::Invalid(format!("reading {}: {e}", path.display())))?;
        MessageReplay::parse(&text, &path.display().to_string())
    }

    /// Reads recorded lines; `name` names the source in errors.
    pub fn parse(text: &str, name: &str) -> Result<MessageReplay> {
        let mut messages = Vec::new();
        for (i, line) in text.lines().enumerate() {
            if line.trim().is_empty() {
                continue;
            }
            let bad = |why: String| Error::Invalid(format!("{name}:{}: {why}", i + 1));
            let doc: Value = serde_json::from_str(line).map_err(|e| bad(e.to_string()))?;
            let tick = doc["tick"]
                .as_u64()
                .ok_or_else(|| bad("no \"tick\" (a whole number)".into()))?;
            let key = doc["key"]
                .as_str()
                .ok_or_else(|| bad("no \"key\" (a string)".into()))?;
            if messages
                .last()
                .is_some_and(|(t, _): &(u64, Message)| *t > tick)
            {
                return Err(bad(format!("tick {tick} comes after a later tick")));
            }
            messages.push((
                tick,
                Message {
                    key: key.to_string(),
                    value: doc.get("value").cloned().unwrap_or(Value::Null),
                    remote: true,
                },
            ));
        }
        Ok(MessageReplay {
            name: name.to_string(),
            messages,
            next: 0,
        })
    }
}

impl Input for MessageReplay {
    fn name(&self) -> String {
        format!("--replay-messages {}", self.name)
    }

    fn poll(&mut self, scene: &mut Scene) -> Result<()> {
        // The coming tick's script phase sees what was recorded at that tick; the recorded
        // order is the delivered order, so it is kept as it is.
        let tick = scene.tick() + 1;
        let start = self.next;
        while self
            .messages
            .get(self.next)
            .is_some_and(|(t, _)| *t <= tick)
        {
            self.next += 1;
        }
        let due: Vec<Message> = self.messages[start..self.next]
            .iter()
            .map(|(_, m)| m.clone())
            .collect();
        scene.mailbox_mut().deliver_in_order(due);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::SceneConfig;
    use crate::session::Session;

    #[test]
    fn malformed_lines_are_named() {
        let err = MessageReplay::parse("{\"tick\":1,\"key\":\"a\"}\nnot json\n", "m.jsonl")
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("m.jsonl:2"), "{err}");
        let err = MessageReplay::parse("{\"key\":\"a\"}", "m.jsonl")
            .err()
            .unwrap()
            .to_string();
        assert!(err.contains("m.jsonl:1: no \"tick\""), "{err}");
        let err = MessageReplay::parse(
            "{\"tick\":3,\"key\":\"a\"}\n{\"tick\":2,\"key\":\"b\"}",
            "m",
        )
        .err()
        .unwrap()
        .to_string();
        assert!(err.contains("m:2"), "{err}");
    }

    /// Delivers given messages at given ticks, as a network input would.
    struct Arrivals(Vec<(u64, Message)>);
    impl Input for Arrivals {
        fn name(&self) -> String {
            "arrivals".into()
        }
        fn poll(&mut self, scene: &mut Scene) -> Result<()> {
            let now = scene.tick() + 1;
            let due = self
                .0
                .iter()
                .filter(|(t, _)| *t == now)
                .map(|(_, m)| m.clone());
            scene.mailbox_mut().deliver(due.collect());
            Ok(())
        }
    }

    /// Takes every inbox as a script would, noting (tick, key) of what it saw.
    #[derive(Default)]
    struct Reader(Vec<(u64, String, String)>);
    impl crate::session::Script for Reader {
        fn run(&mut self, scene: &mut Scene) {
            let tick = scene.tick() + 1;
            for m in scene.mailbox_mut().take_inbox() {
                self.0.push((tick, m.key, m.value.to_string()));
            }
        }
    }

    #[test]
    fn a_replay_delivers_the_recorded_messages_at_the_same_ticks() {
        let dir = std::env::temp_dir().join(format!("troupe-msglog-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.jsonl");
        let msg = |k: &str, v: i64| Message {
            key: k.into(),
            value: json!(v),
            remote: true,
        };
        let scene = || Scene::new(SceneConfig::default()).unwrap();
        let mut live = Session::with_script(scene(), Reader::default());
        live.add_input(Box::new(Arrivals(vec![
            (2, msg("b", 1)),
            (2, msg("a", 2)),
            (5, msg("c", 3)),
        ])));
        live.observe(MessageRecorder::new(&path));
        for _ in 0..6 {
            live.tick().unwrap();
        }
        live.finish().unwrap();
        let seen = live.script().0.clone();
        assert_eq!(
            seen.iter()
                .map(|(t, k, _)| (*t, k.as_str()))
                .collect::<Vec<_>>(),
            vec![(2, "a"), (2, "b"), (5, "c")]
        );
        let mut replay = Session::with_script(scene(), Reader::default());
        replay.add_input(Box::new(MessageReplay::read(&path).unwrap()));
        for _ in 0..6 {
            replay.tick().unwrap();
        }
        assert_eq!(replay.script().0, seen);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
