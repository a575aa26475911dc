//! The walking motor (thesis 2.6 and 6.4.2, after Boulic et al. 90): a procedural walk
//! whose rhythm comes from the normalized cycle of eq. 2-5 / 2-6, driven by a root plan
//! (a target, a path, a speed over time, or a keyframed `Global_motion` sequence), with
//! the personification parameters of fig. 6-11.
//!
//! Each tick:
//! 1. the plan gives the body's floor position, heading and speed;
//! 2. the phase advances by dt / Dc, Dc from the relative velocity RV = V / Ht (eq. 2-5);
//!    each foot is in support while its phase is below Ds / Dc (eq. 2-6), in balance
//!    (swing) after it — so the two double supports last Dds each;
//! 3. a foot in support stays planted where it landed: it rolls about the heel after the
//!    strike and about the ball before the toe-off, and never slides; a swinging foot
//!    travels from where it left the floor to a landing chosen when it lifted: where the
//!    body will be when the foot is [`PLACEMENT`] of the way through its next support
//!    ([`feet`]);
//! 4. the pelvis (translation: sway, bounce, drop; rotation: list, rotation, tilt), the
//!    spine and the arms oscillate with the cycle, scaled by the personification;
//! 5. the legs come from the feet by closed-form IK ([`rig`]); the pelvis is lowered
//!    (smoothly) where a leg could not otherwise reach its planted foot, so the feet
//!    really stay put; while avoidance steers the walk ([`steer`]), the root goes no
//!    further than the planted legs' joint limits allow ([`footing`]).
//!
//! Held up on its way, a walk waits for those in its way, takes a new route round those
//! standing or another standing point, or fails, stuck or out of patience
//! ([`waiting`], [`patience`]).
//!
//! Arrival: the plan slows to a stop at the goal; the feet take their last steps to stand
//! side by side under the hips, the oscillations fade with the speed, and the action
//! finishes once the body stands.

pub mod carry;
pub mod cycle;
pub mod feet;
pub mod footing;
pub mod goal;
pub mod hands;
pub mod knees;
pub mod lanes;
#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod options;
pub mod patience;
pub mod replan;
pub mod rig;
pub mod route;
pub mod shoulders;
pub mod standoff;
pub mod steer;
pub mod surroundings;
pub mod waiting;

pub use cycle::{cycle_at, relative_cycle_length, CycleTimes};
pub use feet::{
    HEEL_OFF, HEEL_ROCKER, LATE_SWING, MAX_ROLL, PLACEMENT, RETARGET_SPEED, STEP_TURN,
    TURN_ON_PLANTED,
};
pub use goal::Goal;
pub use options::WalkOptions;
pub use rig::Rig;
pub use route::{Plan, RootSample, Route, Speed};
pub use waiting::{PROGRESS, STUCK_TIME, UNATTENDED};

use crate::error::{track_dofs, OptionError, Result};
use feet::{Foot, FootPose};
use route::wrap;
use smallvec::SmallVec;
use std::f64::consts::TAU;
use std::sync::Arc;
use troupe_body::glam::{DQuat, DVec2, DVec3};
use troupe_body::math::smoothstep;
use troupe_body::sensors::Side;
use troupe_body::{Scope, Skeleton};
use troupe_motion::Sequence;
use troupe_scene::holding::Holder;
use troupe_scene::space::{
    limit_step, nearest_gaps, Body, Footprint, Navigation, Surroundings, Walking,
};
use troupe_scene::{DofWriter, Generator, GeneratorContext, StartError, Step};

/// How far (m) the pelvis may be lowered below the gait's height for the legs to reach
/// their feet before the body counts as straining them (see [`footing::strain`]): a long
/// step round a table lowers it by up to 0.1 m; a body that walked on from a planted
/// foot dropped to the floor.
pub const MAX_DROP: f64 = 0.1;
/// The most (in thigh heights) the pelvis is lowered below the gait's height for the legs
/// to reach their feet.
pub const LOWEST: f64 = 0.2;
/// Farthest (rad) the body may lean, forwards or sideways, for a walk to start from it.
pub const UPRIGHT: f64 = 0.6;
/// Lowest the pelvis may stand, as a part of its height at rest, for a walk to start: the
/// deepest crouch of a grasp (0.6 m down, to 0.36 of 0.96 m for the adult; a child's legs
/// bend less far) stands up as it walks off; a body sitting or lying on the floor (its
/// pelvis a tenth of that up) does not.
pub const LOWEST_START: f64 = 0.2;

/// Seconds to stand still, both feet down, before the walk reports it has finished.
pub const SETTLE_TIME: f64 = 0.3;
/// How near (m) a planted foot must be to its spot at the walk's end to stay down and
/// count as settled (and its heading within [`SETTLED_YAW`]).
const SETTLED_FOOT: f64 = 0.01;
/// The same, once the plan has ended [`SHUFFLING`] seconds ago: a body pressed by those
/// standing round it (in a ring round a performer) moves by a centimetre or so as they
/// do, its spots with it, and its feet stepped after them for good, the walk never
/// ending; a person there stands.
const SETTLED_FOOT_PRESSED: f64 = 0.03;
/// Seconds after the plan's end before a foot may stand that far from its spot.
const SHUFFLING: f64 = 1.0;
/// How near (radians) a planted foot's heading must be to its spot's to stay down.
const SETTLED_YAW: f64 = 0.05;
/// Seconds after a stop (`stop()`, `cancel()`, a pre-emption) by which a walk that has
/// not finished as on arrival finishes once both its feet are down near each other
/// ([`STOP_STANCE`]), wherever they stand.
/// A walk held where it stands (by someone in its way, or the clearance) has its plan's
/// clock held too, so its stop's deceleration would never run out; an unhindered stop
/// finishes within 2 s (0.8 s of slowing down, the feet catching up, 0.3 s settling).
pub const STOP_DEADLINE: f64 = 2.5;
/// Seconds after [`STOP_DEADLINE`] by which a stopped walk finishes however its feet
/// stand (an unhindered stop takes 1.4–2 s; one held where it stands may not get its
/// feet together and flat).
pub const STOP_GRACE: f64 = 3.0;
/// Farthest apart (m) two planted feet may be for a stopped walk past [`STOP_DEADLINE`]
/// to finish where it stands: beside each other, not in mid-stride (feet side by side
/// stand about 0.2 m apart, a stride's 0.6–0.8 m).
pub const STOP_STANCE: f64 = 0.45;
/// Seconds over which the spine, arms and pelvis go from the posture the actor had to the
/// walk's.
pub const BLEND_IN_TIME: f64 = 0.4;
/// Least pitch (radians) of a foot with its heel raised when a walk starts, that the walk
/// lowers over [`BLEND_IN_TIME`] (the walk's `start_pitch`); a foot pitched less is
/// taken as flat.
pub const RAISED_HEEL: f64 = 0.05;
/// Fastest change (m/s per second) of the speed the spine's and the arms' motion is set by:
/// a walk held up in its tracks has its speed drop to nothing in a tick, and its elbows
/// straightened from 0.3 rad to 0 within it (a pop to see). Faster than a plan's own stop
/// (1.3 m/s to rest over 0.8 s), which it leaves as it was.
pub const UPPER_BODY_EASE: f64 = 3.0;
/// Seconds ahead at which a rising planned speed already sets the cadence.
pub const CADENCE_LOOKAHEAD: f64 = 0.3;
/// Seconds back over which a falling planned speed still sets the cadence.
pub const CADENCE_LOOKBACK: f64 = 0.6;

