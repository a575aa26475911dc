//! An arm's planned motion that bends round other bodies: the temporary goals of
//! [`super::detour`] (thesis 4.6.3) for actions that move an arm from its posture to a
//! planned one by joint interpolation (a grasp's reach and so a receive's, a give's
//! carry to the meeting point).
//!
//! At the start, the planned motion is sampled (forward kinematics of the interpolated
//! postures) and the arm's sensors (elbow, forearm samples, hand) are tested against the
//! other bodies and obstacles near ([`detour::volumes_around_except`]). When they stay
//! clear, nothing changes: the action interpolates as before. When they do not, the
//! hand follows a [`HandPath`] instead, from where it is straight to where the plan puts
//! it, with temporary goals inserted where that line goes through a volume; each tick
//! the arm is solved by IK towards the path's point, pulled towards the interpolated
//! posture in the null space and kept out of the volumes as they stand by the same
//! secondary task as a reach's ([`CollisionAvoidance::with_external`]). On the way to
//! the temporary goals only the hand's position is asked, which leaves the elbow free to
//! go round; on the last segment the wrist also turns, from how it arrived to the
//! plan's orientation. The last tick solves to the planned wrist pose exactly; the
//! action then holds the arm where that solve left it.

use super::detour::{self, HandPath};
use super::{hold_to_joint_speed, quintic, COLLISION_MARGIN, EXTERNAL_MARGIN};
use crate::error::{ActionError, Result};
use troupe_body::collision::Volume;
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::ik::{Goal, IkOptions, IkSolver, IkTask};
use troupe_body::jacobian::{scope_dofs_moving, Effector};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::self_collision::{BodySensors, CollisionAvoidance, SENSOR_SCALE};
use troupe_body::sensors::Side;
use troupe_body::Transform;
use troupe_scene::GeneratorContext;

/// The planned motion is tested at this many postures along it.
const SAMPLES: usize = 24;
/// Pull (per IK iteration) of the arm towards the interpolated posture, in the null
/// space of the hand's task: the arm keeps the plan's shape where the volumes allow.
const POSTURE_GAIN: f64 = 0.05;
/// IK iterations on the ticks before the last (the path moves a few millimetres a tick).
const TRACKING_ITERATIONS: usize = 10;
/// A detoured arm must end this close to the planned wrist position (metres)…
pub const END_TOLERANCE: f64 = crate::grasp::plan::REACH_TOLERANCE;
/// … and this close to its orientation (radians).
pub const END_ANGLE: f64 = crate::grasp::plan::REACH_ANGLE;

/// What an arm's planned motion is: from the actor's posture in `ctx` to the same
/// posture with `to` applied, the wrist of `side` ending at `wrist`.
pub struct PlannedArm<'a> {
    /// Which arm.
    pub side: Side,
    /// The planned changes (DOF, value): the arm's and any the body leans or crouches
    /// with.
    pub to: &'a [(usize, f64)],
    /// The wrist's pose at the end (world).
    pub wrist: Transform,
    /// An object the hand is meant to touch (the grasped one): not avoided.
    pub except: Option<&'a str>,
}

/// An arm's motion through temporary goals round other bodies (see the module's docs).
pub struct ArmDetour {
    side: Side,
    wrist: usize,
    /// The hand sensor's index, and its centre in the wrist's frame and full radius.
    hand: usize,
    centre: DVec3,
    radius: f64,
    sensors: BodySensors,
    solver: IkSolver,
    path: HandPath,
    /// The wrist's orientation when the path's last segment began.
    last_from: Option<DQuat>,
    goal: Transform,
    except: Option<String>,
    volumes: Vec<Volume>,
    detours: usize,
    /// The arm's DOF values as last solved.
    arm: Vec<f64>,
    /// The reference posture of a solve (scratch).
    reference: Vec<f64>,
}

