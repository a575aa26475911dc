//! Replication you can verify (`troupe run SCENE --zenoh-follow PREFIX`): a second
//! troupe runs the same scene file from the leader's seed and the leader's inputs from
//! outside, and compares every posture it computes with the one the leader published for
//! that tick.
//!
//! The inputs of tick N arrive on `<prefix>/inputs` as `u64 N` (little-endian) followed
//! by `.rec` chunks: the bytes the leader's live and relayed devices sent, the tick marks
//! saying which readings each tick took, and the messages from outside with their ticks.
//! [`FollowInput`] hands them, tick by tick, to whatever replays them (the command line
//! gives them to the drivers' `DeviceReplay`). Device streams replayed from a `.rec` file
//! named by the scene are read by both from the same file.

use crate::error::NetError;
use crate::keys::SceneKeys;
use crate::posture::Posture;
use crate::subscriber::PoseFeed;
use crossbeam::channel::{unbounded, Receiver};
use std::collections::{BTreeMap, HashMap};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use troupe_scene::{Event, Input, Observer, Scene};
use zenoh::pubsub::Subscriber;
use zenoh::{Session, Wait};

/// How long a follower waits for the leader's inputs or postures of one tick.
pub const TICK_TIMEOUT: Duration = Duration::from_secs(10);

/// What the leader's `<prefix>/scene` queryable says about the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeaderScene {
    /// The leader's seed.
    pub seed: u64,
    /// The leader's tick rate.
    pub rate: f64,
}

/// A follower's view of a leader: its inputs and its postures, subscribed before the
/// leader starts ticking.
pub struct Leader {
    session: Session,
    keys: SceneKeys,
    _inputs: Subscriber<()>,
    inputs: Receiver<Vec<u8>>,
    poses: PoseFeed,
}

impl Leader {
    /// Subscribes to the leader's postures and inputs under `keys`.
    pub fn subscribe(session: Session, keys: SceneKeys) -> Result<Leader, NetError> {
        let poses = PoseFeed::subscribe(&session, &keys)?;
        let (tx, rx) = unbounded();
        let inputs = session
            .declare_subscriber(keys.inputs())
            .callback(move |sample| {
                let _ = tx.send(sample.payload().to_bytes().into_owned());
            })
            .wait()
            .map_err(|e| NetError::Declare {
                what: "subscriber",
                key: keys.inputs(),
                message: e.to_string(),
            })?;
        Ok(Leader {
            session,
            keys,
            _inputs: inputs,
            inputs: rx,
            poses,
        })
    }

