//! The grasp, release and place generators (thesis 4.3.3–4.3.4, 4.4).
//!
//! A grasp plans at its start ([`super::plan::plan_grasp`]), moves the arm(s) from the
//! current posture to the planned one with the quintic ease (4.3.3: interpolation of the
//! arm DOFs toward the IK solution), then closes the fingers along the hand motion
//! pattern until every finger DOF has stopped (4.3.4), asks the scene to attach the
//! object to the first hand, and completes once the snapshot shows it holding it. When
//! that interpolation would take an arm through another actor's body or an obstacle,
//! the hand goes round it through temporary goals instead ([`ArmDetour`], 4.6.3).

use super::body::{furniture_round, BodyReach, CrouchLegs};
use super::body::{REACH_ANGLE, REACH_TOLERANCE};
use super::close::HandModel;
use super::follow::FollowBody;
use super::keep::KeepArms;
use super::pattern::{BoundPattern, HandPattern};
use super::plan::{plan_grasp, ArmIk, GraspPlan, HandPlan, PlanOptions};
use crate::error::{OptionError, Result};
use crate::reach::arm_detour::{ArmDetour, PlannedArm};
use crate::reach::quintic;
use troupe_body::glam::DVec3;
use troupe_body::sensors::{object_distance, Side};
use troupe_body::{Scope, Skeleton, Transform};
use troupe_scene::holding::HoldRequest;
use troupe_scene::{
    DofWriter, Ending, Generator, GeneratorContext, Note, Notes, Scene, SignalId, StartError, Step,
};

/// Seconds the fingers take to close along a pattern.
pub const CLOSE_SECONDS: f64 = 0.6;
/// Seconds the fingers take to open.
pub const OPEN_SECONDS: f64 = 0.4;
/// Farthest (m) the palm's centre may be from the object's surface when the fingers have
/// closed for the grasp to hold it; further, the hand missed it (the object or the body
/// moved beyond the arm's reach during the grasp) and the grasp fails rather than holding
/// the object at a distance.
pub const PALM_REACH: f64 = 0.1;

/// The DOFs a grasp with these hands drives: arms and hands.
pub fn grasp_scope(skeleton: &Skeleton, sides: &[Side]) -> Result<Scope> {
    let mut scope = Scope::EMPTY;
    for s in sides {
        let e = skeleton.scope(&format!("{0}_arm+{0}_hand", s.name()))?;
        scope = scope.union(&e);
    }
    Ok(scope)
}

/// The DOFs a grasp or receive with the hands `sides` drives by default: the arms and
/// hands, and the whole-body part it may need to reach ([`BodyReach::body_scope`]: the
/// spine, the legs and `root_y`). Its spec yields that part: during a walk the grasp
/// starts at once without the legs (see `docs/scheduling.md`).
pub fn reach_scope(skeleton: &Skeleton, sides: &[Side]) -> Result<(Scope, Scope)> {
    let body = BodyReach::body_scope(skeleton)?;
    Ok((grasp_scope(skeleton, sides)?.union(&body), body))
}

/// Refuses a place that is not finite or not reached in a positive time.
pub(crate) fn check_place(at: DVec3, seconds: f64) -> Result<(), OptionError> {
    check_duration(seconds)?;
    if at.is_finite() {
        Ok(())
    } else {
        Err(OptionError::refused("at", "place: `at` must be finite"))
    }
}

/// The hand of `actor` that holds `object`, if one does (the one it is attached to).
pub fn holding_side(scene: &Scene, actor: usize, object: usize) -> Option<Side> {
    holding_sides(scene, actor, object).first().copied()
}

/// Every hand of `actor` that holds `object`: the one it is attached to, then the other
/// of a two-handed hold.
pub fn holding_sides(scene: &Scene, actor: usize, object: usize) -> Vec<Side> {
    let Some(h) = scene.holder(object).filter(|h| h.actor == actor) else {
        return Vec::new();
    };
    let joints = scene.actors()[actor].skeleton.joints();
    h.wrists()
        .map(|wrist| Side::of_joint(&joints[wrist].name).unwrap_or(Side::Right))
        .collect()
}

