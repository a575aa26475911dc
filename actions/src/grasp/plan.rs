//! Grasp planning (thesis 4.3.2): decide the grasp type and hands, then find each hand's
//! grasp frame and check it is reachable.
//!
//! The frame procedure, for every shape:
//! 1. candidate hand orientations are built from the object's frame: the palm normal
//!    points into the object along a face normal (box, ellipsoid), a horizontal or
//!    downward direction (sphere), around the axis (cylinder, frustum) or onto the top
//!    (disk); the fingers lie along another object axis;
//! 2. a candidate is rejected when the palm would face the exterior side of the body or
//!    the thumb side would be hidden from the eyes ("the thumb always remains on a
//!    visible surface");
//! 3. the origin search: the palm centre starts at the object's centre and moves toward
//!    the border along the approach axis until no hand sensor of the current (open) hand
//!    collides with the object;
//! 4. candidates are ranked by a weighted sum of the translation and rotation from the
//!    current hand pose, and the first one inverse kinematics can reach is kept.

use super::body::{furniture_round, BodyReach, Shortfall, Stage};
use super::close::HandModel;
use super::decision::{decide, Decision, GraspType};
use crate::error::OptionError;
use troupe_body::collision::{BodyVolumes, Capsule, Volume};
use troupe_body::glam::{DMat3, DQuat, DVec3};
use troupe_body::ik::{Goal, IkOptions, IkSolver, IkTask};
use troupe_body::jacobian::{rotation_error, scope_dofs_moving, Effector};
use troupe_body::sensors::{object_distance, Side};
use troupe_body::{ActorState, Scope, Shape, Skeleton, Transform};
use troupe_scene::{Object, World};

/// Weight of rotation (per radian) against translation (per metre) in the frame cost.
pub const ROTATION_WEIGHT: f64 = 0.15;
/// The origin search stops once every sensor is this far from the object (metres).
pub const CLEARANCE: f64 = 0.003;
/// Step of the origin search toward the border (metres).
pub const SEARCH_STEP: f64 = 0.002;
pub use super::body::{REACH_ANGLE, REACH_TOLERANCE};

/// A receiving palm stays at least this far from the giving palm (metres)…
pub const AVOID_DISTANCE: f64 = 0.08;
/// … and this far when a frame allows it: the two hands' solids (about 5 cm round each
/// palm) then do not interpenetrate.
pub const APART_DISTANCE: f64 = 0.11;
/// Cost added to a frame tried only after every other: one whose palm is nearer the
/// giving palm than [`APART_DISTANCE`], or whose hand lies in the furniture by the object
/// (see [`FINGERS_RESTING`]).
const TRIED_LAST: f64 = 10.0;
/// How far (m) a hand sensor may press into the furniture round the object (fingertips
/// resting on the table beside a cup's foot) at a grasp frame; the hand's solids may not
/// go into it at all. A frame whose hand lies deeper backs off, or is tried last: a book,
/// a phone or a tray lying flat on a table was taken by its edge, the fingers under it
/// and the hand 2-6 cm in the table.
pub const FINGERS_RESTING: f64 = 0.003;
/// Objects whose surface is within this distance (m) of the grasped object's centre are
/// the furniture round it, for [`FINGERS_RESTING`].
const FURNITURE_RANGE: f64 = 0.5;
/// Most steps of [`SEARCH_STEP`] a hand in the furniture backs away from the object.
const BACK_STEPS: usize = 20;
/// A hand sensor within this gap (m) of the object's surface still touches it.
const TOUCHING: f64 = 0.03;
/// Cost per metre a hand lies in the furniture, among the frames tried last.
const DEPTH_COST: f64 = 20.0;

/// Which hand(s) a grasp uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandChoice {
    /// The right hand.
    Right,
    /// The left hand.
    Left,
    /// Both hands.
    Both,
    /// Decided by the table (size); with one hand, the nearer shoulder's hand is tried
    /// first and the other one if it cannot reach.
    Auto,
}

impl HandChoice {
    /// Parses `right`, `left`, `both` or `auto`.
    pub fn parse(name: &str) -> Result<HandChoice, OptionError> {
        match name {
            "right" => Ok(HandChoice::Right),
            "left" => Ok(HandChoice::Left),
            "both" => Ok(HandChoice::Both),
            "auto" => Ok(HandChoice::Auto),
            other => Err(OptionError::refused(
                "hand",
                format!(
                    "unknown hand `{other}` (expected \"right\", \"left\", \"both\" or \"auto\")"
                ),
            )),
        }
    }