/// Fastest the body turns about the vertical (rad/s), about a person's quick pivot: well
/// above the plan's own turns (setting off, at most 60° over [`route::TURN_TIME`], which
/// peaks at 2 rad/s; on the spot, [`route::SPOT_TURN_RATE`]), so it holds back only a
/// plan whose clock jumped (see `Walk::pose`).
pub const MAX_TURN_RATE: f64 = 6.0;

/// Fastest (rad/s) a body that its planted feet held back from the plan's heading turns
/// to catch up with it, beyond the plan's own turn: a walk setting off 55° from where the
/// body faced was held at 31.5° until a foot lifted, then turned the rest at
/// [`MAX_TURN_RATE`], a cup in the hand moving 35 mm in a tick.
pub const CATCH_UP_RATE: f64 = 2.0;

/// The cadence (as a walking speed, m/s) of the steps that turn a body on the spot (see
/// [`route::SPOT_TURN_RATE`]).
pub const TURNING_CADENCE: f64 = 1.0;
/// The least cadence (as a walking speed, m/s) of a stopped walk's steps, and of an
/// arrived walk's last steps: a person stopping brings the feet together in a quick step
/// or two, where the cadence of the body's speed, falling to nothing, took the slowest
/// cycle (2.5 s): a stop's last step was still in the air when its time ran out, and a
/// walk stood 2 s at its goal before it completed.
pub const STOPPING_CADENCE: f64 = 1.0;
/// Seconds of plan between two points of the path a walk reports for drawing.
const NAVIGATION_SAMPLE: f64 = 0.1;

/// The walking motor: a [`Generator`] on the root, pelvis, legs, lower spine and arms.
pub struct Walk {
    rig: Rig,
    options: WalkOptions,
    route: Route,
    dofs: Vec<usize>,
    // Run state (set at start).
    plan: Option<Plan>,
    t: f64,
    phase: f64,
    feet: [Foot; 2],
    lambda: [f64; 2],
    poses: [FootPose; 2],
    yaw: f64,
    heading: f64,
    /// The heading the plan (as steered) asked for on the last tick, which the body's may
    /// lag (see [`CATCH_UP_RATE`]).
    plan_heading: f64,
    start_q: Vec<f64>,
    settle_since: Option<f64>,
    /// The walk time at which the plan (as steered) ended, while it stays ended (see
    /// [`SHUFFLING`]).
    ended_since: Option<f64>,
    /// Where the body last stood [`PROGRESS`] away from where it stood before, and the
    /// walk time it did (see [`STUCK_TIME`]).
    progress: Option<(DVec2, f64)>,
    /// The walk time at which the walk was asked to stop, if it was (see [`STOP_DEADLINE`]).
    stopped_at: Option<f64>,
    /// How long a walk with a goal waits for those in its way before it fails, if it is
    /// to give up at all (see [`patience`]).
    patience: Option<patience::Patience>,
    /// Why the walk gives up (stuck, or out of patience), while it stops before it fails.
    giving_up: Option<String>,
    last_miss: f64,
    /// Each hip's twist on the previous tick (the leg IK's starting guess).
    twist: [Option<f64>; 2],
    /// The cadence speed of this tick (see [`Walk::cadence_speed`]).
    cadence: f64,
    /// What the hands hold, carried (see [`carry`]).
    carrying: carry::Carrying,
    /// Where a planned walk goes: the route is planned around the obstacles when it
    /// starts. `None` walks the route as given.
    goal: Option<Goal>,
    /// Where the actor a walk `to = ACTOR` goes to stood when its route was last planned,
    /// and the walk time it was (see [`Walk::follow_actor`]).
    aimed: Option<(DVec2, f64)>,
    /// Walk time since which the body has stood held, on its way or short of its plan's
    /// end (see [`Walk::held`]).
    held_since: Option<f64>,
    /// Walk time since which, and where, the body has stood with nobody moving near
    /// (see [`Walk::boxed_in`]).
    stalled_since: Option<(f64, DVec2)>,
    /// Walk time since which a walk to a point or along a path has stood held near its
    /// end, and its plan's time then (see [`Walk::held`]).
    held_near_end: Option<(f64, f64)>,
    /// The body's radius, for planning (see [`troupe_scene::space::body_radius`]).
    radius: f64,
    /// How the body departs from the plan to avoid others (see [`steer`]).
    steer: steer::Steer,
    /// Scratch: the actors near this one.
    near: Vec<usize>,
    /// Scratch for the steering's decisions (see [`steer::Scratch`]).
    scratch: steer::Scratch,
    /// Scratch for what the clearance sees round the body (see [`surroundings::Lists`]).
    lists: surroundings::Lists,
    /// Scratch: the obstacles' footprints near (see `Crowd::footprints_around`).
    found: Vec<usize>,
    /// When the walk stood blocked and took new routes (see [`replan`]).
    replan: replan::Replan,
    /// How far the shoulders are turned to pass someone (see [`shoulders`]).
    shoulders: shoulders::Shoulders,
    /// How far the free arms depart from the gait to keep off the furniture (see
    /// [`hands`]).
    hands: hands::FreeHands,
    /// The root's floor point on the previous tick, where the feet held it.
    last_floor: Option<DVec2>,
    /// Each thigh on the previous tick, as [`knees`] sees it.
    thighs: [Option<knees::Thigh>; 2],
    /// Per leg, whether its foot was held where it was on the previous tick (see
    /// [`Walk::hold_foot`]): a swinging foot held turns the body no more than a planted one.
    held: [bool; 2],
    /// Per leg, the foot's pitch when the walk started: below 0 for a heel raised (a
    /// crouch stands on its toes), lowered as the pelvis blends in (see
    /// [`RAISED_HEEL`]).
    start_pitch: [f64; 2],
    /// Per leg, the ankle target's correction for the subtalar offset (see
    /// [`Rig::subtalar_shift`]), from the previous tick's solution.
    subtalar: [DVec3; 2],
    /// The speed the spine's and the arms' motion is set by (see [`UPPER_BODY_EASE`]).
    upper_speed: f64,
    /// The tick period (s).
    dt: f64,
}

