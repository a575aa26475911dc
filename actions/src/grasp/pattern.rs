//! Hand motion patterns (thesis 4.3.4): key-framed finger trajectories, one per grasp
//! type, that the fingers follow while closing until their sensors touch.
//!
//! A pattern is a list of tracks; each moves one finger DOF from its value when closing
//! starts to a target over a window `[from, to]` of the pattern's normalized time `s ∈
//! [0, 1]`, eased by `3u² − 2u³`. Every flexion ends at its joint's upper limit (targets
//! above it are clamped), so a finger that touches nothing closes to its limit: after a
//! grasp each finger is either in contact or at its limit.

use super::decision::GraspType;
use troupe_body::math::smoothstep;
use troupe_body::sensors::Side;
use troupe_body::Skeleton;

/// Closes a flexion fully (clamped to the DOF's upper limit).
const FULL: f64 = 180.0;

/// One key-framed DOF of a pattern.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatternTrack {
    /// DOF name without the side prefix (`index1_flexion`).
    pub dof: &'static str,
    /// Normalized time the DOF starts moving.
    pub from: f64,
    /// Normalized time it arrives.
    pub to: f64,
    /// Target value in degrees (clamped to the DOF's limits).
    pub degrees: f64,
}

/// A hand motion pattern: what every finger does while the hand closes.
#[derive(Clone, Debug, PartialEq)]
pub struct HandPattern {
    /// The grasp type it realises.
    pub grasp: GraspType,
    /// Its tracks.
    pub tracks: Vec<PatternTrack>,
}

/// A pattern resolved on a skeleton: DOF indices, start values and clamped targets.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundPattern {
    /// (DOF, from, to, start value, target value) per track.
    pub tracks: Vec<(usize, f64, f64, f64, f64)>,
}

fn t(dof: &'static str, from: f64, to: f64, degrees: f64) -> PatternTrack {
    PatternTrack {
        dof,
        from,
        to,
        degrees,
    }
}

/// The four fingers' flexions closing fully over `[from, to]`, distal joints a little later.
fn fingers(out: &mut Vec<PatternTrack>, names: &[&'static str], from: f64, to: f64) {
    for &f in names {
        let (f0, f1, f2, f3) = match f {
            "index" => (None, "index1_flexion", "index2_flexion", "index3_flexion"),
            "middle" => (
                None,
                "middle1_flexion",
                "middle2_flexion",
                "middle3_flexion",
            ),
            "ring" => (
                Some("ring0_flexion"),
                "ring1_flexion",
                "ring2_flexion",
                "ring3_flexion",
            ),
            _ => (
                Some("pinky0_flexion"),
                "pinky1_flexion",
                "pinky2_flexion",
                "pinky3_flexion",
            ),
        };
        if let Some(f0) = f0 {
            out.push(t(f0, from, to, FULL));
        }
        let lag = 0.15 * (to - from);
        out.push(t(f1, from, to - lag, FULL));
        out.push(t(f2, from + lag, to, FULL));
        out.push(t(f3, from + lag, to, FULL));
    }
}

/// The thumb opposing over `[from, to]` with base abduction `abduction` degrees.
fn thumb(out: &mut Vec<PatternTrack>, abduction: f64, from: f64, to: f64) {
    out.push(t(
        "thumb1_abduction",
        from,
        from + 0.5 * (to - from),
        abduction,
    ));
    out.push(t("thumb1_flexion", from, to, FULL));
    out.push(t("thumb2_flexion", from, to, FULL));
    out.push(t("thumb3_flexion", from, to, FULL));
}

impl HandPattern {
    /// The built-in pattern of a grasp type (figure 4-9 style).
    pub fn builtin(grasp: GraspType) -> HandPattern {
        let mut tracks = Vec::new();
        let all = ["index", "middle", "ring", "pinky"];
        match grasp {
            GraspType::Wrap => {
                thumb(&mut tracks, 60.0, 0.0, 1.0);
                fingers(&mut tracks, &all, 0.0, 1.0);
            }
            GraspType::Pinch => {
                // Ring and pinky fold away first; index and middle meet the thumb.
                fingers(&mut tracks, &["ring", "pinky"], 0.0, 0.5);
                thumb(&mut tracks, 50.0, 0.1, 1.0);
                fingers(&mut tracks, &["index", "middle"], 0.2, 1.0);
            }
            GraspType::Tripod => {
                fingers(&mut tracks, &["ring", "pinky"], 0.0, 0.5);
                tracks.push(t("index1_pivot", 0.0, 0.4, -8.0));
                tracks.push(t("middle1_pivot", 0.0, 0.4, 4.0));
                thumb(&mut tracks, 70.0, 0.0, 1.0);
                fingers(&mut tracks, &["index", "middle"], 0.1, 1.0);
            }
            GraspType::Lateral => {
                // The fingers curl first; the thumb then presses on the index's side.
                fingers(&mut tracks, &all, 0.0, 0.6);
                thumb(&mut tracks, 0.0, 0.5, 1.0);
            }
            GraspType::Disk => {
                // Fingers spread around the rim, then close over it.
                tracks.push(t("index1_pivot", 0.0, 0.3, -15.0));
                tracks.push(t("ring1_pivot", 0.0, 0.3, 10.0));
                tracks.push(t("pinky1_pivot", 0.0, 0.3, 18.0));
                thumb(&mut tracks, 70.0, 0.0, 1.0);
                fingers(&mut tracks, &all, 0.2, 1.0);
            }
        }
        HandPattern { grasp, tracks }
    }

    /// An opening pattern: every finger DOF back to 0 over the whole window.
    pub fn open(skeleton: &Skeleton, side: Side) -> crate::error::Result<BoundPattern> {
        let scope = skeleton.scope(&format!("{}_hand", side.name()))?;
        Ok(BoundPattern {
            tracks: scope.iter().map(|d| (d, 0.0, 1.0, 0.0, 0.0)).collect(),
        })
    }

    /// Resolves the pattern on `side`'s hand of `skeleton`, starting from posture `q`.
    pub fn bind(
        &self,
        skeleton: &Skeleton,
        side: Side,
        q: &[f64],
    ) -> crate::error::Result<BoundPattern> {
        let mut tracks = Vec::with_capacity(self.tracks.len());
        for tr in &self.tracks {
            let name = format!("{}{}", side.prefix(), tr.dof);
            let d = skeleton.dof(&name).map_err(|e| {
                crate::error::ActionError::Unfit(format!("hand pattern {}: {e}", self.grasp.name()))
            })?;
            let dof = &skeleton.dofs()[d];
            let target = dof.clamp(tr.degrees.to_radians());
            tracks.push((d, tr.from, tr.to, q[d], target));
        }
        Ok(BoundPattern { tracks })
    }
}

impl BoundPattern {
    /// Desired values at normalized time `s`, as (DOF, value).
    pub fn sample(&self, s: f64, out: &mut Vec<(usize, f64)>) {
        out.clear();
        for &(d, from, to, start, target) in &self.tracks {
            let u = if to > from {
                ((s - from) / (to - from)).clamp(0.0, 1.0)
            } else if s >= to {
                1.0
            } else {
                0.0
            };
            let e = smoothstep(u);
            out.push((d, start + (target - start) * e));
        }
    }

    /// Restarts every track from the values in `q`.
    pub fn restart_from(&mut self, q: &[f64]) {
        for tr in &mut self.tracks {
            tr.3 = q[tr.0];
        }
    }
}
