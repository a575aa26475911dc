//! Local avoidance between walkers: reciprocal velocity obstacles by sampling (van den
//! Berg, Lin and Manocha 2008, the penalty form of their section 5). Each walker picks,
//! among a fixed list of candidate velocities around the one it would like, the one that
//! best trades deviation against time to collision, taking half the effort of avoiding
//! every neighbour (the "reciprocal" part) and all of it for obstacles. The candidates
//! are tried in a fixed order and the first best wins, so the choice is a pure function
//! of the previous tick's world: bit-identical with any thread count.

use crate::footprint::Footprint;
use troupe_body::glam::DVec2;

/// Seconds ahead a collision matters.
pub const HORIZON: f64 = 3.0;
/// Gap (m) kept between two bodies' discs.
pub const GAP: f64 = 0.03;
/// Weight of 1 / (time to collision) against the deviation from the preferred velocity
/// (m, the penalty's units are m/s).
const URGENCY: f64 = 1.2;
/// Below this speed (m/s) a neighbour counts as standing: it will not take its half.
const STANDING: f64 = 0.1;
/// Speed factors of the candidates.
const SPEEDS: [f64; 5] = [1.0, 0.7, 0.4, 0.15, 0.06];
/// Turns (degrees) of the candidates from the preferred direction; negative turns to the
/// right and comes first, so two walkers head-on both keep right.
const TURNS: [f64; 13] = [
    0.0, -15.0, 15.0, -30.0, 30.0, -45.0, 45.0, -60.0, 60.0, -90.0, 90.0, -120.0, 120.0,
];

/// A body on the floor: where it is, how fast it goes, how wide it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agent {
    /// Floor position (x, z).
    pub position: DVec2,
    /// Velocity (x, z) over the last tick.
    pub velocity: DVec2,
    /// Body radius (m).
    pub radius: f64,
}

/// The velocity `me` should take to go about `preferred` without running into `others`
/// or `obstacles`; `preferred` itself when nothing is in the way (then the second value is
/// true).
pub fn choose_velocity(
    me: &Agent,
    preferred: DVec2,
    others: &[Agent],
    obstacles: &[&Footprint],
) -> (DVec2, bool) {
    let speed = preferred.length();
    let forward = preferred.try_normalize().unwrap_or(DVec2::ZERO);
    // How far each obstacle is now: the same for every candidate, so found once.
    let now: Vec<f64> = obstacles.iter().map(|f| f.distance(me.position)).collect();
    let mut best = (
        preferred,
        penalty(me, preferred, preferred, others, obstacles, &now),
    );
    if best.1 <= 0.0 {
        return (preferred, true);
    }
    // Standing still is always a candidate, then the fan of directions and speeds.
    let still = penalty(me, DVec2::ZERO, preferred, others, obstacles, &now);
    if still < best.1 {
        best = (DVec2::ZERO, still);
    }
    let base = if speed > 1e-6 { speed } else { 0.5 };
    let forward = if speed > 1e-6 { forward } else { DVec2::Y };
    // The fan's turns are the same at every speed: their sines and cosines, once.
    let fan = TURNS.map(|turn| turn.to_radians().sin_cos());
    for k in SPEEDS {
        for &(s, c) in &fan {
            // A positive turn is counter-clockwise seen from above (x, z): to the left of
            // a walker facing +z is +x.
            let dir = DVec2::new(
                forward.x * c + forward.y * s,
                -forward.x * s + forward.y * c,
            );
            let v = dir * base * k;
            let p = penalty(me, v, preferred, others, obstacles, &now);
            if p < best.1 {
                best = (v, p);
            }
        }
    }
    (best.0, false)
}

