//! Actor interaction by hands (thesis 4.5): giving an object, holding hands, shaking
//! hands.
//!
//! Two actors' generators cooperate through signals on the scene's blackboard
//! ([`troupe_scene::blackboard`]): one raises a signal, the other sees it from the next
//! tick on, so the outcome does not depend on which thread stepped which actor first.
//!
//! - **give**: the giver waits, holding the object, until neither actor walks (a
//!   receiver with its back to it turns round first), carries the object to a meeting
//!   point between them (the object leads, the arm follows by IK as in 4.4, standing up
//!   or leaning as it must) and raises `arrived`; the receiver (a gated
//!   [`Grasp`](crate::grasp::Grasp) allowed to take the object from the giver) plans its
//!   grasp on the object there, reaches, closes and attaches; once the snapshot shows the
//!   receiver holding it, the giver opens its hand, lowers the arm and completes.
//!   Both arms bend round a third actor's body or an obstacle in their way through
//!   temporary goals ([`ArmDetour`], thesis 4.6.3), unless `detour` is off.
//! - **hold hands**: the active actor reaches the other's hand (grasp frame from the other
//!   hand's palm, origin search against the other's body solids, its bounding volumes),
//!   closes its fingers around it (sensors against the other's body) and raises `held`;
//!   the passive actor then keeps its hand at the same pose relative to the active hand
//!   by IK every tick, extrapolating the active hand one tick ahead.
//! - **shake hands**: the passive actor holds out its hand ([`offer`]) as the active one
//!   reaches for it there; they hold hands, then the active hand moves up and down and
//!   both follow.

pub mod device_hand;
#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod offer;
pub mod options;

pub use options::{GiveOptions, HoldHandOptions, ReceiveOptions};

use crate::grasp::action::{CLOSE_SECONDS, OPEN_SECONDS};
use crate::grasp::body::{furniture_round, BodyReach, CrouchLegs};
use crate::grasp::close::HandModel;
use crate::grasp::pattern::{BoundPattern, HandPattern};
use crate::grasp::plan::{
    frame_rotation, held_in, ArmIk, CLEARANCE, REACH_ANGLE, REACH_TOLERANCE, ROTATION_WEIGHT,
    SEARCH_STEP,
};
use crate::grasp::GraspType;
use crate::reach::arm_detour::{ArmDetour, PlannedArm};
use crate::reach::{hold_to_joint_speed, quintic};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::jacobian::rotation_error;
use troupe_body::sensors::{solid_distance, Side};
use troupe_body::{Scope, Skeleton, Transform};
use troupe_scene::{
    DofWriter, Ending, Generator, GeneratorContext, Notes, SignalId, StartError, Step, World,
};

/// The giver waits this long for the receiver to take the object.
pub const GIVE_TIMEOUT: f64 = 10.0;
/// Seconds to carry the object to the meeting point.
pub const GIVE_REACH_SECONDS: f64 = 1.0;
/// Seconds over which a giver's empty arm comes down to its side once the hand has
/// opened.
pub const LOWER_SECONDS: f64 = 0.8;

/// How far (0 to 1, eased) an arm let go `seconds` ago has come down to its side.
fn lowered(seconds: f64) -> f64 {
    quintic((seconds / LOWER_SECONDS).clamp(0.0, 1.0))
}
/// Amplitude (metres) and frequency (Hz) of a handshake.
pub const SHAKE: (f64, f64) = (0.03, 2.0);
/// Seconds of shaking.
pub const SHAKE_SECONDS: f64 = 1.5;

fn actor_name(world: &World, i: usize) -> String {
    world
        .actors
        .get(i)
        .map(|a| a.name.clone())
        .unwrap_or_else(|| format!("#{i}"))
}

/// The giver's side of `actor:give`.
pub struct Give {
    object: usize,
    receiver: usize,
    sides: Vec<Side>,
    arrived: SignalId,
    arm: Option<ArmIk>,
    /// The DOFs that carry the object to the meeting point, from `start_q` to `goal_q`:
    /// the arm's, and the spine's and legs' when it leans or crouches.
    moving: Scope,
    start_q: Vec<f64>,
    goal_q: Vec<f64>,
    /// Where the DOFs that carried the object besides the arm go as the hand opens: back
    /// to `start_q` after a lean to give, or the upright posture a crouched giver stood
    /// up to.
    after_q: Vec<f64>,
    open: Option<BoundPattern>,
    phase: u8,
    phase_start: f64,
    q: Vec<f64>,
    samples: Vec<(usize, f64)>,
    /// Seconds the giver waits at the meeting point.
    timeout: f64,
    /// Bring the object into this hand of the receiver (a performer's glove hand) rather
    /// than to the point between the actors.
    receiver_hand: Option<Side>,
    /// Raised when this action ends, however it ends (see [`Generator::end`]); as a
    /// failure, with the reason, when it ends without handing the object over.
    ended: SignalId,
    /// Raised (as a failure, with why) when the receiver's action ends without the object.
    receiver_gave_up: Option<SignalId>,
    /// Whether the carrying arm bends round other bodies and obstacles ([`ArmDetour`]).
    detour: bool,
    /// The carry round other bodies, when the interpolation is blocked.
    arm_detour: Option<ArmDetour>,
    /// The legs while the pelvis goes down to give (or up, a crouched giver standing,
    /// or back after the hand has opened): feet flat where they stand.
    legs: Option<CrouchLegs>,
    /// Whether the give waits, holding the object, for the two actors to stand: a give
    /// started while either walks cannot know where their bodies will meet.
    approaching: bool,
}