/// Refuses a duration that is not a finite number of seconds > 0.
pub(crate) fn check_duration(seconds: f64) -> Result<(), OptionError> {
    if seconds.is_finite() && seconds > 0.0 {
        Ok(())
    } else {
        Err(OptionError::refused(
            "duration",
            format!("duration must be a finite number of seconds > 0, got {seconds}"),
        ))
    }
}

/// One hand's closing state.
struct Closing {
    model: HandModel,
    pattern: BoundPattern,
    blocked: Scope,
}

enum Phase {
    Waiting,
    Reach,
    Close,
    Attach,
    Verify,
}

/// The grasp generator.
pub struct Grasp {
    object: usize,
    options: PlanOptions,
    sides: Vec<Side>,
    reach_seconds: f64,
    plan: Option<GraspPlan>,
    start_q: Vec<f64>,
    phase: Phase,
    phase_start: f64,
    closing: Vec<Closing>,
    s: f64,
    q: Vec<f64>,
    globals: Vec<Transform>,
    samples: Vec<(usize, f64)>,
    /// Wait for this signal before planning (a receiver waits for the giver).
    gate: Option<SignalId>,
    /// Raised when the giver's action ended: a receiver still waiting fails.
    abort: Option<SignalId>,
    /// Raised when the object is held.
    done: Option<SignalId>,
    /// Raised when this action ends without the object, with why (a giver stops waiting).
    gave_up: Option<SignalId>,
    /// Whether the arms bend round other bodies and obstacles ([`ArmDetour`]).
    detour: bool,
    /// Per planned hand, its motion round other bodies when the interpolation is blocked.
    detours: Vec<Option<ArmDetour>>,
    /// The arms' targets, solved again while the body moves on (a grasp during a walk).
    follow: Option<FollowBody>,
    /// The legs under a crouching grasp, solved for each height of the pelvis.
    crouch: Option<CrouchLegs>,
    /// The arms this grasp does not reach with, kept on the body as it leans or crouches.
    keep: KeepArms,
    /// The DOFs of the arms it neither reaches with nor keeps: left to other actions.
    idle: Scope,
}

impl Grasp {
    /// A grasp of object `object` by the hands `sides` (which must be the plan's hands),
    /// reaching in `reach_seconds`.
    pub fn new(
        object: usize,
        options: PlanOptions,
        sides: Vec<Side>,
        reach_seconds: f64,
    ) -> Result<Grasp> {
        check_duration(reach_seconds)?;
        Ok(Grasp {
            object,
            options,
            sides,
            reach_seconds,
            plan: None,
            start_q: Vec::new(),
            phase: Phase::Reach,
            phase_start: 0.0,
            closing: Vec::new(),
            s: 0.0,
            q: Vec::new(),
            globals: Vec::new(),
            samples: Vec::new(),
            gate: None,
            abort: None,
            done: None,
            gave_up: None,
            detour: true,
            detours: Vec::new(),
            follow: None,
            crouch: None,
            keep: KeepArms::default(),
            idle: Scope::EMPTY,
        })
    }

    /// Bends the arms round other bodies and obstacles (`true`, the default) or lets
    /// them interpolate straight to the plan.
    pub fn detouring(mut self, on: bool) -> Self {
        self.detour = on;
        self
    }

    /// Fails while still waiting for its gate once `abort` is raised (the giver's action
    /// ended without the object arriving).
    pub fn abandoned_by(mut self, abort: SignalId) -> Self {
        self.abort = Some(abort);
        self
    }

    /// Raises `gave_up` as a failure, with the reason, if this action ends without the
    /// object (failed or cancelled): the giver fails at once with that reason.
    pub fn reporting(mut self, gave_up: SignalId) -> Self {
        self.gave_up = Some(gave_up);
        self
    }

