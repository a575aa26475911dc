//! Where a performer's device samples come from: a live driver thread, a recording replayed
//! by scene time, or values fed from elsewhere; and the three inputs a performer has
//! (a Flock of Birds, OSC poses, a glove), each with what it last received.

use crate::cyberglove::calibration::GloveCalibration;
use crate::device::health::HealthReport;
use crate::device::reading::Reading;
use crate::device::thread::DeviceHandle;
use crate::gesture::GestureTracker;
use crate::osc::listener::OscListener;
use crate::performer::converter::AnatomicalConverter;
use crate::performer::glove_map::GloveMap;
use crate::record::error::RecordError;
use crate::record::feed::{DeviceReplay, SharedFeed, StreamFeed};
use crate::record::file::Recording;
use glam::{DQuat, DVec3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;
use troupe_body::sensors::Side;

/// A recording that cannot feed a device.
#[derive(Debug, thiserror::Error)]
pub enum SourceError {
    /// The recording cannot be read or decoded.
    #[error(transparent)]
    Recording(#[from] RecordError),
    /// No stream of the device's kind, or several and none named.
    #[error("{} has no single '{kind}' stream (name one with stream=…)", path.display())]
    NoStream {
        /// The recording.
        path: PathBuf,
        /// The device kind.
        kind: String,
    },
}

/// Where a device's samples come from.
pub(crate) enum Source {
    /// A live driver thread, opened `opened` ticks into the scene.
    Live { handle: DeviceHandle, opened: u64 },
    /// A recorded stream (a file, or a leader's), delivered at the recorded run's ticks
    /// (tick marks) or else by scene time from `start` on (deterministic either way).
    Replay {
        feed: SharedFeed,
        opened: u64,
        start: f64,
    },
    /// Fed from elsewhere (a glove whose values come over OSC).
    External,
}

/// The scene's time and tick as the script sees them now (`troupe.time()`,
/// `troupe.tick()`): when a device opens.
pub(crate) fn scene_clock(lua: &mlua::Lua) -> mlua::Result<(f64, u64)> {
    let troupe = lua.globals().get::<mlua::Table>("troupe")?;
    let call = |name: &str| -> mlua::Result<Option<mlua::Value>> {
        troupe
            .get::<Option<mlua::Function>>(name)?
            .map(|f| f.call(()))
            .transpose()
    };
    let time = call("time")?.and_then(|v| v.as_f64()).unwrap_or(0.0);
    let tick = call("tick")?.and_then(|v| v.as_u64()).unwrap_or(0);
    Ok((time, tick))
}

impl Source {
    /// The stream of `kind` (or the one named `stream`) of the recording at `path`,
    /// delivered from now (`time`, `tick`) on.
    pub(crate) fn replay(
        path: &Path,
        stream: Option<&str>,
        kind: &str,
        (time, tick): (f64, u64),
    ) -> Result<Source, SourceError> {
        let rec = Recording::read(path)?;
        let s = rec
            .find(stream.unwrap_or(kind))
            .ok_or_else(|| SourceError::NoStream {
                path: path.to_path_buf(),
                kind: kind.to_string(),
            })?;
        Ok(Source::Replay {
            feed: Arc::new(Mutex::new(StreamFeed::from_recording(&rec, s)?)),
            opened: tick,
            start: time,
        })
    }

    /// The device named `name` read from a replay of the whole run's inputs
    /// (`--replay-devices`, `--zenoh-follow`) in place of its port.
    pub(crate) fn replayed(
        replay: &DeviceReplay,
        name: &str,
        (time, tick): (f64, u64),
    ) -> Result<Source, String> {
        Ok(Source::Replay {
            feed: replay.stream(name)?,
            opened: tick,
            start: time,
        })
    }

    /// Readings due before the tick after `tick` at scene time `time`, with the instant
    /// they arrived (live only).
    pub(crate) fn take(&mut self, tick: u64, time: f64) -> Vec<(Reading, Option<Instant>)> {
        match self {
            Source::Live { handle, opened } => handle
                .drain_at_tick(tick.saturating_sub(*opened))
                .into_iter()
                .map(|s| (s.reading, Some(s.arrived)))
                .collect(),
            Source::Replay {
                feed,
                opened,
                start,
            } => match feed.lock() {
                Ok(mut f) => f
                    .take(tick.saturating_sub(*opened), time - *start)
                    .into_iter()
                    .map(|r| (r, None))
                    .collect(),
                Err(_) => Vec::new(),
            },
            Source::External => Vec::new(),
        }
    }

    /// What a replay's decoder could not use so far: (messages or records, their bytes);
    /// zero for a live device (its health has them) or an external feed.
    pub(crate) fn decode_counters(&self) -> (u64, u64) {
        match self {
            Source::Replay { feed, .. } => feed.lock().map(|f| f.counters()).unwrap_or_default(),
            Source::Live { .. } | Source::External => (0, 0),
        }
    }

    /// The device's health; `None` for a replay or an external feed.
    pub(crate) fn health(&self) -> Option<HealthReport> {
        match self {
            Source::Live { handle, .. } => Some(handle.health.report()),
            Source::Replay { .. } | Source::External => None,
        }
    }
}

/// A Flock of Birds on a performer: its samples and the converter they go through.
pub(crate) struct FobInput {
    /// Where the birds' records come from.
    pub(crate) source: Source,
    /// Bird poses to joint rotations.
    pub(crate) converter: AnatomicalConverter,
    /// The latest pose of each bird, by address.
    pub(crate) latest: BTreeMap<u8, (DVec3, DQuat)>,
}

/// Segment poses sent over OSC, through a converter without sensor offsets.
pub(crate) struct OscPoses {
    /// The UDP listener.
    pub(crate) listener: OscListener,
    /// Segment poses to joint rotations.
    pub(crate) converter: AnatomicalConverter,
    /// Joint name (as sent) → the converter's pseudo-address.
    pub(crate) joints: Vec<(String, u8)>,
    /// The latest pose of each joint, by pseudo-address.
    pub(crate) latest: BTreeMap<u8, (DVec3, DQuat)>,
}

/// A CyberGlove on a performer's hand.
pub(crate) struct GloveInput {
    /// Where the glove's records come from.
    pub(crate) source: Source,
    /// Raw values to angles.
    pub(crate) calibration: GloveCalibration,
    /// Angles to the hand's DOFs.
    pub(crate) map: GloveMap,
    /// The latest raw values.
    pub(crate) latest: Option<Vec<u8>>,
    /// Gesture recognition, once trained.
    pub(crate) gestures: Option<GestureTracker>,
    /// The gloved hand.
    pub(crate) side: Side,
}