impl Give {
    /// `object` (held by the acting actor's hand `side`) goes to `receiver`; `arrived` is
    /// raised when it is at the meeting point, `ended` when the give ends in any way.
    pub fn new(
        object: usize,
        receiver: usize,
        side: Side,
        arrived: SignalId,
        ended: SignalId,
    ) -> Give {
        Give {
            object,
            receiver,
            sides: vec![side],
            arrived,
            arm: None,
            moving: Scope::EMPTY,
            start_q: Vec::new(),
            goal_q: Vec::new(),
            after_q: Vec::new(),
            open: None,
            phase: 0,
            phase_start: 0.0,
            q: Vec::new(),
            samples: Vec::new(),
            timeout: GIVE_TIMEOUT,
            receiver_hand: None,
            ended,
            receiver_gave_up: None,
            detour: true,
            arm_detour: None,
            legs: None,
            approaching: false,
        }
    }

    /// Bends the carrying arm round other bodies and obstacles (`true`, the default) or
    /// lets it interpolate straight to the meeting point.
    pub fn detouring(mut self, on: bool) -> Give {
        self.detour = on;
        self
    }

    /// Waits `seconds` (instead of [`GIVE_TIMEOUT`]) for the receiver to take the object.
    pub fn with_timeout(mut self, seconds: f64) -> Give {
        self.timeout = seconds;
        self
    }

    /// Fails as soon as `gave_up` is raised: the receiver's action ended without the
    /// object; the give's error carries the receiver's reason.
    pub fn watching(mut self, gave_up: SignalId) -> Give {
        self.receiver_gave_up = Some(gave_up);
        self
    }

    /// Brings the object into the receiver's open hand `side` (see
    /// [`crate::grasp::handover::offer_point`]): for a receiver whose hand a person drives.
    pub fn into_hand(mut self, side: Side) -> Give {
        self.receiver_hand = Some(side);
        self
    }
}

/// The legs of a body whose pelvis goes from posture `from`'s height to `to`'s (see
/// [`CrouchLegs`]), if it moves at all.
fn crouch_legs(skeleton: &Skeleton, from: &[f64], to: &[f64]) -> Option<CrouchLegs> {
    let root_y = skeleton.dof("root_y").ok()?;
    let depth = from[root_y] - to[root_y];
    (depth != 0.0)
        .then(|| CrouchLegs::new(skeleton, from, depth))
        .flatten()
}

/// How far (m) a body's pelvis may be lowered, and (radians) its spine bent, and still
/// count as upright for a hand-over.
const UPRIGHT: (f64, f64) = (0.03, 0.15);

/// Actor `actor`'s posture in `world` stood upright, if it crouches or leans (beyond
/// [`UPRIGHT`]): its spine, legs and pelvis height at rest, the rest as it is. `None`
/// when it stands upright already (or is not there).
fn straightened(world: &World, actor: usize) -> Option<Vec<f64>> {
    let skeleton = &world.actors.get(actor)?.skeleton;
    let q = &world.states.get(actor)?.q;
    let root_y = skeleton.dof("root_y").ok()?;
    let spine = skeleton.scope("spine").ok()?;
    let bent = q[root_y] < -UPRIGHT.0 || spine.iter().any(|d| q[d].abs() > UPRIGHT.1);
    if !bent {
        return None;
    }
    let mut upright = q.clone();
    for d in BodyReach::body_scope(skeleton).ok()?.iter() {
        upright[d] = 0.0;
    }
    Some(upright)
}

/// The height (m) of actor `actor`'s shoulders in `world` standing upright (see
/// [`straightened`]: a crouched giver's shoulders put a meeting point at its waist): its
/// right shoulder's, else its left's; `None` for a body without shoulders.
fn shoulder_height(world: &World, actor: usize) -> Option<f64> {
    let skeleton = &world.actors.get(actor)?.skeleton;
    let joint = skeleton
        .joint("r_shoulder")
        .or_else(|_| skeleton.joint("l_shoulder"))
        .ok()?;
    match straightened(world, actor) {
        Some(q) => {
            let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
            troupe_body::kinematics::forward_kinematics(skeleton, &q, &mut globals);
            Some(globals[joint].translation.y)
        }
        None => Some(world.states.get(actor)?.globals[joint].translation.y),
    }
}

/// How far (radians) from a receiver's facing the giver may stand for it to take the
/// object without turning round: beyond, the giver is behind its shoulders.
pub const TURN_TO_TAKE: f64 = std::f64::consts::FRAC_PI_2;

/// The angle (radians, 0 to π) between the way `state`'s body faces and the floor
/// direction `to`.
pub fn facing_angle(state: &troupe_body::ActorState, to: troupe_body::glam::DVec2) -> f64 {
    if to.length_squared() < 1e-12 {
        return 0.0;
    }
    let forward = state.globals[0].rotation * DVec3::Z;
    let facing = troupe_body::glam::DVec2::new(forward.x, forward.z);
    facing.angle_to(to).abs()
}

/// Whether any of `actors` walks: it has a walk that has not ended (one setting off, or
/// turning on the spot, is slow), or its root moved on the floor faster than a body
/// standing (swaying or settling its feet) does over the previous tick.
pub fn walking(world: &World, actors: &[usize]) -> bool {
    actors.iter().any(|&i| {
        world.walks(i)
            || world
                .crowd
                .velocities
                .get(i)
                .is_some_and(|v| v.length() >= crate::walk::replan::STANDING)
    })
}

