//! `--record-messages` and `--replay-messages` on `troupe run`: the messages a scene
//! received from outside (`troupe.subscribe`), kept so a replay sees them at the same
//! ticks (format in docs/distributed.md).

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use troupe_lua::LuaSession;
use troupe_scene::message_log::{MessageRecorder, MessageReplay};

/// Options for recording and replaying received messages.
#[derive(Args, Clone, Debug, Default)]
pub struct MessageArgs {
    /// Write the messages received from outside, with the tick that saw each, to
    /// FILE.jsonl (one JSON document per line).
    #[arg(long, value_name = "FILE.jsonl")]
    pub record_messages: Option<PathBuf>,
    /// Deliver the messages of a --record-messages file at their recorded ticks.
    #[arg(long, value_name = "FILE.jsonl")]
    pub replay_messages: Option<PathBuf>,
}

impl MessageArgs {
    /// The replay, read before the scene loads so a malformed file is refused first.
    pub fn replay(&self) -> Result<Option<MessageReplay>> {
        self.replay_messages
            .as_deref()
            .map(|p| MessageReplay::read(p).context("--replay-messages"))
            .transpose()
    }

    /// Attaches the replay (an input) and the recorder (an observer) to a session.
    pub fn attach(&self, session: &mut LuaSession, replay: Option<MessageReplay>) {
        if let Some(replay) = replay {
            session.add_input(Box::new(replay));
        }
        if let Some(path) = &self.record_messages {
            session.observe(MessageRecorder::new(path));
        }
    }
}
