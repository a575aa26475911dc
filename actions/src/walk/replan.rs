//! Leaving the plan: a walk that has stood blocked by people standing in its way plans a
//! new route round them, from where the body is, and follows it from there.
//!
//! Local avoidance only bends how the plan is followed (see [`super::steer`]): it can wait
//! and sidestep, but a person standing right on the planned line, with others beside
//! them, is a local minimum it does not leave (both sides cost the same, and the pull
//! back onto the plan brings the body behind them again). After [`BLOCKED_TIME`] of
//! waiting, the walk asks the navigation mesh for a path that treats the actors standing
//! near by as obstacles (a mesh built for this query alone), and walks it as a new plan
//! that starts where the body stands: the feet stay where they are planted and the next
//! landings are placed on the new plan.

use troupe_body::glam::DVec2;
use troupe_scene::space::{path_length, Footprint, Pressed, CLEARANCE};
use troupe_scene::GeneratorContext;

/// Seconds a walk waits, blocked, before it plans round those in its way.
pub const BLOCKED_TIME: f64 = 1.0;
/// Seconds between two new routes of one walk, at least.
const REPLAN_INTERVAL: f64 = 2.0;
/// Longest wait (s) between two attempts after attempts that found no route: each such
/// attempt doubles the wait from [`REPLAN_INTERVAL`] up to this. A query builds a mesh
/// of its own (milliseconds among many obstacles), and in a crowd converging on a few
/// spots, where walkers stand blocked for long, attempts every 2 s that found nothing
/// took a quarter of the tick (`troupe bench --actors 1000`).
const LONGEST_INTERVAL: f64 = 16.0;
/// Below this plan clock rate the walk counts as waiting.
pub const WAITING_RATE: f64 = 0.1;
/// Below this speed (m/s) an actor counts as standing: an obstacle for the new route.
pub const STANDING: f64 = 0.1;
/// Actors standing within this distance (m) are obstacles for the new route.
const AROUND: f64 = 4.0;
/// Longest new route taken, in times the straight distance to the goal (plus a metre,
/// and [`DETOUR_PER_SECOND`] for each second the body has stood held with nobody moving
/// near).
const LONGEST: f64 = 1.5;
/// How much longer (m) a new route may be for each second a walk's body has stood held
/// with nobody moving near: a way round is worth the time already lost waiting for
/// those who do not move (a walker whose doorway someone stood in stood there for good,
/// the other door 6 m along the wall: a route 13 m long against 3.4 m straight).
const DETOUR_PER_SECOND: f64 = 1.0;
/// Attempts in a row that found no route after which the next may step out of a
/// standing body's inflation first ([`Pressed::StepOutIfStuck`]): the second attempt,
/// after the walk has stood blocked 5 s. From the first, the twelve layouts of the plaza
/// had more contacts between walkers than any draw of no change (docs/navigation.md,
/// "Landings round corners, stalled bodies, slivers of mesh"). Since troupe inflates the
/// obstacles (the mesh holds the exact clearance), a start within an inflation is off the
/// mesh and steps out at every attempt; this is left for a start within the search's
/// 5 mm of the mesh's edge.
const STEP_OUT_AFTER: u32 = 1;

/// When a walk last stood blocked, and when it last planned anew.
#[derive(Clone, Debug, Default)]
pub struct Replan {
    /// Walk time since which the walk has waited without a break.
    blocked_since: Option<f64>,
    /// Walk time since which its body has stood held with nobody moving near (stalled:
    /// see [`Replan::due`]), without a break.
    still_since: Option<f64>,
    /// Walk time of the last new route (or of the last attempt).
    last: Option<f64>,
    /// How many new routes the walk has taken.
    pub count: u32,
    /// Attempts in a row that found no route (see [`LONGEST_INTERVAL`]).
    failures: u32,
}

impl Replan {
    /// Notes whether the walk waits at walk time `now` (its plan clock `rate`, or its
    /// body `stalled`: see [`Replan::route`]), and says whether it has waited long enough
    /// to look for a new route; for its `last_look` before it gives up as stuck, the wait
    /// between attempts is the shortest (2 s) however many found nothing.
    pub fn due(&mut self, now: f64, rate: f64, (stalled, last_look): (bool, bool)) -> bool {
        self.still_since = if stalled {
            self.still_since.or(Some(now))
        } else {
            None
        };
        if rate >= WAITING_RATE && !stalled {
            self.blocked_since = None;
            return false;
        }
        let since = *self.blocked_since.get_or_insert(now);
        let interval = if last_look {
            REPLAN_INTERVAL
        } else {
            (REPLAN_INTERVAL * 2f64.powi(self.failures.min(8) as i32)).min(LONGEST_INTERVAL)
        };
        now - since >= BLOCKED_TIME && self.last.is_none_or(|t| now - t >= interval)
    }

