//! The options of `simulate`, `servo` and `track`: what drives the simulated DOFs, the
//! simulation's parameters, an optional push, and which DOFs are simulated.

use super::{Drive, DynamicsGenerator, ServoTarget};
use crate::error::{track_dofs, OptionError, Result};
use troupe_body::dynamics::{Gains, SimParams};
use troupe_body::glam::DVec3;
use troupe_body::{Scope, Skeleton};

/// The strongest push (N): ten times a car crash's force, which already throws a body
/// across the room in a tenth of a second. Stronger pushes diverge within a step, or
/// overflow the solve and are misreported as a lost inertia.
pub const MAX_PUSH_FORCE: f64 = 1e6;

/// The strongest turning push (N·m), on the same grounds as [`MAX_PUSH_FORCE`].
pub const MAX_PUSH_TORQUE: f64 = 1e6;

/// The length of `v`, without overflow for huge components (glam's squares them).
fn magnitude(v: DVec3) -> f64 {
    let largest = v.abs().max_element();
    if largest > 0.0 && largest.is_finite() {
        largest * (v / largest).length()
    } else {
        largest
    }
}

/// A force and a torque applied at the centre of mass from the start of a `simulate`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Push {
    /// Force (N, world).
    pub force: DVec3,
    /// Torque (N·m, world).
    pub torque: DVec3,
    /// Seconds it lasts.
    pub duration: f64,
}

/// The options of a dynamics action.
#[derive(Clone, Debug)]
pub struct DynamicsOptions {
    /// What drives the simulated DOFs (and so the kind: `simulate`, `servo`, `track`).
    pub drive: Drive,
    /// The simulation's parameters (time steps, gravity, floor, limits, damping).
    pub params: SimParams,
    /// A push at the start (`simulate` only).
    pub push: Option<Push>,
    /// Whether the action ends once the body has stayed still for half a second.
    pub finish_at_rest: bool,
}

impl DynamicsOptions {
    /// Options for `drive` with the defaults of its kind: a passive simulation is damped
    /// (2 per second) and ends at rest; servos and tracking are undamped and run until
    /// stopped (tracking: until the sequence ends).
    pub fn new(drive: Drive) -> DynamicsOptions {
        let passive = matches!(drive, Drive::Passive);
        DynamicsOptions {
            drive,
            params: SimParams {
                damping: if passive { 2.0 } else { 0.0 },
                ..SimParams::default()
            },
            push: None,
            finish_at_rest: passive,
        }
    }