    /// The hands the choice may use (`auto`: both, the plan picks).
    pub fn sides(self) -> Vec<Side> {
        match self {
            HandChoice::Right => vec![Side::Right],
            HandChoice::Left => vec![Side::Left],
            HandChoice::Both | HandChoice::Auto => vec![Side::Right, Side::Left],
        }
    }
}

/// What a plan may be told beyond the object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanOptions {
    /// Which hand(s).
    pub hand: HandChoice,
    /// Override the table's grasp type (`pattern = …`).
    pub grasp: Option<GraspType>,
    /// Keep the palm at least [`AVOID_DISTANCE`] from this point (another hand holding
    /// the object).
    pub avoid: Option<DVec3>,
    /// The object may be held by this actor (a hand-over).
    pub from: Option<usize>,
    /// What the reach may move besides the arms (see [`super::body`]): the spine to
    /// lean and twist, the legs and `root_y` to crouch; only DOFs in this scope are used
    /// (`None`: all of them).
    pub body: Option<Scope>,
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            hand: HandChoice::Auto,
            grasp: None,
            avoid: None,
            from: None,
            body: None,
        }
    }
}

/// One hand's part of a plan.
#[derive(Clone, Debug, PartialEq)]
pub struct HandPlan {
    /// Which hand.
    pub side: Side,
    /// Goal pose of the wrist joint (world).
    pub wrist: Transform,
    /// Goal of the palm centre (world).
    pub palm: DVec3,
    /// The posture that reaches it: the arm's DOFs and, when the arm alone cannot, the
    /// spine's, the legs' and `root_y` (see [`super::body`]): (DOF, value).
    pub arm: Vec<(usize, f64)>,
    /// The frame's cost (translation + weighted rotation from the current hand pose).
    pub cost: f64,
}

/// A grasp plan: type, hands and frames.
#[derive(Clone, Debug, PartialEq)]
pub struct GraspPlan {
    /// Object index.
    pub object: usize,
    /// What the table decided (before any override).
    pub decision: Decision,
    /// The grasp type used.
    pub grasp: GraspType,
    /// One or two hands; the first one holds the object.
    pub hands: Vec<HandPlan>,
    /// How far (radians) the trunk leans to reach (0 when the arms reach alone).
    pub lean: f64,
    /// How far (metres) the pelvis is lowered to reach (0 standing).
    pub crouch: f64,
}

/// Inverse kinematics of one arm toward a wrist pose, from a posture.
pub struct ArmIk {
    /// Which arm.
    pub side: Side,
    /// The wrist joint.
    pub wrist: usize,
    solver: IkSolver,
}

impl ArmIk {
    /// The arm of `side` (sternoclavicular to wrist DOFs).
    pub fn new(skeleton: &Skeleton, side: Side, iterations: usize) -> crate::error::Result<ArmIk> {
        let wrist = skeleton.joint(&format!("{}wrist", side.prefix()))?;
        let scope = skeleton.scope(&format!("{}_arm", side.name()))?;
        let dofs = scope_dofs_moving(skeleton, &scope, wrist);
        let options = IkOptions {
            max_iterations: iterations,
            ..IkOptions::default()
        };
        let solver = IkSolver::new(skeleton, dofs, options)?;
        Ok(ArmIk {
            side,
            wrist,
            solver,
        })
    }

    /// The same arm following a goal that moves a little each tick, as a reach's path
    /// does before its last tick: its tolerances and iterations, so that a solve that
    /// meets the goal stops there (the default settles null-space tasks for ever).
    pub fn tracking(mut self) -> crate::error::Result<ArmIk> {
        use crate::reach::{
            TRACKING_ITERATIONS, TRACKING_ORIENTATION_TOLERANCE, TRACKING_POSITION_TOLERANCE,
            TRACKING_SETTLE_ITERATIONS,
        };
        let mut options = *self.solver.options();
        options.max_iterations = TRACKING_ITERATIONS;
        options.position_tolerance = TRACKING_POSITION_TOLERANCE;
        options.orientation_tolerance = TRACKING_ORIENTATION_TOLERANCE;
        options.settle_iterations = TRACKING_SETTLE_ITERATIONS;
        self.solver.set_options(options)?;
        Ok(self)
    }

