//! The options of `reach` and `ik`: what reaches, where to, how, and on which DOFs.

use super::{Reach, ReachSpec, Target};
use crate::error::{OptionError, Result};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::jacobian::{ancestor_dofs, scope_dofs_moving, Effector};
use troupe_body::sensors::Side;
use troupe_body::{Scope, Skeleton};

/// What reaches: a hand (the kind `reach`) or any joint (the kind `ik`).
#[derive(Clone, Debug, PartialEq)]
pub enum Reacher {
    /// The centre of a hand's solid, moved by its wrist; the natural scope is the arm.
    Hand(Side),
    /// A point in a joint's frame; the natural scope is every DOF above the joint,
    /// the root's excepted.
    Joint {
        /// The joint's name.
        name: String,
        /// The point in the joint's frame.
        point: DVec3,
    },
}

/// The options of a reach or an IK action.
#[derive(Clone, Debug, PartialEq)]
pub struct ReachOptions {
    /// What reaches.
    pub effector: Reacher,
    /// Where to.
    pub target: Target,
    /// The orientation of the effector's joint frame at the goal (world).
    pub orientation: Option<DQuat>,
    /// Temporary goals on the way (world points).
    pub via: Vec<DVec3>,
    /// Whether self-collision correction is on.
    pub self_collision: bool,
    /// Whether the effector's path bends round other actors' bodies and obstacles
    /// (temporary goals, 4.6.3) and the arm is kept out of them.
    pub detour: bool,
    /// Seconds to reach the goal.
    pub duration: f64,
    /// The DOFs that may move (those that move the effector are used); `None`: the
    /// effector's natural scope.
    pub scope: Option<Scope>,
}

impl ReachOptions {
    /// Reaches `target` with `effector` in one second, on its natural scope, without
    /// orientation or via points; self-collision correction and detours are on for a hand
    /// and off for a joint.
    pub fn new(effector: Reacher, target: Target) -> ReachOptions {
        let self_collision = matches!(effector, Reacher::Hand(_));
        ReachOptions {
            effector,
            target,
            orientation: None,
            via: Vec::new(),
            self_collision,
            detour: self_collision,
            duration: 1.0,
            scope: None,
        }
    }

    /// The kind of action these options make: `reach` for a hand, `ik` for a joint.
    pub fn kind(&self) -> &'static str {
        match self.effector {
            Reacher::Hand(_) => "reach",
            Reacher::Joint { .. } => "ik",
        }
    }

    /// Checks the options that do not depend on a body.
    pub fn validate(&self) -> Result<(), OptionError> {
        if let Reacher::Joint { point, .. } = &self.effector {
            if !point.is_finite() {
                return Err(OptionError::invalid("point", "a finite point", point));
            }
        }
        if let Some(q) = self.orientation {
            if !q.is_finite() {
                return Err(OptionError::invalid("orientation", "a finite rotation", q));
            }
        }
        check_path(self.duration, &self.via, &self.target)
    }

    /// The reach these options ask of `skeleton`: the effector's joint and point, and the
    /// DOFs of the scope that move it.
    pub fn spec(&self, skeleton: &Skeleton) -> Result<ReachSpec> {
        let (effector, natural) = match &self.effector {
            Reacher::Hand(side) => {
                let wrist = skeleton.joint(&format!("{}wrist", side.prefix()))?;
                let hand = format!("{}hand", side.prefix());
                let point = skeleton
                    .solids()
                    .iter()
                    .find(|(_, s)| s.name == hand)
                    .map(|(_, s)| s.center)
                    .unwrap_or(DVec3::ZERO);
                let arm = skeleton.scope(&format!("{}_arm", side.name()))?;
                (
                    Effector {
                        joint: wrist,
                        point,
                    },
                    arm,
                )
            }
            Reacher::Joint { name, point } => {
                let joint = skeleton.joint(name)?;
                let global = skeleton.scope("global").unwrap_or(Scope::EMPTY);
                let natural = ancestor_dofs(skeleton, joint).difference(&global);
                (
                    Effector {
                        joint,
                        point: *point,
                    },
                    natural,
                )
            }
        };
        let scope = self.scope.unwrap_or(natural);
        let dofs = scope_dofs_moving(skeleton, &scope, effector.joint);
        if dofs.is_empty() {
            return Err(OptionError::refused(
                "scope",
                "the scope has no DOF that moves the effector",
            )
            .into());
        }
        Ok(ReachSpec {
            effector,
            target: self.target.clone(),
            orientation: self.orientation,
            duration: self.duration,
            via: self.via.clone(),
            self_collision: self.self_collision,
            detour: self.detour,
            dofs,
        })
    }

    /// The reach generator for `skeleton`, once the options are valid.
    pub fn reach(&self, skeleton: &Skeleton) -> Result<Reach> {
        self.validate()?;
        Reach::new(skeleton, self.spec(skeleton)?)
    }
}

