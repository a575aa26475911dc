//! Turning the shoulders to pass (thesis 6.5.3: a walker brushing past a standing actor,
//! figure 6-21): when another body or an obstacle is close beside the walker, the chest
//! turns towards it about the spine's vertical axis, so that the shoulders, the widest
//! part of a body seen from above, take less room across the way. The turn grows as the
//! side gap shrinks below [`CLEAR`], fades with the neighbour's distance ahead or behind,
//! and changes no faster than `TURN_RATE`. It reads the previous tick's crowd, so it
//! is the same whatever the thread count.

use super::route::direction;
use troupe_body::glam::DVec2;
use troupe_body::math::smoothstep;
use troupe_scene::space::FootprintsAround;
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

/// Gap (m) between the body and anything round it below which the arms swing less, and
/// not at all at a third of it: a swinging hand reaches out of the body's disc, and
/// swinging into a neighbour's it would move faster than the clearance looks (the body's
/// capsule widens only as far as the wrists were out on the last tick).
pub const ARMS_CLEAR: f64 = 0.3;
/// Largest change of the arms' swing (fraction of the full swing per second).
const ARMS_RATE: f64 = 3.0;

/// How far the shoulders are turned now (radians, positive to the left), and how much the
/// arms swing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shoulders {
    /// The turn (radians about the vertical; positive turns the chest to the left).
    pub turn: f64,
    /// The arms' swing, from 0 (held still) to 1 (the gait's own).
    pub arms: f64,
}

impl Default for Shoulders {
    fn default() -> Self {
        Shoulders {
            turn: 0.0,
            arms: 1.0,
        }
    }
}

impl Shoulders {
    /// The turn actor `ctx.actor`, heading `heading`, wants now: towards the closest
    /// neighbour (not in `companions`) or obstacle beside it. `near`, in actor order,
    /// holds at least every actor within 0.9 m ahead or behind (`ALONGSIDE`) whose disc
    /// comes within [`CLEAR`] across (the walk gives those whose surroundings it gathered
    /// this tick, which reach over a metre further), and `footprints` the obstacles round
    /// it.
    pub fn wanted(
        ctx: &GeneratorContext,
        heading: f64,
        companions: &[usize],
        (near, footprints): (&[usize], &FootprintsAround),
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
        // One `CLEAR` or more away, or not beside, needs no turn: passed over before the
        // rest is weighed (most of those near; the same turns).
        for &j in near {
            let d = crowd.positions[j] - p;
            let ahead = d.dot(forward).abs();
            if ahead >= ALONGSIDE {
                continue;
            }
            let lateral = d.dot(left);
            let gap = lateral.abs() - r - crowd.radii[j];
            if gap >= CLEAR || j == me || companions.contains(&j) {
                continue;
            }
            let need = smoothstep((CLEAR - gap) / CLEAR) * smoothstep(1.0 - ahead / ALONGSIDE);
            consider(need, lateral.signum());
        }
        let h = 0.05;
        for f in footprints.within(r + CLEAR) {
            let gap = f.distance(p) - r;
            if gap >= CLEAR {
                continue;
            }
            // Which side it is on, and how much it is beside rather than ahead.
            let slope = (f.distance(p + left * h) - f.distance(p - left * h)) / (2.0 * h);
            let need = smoothstep((CLEAR - gap) / CLEAR) * slope.abs().min(1.0);
            consider(need, -slope.signum());
        }
        best.1 * best.0 * MAX_TURN
    }

    /// Turns towards [`Shoulders::wanted`] by at most `TURN_RATE` × `dt`, and lets the
    /// arms swing as the least `gap` (m) between the body and what is round it allows
    /// (see [`ARMS_CLEAR`]).
    pub fn update(
        &mut self,
        ctx: &GeneratorContext,
        heading: f64,
        companions: &[usize],
        around: (&[usize], &FootprintsAround),
        gap: f64,
    ) {
        let want = Shoulders::wanted(ctx, heading, companions, around);
        let step = TURN_RATE * ctx.dt;
        self.turn += (want - self.turn).clamp(-step, step);
        let arms = smoothstep((gap / ARMS_CLEAR - 1.0 / 3.0) * 1.5);
        let step = ARMS_RATE * ctx.dt;
        self.arms += (arms - self.arms).clamp(-step, step);
    }

    /// The shoulder twists (left, right, as the template's DOF values) that turn each
    /// upper arm back by the shoulders' turn: the walk bends the elbows, and a forearm bent
    /// from a chest turned towards a neighbour points at the neighbour (2.5 cm further out
    /// at the wrist in the plaza, where hands met by 2 to 3 cm); twisted back it points
    /// the way the body goes. The left twist's axis is −Y and the right's +Y.
    pub fn arm_twists(&self) -> [f64; 2] {
        [self.turn, -self.turn]
    }

    /// How much of the gait's arm swing is left: less as the shoulders turn, and as
    /// [`Shoulders::arms`] says.
    pub fn swing(&self) -> f64 {
        (1.0 - (self.turn.abs() / MAX_TURN).min(1.0)) * self.arms
    }
}
