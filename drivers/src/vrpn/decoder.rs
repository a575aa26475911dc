//! From VRPN messages to readings: the sender and type names each connection describes,
//! and the payloads of the tracker (`vrpn_Tracker Pos_Quat`, `Velocity`, `Acceleration`),
//! button (`vrpn_Button Change`, `States`) and analog (`vrpn_Analog Channel`) devices.
//! VRPN's timestamp on each message is kept as the reading's source time.

use crate::vrpn::wire::{system, Message};
use serde::Serialize;
use std::collections::HashMap;

/// Type names of the messages troupe decodes.
pub mod types {
    /// Position and orientation of one sensor.
    pub const POS_QUAT: &str = "vrpn_Tracker Pos_Quat";
    /// Velocity of one sensor.
    pub const VELOCITY: &str = "vrpn_Tracker Velocity";
    /// Acceleration of one sensor.
    pub const ACCELERATION: &str = "vrpn_Tracker Acceleration";
    /// One button changed.
    pub const BUTTON_CHANGE: &str = "vrpn_Button Change";
    /// Every button's state.
    pub const BUTTON_STATES: &str = "vrpn_Button States";
    /// Every analog channel's value.
    pub const ANALOG: &str = "vrpn_Analog Channel";
    /// A client's "are you there" to a device of the server.
    pub const PING: &str = "vrpn_Base ping_message";
    /// The device's answer to a ping.
    pub const PONG: &str = "vrpn_Base pong_message";
}

/// What a VRPN device reported, with the server's timestamp (`time`, seconds since the
/// Unix epoch on the server's clock).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "message", rename_all = "lowercase")]
pub enum VrpnReading {
    /// A tracker sensor's pose: position and quaternion `[x, y, z, w]`, in the server's
    /// frame and units.
    Tracker {
        /// The sender (the device's name on the server).
        device: String,
        /// The sensor, from 0.
        sensor: i32,
        /// Position.
        position: [f64; 3],
        /// Orientation `[x, y, z, w]`.
        quaternion: [f64; 4],
        /// Source time, seconds.
        time: f64,
    },
    /// A tracker sensor's velocity: linear, and the rotation it turns by over `dt` seconds.
    Velocity {
        /// The sender.
        device: String,
        /// The sensor.
        sensor: i32,
        /// Linear velocity.
        velocity: [f64; 3],
        /// Rotation over `dt`, `[x, y, z, w]`.
        quaternion: [f64; 4],
        /// The interval of `quaternion`, seconds.
        dt: f64,
        /// Source time.
        time: f64,
    },
    /// A tracker sensor's acceleration, laid out like its velocity.
    Acceleration {
        /// The sender.
        device: String,
        /// The sensor.
        sensor: i32,
        /// Linear acceleration.
        acceleration: [f64; 3],
        /// Rotation over `dt`, `[x, y, z, w]`.
        quaternion: [f64; 4],
        /// The interval of `quaternion`, seconds.
        dt: f64,
        /// Source time.
        time: f64,
    },
    /// One button pressed or released.
    Button {
        /// The sender.
        device: String,
        /// The button, from 0.
        button: i32,
        /// Down.
        pressed: bool,
        /// Source time.
        time: f64,
    },
    /// Every button's state (sent when a client connects).
    Buttons {
        /// The sender.
        device: String,
        /// Down or up, per button.
        pressed: Vec<bool>,
        /// Source time.
        time: f64,
    },
    /// Every analog channel's value.
    Analog {
        /// The sender.
        device: String,
        /// The values.
        channels: Vec<f64>,
        /// Source time.
        time: f64,
    },
}

impl VrpnReading {
    /// The sender's name.
    pub fn device(&self) -> &str {
        match self {
            VrpnReading::Tracker { device, .. }
            | VrpnReading::Velocity { device, .. }
            | VrpnReading::Acceleration { device, .. }
            | VrpnReading::Button { device, .. }
            | VrpnReading::Buttons { device, .. }
            | VrpnReading::Analog { device, .. } => device,
        }
    }