/// Values the gait writes besides the legs: [root ×6, pelvis ×3, spine ×4, arms ×8].
type UpperValues = ([f64; 6], [f64; 3], [f64; 4], [[f64; 4]; 2]);

impl Walk {
    /// A walk of `route` by a body built from a humanoid template.
    pub fn new(skeleton: &Skeleton, route: Route, options: WalkOptions) -> Result<Walk> {
        let rig = Rig::new(skeleton)?;
        options.validate()?;
        if let Route::Follow(sequence) = &route {
            // The walk reads the root's tracks only, but a name that is no DOF of the
            // body is a slip (`root_yw`) that would leave the walk unturned, unsaid.
            track_dofs(skeleton, sequence, "follow")?;
        }
        route.check(rig.thigh_height)?;
        let dofs = rig.dofs(options.arms);
        let flat = Foot::Stance {
            plant: DVec2::ZERO,
            yaw: 0.0,
            rocker: 0.0,
            roll: Some(0.0),
            next: None,
            stays: false,
        };
        Ok(Walk {
            rig,
            options,
            route,
            dofs,
            plan: None,
            t: 0.0,
            phase: 0.0,
            feet: [flat; 2],
            lambda: [0.0, 0.5],
            poses: [FootPose::default(); 2],
            yaw: 0.0,
            heading: 0.0,
            plan_heading: 0.0,
            start_q: Vec::new(),
            settle_since: None,
            ended_since: None,
            progress: None,
            stopped_at: None,
            patience: options.patience.map(patience::Patience::new),
            giving_up: None,
            last_miss: 0.0,
            twist: [None; 2],
            cadence: 0.0,
            carrying: carry::Carrying::default(),
            goal: None,
            aimed: None,
            held_since: None,
            stalled_since: None,
            held_near_end: None,
            radius: troupe_scene::space::body_radius(skeleton),
            steer: steer::Steer::default(),
            near: Vec::new(),
            scratch: steer::Scratch::default(),
            lists: surroundings::Lists::default(),
            found: Vec::new(),
            replan: replan::Replan::default(),
            shoulders: shoulders::Shoulders::default(),
            hands: hands::FreeHands::default(),
            last_floor: None,
            thighs: [None; 2],
            held: [false; 2],
            start_pitch: [0.0; 2],
            subtalar: [DVec3::ZERO; 2],
            upper_speed: 0.0,
            dt: 0.01,
        })
    }

    /// A walk to `goal`, planned around the obstacles when it starts (an unreachable goal
    /// fails the action with the reason).
    pub fn navigate(skeleton: &Skeleton, goal: Goal, options: WalkOptions) -> Result<Walk> {
        if let Goal::Through(points) = &goal {
            if points.is_empty() {
                return Err(OptionError::refused("path", "the path is empty").into());
            }
        }
        let placeholder = match &goal {
            Goal::Through(points) => points.clone(),
            _ => vec![DVec2::ZERO],
        };
        let mut walk = Walk::path(skeleton, placeholder, options)?;
        walk.goal = Some(goal);
        Ok(walk)
    }

    /// Where the body ends: the plan's end, with the steering's offset.
    fn end_sample(&self, plan: &Plan) -> RootSample {
        let mut end = plan.sample(plan.end_time, self.heading);
        if self.steer.engaged {
            end.position += self.steer.offset;
        }
        end
    }

    /// Whether a foot planted at `plant` heading `yaw` stays down rather than step to
    /// `(spot, heading)`: near enough ([`SETTLED_FOOT`], or [`SETTLED_FOOT_PRESSED`]
    /// once the plan has ended [`SHUFFLING`] seconds ago).
    fn stays_at(&self, plant: DVec2, yaw: f64, (spot, heading): (DVec2, f64)) -> bool {
        let pressed = self.ended_since.is_some_and(|t| self.t - t >= SHUFFLING);
        let near = if pressed {
            SETTLED_FOOT_PRESSED
        } else {
            SETTLED_FOOT
        };
        (spot - plant).length() < near && wrap(heading - yaw).abs() < SETTLED_YAW
    }

    /// The route through `planned`'s points, ending on its heading (or the walk's own),
    /// at `speed` (m/s).
    fn route_to(&self, planned: goal::Planned, speed: f64) -> Route {
        Route::Path {
            points: planned.points.into_iter().map(|(p, _)| p).collect(),
            heading: planned.heading.or(self.options.heading),
            speed,
        }
    }

    /// How many new routes the walk has taken round actors standing in its way.
    pub fn new_routes(&self) -> u32 {
        self.replan.count
    }

    /// The body radius the walk plans with (m).
    pub fn radius(&self) -> f64 {
        self.radius
    }

    /// A walk to floor point `goal` (its y must be the floor, 0) at `options.speed`.
    pub fn to(skeleton: &Skeleton, goal: DVec3, options: WalkOptions) -> Result<Walk> {
        if !goal.is_finite() {
            return Err(
                OptionError::refused("to", format!("the target {goal} is not finite")).into(),
            );
        }
        if goal.y.abs() > 0.05 {
            return Err(OptionError::refused("to", format!(
                "the target {goal} is unreachable by walking: it is {:.2} m off the floor (y must be 0)",
                goal.y
            )).into());
        }
        Walk::path(skeleton, vec![DVec2::new(goal.x, goal.z)], options)
    }

    /// A walk through floor points (x, z), ending at the last one.
    pub fn path(skeleton: &Skeleton, points: Vec<DVec2>, options: WalkOptions) -> Result<Walk> {
        let route = Route::Path {
            points,
            heading: options.heading,
            speed: options.speed,
        };
        Walk::new(skeleton, route, options)
    }

    /// A walk straight ahead at `speed`, for `duration` seconds or until cancelled.
    pub fn velocity(
        skeleton: &Skeleton,
        speed: Speed,
        duration: Option<f64>,
        options: WalkOptions,
    ) -> Result<Walk> {
        Walk::new(skeleton, Route::Velocity { speed, duration }, options)
    }

    /// A walk along the keyframed root path of `sequence` (`Global_motion`, 6.4.2).
    pub fn follow(
        skeleton: &Skeleton,
        sequence: Arc<Sequence>,
        options: WalkOptions,
    ) -> Result<Walk> {
        Walk::new(skeleton, Route::Follow(sequence), options)
    }

