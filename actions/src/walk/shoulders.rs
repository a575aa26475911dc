//! Turning the shoulders to pass (thesis 6.5.3: a walker brushing past a standing actor,
//! figure 6-21): when another body or an obstacle is close beside the walker, the chest
//! turns towards it about the spine's vertical axis, so that the shoulders, the widest
//! part of a body seen from above, take less room across the way. The turn grows as the
//! side gap shrinks below [`CLEAR`], fades with the neighbour's distance ahead or behind,
//! and changes no faster than [`TURN_RATE`]. It reads the previous tick's crowd, so it
//! is the same whatever the thread count.

use super::route::direction;
use troupe_body::glam::DVec2;
use troupe_body::math::smoothstep;
use troupe_scene::GeneratorContext;

/// Largest turn of the shoulders (radians, about 34°).
pub const MAX_TURN: f64 = 0.6;
/// Side gaps (m) between the body discs, or between the disc and an obstacle, below
/// which the shoulders start to turn.
pub const CLEAR: f64 = 0.12;
/// A neighbour further ahead or behind than this (m) is not beside the walker.
const ALONGSIDE: f64 = 0.9;
/// Largest change of the turn (radians per second).
const TURN_RATE: f64 = 1.5;

/// How far the shoulders are turned now (radians, positive to the left).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Shoulders {
    /// The turn (radians about the vertical; positive turns the chest to the left).
    pub turn: f64,
}

impl Shoulders {
    /// The turn actor `ctx.actor`, heading `heading`, wants now: towards the closest
    /// neighbour (not in `companions`) or obstacle beside it. `near`, in actor order,
    /// holds at least the actors the crowd finds near the body (`Crowd::near`) when the
    /// steering has gathered them this tick; `None` looks them up.
    pub fn wanted(
        ctx: &GeneratorContext,
        heading: f64,
        companions: &[usize],
        near: Option<&[usize]>,
    ) -> f64 {
        let crowd = ctx.world.crowd;
        let me = ctx.actor;
        let (Some(&p), Some(&r)) = (crowd.positions.get(me), crowd.radii.get(me)) else {
            return 0.0;
        };
        let forward = direction(heading);
        let left = DVec2::new(forward.y, -forward.x);
        // (need in [0, 1], side: +1 left, −1 right); the first largest need wins.
        let mut best = (0.0f64, 0.0f64);
        let mut consider = |need: f64, side: f64| {
            if need > best.0 {
                best = (need, side);
            }
        };
        let mut found = Vec::new();
        let near = near.unwrap_or_else(|| {
            crowd.near(p, &mut found);
            &found
        });
        // Those only the steering found (farther ahead) are too far to be beside.
        for &j in near {
            if j == me || companions.contains(&j) {
                continue;
            }
            let d = crowd.positions[j] - p;
            let ahead = d.dot(forward).abs();
            let lateral = d.dot(left);
            let gap = lateral.abs() - r - crowd.radii[j];
            if ahead < ALONGSIDE {
                let need = smoothstep((CLEAR - gap) / CLEAR) * smoothstep(1.0 - ahead / ALONGSIDE);
                consider(need, lateral.signum());
            }
        }
        let h = 0.05;
        for f in crowd.footprints_near(p, r + CLEAR) {
            let gap = f.distance(p) - r;
            // Which side it is on, and how much it is beside rather than ahead.
            let slope = (f.distance(p + left * h) - f.distance(p - left * h)) / (2.0 * h);
            let need = smoothstep((CLEAR - gap) / CLEAR) * slope.abs().min(1.0);
            consider(need, -slope.signum());
        }
        best.1 * best.0 * MAX_TURN
    }

    /// Turns towards [`Shoulders::wanted`] by at most [`TURN_RATE`] × `dt`.
    pub fn update(
        &mut self,
        ctx: &GeneratorContext,
        heading: f64,
        companions: &[usize],
        near: Option<&[usize]>,
    ) {
        let want = Shoulders::wanted(ctx, heading, companions, near);
        let step = TURN_RATE * ctx.dt;
        self.turn += (want - self.turn).clamp(-step, step);
    }
}