    /// The kind of action these options make.
    pub fn kind(&self) -> &'static str {
        match self.drive {
            Drive::Passive => "simulate",
            Drive::Servo { .. } => "servo",
            Drive::Track { .. } => "track",
        }
    }

    /// Checks the options that do not depend on a body: the simulation's parameters and
    /// the gains (the body model's errors name the parameter), the push, a posture's
    /// values.
    pub fn validate(&self) -> Result<()> {
        self.params.validate()?;
        match &self.drive {
            Drive::Passive => {}
            Drive::Servo { target, gains, .. } => {
                gains.validate()?;
                if let ServoTarget::Posture(values) = target {
                    if let Some((k, v)) = values.iter().find(|(_, v)| !v.is_finite()) {
                        return Err(OptionError::invalid(
                            "target",
                            format!("finite values (DOF #{k})"),
                            v,
                        )
                        .into());
                    }
                }
            }
            Drive::Track { gains, .. } => gains.validate()?,
        }
        if let Some(push) = &self.push {
            if !(push.duration.is_finite() && push.duration >= 0.0) {
                return Err(OptionError::refused("push", "push.duration must be ≥ 0").into());
            }
            let (force, torque) = (magnitude(push.force), magnitude(push.torque));
            let within = |v: f64, most: f64| v.is_finite() && v <= most;
            if !(within(force, MAX_PUSH_FORCE) && within(torque, MAX_PUSH_TORQUE)) {
                return Err(OptionError::refused(
                    "push",
                    format!(
                        "push.force must be at most {MAX_PUSH_FORCE:e} N and push.torque at most \
                         {MAX_PUSH_TORQUE:e} N·m, got {force:e} N and {torque:e} N·m"
                    ),
                )
                .into());
            }
        }
        Ok(())
    }

    /// The DOFs the action simulates: `asked` or the drive's natural scope (a passive
    /// simulation: the whole body; a posture servo: the DOFs it names; an actor servo:
    /// the body without the root; tracking: the sequence's DOFs), the root always left
    /// out of tracking.
    pub fn scope(&self, skeleton: &Skeleton, asked: Option<Scope>) -> Result<Scope> {
        let root = Scope::range(skeleton.joints()[0].dofs.clone());
        let body = skeleton
            .scope("body")
            .unwrap_or_else(|_| skeleton.all().difference(&root));
        let scope = match &self.drive {
            Drive::Passive => asked.unwrap_or_else(|| skeleton.all()),
            Drive::Servo {
                target: ServoTarget::Posture(values),
                ..
            } => {
                let named: Scope = values.iter().map(|(k, _)| *k).collect();
                if named.is_empty() && asked.is_none() {
                    return Err(OptionError::refused(
                        "target",
                        "the target names no DOF (give some, or a `scope` to hold)",
                    )
                    .into());
                }
                if !named.is_empty() && !named.overlaps(&body) {
                    return Err(OptionError::refused(
                        "target",
                        "the target names only root DOFs, and the root is never servoed",
                    )
                    .into());
                }
                // Servoing DOFs the target does not name holds them where they are: a
                // scope with none of the target's DOFs would ignore the target.
                if let Some(asked) = asked {
                    if !named.is_empty() && !asked.overlaps(&named.intersection(&body)) {
                        return Err(OptionError::refused(
                            "scope",
                            "the scope holds none of the target's DOFs (root excluded)",
                        )
                        .into());
                    }
                }
                asked.unwrap_or_else(|| named.intersection(&body))
            }
            Drive::Servo { .. } => asked.unwrap_or(body),
            Drive::Track { sequence, .. } => {
                let natural: Scope = track_dofs(skeleton, sequence, "sequence")?
                    .into_iter()
                    .collect();
                // Like a servo's, a scope beyond the tracks holds those DOFs, but one
                // with none of them would track nothing.
                let tracked = asked.map_or(natural, |a| a.intersection(&natural));
                if tracked.difference(&root).is_empty() {
                    return Err(OptionError::refused(
                        "scope",
                        "nothing to track (the sequence's DOFs on the scope, root excluded)",
                    )
                    .into());
                }
                asked.unwrap_or(natural).difference(&root)
            }
        };
        if !matches!(self.drive, Drive::Passive)
            && !scope.is_empty()
            && scope.difference(&root).is_empty()
        {
            return Err(OptionError::refused(
                "scope",
                "the scope holds only root DOFs, and the root is never servoed",
            )
            .into());
        }
        Ok(scope)
    }

    /// The generator for `skeleton` on `scope`, once the options are valid.
    pub fn generator(&self, skeleton: &Skeleton, scope: Scope) -> Result<DynamicsGenerator> {
        DynamicsGenerator::new(skeleton, self, scope)
    }
}

