//! The hand a person holds out to shake another's.
//!
//! A handshake begins with both hands going out: the other person does not wait with a
//! hand hanging at the side for the first to fetch it. So for `shake_hands` the passive
//! actor holds out its hand (its `follow_hand` moves it there) while the active one
//! reaches for it where it will be: both compute the same held-out pose from the same
//! world, the previous tick's, when their actions start together.

use crate::grasp::close::HandModel;
use crate::grasp::plan::{frame_rotation, ArmIk};
use troupe_body::glam::DVec3;
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

/// The posture in which actor `follower` of `world` holds out its hand `side` to shake
/// `active`'s: palm facing across, fingers towards `active`, thumb up, halfway between
/// the two a little below the lower one's shoulders. An error says why it cannot.
pub fn offered_hand(
    world: &World,
    follower: usize,
    active: usize,
    side: Side,
) -> Result<Offer, String> {
    let name = |i: usize| super::actor_name(world, i);
    let (Some(mine), Some(theirs)) = (world.states.get(follower), world.states.get(active)) else {
        return Err("no such actor".into());
    };
    let skeleton = &world.actors[follower].skeleton;
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
    let (from, to) = (mine.globals[0].translation, theirs.globals[0].translation);
    let towards = DVec3::new(to.x - from.x, 0.0, to.z - from.z)
        .try_normalize()
        .ok_or_else(|| format!("`{}` stands where `{}` does", name(follower), name(active)))?;
    let middle = DVec3::new(
        (from.x + to.x) / 2.0,
        a.min(b) - BELOW_SHOULDERS,
        (from.z + to.z) / 2.0,
    );
    let palm = middle - towards * SHORT_OF_MIDDLE;
    // A right palm faces the body's left across the way, a left palm its right.
    let left = DVec3::Y.cross(towards);
    let across = if side == Side::Right { left } else { -left };
    let model = HandModel::new(skeleton, side).map_err(|e| e.to_string())?;
    let hs = &model.sensors;
    let rotation = frame_rotation(hs.palm_normal, hs.finger_direction, across, towards);
    let wrist = Transform::new(rotation, palm - rotation * hs.palm);
    let mut ik = ArmIk::new(skeleton, side, 200).map_err(|e| e.to_string())?;
    let mut q = mine.q.clone();
    let (miss, _) = ik
        .solve(skeleton, &mut q, &wrist)
        .map_err(|e| e.to_string())?;
    if miss > OFFER_TOLERANCE {
        return Err(format!(
            "`{}` cannot hold out the {} hand to `{}` {:.2} m away (it misses by {miss:.3} m)",
            name(follower),
            side.name(),
            name(active),
            (to - from).with_y(0.0).length()
        ));
    }
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &q, &mut globals);
    Ok(Offer {
        arm: ik.dofs().iter().map(|&d| (d, q[d])).collect(),
        globals,
    })
}