/// The turns (radians about the vertical) a handed-over object may make on its way to the
/// meeting point, tried in this order: none first.
const MEETING_TURNS: [f64; 12] = {
    use std::f64::consts::PI;
    [
        0.0,
        PI / 6.0,
        -PI / 6.0,
        PI / 3.0,
        -PI / 3.0,
        PI / 2.0,
        -PI / 2.0,
        2.0 * PI / 3.0,
        -2.0 * PI / 3.0,
        5.0 * PI / 6.0,
        -5.0 * PI / 6.0,
        PI,
    ]
};

/// How far below the shoulders a handed-over object meets the other hand, as a part of the
/// shoulders' height (0.3 m for an adult).
const MEETING_BELOW_SHOULDERS: f64 = 0.21;

/// Where a handed-over object's centre may go, in order of preference: halfway between the
/// two actors, 21 % of the way down from the lower one's shoulders (0.3 m for an adult,
/// 0.2 m for a child), then up in 5 cm steps to as far below the giver's.
pub fn meeting_points(world: &World, giver: usize, receiver: usize) -> Option<Vec<DVec3>> {
    let a = world.states.get(giver)?.globals.first()?.translation;
    let b = world.states.get(receiver)?.globals.first()?.translation;
    let below = |y: f64| y * (1.0 - MEETING_BELOW_SHOULDERS);
    let highest = below(shoulder_height(world, giver)?);
    let lowest = shoulder_height(world, receiver).map_or(highest, |r| below(r).min(highest));
    let mid = (a + b) * 0.5;
    let steps = ((highest - lowest) / 0.05).ceil() as usize;
    Some(
        (0..=steps)
            .map(|i| DVec3::new(mid.x, (lowest + 0.05 * i as f64).min(highest), mid.z))
            .collect(),
    )
}

impl Give {
    /// The signal raised when this give ends, for a receiver that waits for it.
    pub fn ended(&self) -> SignalId {
        self.ended
    }

    /// Whether the give can plan where the two meet: neither walks (see [`walking`]).
    fn ready(&self, world: &World, giver: usize) -> bool {
        !walking(world, &[giver, self.receiver])
    }

    /// Plans the carry from the posture of `ctx` to the first meeting point the arm
    /// reaches (leaning or crouching if it must), or says why none is in reach.
    fn plan(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        let w = ctx.world;
        let obj = &w.objects[self.object];
        let me = actor_name(w, ctx.actor);
        let goals = match self.receiver_hand {
            Some(side) => vec![crate::grasp::handover::offer_point(
                w,
                self.receiver,
                side,
                self.object,
            )?],
            None => meeting_points(w, ctx.actor, self.receiver)
                .ok_or_else(|| format!("no actor #{} to give to", self.receiver))?,
        };
        let now = Transform::new(obj.rotation, obj.position);
        let mut ik = ArmIk::new(ctx.skeleton, self.sides[0], 200)?;
        self.start_q = ctx.posture.q.clone();
        self.moving = ik.dofs().iter().copied().collect();
        let allowed = ctx
            .scope
            .intersection(&BodyReach::body_scope(ctx.skeleton)?);
        let furniture = furniture_round(w, ctx.actor, &obj.name);
        let body = BodyReach::new(ctx.skeleton, allowed)?.keeping_knees_off(furniture);
        // A giver crouched or leaning (from picking the object up) stands up as it carries
        // the object: planned from its upright posture, not from the crouch.
        let from = match straightened(w, ctx.actor) {
            Some(upright) if allowed.contains_all(&BodyReach::body_scope(ctx.skeleton)?) => {
                for d in allowed.iter() {
                    if upright[d] != ctx.posture.q[d] {
                        self.moving.insert(d);
                    }
                }
                upright
            }
            _ => ctx.posture.q.clone(),
        };
        // The object may turn about the vertical on the way (a cup stays upright): the
        // hand kept at the angle it picked the object up with could not bring it up and
        // forward (a child's hand, fingers down from grasping a ball at its hip, missed a
        // meeting point 0.3 m ahead by 0.24 m).
        let poses = |goal: DVec3| {
            MEETING_TURNS.iter().map(move |&turn| {
                let turn = DQuat::from_rotation_y(turn);
                let placed = Transform::new(turn * obj.rotation, goal);
                placed.mul(&now.inverse())
            })
        };
        // The lowest meeting point the arm reaches, else reaches leaning or crouching with
        // the object as it is held (as a grasp does: during a walk the body is the walk's,
        // and the arm is alone).
        let (mut miss, mut angle, mut wrist_goal) = (f64::INFINITY, f64::INFINITY, now);
        'goals: for &goal in &goals {
            for delta in poses(goal) {
                let wrist = delta.mul(&ctx.posture.globals[ik.wrist]);
                self.goal_q = from.clone();
                let (m, a) = ik.solve(ctx.skeleton, &mut self.goal_q, &wrist)?;
                // The closest try, for the message: a wrist placed within the tolerance
                // counts as placed, and then its angle decides.
                if (m.max(REACH_TOLERANCE), a) < (miss.max(REACH_TOLERANCE), angle) {
                    (miss, angle) = (m, a);
                }
                if m <= REACH_TOLERANCE && a <= REACH_ANGLE {
                    (miss, angle, wrist_goal) = (m, a, wrist);
                    break 'goals;
                }
            }
            let wrist = poses(goal)
                .next()
                .map_or(now, |delta| delta.mul(&ctx.posture.globals[ik.wrist]));
            let goals = [(self.sides[0], wrist)];
            if let Some(reached) = body.beyond_the_arm(&from, &goals)? {
                self.goal_q = from.clone();
                for &(d, v) in &reached.changed {
                    self.goal_q[d] = v;
                    self.moving.insert(d);
                }
                (miss, angle, wrist_goal) = (0.0, 0.0, wrist);
                break;
            }
        }
        if miss > REACH_TOLERANCE || angle > REACH_ANGLE {
            return Err(format!(
                "the meeting point with `{}` is out of reach of `{me}` ({})",
                actor_name(w, self.receiver),
                wrist_miss(miss, angle)
            )
            .into());
        }
        self.arm_detour = None;
        if self.detour {
            let to: Vec<(usize, f64)> = ik.dofs().iter().map(|&d| (d, self.goal_q[d])).collect();
            let arm = PlannedArm {
                side: self.sides[0],
                to: &to,
                wrist: wrist_goal,
                except: Some(&obj.name),
            };
            self.arm_detour = ArmDetour::plan(ctx, &arm)?;
        }
        self.arm = Some(ik);
        self.legs = crouch_legs(ctx.skeleton, &self.start_q, &self.goal_q);
        self.after_q = from;
        self.q = ctx.posture.q.clone();
        self.phase_start = ctx.local_time;
        Ok(())
    }
}

