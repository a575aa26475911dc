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
use troupe_scene::space::{path_length, Footprint};
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
const WAITING_RATE: f64 = 0.1;
/// Below this speed (m/s) an actor counts as standing: an obstacle for the new route.
const STANDING: f64 = 0.1;
/// Actors standing within this distance (m) are obstacles for the new route.
const AROUND: f64 = 4.0;
/// Within this distance (m) of its goal a blocked walk waits rather than plan anew:
/// those standing in its way stand at or by its goal (a crowd converging on one spot),
/// and a way round them would end behind them all the same. (In `troupe bench`'s crowd,
/// walkers blocked by their goals' pillars built a mesh each and took a quarter of the
/// tick.)
const NEAR_GOAL: f64 = 3.0;
/// Longest new route taken, in times the straight distance to the goal (plus a metre).
const LONGEST: f64 = 1.5;

/// When a walk last stood blocked, and when it last planned anew.
#[derive(Clone, Debug, Default)]
pub struct Replan {
    /// Walk time since which the walk has waited without a break.
    blocked_since: Option<f64>,
    /// Walk time of the last new route (or of the last attempt).
    last: Option<f64>,
    /// How many new routes the walk has taken.
    pub count: u32,
    /// Attempts in a row that found no route (see [`LONGEST_INTERVAL`]).
    failures: u32,
}

impl Replan {
    /// Notes whether the walk waits at walk time `now` (its plan clock `rate`), and says
    /// whether it has waited long enough to look for a new route.
    pub fn due(&mut self, now: f64, rate: f64) -> bool {
        if rate >= WAITING_RATE {
            self.blocked_since = None;
            return false;
        }
        let since = *self.blocked_since.get_or_insert(now);
        let interval =
            (REPLAN_INTERVAL * 2f64.powi(self.failures.min(8) as i32)).min(LONGEST_INTERVAL);
        now - since >= BLOCKED_TIME && self.last.is_none_or(|t| now - t >= interval)
    }

    /// A route from `from` to `goal` for a body of `radius` round the obstacles and the
    /// actors standing within [`AROUND`] (but `companions`), from the previous tick's
    /// world; `None` when there is none (the walk then goes on waiting). Counts as an
    /// attempt at walk time `now`.
    pub fn route(
        &mut self,
        ctx: &GeneratorContext,
        now: f64,
        (from, goal): (DVec2, DVec2),
        radius: f64,
        companions: &[usize],
    ) -> Option<Vec<DVec2>> {
        self.last = Some(now);
        let found = Self::find(ctx, (from, goal), radius, companions);
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
        companions: &[usize],
    ) -> Option<Vec<DVec2>> {
        if (goal - from).length() < NEAR_GOAL {
            return None;
        }
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
        if standing.is_empty() {
            return None;
        }
        let obstacles = ctx.world.obstacles();
        let points = ctx
            .world
            .space
            .path_around(&obstacles, &standing, from, goal, radius)
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
        if path_length(from, &points) > (goal - from).length() * LONGEST + 1.0 {
            return None;
        }
        Some(points)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_new_route_is_due_after_waiting_and_not_too_often() {
        let mut r = Replan::default();
        assert!(!r.due(0.0, 0.0));
        assert!(!r.due(0.5, 0.05));
        assert!(r.due(1.0, 0.0));
        r.last = Some(1.0);
        // Waiting on: not again before the interval.
        assert!(!r.due(2.5, 0.0));
        assert!(r.due(3.0, 0.0));
        // Walking again resets the wait.
        assert!(!r.due(5.0, 0.5));
        assert!(!r.due(5.5, 0.0));
        assert!(!r.due(6.0, 0.0));
        assert!(r.due(6.5, 0.0));
    }

    #[test]
    fn attempts_that_find_nothing_are_spaced_out_more_and_more() {
        let mut r = Replan {
            last: Some(10.0),
            failures: 1,
            ..Replan::default()
        };
        assert!(!r.due(9.0, 0.0));
        // One failure: 4 s, not 2.
        assert!(!r.due(13.0, 0.0));
        assert!(r.due(14.0, 0.0));
        // Many: at most 16 s.
        r.failures = 30;
        assert!(!r.due(25.0, 0.0));
        assert!(r.due(26.0, 0.0));
    }
}