    /// Waits for `gate` before planning.
    pub fn gated(mut self, gate: SignalId) -> Self {
        self.gate = Some(gate);
        self.phase = Phase::Waiting;
        self
    }

    /// Raises `done` once the object is held.
    pub fn signalling(mut self, done: SignalId) -> Self {
        self.done = Some(done);
        self
    }

    fn begin(&mut self, ctx: &GeneratorContext) -> crate::error::Result<()> {
        // A hand-over: keep the palm away from the giver's palm.
        if let (Some(from), Some(h)) = (self.options.from, ctx.world.holder(self.object)) {
            if h.actor == from {
                let giver = &ctx.world.actors[from].skeleton;
                let side = if giver.joints()[h.joint].name.starts_with("l_") {
                    Side::Left
                } else {
                    Side::Right
                };
                let model = HandModel::new(giver, side)?;
                let palm =
                    ctx.world.states[from].globals[h.joint].transform_point(model.sensors.palm);
                self.options.avoid = Some(palm);
            }
        }
        // Lean and crouch with what the action's scope (as admitted) allows.
        self.options.body = Some(
            ctx.scope
                .intersection(&BodyReach::body_scope(ctx.skeleton)?),
        );
        let plan = plan_grasp(
            ctx.skeleton,
            ctx.posture,
            ctx.actor,
            ctx.world,
            self.object,
            &self.options,
        )?;
        let planned: Vec<Side> = plan.hands.iter().map(|h| h.side).collect();
        if planned.iter().any(|s| !self.sides.contains(s)) {
            return Err(crate::error::ActionError::Unfit(format!(
                "the plan needs the {} hand(s), outside this action's scope",
                planned
                    .iter()
                    .map(|s| s.name())
                    .collect::<Vec<_>>()
                    .join(" and ")
            )));
        }
        self.closing.clear();
        for h in &plan.hands {
            let model = HandModel::new(ctx.skeleton, h.side)?;
            let pattern =
                HandPattern::builtin(plan.grasp).bind(ctx.skeleton, h.side, &ctx.posture.q)?;
            self.closing.push(Closing {
                model,
                pattern,
                blocked: Scope::EMPTY,
            });
        }
        self.detours.clear();
        if self.detour {
            let name = ctx.world.objects.get(self.object).map(|o| o.name.as_str());
            for h in &plan.hands {
                let arm = PlannedArm {
                    side: h.side,
                    to: &h.arm,
                    wrist: h.wrist,
                    except: name,
                };
                self.detours.push(ArmDetour::plan(ctx, &arm)?);
            }
        }
        self.start_q = ctx.posture.q.clone();
        self.crouch = None;
        if plan.crouch > 0.0 {
            self.crouch = CrouchLegs::new(ctx.skeleton, &ctx.posture.q, plan.crouch);
        }
        // Leaning or crouching, the arms it does not reach with stay on the body; the
        // arms of hands it neither reaches with nor keeps are left to other actions.
        self.keep = KeepArms::default();
        let kept = if plan.lean > 0.0 || plan.crouch > 0.0 {
            self.keep
                .keep_free_arms(ctx.skeleton, &ctx.scope, &planned, &ctx.posture.globals)?
        } else {
            Vec::new()
        };
        self.idle = Scope::EMPTY;
        for side in [Side::Right, Side::Left] {
            if !self.sides.contains(&side) && !kept.contains(&side) {
                let arm = ctx.skeleton.scope(&format!("{}_arm", side.name()))?;
                self.idle = self.idle.union(&arm);
            }
        }
        self.follow = Some(FollowBody::new(ctx.skeleton, &ctx.posture.q, &plan.hands)?);
        self.plan = Some(plan);
        self.phase = Phase::Reach;
        self.phase_start = ctx.local_time;
        Ok(())
    }