impl Generator for Give {
    fn detours(&self) -> usize {
        self.arm_detour.as_ref().map_or(0, ArmDetour::detours)
    }

    fn unfinished(&self) -> Option<String> {
        (self.phase < 2).then(|| "stopped before the receiver took the object".to_string())
    }

    /// The receiver waiting for the object learns that the give ended, and why if it
    /// ended without handing the object over.
    fn end(&mut self, ending: &Ending, notes: &mut Notes) {
        match ending.failure() {
            None => notes.raise(self.ended),
            Some(why) => notes.fail(self.ended, why),
        }
    }

    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        let w = ctx.world;
        let obj = w
            .objects
            .get(self.object)
            .ok_or_else(|| format!("no object #{}", self.object))?;
        let me = actor_name(w, ctx.actor);
        if self.receiver == ctx.actor {
            return Err(format!("`{me}` cannot give `{}` to itself", obj.name).into());
        }
        if w.holder(self.object).is_none_or(|h| h.actor != ctx.actor) {
            return Err(format!("`{me}` does not hold `{}`", obj.name).into());
        }
        // A meeting point between bodies that walk is not where they will meet: the give
        // waits until both stand (a performer's glove hand is met wherever it is).
        if self.receiver_hand.is_none() && !self.ready(w, ctx.actor) {
            self.approaching = true;
            return Ok(());
        }
        self.plan(ctx)
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        if let Some(why) = self
            .receiver_gave_up
            .and_then(|s| ctx.world.board.failure(s, ctx.tick))
        {
            if ctx
                .world
                .holder(self.object)
                .is_none_or(|h| h.actor != self.receiver)
            {
                return Step::Failed(format!(
                    "`{}`'s receive ended without the object ({why})",
                    actor_name(ctx.world, self.receiver)
                ));
            }
        }
        if self.approaching {
            if !self.ready(ctx.world, ctx.actor) {
                if ctx.local_time > self.timeout {
                    return Step::Failed(format!(
                        "`{}` and `{}` did not both stand still within {} s (a give waits \
                         for that to find where they meet)",
                        actor_name(ctx.world, ctx.actor),
                        actor_name(ctx.world, self.receiver),
                        self.timeout
                    ));
                }
                // The arm keeps the object where it was carried.
                for d in out.scope().iter() {
                    out.set(d, ctx.posture.q[d]);
                }
                return Step::Running;
            }
            if let Err(e) = self.plan(ctx) {
                return Step::Failed(e.reason);
            }
            self.approaching = false;
        }
        let Some(arm) = &self.arm else {
            return Step::Failed("give: not started".into());
        };
        self.q.copy_from_slice(&ctx.posture.q);
        let t = ctx.local_time - self.phase_start;
        match self.phase {
            0 => {
                let u = quintic(t / GIVE_REACH_SECONDS);
                let finished = u >= 1.0 - 1e-12;
                for d in self.moving.iter() {
                    self.q[d] = self.start_q[d] + (self.goal_q[d] - self.start_q[d]) * u;
                }
                if let Some(legs) = &mut self.legs {
                    legs.apply(ctx.skeleton, &mut self.q);
                }
                if let Some(around) = &mut self.arm_detour {
                    let tau = if finished {
                        1.0
                    } else {
                        t / GIVE_REACH_SECONDS
                    };
                    if let Err(e) = around.step(ctx, tau, &mut self.q) {
                        return Step::Failed(e.to_string());
                    }
                    if finished {
                        // From now on the arm stays where the last solve put it.
                        for (d, v) in around.solved() {
                            self.goal_q[d] = v;
                        }
                    }
                }
                if let (true, Some(legs)) = (finished, &self.legs) {
                    // And the legs where they were solved for the pelvis (feet where they
                    // stood), not the plan's interpolation target.
                    for d in legs.dofs() {
                        self.goal_q[d] = self.q[d];
                    }
                }
                if finished {
                    self.phase = 1;
                    self.phase_start = ctx.local_time;
                }
            }
            1 => {
                for d in self.moving.iter() {
                    self.q[d] = self.goal_q[d];
                }
                // The arm is at the goal since the last tick: the object is there.
                out.raise(self.arrived);
                match ctx.world.holder(self.object) {
                    Some(h) if h.actor == self.receiver => {
                        let mut open = match HandPattern::open(ctx.skeleton, self.sides[0]) {
                            Ok(p) => p,
                            Err(e) => return Step::Failed(e.to_string()),
                        };
                        open.restart_from(&ctx.posture.q);
                        self.open = Some(open);
                        self.legs = crouch_legs(ctx.skeleton, &self.goal_q, &self.after_q);
                        self.phase = 2;
                        self.phase_start = ctx.local_time;
                    }
                    Some(h) if h.actor == ctx.actor => {
                        if t > self.timeout {
                            return Step::Failed(format!(
                                "`{}` did not take the object within {} s",
                                actor_name(ctx.world, self.receiver),
                                self.timeout
                            ));
                        }
                    }
                    _ => {
                        return Step::Failed(
                            "the object left the giver's hand without reaching the receiver".into(),
                        )
                    }
                }
            }
            _ => {
                let s = (t / OPEN_SECONDS).min(1.0);
                // The hand opens where it gave; a body that leaned or crouched to give
                // straightens meanwhile; then the empty arm comes down to the side (left
                // held out, it stood in the way of the next person passing: a forearm
                // 7 cm into it).
                let back = quintic(s);
                let down = lowered(t - OPEN_SECONDS);
                for d in self.moving.iter() {
                    self.q[d] = if arm.dofs().contains(&d) {
                        self.goal_q[d] * (1.0 - down)
                    } else {
                        self.goal_q[d] + (self.after_q[d] - self.goal_q[d]) * back
                    };
                }
                if let Some(legs) = &mut self.legs {
                    legs.apply(ctx.skeleton, &mut self.q);
                }
                if let Some(open) = &self.open {
                    open.sample(s, &mut self.samples);
                    for &(d, v) in &self.samples {
                        self.q[d] = v;
                    }
                }
                for d in out.scope().iter() {
                    out.set(d, self.q[d]);
                }
                return if down >= 1.0 {
                    Step::Finished
                } else {
                    Step::Running
                };
            }
        }
        for d in out.scope().iter() {
            out.set(d, self.q[d]);
        }
        Step::Running
    }
}