    /// The arm's DOFs.
    pub fn dofs(&self) -> &[usize] {
        self.solver.dofs()
    }

    /// Moves the arm DOFs of `q` toward the wrist pose `goal`; returns the remaining
    /// (distance, angle).
    pub fn solve(
        &mut self,
        skeleton: &Skeleton,
        q: &mut [f64],
        goal: &Transform,
    ) -> crate::error::Result<(f64, f64)> {
        let task = IkTask {
            effector: Effector::at_joint(self.wrist),
            goal: Goal {
                position: goal.translation,
                orientation: Some(goal.rotation),
            },
            priority: 0,
        };
        self.solver.solve(skeleton, q, &[task], None, None)?;
        let g = self.solver.globals()[self.wrist];
        Ok((
            (g.translation - goal.translation).length(),
            rotation_error(g.rotation, goal.rotation).length(),
        ))
    }
}

/// The rotation taking local axes (`n_l`, `f_l`) onto world axes (`n_w`, `f_w`); both
/// pairs must be orthonormal.
pub fn frame_rotation(n_l: DVec3, f_l: DVec3, n_w: DVec3, f_w: DVec3) -> DQuat {
    let local = DMat3::from_cols(n_l, f_l, n_l.cross(f_l));
    let world = DMat3::from_cols(n_w, f_w, n_w.cross(f_w));
    DQuat::from_mat3(&(world * local.transpose())).normalize()
}

/// The hand length of `skeleton`'s right hand (for the decision table).
pub fn hand_length(skeleton: &Skeleton) -> crate::error::Result<f64> {
    Ok(HandModel::new(skeleton, Side::Right)?.length)
}

fn perpendicular_axes(axes: &[DVec3; 3], a: DVec3) -> Vec<DVec3> {
    let mut out = Vec::new();
    for &e in axes {
        if e.dot(a).abs() < 0.5 {
            out.push(e);
            out.push(-e);
        }
    }
    out
}

/// Candidate (palm normal into the object, finger direction) pairs, world frame.
fn candidates(
    object: &Object,
    grasp: GraspType,
    side: Side,
    two_hands: bool,
    toward: DVec3,
    actor_left: DVec3,
) -> Vec<(DVec3, DVec3)> {
    let r = object.rotation;
    let axes = [r * DVec3::X, r * DVec3::Y, r * DVec3::Z];
    let mut horizontal = DVec3::new(toward.x, 0.0, toward.z);
    if horizontal.length() < 1e-9 {
        horizontal = actor_left.cross(DVec3::Y);
    }
    let h = horizontal.normalize();
    let mut out = Vec::new();
    if two_hands {
        // Both palms press the object from the sides: the right hand pushes toward the
        // actor's left, the left hand toward its right.
        let a = match side {
            Side::Right => actor_left,
            Side::Left => -actor_left,
        };
        for f in [h, -DVec3::Y] {
            out.push((a, f));
        }
        return out;
    }
    match object.shape {
        Shape::Box { .. } | Shape::Ellipsoid { .. } => {
            for &e in &axes {
                for a in [e, -e] {
                    for f in perpendicular_axes(&axes, a) {
                        out.push((a, f));
                    }
                }
            }
        }
        Shape::Sphere { .. } => {
            let side_dir = h.cross(DVec3::Y);
            for f in [DVec3::Y, -DVec3::Y, side_dir, -side_dir] {
                out.push((h, f));
            }
            for f in [h, -h, side_dir, -side_dir] {
                out.push((-DVec3::Y, f));
            }
        }
        Shape::Cylinder { .. } | Shape::Frustum { .. } => {
            let ay = axes[1];
            if grasp == GraspType::Disk {
                let a = if ay.y >= 0.0 { -ay } else { ay };
                for f in perpendicular_axes(&axes, a) {
                    out.push((a, f));
                }
            } else {
                let mut a0 = h - ay * h.dot(ay);
                if a0.length() < 1e-6 {
                    a0 = axes[0];
                }
                let a0 = a0.normalize();
                // Side approaches around the axis every 30°, fingers wrapping around it.
                for k in -3..=3 {
                    let a = DQuat::from_axis_angle(ay, k as f64 * std::f64::consts::PI / 6.0) * a0;
                    let f = a.cross(ay).normalize();
                    out.push((a, f));
                    out.push((a, -f));
                }
            }
        }
    }
    out
}