    /// A route from `from` to `goal` for a body of `radius` round the obstacles and the
    /// actors standing within `AROUND` (but `companions`), from the previous tick's
    /// world; `None` when there is none (the walk then goes on waiting). Counts as an
    /// attempt at walk time `now`.
    ///
    /// With nobody standing near there is nothing new to plan round, unless the body is
    /// `stalled`: it stands, with nobody moving near, while its plan goes on, held back
    /// by the clearance or its feet (a walker pressed against a planter's corner by a
    /// plan that ran into it stood there for the last 75 s of the plaza). A route from
    /// where it stands then starts with a step out of the obstacles' inflation.
    pub fn route(
        &mut self,
        ctx: &GeneratorContext,
        now: f64,
        (from, goal): (DVec2, DVec2),
        radius: f64,
        (companions, stalled): (&[usize], bool),
    ) -> Option<Vec<DVec2>> {
        self.last = Some(now);
        let pressed = if self.failures >= STEP_OUT_AFTER {
            Pressed::StepOutIfStuck
        } else {
            Pressed::SearchFromHere
        };
        // Only a wait for those who stand counts: in a crowd on the move the way clears.
        let waited = now - self.still_since.unwrap_or(now);
        let longer = DETOUR_PER_SECOND * waited.max(0.0);
        let around = (companions, stalled, longer);
        let found = Self::find(ctx, (from, goal), radius, around, pressed);
        match found {
            Some(_) => {
                self.count += 1;
                self.failures = 0;
            }
            None => self.failures += 1,
        }
        found
    }

    /// The route [`Replan::route`] looks for.
    fn find(
        ctx: &GeneratorContext,
        (from, goal): (DVec2, DVec2),
        radius: f64,
        (companions, stalled, longer): (&[usize], bool, f64),
        pressed: Pressed,
    ) -> Option<Vec<DVec2>> {
        let crowd = ctx.world.crowd;
        let mut near = Vec::new();
        crowd.near(from, &mut near);
        let standing: Vec<Footprint> = near
            .into_iter()
            .filter(|&j| j != ctx.actor && !companions.contains(&j))
            .filter(|&j| {
                crowd.velocities[j].length() < STANDING
                    && (crowd.positions[j] - from).length() < AROUND
            })
            .map(|j| {
                let name = ctx.world.actors.get(j).map_or("someone", |a| &a.name);
                Footprint::disc(name, crowd.positions[j], crowd.radii[j])
            })
            .collect();
        if standing.is_empty() && !stalled {
            return None;
        }
        // Only the obstacles that can bear on a route short enough to be taken: each
        // query builds a mesh of its own, and among many obstacles (a field of pillars)
        // the build took a quarter of the tick of `troupe bench`'s crowd.
        let window = RouteWindow::new((from, goal), longer, radius + CLEARANCE);
        let obstacles: Vec<Footprint> = crowd
            .footprints
            .iter()
            .filter(|o| window.may_touch(o))
            .cloned()
            .collect();
        let space = &ctx.world.space;
        let points = if standing.is_empty() {
            // Stalled, with nobody standing near: the lasting obstacles' mesh, cached, as
            // the walk's first plan had it, not a mesh of its own.
            space.path(&crowd.footprints, from, goal, radius)
        } else {
            space.path_around(&obstacles, &standing, from, goal, radius, pressed)
        }
        .ok()?;
        // Pressed against furniture or a wall, a route first steps out to the nearest
        // free point, which may lie beyond it (in a corridor with someone standing in
        // it): a first leg through an obstacle is not taken.
        let first = *points.first()?;
        let steps = ((first - from).length() / 0.05).ceil().max(1.0) as usize;
        let through = (0..=steps).any(|k| {
            let p = from.lerp(first, k as f64 / steps as f64);
            obstacles.iter().any(|o| o.contains(p))
        });
        if through {
            return None;
        }
        // A way round that is much longer than waiting is worth (round a whole corridor,
        // say) is not taken.
        if path_length(from, &points) > longest(from, goal, longer) {
            return None;
        }
        Some(points)
    }
}

/// The longest new route taken from `from` to `to` (m), `longer` (m) for the time waited
/// (see [`LONGEST`]).
fn longest(from: DVec2, to: DVec2, longer: f64) -> f64 {
    (to - from).length() * LONGEST + 1.0 + longer
}

/// Where a route short enough to be taken can lie: every point of a route no longer
/// than [`longest`] is within the ellipse whose foci are its ends
/// (the sum of its distances to them is at most that length), so within the ellipse's
/// bounding box. On a mesh without the obstacles outside the box (grown by the body's
/// inflation), the shortest route is still right: if it leaves the box it is too long
/// and is refused, and if it stays inside it meets every obstacle there.
struct RouteWindow {
    centre: DVec2,
    half: DVec2,
}