    /// The DOFs the walk drives.
    pub fn dofs(&self) -> &[usize] {
        &self.dofs
    }

    /// The DOFs the walk drives, as a scope.
    pub fn scope(&self) -> Scope {
        self.dofs.iter().copied().collect()
    }

    /// The part of its scope the walk can give up and keep walking: the arms (their swing
    /// and carrying) and the spine's lean and counter-rotation. The root, pelvis and legs
    /// are essential.
    pub fn yields(&self) -> Scope {
        let rig = &self.rig;
        let arms = rig
            .arms
            .iter()
            .flatten()
            .chain(rig.carrying_arms.iter().flatten());
        let upper = rig.spine.iter().chain(arms).copied();
        upper.collect::<Scope>().intersection(&self.scope())
    }

    /// What the hand of arm `i` in [`Rig::arms`] (0 left, 1 right) holds, if anything:
    /// the first holding of the actor on a joint of that side.
    fn held_by_arm(ctx: &GeneratorContext, i: usize) -> Option<Holder> {
        let side = if i == 0 { Side::Left } else { Side::Right };
        let joints = ctx.skeleton.joints();
        ctx.world.held.iter().map(|&(_, h)| h).find(|h| {
            h.actor == ctx.actor
                && h.wrists().any(|wrist| {
                    joints
                        .get(wrist)
                        .is_some_and(|j| Side::of_joint(&j.name) == Some(side))
                })
        })
    }

    /// The body model the walk uses (thigh height, DOFs, foot geometry).
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// The gait phase in cycles since the start (its fractional part is φ).
    pub fn phase(&self) -> f64 {
        self.phase
    }

    /// How far (m) an ankle stayed from its planted target on the last tick: 0 unless the
    /// leg could not reach (the pelvis is lowered so that this stays 0).
    pub fn reach_miss(&self) -> f64 {
        self.last_miss
    }

    /// The gait's activity: 0 standing, → 1 at walking speeds (scales the oscillations so
    /// that they fade in and out with the speed).
    fn activity(&self, speed: f64) -> f64 {
        (speed / (0.5 * self.rig.thigh_height)).tanh()
    }

    fn cycle(&self, speed: f64) -> CycleTimes {
        cycle_at(speed, self.rig.thigh_height, self.options.step_length)
    }

    /// The speed that sets the cadence at `t`: the highest of the plan's speed now,
    /// [`CADENCE_LOOKAHEAD`] later and [`CADENCE_LOOKBACK`] earlier. A start quickens the
    /// steps as the body speeds up rather than after, and a stop keeps the rhythm until
    /// the feet have caught up with the body, so that no support lasts longer than the
    /// legs can reach. At constant speed it is the speed, as eq. 2-5 wants.
    fn cadence_speed(&self, plan: &Plan, t: f64) -> f64 {
        let speed = |t: f64| self.steer.speed(plan, t, self.t);
        let now = speed(t);
        let ahead = speed(t + CADENCE_LOOKAHEAD);
        let behind = speed((t - CADENCE_LOOKBACK).max(0.0));
        // Turning on the spot, the feet step round at a walk's cadence.
        let turning = if plan.turns_on_the_spot(self.steer.plan_time(t, self.t)) {
            TURNING_CADENCE
        } else {
            0.0
        };
        // Stopped, or arrived (the plan's body has come to rest): the feet catch up.
        let arrived = self.steer.plan_time(t, self.t) >= plan.end_time;
        let stopping = if self.stopped_at.is_some() || arrived {
            STOPPING_CADENCE
        } else {
            0.0
        };
        now.max(ahead)
            .max(behind)
            .max(self.steer.cadence_floor(plan, t, self.t))
            .max(turning)
            .max(stopping)
    }

    /// Pelvis, spine and arm values for phase `phi` (in cycles) at activity `a` and
    /// relative velocity `rv` (the spine and arms at `upper`'s, see [`UPPER_BODY_EASE`]);
    /// plus the root's lateral sway and vertical offset.
    fn oscillations(
        &self,
        phi: f64,
        (a, rv): (f64, f64),
        upper: (f64, f64),
        sigma: f64,
    ) -> (f64, f64, [f64; 3], [f64; 4], [[f64; 4]; 2]) {
        let o = &self.options;
        let ht = self.rig.thigh_height;
        let c1 = (TAU * phi).cos();
        let s1 = (TAU * phi).sin();
        let rv = rv.min(2.5);
        // Pelvis (thesis 2.6, after Inman: rotation, list, lateral and vertical motion).
        let rot = -(0.03 + 0.03 * rv) * a * o.pelvis * c1;
        let list = -(0.035 + 0.01 * rv) * a * o.pelvis * s1;
        let tilt = 0.02 * a * o.pelvis * (2.0 * TAU * phi).cos();
        let sway = 0.022 * ht * a * o.pelvis * s1 / (1.0 + 0.5 * rv);
        let bounce = (0.012 + 0.006 * rv)
            * ht
            * (1.0 + 1.5 * o.run)
            * o.bounce
            * (2.0 * TAU * (phi - 0.5 * sigma)).cos();
        let drop = (0.015 + 0.01 * rv + 0.10 * o.run) * ht;
        let vertical = a * (bounce - drop);
        let (a, rv) = (upper.0, upper.1.min(2.5));
        // Spine: the thorax turns against the pelvis; lean grows with speed and running.
        let lean = (0.03 + 0.03 * rv + 0.25 * o.run) * a;
        let counter = (0.03 + 0.03 * rv) * a * c1;
        let spine = [lean, 0.5 * counter, 0.5 * counter, -0.3 * list];
        // Arms swing against the legs: the right arm forward with the left foot.
        let swing = (0.12 + 0.10 * rv) * a * o.arm_swing;
        let elbow0 = (0.2 + 0.08 * rv) * a + 1.2 * o.run * a;
        let mut arms = [[0.0; 4]; 2];
        for (i, sign) in [(0usize, -1.0), (1, 1.0)] {
            let flex = sign * swing * c1 + 0.03 * a;
            arms[i] = [flex, 0.06 * a, elbow0 + 0.6 * flex.max(0.0), 0.0];
        }
        (sway, vertical, [tilt, list, rot], spine, arms)
    }