/// How much further apart (m) than when they closed two held hands may come before the
/// hold fails: the follower's arm turns no faster than a reach's and lags a walk's step
/// by a few centimetres.
const HANDS_APART: f64 = 0.15;

/// The active side of `actor:hold_hand` / `actor:shake_hands`.
pub struct HoldHand {
    other: usize,
    other_side: Side,
    side: Side,
    shake: bool,
    /// Whether the other holds its hand out (see [`offer`]): reached for where it will be.
    offered: bool,
    held: SignalId,
    finished: SignalId,
    /// Raised as a failure when the follower's `follow_hand` ends before the hold does.
    follower_gave_up: SignalId,
    /// The other's wrist joint, and how far apart (m) the two wrists were once the
    /// fingers had closed.
    other_wrist: usize,
    apart: Option<f64>,
    model: Option<HandModel>,
    arm: Option<ArmIk>,
    wrist_goal: Transform,
    start_q: Vec<f64>,
    goal_q: Vec<f64>,
    pattern: Option<BoundPattern>,
    blocked: Scope,
    s: f64,
    phase: u8,
    phase_start: f64,
    q: Vec<f64>,
    globals: Vec<Transform>,
    samples: Vec<(usize, f64)>,
    /// Asked to stop: lets go at the next tick (see [`Generator::stop`]).
    letting_go: bool,
}

impl HoldHand {
    /// The acting actor's hand `side` holds `other`'s hand `other_side`; with `shake`, it
    /// shakes it and lets go. `held` is raised once the fingers are closed, `finished`
    /// when a handshake is over; the follower raises `follower_gave_up` as a failure if
    /// its action ends first.
    pub fn new(
        other: usize,
        (side, other_side): (Side, Side),
        shake: bool,
        (held, finished, follower_gave_up): (SignalId, SignalId, SignalId),
    ) -> HoldHand {
        HoldHand {
            other,
            other_side,
            side,
            shake,
            offered: false,
            held,
            finished,
            follower_gave_up,
            other_wrist: 0,
            apart: None,
            model: None,
            arm: None,
            wrist_goal: Transform::IDENTITY,
            start_q: Vec::new(),
            goal_q: Vec::new(),
            pattern: None,
            blocked: Scope::EMPTY,
            s: 0.0,
            phase: 0,
            phase_start: 0.0,
            q: Vec::new(),
            globals: Vec::new(),
            samples: Vec::new(),
            letting_go: false,
        }
    }

    /// Reaches for the other's hand where it holds it out (see [`offer`]), not where it
    /// is now.
    pub fn to_offered_hand(mut self) -> HoldHand {
        self.offered = true;
        self
    }

    fn write(&self, out: &mut DofWriter) {
        for d in out.scope().iter() {
            out.set(d, self.q[d]);
        }
    }
}

/// Signed distance from `p` to actor `actor`'s body solids in `world`.
fn body_distance(world: &World, actor: usize, p: DVec3) -> f64 {
    posed_distance(
        &world.actors[actor].skeleton,
        &world.states[actor].globals,
        p,
    )
}

/// Signed distance from `p` to the solids of `skeleton` with joint frames `globals`.
fn posed_distance(skeleton: &Skeleton, globals: &[Transform], p: DVec3) -> f64 {
    skeleton
        .solids()
        .iter()
        .map(|(j, s)| solid_distance(s, &globals[*j], p))
        .fold(f64::INFINITY, f64::min)
}

impl Generator for HoldHand {
    /// A hold that ends any way (cancelled, pre-empted, its duration over, failed to
    /// start, never admitted) lets the follower go too, from the next tick on.
    fn end(&mut self, _ending: &Ending, notes: &mut Notes) {
        notes.raise(self.finished);
    }