    /// Sets each planned hand's arm in `self.q`: the part `u` of the way from where the
    /// grasp started to its target, or (`None`) the target itself; the targets follow the
    /// body as it moves on (see [`FollowBody`]).
    fn set_arms(&mut self, ctx: &GeneratorContext, u: Option<f64>) -> Result<(), String> {
        let Some(plan) = &self.plan else {
            return Err("grasp: no plan".into());
        };
        for i in 0..plan.hands.len() {
            let arm = match &mut self.follow {
                Some(f) => f
                    .arm(ctx.skeleton, &ctx.posture.q, &plan.hands, i)
                    .map_err(|e| e.to_string())?,
                None => &plan.hands[i].arm,
            };
            for &(d, v) in arm {
                self.q[d] = match u {
                    Some(u) => self.start_q[d] + (v - self.start_q[d]) * u,
                    None => v,
                };
            }
        }
        if let (Some(legs), Some(_)) = (&mut self.crouch, u) {
            legs.apply(ctx.skeleton, &mut self.q);
        }
        self.keep
            .apply(ctx.skeleton, &mut self.q)
            .map_err(|e| e.to_string())?;
        Ok(())
    }

    /// From the end of a reach round other bodies on, the arms stay where its last solve
    /// put them (at the planned wrist poses, the joints as the path left them).
    fn hold_detoured_arms(&mut self) {
        let solved: Vec<(usize, f64)> = self
            .detours
            .iter()
            .flatten()
            .flat_map(ArmDetour::solved)
            .collect();
        let Some(plan) = &mut self.plan else {
            return;
        };
        for h in &mut plan.hands {
            for &(d, v) in &solved {
                match h.arm.iter_mut().find(|(x, _)| *x == d) {
                    Some(entry) => entry.1 = v,
                    None => h.arm.push((d, v)),
                }
            }
        }
    }

    fn write(&self, out: &mut DofWriter, q: &[f64]) {
        for d in out.scope().difference(&self.idle).iter() {
            out.set(d, q[d]);
        }
    }
}