/// The name of what the `side` hand of `actor` holds in `world`, if it holds anything.
pub(crate) fn held_in<'w>(
    world: &'w World,
    skeleton: &Skeleton,
    actor: usize,
    side: Side,
) -> Option<&'w str> {
    world.held.iter().find_map(|&(object, h)| {
        let on_side = h.wrists().any(|wrist| {
            skeleton
                .joints()
                .get(wrist)
                .is_some_and(|j| Side::of_joint(&j.name) == Some(side))
        });
        (h.actor == actor && on_side)
            .then(|| world.objects.get(object).map(|o| o.name.as_str()))
            .flatten()
    })
}

/// Refuses a grasp by `actor` with `hand` when that hand is full (or, for `auto`, both
/// are), as planning would: a receive checks it when it starts rather than when the
/// giver's hand has arrived.
pub fn hands_free(
    world: &World,
    skeleton: &Skeleton,
    actor: usize,
    hand: HandChoice,
) -> crate::error::Result<()> {
    let full = |side: Side| held_in(world, skeleton, actor, side);
    let sides: &[Side] = match hand {
        HandChoice::Right => &[Side::Right],
        HandChoice::Left => &[Side::Left],
        HandChoice::Both => &[Side::Right, Side::Left],
        HandChoice::Auto => {
            if let (Some(r), Some(l)) = (full(Side::Right), full(Side::Left)) {
                return Err(crate::error::ActionError::Unfit(format!(
                    "both hands are full (`{r}` and `{l}`): place or release one first"
                )));
            }
            &[]
        }
    };
    match sides
        .iter()
        .find_map(|&side| full(side).map(|held| (side, held)))
    {
        Some((side, held)) => Err(crate::error::ActionError::Unfit(format!(
            "the {} hand already holds `{held}`: place or release it first",
            side.name()
        ))),
        None => Ok(()),
    }
}

