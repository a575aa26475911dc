//! Where a tick's time goes: per-phase timings that a scene collects on request.
//!
//! Profiling is off by default, because reading the clock four times per actor-tick costs
//! about 1 % of a keyframe actor's tick. `troupe bench` switches it on to print the share
//! of each phase. Actor phases run in parallel, so they are measured as CPU time summed
//! over actors; [`StepProfile::split_wall`] turns them into shares of the step's wall
//! time.

use std::time::{Duration, Instant};

/// CPU time spent in each phase of the actors' ticks, summed over actors.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ActorPhases {
    /// Admission, status transitions and retiring ended actions.
    pub scheduling: Duration,
    /// Stepping the generators.
    pub generators: Duration,
    /// Blending, clamping to limits and forward kinematics.
    pub blend_fk: Duration,
}

impl ActorPhases {
    /// Adds another measurement to this one.
    pub fn add(&mut self, other: &ActorPhases) {
        self.scheduling += other.scheduling;
        self.generators += other.generators;
        self.blend_fk += other.blend_fk;
    }

    /// The sum of all phases.
    pub fn total(&self) -> Duration {
        self.scheduling + self.generators + self.blend_fk
    }
}

/// The timings of one or more scene steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepProfile {
    /// Wall time of the parallel actor step (fork to join).
    pub step_wall: Duration,
    /// Wall time of the serial publish after the join (state swap, events, records).
    pub publish_wall: Duration,
    /// Wall time of the serial sensor and attachment phase after the publish (objects
    /// attached, released and moved with the hands that hold them).
    pub collision_wall: Duration,
    /// CPU time per actor phase, summed over actors.
    pub actors: ActorPhases,
}

impl StepProfile {
    /// Adds another measurement to this one.
    pub fn add(&mut self, other: &StepProfile) {
        self.step_wall += other.step_wall;
        self.publish_wall += other.publish_wall;
        self.collision_wall += other.collision_wall;
        self.actors.add(&other.actors);
    }

    /// The wall time of the step split by phase: the parallel step's wall time is shared
    /// out in proportion to the actors' CPU time per phase (fork/join overhead included),
    /// and the serial publish counts as scheduling. Returns (scheduling, generators,
    /// blend + FK, collision).
    pub fn split_wall(&self) -> (Duration, Duration, Duration, Duration) {
        let cpu = self.actors.total().as_secs_f64();
        let wall = self.step_wall.as_secs_f64();
        let share = |d: Duration| {
            if cpu > 0.0 {
                Duration::from_secs_f64(wall * d.as_secs_f64() / cpu)
            } else {
                Duration::ZERO
            }
        };
        let generators = share(self.actors.generators);
        let blend_fk = share(self.actors.blend_fk);
        let scheduling = self
            .step_wall
            .saturating_sub(generators + blend_fk)
            .saturating_add(self.publish_wall);
        (scheduling, generators, blend_fk, self.collision_wall)
    }
}

/// A stopwatch that attributes elapsed time to phases when enabled and costs nothing
/// otherwise.
pub(crate) struct PhaseClock {
    last: Option<Instant>,
}

impl PhaseClock {
    /// Starts timing if `enabled`.
    #[inline]
    pub fn start(enabled: bool) -> Self {
        PhaseClock {
            last: enabled.then(Instant::now),
        }
    }

    /// Adds the time since the previous lap to `slot`.
    #[inline]
    pub fn lap(&mut self, slot: &mut Duration) {
        if let Some(last) = self.last.as_mut() {
            let now = Instant::now();
            *slot += now - *last;
            *last = now;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_wall_shares_the_step_by_cpu_time_and_adds_the_publish_to_scheduling() {
        let p = StepProfile {
            step_wall: Duration::from_millis(10),
            publish_wall: Duration::from_millis(1),
            collision_wall: Duration::from_millis(2),
            actors: ActorPhases {
                scheduling: Duration::from_millis(2),
                generators: Duration::from_millis(10),
                blend_fk: Duration::from_millis(8),
            },
        };
        let (sched, gen, fk, coll) = p.split_wall();
        assert_eq!(gen, Duration::from_millis(5));
        assert_eq!(fk, Duration::from_millis(4));
        assert_eq!(sched, Duration::from_millis(2));
        assert_eq!(coll, Duration::from_millis(2));
    }

    #[test]
    fn a_disabled_clock_records_nothing() {
        let mut slot = Duration::ZERO;
        let mut clock = PhaseClock::start(false);
        std::thread::sleep(Duration::from_millis(2));
        clock.lap(&mut slot);
        assert_eq!(slot, Duration::ZERO);
        let mut clock = PhaseClock::start(true);
        std::thread::sleep(Duration::from_millis(2));
        clock.lap(&mut slot);
        assert!(slot >= Duration::from_millis(2));
    }
}
