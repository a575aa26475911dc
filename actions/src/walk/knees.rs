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
use troupe_scene::space::{gap_bound, Footprint, OBSTACLE_MARGIN};

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

    /// The least gap (m) between the thigh and the obstacles (each with the circle round
    /// it, centre and radius): negative where it is in one.
    pub fn gap(&self, obstacles: &[(&Footprint, (DVec2, f64))]) -> f64 {
        let mut least = f64::INFINITY;
        for (f, _) in obstacles {
            for &(p, r) in &self.0 {
                least = least.min(f.distance(p) - r);
            }
        }
        least
    }

    /// Whether the thigh, where it was `before`, comes nearer the obstacles than the
    /// margin and than it was. The circles round the obstacles tell first: a thigh whose
    /// points stay the margin away from every circle stays so from the obstacles, and
    /// nothing is measured (most ticks of a walker passing a pillar).
    pub fn closes(&self, before: &Thigh, obstacles: &[(&Footprint, (DVec2, f64))]) -> bool {
        // Never above the gap measured; the slack keeps the rounding from disagreeing.
        let circle_gap = obstacles
            .iter()
            .flat_map(|&(_, circle)| self.0.iter().map(move |&point| gap_bound(point, circle)))
            .fold(f64::INFINITY, f64::min)
            - 1e-9;
        if circle_gap >= OBSTACLE_MARGIN {
            return false;
        }
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
        let obstacles = [(&planter, planter.bounding_circle())];
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

    #[test]
    fn the_circles_change_no_answer_of_closes() {
        // Thighs scattered round two planters, 5,000 pairs: `closes` as its measure alone
        // says, whether the circles answered or the footprints were measured.
        let planters = [
            Footprint::hull(
                "a",
                &[(0.0, 0.0), (1.0, 0.0), (1.0, 0.4), (0.0, 0.4)].map(DVec2::from),
            ),
            Footprint::disc("b", DVec2::new(-0.8, 0.9), 0.3),
        ];
        let obstacles: Vec<_> = planters.iter().map(|f| (f, f.bounding_circle())).collect();
        let mut next = troupe_body::math::draws(11);
        let mut thigh = || {
            let hip = DVec2::new(next() * 3.0 - 1.5, next() * 3.0 - 1.0);
            let knee = hip + DVec2::new(next() - 0.5, next() - 0.5) * 0.9;
            Thigh(ALONG.map(|t| (hip.lerp(knee, t), 0.06 + 0.02 * t)))
        };
        let (mut near, mut far) = (0, 0);
        for _ in 0..5000 {
            let (now, before) = (thigh(), thigh());
            let gap = now.gap(&obstacles);
            let measured = gap < OBSTACLE_MARGIN && gap < before.gap(&obstacles);
            assert_eq!(now.closes(&before, &obstacles), measured);
            if gap < OBSTACLE_MARGIN + 0.05 {
                near += 1;
            } else {
                far += 1;
            }
        }
        assert!(near > 500 && far > 500, "{near} {far}");
    }
}