    /// The part of this walker's body its step carries, as the previous tick left it (see
    /// `troupe_nav::clearance`): the crowd's core capsule, or its disc.
    fn body(&self, ctx: &GeneratorContext) -> Body {
        let crowd = ctx.world.crowd;
        crowd.cores.get(ctx.actor).copied().unwrap_or_else(|| {
            let at = crowd.positions.get(ctx.actor).copied().unwrap_or_default();
            Body::around(at, DVec2::ZERO, self.radius, 0.0, &[])
        })
    }

    /// Computes the whole pose for this tick and writes it.
    fn pose(
        &mut self,
        ctx: &GeneratorContext,
        around: &Surroundings,
        plan: &Plan,
        out: &mut DofWriter,
    ) -> UpperValues {
        let mut sample = self.steer.sample(plan, self.t, self.t, self.heading);
        // The body turns no faster than a person pivots: the plan's clock can jump ahead
        // (a push along a route that has just set off, whose speed is still small, moves
        // it by several ticks), and its heading, still turning in, with it; and no further
        // from a planted foot than the hip twists. Unsteered, a body the planted feet
        // held back catches up with the plan no faster than [`CATCH_UP_RATE`] beyond the
        // plan's own turn (a steered one at once: held back among others, its heading
        // lagging its way put more limbs into theirs in the plaza).
        let plan_turn = wrap(sample.heading - self.plan_heading);
        self.plan_heading = sample.heading;
        let most = if self.steer.engaged {
            MAX_TURN_RATE * ctx.dt
        } else {
            (plan_turn.abs() + CATCH_UP_RATE * ctx.dt).min(MAX_TURN_RATE * ctx.dt)
        };
        let turn = wrap(sample.heading - self.heading);
        let allowed = self.turn_on_planted_feet(turn.clamp(-most, most));
        if allowed != turn {
            sample.heading = self.heading + allowed;
        }
        self.heading = sample.heading;
        self.held = [false; 2];
        let v = sample.speed;
        let a = self.activity(v);
        self.cadence = self.cadence_speed(plan, self.t);
        let cycle = self.cycle(self.cadence);
        let sigma = cycle.support_fraction();
        let phi = self.phase.rem_euclid(1.0);
        let before = self.poses;
        for leg in 0..2 {
            let lambda = (self.phase - 0.5 * leg as f64).rem_euclid(1.0);
            self.poses[leg] = self.step_foot(around, plan, leg, lambda, sigma);
        }
        let rv = v / self.rig.thigh_height;
        let most = UPPER_BODY_EASE * ctx.dt;
        self.upper_speed += (v - self.upper_speed).clamp(-most, most);
        let upper = (
            self.activity(self.upper_speed),
            self.upper_speed / self.rig.thigh_height,
        );
        let (sway, vertical, mut pelvis, spine, arms) =
            self.oscillations(phi, (a, rv), upper, sigma);
        // The pelvis blends in from the posture the actor had before the legs are solved
        // for it (the legs must reach the feet from where the pelvis really is).
        let k = smoothstep(self.t / BLEND_IN_TIME);
        if k < 1.0 {
            for (i, p) in pelvis.iter_mut().enumerate() {
                let s = self.start_q[self.rig.pelvis[i]];
                *p = s + (*p - s) * k;
            }
        }
        let heading = sample.heading;
        self.yaw += wrap(heading - self.yaw);
        let left = DVec2::new(heading.cos(), -heading.sin());
        let lift = (vertical, a, k);
        let mut floor = sample.position + left * sway;
        // Whatever the steering chose, the body closes on no other body or obstacle past
        // the clearance limit (see `troupe_nav::clearance`). The legs are solved after it,
        // once for where the body goes (solving both legs is about a fifth of the crowd
        // benchmark's tick).
        let crowd = ctx.world.crowd;
        let navigated = ctx.world.space.walking == Walking::Navigated;
        if let (Some(&from), true) = (crowd.positions.get(ctx.actor), navigated) {
            let clear = from + limit_step(&self.body(ctx), floor - from, around);
            if clear != floor {
                if !self.steer.engaged {
                    self.steer.engage(self.t, DVec2::ZERO);
                }
                self.steer.hold(plan, clear - floor);
                floor = clear;
            }
        }
        let mut legs = self.legs_at(floor, heading, pelvis, lift);
        // A steered body goes no further than its planted feet allow (see [`footing`]):
        // between where it stood and where the clearance let it go, so still within the
        // clearance's limits (each a half-plane that holds both).
        if self.steer.engaged {
            if let Some(last) = self.last_floor {
                let held = footing::hold(
                    last,
                    floor,
                    legs.strain,
                    |p| self.legs_at(p, heading, pelvis, lift),
                    |legs| legs.strain,
                );
                if let Some((held, held_legs)) = held.filter(|(held, _)| *held != floor) {
                    self.steer.hold(plan, held - floor);
                    floor = held;
                    legs = held_legs;
                }
            }
        }
        if !around.obstacles.is_empty() {
            legs =
                self.keep_knees_clear(around, before, sigma, floor, (heading, pelvis), lift, legs);
        } else {
            self.thighs = [None; 2];
        }
        self.last_floor = Some(floor);
        let rig = &self.rig;
        let root_vals = [
            floor.x - rig.root_rest.x,
            legs.root_y,
            floor.y - rig.root_rest.z,
            self.yaw,
            0.0,
            0.0,
        ];
        for leg in 0..2 {
            self.subtalar[leg] = self.rig.subtalar_shift(leg, legs.pelvis, &legs.values[leg]);
        }
        let rig = &self.rig;
        for leg in 0..2 {
            self.twist[leg] = Some(legs.values[leg][2]);
            for (i, &d) in rig.legs[leg].dofs.iter().enumerate() {
                out.set(d, legs.values[leg][i]);
            }
        }
        self.last_miss = legs.miss;
        (root_vals, pelvis, spine, arms)
    }

