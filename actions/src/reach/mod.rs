//! The reach generator (thesis 4.3.3, 4.6): an end effector follows a smooth path to a goal
//! by inverse kinematics, through optional temporary goals (`via`, 4.6.3), with
//! self-collision correction (4.6.2) as the IK secondary task; a hand's path also bends
//! round other actors' bodies and obstacles through temporary goals of its own
//! ([`detour`]), and the arm is kept out of them the same way as out of its own body.
//!
//! The path from the effector's start to the goal is a polyline through the via points;
//! each segment is travelled with the quintic `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵` (zero velocity
//! and acceleration at both ends), its share of the duration proportional to its length.
//! The goal is read from the world every tick, so a moving object or joint is followed.
//! At the end, the action completes when the effector is within [`POSITION_TOLERANCE`] (and
//! [`ORIENTATION_TOLERANCE`] when an orientation is asked) and fails otherwise, with the
//! residual distance in the reason.

pub mod arm_detour;
pub mod detour;
#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod options;

pub use options::{ReachOptions, Reacher};

use crate::error::{OptionError, Result};
use crate::grasp::body::{furniture_round, BodyReach, CrouchLegs, Stage};
use std::sync::Arc;
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::ik::{Goal, IkOptions, IkSolver, IkTask};
use troupe_body::jacobian::scope_dofs_moving;
use troupe_body::jacobian::Effector;
use troupe_body::self_collision::{BodySensors, CollisionAvoidance};
use troupe_body::{Scope, Skeleton};
use troupe_scene::{DofWriter, Generator, GeneratorContext, StartError, Step, World};

/// A reach completes when the effector ends this close to its goal (metres).
pub const POSITION_TOLERANCE: f64 = 1e-3;
/// … and, with an orientation goal, within this angle (radians, 1°).
pub const ORIENTATION_TOLERANCE: f64 = std::f64::consts::PI / 180.0;

/// Position error accepted on the ticks before the last (metres).
pub(crate) const TRACKING_POSITION_TOLERANCE: f64 = 2e-4;
/// Orientation error accepted on the ticks before the last (radians, about 0.1°).
pub(crate) const TRACKING_ORIENTATION_TOLERANCE: f64 = 2e-3;
/// Most IK iterations on the ticks before the last.
pub(crate) const TRACKING_ITERATIONS: usize = 10;
/// Most iterations of self-collision correction per tick once the goal is met; the
/// correction goes on next tick.
pub(crate) const TRACKING_SETTLE_ITERATIONS: usize = 2;
/// Self-collision correction keeps sensors this far from the body (metres).
pub const COLLISION_MARGIN: f64 = 0.01;
/// How far outside other bodies and obstacles the arm's sensors start to be pushed away
/// (metres). The sensors are spheres a few centimetres apart and another's arm may pass
/// between them within a tick: with the body's 1 cm, a forearm brushing past another's
/// arm went 2-9 mm into it in six of the twelve layouts of docs/navigation.md ("A hand
/// going over another's arm") and an elbow swinging over it 18 mm; with 3 cm, none.
pub const EXTERNAL_MARGIN: f64 = 0.03;
/// The fastest a reach, or a grasp going round others, turns any of its DOFs (rad/s;
/// m/s for the root's height). Where a DOF locks at its limit the IK may find the arm
/// another way at once: a shoulder's abduction jumped 31° in one tick (54 rad/s) going
/// over another's arm. A reach whose arm is still held back when its time is up goes on
/// until it has caught up, for up to [`CATCH_UP`]; `manipulate` and a hand following
/// another's and a walk's carrying arm are held to it too ([`hold_to_joint_speed`]).
pub(crate) const MAX_JOINT_SPEED: f64 = 8.0;

/// Longest a reach or a manipulation goes on past its duration (s) while its arm, held
/// to [`MAX_JOINT_SPEED`], catches up with the posture that puts the hand on the goal;
/// then the last tick solves onto it whatever the jump.
pub(crate) const CATCH_UP: f64 = 0.5;

