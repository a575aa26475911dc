//! Per-user glove calibration: raw sensor bytes to joint angles, fitted from two poses and
//! kept as JSON.

use crate::cyberglove::decoder::sensor_names;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A calibration that cannot be fitted, read or written.
#[derive(Debug, thiserror::Error)]
pub enum CalibrationError {
    /// The two poses and their angles do not have one value per sensor each.
    #[error("calibration poses disagree on the sensor count ({}, {}, {}, {})", .0[0], .0[1], .0[2], .0[3])]
    PoseLengths([usize; 4]),
    /// A sensor reads the same in both poses.
    #[error("sensor {index} ({name}) reads {raw} in both calibration poses; is it connected?")]
    Unmoved {
        /// Sensor index in wire order.
        index: usize,
        /// Sensor name.
        name: &'static str,
        /// The reading of both poses.
        raw: u8,
    },
    /// The calibration could not be encoded as JSON.
    #[error("{0}")]
    Encode(#[source] serde_json::Error),
    /// The file could not be written.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// The file could not be read.
    #[error("reading {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a calibration's JSON.
    #[error("{}: not a glove calibration: {source}", path.display())]
    NotACalibration {
        /// The file.
        path: PathBuf,
        /// What the JSON parser said (with line and column).
        #[source]
        source: serde_json::Error,
    },
    /// The file's lists disagree in length.
    #[error("{}: {sensors} sensors but {gains} gains and {offsets} offsets", path.display())]
    Lists {
        /// The file.
        path: PathBuf,
        /// Sensor names.
        sensors: usize,
        /// Gains.
        gains: usize,
        /// Offsets.
        offsets: usize,
    },
}

/// Per-sensor linear calibration: angle (radians) = gain × (raw − offset).
///
/// Reference: "Raw bytes become angles through a per-user calibration (gain and offset per
/// sensor, taken from a flat hand and a fist, or similar poses)". Thesis 6.4.1: each
/// performer calibrates before a session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GloveCalibration {
    /// Sensor names, in wire order.
    pub sensors: Vec<String>,
    /// Gain per sensor, radians per raw unit.
    pub gain: Vec<f64>,
    /// Raw value per sensor that maps to angle zero.
    pub offset: Vec<f64>,
}

impl GloveCalibration {
    /// The identity-like calibration: every sensor linear over 1…255 → 0…π/2.
    pub fn nominal(sensors: usize) -> GloveCalibration {
        GloveCalibration {
            sensors: sensor_names(sensors)
                .into_iter()
                .map(String::from)
                .collect(),
            gain: vec![std::f64::consts::FRAC_PI_2 / 254.0; sensors],
            offset: vec![1.0; sensors],
        }
    }

    /// Fits gain and offset from two poses: raw values of a flat hand (angle `flat_angles`)
    /// and of a fist (angle `fist_angles`), per sensor. A sensor that reads the same in both
    /// poses cannot be calibrated and is an error naming it.
    pub fn from_poses(
        flat: &[u8],
        fist: &[u8],
        flat_angles: &[f64],
        fist_angles: &[f64],
    ) -> Result<GloveCalibration, CalibrationError> {
        let n = flat.len();
        if fist.len() != n || flat_angles.len() != n || fist_angles.len() != n {
            return Err(CalibrationError::PoseLengths([
                n,
                fist.len(),
                flat_angles.len(),
                fist_angles.len(),
            ]));
        }
        let names = sensor_names(n);
        let mut gain = Vec::with_capacity(n);
        let mut offset = Vec::with_capacity(n);
        for i in 0..n {
            let (r0, r1) = (f64::from(flat[i]), f64::from(fist[i]));
            let (a0, a1) = (flat_angles[i], fist_angles[i]);
            if (a1 - a0).abs() < 1e-12 {
                // Sensor not exercised by these poses (e.g. the wrist between a flat hand
                // and a fist): nominal gain, zero at the flat reading.
                let g = std::f64::consts::FRAC_PI_2 / 254.0;
                gain.push(g);
                offset.push(r0 - a0 / g);
                continue;
            }
            if r0 == r1 {
                return Err(CalibrationError::Unmoved {
                    index: i,
                    name: names.get(i).copied().unwrap_or("?"),
                    raw: flat[i],
                });
            }
            let g = (a1 - a0) / (r1 - r0);
            gain.push(g);
            offset.push(r0 - a0 / g);
        }
        Ok(GloveCalibration {
            sensors: names.into_iter().map(String::from).collect(),
            gain,
            offset,
        })
    }

    /// Angles in radians for a record's raw values.
    pub fn angles(&self, raw: &[u8]) -> Vec<f64> {
        raw.iter()
            .zip(self.gain.iter().zip(&self.offset))
            .map(|(&r, (&g, &o))| g * (f64::from(r) - o))
            .collect()
    }

    /// Saves as JSON.
    pub fn save(&self, path: &Path) -> Result<(), CalibrationError> {
        let text = serde_json::to_string_pretty(self).map_err(CalibrationError::Encode)?;
        std::fs::write(path, text).map_err(|source| CalibrationError::Write {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Loads a JSON calibration; checks that the three lists agree.
    pub fn load(path: &Path) -> Result<GloveCalibration, CalibrationError> {
        let text = std::fs::read_to_string(path).map_err(|source| CalibrationError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let c: GloveCalibration =
            serde_json::from_str(&text).map_err(|source| CalibrationError::NotACalibration {
                path: path.to_path_buf(),
                source,
            })?;
        if c.gain.len() != c.sensors.len() || c.offset.len() != c.sensors.len() {
            return Err(CalibrationError::Lists {
                path: path.to_path_buf(),
                sensors: c.sensors.len(),
                gains: c.gain.len(),
                offsets: c.offset.len(),
            });
        }
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn calibration_from_flat_and_fist() {
        let flat = [20u8, 40];
        let fist = [220u8, 240];
        let c = GloveCalibration::from_poses(&flat, &fist, &[0.0, 0.0], &[1.5, 1.0]).unwrap();
        let a = c.angles(&[120, 240]);
        assert!((a[0] - 0.75).abs() < 1e-12 && (a[1] - 1.0).abs() < 1e-12);
        let err =
            GloveCalibration::from_poses(&[5, 5], &[5, 9], &[0.0, 0.0], &[1.0, 1.0]).unwrap_err();
        assert!(err.to_string().contains("thumb_rotation"), "{err}");
        let dir = std::env::temp_dir().join(format!("troupe-cal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("cal.json");
        c.save(&p).unwrap();
        assert_eq!(GloveCalibration::load(&p).unwrap(), c);
        std::fs::write(&p, "{}").unwrap();
        assert!(GloveCalibration::load(&p)
            .unwrap_err()
            .to_string()
            .contains("not a glove calibration"));
    }
}
