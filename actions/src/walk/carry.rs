//! Carrying: what the hands hold is brought in to the body and carried level.
//!
//! A grasp leaves its arm where the hand closed, often reaching out over a table, and a
//! two-handed grasp attaches the object to one hand. Walking on with that arm frozen
//! there (as the walk once did) carried a cup at arm's length, tilting and sinking towards
//! the thigh as the trunk straightened from the reach, and left a box floating before the
//! belly while the other arm swung free. So over the walk's first [`CARRY_TIME`] each held
//! object is brought from where it is, relative to the body's heading, to its carrying
//! place: in one hand, the wrist at the elbow's height beside the body, a forearm ahead of
//! the elbow (the upper arm hanging a little forward, the forearm about level); in two
//! hands, centred before the belly at the elbows' height. It keeps the turn it had
//! relative to the heading (a cup upright stays upright, a box square to the body), and
//! it is clear of the trunk. Its height is kept in the world, so the arms take up the
//! pelvis' bounce and the spine's lean. Every arm that holds it is solved each tick (the
//! arm's damped least squares, from its last solution) for its wrist's pose on the object:
//! both arms of a two-handed hold move as one.
//!
//! What the hands take up during the walk is carried from then on in the same way: a
//! grasp takes its arm from the walk and gives it back when it ends (the walk's spec
//! `takes_back`), and the walk then brings the object in over [`CARRY_TIME`] from where
//! the hand closed. A load whose arm another action takes is let go, and found again when
//! the arm comes back.

use crate::grasp::plan::ArmIk;
use crate::reach::hold_to_joint_speed;
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::math::smoothstep;
use troupe_body::scope::Scope;
use troupe_body::sensors::Side;
use troupe_body::{Shape, Skeleton, Transform};
use troupe_scene::space::surface_points;
use troupe_scene::{DofWriter, GeneratorContext};

/// Seconds over which a held object comes from where the walk found it to its carrying
/// place: about two steps.
pub const CARRY_TIME: f64 = 1.0;

/// Seconds over which what one hand carries comes in to the chest as the body starts
/// turning on the spot or comes close beside someone ([`TUCK_NEAR`]), and goes back out
/// once it has turned and nobody is that close. Carried a forearm ahead,
/// it swept round with the body: turning to leave a counter with a cup just taken from
/// it, the forearm went 3.7 cm into the arm of the one standing beside.
pub const TUCK_TIME: f64 = 0.4;

/// Gap (m) between the body (with what it carries) and another body below which a
/// one-hand load is tucked as for a turn (see [`TUCK_TIME`]), as a person keeps a cup
/// close among others. Not beside furniture: the load goes out over the table it is
/// carried to.
pub const TUCK_NEAR: f64 = 0.15;

/// How far out to its side (a fraction of the carrying place's) a tucked load stays:
/// most of the way in to the middle of the chest, the forearm across it.
const TUCK_ACROSS: f64 = 0.3;

/// How far (rad) the carrying upper arm hangs forward of vertical.
const UPPER_ARM_FORWARD: f64 = 0.25;

/// How far (rad) the carrying forearm rises above level.
const FOREARM_UP: f64 = 0.15;

/// The least gap (m) between a carried object and the front of the trunk at rest.
const TRUNK_GAP: f64 = 0.04;

/// The held objects a walk carries.
#[derive(Default)]
pub struct Carrying {
    loads: Vec<Load>,
    /// How far (0 to 1) the one-handed loads are brought in to the chest while the body
    /// turns on the spot or passes close beside someone (see [`TUCK_TIME`]).
    tuck: f64,
    /// The joint the shoulders hang from (the upper thorax), if the body has one: a load
    /// starts out moving with it, so that the arms need not stretch or fold as the trunk
    /// straightens from a reach (the walk's blend-in) before the load has come in.
    trunk: Option<usize>,
    /// The floor's height under the body when the walk started.
    floor: f64,
    /// The body at rest, measured once something is carried.
    rest: Option<Rest>,
    /// Per side (left, right), the DOFs a carrying arm's solve moves, found once: a held
    /// object whose arms are not the walk's is passed over each tick without building
    /// their solvers.
    arm_dofs: [Option<Scope>; 2],
    /// Scratch posture and joint frames for the arms' solves.
    q: Vec<f64>,
    globals: Vec<Transform>,
}