    /// Stopped or cancelled once the hands hold, the hand opens, lets go and the arm
    /// comes down to the side as after a handshake; before, the action eases out.
    fn stop(&mut self) -> bool {
        if self.phase < 2 {
            return false;
        }
        self.letting_go = true;
        true
    }

    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        let w = ctx.world;
        let me = actor_name(w, ctx.actor);
        if self.other == ctx.actor || self.other >= w.actors.len() {
            return Err(format!("`{me}` needs another actor to hold hands with").into());
        }
        let other = actor_name(w, self.other);
        let their_skeleton = &w.actors[self.other].skeleton;
        let theirs = HandModel::new(their_skeleton, self.other_side)?;
        self.other_wrist = theirs.sensors.wrist;
        // A hand that holds something takes no other hand: a shake with a cup in it
        // closed the other's fingers round the cup.
        for (actor, skeleton, side) in [
            (ctx.actor, ctx.skeleton, self.side),
            (self.other, their_skeleton, self.other_side),
        ] {
            if let Some(held) = held_in(w, skeleton, actor, side) {
                let whose = if actor == ctx.actor {
                    "the".to_string()
                } else {
                    format!("`{other}`'s")
                };
                return Err(format!(
                    "{whose} {} hand already holds `{held}`: place or release it first",
                    side.name()
                )
                .into());
            }
        }
        // Their body as it will be once the hand is held out, or as it is.
        let posed;
        let their_globals: &[Transform] = if self.offered {
            let grip = if self.shake {
                offer::Grip::Shake
            } else {
                offer::Grip::Hold
            };
            let (theirs, mine) = ((self.other, self.other_side), (ctx.actor, self.side));
            posed = offer::offered_hand(w, theirs, mine, grip)?.globals;
            &posed
        } else {
            &w.states[self.other].globals
        };
        let tg = &their_globals[theirs.sensors.wrist];
        let their_palm = tg.transform_point(theirs.sensors.palm);
        let their_normal = tg.rotation * theirs.sensors.palm_normal;
        let their_fingers = tg.rotation * theirs.sensors.finger_direction;
        let model = HandModel::new(ctx.skeleton, self.side)?;
        let hs = &model.sensors;
        let g = &ctx.posture.globals;
        let wrist_now = g[hs.wrist];
        let local: Vec<(DVec3, f64)> = (0..hs.sensors.len())
            .map(|i| {
                (
                    wrist_now.inverse().transform_point(hs.center(i, g)),
                    hs.sensors[i].radius,
                )
            })
            .collect();
        // Palm against their palm or around the back of their hand (4.5: the hand's
        // bounding volumes guide the frame); fingers along or against theirs. The cost
        // (translation + rotation) and reachability choose.
        let mut ranked = Vec::new();
        let mut pairs = Vec::new();
        for a in [-their_normal, their_normal] {
            // Fingers along theirs, turned about the palm normal in 45° steps.
            for k in 0..8 {
                let turn = DQuat::from_axis_angle(a, k as f64 * std::f64::consts::FRAC_PI_4);
                pairs.push((a, (turn * their_fingers).normalize()));
            }
        }
        for (a, f) in pairs {
            let rot = frame_rotation(hs.palm_normal, hs.finger_direction, a, f);
            let mut origin = their_palm;
            let mut free = false;
            for _ in 0..200 {
                let wrist = Transform::new(rot, origin - rot * hs.palm);
                if local.iter().all(|(p, r)| {
                    posed_distance(their_skeleton, their_globals, wrist.transform_point(*p)) - r
                        >= CLEARANCE
                }) {
                    free = true;
                    break;
                }
                origin -= a * SEARCH_STEP;
            }
            if !free {
                continue;
            }
            let wrist = Transform::new(rot, origin - rot * hs.palm);
            let cost = (origin - wrist_now.transform_point(hs.palm)).length()
                + ROTATION_WEIGHT * rotation_error(wrist_now.rotation, rot).length();
            ranked.push((cost, wrist));
        }
        ranked.sort_by(|x, y| x.0.total_cmp(&y.0));
        let mut ik = ArmIk::new(ctx.skeleton, self.side, 200)?;
        let mut best = f64::INFINITY;
        for (_, wrist) in ranked.iter().take(12) {
            let mut q = ctx.posture.q.clone();
            let (miss, angle) = ik.solve(ctx.skeleton, &mut q, wrist)?;
            if miss <= REACH_TOLERANCE && angle <= REACH_ANGLE {
                self.goal_q = q;
                self.wrist_goal = *wrist;
                self.start_q = ctx.posture.q.clone();
                self.q = ctx.posture.q.clone();
                self.pattern = Some(HandPattern::builtin(GraspType::Wrap).bind(
                    ctx.skeleton,
                    self.side,
                    &ctx.posture.q,
                )?);
                self.model = Some(model);
                self.arm = Some(ik);
                return Ok(());
            }
            best = best.min(miss);
        }
        Err(format!(
            "`{other}`'s {} hand is out of reach of `{me}`'s {} hand (misses by {best:.3} m)",
            self.other_side.name(),
            self.side.name()
        )
        .into())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let (Some(model), Some(arm)) = (&self.model, &mut self.arm) else {
            return Step::Failed("hold_hand: not started".into());
        };
        let t = ctx.local_time - self.phase_start;
        self.q.copy_from_slice(&ctx.posture.q);
        let board = ctx.world.board;
        // Letting go, the other's hand may go first.
        let going = self.letting_go || self.phase > 2;
        if let (Some(why), false) = (board.failure(self.follower_gave_up, ctx.tick), going) {
            return Step::Failed(format!(
                "`{}`'s follow_hand ended first ({why}): nobody holds the other hand",
                actor_name(ctx.world, self.other)
            ));
        }
        let wrists_apart = || {
            let theirs = ctx.world.states[self.other].globals[self.other_wrist];
            let mine = ctx.posture.globals[model.sensors.wrist];
            mine.translation.distance(theirs.translation)
        };
        let let_go = self.phase > 2 && t >= OPEN_SECONDS;
        if let (Some(apart), false) = (self.apart, let_go) {
            // A follower that walks away, or is carried off, takes its hand out of ours
            // (once the hand has opened to let go, the other's comes down).
            let now = wrists_apart();
            if now > apart + HANDS_APART {
                return Step::Failed(format!(
                    "the hands came apart: `{}`'s {} hand is {now:.2} m from `{}`'s {} hand",
                    actor_name(ctx.world, self.other),
                    self.other_side.name(),
                    actor_name(ctx.world, ctx.actor),
                    self.side.name()
                ));
            }
        }
        match self.phase {
            0 => {
                let u = quintic(t / 1.0);
                for &d in arm.dofs() {
                    self.q[d] = self.start_q[d] + (self.goal_q[d] - self.start_q[d]) * u;
                }
                if u >= 1.0 - 1e-12 {
                    self.phase = 1;
                    self.phase_start = ctx.local_time;
                    if let Some(p) = &mut self.pattern {
                        p.restart_from(&ctx.posture.q);
                    }
                }
            }
            1 => {
                for &d in arm.dofs() {
                    self.q[d] = self.goal_q[d];
                }
                self.globals.clear();
                self.globals.extend_from_slice(&ctx.posture.globals);
                self.s = (self.s + ctx.dt / CLOSE_SECONDS).min(1.0);
                if let Some(p) = &self.pattern {
                    p.sample(self.s, &mut self.samples);
                }
                let (w, other) = (ctx.world, self.other);
                let field = |p: DVec3| body_distance(w, other, p);
                model.advance(
                    ctx.skeleton,
                    &mut self.q,
                    &mut self.globals,
                    &self.samples,
                    &mut self.blocked,
                    &field,
                );
                if self.s >= 1.0 {
                    out.raise(self.held);
                    self.apart = Some(wrists_apart());
                    self.phase = 2;
                    self.phase_start = ctx.local_time;
                }
            }
            2 => {
                if !self.shake {
                    // Holding: the arm keeps its posture relative to the body; the
                    // passive actor follows.
                    for &d in arm.dofs() {
                        self.q[d] = self.goal_q[d];
                    }
                } else {
                    let (amplitude, hz) = SHAKE;
                    let dy = amplitude * (std::f64::consts::TAU * hz * (t + ctx.dt)).sin();
                    let goal = Transform::new(
                        self.wrist_goal.rotation,
                        self.wrist_goal.translation + DVec3::Y * dy,
                    );
                    if let Err(e) = arm.solve(ctx.skeleton, &mut self.q, &goal) {
                        return Step::Failed(e.to_string());
                    }
                }
                // Let go when the shake is over, or when asked to stop (a hold cancelled
                // or stopped: its arm stayed held out for good).
                if self.letting_go || (self.shake && t + ctx.dt >= SHAKE_SECONDS) {
                    // The hand opens where the shake left the arm: the per-tick solve
                    // drifts from the planned posture, and going back to it in one
                    // tick snapped the elbow (10 rad/s).
                    for &d in arm.dofs() {
                        self.goal_q[d] = self.q[d];
                    }
                    self.phase = 3;
                    self.phase_start = ctx.local_time;
                    if let Some(p) = &mut self.pattern {
                        *p = match HandPattern::open(ctx.skeleton, self.side) {
                            Ok(p) => p,
                            Err(e) => return Step::Failed(e.to_string()),
                        };
                        p.restart_from(&ctx.posture.q);
                    }
                }
            }
            _ => {
                // The hand opens, lets the other go, and the arm comes down to the side.
                let s = (t / OPEN_SECONDS).min(1.0);
                let down = lowered(t - OPEN_SECONDS);
                for &d in arm.dofs() {
                    self.q[d] = self.goal_q[d] * (1.0 - down);
                }
                if let Some(p) = &self.pattern {
                    p.sample(s, &mut self.samples);
                    for &(d, v) in &self.samples {
                        self.q[d] = v;
                    }
                }
                if s >= 1.0 {
                    out.raise(self.finished);
                }
                if down >= 1.0 {
                    self.write(out);
                    return Step::Finished;
                }
            }
        }
        self.write(out);
        Step::Running
    }
}