impl RouteWindow {
    /// The window of routes from `from` to `to`, `longer` (m) for the time waited, for a
    /// body inflated by `inflation` (m).
    fn new((from, to): (DVec2, DVec2), longer: f64, inflation: f64) -> RouteWindow {
        let straight = (to - from).length();
        let axis = (to - from).try_normalize().unwrap_or(DVec2::X);
        let a = longest(from, to, longer) / 2.0;
        let b = (a * a - straight * straight / 4.0).max(0.0).sqrt();
        let half = DVec2::new(
            (a * a * axis.x * axis.x + b * b * axis.y * axis.y).sqrt(),
            (a * a * axis.y * axis.y + b * b * axis.x * axis.x).sqrt(),
        );
        RouteWindow {
            centre: (from + to) / 2.0,
            half: half + DVec2::splat(inflation),
        }
    }

    /// Whether obstacle `o` may come within the window (by its bounding circle).
    fn may_touch(&self, o: &Footprint) -> bool {
        let (c, r) = o.bounding_circle();
        let outside = ((c - self.centre).abs() - self.half).max(DVec2::ZERO);
        outside.length() <= r
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_route_is_due_after_waiting_and_not_too_often() {
        let mut r = Replan::default();
        assert!(!r.due(0.0, 0.0, (false, false)));
        assert!(!r.due(0.5, 0.05, (false, false)));
        assert!(r.due(1.0, 0.0, (false, false)));
        r.last = Some(1.0);
        // Waiting on: not again before the interval.
        assert!(!r.due(2.5, 0.0, (false, false)));
        assert!(r.due(3.0, 0.0, (false, false)));
        // Walking again resets the wait.
        assert!(!r.due(5.0, 0.5, (false, false)));
        assert!(!r.due(5.5, 0.0, (false, false)));
        assert!(!r.due(6.0, 0.0, (false, false)));
        assert!(r.due(6.5, 0.0, (false, false)));
    }

    #[test]
    fn a_stalled_body_counts_as_waiting_whatever_its_plan_clock() {
        let mut r = Replan::default();
        assert!(!r.due(0.0, 1.0, (true, false)));
        assert!(!r.due(0.5, 1.0, (true, false)));
        assert!(r.due(1.0, 1.0, (true, false)));
        // Moving again resets the wait.
        let mut r = Replan::default();
        assert!(!r.due(0.0, 1.0, (true, false)));
        assert!(!r.due(0.5, 1.0, (false, false)));
        assert!(!r.due(1.0, 1.0, (true, false)));
    }

    #[test]
    fn the_window_holds_every_route_short_enough_to_take() {
        let (from, to) = (DVec2::new(1.0, 2.0), DVec2::new(7.0, -3.0));
        let w = RouteWindow::new((from, to), 0.0, 0.0);
        let longest = longest(from, to, 0.0);
        // Points on the ellipse of routes of the longest length, all round it.
        for k in 0..360 {
            let dir = DVec2::from_angle((k as f64).to_radians());
            // The distance along `dir` from `from` at which the sum reaches `longest`.
            let (mut lo, mut hi) = (0.0, longest);
            for _ in 0..60 {
                let m = (lo + hi) / 2.0;
                let p = from + dir * m;
                if (p - from).length() + (p - to).length() < longest {
                    lo = m;
                } else {
                    hi = m;
                }
            }
            let p = from + dir * lo;
            assert!(
                w.may_touch(&Footprint::disc("p", p, 1e-6)),
                "{p} is on a route short enough but outside the window"
            );
        }
        // And a pillar well beyond it is left out.
        assert!(!w.may_touch(&Footprint::disc("far", DVec2::new(30.0, 0.0), 0.5)));
    }

    #[test]
    fn a_longer_wait_takes_a_longer_way_round() {
        let (from, to) = (DVec2::new(-2.6, 2.6), DVec2::new(-2.0, 6.0));
        // Round by a door 6 m along: about 13 m against 3.5 m straight.
        let round = 13.0;
        assert!(longest(from, to, 0.0) < round);
        assert!(longest(from, to, DETOUR_PER_SECOND * 15.0) > round);
        // The window grows with it: the far door's jamb is in it only after the wait.
        let jamb = Footprint::disc("jamb", DVec2::new(4.5, 3.0), 0.05);
        assert!(!RouteWindow::new((from, to), 0.0, 0.36).may_touch(&jamb));
        assert!(RouteWindow::new((from, to), 15.0, 0.36).may_touch(&jamb));
    }

    #[test]
    fn attempts_that_find_nothing_are_spaced_out_more_and_more() {
        let mut r = Replan {
            last: Some(10.0),
            failures: 1,
            ..Replan::default()
        };
        assert!(!r.due(9.0, 0.0, (false, false)));
        // One failure: 4 s, not 2.
        assert!(!r.due(13.0, 0.0, (false, false)));
        assert!(r.due(14.0, 0.0, (false, false)));
        // Many: at most 16 s.
        r.failures = 30;
        assert!(!r.due(25.0, 0.0, (false, false)));
        assert!(r.due(26.0, 0.0, (false, false)));
        // But a last look before giving up as stuck waits 2 s only.
        r.last = Some(26.0);
        assert!(!r.due(27.0, 0.0, (false, false)));
        assert!(!r.due(27.0, 0.0, (false, true)));
        assert!(r.due(28.0, 0.0, (false, true)));
    }
}
