//! The key expressions a published scene uses, all under one prefix (`troupe/NAME`):
//!
//! | key | what | encoding |
//! |---|---|---|
//! | `<prefix>/actors/<actor>/pose` | the actor's posture, every tick | binary ([`crate::posture`]) |
//! | `<prefix>/actors/<actor>/dofs` | queryable: the actor's template and DOF names | JSON |
//! | `<prefix>/objects/<object>` | the object's pose, every tick | JSON |
//! | `<prefix>/events` | action events (started, completed, cancelled, failed) | JSON |
//! | `<prefix>/messages` | behavior messages: what the scene's `troupe.publish` sent, with its tick | JSON |
//! | `<prefix>/scene` | queryable: layout version, rate, seed, actor and object names | JSON |
//! | `<prefix>/inputs` | each tick's inputs from outside, for followers: `u64` tick, then `.rec` chunks | binary |
//! | `<prefix>/followers/<id>` | a follower's hello, once it has subscribed | empty |

use crate::error::NetError;
use zenoh::key_expr::KeyExpr;

/// The keys of one published scene.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneKeys {
    prefix: String,
}

impl SceneKeys {
    /// Keys under `prefix`, which must be a Zenoh key expression without wildcards.
    pub fn new(prefix: &str) -> Result<SceneKeys, NetError> {
        let key = KeyExpr::try_from(prefix.to_string()).map_err(|e| NetError::Key {
            key: prefix.to_string(),
            message: e.to_string(),
        })?;
        if key.is_wild() || prefix.contains(['$', '?', '#']) {
            return Err(NetError::Key {
                key: prefix.to_string(),
                message: "a prefix names one scene: no wildcards (*, **, $*)".into(),
            });
        }
        Ok(SceneKeys {
            prefix: prefix.to_string(),
        })
    }

    /// The prefix.
    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    /// Where `actor`'s postures are published.
    pub fn pose(&self, actor: &str) -> Result<String, NetError> {
        Ok(format!("{}/actors/{}/pose", self.prefix, chunk(actor)?))
    }

    /// Where `actor`'s DOF names are served.
    pub fn dofs(&self, actor: &str) -> Result<String, NetError> {
        Ok(format!("{}/actors/{}/dofs", self.prefix, chunk(actor)?))
    }

    /// Every actor's postures (a subscriber's key expression).
    pub fn all_poses(&self) -> String {
        format!("{}/actors/*/pose", self.prefix)
    }

    /// Every actor's DOF names (a query's key expression).
    pub fn all_dofs(&self) -> String {
        format!("{}/actors/*/dofs", self.prefix)
    }

    /// Where `object`'s pose is published.
    pub fn object(&self, object: &str) -> Result<String, NetError> {
        Ok(format!("{}/objects/{}", self.prefix, chunk(object)?))
    }

    /// Where action events are published.
    pub fn events(&self) -> String {
        format!("{}/events", self.prefix)
    }

    /// Where the behaviors' messages (`troupe.publish`) are published with their tick.
    pub fn messages(&self) -> String {
        format!("{}/messages", self.prefix)
    }

    /// Where each tick's inputs are published for followers.
    pub fn inputs(&self) -> String {
        format!("{}/inputs", self.prefix)
    }

    /// Where followers say hello (`<prefix>/followers/<id>`), once subscribed.
    pub fn followers(&self) -> String {
        format!("{}/followers/*", self.prefix)
    }

    /// Where the scene's description is served.
    pub fn scene(&self) -> String {
        format!("{}/scene", self.prefix)
    }

    /// The actor name in a pose or dofs key of this scene (`None` for other keys).
    pub fn actor_of<'k>(&self, key: &'k str) -> Option<&'k str> {
        let rest = key.strip_prefix(&self.prefix)?.strip_prefix("/actors/")?;
        let (name, tail) = rest.split_once('/')?;
        matches!(tail, "pose" | "dofs").then_some(name)
    }
}

/// A name as one key chunk: refused when it would be read as several chunks or a
/// wildcard, so one actor's key never matches another's.
fn chunk(name: &str) -> Result<&str, NetError> {
    let bad = name.is_empty()
        || name.contains(['/', '*', '$', '?', '#'])
        || name.contains(char::is_whitespace);
    if bad {
        return Err(NetError::Key {
            key: name.to_string(),
            message: "an actor or object name in a key has no '/', '*', '$', '?', '#' or spaces"
                .into(),
        });
    }
    Ok(name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_are_built_under_the_prefix_and_read_back() {
        let keys = SceneKeys::new("troupe/stage").unwrap();
        assert_eq!(keys.pose("ann").unwrap(), "troupe/stage/actors/ann/pose");
        assert_eq!(keys.dofs("ann").unwrap(), "troupe/stage/actors/ann/dofs");
        assert_eq!(keys.object("cup").unwrap(), "troupe/stage/objects/cup");
        assert_eq!(keys.events(), "troupe/stage/events");
        assert_eq!(keys.messages(), "troupe/stage/messages");
        assert_eq!(keys.actor_of("troupe/stage/actors/ann/pose"), Some("ann"));
        assert_eq!(keys.actor_of("troupe/other/actors/ann/pose"), None);
        assert_eq!(keys.actor_of("troupe/stage/objects/cup"), None);
    }

    #[test]
    fn wildcard_prefixes_and_names_are_refused() {
        for bad in ["troupe/*", "troupe/**", "", "troupe//x", "/troupe"] {
            assert!(SceneKeys::new(bad).is_err(), "{bad:?} accepted");
        }
        let keys = SceneKeys::new("troupe/stage").unwrap();
        for bad in ["a/b", "*", "", "two words", "$*"] {
            assert!(keys.pose(bad).is_err(), "{bad:?} accepted");
        }
    }
}
