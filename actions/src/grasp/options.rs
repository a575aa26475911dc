//! The options of `grasp`, `release` and `place`: which object, which hand(s), which
//! pattern, how long, and where to put the object down.

use super::action::{
    check_duration, check_place, grasp_scope, holding_sides, reach_scope, Grasp, Release,
};
use super::decision::GraspType;
use super::plan::{HandChoice, PlanOptions};
use crate::error::{OptionError, Result};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::sensors::Side;
use troupe_body::{Scope, Skeleton, Transform};
use troupe_scene::Scene;

/// The options of a grasp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GraspOptions {
    /// The object's index in the scene.
    pub object: usize,
    /// Which hand(s).
    pub hand: HandChoice,
    /// The grasp type, instead of the one the decision table picks.
    pub pattern: Option<GraspType>,
    /// Seconds to reach the object.
    pub duration: f64,
    /// Whether the arm bends round other actors' bodies and obstacles on its way
    /// (temporary goals, thesis 4.6.3; see [`crate::reach::arm_detour`]).
    pub detour: bool,
}

impl GraspOptions {
    /// Grasps `object` with the hand(s) the plan picks, the table's pattern, reaching in
    /// one second.
    pub fn new(object: usize) -> GraspOptions {
        GraspOptions {
            object,
            hand: HandChoice::Auto,
            pattern: None,
            duration: 1.0,
            detour: true,
        }
    }

    /// Checks the options that do not depend on a body: the reach time.
    pub fn validate(&self) -> Result<(), OptionError> {
        check_duration(self.duration)
    }

    /// The DOFs a grasp with these hands drives, on `skeleton`, and the part of them it
    /// yields (the spine, legs and `root_y` it leans and crouches with: see
    /// [`reach_scope`]; and the other arm, kept on the body as it leans or crouches).
    pub fn scope(&self, skeleton: &Skeleton) -> Result<(Scope, Scope)> {
        let sides = self.hand.sides();
        let (scope, body) = reach_scope(skeleton, &sides)?;
        let others = other_arms(skeleton, &sides)?;
        Ok((scope.union(&others), body.union(&others)))
    }

    /// The grasp generator, once the options are valid.
    pub fn grasp(&self) -> Result<Grasp> {
        self.validate()?;
        let options = PlanOptions {
            hand: self.hand,
            grasp: self.pattern,
            ..PlanOptions::default()
        };
        Ok(
            Grasp::new(self.object, options, self.hand.sides(), self.duration)?
                .detouring(self.detour),
        )
    }
}

/// Where `place` puts an object down.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Place {
    /// The object's centre at the end (world).
    pub at: DVec3,
    /// Its orientation at the end; `None` keeps the one it has.
    pub rotation: Option<DQuat>,
    /// Seconds to carry it there.
    pub duration: f64,
}

/// The options of a release, or of a place when [`ReleaseOptions::place`] is given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReleaseOptions {
    /// The object's index in the scene.
    pub object: usize,
    /// Where to put it down first.
    pub place: Option<Place>,
}

impl ReleaseOptions {
    /// Checks the options that do not depend on the scene: a finite place reached in a
    /// positive time.
    pub fn validate(&self) -> Result<(), OptionError> {
        match &self.place {
            Some(place) => check_place(place.at, place.duration),
            None => Ok(()),
        }
    }

    /// The release generator for `actor` of `scene`, the DOFs it drives and the part of
    /// them it yields: the arms and hands that hold the object, both of a two-handed hold
    /// (the right ones when none does: the action then fails at its start, saying so); a
    /// place also the spine, the legs and `root_y`, to lean or crouch for a place the arm
    /// alone cannot reach, as a grasp does, and the other arm, kept on the body as it
    /// leans, and yields them (during a walk it places with the arm alone).
    pub fn release(&self, scene: &Scene, actor: usize) -> Result<(Release, Scope, Scope)> {
        self.validate()?;
        let mut sides = holding_sides(scene, actor, self.object);
        if sides.is_empty() {
            sides.push(Side::Right);
        }
        let place = self.place.map(|p| {
            let rotation = p.rotation.unwrap_or(scene.objects()[self.object].rotation);
            (Transform::new(rotation, p.at), p.duration)
        });
        let skeleton = &scene.actors()[actor].skeleton;
        let (scope, body) = match place {
            Some(_) => {
                // The other arm too, to keep it on the body as the place leans or
                // crouches (`super::keep`); yielded, so an action that drives it keeps it.
                let (scope, body) = reach_scope(skeleton, &sides)?;
                let body = body.union(&other_arms(skeleton, &sides)?);
                (scope.union(&body), body)
            }
            None => (grasp_scope(skeleton, &sides)?, Scope::EMPTY),
        };
        Ok((Release::new(self.object, sides, place)?, scope, body))
    }
}

/// The arms (without the hands) of the sides not in `sides`: an action that leans or
/// crouches keeps them on the body (`super::keep`).
fn other_arms(skeleton: &Skeleton, sides: &[Side]) -> Result<Scope> {
    let mut arms = Scope::EMPTY;
    for side in [Side::Right, Side::Left] {
        if !sides.contains(&side) {
            arms = arms.union(&skeleton.scope(&format!("{}_arm", side.name()))?);
        }
    }
    Ok(arms)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn good_options_pass() {
        GraspOptions::new(0).validate().unwrap();
        let place = Place {
            at: DVec3::new(0.4, 0.9, 0.3),
            rotation: None,
            duration: 0.5,
        };
        ReleaseOptions {
            object: 0,
            place: Some(place),
        }
        .validate()
        .unwrap();
    }

    #[test]
    fn each_bad_option_is_named() {
        let grasp = GraspOptions {
            duration: -1.0,
            ..GraspOptions::new(0)
        };
        grasp.validate().unwrap_err().assert_names("duration");
        let place = |at: DVec3, duration: f64| ReleaseOptions {
            object: 0,
            place: Some(Place {
                at,
                rotation: None,
                duration,
            }),
        };
        place(DVec3::ZERO, 0.0)
            .validate()
            .unwrap_err()
            .assert_names("duration");
        place(DVec3::NAN, 1.0)
            .validate()
            .unwrap_err()
            .assert_names("at");
        HandChoice::parse("middle")
            .unwrap_err()
            .assert_names("hand");
        GraspType::parse("fist")
            .unwrap_err()
            .assert_names("pattern");
    }
}
