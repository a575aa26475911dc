//! VMC messages as OSC: building a frame's bundle, and reading a datagram back into a
//! pose, counting what is wrong instead of failing.
//!
//! | address | arguments |
//! |---|---|
//! | `/VMC/Ext/OK` | `loaded` (int): 1 once the avatar's bones are sent |
//! | `/VMC/Ext/T` | `time` (float): the sender's clock, seconds |
//! | `/VMC/Ext/Root/Pos` | `"root"`, `p.x p.y p.z q.x q.y q.z q.w` (floats; more are allowed) |
//! | `/VMC/Ext/Bone/Pos` | bone name (Unity `HumanBodyBones`), `p.x p.y p.z q.x q.y q.z q.w` |

use crate::osc::datagram::decode_datagram;
use crate::vmc::bones::{bone_index, IGNORED_BONES};
use crate::vmc::rig::VmcPose;
use glam::{DQuat, DVec3};
use rosc::{OscBundle, OscMessage, OscPacket, OscType};
use troupe_body::transform::Transform;

/// A quaternion further than this from unit length is refused rather than normalized.
pub const UNIT_TOLERANCE: f64 = 0.05;

/// What one datagram carried.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VmcPacket {
    /// The root and the bones it set.
    pub pose: VmcPose,
    /// `/VMC/Ext/T`: the sender's time.
    pub time: Option<f64>,
    /// `/VMC/Ext/OK`: whether the sender has an avatar loaded.
    pub loaded: Option<bool>,
}

impl VmcPacket {
    /// Whether the datagram gave nothing troupe reads: not OSC, or no VMC message it
    /// uses (what `probe` does not count as a sample).
    pub fn is_empty(&self) -> bool {
        self.pose.is_empty() && self.time.is_none() && self.loaded.is_none()
    }
}

/// Counters of what a receiver could not use; each kind of problem apart.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct VmcCounters {
    /// Datagrams received.
    pub packets: u64,
    /// Datagrams that are not OSC (truncated, garbage).
    pub malformed: u64,
    /// Messages outside `/VMC/` (another protocol on the port).
    pub unknown: u64,
    /// `/VMC/` messages troupe does not read (blend shapes, cameras, trackers, …).
    pub ignored: u64,
    /// Messages with wrong argument types or counts, NaN, or a non-unit quaternion.
    pub invalid: u64,
    /// Bone names outside VRM's humanoid bones.
    pub unknown_bones: u64,
}

impl VmcCounters {
    /// Adds another receiver's counts.
    pub fn add(&mut self, o: &VmcCounters) {
        self.packets += o.packets;
        self.malformed += o.malformed;
        self.unknown += o.unknown;
        self.ignored += o.ignored;
        self.invalid += o.invalid;
        self.unknown_bones += o.unknown_bones;
    }
}

/// The bundle of one frame: OK, T, the root and every bone the pose has.
pub fn frame_bundle(pose: &VmcPose, time: f64) -> OscPacket {
    let mut content = vec![
        message("/VMC/Ext/OK", vec![OscType::Int(1)]),
        message("/VMC/Ext/T", vec![OscType::Float(time as f32)]),
    ];
    if let Some(root) = pose.root {
        content.push(pose_message("/VMC/Ext/Root/Pos", "root", &root));
    }
    for (b, t) in crate::vmc::bones::VRM_BONES.iter().zip(&pose.bones) {
        if let Some(t) = t {
            content.push(pose_message("/VMC/Ext/Bone/Pos", b.name, t));
        }
    }
    OscPacket::Bundle(OscBundle {
        // "Immediately": receivers apply a frame when it arrives.
        timetag: (0, 1).into(),
        content,
    })
}

fn message(addr: &str, args: Vec<OscType>) -> OscPacket {
    OscPacket::Message(OscMessage {
        addr: addr.into(),
        args,
    })
}

