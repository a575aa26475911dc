//! The body stays on its feet: while avoidance steers a walk, the root goes only where
//! the legs can still reach the feet they have planted. Steering changes the pace and the
//! sidestep after a landing was chosen for the old ones; followed blindly, the body would
//! walk away from a planted foot: the leg's solution past the ankle's or the hip's joint
//! limits (the scene clamps them, the foot drags and its sole dips below the floor).
//! So each tick the steered root position is tried first; if a planted leg would be
//! strained, the root goes only as far from where it stood on the previous tick as the
//! legs allow (a bisection on the straight line between the two), and the steering takes
//! the difference ([`super::steer::Steer::hold`]).

use super::rig::Leg;
use troupe_body::glam::DVec2;

/// Strain (radians past a joint limit, or metres of missed reach) a planted leg may have
/// before the body is held back: the walk's own small excursions (the ankle at the end of
/// a long support) stay free.
pub const TOLERANCE: f64 = 0.01;
/// Halvings of the bisection: the held position is within 1/256 of the tick's motion of
/// the farthest the legs allow.
const HALVINGS: usize = 8;

/// How far the DOF `values` of `leg` (in [`Leg::dofs`] order) go past the leg's joint
/// limits (the largest excess, radians), or `miss`, how far its ankle stays from its
/// target, if that is more.
pub fn strain(leg: &Leg, values: &[f64; 7], miss: f64) -> f64 {
    values
        .iter()
        .zip(&leg.limits)
        .map(|(&v, &(lo, hi))| (lo - v).max(v - hi))
        .fold(miss, f64::max)
}

/// Where the root goes, between `last` (where it stood on the previous tick) and
/// `wanted` (where the steering puts it, a planted leg then strained by `strain_wanted`),
/// given the legs `solve` finds for any point and the `strain` they ask: `None` when
/// `wanted` stands, that is when it is within [`TOLERANCE`] or when even `last` is
/// strained at least as much (nothing to hold on to); else the farthest point towards it
/// within the tolerance (`last` itself when strained but less), with the legs solved there
/// (the bisection has them already: solving them again would cost the walk a second
/// solve of both legs).
pub fn hold<T>(
    last: DVec2,
    wanted: DVec2,
    strain_wanted: f64,
    solve: impl Fn(DVec2) -> T,
    strain: impl Fn(&T) -> f64,
) -> Option<(DVec2, T)> {
    if strain_wanted <= TOLERANCE {
        return None;
    }
    let from = solve(last);
    let strain_from = strain(&from);
    if strain_from > TOLERANCE {
        return (strain_from < strain_wanted).then_some((last, from));
    }
    let (mut free, mut strained) = (0.0, 1.0);
    let mut best = from;
    for _ in 0..HALVINGS {
        let mid = 0.5 * (free + strained);
        let solved = solve(last + (wanted - last) * mid);
        if strain(&solved) <= TOLERANCE {
            free = mid;
            best = solved;
        } else {
            strained = mid;
        }
    }
    Some((last + (wanted - last) * free, best))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A leg that reaches 0.5 m from the origin: its strain is how far beyond.
    fn reach(p: DVec2) -> f64 {
        (p.length() - 0.5).max(0.0)
    }

    /// [`hold`] for that leg, "solved" as the point itself: where the root goes.
    fn held(last: DVec2, wanted: DVec2) -> DVec2 {
        match hold(last, wanted, reach(wanted), |p| p, |&p| reach(p)) {
            Some((at, solved)) => {
                assert_eq!(
                    at, solved,
                    "the solution handed back is the one at the point"
                );
                at
            }
            None => wanted,
        }
    }

    #[test]
    fn a_free_step_is_taken_and_a_strained_one_stops_where_the_leg_reaches() {
        let last = DVec2::new(0.3, 0.0);
        let free = DVec2::new(0.4, 0.0);
        assert_eq!(held(last, free), free);
        let far = DVec2::new(0.7, 0.0);
        let held = held(last, far);
        assert!(reach(held) <= TOLERANCE, "{held}");
        assert!(held.x > 0.5 && held.x < 0.5 + TOLERANCE, "{held}");
    }

    #[test]
    fn a_body_already_strained_moves_only_to_ease_it() {
        let last = DVec2::new(0.8, 0.0);
        let easier = DVec2::new(0.7, 0.0);
        assert_eq!(held(last, easier), easier);
        let worse = DVec2::new(0.9, 0.0);
        assert_eq!(held(last, worse), last);
    }
}