impl Generator for Grasp {
    fn detours(&self) -> usize {
        self.detours.iter().flatten().map(ArmDetour::detours).sum()
    }

    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        if ctx.world.objects.get(self.object).is_none() {
            return Err(
                crate::error::ActionError::Unfit(format!("no object #{}", self.object)).into(),
            );
        }
        self.q = ctx.posture.q.clone();
        if self.gate.is_none() {
            self.begin(ctx)?;
        } else {
            // A receive waits for the giver's hand: a full hand is said now, not then.
            let hand = self.options.hand;
            super::plan::hands_free(ctx.world, ctx.skeleton, ctx.actor, hand)?;
        }
        Ok(())
    }

    fn unfinished(&self) -> Option<String> {
        (!matches!(self.phase, Phase::Verify))
            .then(|| "stopped before the hand held the object".to_string())
    }

    fn end(&mut self, ending: &Ending, notes: &mut Notes) {
        if let (Some(signal), Some(why)) = (self.gave_up, ending.failure()) {
            notes.fail(signal, why);
        }
        notes.post(Note::Unclaim(self.object));
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let board = ctx.world.board;
        // A giver that failed takes the hand-over with it, whatever this hand is doing.
        if let Some(why) = self.abort.and_then(|a| board.failure(a, ctx.tick)) {
            if !matches!(self.phase, Phase::Verify) {
                return Step::Failed(format!("the giver gave up: {why}"));
            }
        }
        // Two hands going for one object: the first to reach for it keeps it, the other
        // gives up at once rather than closing inside the first hand.
        if matches!(self.phase, Phase::Reach | Phase::Close | Phase::Attach) {
            match board.claimed_by(self.object) {
                Some(other) if other != ctx.actor => {
                    let name = |i: usize| ctx.world.actors.get(i).map_or("?", |a| a.name.as_str());
                    let object = ctx
                        .world
                        .objects
                        .get(self.object)
                        .map_or("?", |o| o.name.as_str());
                    return Step::Failed(format!(
                        "`{}` is already reaching for `{object}`",
                        name(other)
                    ));
                }
                Some(_) => {}
                None => out.post(Note::Claim(self.object)),
            }
        }
        match self.phase {
            Phase::Waiting => {
                self.q.copy_from_slice(&ctx.posture.q);
                let open = self.gate.is_some_and(|g| board.before(g, ctx.tick));
                if !open && self.abort.is_some_and(|a| board.before(a, ctx.tick)) {
                    return Step::Failed(
                        "the giver's action ended before the object reached the meeting point"
                            .into(),
                    );
                }
                if open {
                    if let Err(e) = self.begin(ctx) {
                        return Step::Failed(e.to_string());
                    }
                } else {
                    let q = self.q.clone();
                    self.write(out, &q);
                    return Step::Running;
                }
                self.step(ctx, out)
            }
            Phase::Reach => {
                let tau = (ctx.local_time - self.phase_start) / self.reach_seconds;
                let u = quintic(tau);
                let finished = u >= 1.0 - 1e-12;
                self.q.copy_from_slice(&ctx.posture.q);
                if let Err(e) = self.set_arms(ctx, Some(u)) {
                    return Step::Failed(e);
                }
                for arm in self.detours.iter_mut().flatten() {
                    let tau = if finished { 1.0 } else { tau };
                    if let Err(e) = arm.step(ctx, tau, &mut self.q) {
                        return Step::Failed(e.to_string());
                    }
                }
                let q = std::mem::take(&mut self.q);
                self.write(out, &q);
                self.q = q;
                if finished {
                    self.hold_detoured_arms();
                    self.phase = Phase::Close;
                    self.s = 0.0;
                    for c in &mut self.closing {
                        c.pattern.restart_from(&ctx.posture.q);
                    }
                }
                Step::Running
            }
            Phase::Close => {
                let Some(obj) = ctx.world.objects.get(self.object) else {
                    return Step::Failed("the object is gone".into());
                };
                self.q.copy_from_slice(&ctx.posture.q);
                if let Err(e) = self.set_arms(ctx, None) {
                    return Step::Failed(e);
                }
                self.globals.clear();
                self.globals.extend_from_slice(&ctx.posture.globals);
                self.s = (self.s + ctx.dt / CLOSE_SECONDS).min(1.0);
                let field = |p| object_distance(obj, p);
                for c in &mut self.closing {
                    // Finger DOFs: this action's own last values (the posture has them).
                    c.pattern.sample(self.s, &mut self.samples);
                    c.model.advance(
                        ctx.skeleton,
                        &mut self.q,
                        &mut self.globals,
                        &self.samples,
                        &mut c.blocked,
                        &field,
                    );
                }
                let q = std::mem::take(&mut self.q);
                self.write(out, &q);
                self.q = q;
                if self.s >= 1.0 {
                    self.phase = Phase::Attach;
                }
                Step::Running
            }
            Phase::Attach => {
                let Some(first) = self.closing.first() else {
                    return Step::Failed("grasp: no plan".into());
                };
                let Some(obj) = ctx.world.objects.get(self.object) else {
                    return Step::Failed("the object is gone".into());
                };
                let sensors = &first.model.sensors;
                let palm = ctx.posture.globals[sensors.wrist].transform_point(sensors.palm);
                let gap = object_distance(obj, palm);
                if gap > PALM_REACH {
                    let moved = self
                        .follow
                        .as_ref()
                        .is_some_and(|f| f.moved(&ctx.posture.q));
                    return Step::Failed(format!(
                        "the hand closed {gap:.2} m from `{}`{}",
                        obj.name,
                        if moved {
                            ": the body moved on beyond the arm's reach"
                        } else {
                            ": the object moved beyond the arm's reach"
                        }
                    ));
                }
                out.request(HoldRequest::Attach {
                    object: self.object,
                    joint: first.model.sensors.wrist,
                    also: self.closing.get(1).map(|c| c.model.sensors.wrist),
                    from: self.options.from,
                });
                let q = std::mem::take(&mut self.q);
                self.write(out, &q);
                self.q = q;
                self.phase = Phase::Verify;
                Step::Running
            }
            Phase::Verify => {
                let q = std::mem::take(&mut self.q);
                self.write(out, &q);
                self.q = q;
                match ctx.world.holder(self.object) {
                    Some(h) if h.actor == ctx.actor => {
                        if let Some(d) = self.done {
                            out.raise(d);
                        }
                        Step::Finished
                    }
                    Some(h) => Step::Failed(format!(
                        "could not attach the object: `{}` holds it",
                        ctx.world
                            .actors
                            .get(h.actor)
                            .map(|a| a.name.as_str())
                            .unwrap_or("?")
                    )),
                    None => Step::Failed("could not attach the object".into()),
                }
            }
        }
    }
}

