//! VMC into a performer: datagrams from a live listener (a UDP port or a relay's key), a
//! replay of the whole run's inputs (`--replay-devices`, `--zenoh-follow`) or a `.rec`
//! file are read into poses, wait in the jitter buffer, and play out as the performer's
//! posture, retargeted through the T-pose onto the actor.
//!
//! A live input notes in the recording which datagrams each tick took (tick marks) and
//! the receiver clock it played the buffer at (clock marks); a replay of the whole run
//! takes the same datagrams at the same ticks and plays at the same clock, so its
//! postures are the live run's bit for bit.

use crate::device::health::HealthReport;
use crate::device::reading::Reading;
use crate::record::error::RecordError;
use crate::record::feed::SharedFeed;
use crate::record::file::Recording;
use crate::vmc::jitter::{JitterBuffer, Playout};
use crate::vmc::listener::{VmcListener, REC_KIND};
use crate::vmc::message::{read_datagram, VmcCounters};
use crate::vmc::rig::VmcRig;
use crate::vmc::stream::clock_seconds;
use std::path::Path;
use troupe_body::transform::Transform;

/// Where a performer's VMC datagrams come from.
pub enum VmcSource {
    /// A listener (UDP or a relay's key), made `opened` ticks into the scene.
    Live {
        /// The listener thread.
        listener: VmcListener,
        /// The tick the performer was made at.
        opened: u64,
    },
    /// A recording's datagrams `(seconds, bytes)`, delivered by scene time (`replay =`).
    Replay {
        /// The datagrams in recorded order.
        datagrams: Vec<(f64, Vec<u8>)>,
        /// The next to deliver.
        next: usize,
        /// The scene time the replay started.
        start: f64,
    },
    /// The stream of this performer in a replay of the whole run's inputs: datagrams at
    /// the ticks the recorded run took them, played at its clock (by scene time from
    /// `start` when the recording has no marks).
    Replayed {
        /// The stream's feed.
        feed: SharedFeed,
        /// The tick the performer was made at.
        opened: u64,
        /// The scene time it was made at.
        start: f64,
    },
}

/// A `.rec` without a VMC stream to replay.
#[derive(Debug, thiserror::Error)]
pub enum VmcReplayError {
    /// The recording cannot be read.
    #[error(transparent)]
    Recording(#[from] RecordError),
    /// No stream of kind `vmc`, or several and none named.
    #[error("{path} has no single 'vmc' stream (name one with stream=…)")]
    NoStream {
        /// The file.
        path: String,
    },
}

impl VmcSource {
    /// The VMC stream (the one named `stream`, or the only one) of the recording at
    /// `path`, delivered from scene time `scene_time` on.
    pub fn replay(
        path: &Path,
        stream: Option<&str>,
        scene_time: f64,
    ) -> Result<VmcSource, VmcReplayError> {
        let rec = Recording::read(path)?;
        let s = rec
            .find(stream.unwrap_or(REC_KIND))
            .filter(|&s| rec.streams[s].kind == REC_KIND)
            .ok_or_else(|| VmcReplayError::NoStream {
                path: path.display().to_string(),
            })?;
        let datagrams = rec
            .chunks
            .into_iter()
            .filter(|c| usize::from(c.stream) == s)
            .map(|c| (c.micros as f64 * 1e-6, c.bytes))
            .collect();
        Ok(VmcSource::Replay {
            datagrams,
            next: 0,
            start: scene_time,
        })
    }
}

/// A performer's VMC input.
pub struct VmcInput {
    /// Where datagrams come from.
    pub source: VmcSource,
    /// The template's VRM bones.
    pub rig: VmcRig,
    /// The sender's world in the scene: the performer's place and facing.
    pub place: Transform,
    /// Frames waiting to play.
    pub buffer: JitterBuffer,
    /// What could not be used.
    pub counters: VmcCounters,
    /// The sender's `/VMC/Ext/T` of the pose last played.
    pub source_time: Option<f64>,
    /// The last played pose retargeted: target DOF values and which are set.
    pub target: Option<(Vec<f64>, Vec<bool>)>,
}

impl VmcInput {
    /// An input from `source` onto `rig`'s actor, placed at `place`, delaying frames by
    /// `latency` seconds.
    pub fn new(source: VmcSource, rig: VmcRig, place: Transform, latency: f64) -> VmcInput {
        VmcInput {
            source,
            rig,
            place,
            buffer: JitterBuffer::new(latency),
            counters: VmcCounters::default(),
            source_time: None,
            target: None,
        }
    }

    /// The listener's health, with every refused datagram or message counted as a resync
    /// (what `troupe run` prints); `None` for a replay.
    pub fn health(&self) -> Option<HealthReport> {
        match &self.source {
            VmcSource::Live { listener, .. } => {
                let mut h = listener.health.report();
                let c = &self.counters;
                h.resyncs += c.malformed + c.unknown + c.invalid + c.unknown_bones;
                Some(h)
            }
            VmcSource::Replay { .. } | VmcSource::Replayed { .. } => None,
        }
    }

    /// Reads what arrived, and plays the buffer at `tick` (scene time `scene_time`) onto
    /// the actor whose posture is `q`: returns the played frame when there is one (its
    /// arrival instant for the latency measurement); the retargeted pose is in `target`.
    pub fn poll(&mut self, tick: u64, scene_time: f64, q: &[f64]) -> Option<Playout> {
        let now = match &mut self.source {
            VmcSource::Live { listener, opened } => {
                let ticks = tick.saturating_sub(*opened);
                for d in listener.drain_at_tick(ticks) {
                    let p = read_datagram(&d.bytes, &mut self.counters);
                    let arrival = clock_seconds(d.micros);
                    self.buffer.push(arrival, p.time, &p.pose, Some(d.arrived));
                }
                clock_seconds(listener.clock_at_tick(ticks))
            }
            VmcSource::Replay {
                datagrams,
                next,
                start,
            } => {
                let t0 = datagrams.first().map(|d| d.0).unwrap_or(0.0);
                let now = t0 + (scene_time - *start);
                while *next < datagrams.len() && datagrams[*next].0 <= now + 1e-9 {
                    let (at, bytes) = &datagrams[*next];
                    let p = read_datagram(bytes, &mut self.counters);
                    self.buffer.push(*at, p.time, &p.pose, None);
                    *next += 1;
                }
                now
            }
            VmcSource::Replayed {
                feed,
                opened,
                start,
            } => {
                let ticks = tick.saturating_sub(*opened);
                let mut f = feed.lock().ok()?;
                for (at, reading) in f.take_timed(ticks, scene_time - *start) {
                    if let Reading::Datagram { bytes } = reading {
                        let p = read_datagram(&bytes, &mut self.counters);
                        self.buffer.push(at, p.time, &p.pose, None);
                    }
                }
                match f.clock_at(ticks) {
                    Some(micros) => clock_seconds(micros),
                    None => f.first_time().unwrap_or(0.0) + (scene_time - *start),
                }
            }
        };
        let played = self.buffer.play(now)?;
        let mut target = q.to_vec();
        let mut mask = vec![false; q.len()];
        self.rig
            .retarget(&played.pose, &self.place, &mut target, &mut mask);
        self.source_time = played.source_time;
        self.target = Some((target, mask));
        Some(played)
    }

    /// Writes the last retargeted pose's DOFs into `q` and marks them in `mask`.
    pub fn apply(&self, q: &mut [f64], mask: &mut [bool]) {
        if let Some((t, m)) = &self.target {
            for (d, set) in m.iter().enumerate() {
                if *set {
                    q[d] = t[d];
                    mask[d] = true;
                }
            }
        }
    }
}