/// Plans a grasp of `object` by `actor` (posture `posture`) in `world`.
pub fn plan_grasp(
    skeleton: &Skeleton,
    posture: &ActorState,
    actor: usize,
    world: &World,
    object: usize,
    options: &PlanOptions,
) -> crate::error::Result<GraspPlan> {
    let obj = world
        .objects
        .get(object)
        .ok_or_else(|| crate::error::ActionError::Unfit(format!("no object #{object}")))?;
    if let Some(h) = world.holder(object) {
        if h.actor == actor {
            return Err(crate::error::ActionError::Unfit(format!(
                "`{}` is already held by this actor",
                obj.name
            )));
        }
        if options.from != Some(h.actor) {
            let who = world
                .actors
                .get(h.actor)
                .map(|a| a.name.as_str())
                .unwrap_or("another actor");
            return Err(crate::error::ActionError::Unfit(format!(
                "`{}` is held by `{who}`: it must be handed over with {who}:give{{object=…, to=…}}",
                obj.name
            )));
        }
    }
    let right = HandModel::new(skeleton, Side::Right)?;
    let decision = decide(&obj.shape, right.length);
    let grasp = options.grasp.unwrap_or(decision.grasp);
    let g = &posture.globals;
    let shoulder = |side: Side| -> crate::error::Result<DVec3> {
        let j = skeleton.joint(&format!("{}shoulder", side.prefix()))?;
        Ok(g[j].translation)
    };
    let mut sides: Vec<Side> = match options.hand {
        HandChoice::Right => vec![Side::Right],
        HandChoice::Left => vec![Side::Left],
        HandChoice::Both => vec![Side::Right, Side::Left],
        HandChoice::Auto if decision.hands == 2 => vec![Side::Right, Side::Left],
        HandChoice::Auto => {
            let dr = (shoulder(Side::Right)? - obj.position).length();
            let dl = (shoulder(Side::Left)? - obj.position).length();
            if dl < dr {
                vec![Side::Left, Side::Right]
            } else {
                vec![Side::Right, Side::Left]
            }
        }
    };
    // A hand that holds something grasps nothing else: one of two takes the free one.
    if options.hand == HandChoice::Auto && decision.hands != 2 {
        hands_free(world, skeleton, actor, HandChoice::Auto)?;
        sides.retain(|&side| held_in(world, skeleton, actor, side).is_none());
    }
    let chosen = match sides.as_slice() {
        [Side::Left] => HandChoice::Left,
        [Side::Right] => HandChoice::Right,
        _ => HandChoice::Both,
    };
    hands_free(world, skeleton, actor, chosen)?;
    let two = match options.hand {
        HandChoice::Both => true,
        HandChoice::Auto => decision.hands == 2,
        _ => false,
    };
    let root = g[0];
    let actor_left = (root.rotation * DVec3::X).normalize();
    let head = skeleton
        .joint("skullbase")
        .map(|j| g[j].translation)
        .unwrap_or(root.translation + DVec3::Y * 0.6);
    let one_of = options.hand == HandChoice::Auto && !two;
    let furniture = Furniture::round(world, object);
    let body_volumes = BodyVolumes::new(skeleton);
    let mut placed = Vec::new();
    body_volumes.place(g, &mut placed);
    let mut first_error = None;
    // Each hand's grasp frames, cheapest first.
    let mut frames: Vec<(Side, Vec<Frame>)> = Vec::new();
    for side in sides {
        let result = (|| -> crate::error::Result<Vec<Frame>> {
            let model = if side == Side::Right {
                right.clone()
            } else {
                HandModel::new(skeleton, side)?
            };
            let hs = &model.sensors;
            let wrist_now = g[hs.wrist];
            let palm_now = wrist_now.transform_point(hs.palm);
            let from_shoulder = obj.position - shoulder(side)?;
            // Sensor centres in the wrist frame for the current finger posture.
            let local: Vec<(DVec3, f64)> = (0..hs.sensors.len())
                .map(|i| {
                    (
                        wrist_now.inverse().transform_point(hs.center(i, g)),
                        hs.sensors[i].radius,
                    )
                })
                .collect();
            // The hand as the solids' measure sees it (its sensors and the solids its
            // joints carry), in the wrist frame.
            let hand = HandVolumes::new(&model, (&body_volumes, &placed), &local, &wrist_now);
            let outward = match side {
                Side::Right => -actor_left,
                Side::Left => actor_left,
            };
            let mut ranked: Vec<Frame> = Vec::new();
            for (a, f) in candidates(obj, grasp, side, two, from_shoulder, actor_left) {
                let rot = frame_rotation(hs.palm_normal, hs.finger_direction, a, f);
                // The palm must not face the exterior side of the body.
                if !two && a.dot(outward) > 0.5 {
                    continue;
                }
                // The thumb side stays visible from the eyes.
                let thumb = rot * DVec3::Z;
                if thumb.dot((head - obj.position).normalize_or_zero()) < -0.2 {
                    continue;
                }
                // Fingers do not point back at the actor.
                if f.dot(from_shoulder.normalize_or_zero()) < -0.5 {
                    continue;
                }
                // Origin search: from the centre toward the border until the hand is free.
                let mut origin = obj.position;
                let mut free = false;
                for _ in 0..400 {
                    let wrist = Transform::new(rot, origin - rot * hs.palm);
                    if local.iter().all(|(p, r)| {
                        object_distance(obj, wrist.transform_point(*p)) - r >= CLEARANCE
                    }) {
                        free = true;
                        break;
                    }
                    origin -= a * SEARCH_STEP;
                }
                if !free {
                    continue;
                }
                // A hand in the furniture the object lies on (a palm on a phone lying on
                // a table, the hand's solid below the phone's top) backs away from the
                // object while it still touches it, until it is clear; else the frame is
                // tried last, the shallower first.
                let wrist_at = |origin: DVec3| Transform::new(rot, origin - rot * hs.palm);
                let mut penalty = 0.0;
                let depth = furniture.depth(&hand, &wrist_at(origin));
                if depth > 0.0 {
                    let backed = (1..=BACK_STEPS)
                        .map(|k| origin - a * (k as f64 * SEARCH_STEP))
                        .take_while(|&at| hand.touches(obj, &wrist_at(at)))
                        .find(|&at| furniture.depth(&hand, &wrist_at(at)) <= 0.0);
                    match backed {
                        Some(at) => origin = at,
                        None => penalty = TRIED_LAST + DEPTH_COST * depth,
                    }
                }
                if let Some(avoid) = options.avoid {
                    let apart = (origin - avoid).length();
                    if apart < AVOID_DISTANCE {
                        continue;
                    }
                    if apart < APART_DISTANCE {
                        penalty += TRIED_LAST;
                    }
                }
                let wrist = wrist_at(origin);
                let angle = rotation_error(wrist_now.rotation, rot).length();
                let cost = (origin - palm_now).length() + ROTATION_WEIGHT * angle + penalty;
                ranked.push((cost, wrist, origin));
            }
            if ranked.is_empty() {
                return Err(crate::error::ActionError::Unfit(format!(
                    "no grasp frame for `{}` with the {} hand (every candidate hides the thumb, turns the palm outward or is blocked)",
                    obj.name,
                    side.name()
                )));
            }
            ranked.sort_by(|x, y| x.0.total_cmp(&y.0));
            ranked.truncate(MAX_FRAMES);
            Ok(ranked)
        })();
        match result {
            Ok(r) => frames.push((side, r)),
            Err(e) if one_of => {
                first_error.get_or_insert(e);
            }
            Err(e) => return Err(e),
        }
    }
    if frames.is_empty() {
        return Err(first_error
            .unwrap_or_else(|| crate::error::ActionError::Unfit("no hand to grasp with".into())));
    }
    // Reach: the arm alone first, then leaning, then crouching; for each, the frames in
    // order of cost (with `auto` and one hand, the nearer hand's first). Two hands try
    // their k-th frames together.
    let allowed = match options.body {
        Some(s) => s,
        None => BodyReach::body_scope(skeleton)?,
    };
    let furniture = furniture_round(world, actor, &obj.name);
    let body = BodyReach::new(skeleton, allowed)?.keeping_knees_off(furniture);
    let attempts: Vec<Vec<(Side, usize)>> = if two {
        let n = frames.iter().map(|(_, r)| r.len()).min().unwrap_or(0);
        (0..n)
            .map(|k| frames.iter().map(|(s, _)| (*s, k)).collect())
            .collect()
    } else {
        frames
            .iter()
            .flat_map(|(s, r)| (0..r.len()).map(move |k| vec![(*s, k)]))
            .collect()
    };
    let frame = |side: Side, k: usize| {
        frames
            .iter()
            .find(|(s, _)| *s == side)
            .map(|(_, r)| r[k])
            .expect("a planned side")
    };
    let mut shortfall = Shortfall::default();
    // Frames that keep a receiving hand apart from the giving one first, whichever hand.
    for near in [false, true] {
        for stage in body.stages() {
            for attempt in &attempts {
                // A crouch is tried for the cheapest frames only: each costs a full solve.
                if matches!(stage, Stage::Crouch(_)) && attempt[0].1 >= MAX_CROUCH_FRAMES {
                    continue;
                }
                if attempt.iter().any(|&(s, k)| frame(s, k).0 >= TRIED_LAST) != near {
                    continue;
                }
                let goals: Vec<(Side, Transform)> =
                    attempt.iter().map(|&(s, k)| (s, frame(s, k).1)).collect();
                match body.reach(&posture.q, &goals, stage)? {
                    Ok(reached) => {
                        let hands = attempt
                            .iter()
                            .map(|&(side, k)| {
                                let (cost, wrist, palm) = frame(side, k);
                                HandPlan {
                                    side,
                                    wrist,
                                    palm,
                                    arm: reached.changed.clone(),
                                    cost,
                                }
                            })
                            .collect();
                        return Ok(GraspPlan {
                            object,
                            decision,
                            grasp,
                            hands,
                            lean: reached.lean,
                            crouch: reached.crouch,
                        });
                    }
                    // Reached, but only by folding over (a deeper crouch may do it
                    // upright) or falling, or not at all: the error says which.
                    Err(missed) => shortfall.note(missed),
                }
            }
        }
    }
    let hands: Vec<&str> = frames.iter().map(|(s, _)| s.name()).collect();
    let how = match stages_used(&body) {
        // The whole body was not the action's to move: said, since the same grasp may
        // well reach leaning (one started as another action let go of the spine).
        "" if !BodyReach::body_scope(skeleton)?.is_empty() => {
            " (the arm alone: the spine and the legs are outside the action's scope, or \
             another action has them)"
                .to_string()
        }
        "" => String::new(),
        used => format!(" (even {used})"),
    };
    shortfall.knees_by = body.knees_by();
    Err(crate::error::ActionError::Unfit(format!(
        "`{}` is out of reach of the {} hand{}{how}: {}",
        obj.name,
        hands.join(" and "),
        if hands.len() > 1 { "s" } else { "" },
        shortfall.describe("the best grasp")
    )))
}

