//! Each actor's body on the floor as the clearance that keeps walkers apart sees it
//! (`troupe_nav::clearance`): a capsule along the way it faces, made each tick from its
//! posture, its facing and its speed.

use troupe_body::glam::{DVec2, DVec3};
use troupe_body::state::ActorState;
use troupe_body::{Skeleton, Transform};
use troupe_nav::{Body, Capsule, FootSpan, Walking};

/// How far (m) a foot's solid reaches round the segment under it from its heel to its toe
/// tip: the template's foot frustum (0.024 h at the ball) for bodies up to 2.08 m.
pub const FOOT_RADIUS: f64 = 0.05;
/// How far (m) a thigh's solid reaches round the point over its knee: the template's
/// thigh frustum (0.030 h at the knee) for bodies up to 2.0 m.
const KNEE_RADIUS: f64 = 0.06;
/// The template foot's heel and toe tip, as fractions of the ankle-to-ball length from
/// the point under the ankle (`troupe_body`'s template: heel at -0.2, ball at 0.69 and
/// toe tip at 0.85 of the foot's length).
const HEEL: f64 = 0.2 / 0.69;
const TOE: f64 = 0.85 / 0.69;
/// How far (m) a finger's tip reaches past its last joint.
const FINGERTIP: f64 = 0.02;
/// Radius (m) of an elbow's solid, about: the most an elbow held out is allowed past
/// where the body's capsule reaches it (see [`BodyJoints::body`]).
const ELBOW_RADIUS: f64 = 0.05;

/// How far a walking body reaches forwards and backwards past its disc at
/// [`STRIDE_SPEED`] or faster, as a fraction of its radius, besides where its feet stand:
/// the swinging leg's knee and foot on their way to a landing the feet do not show yet
/// (the template adult, radius 0.28 m: its front toe tip at heel strike and back heel at
/// toe-off are about 0.5 m from its root, its hands swing about 0.37 m from it). Slower,
/// the strides are shorter.
const STRIDE: f64 = 0.9;
/// The speed (m/s, along the way the body faces) from which the stride is full.
const STRIDE_SPEED: f64 = 1.2;

/// What a hand holds, as the body's capsule widens for it.
#[derive(Clone, Debug)]
pub struct Held {
    /// The holding wrist joint.
    pub wrist: usize,
    /// The height (m) of the held object's lowest point.
    pub lowest: f64,
    /// The held object's points (x, z) seen from above: its corners, or points round it.
    pub outline: Vec<DVec2>,
}

/// One actor's place in the crowd (`troupe_nav::Crowd`'s entries), found from its posture
/// at the end of a tick.
pub(crate) struct CrowdEntry {
    /// The floor points under its ankles.
    pub feet: [DVec2; 2],
    /// Its feet seen from above, if it has them.
    pub soles: Option<[FootSpan; 2]>,
    /// The floor point under its root.
    pub position: DVec2,
    /// Its root's velocity on the floor.
    pub velocity: DVec2,
    /// The unit floor direction its root's +z faces.
    pub facing: DVec2,
    /// The capsule of its whole body.
    pub body: Capsule,
    /// The part of its body its root's step carries.
    pub core: Body,
}

impl CrowdEntry {
    /// The entry of the actor in `state`, going at `velocity` (x, z) on the floor, whose
    /// body has the `joints`, a disc of `radius` and the holding hands `held`; with
    /// `Walking::Straight` its bodies are its disc alone, since nothing keeps bodies apart.
    pub fn of(
        state: &ActorState,
        (vx, vz): (f64, f64),
        (joints, radius, held): (&BodyJoints, f64, &[&Held]),
        walking: Walking,
    ) -> Self {
        let root = state.globals[0].translation;
        let position = DVec2::new(root.x, root.z);
        let velocity = DVec2::new(vx, vz);
        let forward = state.globals[0].rotation * DVec3::Z;
        let facing = DVec2::new(forward.x, forward.z).normalize_or_zero();
        // Kept for the swinging feet, and the capsule's own.
        let soles = joints.sole_spans(&state.globals);
        let (whole, core) = match walking {
            Walking::Navigated => {
                joints.body(&state.globals, soles, (facing, velocity, radius), held)
            }
            Walking::Straight => {
                let disc = Body::around(position, facing, radius, 0.0, &[]);
                (disc, disc)
            }
        };
        CrowdEntry {
            feet: joints.ankle_points(&state.globals),
            soles,
            position,
            velocity,
            facing,
            body: whole.shape,
            core,
        }
    }
}

