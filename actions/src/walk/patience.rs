//! How long a walk waits for others before it gives up (`walk{ patience = seconds }`).
//!
//! A walk held by people standing in its way or on its goal waits for them to move, as
//! long as it takes (see `Walk::waiting_for_someone`): in a crowd they usually do. Where
//! they will not (a block of places filled from the front, a doorway someone stands in),
//! a behaviour author wants the walk to fail after a while, naming who stands there, so
//! that the script can send the actor elsewhere; game engines' "move to" gives up when
//! blocked in the same way. Getting on is measured along the route, by the plan's clock,
//! which the steering holds back where the body is held: a sidestep or a shuffle on the
//! spot is no progress, a detour walked is.

/// Plan seconds by which a walk's remaining way must shrink to count as getting on (at
/// the cruising 1.3 m/s, 6.5 cm).
pub const PROGRESS_TIME: f64 = 0.05;

/// How long a walk may go without getting on before it fails, and since when it has.
#[derive(Clone, Debug)]
pub struct Patience {
    /// Seconds the walk may go without getting on.
    limit: f64,
    /// The least plan time left seen since the walk last got on, and the walk time it
    /// last did.
    least: Option<(f64, f64)>,
}

impl Patience {
    /// A patience of `limit` seconds, counted from the walk's start.
    pub fn new(limit: f64) -> Patience {
        Patience { limit, least: None }
    }

    /// The seconds the walk may go without getting on.
    pub fn limit(&self) -> f64 {
        self.limit
    }

    /// Notes that at walk time `now` the plan has `left` seconds to go, and says whether
    /// the walk has now gone `limit` seconds without getting [`PROGRESS_TIME`] nearer its
    /// end than it had been.
    ///
    /// A new plan (a new route round those standing, another free place) may have more
    /// to go than the one before: it is measured from then on, but the time already
    /// waited still counts, so that a walk that keeps taking new routes and is held on
    /// each runs out of patience too.
    pub fn run_out(&mut self, now: f64, left: f64) -> bool {
        let (least, since) = *self.least.get_or_insert((left, now));
        if left < least - PROGRESS_TIME {
            self.least = Some((left, now));
            return false;
        }
        if left > least {
            self.least = Some((left, since));
        }
        now - since >= self.limit
    }

    /// Forgets what was waited: the walk starts again.
    pub fn restart(&mut self) {
        self.least = None;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_walk_getting_on_keeps_its_patience() {
        let mut p = Patience::new(2.0);
        for k in 0..1000 {
            let now = k as f64 * 0.01;
            assert!(!p.run_out(now, 20.0 - now), "at {now}");
        }
    }

    #[test]
    fn a_walk_held_runs_out_after_its_limit_and_not_before() {
        let mut p = Patience::new(2.0);
        assert!(!p.run_out(0.0, 5.0));
        // Creeping by less than the progress counts as held.
        assert!(!p.run_out(1.0, 4.98));
        assert!(!p.run_out(1.99, 4.96));
        assert!(p.run_out(2.0, 4.96));
    }

    #[test]
    fn getting_on_starts_the_count_again() {
        let mut p = Patience::new(2.0);
        assert!(!p.run_out(0.0, 5.0));
        assert!(!p.run_out(1.5, 4.9));
        assert!(!p.run_out(3.4, 4.9));
        assert!(p.run_out(3.5, 4.9));
    }

    #[test]
    fn a_longer_new_plan_does_not_reset_the_wait() {
        let mut p = Patience::new(2.0);
        assert!(!p.run_out(0.0, 5.0));
        // A new route, longer, taken after a second's wait: held on it as well.
        assert!(!p.run_out(1.0, 9.0));
        assert!(!p.run_out(1.9, 9.0));
        assert!(p.run_out(2.0, 9.0));
        // Walking the new route is getting on.
        let mut q = Patience::new(2.0);
        assert!(!q.run_out(0.0, 5.0));
        assert!(!q.run_out(1.0, 9.0));
        assert!(!q.run_out(1.5, 8.5));
        assert!(!q.run_out(3.4, 8.5));
        assert!(q.run_out(3.5, 8.5));
    }

    #[test]
    fn a_restart_forgets_the_wait() {
        let mut p = Patience::new(1.0);
        assert!(!p.run_out(0.0, 5.0));
        p.restart();
        assert!(!p.run_out(0.5, 5.0));
        assert!(!p.run_out(1.25, 5.0));
        assert!(p.run_out(1.5, 5.0));
    }
}