/// A candidate grasp frame: its cost, the wrist's goal pose and the palm centre's goal.
type Frame = (f64, Transform, DVec3);

/// The furniture round an object being grasped: the other objects (not held) whose
/// surface lies within [`FURNITURE_RANGE`] of its centre (the table it lies on, the shelf
/// beside it), which a hand keeps out of (see [`FINGERS_RESTING`]).
struct Furniture(Vec<Volume>);

impl Furniture {
    /// The furniture round object `object` of `world`.
    fn round(world: &World, object: usize) -> Furniture {
        let Some(obj) = world.objects.get(object) else {
            return Furniture(Vec::new());
        };
        Furniture(
            world
                .objects
                .iter()
                .enumerate()
                .filter(|&(i, o)| {
                    i != object
                        && world.holder(i).is_none()
                        && object_distance(o, obj.position) < FURNITURE_RANGE
                })
                .map(|(_, o)| Volume::Shape {
                    shape: o.shape,
                    pose: Transform::new(o.rotation, o.position),
                })
                .collect(),
        )
    }

    /// How deep (m) `hand` with its wrist at `wrist` lies in the furniture at most, its
    /// sensors counted from [`FINGERS_RESTING`] (negative: how far it stays clear; `-inf`
    /// with no furniture).
    fn depth(&self, hand: &HandVolumes, wrist: &Transform) -> f64 {
        let mut deepest = f64::NEG_INFINITY;
        for volume in &self.0 {
            for (c, r) in hand.sensors(wrist) {
                deepest = deepest.max(volume.sphere_depth(c, r) - FINGERS_RESTING);
            }
            for solid in hand.solids.iter().map(|k| k.placed(wrist)) {
                let depth = if solid.a == solid.b && solid.ra == solid.rb {
                    volume.sphere_depth(solid.a, solid.ra)
                } else if volume.may_touch(&solid) {
                    volume.capsule_depth(&solid).0
                } else {
                    continue;
                };
                deepest = deepest.max(depth);
            }
        }
        deepest
    }
}

