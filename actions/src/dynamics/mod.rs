//! Dynamics generators (thesis chapter 3): `simulate` (passive forward dynamics, e.g.
//! falling), `servo` (PD servos toward a posture or another actor's posture, fig. 3-7) and
//! `track` (closed-loop tracking of a sequence with inverse dynamics, fig. 3-4).
//!
//! Each action runs its own [`Simulation`] of the whole body, started from the actor's
//! posture: the DOFs of its scope are integrated from forces, the others are prescribed
//! and follow the actor's posture tick by tick (an arm servo moves on a body that other
//! actions place). The root is simulated as a floating base only by `simulate`, and only
//! when the scope holds all six root DOFs; `servo` and `track` never move the root.

#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod options;
pub mod torque_recorder;

pub use options::{DynamicsOptions, Push};
pub use torque_recorder::TorqueRecorder;

use crate::error::{track_dofs, Result};
use std::sync::Arc;
use troupe_body::dynamics::{Control, Gains, SimParams, Simulation};
use troupe_body::{Scope, Skeleton};
use troupe_motion::Sequence;
use troupe_scene::{DofWriter, Generator, GeneratorContext, Note, StartError, Step};

/// What a servo follows.
#[derive(Clone, Debug, PartialEq)]
pub enum ServoTarget {
    /// Fixed desired values (DOF index, value); other DOFs keep their starting value.
    Posture(Vec<(usize, f64)>),
    /// Another actor's posture (and velocities), read each tick.
    Actor(usize),
}

/// What drives a dynamics action's simulated DOFs.
#[derive(Clone, Debug)]
pub enum Drive {
    /// Nothing: gravity, contact, limits and damping only.
    Passive,
    /// PD servos (eq. 4-1) toward a target.
    Servo {
        /// The target.
        target: ServoTarget,
        /// Gains per unit inertia.
        gains: Gains,
        /// Add the inverse-dynamics gravity torques.
        gravity_compensation: bool,
    },
    /// Closed-loop tracking of a sequence.
    Track {
        /// The sequence.
        sequence: Arc<Sequence>,
        /// Gains per unit inertia.
        gains: Gains,
    },
}

/// A dynamics action's generator.
pub struct DynamicsGenerator {
    drive: Drive,
    scope: Scope,
    params: SimParams,
    push: Option<Push>,
    finish_at_rest: bool,
    sim: Option<Simulation>,
    tracks: Vec<(usize, usize)>,
    desired: Vec<f64>,
    desired_qd: Vec<f64>,
    desired_qdd: Vec<f64>,
    at_rest_for: f64,
}

impl DynamicsGenerator {
    /// A generator simulating `scope` as `options` ask, once they are valid.
    pub fn new(
        skeleton: &Skeleton,
        options: &DynamicsOptions,
        scope: Scope,
    ) -> Result<DynamicsGenerator> {
        options.validate()?;
        let DynamicsOptions {
            drive,
            params,
            push,
            finish_at_rest,
        } = options.clone();
        let mut tracks = Vec::new();
        if let Drive::Track { sequence, .. } = &drive {
            let dofs = track_dofs(skeleton, sequence, "sequence")?;
            tracks.extend(dofs.into_iter().enumerate().map(|(i, d)| (d, i)));
        }
        let n = skeleton.dof_count();
        Ok(DynamicsGenerator {
            drive,
            scope,
            params,
            push,
            finish_at_rest,
            sim: None,
            tracks,
            desired: vec![0.0; n],
            desired_qd: vec![0.0; n],
            desired_qdd: vec![0.0; n],
            at_rest_for: 0.0,
        })
    }