/// Deviation from `preferred` plus urgency over the time to the first collision of
/// candidate `v` (`now`: each obstacle's present distance); 0 when `v` is `preferred` and
/// nothing is hit within [`HORIZON`].
fn penalty(
    me: &Agent,
    v: DVec2,
    preferred: DVec2,
    others: &[Agent],
    obstacles: &[&Footprint],
    now: &[f64],
) -> f64 {
    let mut ttc = f64::INFINITY;
    for o in others {
        let d = o.position - me.position;
        let reach = me.radius + o.radius + GAP;
        // Reciprocal: I take half the change and they are assumed to take the other half,
        // unless they stand still: then I go round them alone.
        let rel = if o.velocity.length() > STANDING {
            2.0 * v - me.velocity - o.velocity
        } else {
            v - o.velocity
        };
        if d.length() < reach {
            // Already too close: only moving apart (or not closer) is acceptable, whatever
            // the other does.
            let closing = (v - o.velocity).dot(d) / d.length().max(1e-9);
            if closing > 0.0 {
                return 1e9 + closing;
            }
            continue;
        }
        ttc = ttc.min(ray_disc(d, rel, reach));
    }
    for (f, &now) in obstacles.iter().zip(now) {
        // Obstacles stand still: only the next moments matter, or a slow sidestep towards
        // a wall would count as a collision long before it could be one.
        for step in 1..=3 {
            let t = step as f64 * 0.25;
            let gap = f.distance(me.position + v * t);
            if gap < me.radius && gap < now {
                ttc = ttc.min(t);
                break;
            }
        }
    }
    let deviation = (v - preferred).length();
    if ttc > HORIZON {
        deviation
    } else {
        deviation + URGENCY / ttc.max(1e-3)
    }
}

/// When a point leaving the origin at velocity `v` first comes within `reach` of `d`.
fn ray_disc(d: DVec2, v: DVec2, reach: f64) -> f64 {
    let a = v.length_squared();
    if a < 1e-12 {
        return f64::INFINITY;
    }
    let b = v.dot(d);
    let c = d.length_squared() - reach * reach;
    let disc = b * b - a * c;
    if b <= 0.0 || disc < 0.0 {
        return f64::INFINITY;
    }
    (b - disc.sqrt()) / a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn agent(x: f64, z: f64, vx: f64, vz: f64) -> Agent {
        Agent {
            position: DVec2::new(x, z),
            velocity: DVec2::new(vx, vz),
            radius: 0.28,
        }
    }

    #[test]
    fn nothing_in_the_way_keeps_the_preferred_velocity() {
        let me = agent(0.0, 0.0, 0.0, 1.2);
        let aside = agent(3.0, 0.0, 0.0, 1.2);
        let (v, free) = choose_velocity(&me, DVec2::new(0.0, 1.2), &[aside], &[]);
        assert!(free);
        assert_eq!(v, DVec2::new(0.0, 1.2));
    }

    #[test]
    fn head_on_walkers_both_keep_right() {
        let a = agent(0.0, 0.0, 0.0, 1.2);
        let b = agent(0.0, 3.0, 0.0, -1.2);
        let (va, _) = choose_velocity(&a, DVec2::new(0.0, 1.2), &[b], &[]);
        let (vb, _) = choose_velocity(&b, DVec2::new(0.0, -1.2), &[a], &[]);
        // a faces +z: its right is −x; b faces −z: its right is +x.
        assert!(va.x < 0.0 && vb.x > 0.0, "{va} {vb}");
        // Mirror images: the choice depends only on the geometry.
        assert!((va.x + vb.x).abs() < 1e-12 && (va.y + vb.y).abs() < 1e-12);
    }

    #[test]
    fn overlapping_bodies_never_close_in() {
        let me = agent(0.0, 0.0, 0.0, 1.0);
        let other = agent(0.0, 0.5, 0.0, 0.0);
        let (v, _) = choose_velocity(&me, DVec2::new(0.0, 1.0), &[other], &[]);
        assert!(v.y <= 0.0, "{v}");
    }

    #[test]
    fn a_wall_ahead_is_not_walked_into() {
        let wall = Footprint::hull(
            "wall",
            &[
                DVec2::new(-2.0, 0.5),
                DVec2::new(2.0, 0.5),
                DVec2::new(2.0, 0.6),
                DVec2::new(-2.0, 0.6),
            ],
        );
        let me = agent(0.0, 0.0, 0.0, 1.0);
        let (v, _) = choose_velocity(&me, DVec2::new(0.0, 1.0), &[], &[&wall]);
        assert!(v.y < 0.5, "{v}");
    }
}
