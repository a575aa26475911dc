//! CyberGlove (Virtual Technologies): commands, sensor names, and a decoder that frames
//! records out of a byte stream and resynchronizes on loss.
//!
//! Protocol facts come from `shared/reference/devices.md`, section "CyberGlove"; the
//! comments quote the fact they rely on. Thesis 4.7 and 6.4.1 use the glove for the
//! performer's hand and for gestures.

use serde::{Deserialize, Serialize};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cyberglove::query::{parse_query_reply, Query};

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