fn pose_message(addr: &str, name: &str, t: &Transform) -> OscPacket {
    let (p, q) = (t.translation, t.rotation);
    let mut args = vec![OscType::String(name.into())];
    args.extend(
        [p.x, p.y, p.z, q.x, q.y, q.z, q.w]
            .iter()
            .map(|v| OscType::Float(*v as f32)),
    );
    message(addr, args)
}

/// Reads one datagram; what cannot be used is counted in `counters` and skipped. A
/// datagram that is not one whole OSC packet (cut short, a lying bundle size, garbage)
/// is `malformed` and gives nothing: a frame is taken whole or not at all.
pub fn read_datagram(bytes: &[u8], counters: &mut VmcCounters) -> VmcPacket {
    counters.packets += 1;
    let mut out = VmcPacket::default();
    match decode_datagram(bytes) {
        Ok(p) => read_packet(&p, &mut out, counters),
        Err(_) => counters.malformed += 1,
    }
    out
}

fn read_packet(p: &OscPacket, out: &mut VmcPacket, counters: &mut VmcCounters) {
    match p {
        OscPacket::Message(m) => read_message(m, out, counters),
        OscPacket::Bundle(b) => b.content.iter().for_each(|c| read_packet(c, out, counters)),
    }
}

fn float(a: &OscType) -> Option<f64> {
    match a {
        OscType::Float(f) => Some(f64::from(*f)),
        OscType::Double(d) => Some(*d),
        _ => None,
    }
}

fn read_message(m: &OscMessage, out: &mut VmcPacket, counters: &mut VmcCounters) {
    match m.addr.as_str() {
        "/VMC/Ext/OK" => match m.args.first() {
            Some(OscType::Int(v)) => out.loaded = Some(*v != 0),
            _ => counters.invalid += 1,
        },
        "/VMC/Ext/T" => match m.args.first().and_then(float) {
            Some(t) if t.is_finite() && m.args.len() == 1 => out.time = Some(t),
            _ => counters.invalid += 1,
        },
        "/VMC/Ext/Root/Pos" => match named_pose(&m.args) {
            Some((_, t)) => out.pose.root = Some(t),
            None => counters.invalid += 1,
        },
        "/VMC/Ext/Bone/Pos" => match named_pose(&m.args) {
            Some((name, t)) => match bone_index(name) {
                Some(i) => out.pose.bones[i] = Some(t),
                None if IGNORED_BONES.contains(&name) => counters.ignored += 1,
                None => counters.unknown_bones += 1,
            },
            None => counters.invalid += 1,
        },
        a if a.starts_with("/VMC/") => counters.ignored += 1,
        _ => counters.unknown += 1,
    }
}