/// The joints that shape an actor's body on the floor beyond its disc
/// ([`Body`]): the feet, which stretch it along the way it faces, and the
/// elbows and wrists, which widen or lengthen it as the arms swing or carry out.
#[derive(Clone, Debug, Default)]
pub struct BodyJoints {
    /// The ankle joints (left, right), each if the skeleton has it: the points under them
    /// are what avoidance weighs of the feet (`troupe_nav::Crowd::feet`).
    ankles: [Option<usize>; 2],
    /// The ankle and ball joints of each foot (left, right), if it has them.
    feet: Option<[[usize; 2]; 2]>,
    /// The knee joints: a leg lifted to step (even in place) brings its knee forwards.
    knees: Vec<usize>,
    /// Each wrist joint, its horizontal distance from the root at rest, where the body's
    /// radius holds the hand hanging from it, and how far the hand reaches from it (to
    /// the farthest fingertip).
    wrists: Vec<(usize, f64, f64)>,
    /// The elbow above each wrist, if the skeleton has it, and its horizontal distance
    /// from the root at rest: a tray carried in both hands holds the elbows out (two
    /// waiters passing in an aisle put their upper arms 63 mm into each other).
    elbows: Vec<Option<(usize, f64)>>,
}

impl BodyJoints {
    /// The joints of `skeleton`, posed at rest at `globals`.
    pub fn new(skeleton: &Skeleton, globals: &[Transform]) -> Self {
        let j = |name: &str| skeleton.joint(name).ok();
        let feet = (|| {
            Some([
                [j("l_ankle")?, j("l_metatarsal")?],
                [j("r_ankle")?, j("r_metatarsal")?],
            ])
        })();
        let knees = ["l_knee", "r_knee"].into_iter().filter_map(j).collect();
        let root = floor_point(&globals[0]);
        // The hand: the wrist's subtree, to its farthest joint and a fingertip past it.
        let hand_reach = |w: usize| {
            let from = |i: usize| {
                globals
                    .get(i)
                    .map_or(0.0, |g| g.translation.distance(globals[w].translation))
            };
            skeleton
                .subtree(w)
                .into_iter()
                .map(from)
                .fold(0.0, f64::max)
                + FINGERTIP
        };
        let at_rest = |i: usize| Some((floor_point(globals.get(i)?) - root).length());
        let arms: Vec<_> = [("l_wrist", "l_elbow"), ("r_wrist", "r_elbow")]
            .into_iter()
            .filter_map(|(w, e)| {
                let w = j(w)?;
                let wrist = (w, at_rest(w)?, hand_reach(w));
                Some((wrist, j(e).and_then(|e| Some((e, at_rest(e)?)))))
            })
            .collect();
        let wrists = arms.iter().map(|a| a.0).collect();
        let elbows = arms.iter().map(|a| a.1).collect();
        BodyJoints {
            ankles: [j("l_ankle"), j("r_ankle")],
            feet,
            knees,
            wrists,
            elbows,
        }
    }

