//! The hand a person holds out to shake another's, or lifts to be taken.
//!
//! A handshake begins with both hands going out: the other person does not wait with a
//! hand hanging at the side for the first to fetch it. So for `shake_hands` the passive
//! actor holds out its hand (its `follow_hand` moves it there) while the active one
//! reaches for it where it will be: both compute the same held-out pose from the same
//! world, the previous tick's, when their actions start together. For `hold_hand`, a
//! follower whose hand hangs lower than the active one's lifts it the same way
//! ([`Grip::Hold`]): a taller person cannot reach below its own hanging hand.

use crate::grasp::close::HandModel;
use crate::grasp::plan::{frame_rotation, ArmIk};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::sensors::Side;
use troupe_body::Transform;
use troupe_scene::World;

/// Seconds the passive actor takes to hold out its hand.
pub const OFFER_SECONDS: f64 = 0.8;

/// How far (m) below the lower of the two actors' shoulders the hands meet.
const BELOW_SHOULDERS: f64 = 0.42;

/// How far (m) short of the midpoint between the two actors the held-out palm stops: the
/// other hand closes round it there.
const SHORT_OF_MIDDLE: f64 = 0.025;

/// How far (m) the held-out wrist may end from its pose; further, the hand cannot be held
/// out to the other (the two stand too far apart, or too close).
const OFFER_TOLERANCE: f64 = 0.03;

/// A hand held out: the arm's values and the actor's joint frames with the arm there.
pub struct Offer {
    /// The arm's DOFs and the values that hold the hand out.
    pub arm: Vec<(usize, f64)>,
    /// The holding-out actor's joint frames in that posture (the rest as it stands).
    pub globals: Vec<Transform>,
}

/// How a hand is held out: for a handshake, or to be taken side by side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Grip {
    /// Palm facing across, fingers towards the other, thumb up, between the two.
    Shake,
    /// The hand as it hangs, raised to where the other's hangs: a taller person cannot
    /// reach below its own hanging hand (an adult of 1.82 m missed the hanging hand of
    /// one of 1.65 m by 4.6 cm), so the shorter lifts its hand to be taken.
    Hold,
}

/// How far (m) a held-out hand for a handshake may go up from its first height, in steps
/// of [`RAISE_STEP`], while the holding-out arm does not reach there: a taller person's
/// arm does not reach as low and as far as a shorter's.
const MOST_RAISED: f64 = 0.18;
/// The step (m) of those heights.
const RAISE_STEP: f64 = 0.03;

/// How far (m) the other's hand may end from a palm-to-palm pose for that height of the
/// held-out hand to count as within its reach (its own reach, against the real hand,
/// then has 5 mm).
const THEIR_TOLERANCE: f64 = 0.005;

/// How far (m) below the other's hanging palm a hand held up to be taken side by side
/// goes: the other's arm reaches there with the elbow a little bent.
const BELOW_THEIR_PALM: f64 = 0.02;

/// The pitches (radians about the body's left-right axis) tried in turn for a hand held
/// up to be taken side by side.
const HELD_UP_PITCHES: [f64; 7] = [0.0, -0.5, 0.5, -1.0, 1.0, -1.5, 1.5];

