//! How each actor's actions ended in a run: the numbers a run's summary prints.

use crate::action::{Event, Status};
use crate::error::Result;
use crate::scene::Scene;
use crate::session::Observer;

/// Counts, per actor, the actions that completed, were cancelled and failed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ActionTally {
    /// Per actor index: `[completed, cancelled, failed]`.
    pub counts: Vec<[usize; 3]>,
}

impl ActionTally {
    /// An empty tally.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the ends among `events`.
    pub fn count(&mut self, events: &[Event]) {
        for e in events {
            let column = match e.status {
                Status::Completed => 0,
                Status::Cancelled => 1,
                Status::Failed => 2,
                _ => continue,
            };
            if self.counts.len() <= e.actor {
                self.counts.resize(e.actor + 1, [0; 3]);
            }
            self.counts[e.actor][column] += 1;
        }
    }

    /// The counts of actor `actor` (zeros for an actor none of whose actions ended).
    pub fn of(&self, actor: usize) -> [usize; 3] {
        self.counts.get(actor).copied().unwrap_or([0; 3])
    }

    /// One line per actor: `  NAME  actions: N completed, N cancelled, N failed`.
    pub fn summary(&self, scene: &Scene) -> String {
        scene
            .actors()
            .iter()
            .enumerate()
            .map(|(i, actor)| {
                let [done, cancelled, failed] = self.of(i);
                format!(
                    "  {:<12} actions: {done} completed, {cancelled} cancelled, {failed} failed",
                    actor.name
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

impl Observer for ActionTally {
    fn name(&self) -> String {
        "action tally".into()
    }

    fn publish(&mut self, _scene: &Scene, events: &[Event]) -> Result<()> {
        self.count(events);
        Ok(())
    }
}