/// The passive side of holding hands: keeps its hand where it is relative to the active
/// actor's hand, by IK every tick.
pub struct FollowHand {
    active: usize,
    active_wrist: usize,
    side: Side,
    held: SignalId,
    finished: SignalId,
    /// Raised as a failure if this action ends before the hold does.
    gave_up: SignalId,
    arm: Option<ArmIk>,
    /// How it holds its hand out first, if it does (see [`offer`]), to the active hand
    /// of which side; and then the arm's values from where it started to where it holds
    /// the hand out.
    offers: Option<(offer::Grip, Side)>,
    offer: Vec<(usize, f64, f64)>,
    relative: Option<Transform>,
    last: Option<Transform>,
    /// When the hold ended (local time), and the arm's values then, which it lowers from.
    let_go: Option<f64>,
    lower_from: Vec<(usize, f64)>,
    q: Vec<f64>,
}

impl FollowHand {
    /// Follows `active`'s joint `active_wrist` with the hand `side` once `held` is raised,
    /// until `finished` is; raises `gave_up` as a failure if it ends before that.
    pub fn new(
        (active, active_wrist): (usize, usize),
        side: Side,
        (held, finished, gave_up): (SignalId, SignalId, SignalId),
    ) -> FollowHand {
        FollowHand {
            active,
            active_wrist,
            side,
            held,
            finished,
            gave_up,
            arm: None,
            offers: None,
            offer: Vec::new(),
            relative: None,
            last: None,
            let_go: None,
            lower_from: Vec::new(),
            q: Vec::new(),
        }
    }