    /// The source time, seconds.
    pub fn time(&self) -> f64 {
        match self {
            VrpnReading::Tracker { time, .. }
            | VrpnReading::Velocity { time, .. }
            | VrpnReading::Acceleration { time, .. }
            | VrpnReading::Button { time, .. }
            | VrpnReading::Buttons { time, .. }
            | VrpnReading::Analog { time, .. } => *time,
        }
    }
}

/// One line for a console (`troupe devices probe vrpn`).
impl std::fmt::Display for VrpnReading {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let v3 = |v: &[f64; 3]| format!("{:8.4} {:8.4} {:8.4}", v[0], v[1], v[2]);
        let v4 = |q: &[f64; 4]| format!("{:7.4} {:7.4} {:7.4} {:7.4}", q[0], q[1], q[2], q[3]);
        write!(f, "[{:.6}] {} ", self.time(), self.device())?;
        match self {
            VrpnReading::Tracker {
                sensor,
                position,
                quaternion,
                ..
            } => {
                write!(
                    f,
                    "sensor {sensor} pos {} quat(xyzw) {}",
                    v3(position),
                    v4(quaternion)
                )
            }
            VrpnReading::Velocity {
                sensor,
                velocity,
                quaternion,
                dt,
                ..
            } => write!(
                f,
                "sensor {sensor} vel {} turn {} over {dt} s",
                v3(velocity),
                v4(quaternion)
            ),
            VrpnReading::Acceleration {
                sensor,
                acceleration,
                quaternion,
                dt,
                ..
            } => write!(
                f,
                "sensor {sensor} acc {} turn {} over {dt} s",
                v3(acceleration),
                v4(quaternion)
            ),
            VrpnReading::Button {
                button, pressed, ..
            } => {
                write!(
                    f,
                    "button {button} {}",
                    if *pressed { "down" } else { "up" }
                )
            }
            VrpnReading::Buttons { pressed, .. } => {
                let s: String = pressed.iter().map(|&p| if p { '1' } else { '0' }).collect();
                write!(f, "buttons {s}")
            }
            VrpnReading::Analog { channels, .. } => write!(f, "analog {channels:?}"),
        }
    }
}

/// Counts of messages the decoder could not use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct DecodeCounters {
    /// Messages whose payload does not fit their type (short, a count that lies, not a
    /// number), or descriptions that do not parse.
    pub malformed: u64,
    /// Bytes of those messages.
    pub malformed_bytes: u64,
    /// Messages naming a sender or type id no description named.
    pub undescribed: u64,
}

/// Turns one connection's messages into readings of the devices it listens to.
#[derive(Debug)]
pub struct Decoder {
    /// The senders (device names) whose reports are wanted.
    wanted: Vec<String>,
    senders: HashMap<i32, String>,
    types: HashMap<i32, String>,
    counters: DecodeCounters,
}

/// Big-endian reader over a payload; every read checks the length.
struct Payload<'a>(&'a [u8]);

impl Payload<'_> {
    fn take<const N: usize>(&mut self) -> Option<[u8; N]> {
        let (head, rest) = self.0.split_at_checked(N)?;
        self.0 = rest;
        head.try_into().ok()
    }
    fn i32(&mut self) -> Option<i32> {
        self.take::<4>().map(i32::from_be_bytes)
    }
    fn f64(&mut self) -> Option<f64> {
        self.take::<8>().map(f64::from_be_bytes)
    }
    fn f64s<const N: usize>(&mut self) -> Option<[f64; N]> {
        let mut out = [0.0; N];
        for v in &mut out {
            *v = self.f64()?;
        }
        Some(out)
    }
}

impl Decoder {
    /// A decoder for the reports of the given senders.
    pub fn new(wanted: Vec<String>) -> Decoder {
        Decoder {
            wanted,
            senders: HashMap::new(),
            types: HashMap::new(),
            counters: DecodeCounters::default(),
        }
    }

    /// Forgets the descriptions: ids are per connection.
    pub fn new_connection(&mut self) {
        self.senders.clear();
        self.types.clear();
    }

    /// What could not be used so far.
    pub fn counters(&self) -> DecodeCounters {
        self.counters
    }

    fn malformed(&mut self, m: &Message) {
        self.counters.malformed += 1;
        self.counters.malformed_bytes += m.payload.len() as u64;
    }

