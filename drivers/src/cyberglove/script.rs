//! A scripted CyberGlove performance without hardware: a `.rec` recording of a glove that
//! opens and closes along given keys, for tests, benchmarks and examples.

use super::decoder::{sensor_names, GloveLayout};
use super::protocol::GloveConfig;
use crate::device::protocol::Mode;
use crate::record::error::RecordError;
use crate::record::writer::Recorder;

/// A glove script that cannot be written.
#[derive(Debug, thiserror::Error)]
pub enum GloveScriptError {
    /// Neither 18 nor 22 sensors.
    #[error("glove script: sensors must be 18 or 22, got {0}")]
    Sensors(usize),
    /// A rate that is not a positive number.
    #[error("glove script: rate must be > 0 Hz, got {0}")]
    Rate(f64),
    /// No keys, or times that do not increase.
    #[error("glove script: keys must be non-empty with increasing times")]
    Times,
    /// A key with a non-finite time or a closure outside 0…1.
    #[error("glove script: key ({time}, {closure}) needs a finite time and a closure in 0…1")]
    Key {
        /// The key's time (s).
        time: f64,
        /// The key's closure.
        closure: f64,
    },
    /// The glove settings could not be encoded.
    #[error("{0}")]
    Settings(#[from] serde_json::Error),
    /// The recording could not be written.
    #[error(transparent)]
    Record(#[from] RecordError),
}

/// Writes a `.rec` file with one 18- or 22-sensor CyberGlove stream (streaming mode) that
/// opens and closes the hand along `keys`: (seconds, closure 0…1) pairs, interpolated
/// linearly, sampled at `rate` Hz. Every finger and thumb sensor reads `1 + 254·closure`
/// (0 to the DOF's upper limit through the nominal calibration); the wrist sensors stay
/// at 1 (wrist straight). A glove performance without hardware, for tests and examples.
pub fn write_glove_script(
    path: &std::path::Path,
    sensors: usize,
    rate: f64,
    keys: &[(f64, f64)],
) -> Result<(), GloveScriptError> {
    if sensors != 18 && sensors != 22 {
        return Err(GloveScriptError::Sensors(sensors));
    }
    if !(rate.is_finite() && rate > 0.0) {
        return Err(GloveScriptError::Rate(rate));
    }
    if keys.is_empty() || keys.windows(2).any(|w| w[1].0 <= w[0].0) {
        return Err(GloveScriptError::Times);
    }
    if let Some(&(time, closure)) = keys
        .iter()
        .find(|k| !(k.0.is_finite() && (0.0..=1.0).contains(&k.1)))
    {
        return Err(GloveScriptError::Key { time, closure });
    }
    let config = GloveConfig {
        layout: GloveLayout {
            sensors,
            status_byte: false,
        },
        mode: Mode::Stream,
    };
    let settings = serde_json::to_value(config)?;
    let rec = Recorder::create(path)?;
    let stream = rec.add_stream("performer.glove", "cyberglove", settings);
    let names = sensor_names(sensors);
    let closure = |t: f64| {
        let i = keys.partition_point(|k| k.0 <= t);
        match i {
            0 => keys[0].1,
            i if i == keys.len() => keys[i - 1].1,
            i => {
                let (a, b) = (keys[i - 1], keys[i]);
                a.1 + (b.1 - a.1) * (t - a.0) / (b.0 - a.0)
            }
        }
    };
    let end = keys[keys.len() - 1].0;
    let count = (end * rate).round() as u64;
    for i in 0..=count {
        let t = i as f64 / rate;
        let k = closure(t);
        let mut bytes = vec![b'S'];
        for n in &names {
            let v = if n.starts_with("wrist") {
                1
            } else {
                (1.0 + 254.0 * k).round() as u8
            };
            bytes.push(v);
        }
        bytes.push(0);
        rec.data_at(stream, (t * 1e6).round() as u64, &bytes);
    }
    Ok(rec.finish()?)
}