    /// Asks the leader for its seed and rate until it answers (it does once its scene is
    /// loaded), for at most `timeout`.
    pub fn scene(&self, timeout: Duration) -> Result<LeaderScene, NetError> {
        let deadline = Instant::now() + timeout;
        let key = self.keys.scene();
        // Subscribed already: say so, for a leader waiting on followers (every round, and
        // once more after the answer, since the leader listens from before it answers).
        let hello = format!("{}/followers/{}", self.keys.prefix(), self.session.zid());
        let say_hello = || {
            let _ = self.session.put(hello.as_str(), Vec::<u8>::new()).wait();
        };
        while Instant::now() < deadline {
            say_hello();
            let replies = crate::session::query(&self.session, &key, Duration::from_millis(500))?;
            while let Ok(reply) = replies.recv() {
                let Ok(sample) = reply.result() else { continue };
                let doc: serde_json::Value =
                    serde_json::from_slice(&sample.payload().to_bytes()).unwrap_or_default();
                if let (Some(seed), Some(rate)) = (doc["seed"].as_u64(), doc["rate"].as_f64()) {
                    say_hello();
                    return Ok(LeaderScene { seed, rate });
                }
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        Err(NetError::Open(format!(
            "no leader answered on {key} within {} s",
            timeout.as_secs_f64()
        )))
    }

    /// The input and the checking observer of a follower session.
    pub fn into_parts(self) -> (FollowInput, FollowCheck) {
        let report = Arc::new(Mutex::new(Report::default()));
        (
            FollowInput {
                prefix: self.keys.prefix().to_string(),
                _subscriber: self._inputs,
                inputs: self.inputs,
                pending: BTreeMap::new(),
                report: report.clone(),
                replay: None,
            },
            FollowCheck {
                prefix: self.keys.prefix().to_string(),
                _session: self.session,
                poses: self.poses,
                leader: HashMap::new(),
                report,
            },
        )
    }
}

/// What a follower found, shared by its input and its check.
#[derive(Debug, Default)]
struct Report {
    /// The first tick whose inputs never came.
    missing_inputs: Option<u64>,
    /// Ticks compared, actor by actor.
    compared: u64,
    /// Postures the leader published that never came (not compared).
    unchecked: u64,
    /// The first difference: tick, actor, DOF index, leader's value, own value.
    first_difference: Option<(u64, String, usize, f64, f64)>,
}

/// Takes the inputs (`.rec` chunks) of each tick; an error names what was wrong.
pub type InputsSink = Box<dyn FnMut(&[u8]) -> Result<(), String> + Send>;

/// Waits, before each tick, for the leader's inputs of that tick and hands them to the
/// replay (an [`Input`]; add it before the inputs that read the replay).
pub struct FollowInput {
    prefix: String,
    /// Kept declared as long as the inputs are read.
    _subscriber: Subscriber<()>,
    inputs: Receiver<Vec<u8>>,
    /// Inputs received, by tick.
    pending: BTreeMap<u64, Vec<u8>>,
    report: Arc<Mutex<Report>>,
    replay: Option<InputsSink>,
}

impl FollowInput {
    /// Hands each tick's inputs to `replay`, in tick order.
    pub fn replay_into(&mut self, replay: InputsSink) {
        self.replay = Some(replay);
    }

    /// Reads one inputs packet into `pending`.
    fn take(&mut self, bytes: &[u8]) -> Result<(), String> {
        let (tick, chunks) = bytes
            .split_first_chunk::<8>()
            .ok_or("inputs shorter than their tick")?;
        self.pending
            .insert(u64::from_le_bytes(*tick), chunks.to_vec());
        Ok(())
    }
}

impl Input for FollowInput {
    fn name(&self) -> String {
        format!("--zenoh-follow {}", self.prefix)
    }

    fn poll(&mut self, scene: &mut Scene) -> troupe_scene::Result<()> {
        let tick = scene.tick() + 1;
        let deadline = Instant::now() + TICK_TIMEOUT;
        while !self.pending.contains_key(&tick) {
            let left = deadline.saturating_duration_since(Instant::now());
            match self.inputs.recv_timeout(left) {
                Ok(bytes) => self
                    .take(&bytes)
                    .map_err(|e| troupe_scene::Error::Invalid(format!("tick {tick}: {e}")))?,
                Err(_) => {
                    let mut report = self.report.lock().expect("report lock");
                    report.missing_inputs.get_or_insert(tick);
                    return Err(troupe_scene::Error::Invalid(format!(
                        "no inputs from the leader for tick {tick} within {} s",
                        TICK_TIMEOUT.as_secs_f64()
                    )));
                }
            }
        }
        let chunks = self.pending.remove(&tick).unwrap_or_default();
        // Older ticks can only be repeats; drop them.
        self.pending.retain(|t, _| *t > tick);
        if let Some(replay) = &mut self.replay {
            replay(&chunks).map_err(|e| {
                troupe_scene::Error::Invalid(format!("the leader's inputs of tick {tick}: {e}"))
            })?;
        }
        Ok(())
    }
}

/// Compares each tick's postures with the leader's (an [`Observer`]); the run fails at
/// its end if any differ, naming the first tick, actor and DOF.
pub struct FollowCheck {
    prefix: String,
    _session: Session,
    poses: PoseFeed,
    /// Leader postures received and not yet compared, by (actor, tick).
    leader: HashMap<(String, u64), Posture>,
    report: Arc<Mutex<Report>>,
}

impl FollowCheck {
    /// The leader's posture of `actor` at `tick`, waiting for it up to the tick timeout.
    fn leader_posture(&mut self, actor: &str, tick: u64) -> Option<Posture> {
        let key = (actor.to_string(), tick);
        let deadline = Instant::now() + TICK_TIMEOUT;
        while !self.leader.contains_key(&key) {
            let left = deadline.saturating_duration_since(Instant::now());
            let Ok(m) = self.poses.received().recv_timeout(left) else {
                return None;
            };
            if let Ok(p) = m.posture {
                // Postures of ticks already compared are late repeats.
                if p.tick >= tick {
                    self.leader.insert((m.actor, p.tick), p);
                }
            }
        }
        self.leader.remove(&key)
    }
}

impl Observer for FollowCheck {
    fn name(&self) -> String {
        format!("--zenoh-follow {}", self.prefix)
    }

    fn publish(&mut self, scene: &Scene, _events: &[Event]) -> troupe_scene::Result<()> {
        let tick = scene.tick();
        for (info, state) in scene.actors().iter().zip(scene.states()) {
            let theirs = self.leader_posture(&info.name, tick);
            let mut report = self.report.lock().expect("report lock");
            let Some(theirs) = theirs else {
                report.unchecked += 1;
                continue;
            };
            report.compared += 1;
            if report.first_difference.is_some() {
                continue;
            }
            let differs = theirs.values.len() != state.q.len()
                || theirs
                    .values
                    .iter()
                    .zip(&state.q)
                    .any(|(a, b)| a.to_bits() != b.to_bits());
            if differs {
                let d = (0..state.q.len())
                    .find(|&d| {
                        theirs.values.get(d).map(|v| v.to_bits()) != Some(state.q[d].to_bits())
                    })
                    .unwrap_or(0);
                let leader = theirs.values.get(d).copied().unwrap_or(f64::NAN);
                report.first_difference = Some((tick, info.name.clone(), d, leader, state.q[d]));
            }
        }
        Ok(())
    }

    fn finish(&mut self, scene: &Scene) -> troupe_scene::Result<Option<String>> {
        let report = self.report.lock().expect("report lock");
        if let Some((tick, actor, d, leader, own)) = &report.first_difference {
            let dof = scene
                .actors()
                .iter()
                .find(|a| &a.name == actor)
                .and_then(|a| a.skeleton.dofs().get(*d))
                .map_or("?", |dof| dof.name.as_str());
            return Err(troupe_scene::Error::Invalid(format!(
                "postures differ from the leader first at tick {tick}: {actor} {dof} is {own:?} here, {leader:?} on the leader"
            )));
        }
        if let Some(tick) = report.missing_inputs {
            return Err(troupe_scene::Error::Invalid(format!(
                "the leader's inputs stopped at tick {tick}; compared {} postures before",
                report.compared
            )));
        }
        let mut line = format!(
            "followed {}: {} postures compared, all equal to the leader's bit for bit",
            self.prefix, report.compared
        );
        if report.unchecked > 0 {
            line += &format!(
                " ({} never arrived and were not compared)",
                report.unchecked
            );
        }
        Ok(Some(line))
    }
}
