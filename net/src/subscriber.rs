//! Reading a published scene back: every actor's postures as they arrive, and the DOF
//! names from the queryable (tools, tests, render nodes).

use crate::error::NetError;
use crate::keys::SceneKeys;
use crate::posture::{self, Posture, PostureError};
use crossbeam::channel::{unbounded, Receiver};
use std::time::Duration;
use zenoh::pubsub::Subscriber;
use zenoh::{Session, Wait};

/// One posture packet as received.
#[derive(Clone, Debug, PartialEq)]
pub struct PoseMessage {
    /// The actor, from the key.
    pub actor: String,
    /// The decoded posture, or why the bytes were refused.
    pub posture: Result<Posture, PostureError>,
}

/// Every actor's postures under one prefix, queued as they arrive.
pub struct PoseFeed {
    _subscriber: Subscriber<()>,
    received: Receiver<PoseMessage>,
}

impl PoseFeed {
    /// Subscribes to `<prefix>/actors/*/pose`.
    pub fn subscribe(session: &Session, keys: &SceneKeys) -> Result<PoseFeed, NetError> {
        let (tx, rx) = unbounded();
        let scene = keys.clone();
        let key = keys.all_poses();
        let subscriber = session
            .declare_subscriber(key.clone())
            .callback(move |sample| {
                let key = sample.key_expr().as_str();
                let Some(actor) = scene.actor_of(key) else {
                    return;
                };
                let bytes = sample.payload().to_bytes();
                let _ = tx.send(PoseMessage {
                    actor: actor.to_string(),
                    posture: posture::decode(&bytes),
                });
            })
            .wait()
            .map_err(|e| NetError::Declare {
                what: "subscriber",
                key,
                message: e.to_string(),
            })?;
        Ok(PoseFeed {
            _subscriber: subscriber,
            received: rx,
        })
    }

    /// The queue of received postures.
    pub fn received(&self) -> &Receiver<PoseMessage> {
        &self.received
    }
}

/// What the scene says about one actor: enough to build it elsewhere.
#[derive(Clone, Debug, PartialEq)]
pub struct ActorBody {
    /// The actor's name.
    pub actor: String,
    /// Its body template.
    pub template: String,
    /// Its height in metres, when the template was scaled.
    pub height: Option<f64>,
    /// Its DOF names, in the order of the posture packets.
    pub dofs: Vec<String>,
}

/// Asks the scene for its actors (`<prefix>/actors/*/dofs`), sorted by name; empty when
/// nobody answered within `timeout`.
pub fn actor_bodies(
    session: &Session,
    keys: &SceneKeys,
    timeout: Duration,
) -> Result<Vec<ActorBody>, NetError> {
    let key = keys.all_dofs();
    let replies = crate::session::query(session, &key, timeout)?;
    let mut out = Vec::new();
    while let Ok(reply) = replies.recv() {
        let Ok(sample) = reply.result() else { continue };
        let doc: serde_json::Value =
            serde_json::from_slice(&sample.payload().to_bytes()).map_err(|e| NetError::Key {
                key: sample.key_expr().to_string(),
                message: format!("an actor description that is not JSON: {e}"),
            })?;
        out.push(ActorBody {
            actor: doc["actor"].as_str().unwrap_or_default().to_string(),
            template: doc["template"].as_str().unwrap_or("adult").to_string(),
            height: doc["height"].as_f64(),
            dofs: doc["dofs"]
                .as_array()
                .map(|a| {
                    a.iter()
                        .filter_map(|d| d.as_str().map(String::from))
                        .collect()
                })
                .unwrap_or_default(),
        });
    }
    out.sort_by(|a, b| a.actor.cmp(&b.actor));
    Ok(out)
}