/// Holds each DOF `d` of `before` (its value on the last tick) within
/// [`MAX_JOINT_SPEED`] × `dt` of that value in `q`, which an IK has just solved; true if
/// any was held back.
pub(crate) fn hold_to_joint_speed(
    q: &mut [f64],
    before: impl IntoIterator<Item = (usize, f64)>,
    dt: f64,
) -> bool {
    let most = MAX_JOINT_SPEED * dt;
    let mut held = false;
    for (d, was) in before {
        let v = q[d].clamp(was - most, was + most);
        held |= v != q[d];
        q[d] = v;
    }
    held
}

/// Where a target is: read from the world each tick.
#[derive(Clone, Debug, PartialEq)]
pub enum Target {
    /// A fixed world point.
    Point(DVec3),
    /// The centre of the object called so.
    Object(String),
    /// A joint (plus an offset in its frame) of the actor called so.
    Joint {
        /// The actor's name.
        actor: String,
        /// The joint's name.
        joint: String,
        /// Offset in the joint's frame.
        offset: DVec3,
    },
}

impl Target {
    /// The target's world position now, or why it cannot be found.
    pub fn position(&self, world: &World) -> Result<DVec3, TargetLost> {
        let p = match self {
            Target::Point(p) => *p,
            Target::Object(name) => world
                .objects
                .iter()
                .find(|o| &o.name == name)
                .map(|o| o.position)
                .ok_or_else(|| TargetLost::Object(name.clone()))?,
            Target::Joint {
                actor,
                joint,
                offset,
            } => {
                let a = world
                    .actor_index(actor)
                    .filter(|&a| a < world.states.len())
                    .ok_or_else(|| TargetLost::Actor(actor.clone()))?;
                let j = world.actors[a].skeleton.joint(joint)?;
                world.states[a]
                    .globals
                    .get(j)
                    .ok_or_else(|| TargetLost::Joint {
                        actor: actor.clone(),
                        joint: joint.clone(),
                    })?
                    .transform_point(*offset)
            }
        };
        if p.is_finite() {
            Ok(p)
        } else {
            Err(TargetLost::NotFinite)
        }
    }
}

/// Why a target cannot be found in the world while an action runs.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum TargetLost {
    /// The object left the scene.
    #[error("target object `{0}` is gone")]
    Object(String),
    /// The actor left the scene.
    #[error("target actor `{0}` is gone")]
    Actor(String),
    /// The actor's body has no such joint.
    #[error(transparent)]
    Body(#[from] troupe_body::Error),
    /// The actor's posture has no transform for the joint.
    #[error("target actor `{actor}` has no joint `{joint}`")]
    Joint {
        /// The actor's name.
        actor: String,
        /// The joint's name.
        joint: String,
    },
    /// The position is not finite.
    #[error("the target position is not finite")]
    NotFinite,
}

impl Target {
    /// Refuses a point target that is not finite (names and joints are looked up when
    /// the action runs).
    pub fn check(&self) -> Result<(), OptionError> {
        match self {
            Target::Point(p) if !p.is_finite() => Err(OptionError::refused(
                "target",
                "the target position is not finite",
            )),
            _ => Ok(()),
        }
    }
}

/// What a reach is asked to do.
#[derive(Clone, Debug)]
pub struct ReachSpec {
    /// The point that reaches.
    pub effector: Effector,
    /// The goal.
    pub target: Target,
    /// Goal orientation of the effector's joint frame (world).
    pub orientation: Option<DQuat>,
    /// Seconds to reach the goal.
    pub duration: f64,
    /// Temporary goals on the way (world points).
    pub via: Vec<DVec3>,
    /// Whether self-collision correction is on.
    pub self_collision: bool,
    /// Whether the path bends round other bodies and obstacles ([`detour`]).
    pub detour: bool,
    /// The DOFs IK moves (all must move the effector).
    pub dofs: Vec<usize>,
}

/// The reach generator.
pub struct Reach {
    spec: ReachSpec,
    solver: IkSolver,
    sensors: Option<Arc<BodySensors>>,
    effector_sensor: Option<usize>,
    q: Vec<f64>,
    started: bool,
    start: DVec3,
    start_rotation: DQuat,
    /// The legs' and `root_y`'s (start, goal) values of a crouching reach (see
    /// [`Reach::widen`]), interpolated along the path.
    crouch: Vec<(usize, f64, f64)>,
    /// The legs of a crouching reach, solved again for each height of the pelvis.
    legs: Option<CrouchLegs>,
    /// The path: through the spec's via points and the temporary goals of [`detour`].
    path: detour::HandPath,
    /// How many temporary goals [`detour`] inserted at the start.
    detours: usize,
    /// Other bodies and obstacles near, as of the previous tick (with `detour`).
    volumes: Vec<troupe_body::collision::Volume>,
}

