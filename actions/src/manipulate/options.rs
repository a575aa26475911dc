//! The options of `manipulate`: which held object, and the keys it moves through.

use super::{Manipulate, ObjectKey};
use crate::error::{OptionError, Result};
use crate::grasp::action::holding_side;
use troupe_body::sensors::Side;
use troupe_body::Scope;
use troupe_scene::Scene;

/// The options of a manipulation.
#[derive(Clone, Debug, PartialEq)]
pub struct ManipulateOptions {
    /// The held object's index in the scene.
    pub object: usize,
    /// Where it goes, key by key.
    pub keys: Vec<ObjectKey>,
}

impl ManipulateOptions {
    /// Checks the keys: at least one, finite, at times ≥ 0 in increasing order.
    pub fn validate(&self) -> Result<(), OptionError> {
        check_keys(&self.keys)
    }

    /// The manipulate generator for `actor` of `scene` and the DOFs it drives: the arm
    /// of the hand that holds the object (the right one when none does: the action then
    /// fails at its start, saying so).
    pub fn manipulate(&self, scene: &Scene, actor: usize) -> Result<(Manipulate, Scope)> {
        let side = holding_side(scene, actor, self.object).unwrap_or(Side::Right);
        let scope = scene.actors()[actor]
            .skeleton
            .scope(&format!("{}_arm", side.name()))?;
        let manipulate = Manipulate::new(self.object, self.keys.clone(), vec![side])?;
        Ok((manipulate, scope))
    }
}

/// Refuses keys that are absent, not finite, before time 0 or out of order.
pub(super) fn check_keys(keys: &[ObjectKey]) -> Result<(), OptionError> {
    if keys.is_empty() {
        return Err(OptionError::refused(
            "keys",
            "`keys` needs at least one key",
        ));
    }
    for (i, k) in keys.iter().enumerate() {
        if !(k.time.is_finite() && k.time >= 0.0 && k.position.is_finite()) {
            return Err(OptionError::refused(
                "keys",
                format!("key {}: time and position must be finite (time ≥ 0)", i + 1),
            ));
        }
        if i > 0 && k.time <= keys[i - 1].time {
            return Err(OptionError::refused(
                "keys",
                format!(
                    "key {}: times must increase (got {} after {})",
                    i + 1,
                    k.time,
                    keys[i - 1].time
                ),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::glam::DVec3;

    fn key(time: f64, x: f64) -> ObjectKey {
        ObjectKey {
            time,
            position: DVec3::new(x, 1.0, 0.3),
            rotation: None,
        }
    }

    fn refused(keys: Vec<ObjectKey>, needle: &str) {
        let e = ManipulateOptions { object: 0, keys }
            .validate()
            .expect_err(needle);
        assert_eq!(e.option(), "keys");
        assert!(e.to_string().contains(needle), "{e}");
    }

    #[test]
    fn increasing_finite_keys_pass() {
        let keys = vec![key(0.5, 0.1), key(1.0, 0.2)];
        ManipulateOptions { object: 0, keys }.validate().unwrap();
    }

    #[test]
    fn bad_keys_are_refused_naming_them() {
        refused(vec![], "at least one key");
        refused(vec![key(-1.0, 0.0)], "key 1");
        refused(vec![key(0.5, f64::NAN)], "key 1");
        refused(
            vec![key(0.5, 0.0), key(0.5, 0.1)],
            "key 2: times must increase",
        );
    }
}