/// `name p.x p.y p.z q.x q.y q.z q.w [more floats]` with finite numbers and a unit
/// quaternion (normalized), or `None`.
fn named_pose(args: &[OscType]) -> Option<(&str, Transform)> {
    let (OscType::String(name), rest) = args.split_first()? else {
        return None;
    };
    if rest.len() < 7 {
        return None;
    }
    let v: Vec<f64> = rest.iter().map(float).collect::<Option<_>>()?;
    if v.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let q = DQuat::from_xyzw(v[3], v[4], v[5], v[6]);
    if (q.length() - 1.0).abs() > UNIT_TOLERANCE {
        return None;
    }
    Some((
        name.as_str(),
        Transform::new(q.normalize(), DVec3::new(v[0], v[1], v[2])),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bone_msg(name: &str, vals: &[f32]) -> OscPacket {
        let mut args = vec![OscType::String(name.into())];
        args.extend(vals.iter().map(|v| OscType::Float(*v)));
        message("/VMC/Ext/Bone/Pos", args)
    }

    fn encode(p: &OscPacket) -> Vec<u8> {
        rosc::encoder::encode(p).unwrap()
    }

    #[test]
    fn a_frame_reads_back() {
        let mut pose = VmcPose::default();
        let t = Transform::new(DQuat::from_rotation_x(0.3), DVec3::new(0.1, 0.9, -0.2));
        pose.root = Some(Transform::IDENTITY);
        pose.bones[3] = Some(t);
        let mut c = VmcCounters::default();
        let got = read_datagram(&encode(&frame_bundle(&pose, 2.5)), &mut c);
        assert_eq!(got.time, Some(2.5));
        assert_eq!(got.loaded, Some(true));
        let b = got.pose.bones[3].unwrap();
        assert!(b.rotation.angle_between(t.rotation) < 1e-6);
        assert!((b.translation - t.translation).length() < 1e-6);
        assert_eq!(
            c,
            VmcCounters {
                packets: 1,
                ..Default::default()
            }
        );
    }

    #[test]
    fn bad_input_is_counted_and_skipped() {
        let mut c = VmcCounters::default();
        let good = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        let bundle = OscPacket::Bundle(OscBundle {
            timetag: (0, 1).into(),
            content: vec![
                bone_msg("Head", &good),
                bone_msg("Tail", &good),
                bone_msg("Jaw", &good),
                bone_msg("Neck", &[0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 1.0]),
                bone_msg("Neck", &[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0]),
                bone_msg("Neck", &[0.0, 0.0]),
                message("/VMC/Ext/Bone/Pos", vec![OscType::Int(3)]),
                message("/VMC/Ext/T", vec![OscType::String("x".into())]),
                message(
                    "/VMC/Ext/Blend/Val",
                    vec![OscType::String("A".into()), OscType::Float(1.0)],
                ),
                message("/other", vec![]),
            ],
        });
        let got = read_datagram(&encode(&bundle), &mut c);
        assert!(got.pose.bones[bone_index("Head").unwrap()].is_some());
        assert!(got.pose.bones[bone_index("Neck").unwrap()].is_none());
        assert_eq!(
            c,
            VmcCounters {
                packets: 1,
                malformed: 0,
                unknown: 1,
                ignored: 2,
                invalid: 5,
                unknown_bones: 1,
            }
        );
        let bytes = encode(&bundle);
        for cut in [1, 7, 16, bytes.len() / 2, bytes.len() - 1] {
            read_datagram(&bytes[..cut], &mut c);
        }
        read_datagram(b"\xff\xfe garbage", &mut c);
        // Every cut but 16 (right after the bundle header: an empty bundle, valid OSC).
        assert_eq!(c.malformed, 5, "{c:?}");
    }

    #[test]
    fn only_datagrams_with_vmc_content_are_samples() {
        let mut c = VmcCounters::default();
        let frame = encode(&frame_bundle(&VmcPose::default(), 1.0));
        assert!(!read_datagram(&frame, &mut c).is_empty());
        let ok = encode(&message("/VMC/Ext/OK", vec![OscType::Int(0)]));
        assert!(!read_datagram(&ok, &mut c).is_empty());
        let other = encode(&message("/other", vec![OscType::Int(0)]));
        for bytes in [&b"\x13\x37 random"[..], &frame[..frame.len() - 3], &other] {
            assert!(read_datagram(bytes, &mut c).is_empty());
        }
    }

    #[test]
    fn a_frame_cut_inside_a_bone_is_dropped_whole_and_counted() {
        // The tester's case: pose B's frame cut inside its `LeftUpperArm` message. Its
        // hips and right arm decode, but applying them would mix B with the last pose.
        let mut pose = VmcPose::default();
        for name in ["Hips", "RightUpperArm", "LeftUpperArm"] {
            let t = Transform::new(DQuat::from_rotation_y(1.0), DVec3::new(0.0, 0.8, 0.0));
            pose.bones[bone_index(name).unwrap()] = Some(t);
        }
        let bytes = encode(&frame_bundle(&pose, 1.0));
        let at = bytes
            .windows(12)
            .position(|w| w == b"LeftUpperArm")
            .unwrap();
        let mut c = VmcCounters::default();
        let got = read_datagram(&bytes[..at + 8], &mut c);
        assert_eq!(got, VmcPacket::default());
        assert_eq!((c.packets, c.malformed, c.invalid), (1, 1, 0));
    }
}
