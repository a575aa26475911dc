//! Knees kept off the furniture. The clearance (`troupe_nav::clearance`) keeps the body's
//! core off an obstacle and a foot, landing or in the air, a leg's clearance from it; the
//! knee, between the two, it does not see. Under a body that stands still or creeps in
//! front of a planter, a heel rising as its support ends (the foot rolling onto its toes)
//! or a foot lifted to step brings the knee up to 0.3 m forwards of the hip, over the
//! planter's edge: in the plaza, thighs went 2–8 cm into planters so.
//!
//! So once the legs are solved for where the body goes, a thigh that would come nearer an
//! obstacle than [`OBSTACLE_MARGIN`] and nearer than it was on the previous tick keeps its
//! foot's pose of the previous tick (see `Walk::keep_knees_clear`): the knee then moves
//! only with the hip, which the clearance holds. A swinging foot held so swings on to its
//! landing from where it was held, as one held by `troupe_nav::clearance::foot_may_move`
//! does.
//!
//! The thigh is seen from above, as the obstacles are (footprints standing from the floor
//! up): a few points along it from its middle to the knee, each with the solid's radius
//! there; its upper half stays near the hip, as a rule within the body's disc, which the
//! clearance keeps off.

use super::rig::Rig;
use troupe_body::glam::{DQuat, DVec2, DVec3};
use troupe_scene::space::{Footprint, OBSTACLE_MARGIN};

/// Where along the thigh (0 at the hip, 1 at the knee) it is looked at.
const ALONG: [f64; 3] = [0.5, 0.75, 1.0];

/// A thigh seen from above: points along it (x, z) and the solid's radius at each.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thigh([(DVec2, f64); 3]);

impl Thigh {
    /// The thigh of `leg` at DOF `values`, its hip at `hip` under the pelvis' world
    /// rotation `pelvis`.
    pub fn of(rig: &Rig, leg: usize, pelvis: DQuat, hip: DVec3, values: &[f64; 7]) -> Thigh {
        let knee = rig.knee_position(leg, pelvis, hip, values);
        let [at_hip, at_knee] = rig.legs[leg].thigh_radii;
        Thigh(ALONG.map(|t| {
            let p = hip.lerp(knee, t);
            (DVec2::new(p.x, p.z), at_hip + (at_knee - at_hip) * t)
        }))
    }

    /// The least gap (m) between the thigh and the obstacles: negative where it is in one.
    pub fn gap(&self, obstacles: &[&Footprint]) -> f64 {
        let mut least = f64::INFINITY;
        for f in obstacles {
            for &(p, r) in &self.0 {
                least = least.min(f.distance(p) - r);
            }
        }
        least
    }

    /// Whether the thigh, where it was `before`, comes nearer the obstacles than the
    /// margin and than it was.
    pub fn closes(&self, before: &Thigh, obstacles: &[&Footprint]) -> bool {
        let now = self.gap(obstacles);
        now < OBSTACLE_MARGIN && now < before.gap(obstacles)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::template::default_skeleton;

    #[test]
    fn a_thigh_closes_on_a_planter_only_when_it_comes_nearer_than_the_margin() {
        let skeleton = default_skeleton("adult").unwrap();
        let rig = Rig::new(&skeleton).unwrap();
        let pelvis = rig.pelvis_rotation(0.0, [0.0; 3]);
        let hip = rig.hip_position(0, rig.root_rest, 0.0, pelvis);
        let planter = Footprint::hull(
            "planter",
            &[
                DVec2::new(-1.0, 0.35),
                DVec2::new(1.0, 0.35),
                DVec2::new(1.0, 1.5),
                DVec2::new(-1.0, 1.5),
            ],
        );
        let obstacles = [&planter];
        // Hip flexion lifts the knee forwards, towards the planter 0.35 m ahead.
        let thigh = |flexion: f64| {
            let mut values = [0.0; 7];
            values[0] = flexion;
            Thigh::of(&rig, 0, pelvis, hip, &values)
        };
        let (standing, lifted) = (thigh(0.0), thigh(1.2));
        let forwards = |t: &Thigh| t.0[2].0.y;
        let (lifted, standing) = if forwards(&lifted) > forwards(&standing) {
            (lifted, standing)
        } else {
            (thigh(-1.2), standing)
        };
        assert!(
            standing.gap(&obstacles) > 0.2,
            "{}",
            standing.gap(&obstacles)
        );
        assert!(lifted.gap(&obstacles) < 0.0, "{}", lifted.gap(&obstacles));
        assert!(lifted.closes(&standing, &obstacles));
        assert!(!standing.closes(&lifted, &obstacles));
        assert!(!standing.closes(&standing, &obstacles));
    }
}