    /// Decodes one message: a description updates the tables, a report of a wanted sender
    /// becomes a reading, anything else is skipped (and counted if it cannot be read).
    pub fn decode(&mut self, m: &Message, out: &mut dyn FnMut(VrpnReading)) {
        let h = &m.header;
        match h.kind {
            system::SENDER_DESCRIPTION | system::TYPE_DESCRIPTION => {
                let Some(name) = description_name(&m.payload) else {
                    return self.malformed(m);
                };
                let table = if h.kind == system::SENDER_DESCRIPTION {
                    &mut self.senders
                } else {
                    &mut self.types
                };
                table.insert(h.sender, name);
                return;
            }
            k if k < 0 => return, // UDP and log descriptions: nothing to decode.
            _ => {}
        }
        let (Some(sender), Some(kind)) = (self.senders.get(&h.sender), self.types.get(&h.kind))
        else {
            self.counters.undescribed += 1;
            return;
        };
        if !self.wanted.iter().any(|w| w == sender) {
            return;
        }
        let device = sender.clone();
        let time = h.time();
        let mut p = Payload(&m.payload);
        let reading = match kind.as_str() {
            types::POS_QUAT => (|| {
                let sensor = p.i32()?;
                p.i32()?; // alignment word
                Some(VrpnReading::Tracker {
                    device,
                    sensor,
                    position: p.f64s()?,
                    quaternion: p.f64s()?,
                    time,
                })
            })(),
            types::VELOCITY | types::ACCELERATION => (|| {
                let sensor = p.i32()?;
                p.i32()?;
                let linear = p.f64s()?;
                let quaternion = p.f64s()?;
                let dt = p.f64()?;
                Some(if kind == types::VELOCITY {
                    VrpnReading::Velocity {
                        device,
                        sensor,
                        velocity: linear,
                        quaternion,
                        dt,
                        time,
                    }
                } else {
                    VrpnReading::Acceleration {
                        device,
                        sensor,
                        acceleration: linear,
                        quaternion,
                        dt,
                        time,
                    }
                })
            })(),
            types::BUTTON_CHANGE => (|| {
                let button = p.i32()?;
                let state = p.i32()?;
                Some(VrpnReading::Button {
                    device,
                    button,
                    pressed: state != 0,
                    time,
                })
            })(),
            types::BUTTON_STATES => (|| {
                let n = usize::try_from(p.i32()?).ok()?;
                // The count must fit the payload: a lying count reads nothing.
                if n > p.0.len() / 4 {
                    return None;
                }
                let pressed = (0..n)
                    .map(|_| p.i32().map(|s| s != 0))
                    .collect::<Option<_>>()?;
                Some(VrpnReading::Buttons {
                    device,
                    pressed,
                    time,
                })
            })(),
            types::ANALOG => (|| {
                let n = p.f64()?;
                if !(n >= 0.0 && n <= (p.0.len() / 8) as f64 && n.fract() == 0.0) {
                    return None;
                }
                let channels = (0..n as usize).map(|_| p.f64()).collect::<Option<_>>()?;
                Some(VrpnReading::Analog {
                    device,
                    channels,
                    time,
                })
            })(),
            // Pongs (answers to troupe's pings), another device class's messages (text,
            // dials, …): nothing to decode.
            _ => return,
        };
        match reading {
            Some(r) => out(r),
            None => self.malformed(m),
        }
    }
}

