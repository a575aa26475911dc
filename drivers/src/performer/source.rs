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
use crate::record::file::Recording;
use glam::{DQuat, DVec3};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
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
    /// A live driver thread.
    Live(DeviceHandle),
    /// A recording, delivered by scene time (deterministic).
    Replay {
        readings: Vec<(f64, Reading)>,
        next: usize,
        start: f64,
    },
    /// Fed from elsewhere (a glove whose values come over OSC).
    External,
}

impl Source {
    /// The stream of `kind` (or the one named `stream`) of the recording at `path`,
    /// delivered by scene time from `scene_time` on.
    pub(crate) fn replay(
        path: &Path,
        stream: Option<&str>,
        kind: &str,
        scene_time: f64,
    ) -> Result<Source, SourceError> {
        let rec = Recording::read(path)?;
        let s = rec
            .find(stream.unwrap_or(kind))
            .ok_or_else(|| SourceError::NoStream {
                path: path.to_path_buf(),
                kind: kind.to_string(),
            })?;
        Ok(Source::Replay {
            readings: rec.readings(s)?,
            next: 0,
            start: scene_time,
        })
    }

    /// Readings due now, with the instant they arrived (live only).
    pub(crate) fn take(&mut self, scene_time: f64) -> Vec<(Reading, Option<Instant>)> {
        match self {
            Source::Live(h) => h
                .drain()
                .into_iter()
                .map(|s| (s.reading, Some(s.arrived)))
                .collect(),
            Source::Replay {
                readings,
                next,
                start,
            } => {
                let t0 = readings.first().map(|r| r.0).unwrap_or(0.0);
                let mut out = Vec::new();
                while *next < readings.len() && readings[*next].0 - t0 <= scene_time - *start + 1e-9
                {
                    out.push((readings[*next].1.clone(), None));
                    *next += 1;
                }
                out
            }
            Source::External => Vec::new(),
        }
    }

    /// The device's health; `None` for a replay or an external feed.
    pub(crate) fn health(&self) -> Option<HealthReport> {
        match self {
            Source::Live(h) => Some(h.health.report()),
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