/// One carried object.
struct Load {
    /// The object's index in the scene.
    object: usize,
    /// The walk's time when the walk took it up.
    since: f64,
    /// Its turn in the heading frame when the walk took it up, which it keeps.
    turn: DQuat,
    /// Its centre in the trunk's frame (see [`Carrying::trunk`]) when the walk took it up.
    from: DVec3,
    /// Its centre's carrying place in the heading frame.
    to: DVec3,
    /// Its carrying place when tucked (see [`TUCK_TIME`]): as near the chest as it clears
    /// the trunk, and most of the way to its middle ([`TUCK_ACROSS`]).
    tucked: DVec3,
    /// The arms that hold it: the attached hand's first.
    arms: Vec<CarryingArm>,
}

/// An arm holding a carried object.
struct CarryingArm {
    ik: ArmIk,
    /// The wrist's pose in the object's frame, as the walk took it up.
    grip: Transform,
    /// The arm's values asked for on the last tick.
    values: Vec<(usize, f64)>,
}

/// Where the body stood at rest, for the carrying places: in the frame of a body standing
/// on the floor at the origin and facing +Z.
struct Rest {
    /// Each side's (left, right) shoulder, elbow and wrist joints' positions.
    arms: [[DVec3; 3]; 2],
    /// How far forward (z) the trunk's solids reach.
    trunk_front: f64,
}

impl Carrying {
    /// The objects `ctx`'s actor holds when its walk starts, in arms the walk drives;
    /// `heading` is the body's heading frame then (see [`heading_frame`]) and `floor` the
    /// floor's height under it.
    pub fn start(ctx: &GeneratorContext, heading: Transform, floor: f64) -> Carrying {
        let sk = ctx.skeleton;
        let mut carrying = Carrying {
            trunk: sk
                .joint("l_sternoclavicular")
                .ok()
                .and_then(|j| sk.joints()[j].parent),
            floor,
            ..Carrying::default()
        };
        carrying.take_up(ctx, 0.0, heading, ctx.scope);
        carrying
    }

    /// Takes up, at walk time `t` and in the heading frame `heading`, each object the hands
    /// hold that no load carries yet, when every arm holding it is in `scope`.
    fn take_up(&mut self, ctx: &GeneratorContext, t: f64, heading: Transform, scope: Scope) {
        let sk = ctx.skeleton;
        let trunk = self.trunk.map_or(heading, |j| ctx.posture.globals[j]);
        let mine = ctx.world.held.iter().filter(|(_, h)| h.actor == ctx.actor);
        for &(object, h) in mine {
            if self.loads.iter().any(|load| load.object == object) {
                continue;
            }
            let ours = h.wrists().all(|wrist| {
                let side = sk.joints().get(wrist).and_then(|j| Side::of_joint(&j.name));
                side.and_then(|side| self.arm_dofs(sk, side))
                    .is_some_and(|dofs| scope.contains_all(&dofs))
            });
            if !ours {
                continue;
            }
            let Some(obj) = ctx.world.objects.get(object) else {
                continue;
            };
            let pose = Transform::new(obj.rotation, obj.position);
            let arms: Option<Vec<CarryingArm>> = h
                .wrists()
                .map(|wrist| {
                    let side = Side::of_joint(&sk.joints().get(wrist)?.name)?;
                    let ik = ArmIk::new(sk, side, 1).and_then(ArmIk::tracking).ok()?;
                    let values = ik.dofs().iter().map(|&d| (d, ctx.posture.q[d])).collect();
                    let grip = pose.inverse().mul(&ctx.posture.globals[wrist]);
                    Some(CarryingArm { ik, grip, values })
                })
                .collect();
            let Some(arms) = arms else { continue };
            if !arms.iter().all(|arm| arm.in_scope(scope)) {
                continue;
            }
            let rest = self.rest.get_or_insert_with(|| Rest::of(sk));
            let turn = heading.rotation.inverse() * obj.rotation;
            let to = carrying_place(rest, &obj.shape, turn, &arms, self.floor);
            let tucked = DVec3::new(
                to.x * TUCK_ACROSS,
                to.y,
                clear_of_trunk(rest, &obj.shape, turn).min(to.z),
            );
            self.loads.push(Load {
                object,
                since: t,
                turn,
                from: trunk.inverse().transform_point(obj.position),
                to,
                tucked,
                arms,
            });
        }
    }