/// Opens a hand (or both) and lets go of an object (`actor:release`), optionally after
/// moving it to a place (`actor:place`).
pub struct Release {
    object: usize,
    place: Option<(Transform, f64)>,
    sides: Vec<Side>,
    /// The DOFs a place moves, from `start_q` to `goal_q`: the arms', and the spine's and
    /// legs' when it leans or crouches.
    moving: Scope,
    /// The DOFs it writes: the holding arms and hands, and what it moves.
    writes: Scope,
    start_q: Vec<f64>,
    goal_q: Vec<f64>,
    patterns: Vec<BoundPattern>,
    /// A place's hands: each wrist's goal and the arm that reaches it from the start.
    hands: Vec<HandPlan>,
    /// The hands kept on their wrist goals while the body moves on (a place during a
    /// walk), as a grasp's are.
    follow: Option<FollowBody>,
    /// The legs under a crouching place, solved for each height of the pelvis.
    crouch: Option<CrouchLegs>,
    /// The second hand of a two-handed hold, kept on the object as the first carries it,
    /// and the arms this place does not place with, kept on the body as it leans.
    keep: KeepArms,
    phase: u8,
    phase_start: f64,
    released: bool,
    q: Vec<f64>,
    samples: Vec<(usize, f64)>,
}

/// A placed object must end this close to where it was asked to go (metres).
pub const PLACE_TOLERANCE: f64 = 0.01;

impl Release {
    /// Releases `object`, opening the hands `sides`; with `place = (pose, seconds)` the
    /// object is first carried to `pose`.
    pub fn new(
        object: usize,
        sides: Vec<Side>,
        place: Option<(Transform, f64)>,
    ) -> Result<Release> {
        if let Some((pose, seconds)) = &place {
            check_place(pose.translation, *seconds)?;
        }
        Ok(Release {
            object,
            place,
            sides,
            moving: Scope::EMPTY,
            writes: Scope::EMPTY,
            start_q: Vec::new(),
            goal_q: Vec::new(),
            patterns: Vec::new(),
            hands: Vec::new(),
            follow: None,
            crouch: None,
            keep: KeepArms::default(),
            phase: 0,
            phase_start: 0.0,
            released: false,
            q: Vec::new(),
            samples: Vec::new(),
        })
    }
}