/// Checks the timing and the path of a reach: a positive duration, finite via points and
/// a finite target point.
pub(super) fn check_path(duration: f64, via: &[DVec3], target: &Target) -> Result<(), OptionError> {
    if !(duration.is_finite() && duration > 0.0) {
        return Err(OptionError::refused(
            "duration",
            format!("duration must be a finite number of seconds > 0, got {duration}"),
        ));
    }
    if via.iter().any(|v| !v.is_finite()) {
        return Err(OptionError::refused("via", "via points must be finite"));
    }
    target.check()
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::template::default_skeleton;

    fn options() -> ReachOptions {
        ReachOptions::new(
            Reacher::Hand(Side::Right),
            Target::Point(DVec3::new(0.3, 1.2, 0.4)),
        )
    }

    fn refused(options: ReachOptions, option: &str) {
        options.validate().expect_err(option).assert_names(option);
    }

    #[test]
    fn good_options_pass() {
        let o = options();
        o.validate().unwrap();
        assert_eq!(o.kind(), "reach");
        let skeleton = default_skeleton("adult").unwrap();
        let spec = o.spec(&skeleton).unwrap();
        assert!(!spec.dofs.is_empty());
        let ik = ReachOptions::new(
            Reacher::Joint {
                name: "l_ankle".into(),
                point: DVec3::ZERO,
            },
            Target::Point(DVec3::new(0.1, 0.2, 0.0)),
        );
        ik.validate().unwrap();
        assert_eq!(ik.kind(), "ik");
        assert!(!ik.self_collision);
        assert!(!ik.spec(&skeleton).unwrap().dofs.is_empty());
    }

    #[test]
    fn each_bad_option_is_named() {
        refused(
            ReachOptions {
                duration: 0.0,
                ..options()
            },
            "duration",
        );
        refused(
            ReachOptions {
                via: vec![DVec3::NAN],
                ..options()
            },
            "via",
        );
        refused(
            ReachOptions {
                target: Target::Point(DVec3::INFINITY),
                ..options()
            },
            "target",
        );
        refused(
            ReachOptions {
                orientation: Some(DQuat::from_xyzw(f64::NAN, 0.0, 0.0, 1.0)),
                ..options()
            },
            "orientation",
        );
        refused(
            ReachOptions {
                effector: Reacher::Joint {
                    name: "l_ankle".into(),
                    point: DVec3::NAN,
                },
                ..options()
            },
            "point",
        );
    }

    #[test]
    fn a_scope_that_cannot_move_the_effector_is_refused() {
        let skeleton = default_skeleton("adult").unwrap();
        let o = ReachOptions {
            scope: Some(skeleton.scope("left_arm").unwrap()),
            ..options()
        };
        let e = o.spec(&skeleton).expect_err("refused");
        assert!(e.to_string().contains("no DOF that moves"), "{e}");
    }
}
