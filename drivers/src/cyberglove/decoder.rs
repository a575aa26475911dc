//! CyberGlove (Virtual Technologies): record framing, queries and per-user calibration.
//!
//! Protocol facts come from `shared/reference/devices.md`, section "CyberGlove"; the
//! comments quote the fact they rely on. Thesis 4.7 and 6.4.1 use the glove for the
//! performer's hand and for gestures.

use serde::{Deserialize, Serialize};
use std::path::Path;

/// Poll one record (reference: "`G` polls one record").
pub const CMD_POLL: u8 = b'G';
/// Start streaming (reference: "`S` starts streaming").
pub const CMD_STREAM: u8 = b'S';
/// Stop streaming (reference: "byte 0x03 stops streaming").
pub const CMD_STOP: u8 = 0x03;
/// Query prefix (reference: "Queries `?` + letter").
pub const CMD_QUERY: u8 = b'?';

/// Names of the 22 sensors in wire order (reference: "Sensor order (22-sensor glove)").
pub const SENSORS_22: [&str; 22] = [
    "thumb_rotation",
    "thumb_mpj",
    "thumb_ij",
    "thumb_index_abduction",
    "index_mpj",
    "index_pij",
    "index_dij",
    "middle_mpj",
    "middle_pij",
    "middle_dij",
    "middle_index_abduction",
    "ring_mpj",
    "ring_pij",
    "ring_dij",
    "ring_middle_abduction",
    "pinky_mpj",
    "pinky_pij",
    "pinky_dij",
    "pinky_ring_abduction",
    "palm_arch",
    "wrist_pitch",
    "wrist_yaw",
];

/// Names of the 18 sensors in wire order: the 22-sensor order without the four DIJ
/// sensors (reference: "The 18-sensor glove omits the four DIJ sensors").
pub fn sensor_names(count: usize) -> Vec<&'static str> {
    if count == 22 {
        SENSORS_22.to_vec()
    } else {
        SENSORS_22
            .iter()
            .copied()
            .filter(|n| !n.ends_with("_dij"))
            .take(count)
            .collect()
    }
}

/// How a glove's records are laid out.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct GloveLayout {
    /// Sensors per record: 18 or 22.
    pub sensors: usize,
    /// Whether a status byte follows the sensors (`u 1`).
    pub status_byte: bool,
}

impl GloveLayout {
    /// Bytes per record: command letter, sensors, optional status, terminator
    /// (reference: "An 18-sensor record is 20 bytes").
    pub fn record_bytes(&self) -> usize {
        self.sensors + 2 + usize::from(self.status_byte)
    }
}

/// One glove record: raw sensor values 1…255.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct GloveRecord {
    /// The command letter the record answered (`G` or `S`).
    pub command: u8,
    /// Raw sensor values, in wire order.
    pub raw: Vec<u8>,
    /// The status byte, when enabled.
    pub status: Option<u8>,
}

/// Counters kept by a [`GloveDecoder`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct GloveStats {
    /// Records decoded.
    pub records: u64,
    /// Times framing was lost.
    pub resyncs: u64,
    /// Bytes thrown away.
    pub dropped_bytes: u64,
}

/// Incremental record decoder.
///
/// Framing (reference): "the command letter (`G`, or `S` while streaming), one byte per
/// sensor, optional status byte, then a terminating 0x00 … Sensor bytes never take the value
/// 0". A zero among the sensor bytes means a truncated record; a missing terminator means
/// lost framing. Either way decoding restarts at the byte after the abandoned letter, since
/// a sensor value may equal `G` or `S`.
#[derive(Clone, Debug)]
pub struct GloveDecoder {
    layout: GloveLayout,
    buf: Vec<u8>,
    stats: GloveStats,
}

