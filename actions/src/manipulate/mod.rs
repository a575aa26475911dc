//! Object manipulation (thesis 4.4): a held object moves along key frames and the holding
//! arm(s) follow it by inverse kinematics every tick ("the object moves actively while
//! the joints of an arm move passively following the object movement").
//!
//! The object's pose between keys is interpolated linearly (positions) and spherically
//! (rotations); each tick the wrist goal is the object's displacement since the start
//! applied to the wrist's start pose (the grip stays fixed), and IK solves the arm from
//! its previous solution.

#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod options;

pub use options::ManipulateOptions;

use crate::error::OptionError;
use crate::grasp::plan::ArmIk;
use crate::reach::{hold_to_joint_speed, CATCH_UP};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::sensors::Side;
use troupe_body::Transform;
use troupe_scene::{DofWriter, Generator, GeneratorContext, StartError, Step};

/// The arm must follow the last key within this distance (metres).
pub const FOLLOW_TOLERANCE: f64 = 0.01;

/// One key of an object trajectory.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ObjectKey {
    /// Seconds from the action's start.
    pub time: f64,
    /// World position of the object's centre.
    pub position: DVec3,
    /// World orientation (`None`: keep the orientation it had at the start).
    pub rotation: Option<DQuat>,
}

/// The manipulate generator.
pub struct Manipulate {
    object: usize,
    keys: Vec<ObjectKey>,
    sides: Vec<Side>,
    arms: Vec<(ArmIk, Transform)>,
    start: Transform,
    q: Vec<f64>,
}

/// The object's pose at `t` along `keys` (sorted by time), given its start pose.
pub fn pose_at(keys: &[ObjectKey], start: &Transform, t: f64) -> Transform {
    let rot = |k: &ObjectKey| k.rotation.unwrap_or(start.rotation);
    let Some(first) = keys.first() else {
        return *start;
    };
    if t <= first.time {
        // Before the first key: from the start pose toward it.
        let u = if first.time > 0.0 {
            (t / first.time).clamp(0.0, 1.0)
        } else {
            1.0
        };
        return Transform::new(
            start.rotation.slerp(rot(first), u),
            start.translation.lerp(first.position, u),
        );
    }
    for w in keys.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if t <= b.time {
            let u = ((t - a.time) / (b.time - a.time)).clamp(0.0, 1.0);
            return Transform::new(rot(a).slerp(rot(b), u), a.position.lerp(b.position, u));
        }
    }
    let last = keys.last().expect("keys are not empty");
    Transform::new(rot(last), last.position)
}

impl Manipulate {
    /// Moves held `object` along `keys` with the arms `sides`. Keys must be finite, at
    /// times ≥ 0 in increasing order, and at least one.
    pub fn new(
        object: usize,
        keys: Vec<ObjectKey>,
        sides: Vec<Side>,
    ) -> Result<Manipulate, OptionError> {
        options::check_keys(&keys)?;
        Ok(Manipulate {
            object,
            keys,
            sides,
            arms: Vec::new(),
            start: Transform::IDENTITY,
            q: Vec::new(),
        })
    }
}

impl Generator for Manipulate {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        let obj = ctx
            .world
            .objects
            .get(self.object)
            .ok_or_else(|| format!("no object #{}", self.object))?;
        let me = &ctx.world.actors[ctx.actor].name;
        if ctx
            .world
            .holder(self.object)
            .is_none_or(|h| h.actor != ctx.actor)
        {
            return Err(format!("`{me}` does not hold `{}`", obj.name).into());
        }
        self.start = Transform::new(obj.rotation, obj.position);
        self.q = ctx.posture.q.clone();
        for &s in &self.sides {
            let ik = ArmIk::new(ctx.skeleton, s, 40)?;
            let wrist = ctx.posture.globals[ik.wrist];
            self.arms.push((ik, wrist));
        }
        Ok(())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let t = ctx.local_time + ctx.dt;
        let goal = pose_at(&self.keys, &self.start, t);
        let delta = goal.mul(&self.start.inverse());
        // Start from the posture, with this action's arm DOFs as it last solved them.
        let mine: Vec<(usize, f64)> = out.scope().iter().map(|d| (d, self.q[d])).collect();
        self.q.copy_from_slice(&ctx.posture.q);
        for &(d, v) in &mine {
            self.q[d] = v;
        }
        let end = self.keys.last().map(|k| k.time).unwrap_or(0.0);
        let last = t + 0.5 * ctx.dt >= end;
        let mut worst: f64 = 0.0;
        for (ik, wrist) in &mut self.arms {
            let target = delta.mul(wrist);
            match ik.solve(ctx.skeleton, &mut self.q, &target) {
                Ok((miss, _)) => worst = worst.max(miss),
                Err(e) => return Step::Failed(e.to_string()),
            }
        }
        // As a reach's: where a DOF locks at its limit the IK may turn the arm another way
        // at once (a shoulder's flexion jumped 0.9 rad in a tick with the hands overhead);
        // past the last key the arm catches up before the manipulation ends.
        let held = (!last || t < end + CATCH_UP) && hold_to_joint_speed(&mut self.q, mine, ctx.dt);
        for d in out.scope().iter() {
            out.set(d, self.q[d]);
        }
        if !last || held {
            return Step::Running;
        }
        if worst > FOLLOW_TOLERANCE {
            Step::Failed(format!(
                "the last key is out of reach: the hand stopped {worst:.3} m from it"
            ))
        } else {
            Step::Finished
        }
    }
}