    /// Moves the carrying arms at walk time `t`, the root this tick on the floor at `root`
    /// turned by `yaw` (`tuck`: whether what one hand carries is to come in, see
    /// [`TUCK_TIME`]), and `upper` this tick's root,
    /// pelvis and spine values as written. A load that is no longer held as it was, or
    /// whose arms another action has taken, is let go; what the hands have taken up since
    /// is taken up.
    pub fn step(
        &mut self,
        ctx: &GeneratorContext,
        (t, root, yaw, tuck): (f64, DVec3, f64, bool),
        upper: &[(usize, f64)],
        out: &mut DofWriter,
    ) {
        let towards = if tuck { 1.0 } else { 0.0 };
        self.tuck += (towards - self.tuck).clamp(-ctx.dt / TUCK_TIME, ctx.dt / TUCK_TIME);
        let scope = out.scope();
        self.loads.retain(|load| {
            load.arms.iter().all(|arm| arm.in_scope(scope))
                && ctx.world.holder(load.object).is_some_and(|h| {
                    h.actor == ctx.actor
                        && h.wrists().count() == load.arms.len()
                        && load.arms.iter().all(|arm| h.held_by(arm.ik.wrist))
                })
        });
        // Every walker of a crowd passes here: the rest only for a walk whose hands hold.
        if !ctx.world.held.iter().any(|(_, h)| h.actor == ctx.actor) {
            self.loads.clear();
            return;
        }
        let heading = heading_frame(root, yaw);
        self.take_up(ctx, t, heading, scope);
        if self.loads.is_empty() {
            return;
        }
        let sk = ctx.skeleton;
        self.q.clear();
        self.q.extend_from_slice(&ctx.posture.q);
        for &(d, v) in upper {
            self.q[d] = v;
        }
        let coming = self.loads.iter().any(|load| t - load.since < CARRY_TIME);
        let trunk = match self.trunk {
            Some(j) if coming => {
                self.globals.resize(sk.joints().len(), Transform::IDENTITY);
                forward_kinematics(sk, &self.q, &mut self.globals);
                self.globals[j]
            }
            _ => heading,
        };
        for load in &mut self.loads {
            let s = smoothstep((t - load.since) / CARRY_TIME);
            // Where it was on the trunk, turned as it was on the heading; then where it
            // is carried.
            let from = trunk.transform_point(load.from);
            let to = heading.transform_point(load.to.lerp(load.tucked, smoothstep(self.tuck)));
            let goal = Transform::new(heading.rotation * load.turn, from.lerp(to, s));
            for arm in &mut load.arms {
                for &(d, v) in &arm.values {
                    self.q[d] = v;
                }
                if arm.ik.solve(sk, &mut self.q, &goal.mul(&arm.grip)).is_err() {
                    continue;
                }
                // The solve may find the arm another way at once where a DOF locks at
                // its limit: a ball carried up from the floor, the shoulder's abduction
                // at its limit and the elbow straight, turned the upper arm 0.42 rad and
                // bent the elbow 0.45 rad in a tick. The hand, and what it holds, lags
                // its carrying place for a few ticks instead.
                hold_to_joint_speed(&mut self.q, arm.values.iter().copied(), ctx.dt);
                for (d, v) in arm.values.iter_mut() {
                    *v = self.q[*d];
                    out.set(*d, *v);
                }
            }
        }
    }
}

impl Carrying {
    /// The DOFs the carrying solve of the `side` arm of `skeleton` moves, found once;
    /// `None` for a body without that arm.
    fn arm_dofs(&mut self, skeleton: &Skeleton, side: Side) -> Option<Scope> {
        let slot = &mut self.arm_dofs[usize::from(side == Side::Right)];
        if slot.is_none() {
            let ik = ArmIk::new(skeleton, side, 1).ok()?;
            *slot = Some(ik.dofs().iter().copied().collect());
        }
        *slot
    }
}