impl GloveDecoder {
    /// A decoder for the given layout.
    pub fn new(layout: GloveLayout) -> GloveDecoder {
        GloveDecoder {
            layout,
            buf: Vec::with_capacity(32),
            stats: GloveStats::default(),
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> GloveStats {
        self.stats
    }

    /// The layout decoded.
    pub fn layout(&self) -> GloveLayout {
        self.layout
    }

    /// Feeds bytes; calls `out` with each complete record.
    pub fn feed(&mut self, bytes: &[u8], mut out: impl FnMut(GloveRecord)) {
        let n = self.layout.record_bytes();
        for &b in bytes {
            self.buf.push(b);
            loop {
                if self.buf.is_empty() {
                    break;
                }
                if self.buf[0] != CMD_POLL && self.buf[0] != CMD_STREAM {
                    self.buf.remove(0);
                    self.stats.dropped_bytes += 1;
                    continue;
                }
                // Every byte after the letter up to the sensors' end must be non-zero, and
                // a complete record must end with the terminator.
                let len = self.buf.len();
                let data_end = 1 + self.layout.sensors;
                let sensors_so_far = &self.buf[1..len.min(data_end)];
                let bad = sensors_so_far.contains(&0) || (len == n && self.buf[n - 1] != 0);
                if bad {
                    self.stats.resyncs += 1;
                    self.stats.dropped_bytes += 1;
                    self.buf.remove(0);
                    continue;
                }
                if len == n {
                    let raw = self.buf[1..data_end].to_vec();
                    let status = self.layout.status_byte.then(|| self.buf[data_end]);
                    let command = self.buf[0];
                    self.buf.clear();
                    self.stats.records += 1;
                    out(GloveRecord {
                        command,
                        raw,
                        status,
                    });
                }
                break;
            }
        }
    }

    /// Feeds bytes and collects the records.
    pub fn feed_collect(&mut self, bytes: &[u8]) -> Vec<GloveRecord> {
        let mut v = Vec::new();
        self.feed(bytes, |r| v.push(r));
        v
    }
}

/// A query the driver can send, with the payload length of its binary reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    /// `?G`: status byte (bit 0 initialized, bit 1 glove plugged in).
    Status,
    /// `?S`: number of sensors in the hardware.
    SensorsInHardware,
    /// `?N`: number of sensors sampled.
    SensorsSampled,
    /// `?M`: 3-byte sensor mask.
    Mask,
    /// `?R`: right-handed (1) or left (0).
    RightHanded,
    /// `?V`: version text.
    Version,
}

impl Query {
    /// The query letter.
    pub fn letter(self) -> u8 {
        match self {
            Query::Status => b'G',
            Query::SensorsInHardware => b'S',
            Query::SensorsSampled => b'N',
            Query::Mask => b'M',
            Query::RightHanded => b'R',
            Query::Version => b'V',
        }
    }