/// The posture in which actor `follower` of `world` holds out its hand `side` to
/// `active`, the way `grip` says: for a handshake palm facing across, fingers towards
/// `active`, thumb up, halfway between the two a little below the lower one's shoulders
/// (higher where its arm does not reach there); to be held side by side, raised to just
/// below the other's hanging hand `active_side`. An error says why it cannot.
pub fn offered_hand(
    world: &World,
    (follower, side): (usize, Side),
    (active, active_side): (usize, Side),
    grip: Grip,
) -> Result<Offer, String> {
    let name = |i: usize| super::actor_name(world, i);
    let (Some(mine), Some(theirs)) = (world.states.get(follower), world.states.get(active)) else {
        return Err("no such actor".into());
    };
    let skeleton = &world.actors[follower].skeleton;
    let model = HandModel::new(skeleton, side).map_err(|e| e.to_string())?;
    let hs = &model.sensors;
    let mut ik = ArmIk::new(skeleton, side, 200).map_err(|e| e.to_string())?;
    let (from, to) = (mine.globals[0].translation, theirs.globals[0].translation);
    let apart = (to - from).with_y(0.0).length();
    let mut q = mine.q.clone();
    let mut reach = |wrist: &Transform, q: &mut Vec<f64>| -> Result<f64, String> {
        q.copy_from_slice(&mine.q);
        Ok(ik.solve(skeleton, q, wrist).map_err(|e| e.to_string())?.0)
    };
    let miss = match grip {
        Grip::Shake => {
            let (Some(a), Some(b)) = (
                super::shoulder_height(world, follower),
                super::shoulder_height(world, active),
            ) else {
                return Err(format!(
                    "`{}` or `{}` has no shoulders",
                    name(follower),
                    name(active)
                ));
            };
            let towards = DVec3::new(to.x - from.x, 0.0, to.z - from.z)
                .try_normalize()
                .ok_or_else(|| {
                    format!("`{}` stands where `{}` does", name(follower), name(active))
                })?;
            // A right palm faces the body's left across the way, a left palm its right.
            let left = DVec3::Y.cross(towards);
            let across = if side == Side::Right { left } else { -left };
            let rotation = frame_rotation(hs.palm_normal, hs.finger_direction, across, towards);
            let middle = DVec3::new((from.x + to.x) / 2.0, 0.0, (from.z + to.z) / 2.0);
            // The other's hand comes to it palm to palm, its fingers the other way: the
            // height suits both arms (a taller one reaching for a shorter's hand missed
            // it by a centimetre).
            let their_skeleton = &world.actors[active].skeleton;
            let their_model =
                HandModel::new(their_skeleton, active_side).map_err(|e| e.to_string())?;
            let their_hs = &their_model.sensors;
            let their_across = if active_side == Side::Right {
                -left
            } else {
                left
            };
            let their_rotation = frame_rotation(
                their_hs.palm_normal,
                their_hs.finger_direction,
                their_across,
                -towards,
            );
            let mut their_ik =
                ArmIk::new(their_skeleton, active_side, 200).map_err(|e| e.to_string())?;
            let mut their_q = theirs.q.clone();
            // The least miss over the heights, and the first height this arm reaches
            // (kept if the other's reaches none: it then reaches as best it can).
            let mut least = f64::INFINITY;
            let mut first_reached: Option<Transform> = None;
            let mut chosen = None;
            let steps = (MOST_RAISED / RAISE_STEP).round() as usize;
            for k in 0..=steps {
                let y = a.min(b) - BELOW_SHOULDERS + RAISE_STEP * k as f64;
                let palm = middle.with_y(y) - towards * SHORT_OF_MIDDLE;
                let wrist = Transform::new(rotation, palm - rotation * hs.palm);
                let miss = reach(&wrist, &mut q)?;
                least = least.min(miss);
                if miss > OFFER_TOLERANCE {
                    continue;
                }
                first_reached.get_or_insert(wrist);
                let their_palm = middle.with_y(y) + towards * SHORT_OF_MIDDLE;
                let their_wrist =
                    Transform::new(their_rotation, their_palm - their_rotation * their_hs.palm);
                their_q.copy_from_slice(&theirs.q);
                let (theirs_miss, _) = their_ik
                    .solve(their_skeleton, &mut their_q, &their_wrist)
                    .map_err(|e| e.to_string())?;
                if theirs_miss <= THEIR_TOLERANCE {
                    chosen = Some(miss);
                    break;
                }
            }
            match (chosen, first_reached) {
                (Some(miss), _) => miss,
                // `q` holds the last height tried: solve the first reached again.
                (None, Some(wrist)) => reach(&wrist, &mut q)?,
                (None, None) => least,
            }
        }
        Grip::Hold => {
            let theirs_model = HandModel::new(&world.actors[active].skeleton, active_side)
                .map_err(|e| e.to_string())?;
            let their_palm = theirs.globals[theirs_model.sensors.wrist]
                .transform_point(theirs_model.sensors.palm);
            let wrist_now = mine.globals[hs.wrist];
            let palm_now = wrist_now.transform_point(hs.palm);
            let palm = palm_now.with_y(their_palm.y - BELOW_THEIR_PALM);
            // The hand as it hangs, else pitched forwards or back about the body's
            // left-right axis: a child's arm raised to an adult's hand cannot keep its
            // fingers pointing down.
            let forward = mine.globals[0].rotation * DVec3::Z;
            let left = DVec3::Y.cross(forward.with_y(0.0)).normalize_or(DVec3::X);
            let mut least = f64::INFINITY;
            for pitch in HELD_UP_PITCHES {
                let rotation = DQuat::from_axis_angle(left, pitch) * wrist_now.rotation;
                let wrist = Transform::new(rotation, palm - rotation * hs.palm);
                let miss = reach(&wrist, &mut q)?;
                if miss <= OFFER_TOLERANCE {
                    least = miss;
                    break;
                }
                least = least.min(miss);
            }
            least
        }
    };
    if miss > OFFER_TOLERANCE {
        return Err(format!(
            "`{}` cannot hold out the {} hand to `{}` {apart:.2} m away (it misses by {miss:.3} m)",
            name(follower),
            side.name(),
            name(active),
        ));
    }
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &q, &mut globals);
    Ok(Offer {
        arm: ik.dofs().iter().map(|&d| (d, q[d])).collect(),
        globals,
    })
}