/// The gains of a servo or a tracker: `kp` alone sets `kd` to its critical damping.
pub fn gains(kp: Option<f64>, kd: Option<f64>) -> Gains {
    let mut g = Gains::default();
    if let Some(kp) = kp {
        g.kp = kp;
        g.kd = 2.0 * kp.max(0.0).sqrt();
    }
    if let Some(kd) = kd {
        g.kd = kd;
    }
    g
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;
    use troupe_body::template::default_skeleton;
    use troupe_motion::{Key, Sequence, Track};

    fn servo(values: Vec<(usize, f64)>, gains: Gains) -> DynamicsOptions {
        DynamicsOptions::new(Drive::Servo {
            target: ServoTarget::Posture(values),
            gains,
            gravity_compensation: true,
        })
    }

    fn refused(options: DynamicsOptions, needle: &str) {
        let e = options.validate().expect_err(needle);
        assert!(e.to_string().contains(needle), "{e}");
    }

    #[test]
    fn the_defaults_of_each_kind_pass() {
        let simulate = DynamicsOptions::new(Drive::Passive);
        simulate.validate().unwrap();
        assert_eq!(simulate.kind(), "simulate");
        assert!(simulate.finish_at_rest);
        assert_eq!(simulate.params.damping, 2.0);
        let s = servo(vec![(7, 0.5)], gains(Some(100.0), None));
        s.validate().unwrap();
        assert_eq!(s.kind(), "servo");
        assert_eq!(gains(Some(100.0), None).kd, 20.0);
    }

    #[test]
    fn each_bad_option_is_refused_naming_it() {
        refused(servo(vec![(7, 0.5)], gains(Some(-1.0), None)), "kp");
        refused(servo(vec![(7, 0.5)], gains(None, Some(f64::NAN))), "kd");
        refused(servo(vec![(7, f64::INFINITY)], Gains::default()), "target");
        let mut damped = DynamicsOptions::new(Drive::Passive);
        damped.params.damping = -1.0;
        refused(damped, "damping");
        let mut stepped = DynamicsOptions::new(Drive::Passive);
        stepped.params.time_step = 0.0;
        refused(stepped, "time_step");
        let pushed = DynamicsOptions {
            push: Some(Push {
                force: DVec3::X,
                torque: DVec3::ZERO,
                duration: -0.1,
            }),
            ..DynamicsOptions::new(Drive::Passive)
        };
        refused(pushed, "push");
    }

    #[test]
    fn tracking_only_the_root_is_refused() {
        let skeleton = default_skeleton("adult").unwrap();
        let mut seq = Sequence::new("slide");
        let keys = vec![Key::new(0.0, 0.0), Key::new(1.0, 1.0)];
        seq.add_track(Track::new("root_x", keys).unwrap()).unwrap();
        let track = DynamicsOptions::new(Drive::Track {
            sequence: Arc::new(seq),
            gains: Gains::default(),
        });
        track.validate().unwrap();
        let e = track.scope(&skeleton, None).expect_err("refused");
        assert!(e.to_string().contains("nothing to track"), "{e}");
    }

    #[test]
    fn a_scope_with_none_of_the_tracks_is_refused() {
        let skeleton = default_skeleton("adult").unwrap();
        let mut seq = Sequence::new("bend");
        let keys = vec![Key::new(0.0, 0.5), Key::new(1.0, 1.2)];
        seq.add_track(Track::new("r_elbow_flexion", keys).unwrap())
            .unwrap();
        let track = DynamicsOptions::new(Drive::Track {
            sequence: Arc::new(seq),
            gains: Gains::default(),
        });
        let head = skeleton.scope("head").unwrap();
        let e = track.scope(&skeleton, Some(head)).expect_err("refused");
        assert!(e.to_string().contains("nothing to track"), "{e}");
        let arm = skeleton.scope("right_arm").unwrap();
        assert_eq!(track.scope(&skeleton, Some(arm)).unwrap(), arm);
    }

    #[test]
    fn a_servo_of_the_root_or_beside_its_target_is_refused_saying_why() {
        let skeleton = default_skeleton("adult").unwrap();
        let root_x = skeleton.dof("root_x").unwrap();
        let e = servo(vec![(root_x, 0.5)], Gains::default())
            .scope(&skeleton, None)
            .expect_err("refused");
        assert!(e.to_string().contains("root is never servoed"), "{e}");
        let elbow = skeleton.dof("r_elbow_flexion").unwrap();
        let head = skeleton.scope("head").unwrap();
        let e = servo(vec![(elbow, 0.5)], Gains::default())
            .scope(&skeleton, Some(head))
            .expect_err("refused");
        assert!(e.to_string().contains("none of the target's DOFs"), "{e}");
        let root = Scope::range(skeleton.joints()[0].dofs.clone());
        let follow = DynamicsOptions::new(Drive::Servo {
            target: ServoTarget::Actor(1),
            gains: Gains::default(),
            gravity_compensation: true,
        });
        let e = follow.scope(&skeleton, Some(root)).expect_err("refused");
        assert!(e.to_string().contains("root is never servoed"), "{e}");
        let arm = skeleton.scope("right_arm").unwrap();
        assert_eq!(follow.scope(&skeleton, Some(arm)).unwrap(), arm);
    }
}