    /// The bytes to send.
    pub fn command(self) -> [u8; 2] {
        [CMD_QUERY, self.letter()]
    }
}

/// A decoded query reply: `?`, the letter, the payload, a terminating 0x00
/// (reference: "`?G` status (reply `? G st 0`)").
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct QueryReply {
    /// The letter echoed.
    pub letter: u8,
    /// Payload bytes between the letter and the terminator.
    pub payload: Vec<u8>,
}

/// Error replies (reference: "`e?` unknown command, `eg` glove not plugged in, `es`
/// sampling too fast").
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum GloveError {
    /// `e?`
    #[error("the glove did not understand the command (e?)")]
    UnknownCommand,
    /// `eg`
    #[error("the glove is not plugged into its interface unit (eg)")]
    NotPlugged,
    /// `es`
    #[error("sampling too fast for the baud rate (es)")]
    TooFast,
    /// Any other `e` + letter.
    #[error("glove error '{0}'")]
    Other(char),
}

/// Parses an error reply letter.
pub fn error_reply(letter: u8) -> GloveError {
    match letter {
        b'?' => GloveError::UnknownCommand,
        b'g' => GloveError::NotPlugged,
        b's' => GloveError::TooFast,
        c => GloveError::Other(c as char),
    }
}

/// Tries to parse a query reply from the start of `bytes`: returns the reply and the bytes
/// used, `Ok(None)` when more bytes are needed. Fixed-size payloads are read by length
/// (a sensor mask byte may be zero); the version is text up to the terminator.
pub fn parse_query_reply(
    query: Query,
    bytes: &[u8],
) -> Result<Option<(QueryReply, usize)>, String> {
    if bytes.is_empty() {
        return Ok(None);
    }
    if bytes[0] == b'e' {
        return match bytes.get(1) {
            Some(&c) => Err(error_reply(c).to_string()),
            None => Ok(None),
        };
    }
    if bytes[0] != CMD_QUERY {
        return Err(format!(
            "query reply starts with 0x{:02x}, expected '?'",
            bytes[0]
        ));
    }
    let Some(&letter) = bytes.get(1) else {
        return Ok(None);
    };
    if letter != query.letter() {
        return Err(format!(
            "query reply for '{}' answers '{}'",
            query.letter() as char,
            letter as char
        ));
    }
    let fixed = match query {
        Query::Mask => Some(3),
        Query::Version => None,
        _ => Some(1),
    };
    let end = match fixed {
        Some(k) => {
            if bytes.len() < 2 + k + 1 {
                return Ok(None);
            }
            2 + k
        }
        None => match bytes[2..].iter().position(|&b| b == 0) {
            Some(p) => 2 + p,
            None => return Ok(None),
        },
    };
    if bytes[end] != 0 {
        return Err(format!(
            "query reply '{}' is not terminated by 0x00",
            letter as char
        ));
    }
    Ok(Some((
        QueryReply {
            letter,
            payload: bytes[2..end].to_vec(),
        },
        end + 1,
    )))
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
    ) -> Result<GloveCalibration, String> {
        let n = flat.len();
        if fist.len() != n || flat_angles.len() != n || fist_angles.len() != n {
            return Err(format!(
                "calibration poses disagree on the sensor count ({n}, {}, {}, {})",
                fist.len(),
                flat_angles.len(),
                fist_angles.len()
            ));
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
                return Err(format!(
                    "sensor {} ({}) reads {} in both calibration poses; is it connected?",
                    i,
                    names.get(i).copied().unwrap_or("?"),
                    flat[i]
                ));
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
    pub fn save(&self, path: &Path) -> Result<(), String> {
        let text = serde_json::to_string_pretty(self).map_err(|e| e.to_string())?;
        std::fs::write(path, text).map_err(|e| format!("writing {}: {e}", path.display()))
    }

    /// Loads a JSON calibration; checks that the three lists agree.
    pub fn load(path: &Path) -> Result<GloveCalibration, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("reading {}: {e}", path.display()))?;
        let c: GloveCalibration = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a glove calibration: {e}", path.display()))?;
        if c.gain.len() != c.sensors.len() || c.offset.len() != c.sensors.len() {
            return Err(format!(
                "{}: {} sensors but {} gains and {} offsets",
                path.display(),
                c.sensors.len(),
                c.gain.len(),
                c.offset.len()
            ));
        }
        Ok(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(letter: u8, sensors: &[u8], status: Option<u8>) -> Vec<u8> {
        let mut v = vec![letter];
        v.extend_from_slice(sensors);
        v.extend(status);
        v.push(0);
        v
    }

    #[test]
    fn eighteen_sensor_poll_record_is_twenty_bytes() {
        let layout = GloveLayout {
            sensors: 18,
            status_byte: false,
        };
        assert_eq!(layout.record_bytes(), 20);
        let sensors: Vec<u8> = (1..=18).map(|i| i * 10).collect();
        // Built by hand: 'G', 18 values, 0x00.
        let mut bytes = vec![0x47];
        bytes.extend_from_slice(&sensors);
        bytes.push(0x00);
        let recs = GloveDecoder::new(layout).feed_collect(&bytes);
        assert_eq!(
            recs,
            vec![GloveRecord {
                command: b'G',
                raw: sensors,
                status: None
            }]
        );
        assert_eq!(sensor_names(18).len(), 18);
        assert!(!sensor_names(18).contains(&"index_dij"));
        assert_eq!(
            sensor_names(18)[4..7],
            ["index_mpj", "index_pij", "middle_mpj"]
        );
    }

    #[test]
    fn twenty_two_sensors_with_status_stream() {
        let layout = GloveLayout {
            sensors: 22,
            status_byte: true,
        };
        let a: Vec<u8> = (0..22).map(|i| 255 - i).collect();
        let b: Vec<u8> = vec![1; 22];
        let mut bytes = record(b'S', &a, Some(0x03));
        bytes.extend(record(b'S', &b, Some(0x01)));
        let mut d = GloveDecoder::new(layout);
        let mut recs = Vec::new();
        for chunk in bytes.chunks(5) {
            d.feed(chunk, |r| recs.push(r));
        }
        assert_eq!(recs.len(), 2);
        assert_eq!(recs[0].raw, a);
        assert_eq!(recs[0].status, Some(3));
        assert_eq!(recs[1].raw, b);
        assert_eq!(d.stats().resyncs, 0);
    }

    #[test]
    fn truncated_record_and_garbage_resync() {
        let layout = GloveLayout {
            sensors: 18,
            status_byte: false,
        };
        let good: Vec<u8> = vec![100; 18];
        let mut bytes = vec![0x01, 0x02, 0xFF]; // garbage
        bytes.extend_from_slice(&[b'G', 50, 60, 0]); // truncated record
        bytes.extend(record(b'G', &good, None));
        let mut d = GloveDecoder::new(layout);
        let recs = d.feed_collect(&bytes);
        assert_eq!(recs.len(), 1);
        assert_eq!(recs[0].raw, good);
        assert!(d.stats().resyncs >= 1);
        assert_eq!(d.stats().dropped_bytes, 7);
    }

    #[test]
    fn a_sensor_equal_to_the_letter_does_not_confuse_framing() {
        let layout = GloveLayout {
            sensors: 18,
            status_byte: false,
        };
        let mut s = vec![b'G'; 18];
        s[3] = b'S';
        let mut bytes = vec![b'G', 9, 9]; // truncated, followed by a record of 'G' values
        bytes.extend(record(b'G', &s, None));
        let recs = GloveDecoder::new(layout).feed_collect(&bytes);
        assert_eq!(recs.last().map(|r| r.raw.clone()), Some(s));
    }

    #[test]
    fn query_replies() {
        assert_eq!(
            parse_query_reply(Query::Status, &[b'?', b'G', 0x03, 0]).unwrap(),
            Some((
                QueryReply {
                    letter: b'G',
                    payload: vec![3]
                },
                4
            ))
        );
        assert_eq!(
            parse_query_reply(Query::Mask, &[b'?', b'M', 0xFF, 0x00, 0x3F, 0])
                .unwrap()
                .unwrap()
                .0
                .payload,
            vec![0xFF, 0x00, 0x3F]
        );
        assert_eq!(parse_query_reply(Query::Version, b"?V1.2").unwrap(), None);
        assert_eq!(
            parse_query_reply(Query::Version, b"?V1.2\0")
                .unwrap()
                .unwrap()
                .0
                .payload,
            b"1.2".to_vec()
        );
        assert!(parse_query_reply(Query::Status, b"eg")
            .unwrap_err()
            .contains("not plugged"));
        assert!(parse_query_reply(Query::Status, &[b'?', b'S', 18, 0]).is_err());
    }

    #[test]
    fn calibration_from_flat_and_fist() {
        let flat = [20u8, 40];
        let fist = [220u8, 240];
        let c = GloveCalibration::from_poses(&flat, &fist, &[0.0, 0.0], &[1.5, 1.0]).unwrap();
        let a = c.angles(&[120, 240]);
        assert!((a[0] - 0.75).abs() < 1e-12 && (a[1] - 1.0).abs() < 1e-12);
        let err =
            GloveCalibration::from_poses(&[5, 5], &[5, 9], &[0.0, 0.0], &[1.0, 1.0]).unwrap_err();
        assert!(err.contains("thumb_rotation"), "{err}");
        let dir = std::env::temp_dir().join(format!("troupe-cal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("cal.json");
        c.save(&p).unwrap();
        assert_eq!(GloveCalibration::load(&p).unwrap(), c);
        std::fs::write(&p, "{}").unwrap();
        assert!(GloveCalibration::load(&p)
            .unwrap_err()
            .contains("not a glove calibration"));
    }

    proptest::proptest! {
        #[test]
        fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..512),
                                       big: bool, status: bool) {
            let layout = GloveLayout { sensors: if big { 22 } else { 18 }, status_byte: status };
            let mut d = GloveDecoder::new(layout);
            let recs = d.feed_collect(&bytes);
            for r in &recs {
                proptest::prop_assert!(r.raw.iter().all(|&v| v != 0));
            }
            for q in [Query::Status, Query::Mask, Query::Version] {
                let _ = parse_query_reply(q, &bytes);
            }
        }
    }
}