impl Release {
    /// Plans a place of the object at `goal`: every holding arm moves by the object's
    /// displacement (thesis 4.4); when an arm alone cannot, the body leans or crouches
    /// for all the hands together, as a grasp does (a lean for one hand moves the other's
    /// shoulder too: solved one at a time, the hands of a box pulled it apart).
    fn plan_place(&mut self, ctx: &GeneratorContext, goal: Transform, name: &str) -> Result<()> {
        let sk = ctx.skeleton;
        let q0 = &ctx.posture.q;
        let obj = &ctx.world.objects[self.object];
        let delta = goal.mul(&Transform::new(obj.rotation, obj.position).inverse());
        let mut goals = Vec::new();
        let mut arms = Vec::new();
        let mut arm_miss = None::<f64>;
        for &s in &self.sides {
            let mut ik = ArmIk::new(sk, s, 200)?;
            let wrist_goal = delta.mul(&ctx.posture.globals[ik.wrist]);
            self.moving = self.moving.union(&ik.dofs().iter().copied().collect());
            let (miss, angle) = ik.solve(sk, &mut self.goal_q, &wrist_goal)?;
            if miss > REACH_TOLERANCE || angle > REACH_ANGLE {
                arm_miss = Some(arm_miss.unwrap_or(0.0).max(miss));
            }
            goals.push((s, wrist_goal));
            arms.push(ik.dofs().to_vec());
        }
        let body_scope = BodyReach::body_scope(sk)?;
        if let Some(miss) = arm_miss {
            let allowed = ctx.scope.intersection(&body_scope);
            let furniture = furniture_round(ctx.world, ctx.actor, &obj.name);
            let body = BodyReach::new(sk, allowed)?.keeping_knees_off(furniture);
            let reached = match body.search_beyond_the_arm(q0, &goals)? {
                Ok(reached) => reached,
                Err(shortfall) => {
                    let hands: Vec<&str> = self.sides.iter().map(|s| s.name()).collect();
                    let hands = format!(
                        "{} hand{}",
                        hands.join(" and "),
                        if hands.len() > 1 { "s" } else { "" }
                    );
                    let why = if allowed.is_empty() {
                        format!("the arm alone misses by {miss:.3} m")
                    } else {
                        format!(
                            "the arm alone misses by {miss:.3} m; {}",
                            shortfall.describe("leaning and crouching, the best posture")
                        )
                    };
                    let how = if allowed.is_empty() {
                        ""
                    } else {
                        " (even leaning and crouching)"
                    };
                    return Err(crate::error::ActionError::Unfit(format!(
                        "the place for `{name}` is out of reach of the {hands}{how}: {why}"
                    )));
                }
            };
            self.goal_q.copy_from_slice(q0);
            for &(d, v) in &reached.changed {
                self.goal_q[d] = v;
                self.moving.insert(d);
            }
            if reached.crouch > 0.0 {
                self.crouch = CrouchLegs::new(sk, q0, reached.crouch);
                if let Some(legs) = &self.crouch {
                    self.moving = self.moving.union(&legs.dofs().collect());
                }
            }
        }
        for ((side, wrist), arm) in goals.into_iter().zip(arms) {
            self.hands.push(HandPlan {
                side,
                wrist,
                palm: wrist.translation,
                arm: arm.iter().map(|&d| (d, self.goal_q[d])).collect(),
                cost: 0.0,
            });
        }
        self.plan_keep(ctx, self.moving.overlaps(&body_scope))?;
        self.writes = self.writes.union(&self.moving).union(&self.keep.dofs());
        self.follow = Some(FollowBody::new(sk, q0, &self.hands)?);
        Ok(())
    }

    /// The arms kept as the place moves: the second hand of a two-handed hold on the
    /// first, and when the body leans or crouches (`body_moves`), each other arm still in
    /// the action's scope (none that another action drives) on the body.
    fn plan_keep(&mut self, ctx: &GeneratorContext, body_moves: bool) -> Result<()> {
        let sk = ctx.skeleton;
        let g = &ctx.posture.globals;
        if let [first, second, ..] = self.sides[..] {
            let anchor = sk.joint(&format!("{}wrist", first.prefix()))?;
            self.keep.keep(sk, second, anchor, g)?;
        }
        if body_moves {
            self.keep.keep_free_arms(sk, &ctx.scope, &self.sides, g)?;
        }
        Ok(())
    }
}