    /// The legs `legs` solved for the body over `floor` again where a thigh would close on
    /// an obstacle (see [`knees`]): that leg's foot keeps its pose `before` of the previous
    /// tick (a foot rolling onto its toes or swinging: a flat one bends no knee
    /// forwards).
    #[allow(clippy::too_many_arguments)]
    fn keep_knees_clear(
        &mut self,
        around: &Surroundings,
        before: [FootPose; 2],
        sigma: f64,
        floor: DVec2,
        (heading, pelvis): (f64, [f64; 3]),
        lift: (f64, f64, f64),
        mut legs: Legs,
    ) -> Legs {
        // Beyond a thigh's reach from the body's floor point (with a step's slack), no
        // obstacle can come within the margin of it this tick or the next: the thighs are
        // measured against the obstacles within it alone, and most ticks of a walker
        // among furniture end here.
        let rig = &self.rig;
        let reach = rig.hip_half_width + rig.legs[0].thigh + rig.legs[0].thigh_radii[0] + 0.1;
        let near: SmallVec<[(&Footprint, (DVec2, f64)); 8]> = (around.obstacles.iter())
            .enumerate()
            .filter(|&(k, f)| {
                around.circle_gap(k, (floor, 0.0)) <= reach && f.distance(floor) <= reach
            })
            .map(|(k, &f)| (f, around.obstacle_bound(k)))
            .collect();
        if near.is_empty() {
            self.thighs = [None; 2];
            return legs;
        }
        let thighs = |rig: &Rig, legs: &Legs| {
            [0, 1].map(|leg| {
                knees::Thigh::of(rig, leg, legs.pelvis, legs.hips[leg], &legs.values[leg])
            })
        };
        let mut now = thighs(&self.rig, &legs);
        let mut held = false;
        for leg in 0..2 {
            let closes = self.thighs[leg].is_some_and(|last| now[leg].closes(&last, &near));
            if closes && self.hold_foot(leg, before[leg], sigma) {
                held = true;
            }
        }
        if held {
            legs = self.legs_at(floor, heading, pelvis, lift);
            now = thighs(&self.rig, &legs);
        }
        self.thighs = now.map(Some);
        legs
    }

    /// The legs for the root over floor point `floor` with heading `heading` and the pelvis
    /// at `pelvis`; `(vertical, a, k)` are the gait's vertical offset, its activity and
    /// how far the pelvis has blended in.
    fn legs_at(&self, floor: DVec2, heading: f64, pelvis: [f64; 3], lift: (f64, f64, f64)) -> Legs {
        let (vertical, a, k) = lift;
        let rig = &self.rig;
        let pelvis_rot = rig.pelvis_rotation(heading, pelvis);
        // Highest root drop that lets both legs reach their feet: a smooth minimum, so the
        // pelvis height stays continuous in value and velocity.
        let root0 = rig.root_rest + DVec3::new(floor.x, 0.0, floor.y);
        let mut highest = [vertical; 3];
        for leg in 0..2 {
            let hip = rig.hip_position(leg, root0, heading, pelvis_rot);
            let ankle = self.poses[leg].ankle;
            let l = (rig.legs[leg].thigh + rig.legs[leg].shank) * 0.99999;
            let horizontal = DVec2::new(hip.x - ankle.x, hip.z - ankle.z).length();
            highest[leg + 1] = ankle.y + (l * l - horizontal * horizontal).max(0.0).sqrt() - hip.y;
        }
        // A body that starts lowered (crouched to pick something up) rises to the gait's
        // height as the pelvis blends in, rather than jumping up.
        let crouched = self.start_q[rig.root[1]];
        // Never more than `LOWEST` below the gait's height: a leg that cannot reach its
        // foot from there misses it rather than pulling the body down to the floor.
        let lowered = soft_min(highest, 0.006 * a).max(vertical - LOWEST * rig.thigh_height);
        let root_y = lowered + crouched.min(0.0) * (1.0 - k);
        let root = root0 + DVec3::Y * root_y;
        let pelvis_yaw = heading + pelvis[2];
        let mut legs = Legs {
            root_y,
            values: [[0.0; 7]; 2],
            miss: 0.0,
            strain: (vertical - lowered - MAX_DROP).max(0.0),
            pelvis: pelvis_rot,
            hips: [DVec3::ZERO; 2],
        };
        for leg in 0..2 {
            let hip = rig.hip_position(leg, root, heading, pelvis_rot);
            legs.hips[leg] = hip;
            let p = self.poses[leg];
            let (values, miss) = rig.solve_leg(
                leg,
                pelvis_rot,
                pelvis_yaw,
                self.twist[leg],
                hip,
                p.ankle + self.subtalar[leg],
                (p.yaw, p.pitch, p.toes),
            );
            legs.miss = legs.miss.max(miss);
            if matches!(self.feet[leg], Foot::Stance { stays: false, .. }) {
                legs.strain = legs
                    .strain
                    .max(footing::strain(&rig.legs[leg], &values, miss));
            }
            legs.values[leg] = values;
        }
        legs
    }
}

/// Both legs solved for one root position (see [`Walk::legs_at`]).
struct Legs {
    /// The root's height DOF.
    root_y: f64,
    /// Each leg's DOF values, in [`rig::Leg::dofs`] order.
    values: [[f64; 7]; 2],
    /// How far an ankle stays from its target.
    miss: f64,
    /// How far a planted leg is asked past what it can do (see [`footing::strain`]).
    strain: f64,
    /// The pelvis' world rotation the legs were solved under.
    pelvis: DQuat,
    /// Each hip's world position the legs were solved from.
    hips: [DVec3; 2],
}

/// A smooth minimum of three values (log-sum-exp with temperature `k`); the plain minimum
/// when `k` is 0. Never above the plain minimum.
fn soft_min(x: [f64; 3], k: f64) -> f64 {
    let m = x[0].min(x[1]).min(x[2]);
    if k < 1e-9 {
        return m;
    }
    let s: f64 = x.iter().map(|&v| (-(v - m) / k).exp()).sum();
    m - k * s.ln()
}