impl CarryingArm {
    /// Whether every DOF the arm's solve moves is in `scope`.
    fn in_scope(&self, scope: Scope) -> bool {
        self.values.iter().all(|&(d, _)| scope.contains(d))
    }
}

/// The body's heading frame: on the floor under the root (its height 0, so that heights
/// in it are the world's), turned by the body's heading.
pub fn heading_frame(root: DVec3, heading: f64) -> Transform {
    Transform::new(
        DQuat::from_rotation_y(heading),
        DVec3::new(root.x, 0.0, root.z),
    )
}

impl Rest {
    /// The rest posture of `skeleton`, measured.
    fn of(skeleton: &Skeleton) -> Rest {
        let q = vec![0.0; skeleton.dof_count()];
        let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
        forward_kinematics(skeleton, &q, &mut globals);
        let root = globals[0].translation;
        let at = |name: &str| {
            skeleton
                .joint(name)
                .map(|j| globals[j].translation - DVec3::new(root.x, 0.0, root.z))
                .unwrap_or(DVec3::ZERO)
        };
        let arm = |p: &str| {
            [
                at(&format!("{p}shoulder")),
                at(&format!("{p}elbow")),
                at(&format!("{p}wrist")),
            ]
        };
        // The trunk: the solids of the joints the shoulders hang from (pelvis to neck).
        let mut trunk = Vec::new();
        let mut j = skeleton.joint("l_sternoclavicular").ok();
        while let Some(joint) = j.and_then(|j| skeleton.joints()[j].parent) {
            trunk.push(joint);
            j = Some(joint);
        }
        let trunk_front = skeleton
            .solids()
            .iter()
            .filter(|(joint, _)| trunk.contains(joint))
            .flat_map(|(joint, solid)| {
                let g = globals[*joint];
                surface_points(
                    &solid.shape,
                    g.rotation * solid.orientation,
                    g.transform_point(solid.center),
                )
            })
            .map(|p| p.z - root.z)
            .fold(0.0, f64::max);
        Rest {
            arms: [arm("l_"), arm("r_")],
            trunk_front,
        }
    }
}

/// The least distance (z, heading frame) ahead of the root at which an object of `shape`
/// turned by `turn` clears the front of the trunk at `rest` by [`TRUNK_GAP`].
fn clear_of_trunk(rest: &Rest, shape: &Shape, turn: DQuat) -> f64 {
    // How far the object reaches back towards the body from its centre.
    let back = surface_points(shape, turn, DVec3::ZERO)
        .iter()
        .map(|p| -p.z)
        .fold(0.0, f64::max);
    rest.trunk_front + TRUNK_GAP + back
}

/// The carrying place, in the heading frame, of the centre of an object of `shape` turned
/// by `turn` in that frame and held by `arms`; `floor` is the floor's height under the body.
fn carrying_place(
    rest: &Rest,
    shape: &Shape,
    turn: DQuat,
    arms: &[CarryingArm],
    floor: f64,
) -> DVec3 {
    let clear = clear_of_trunk(rest, shape, turn);
    let lifted = |p: DVec3| p + DVec3::Y * floor;
    if arms.len() > 1 {
        // Two hands: centred before the belly, its centre at the elbows' height.
        let elbow = 0.5 * (rest.arms[0][1].y + rest.arms[1][1].y);
        return lifted(DVec3::new(0.0, elbow, clear));
    }
    let [shoulder, elbow, wrist] = rest.arms[usize::from(arms[0].ik.side == Side::Right)];
    let (upper, fore) = (shoulder.distance(elbow), elbow.distance(wrist));
    let elbow =
        shoulder + upper * DVec3::new(0.0, -UPPER_ARM_FORWARD.cos(), UPPER_ARM_FORWARD.sin());
    let hand = elbow + fore * DVec3::new(0.0, FOREARM_UP.sin(), FOREARM_UP.cos());
    // The wrist turned as the object's turn and the grip ask; the object ahead of the
    // trunk, the whole moved forward if it would not be.
    let wrist_turn = turn * arms[0].grip.rotation;
    let object = Transform::new(wrist_turn, hand).mul(&arms[0].grip.inverse());
    let forward = (clear - object.translation.z).max(0.0);
    lifted(object.translation + DVec3::Z * forward)
}