    fn fill_desired(&mut self, ctx: &GeneratorContext) -> Result<(), String> {
        let posture = ctx.posture;
        match &self.drive {
            Drive::Passive => {}
            Drive::Servo { target, .. } => match target {
                ServoTarget::Posture(_) => {}
                ServoTarget::Actor(i) => {
                    let state = ctx
                        .world
                        .states
                        .get(*i)
                        .ok_or_else(|| format!("servo: no actor #{i}"))?;
                    for k in 0..self.desired.len() {
                        if self.scope.contains(k) {
                            self.desired[k] = state.q[k];
                            self.desired_qd[k] = state.qd[k];
                        }
                    }
                }
            },
            Drive::Track { sequence, .. } => {
                let t = sequence.start() + ctx.local_time.min(sequence.duration());
                let h = 1e-3;
                for &(k, i) in &self.tracks {
                    let track = &sequence.tracks()[i];
                    self.desired[k] = track.value(t);
                    self.desired_qd[k] = track.velocity(t);
                    self.desired_qdd[k] =
                        (track.velocity(t + h) - track.velocity(t - h)) / (2.0 * h);
                }
            }
        }
        // DOFs outside the scope are prescribed from the actor's posture.
        if let Some(sim) = &mut self.sim {
            for k in 0..posture.q.len() {
                if sim.is_prescribed(k) {
                    sim.set_prescribed(k, posture.q[k], posture.qd[k]);
                }
            }
        }
        Ok(())
    }
}

impl Generator for DynamicsGenerator {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        let n = ctx.skeleton.dof_count();
        let root = ctx.skeleton.joints()[0].dofs.clone();
        let dynamic: Vec<bool> = (0..n)
            .map(|k| {
                self.scope.contains(k)
                    && (matches!(self.drive, Drive::Passive) || !root.contains(&k))
            })
            .collect();
        let mut sim = Simulation::new(
            ctx.skeleton,
            &ctx.posture.q,
            &ctx.posture.qd,
            &dynamic,
            self.params,
        )
        .map_err(|e| e.to_string())?;
        if let Some(p) = self.push {
            sim.push(p.force, p.torque, p.duration);
        }
        self.desired.copy_from_slice(&ctx.posture.q);
        if let Drive::Servo {
            target: ServoTarget::Posture(values),
            ..
        } = &self.drive
        {
            for &(k, v) in values {
                self.desired[k] = v;
            }
        }
        self.sim = Some(sim);
        Ok(())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        if let Err(e) = self.fill_desired(ctx) {
            return Step::Failed(e);
        }
        let Some(sim) = &mut self.sim else {
            return Step::Failed("dynamics: not started".into());
        };
        let control = match &self.drive {
            Drive::Passive => Control::Passive,
            Drive::Servo {
                gains,
                gravity_compensation,
                ..
            } => Control::Servo {
                q: &self.desired,
                qd: &self.desired_qd,
                gains: *gains,
                gravity_compensation: *gravity_compensation,
            },
            Drive::Track { gains, .. } => Control::Track {
                q: &self.desired,
                qd: &self.desired_qd,
                qdd: &self.desired_qdd,
                gains: *gains,
            },
        };
        if let Err(e) = sim.advance(ctx.dt, &control) {
            return Step::Failed(e.to_string());
        }
        let q = sim.q();
        for k in self.scope.iter() {
            if !sim.is_prescribed(k) {
                out.set(k, q[k]);
            }
        }
        // The joint forces applied over the tick (their mean over the sub-steps), for
        // observers such as `troupe run --record-torques` (thesis fig. 3-9).
        let tau = sim.mean_torques();
        for k in self.scope.iter() {
            if !sim.is_prescribed(k) {
                out.post(Note::Torque {
                    dof: k,
                    torque: tau[k],
                });
            }
        }
        match &self.drive {
            Drive::Track { sequence, .. } if ctx.local_time >= sequence.duration() => {
                return Step::Finished
            }
            Drive::Passive if self.finish_at_rest => {
                let (kinetic, _) = sim.energy();
                if kinetic < 1e-3 * sim.model().total_mass() {
                    self.at_rest_for += ctx.dt;
                } else {
                    self.at_rest_for = 0.0;
                }
                if self.at_rest_for >= 0.5 {
                    return Step::Finished;
                }
            }
            _ => {}
        }
        Step::Running
    }
}