impl Generator for Walk {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        let q = &ctx.posture.q;
        let rig = &self.rig;
        let start = DVec2::new(
            rig.root_rest.x + q[rig.root[0]],
            rig.root_rest.z + q[rig.root[2]],
        );
        let heading = q[rig.root[3]];
        // A walk starts on its feet: from a body lying on the floor (after a fall) it
        // would snap the body upright in one tick, a foot through the floor.
        let (pitch, roll) = (q[rig.root[4]], q[rig.root[5]]);
        let pelvis = rig.root_rest.y + q[rig.root[1]];
        if pitch.abs() > UPRIGHT || roll.abs() > UPRIGHT || pelvis < LOWEST_START * rig.root_rest.y
        {
            return Err(format!(
                "walk: the body is not on its feet (tilted {:.2} rad forwards and {:.2} rad \
                 sideways, its pelvis {pelvis:.2} m above the floor): a walk starts standing \
                 (pose the actor up first)",
                pitch, roll
            )
            .into());
        }
        self.yaw = heading;
        self.heading = heading;
        self.plan_heading = heading;
        // The companions first: a standing point where one of them stands is not taken.
        self.steer = steer::Steer::start(ctx);
        self.aimed = None;
        self.held_since = None;
        self.stalled_since = None;
        self.held_near_end = None;
        if let Some(goal) = &self.goal {
            let companions = (self.steer.companions.as_slice(), goal::Choice::First);
            let planned = goal.plan(ctx, start, self.radius, companions)?;
            if let Goal::Actor { actor, .. } = goal {
                self.aimed = ctx.world.crowd.positions.get(*actor).map(|&p| (p, 0.0));
            }
            self.route = self.route_to(planned, self.options.speed);
        }
        let plan = Plan::new(&self.route, start, heading);
        // Both feet start planted where they are, flat or with the heel raised.
        let mut floor = f64::INFINITY;
        for leg in 0..2 {
            let g = ctx.posture.globals[rig.legs[leg].joints[0]];
            let (yaw, pitch) = Rig::foot_heading_pitch(&g);
            // A heel raised by more than [`RAISED_HEEL`] (a crouch stands on its toes) is
            // lowered as the walk blends in; a foot pitched less is flat enough to stand on.
            let pitch = if pitch < -RAISED_HEEL { pitch } else { 0.0 };
            self.start_pitch[leg] = pitch;
            // The floor point under the ankle of the foot put flat, its ball where it is
            // (a flat foot's read as before, under the ankle, to the bit).
            let plant = if pitch < 0.0 {
                rig.plant_under(leg, g.translation, yaw, pitch)
            } else {
                g.translation - DVec3::Y * rig.ankle_height
            };
            floor = floor.min(plant.y);
            self.feet[leg] = Foot::Stance {
                plant: DVec2::new(plant.x, plant.z),
                yaw,
                rocker: 0.0,
                // The right foot starts late in its support: it lifts without rolling.
                roll: if leg == 0 { None } else { Some(0.0) },
                next: None,
                stays: false,
            };
        }
        self.phase = 0.0;
        self.lambda = [0.0, 0.5];
        self.t = 0.0;
        self.start_q = q.clone();
        let root = DVec3::new(start.x, 0.0, start.y);
        self.carrying = carry::Carrying::start(ctx, carry::heading_frame(root, heading), floor);
        self.settle_since = None;
        self.ended_since = None;
        self.progress = None;
        self.stopped_at = None;
        if let Some(patience) = &mut self.patience {
            patience.restart();
        }
        self.giving_up = None;
        self.twist = [None; 2];
        self.last_floor = None;
        self.thighs = [None; 2];
        self.held = [false; 2];
        self.subtalar = [DVec3::ZERO; 2];
        self.replan = replan::Replan::default();
        self.shoulders = shoulders::Shoulders::default();
        self.plan = Some(plan);
        Ok(())
    }

    /// Slows down from now and stops with both feet side by side (the walk then reports
    /// `Finished`, as on arrival).
    fn stop(&mut self) -> bool {
        match &mut self.plan {
            Some(plan) => {
                plan.stop_at(self.steer.plan_time(self.t, self.t));
                self.stopped_at.get_or_insert(self.t);
                true
            }
            None => false,
        }
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let Some(mut plan) = self.plan.take() else {
            return Step::Failed("walk: stepped before it started".into());
        };
        let navigated = ctx.world.space.walking == Walking::Navigated;
        // The obstacles round the body, found once for the steering, the clearance and the
        // shoulders; none when walks go straight, unnavigated.
        let crowd = ctx.world.crowd;
        let footprints = navigated.then(|| {
            let at = crowd.positions.get(ctx.actor).copied().unwrap_or_default();
            crowd.footprints_around(at, std::mem::take(&mut self.found))
        });
        // Whether `self.near` holds this tick's neighbours (see [`steer::Steer::decide`]).
        // Every walk is steered: one with a goal round its route, a followed walk round its
        // keyframed path, a velocity walk round its line; only one with a goal takes new
        // routes. (A followed path went on through whoever stood on it, its feet pinched
        // into stepping in place behind a body that went on: a leg 1.1 m short of its foot.)
        let mut gathered = false;
        // A walk told to stop keeps its stopping plan: no new route, no other place, nobody
        // followed (following, one went on 1.96 m after `stop()`).
        let planning = self.stopped_at.is_none();
        if let Some(footprints) = &footprints {
            let ring = self.goal.as_ref().and_then(|g| g.ring(ctx, self.radius));
            let at = crowd.positions.get(ctx.actor).copied().unwrap_or_default();
            self.steer.keep_out_of(ctx, ring, (at, self.radius));
            let (t, near) = (self.t, (&mut self.near, &mut self.scratch));
            gathered = self.steer.decide(ctx, (&plan, footprints), t, near);
            if self.steer.engaged && matches!(self.route, Route::Path { .. }) {
                // Only a steered walk plans anew: the stall is looked at only for one.
                let stalled = self.stalled(ctx, &plan, gathered);
                // Only held with nobody moving near: in a crowd on the move a last look
                // every 2 s put more feet into one another in the plaza.
                let last_look = stalled && self.stuck_soon();
                if self
                    .replan
                    .due(self.t, self.steer.rate, (stalled, last_look))
                    && planning
                {
                    if let Some(new) = self.new_route(ctx, &plan, stalled) {
                        plan = new;
                    }
                }
                if planning {
                    if let Some(new) = self.boxed_in(ctx, &plan, (stalled, gathered)) {
                        plan = new;
                    }
                }
            }
        }
        if planning {
            if let Some(new) = self.follow_actor(ctx, &plan) {
                plan = new;
            }
            if let Some(new) = self.held(ctx, &plan) {
                plan = new;
            }
        }
        // A walk that gives up stops as one told to, its feet brought together, and then
        // fails: failing at once left a foot in the air for good.
        let stuck = footprints
            .as_ref()
            .and_then(|footprints| self.stuck(ctx, &plan, footprints));
        if let Some(why) = stuck.or_else(|| self.impatient(ctx, &plan)) {
            plan.stop_at(self.steer.plan_time(self.t, self.t));
            self.stopped_at.get_or_insert(self.t);
            self.giving_up = Some(why);
        }
        self.dt = ctx.dt;
        // What the clearance sees round the body (see [`surroundings`]).
        let around = match &footprints {
            Some(footprints) => {
                let near = (&mut self.near, gathered);
                let lists = &mut self.lists;
                surroundings::gather(ctx, &self.steer.companions, near, footprints, lists)
            }
            None => Surroundings::default(),
        };
        let (root, pelvis, mut spine, mut arms) = self.pose(ctx, &around, &plan, out);
        // The shoulders turn to pass someone close beside (see [`shoulders`]); the arms,
        // whose swing would now go sideways into the other, hang still as they turn,
        // twisted back so that the bent elbows keep the forearms along the way and not
        // towards the other, and swing less as anything comes close.
        let (mut near_body, mut near_obstacle) = (f64::INFINITY, f64::INFINITY);
        if let Some(footprints) = &footprints {
            let me = self.body(ctx);
            let (bodies, obstacles) = nearest_gaps(&me, &around, shoulders::ARMS_CLEAR);
            (near_body, near_obstacle) = (bodies, obstacles);
            let gap = bodies.min(obstacles);
            // Those near enough to turn for are among those `gather` kept.
            let around = (self.lists.close(), footprints);
            self.shoulders
                .update(ctx, self.heading, &self.steer.companions, around, gap);
        }
        spine[1] += self.shoulders.turn / 2.0;
        spine[2] += self.shoulders.turn / 2.0;
        let swing = self.shoulders.swing();
        for (arm, twist) in arms.iter_mut().zip(self.shoulders.arm_twists()) {
            arm[0] *= swing;
            arm[1] *= swing;
            arm[3] = twist;
        }
        let rig = &self.rig;
        for (&d, &v) in rig.root.iter().zip(&root) {
            out.set(d, v);
        }
        for (&d, &v) in rig.pelvis.iter().zip(&pelvis) {
            out.set(d, v);
        }
        // The upper body blends in from the posture the actor had.
        let k = smoothstep(self.t / BLEND_IN_TIME);
        let start_q = &self.start_q;
        let blended = |dof: usize, v: f64| {
            if k < 1.0 {
                start_q[dof] + (v - start_q[dof]) * k
            } else {
                v
            }
        };
        // This tick's root, pelvis and spine values, for the carrying arms' kinematics.
        let mut upper = [(0usize, 0.0f64); 13];
        for (slot, (&d, &v)) in upper.iter_mut().zip(
            rig.root
                .iter()
                .chain(&rig.pelvis)
                .zip(root.iter().chain(&pelvis)),
        ) {
            *slot = (d, v);
        }
        for (i, (&d, &v)) in rig.spine.iter().zip(&spine).enumerate() {
            let v = blended(d, v);
            upper[9 + i] = (d, v);
            out.set(d, v);
        }
        if self.options.arms {
            let holding = [0, 1].map(|i| Walk::held_by_arm(ctx, i).is_some());
            // A hand that holds nothing keeps off the furniture beside it (see [`hands`]).
            let scope = out.scope();
            let free =
                [0, 1].map(|i| !holding[i] && rig.arms[i][..3].iter().all(|&d| scope.contains(d)));
            let obstacles = (&around, near_obstacle);
            self.hands
                .keep_clear(ctx, (rig.arms, free), &upper, obstacles, &mut arms);
            for (i, (dofs, values)) in rig.arms.iter().zip(&arms).enumerate() {
                // A hand that holds something keeps its arm out of the swing, which would
                // lower the load to the thigh: the carrying moves it (see [`carry`]).
                if holding[i] {
                    continue;
                }
                for (&d, &v) in dofs.iter().zip(values) {
                    out.set(d, blended(d, v));
                }
            }
        }
        let root_at = DVec3::new(rig.root_rest.x + root[0], 0.0, rig.root_rest.z + root[2]);
        // Turning on the spot, or close beside someone: what one hand carries comes in
        // to the chest.
        let tuck = plan.turns_on_the_spot(self.steer.plan_time(self.t, self.t))
            || near_body < carry::TUCK_NEAR;
        self.carrying
            .step(ctx, (self.t, root_at, root[3], tuck), &upper, out);
        // Finished once the plan has ended and both feet stand at their final spots.
        let mut done = false;
        if self.steer.plan_time(self.t, self.t) >= plan.end_time {
            self.ended_since.get_or_insert(self.t);
            let end = self.end_sample(&plan);
            let settled = (0..2).all(|leg| match self.feet[leg] {
                // Its heading too: a turn larger than a step takes more steps.
                Foot::Stance { plant, yaw, .. } => {
                    let spot = self.spot(&around, leg, &end, 1.0, 0.0).0;
                    self.stays_at(plant, yaw, (spot, end.heading)) && self.poses[leg].pitch == 0.0
                }
                Foot::Swing { .. } => false,
            });
            if settled {
                let since = *self.settle_since.get_or_insert(self.t);
                done = self.t - since >= SETTLE_TIME;
            } else {
                self.settle_since = None;
            }
        } else {
            self.ended_since = None;
        }
        if let Some(stopped_at) = self.stopped_at {
            // A walk held where it stands (its plan's clock, or its body, held by someone in
            // its way or by the clearance) steps towards spots it never reaches.
            let since = self.t - stopped_at;
            // Flat on both soles too: a foot that has just struck the floor, toes up, would
            // stay so once the walk ends.
            let standing = match self.feet {
                [Foot::Stance { plant: l, .. }, Foot::Stance { plant: r, .. }] => {
                    (l - r).length() < STOP_STANCE
                        && self.poses.iter().all(|pose| pose.pitch == 0.0)
                }
                _ => false,
            };
            // One that gives up, held where it stands, fails as soon as both feet are down
            // side by side: it has nowhere to slow down to.
            let waited = self.giving_up.is_some() || since >= STOP_DEADLINE;
            done |= since >= STOP_DEADLINE + STOP_GRACE || (waited && standing);
        }
        self.lists.keep(around);
        if let Some(footprints) = footprints {
            self.found = footprints.into_found();
        }
        // Advance the clock and the phase (dφ = dt / Dc, eq. 2-5).
        self.phase += ctx.dt / self.cycle(self.cadence).cycle;
        self.steer.advance(ctx.dt);
        self.t += ctx.dt;
        self.plan = Some(plan);
        if !done {
            Step::Running
        } else if let Some(why) = self.giving_up.take() {
            Step::Failed(why)
        } else {
            Step::Finished
        }
    }

    /// The plan ahead, sampled every `NAVIGATION_SAMPLE` seconds from where its clock
    /// is now, and the last avoidance decision; walks that end only (not a velocity walk
    /// without a duration).
    fn navigation(&self) -> Option<Navigation> {
        let plan = self.plan.as_ref()?;
        if !plan.end_time.is_finite() {
            return None;
        }
        let now = self.steer.plan_time(self.t, self.t).min(plan.end_time);
        let samples = (((plan.end_time - now) / NAVIGATION_SAMPLE).ceil() as usize).min(10_000);
        let at = |t: f64| plan.sample(t, self.heading).position;
        let mut path: Vec<DVec2> = (0..samples)
            .map(|k| at(now + k as f64 * NAVIGATION_SAMPLE))
            .collect();
        let goal = at(plan.end_time);
        path.push(goal);
        Some(Navigation {
            path,
            goal,
            velocities: self.steer.decision,
        })
    }
}

#[cfg(test)]
mod tests;