/// The quintic ease `10τ³ − 15τ⁴ + 6τ⁵` on [0, 1].
pub fn quintic(t: f64) -> f64 {
    let t = t.clamp(0.0, 1.0);
    t * t * t * (10.0 + t * (-15.0 + 6.0 * t))
}

impl Reach {
    /// A reach on `skeleton`. Fails when the DOF list is empty or invalid, the duration is
    /// not positive, or a via point is not finite.
    pub fn new(skeleton: &Skeleton, spec: ReachSpec) -> Result<Reach> {
        options::check_path(spec.duration, &spec.via, &spec.target)?;
        let options = IkOptions {
            max_iterations: 30,
            ..IkOptions::default()
        };
        let solver = IkSolver::new(skeleton, spec.dofs.clone(), options)?;
        let (sensors, effector_sensor) = if spec.self_collision || spec.detour {
            let s = BodySensors::new(skeleton)?;
            // The sensor riding on the effector's joint (the hand) follows the main task.
            let own = s
                .sensors()
                .iter()
                .position(|x| x.joint == spec.effector.joint);
            (Some(Arc::new(s)), own)
        } else {
            (None, None)
        };
        Ok(Reach {
            spec,
            solver,
            sensors,
            effector_sensor,
            q: Vec::new(),
            started: false,
            start: DVec3::ZERO,
            start_rotation: DQuat::IDENTITY,
            crouch: Vec::new(),
            legs: None,
            path: detour::HandPath::default(),
            detours: 0,
            volumes: Vec::new(),
        })
    }

    /// Whole-body reach ([`crate::grasp::body`]): when the action's scope has more than
    /// the IK's DOFs (a hand reach's default scope adds the spine, the legs and
    /// `root_y`) and the goal is out of reach of those DOFs, the IK also gets the spine
    /// and, for a low goal, the body crouches along the path.
    fn widen(&mut self, ctx: &GeneratorContext, goal: DVec3) -> Result<()> {
        let sk = ctx.skeleton;
        let body = BodyReach::body_scope(sk)?;
        let mine: Scope = self.solver.dofs().iter().copied().collect();
        let allowed = ctx.scope.intersection(&body).difference(&mine);
        if allowed.is_empty() {
            return Ok(());
        }
        let furniture = furniture_round(ctx.world, ctx.actor, "");
        let reach = BodyReach::new(sk, allowed)?.keeping_knees_off(furniture);
        let task = IkTask {
            effector: self.spec.effector,
            goal: Goal {
                position: goal,
                orientation: self.spec.orientation,
            },
            priority: 0,
        };
        let tolerance = (POSITION_TOLERANCE, ORIENTATION_TOLERANCE);
        for stage in reach.stages() {
            let tasks = [(task, mine)];
            let Ok(reached) = reach.reach_tasks(&ctx.posture.q, &tasks, stage, tolerance)? else {
                continue;
            };
            if stage == Stage::Arms {
                return Ok(());
            }
            let spine = sk.scope("spine")?.intersection(&allowed);
            let wider = mine.union(&spine);
            let dofs = scope_dofs_moving(sk, &wider, self.spec.effector.joint);
            self.solver = IkSolver::new(sk, dofs, *self.solver.options())?;
            let moving: Scope = self.solver.dofs().iter().copied().collect();
            self.crouch = reached
                .changed
                .iter()
                .filter(|(d, _)| allowed.contains(*d) && !moving.contains(*d))
                .map(|&(d, v)| (d, ctx.posture.q[d], v))
                .collect();
            if reached.crouch > 0.0 {
                self.legs = CrouchLegs::new(sk, &ctx.posture.q, reached.crouch);
            }
            return Ok(());
        }
        Ok(())
    }