    /// Holds the hand out to the active actor's hand `active_side` until it is held, as
    /// `grip` says (see [`offer`]).
    pub fn offering(mut self, grip: offer::Grip, active_side: Side) -> FollowHand {
        self.offers = Some((grip, active_side));
        self
    }
}

impl Generator for FollowHand {
    /// A follower that ends before the hold (cancelled, pre-empted, failed) lets the
    /// holding actor know, which then fails rather than hold an empty hand.
    fn end(&mut self, ending: &Ending, notes: &mut Notes) {
        if let Some(why) = ending.failure() {
            notes.fail(self.gave_up, why);
        }
    }

    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        if ctx.world.states.get(self.active).is_none() {
            return Err(format!("no actor #{} to follow", self.active).into());
        }
        self.arm = Some(ArmIk::new(ctx.skeleton, self.side, 40)?);
        self.q = ctx.posture.q.clone();
        if let Some((grip, active_side)) = self.offers {
            let (mine, theirs) = ((ctx.actor, self.side), (self.active, active_side));
            let offer = offer::offered_hand(ctx.world, mine, theirs, grip)?;
            self.offer = offer
                .arm
                .iter()
                .map(|&(d, v)| (d, ctx.posture.q[d], v))
                .collect();
        }
        Ok(())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let Some(arm) = &mut self.arm else {
            return Step::Failed("follow: not started".into());
        };
        let mine: Vec<(usize, f64)> = out.scope().iter().map(|d| (d, self.q[d])).collect();
        self.q.copy_from_slice(&ctx.posture.q);
        if ctx.world.board.before(self.finished, ctx.tick) {
            // Let go: the arm comes down to the side from where the hold left it.
            let since = *self.let_go.get_or_insert(ctx.local_time);
            let down = lowered(ctx.local_time - since);
            if self.lower_from.is_empty() {
                self.lower_from = arm.dofs().iter().map(|&d| (d, ctx.posture.q[d])).collect();
            }
            for &(d, from) in &self.lower_from {
                self.q[d] = from * (1.0 - down);
            }
            for d in out.scope().iter() {
                out.set(d, self.q[d]);
            }
            return if down >= 1.0 {
                Step::Finished
            } else {
                Step::Running
            };
        }
        if ctx.world.board.before(self.held, ctx.tick) {
            for &(d, v) in &mine {
                self.q[d] = v;
            }
            let a = ctx.world.states[self.active].globals[self.active_wrist];
            let rel = *self
                .relative
                .get_or_insert_with(|| a.inverse().mul(&ctx.posture.globals[arm.wrist]));
            // Extrapolate the active hand one tick: this tick's output lands with it.
            let predicted = match self.last {
                Some(l) => Transform::new(
                    (a.rotation * l.rotation.inverse()) * a.rotation,
                    a.translation + (a.translation - l.translation),
                ),
                None => a,
            };
            self.last = Some(a);
            let goal = predicted.mul(&rel);
            if let Err(e) = arm.solve(ctx.skeleton, &mut self.q, &goal) {
                return Step::Failed(e.to_string());
            }
            // As a reach's: the IK may find the arm another way at once where a DOF locks
            // at its limit, or swing it between two ways with the hand out of reach.
            hold_to_joint_speed(&mut self.q, mine, ctx.dt);
        } else {
            // Holding the hand out, until the other has it.
            let u = quintic(ctx.local_time / offer::OFFER_SECONDS);
            for &(d, from, to) in &self.offer {
                self.q[d] = from + (to - from) * u;
            }
        }
        for d in out.scope().iter() {
            out.set(d, self.q[d]);
        }
        Step::Running
    }
}

/// What a wrist goal out of reach missed by: the distance when its position missed, the
/// angle (degrees) when its orientation did, both when both did.
fn wrist_miss(miss: f64, angle: f64) -> String {
    let degrees = angle.to_degrees();
    match (miss > REACH_TOLERANCE, angle > REACH_ANGLE) {
        (true, true) => format!("misses by {miss:.3} m, and the wrist's angle by {degrees:.1}°"),
        (false, true) => format!("reaches it, but the wrist's angle misses by {degrees:.1}°"),
        _ => format!("misses by {miss:.3} m"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrist_miss_names_what_missed() {
        let off = 10f64.to_radians();
        // The position missed: the distance alone.
        assert_eq!(wrist_miss(0.2, 0.0), "misses by 0.200 m");
        // The orientation missed, the position reached: the angle, not the tolerance's
        // distance (it said "misses by 0.003 m").
        assert_eq!(
            wrist_miss(0.003, off),
            "reaches it, but the wrist's angle misses by 10.0°"
        );
        // Both missed: both.
        assert_eq!(
            wrist_miss(0.2, off),
            "misses by 0.200 m, and the wrist's angle by 10.0°"
        );
    }
}