/// The name in a sender or type description: `u32 len+1`, the name, NUL.
fn description_name(payload: &[u8]) -> Option<String> {
    let mut p = Payload(payload);
    let n = usize::try_from(p.i32()?).ok()?;
    let bytes = p.0.get(..n)?;
    let name = bytes.strip_suffix(&[0]).unwrap_or(bytes);
    String::from_utf8(name.to_vec()).ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::vrpn::wire::{encode, name_payload, Framer};

    fn feed(d: &mut Decoder, bytes: &[u8]) -> Vec<VrpnReading> {
        let mut f = Framer::default();
        f.push(bytes);
        let mut out = Vec::new();
        while let Some(m) = f.next_message().unwrap() {
            d.decode(&m, &mut |r| out.push(r));
        }
        out
    }

    fn described() -> Vec<u8> {
        [
            encode(
                0,
                0,
                3,
                system::SENDER_DESCRIPTION,
                &name_payload("Tracker0"),
            ),
            encode(0, 0, 4, system::SENDER_DESCRIPTION, &name_payload("Other")),
            encode(
                0,
                0,
                9,
                system::TYPE_DESCRIPTION,
                &name_payload(types::POS_QUAT),
            ),
            encode(
                0,
                0,
                10,
                system::TYPE_DESCRIPTION,
                &name_payload(types::BUTTON_CHANGE),
            ),
            encode(
                0,
                0,
                11,
                system::TYPE_DESCRIPTION,
                &name_payload(types::ANALOG),
            ),
            encode(
                0,
                0,
                12,
                system::TYPE_DESCRIPTION,
                &name_payload(types::BUTTON_STATES),
            ),
        ]
        .concat()
    }

    fn pos_quat(sensor: i32) -> Vec<u8> {
        let mut p = sensor.to_be_bytes().to_vec();
        p.extend_from_slice(&sensor.to_be_bytes());
        for v in [1.0f64, 2.0, 3.0, 0.0, 0.0, 0.0, 1.0] {
            p.extend_from_slice(&v.to_be_bytes());
        }
        p
    }

    #[test]
    fn reports_of_the_wanted_sender_decode_with_their_source_time() {
        let mut d = Decoder::new(vec!["Tracker0".into()]);
        let bytes = [
            described(),
            encode(100, 500_000, 3, 9, &pos_quat(1)),
            encode(100, 600_000, 4, 9, &pos_quat(0)), // another device: skipped
            encode(101, 0, 3, 10, &[0, 0, 0, 2, 0, 0, 0, 1]),
            encode(
                101,
                0,
                3,
                11,
                &[
                    2.0f64.to_be_bytes(),
                    0.5f64.to_be_bytes(),
                    (-1.0f64).to_be_bytes(),
                ]
                .concat(),
            ),
        ]
        .concat();
        let r = feed(&mut d, &bytes);
        assert_eq!(r.len(), 3);
        assert_eq!(
            r[0],
            VrpnReading::Tracker {
                device: "Tracker0".into(),
                sensor: 1,
                position: [1.0, 2.0, 3.0],
                quaternion: [0.0, 0.0, 0.0, 1.0],
                time: 100.5
            }
        );
        assert!(matches!(
            r[1],
            VrpnReading::Button {
                button: 2,
                pressed: true,
                ..
            }
        ));
        assert!(matches!(&r[2], VrpnReading::Analog { channels, .. } if channels == &[0.5, -1.0]));
        assert_eq!(d.counters(), DecodeCounters::default());
    }

    #[test]
    fn short_payloads_lying_counts_and_unknown_ids_are_counted_not_decoded() {
        let mut d = Decoder::new(vec!["Tracker0".into()]);
        let bytes = [
            described(),
            encode(0, 0, 3, 9, &pos_quat(0)[..40]), // short
            encode(0, 0, 3, 12, &[0x7f, 0xff, 0xff, 0xff, 0, 0, 0, 1]), // count lies
            encode(0, 0, 3, 11, &1e300f64.to_be_bytes()), // channel count lies
            encode(0, 0, 3, 77, &pos_quat(0)),      // type never described
            encode(0, 0, 1, system::SENDER_DESCRIPTION, &[0, 0, 0, 200, b'x']), // name cut
        ]
        .concat();
        assert!(feed(&mut d, &bytes).is_empty());
        let c = d.counters();
        assert_eq!((c.malformed, c.undescribed), (4, 1));
    }

    #[test]
    fn a_new_connection_forgets_the_ids() {
        let mut d = Decoder::new(vec!["Tracker0".into()]);
        assert_eq!(
            feed(
                &mut d,
                &[described(), encode(0, 0, 3, 9, &pos_quat(0))].concat()
            )
            .len(),
            1
        );
        d.new_connection();
        assert!(feed(&mut d, &encode(0, 0, 3, 9, &pos_quat(0))).is_empty());
        assert_eq!(d.counters().undescribed, 1);
    }
}