impl Generator for Release {
    fn unfinished(&self) -> Option<String> {
        (!self.released).then(|| "stopped before the hands let go of the object".to_string())
    }

    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        let name = ctx
            .world
            .objects
            .get(self.object)
            .map(|o| o.name.clone())
            .ok_or_else(|| {
                crate::error::ActionError::Unfit(format!("no object #{}", self.object))
            })?;
        let me = &ctx.world.actors[ctx.actor].name;
        if ctx
            .world
            .holder(self.object)
            .is_none_or(|h| h.actor != ctx.actor)
        {
            return Err(
                crate::error::ActionError::Unfit(format!("`{me}` does not hold `{name}`")).into(),
            );
        }
        self.q = ctx.posture.q.clone();
        self.start_q = ctx.posture.q.clone();
        self.goal_q = ctx.posture.q.clone();
        for &s in &self.sides {
            self.patterns.push(HandPattern::open(ctx.skeleton, s)?);
            let p = self.patterns.last_mut().expect("just pushed");
            p.restart_from(&ctx.posture.q);
        }
        self.writes = grasp_scope(ctx.skeleton, &self.sides)?;
        if let Some((goal, _)) = self.place {
            self.plan_place(ctx, goal, &name)?;
        } else {
            self.phase = 1;
        }
        Ok(())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        self.q.copy_from_slice(&ctx.posture.q);
        let t = ctx.local_time - self.phase_start;
        // The arms' goals follow the body as it moves on (see [`FollowBody`]).
        if let Some(follow) = &mut self.follow {
            for i in 0..self.hands.len() {
                match follow.arm(ctx.skeleton, &ctx.posture.q, &self.hands, i) {
                    Ok(arm) => {
                        for &(d, v) in arm {
                            self.goal_q[d] = v;
                        }
                    }
                    Err(e) => return Step::Failed(e.to_string()),
                }
            }
        }
        if self.phase == 0 {
            let seconds = self.place.map(|p| p.1).unwrap_or(1.0);
            let u = quintic(t / seconds);
            for d in self.moving.iter() {
                self.q[d] = self.start_q[d] + (self.goal_q[d] - self.start_q[d]) * u;
            }
            if let Some(legs) = &mut self.crouch {
                legs.apply(ctx.skeleton, &mut self.q);
            }
            if let Err(e) = self.keep.apply(ctx.skeleton, &mut self.q) {
                return Step::Failed(e.to_string());
            }
            if u >= 1.0 - 1e-12 {
                self.phase = 1;
                self.phase_start = ctx.local_time;
            }
        } else {
            for d in self.moving.iter() {
                self.q[d] = self.goal_q[d];
            }
            if let Err(e) = self.keep.apply(ctx.skeleton, &mut self.q) {
                return Step::Failed(e.to_string());
            }
            if !self.released {
                if let (Some((goal, _)), Some(obj)) =
                    (self.place, ctx.world.objects.get(self.object))
                {
                    let off = (obj.position - goal.translation).length();
                    if off > PLACE_TOLERANCE {
                        return Step::Failed(format!(
                            "the object ended {off:.3} m from where it was to be placed"
                        ));
                    }
                }
                out.request(HoldRequest::Release {
                    object: self.object,
                });
                self.released = true;
                // The empty hand opens as it is, moving on with the body: no longer kept
                // on the place behind a walker (0.24 m back at 0.6 m/s by the time it is
                // open).
                self.follow = None;
            }
            let s = (t / OPEN_SECONDS).min(1.0);
            for p in &self.patterns {
                p.sample(s, &mut self.samples);
                for &(d, v) in &self.samples {
                    self.q[d] = v;
                }
            }
            for d in out.scope().intersection(&self.writes).iter() {
                out.set(d, self.q[d]);
            }
            return if s >= 1.0 {
                Step::Finished
            } else {
                Step::Running
            };
        }
        for d in out.scope().intersection(&self.writes).iter() {
            out.set(d, self.q[d]);
        }
        Step::Running
    }
}