impl ArmDetour {
    /// Plans `arm`'s motion for the actor of `ctx` from its posture now: `None` when
    /// the planned motion keeps the arm clear of the other bodies and obstacles near.
    pub fn plan(ctx: &GeneratorContext, arm: &PlannedArm) -> Result<Option<ArmDetour>> {
        let sk = ctx.skeleton;
        // A body without the humanoid sensors (4.6.2) cannot be kept out of others: its
        // arm moves as planned.
        let Ok(sensors) = BodySensors::new(sk) else {
            return Ok(None);
        };
        let prefix = arm.side.prefix();
        let hand = sensors
            .index_of(&format!("{prefix}hand"))
            .ok_or_else(|| ActionError::Unfit(format!("`{}` has no hand sensor", sk.name())))?;
        let wrist = sk.joint(&format!("{prefix}wrist"))?;
        let centre = sensors.sensors()[hand].point;
        let radius = sensors.sensors()[hand].radius / SENSOR_SCALE;
        let g = &ctx.posture.globals;
        let start = g[wrist].transform_point(centre);
        let goal = arm.wrist.transform_point(centre);
        let volumes =
            detour::volumes_around_except(ctx.world, ctx.actor, start, goal, radius, arm.except);
        if volumes.is_empty() {
            return Ok(None);
        }
        // The arm's own sensors: the upper arm's and the forearm's samples, the elbow,
        // the hand.
        let mine: Vec<usize> = (0..sensors.sensors().len())
            .filter(|&i| {
                let name = &sensors.sensors()[i].name;
                ["upper_arm", "elbow", "forearm", "hand"]
                    .iter()
                    .any(|part| name.starts_with(&format!("{prefix}{part}")))
            })
            .collect();
        let mut q = ctx.posture.q.clone();
        let mut globals = g.clone();
        let blocked = (1..SAMPLES).any(|k| {
            let u = k as f64 / SAMPLES as f64;
            for &(d, v) in arm.to {
                q[d] = ctx.posture.q[d] + (v - ctx.posture.q[d]) * u;
            }
            forward_kinematics(sk, &q, &mut globals);
            mine.iter().any(|&i| {
                let c = sensors.center(i, &globals);
                let r = sensors.sensors()[i].radius / SENSOR_SCALE;
                volumes.iter().any(|v| v.sphere_depth(c, r) > 0.0)
            })
        });
        if !blocked {
            return Ok(None);
        }
        let arm_of = detour::Arm::of(sk, &sensors, wrist, g);
        let via = detour::temporary_goals(start, &[], goal, radius, &volumes, arm_of);
        let scope = sk.scope(&format!("{}_arm", arm.side.name()))?;
        let options = IkOptions {
            max_iterations: TRACKING_ITERATIONS,
            posture_gain: POSTURE_GAIN,
            ..IkOptions::default()
        };
        let solver = IkSolver::new(sk, scope_dofs_moving(sk, &scope, wrist), options)?;
        let values = solver.dofs().iter().map(|&d| ctx.posture.q[d]).collect();
        Ok(Some(ArmDetour {
            side: arm.side,
            wrist,
            hand,
            centre,
            radius,
            sensors,
            solver,
            detours: via.len(),
            path: HandPath::new(start, via, goal),
            last_from: None,
            goal: arm.wrist,
            except: arm.except.map(str::to_owned),
            volumes,
            arm: values,
            reference: Vec::new(),
        }))
    }

    /// How many temporary goals the hand's path took.
    pub fn detours(&self) -> usize {
        self.detours
    }

    /// The arm's DOFs and their values as last solved.
    pub fn solved(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.solver
            .dofs()
            .iter()
            .copied()
            .zip(self.arm.iter().copied())
    }

    /// Moves the arm's DOFs of `q` (the planned motion's posture at this tick, which the
    /// arm is pulled towards) to follow the path at `tau` (0 to 1, the fraction of the
    /// motion's time), out of the volumes as they stand in `ctx`'s world. At `tau` = 1 it
    /// fails when the hand cannot end at the planned pose.
    pub fn step(&mut self, ctx: &GeneratorContext, tau: f64, q: &mut [f64]) -> Result<()> {
        let tau = tau.clamp(0.0, 1.0);
        let finishing = tau >= 1.0;
        self.reference.clear();
        self.reference.extend_from_slice(q);
        for (&d, &v) in self.solver.dofs().iter().zip(&self.arm) {
            q[d] = v;
        }
        let goal = self.goal.transform_point(self.centre);
        // The others move: the volumes as they stood last tick.
        self.volumes = detour::volumes_around_except(
            ctx.world,
            ctx.actor,
            self.path.start(),
            goal,
            self.radius,
            self.except.as_deref(),
        );
        let mut point = self.path.at(tau, goal);
        if !finishing {
            point = detour::push_out(point, self.radius, COLLISION_MARGIN, &self.volumes);
        }
        let (segment, local) = self.path.segment(tau);
        let orientation = (segment == self.path.via().len()).then(|| {
            let from = *self
                .last_from
                .get_or_insert(ctx.posture.globals[self.wrist].rotation);
            from.slerp(self.goal.rotation, quintic(local))
        });
        let task = IkTask {
            effector: Effector {
                joint: self.wrist,
                point: self.centre,
            },
            goal: Goal {
                position: point,
                orientation,
            },
            priority: 0,
        };
        let mut options = *self.solver.options();
        options.max_iterations = if finishing { 200 } else { TRACKING_ITERATIONS };
        self.solver.set_options(options)?;
        let mut avoid = CollisionAvoidance::new(&self.sensors, COLLISION_MARGIN, vec![self.hand])
            .with_external(&self.volumes, EXTERNAL_MARGIN)
            .without_own_body();
        self.solver.solve(
            ctx.skeleton,
            q,
            &[task],
            Some(&self.reference),
            Some(&mut avoid),
        )?;
        // As a reach's: no DOF faster than the limit while the path runs.
        if !finishing {
            let before = self
                .solver
                .dofs()
                .iter()
                .copied()
                .zip(self.arm.iter().copied());
            hold_to_joint_speed(q, before, ctx.dt);
        }
        for (v, &d) in self.arm.iter_mut().zip(self.solver.dofs()) {
            *v = q[d];
        }
        if finishing {
            let w = self.solver.globals()[self.wrist];
            let miss = (w.translation - self.goal.translation).length();
            let angle =
                troupe_body::jacobian::rotation_error(w.rotation, self.goal.rotation).length();
            if miss > END_TOLERANCE || angle > END_ANGLE {
                return Err(ActionError::Unfit(format!(
                    "the {} hand, going round {} temporary goal(s), stopped {miss:.3} m and \
                     {:.1}° from its planned pose",
                    self.side.name(),
                    self.detours,
                    angle.to_degrees()
                )));
            }
        }
        Ok(())
    }
}
