//! What an emulator's devices do: a built-in synthetic motion, a BVH file's joints, or the
//! readings of a `.rec` recording, looped.

use crate::device::reading::Reading;
use crate::emulator::error::MotionError;
use crate::fob::decoder::BirdRecord;
use crate::fob::pose::{angles_to_quat, bird_pose};
use crate::record::file::Recording;
use glam::{DQuat, DVec3};
use std::path::Path;

/// Where an emulator's motion comes from.
pub enum Motion {
    /// Smooth built-in motion: each bird on its own slow orbit and rotation; glove fingers
    /// opening and closing in a wave.
    Synthetic,
    /// A BVH file: bird `i` follows joint `joints[i]`, positions scaled to metres.
    Bvh {
        /// The motion.
        bvh: Box<troupe_formats::bvh::Bvh>,
        /// Joint index per bird.
        joints: Vec<usize>,
        /// File units to metres.
        scale: f64,
    },
    /// Readings decoded from a recording, looped.
    Recorded {
        /// (time, reading) in recording order.
        readings: Vec<(f64, Reading)>,
    },
}

impl Motion {
    /// Loads a BVH or `.rec` file by extension; `joints` names the BVH joint of each bird
    /// (empty: the first joints of the hierarchy); `kind` picks the recorded stream
    /// (`fob` or `cyberglove`).
    pub fn from_file(
        path: &Path,
        kind: &str,
        joints: &[String],
        birds: usize,
        scale: f64,
    ) -> Result<Motion, MotionError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        match ext.as_str() {
            "bvh" => {
                let bvh = troupe_formats::bvh::read_bvh(path)?;
                let idx: Vec<usize> = if joints.is_empty() {
                    (0..birds.min(bvh.joints().len())).collect()
                } else {
                    joints
                        .iter()
                        .map(|j| {
                            bvh.joint(j).ok_or_else(|| MotionError::NoJoint {
                                path: path.to_path_buf(),
                                joint: j.clone(),
                            })
                        })
                        .collect::<Result<_, _>>()?
                };
                if idx.len() < birds {
                    return Err(MotionError::TooFewJoints {
                        path: path.to_path_buf(),
                        joints: idx.len(),
                        birds,
                    });
                }
                Ok(Motion::Bvh {
                    bvh: Box::new(bvh),
                    joints: idx,
                    scale,
                })
            }
            "rec" => {
                let rec = Recording::read(path)?;
                let s = rec.find(kind).ok_or_else(|| MotionError::NoStream {
                    path: path.to_path_buf(),
                    kind: kind.to_string(),
                })?;
                let readings = rec.readings(s)?;
                if readings.is_empty() {
                    return Err(MotionError::EmptyStream {
                        path: path.to_path_buf(),
                        kind: kind.to_string(),
                    });
                }
                Ok(Motion::Recorded { readings })
            }
            _ => Err(MotionError::Extension(path.to_path_buf())),
        }
    }

    /// Position (metres) and orientation of bird `i` (0-based) at time `t`.
    pub fn bird(&self, t: f64, i: usize) -> (DVec3, DQuat) {
        match self {
            Motion::Synthetic => synthetic_bird(t, i),
            Motion::Bvh { bvh, joints, scale } => {
                let frames = bvh.frame_count().max(1);
                let k = ((t / bvh.frame_time().max(1e-6)) as usize) % frames;
                let mut g = vec![troupe_body::transform::Transform::IDENTITY; bvh.joints().len()];
                bvh.global_transforms(k, &mut g);
                let tr = g[joints[i.min(joints.len() - 1)]];
                (tr.translation * *scale, tr.rotation)
            }
            Motion::Recorded { readings } => {
                let birds: Vec<&BirdRecord> = readings
                    .iter()
                    .filter_map(|(_, r)| match r {
                        Reading::Bird(b)
                            if usize::from(b.address) == i + 1 || (b.address == 1 && i == 0) =>
                        {
                            Some(b)
                        }
                        _ => None,
                    })
                    .collect();
                let times: Vec<f64> = readings
                    .iter()
                    .filter(
                        |(_, r)| matches!(r, Reading::Bird(b) if usize::from(b.address) == i + 1),
                    )
                    .map(|(t, _)| *t)
                    .collect();
                match pick(&times, t) {
                    Some(k) => bird_pose(birds[k]),
                    None => synthetic_bird(0.0, i),
                }
            }
        }
    }

    /// Raw glove values (1…255) for `sensors` sensors at time `t`.
    pub fn glove(&self, t: f64, sensors: usize) -> Vec<u8> {
        match self {
            Motion::Recorded { readings } => {
                let gloves: Vec<(f64, &Vec<u8>)> = readings
                    .iter()
                    .filter_map(|(tt, r)| match r {
                        Reading::Glove(g) => Some((*tt, &g.raw)),
                        _ => None,
                    })
                    .collect();
                let times: Vec<f64> = gloves.iter().map(|g| g.0).collect();
                match pick(&times, t) {
                    Some(k) => {
                        let mut v = gloves[k].1.clone();
                        v.resize(sensors, 128);
                        v
                    }
                    None => synthetic_glove(t, sensors),
                }
            }
            _ => synthetic_glove(t, sensors),
        }
    }
}

/// Index of the latest time ≤ `t` modulo the duration (loops the recording).
fn pick(times: &[f64], t: f64) -> Option<usize> {
    let (first, last) = (*times.first()?, *times.last()?);
    let span = (last - first).max(1e-3);
    let tt = first + (t % (span + 0.01)).min(span);
    Some(times.partition_point(|&x| x <= tt).saturating_sub(1))
}

fn synthetic_bird(t: f64, i: usize) -> (DVec3, DQuat) {
    let f = i as f64;
    let p = DVec3::new(
        0.3 + 0.05 * f + 0.1 * (0.9 * t + f).sin(),
        0.2 * (0.7 * t + 0.5 * f).sin(),
        -0.1 + 0.08 * (1.1 * t + f).cos(),
    );
    let a = [
        40.0 * (0.5 * t + f).sin(),
        25.0 * (0.8 * t).sin(),
        15.0 * (0.3 * t + f).cos(),
    ];
    (p, angles_to_quat(a))
}

fn synthetic_glove(t: f64, sensors: usize) -> Vec<u8> {
    (0..sensors)
        .map(|k| {
            let phase = 0.25 * k as f64;
            (1.0 + 254.0 * (0.5 - 0.5 * (1.5 * t + phase).cos()))
                .round()
                .clamp(1.0, 255.0) as u8
        })
        .collect()
}