    /// The DOFs the reach moves.
    pub fn dofs(&self) -> &[usize] {
        self.solver.dofs()
    }

    /// How many temporary goals the path got round other bodies and obstacles when it
    /// started (0 before it starts or when the straight path was clear).
    pub fn detours(&self) -> usize {
        self.detours
    }

    /// The effector's sensor's radius at full size (the hand's solid), and the offset
    /// from the effector to the sensor's centre now.
    fn hand_sphere(&self, globals: &[troupe_body::Transform]) -> Option<(f64, DVec3)> {
        let (sensors, own) = (self.sensors.as_ref()?, self.effector_sensor?);
        let radius = sensors.sensors()[own].radius / troupe_body::self_collision::SENSOR_SCALE;
        Some((
            radius,
            sensors.center(own, globals) - self.spec.effector.position(globals),
        ))
    }

    /// The point on the path at `t` seconds for the goal now at `goal`.
    fn path(&self, t: f64, goal: DVec3) -> DVec3 {
        self.path.at(t / self.spec.duration, goal)
    }
}

impl Generator for Reach {
    fn detours(&self) -> usize {
        self.detours
    }

    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        let goal = self
            .spec
            .target
            .position(ctx.world)
            .map_err(|e| e.to_string())?;
        self.q = ctx.posture.q.clone();
        self.crouch.clear();
        self.legs = None;
        self.widen(ctx, goal).map_err(|e| e.to_string())?;
        self.start = self.spec.effector.position(&ctx.posture.globals);
        self.start_rotation = self.spec.effector.rotation(&ctx.posture.globals);
        let mut via = self.spec.via.clone();
        self.detours = 0;
        if let (true, Some((radius, offset))) =
            (self.spec.detour, self.hand_sphere(&ctx.posture.globals))
        {
            // 4.6.3: temporary goals round what the straight path would go through.
            let start = self.start + offset;
            self.volumes =
                detour::volumes_around(ctx.world, ctx.actor, start, goal + offset, radius);
            let shifted: Vec<DVec3> = self.spec.via.iter().map(|p| *p + offset).collect();
            let arm = self.sensors.as_ref().and_then(|sensors| {
                let hand = self.spec.effector.joint;
                detour::Arm::of(ctx.skeleton, sensors, hand, &ctx.posture.globals)
            });
            let around =
                detour::temporary_goals(start, &shifted, goal + offset, radius, &self.volumes, arm);
            self.detours = around.len() - shifted.len();
            via = around.into_iter().map(|p| p - offset).collect();
        }
        self.path = detour::HandPath::new(self.start, via, goal);
        self.started = true;
        Ok(())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        if !self.started {
            if let Err(e) = self.start(ctx) {
                return Step::Failed(e.to_string());
            }
        }
        let goal = match self.spec.target.position(ctx.world) {
            Ok(g) => g,
            Err(e) => return Step::Failed(e.to_string()),
        };
        // The body as it is, with this action's own DOFs as it last solved them.
        let dofs = self.solver.dofs().to_vec();
        let saved: Vec<f64> = dofs.iter().map(|&d| self.q[d]).collect();
        self.q.copy_from_slice(&ctx.posture.q);
        for (&d, v) in dofs.iter().zip(saved) {
            self.q[d] = v;
        }
        let t = ctx.local_time;
        let finishing = t + 0.5 * ctx.dt >= self.spec.duration;
        // Where the path is now: its end from the finishing tick on, which for a reach
        // shorter than a tick is its first (the path's start was measured there, and the
        // arm failed 0.5 m short of a goal it never aimed at).
        let along = if finishing {
            t.max(self.spec.duration)
        } else {
            t
        };
        // A crouching reach lowers the body along the same ease as the path.
        let s = quintic(along / self.spec.duration);
        for &(d, from, to) in &self.crouch {
            self.q[d] = from + (to - from) * s;
            out.set(d, self.q[d]);
        }
        if let Some(legs) = &mut self.legs {
            legs.apply(ctx.skeleton, &mut self.q);
            for d in legs.dofs() {
                out.set(d, self.q[d]);
            }
        }
        let mut point = self.path(along, goal);
        if let (true, Some((radius, offset))) =
            (self.spec.detour, self.hand_sphere(&ctx.posture.globals))
        {
            // The others move: the volumes as they stood last tick, and the path point
            // out of them.
            let start = self.start + offset;
            self.volumes =
                detour::volumes_around(ctx.world, ctx.actor, start, goal + offset, radius);
            point =
                detour::push_out(point + offset, radius, COLLISION_MARGIN, &self.volumes) - offset;
        }
        if let (true, Some(sensors), Some(own)) = (
            self.spec.self_collision,
            &self.sensors,
            self.effector_sensor,
        ) {
            // 4.6.3: a path point inside the body becomes a temporary goal outside it.
            point = sensors.push_out(
                ctx.skeleton,
                &ctx.posture.globals,
                own,
                point
                    + (sensors.center(own, &ctx.posture.globals)
                        - self.spec.effector.position(&ctx.posture.globals)),
                COLLISION_MARGIN,
            ) - (sensors.center(own, &ctx.posture.globals)
                - self.spec.effector.position(&ctx.posture.globals));
        }
        let orientation = self
            .spec
            .orientation
            .map(|r| self.start_rotation.slerp(r, s));
        let task = IkTask {
            effector: self.spec.effector,
            goal: Goal {
                position: point,
                orientation,
            },
            priority: 0,
        };
        // While the path runs, the goal moves a few millimetres per tick and the next tick
        // corrects what is left, so a tracking tolerance and a few iterations suffice; the
        // last tick solves to the full tolerance to decide completion.
        let mut options = *self.solver.options();
        if finishing {
            options.max_iterations = 200;
            options.position_tolerance = IkOptions::default().position_tolerance;
            options.orientation_tolerance = IkOptions::default().orientation_tolerance;
            options.settle_iterations = usize::MAX;
        } else {
            options.max_iterations = TRACKING_ITERATIONS;
            options.position_tolerance = TRACKING_POSITION_TOLERANCE;
            options.orientation_tolerance = TRACKING_ORIENTATION_TOLERANCE;
            options.settle_iterations = TRACKING_SETTLE_ITERATIONS;
        }
        if self.solver.set_options(options).is_err() {
            return Step::Failed("invalid IK options".into());
        }
        let skip: Vec<usize> = self.effector_sensor.into_iter().collect();
        let before: Vec<f64> = dofs.iter().map(|&d| self.q[d]).collect();
        let report = match &self.sensors {
            Some(sensors) => {
                let external: &[troupe_body::collision::Volume] =
                    if self.spec.detour { &self.volumes } else { &[] };
                let mut avoid = CollisionAvoidance::new(sensors, COLLISION_MARGIN, skip)
                    .with_external(external, EXTERNAL_MARGIN);
                if !self.spec.self_collision {
                    avoid = avoid.without_own_body();
                }
                self.solver
                    .solve(ctx.skeleton, &mut self.q, &[task], None, Some(&mut avoid))
            }
            None => self
                .solver
                .solve(ctx.skeleton, &mut self.q, &[task], None, None),
        };
        if let Err(e) = report {
            return Step::Failed(e.to_string());
        }
        // Past its duration the reach goes on while the arm catches up, so that its last
        // tick does not jump there.
        let held = (!finishing || t < self.spec.duration + CATCH_UP)
            && hold_to_joint_speed(&mut self.q, dofs.iter().copied().zip(before), ctx.dt);
        for &d in &dofs {
            out.set(d, self.q[d]);
        }
        if !finishing || held {
            return Step::Running;
        }
        let g = self.solver.globals();
        let distance = (self.spec.effector.position(g) - goal).length();
        let angle = self.spec.orientation.map_or(0.0, |r| {
            troupe_body::jacobian::rotation_error(self.spec.effector.rotation(g), r).length()
        });
        if distance <= POSITION_TOLERANCE && angle <= ORIENTATION_TOLERANCE {
            Step::Finished
        } else if distance > POSITION_TOLERANCE {
            Step::Failed(format!(
                "target unreachable: the effector stopped {distance:.4} m from it (tolerance {POSITION_TOLERANCE} m)"
            ))
        } else {
            Step::Failed(format!(
                "orientation unreachable: {:.2}° off (tolerance 1°)",
                angle.to_degrees()
            ))
        }
    }
}
