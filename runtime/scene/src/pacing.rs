//! Real-time pacing: sleep until each tick's deadline and count overruns.

use crate::action::Event;
use crate::error::Result;
use crate::scene::Scene;
use crate::session::Observer;
use std::time::{Duration, Instant};

/// Keeps a loop at a fixed period in wall-clock time.
#[derive(Debug)]
pub struct Pacer {
    period: Duration,
    next: Instant,
    overruns: u64,
    worst_lateness: Duration,
}

impl Pacer {
    /// A pacer for ticks of `period`, starting now.
    pub fn new(period: Duration) -> Self {
        Pacer {
            period,
            next: Instant::now() + period,
            overruns: 0,
            worst_lateness: Duration::ZERO,
        }
    }

    /// Sleeps until the next tick is due. A tick that finished late counts as an overrun;
    /// the schedule then restarts from now instead of rushing to catch up.
    pub fn wait(&mut self) {
        let now = Instant::now();
        if now <= self.next {
            std::thread::sleep(self.next - now);
            self.next += self.period;
        } else {
            let late = now - self.next;
            self.overruns += 1;
            self.worst_lateness = self.worst_lateness.max(late);
            if self.overruns == 1 || self.overruns.is_power_of_two() {
                tracing::warn!(
                    overruns = self.overruns,
                    late_ms = late.as_secs_f64() * 1e3,
                    "tick overran its real-time deadline"
                );
            }
            self.next = now + self.period;
        }
    }

    /// Ticks that missed their deadline.
    pub fn overruns(&self) -> u64 {
        self.overruns
    }

    /// The latest a tick has finished after its deadline.
    pub fn worst_lateness(&self) -> Duration {
        self.worst_lateness
    }
}

impl Observer for Pacer {
    fn name(&self) -> String {
        "real-time pacing".into()
    }

    /// Restarts the schedule: the first tick is due one period after the run starts, not
    /// after the pacer was made (loading a scene may take a while).
    fn start(&mut self, _scene: &Scene) -> Result<()> {
        self.next = Instant::now() + self.period;
        Ok(())
    }

    /// Waits for the tick's deadline.
    fn publish(&mut self, _scene: &Scene, _events: &[Event]) -> Result<()> {
        self.wait();
        Ok(())
    }

    /// How many ticks were late.
    fn finish(&mut self, _scene: &Scene) -> Result<Option<String>> {
        Ok(Some(format!(
            "real time: {} overruns (worst {:.1} ms late)",
            self.overruns,
            self.worst_lateness.as_secs_f64() * 1e3
        )))
    }
}