    /// The body posed at `globals` (its feet `soles`, as [`BodyJoints::sole_spans`] finds
    /// them there), facing `facing` and going at `velocity` (x, z), of
    /// disc `radius`, whole and carried: the disc stretched by the stride at that speed
    /// (see `STRIDE`), widened or lengthened to reach a wrist further out from it than at
    /// rest, and what the hand holds (each hand with how low it reaches: the
    /// fingertips, or the lowest point of what it holds), and,
    /// whole, stretched to hold its feet and knees as well. The carried body is
    /// what the root's step moves (`Crowd::cores`); the planted feet stay behind.
    pub fn body(
        &self,
        globals: &[Transform],
        soles: Option<[FootSpan; 2]>,
        (facing, velocity, radius): (DVec2, DVec2, f64),
        held: &[&Held],
    ) -> (Body, Body) {
        let root = floor_point(&globals[0]);
        let stride = STRIDE * radius * (velocity.dot(facing).abs() / STRIDE_SPEED).min(1.0);
        let (spans, count) = self.foot_spans(globals, soles);
        let feet = &spans[..count];
        let mut whole = Body::around(root, facing, radius, stride, feet);
        let mut core = Body::around(root, facing, radius, stride, &[]);
        for (i, &(wrist, at_rest, reach)) in self.wrists.iter().enumerate() {
            if let Some(w) = globals.get(wrist) {
                // How low the hand reaches, and what it holds.
                let holds = || held.iter().filter(|h| h.wrist == wrist);
                let lowest = holds().fold(w.translation.y - reach, |low, h| low.min(h.lowest));
                let w = floor_point(w);
                // The elbow of a hand that holds something, allowed as far out as it
                // stands at rest within the disc, or its own solid's radius if less: held
                // out to carry a tray, with the allowance of a wrist, two waiters could
                // not pass in a 1.8 m aisle. An arm that swings empty keeps its elbow
                // within the disc (counted, its small sways changed the plaza's contacts
                // for the worse: six layouts of twelve within 1 cm, against eleven).
                let elbow = (holds().next().is_some())
                    .then(|| self.elbows.get(i).copied().flatten())
                    .flatten()
                    .and_then(|(e, at_rest)| {
                        let at_rest = at_rest.max(radius - ELBOW_RADIUS);
                        Some((floor_point(globals.get(e)?), radius, at_rest))
                    });
                let allowed = radius - at_rest;
                let held =
                    || holds().flat_map(move |h| h.outline.iter().map(move |&p| (p, allowed)));
                for body in [&mut whole, &mut core] {
                    // What the hand holds, then the wrist and the elbow. A cup carried out in
                    // front reaches past the wrist: its far side, and the fingers round it,
                    // went 6 cm into a door's jamb.
                    let joints = std::iter::once((w, radius, at_rest)).chain(elbow);
                    let hand = body.reaching(held(), joints, lowest);
                    body.add_hand(i, hand);
                }
            }
        }
        (whole, core)
    }

    /// The floor points under the ankles (left, right) of the body posed at `globals`;
    /// under its root for an ankle the skeleton lacks.
    pub fn ankle_points(&self, globals: &[Transform]) -> [DVec2; 2] {
        let root = floor_point(&globals[0]);
        self.ankles
            .map(|a| a.and_then(|a| globals.get(a)).map_or(root, floor_point))
    }

    /// The feet (left, right) of the body posed at `globals` seen from above: each the span
    /// under it from the heel to the toe tip, on the floor or in the air (none for a body
    /// without them).
    pub fn sole_spans(&self, globals: &[Transform]) -> Option<[FootSpan; 2]> {
        let span = |[ankle, ball]: [usize; 2]| {
            let (a, b) = (
                floor_point(globals.get(ankle)?),
                floor_point(globals.get(ball)?),
            );
            Some(FootSpan {
                heel: a - (b - a) * HEEL,
                toe: a + (b - a) * TOE,
                radius: FOOT_RADIUS,
            })
        };
        let [left, right] = self.feet?;
        Some([span(left)?, span(right)?])
    }

    /// The legs on the floor of the body posed at `globals` (its feet `soles`): each
    /// foot's span and each knee's point (none for a body without them), the first
    /// `count` spans of the array (every body's, every tick: a list made for them cost
    /// 330 instructions an actor-tick).
    fn foot_spans(
        &self,
        globals: &[Transform],
        soles: Option<[FootSpan; 2]>,
    ) -> ([FootSpan; 4], usize) {
        let feet = soles.into_iter().flatten();
        let knees = self.knees.iter().filter_map(|&k| {
            let at = floor_point(globals.get(k)?);
            Some(FootSpan {
                heel: at,
                toe: at,
                radius: KNEE_RADIUS,
            })
        });
        let none = FootSpan {
            heel: DVec2::ZERO,
            toe: DVec2::ZERO,
            radius: 0.0,
        };
        let mut spans = [none; 4];
        let mut count = 0;
        for (span, found) in spans.iter_mut().zip(feet.chain(knees)) {
            *span = found;
            count += 1;
        }
        (spans, count)
    }
}

/// The floor point (x, z) under a joint.
fn floor_point(g: &Transform) -> DVec2 {
    DVec2::new(g.translation.x, g.translation.z)
}