/// A hand as the grasp's sensors and the solids' measure (`troupe.deepest_overlap`) see
/// it, in its wrist's frame: its sensors (spheres) and the solids its joints carry (a
/// ball round the palm for the templates).
struct HandVolumes {
    /// The sensors: (centre, radius).
    sensors: Vec<(DVec3, f64)>,
    /// The solids, as the capsules that cover them.
    solids: Vec<Capsule>,
}

impl HandVolumes {
    /// The hand of `model` as it is now: its wrist at `wrist_now`, its sensors at
    /// `sensors` (wrist frame), the body's solids `body` placed at `placed` (world).
    fn new(
        model: &HandModel,
        (body, placed): (&BodyVolumes, &[Capsule]),
        sensors: &[(DVec3, f64)],
        wrist_now: &Transform,
    ) -> HandVolumes {
        let to_wrist = wrist_now.inverse();
        let solids = placed
            .iter()
            .enumerate()
            .filter(|&(i, _)| {
                let joint = body.joint(i);
                joint == model.sensors.wrist || model.joints.contains(&joint)
            })
            .map(|(_, world)| world.placed(&to_wrist))
            .collect();
        HandVolumes {
            sensors: sensors.to_vec(),
            solids,
        }
    }

    /// The sensors with the wrist at `wrist` (world).
    fn sensors<'a>(&'a self, wrist: &'a Transform) -> impl Iterator<Item = (DVec3, f64)> + 'a {
        self.sensors
            .iter()
            .map(move |&(c, r)| (wrist.transform_point(c), r))
    }

    /// Whether some sensor of the hand, its wrist at `wrist`, is within [`TOUCHING`] of
    /// `object`'s surface.
    fn touches(&self, object: &Object, wrist: &Transform) -> bool {
        self.sensors(wrist)
            .any(|(c, r)| object_distance(object, c) - r < TOUCHING)
    }
}

/// The frames of each hand tried by the arm and the lean.
const MAX_FRAMES: usize = 8;
/// The frames of each hand tried at each crouch depth.
const MAX_CROUCH_FRAMES: usize = 3;

/// What a failed plan tried besides the arm, for its error.
fn stages_used(body: &BodyReach) -> &'static str {
    let stages = body.stages();
    if stages.iter().any(|s| matches!(s, Stage::Crouch(_))) {
        "leaning and crouching"
    } else if stages.contains(&Stage::Spine) {
        "leaning"
    } else {
        ""
    }
}
