//! BVH (Biovision Hierarchy) motion files: import, forward kinematics and export.
//!
//! The reader accepts what real files contain: any of the six rotation orders per joint,
//! rotation channels listed before or after position channels, CRLF or LF line ends (mixed
//! too), tabs or spaces, `End Site` blocks, several roots, and a root with a non-zero
//! `OFFSET` together with absolute position channels. A `Frames:` count that disagrees
//! with the data rows is reported with a `tracing` warning and the rows are used.
//!
//! Conventions (those of pybvh, bvhio and bvhtoolbox): rotation channels compose in the
//! order listed, intrinsically (`Zrotation Xrotation Yrotation` means `R = Rz·Rx·Ry`);
//! a joint's local transform is `translate(t) · R`, where `t` is the joint's `OFFSET` with
//! every component that has a position channel replaced by that channel's value.
//!
//! A [`Bvh`] keeps the file's own units (degrees, and whatever length unit the file uses);
//! conversion to troupe's metres and radians happens where a BVH becomes a troupe
//! [`Sequence`](troupe_motion::Sequence) (see [`Bvh::to_channel_sequence`] and
//! [`crate::retarget`]).

use crate::error::{Error, Result};
use glam::{DMat3, DQuat, DVec3, EulerRot};
use std::fmt::{self, Write as _};
use std::path::Path;
use std::str::FromStr;
use troupe_body::transform::Transform;
use troupe_motion::sequence::{Key, Sequence, Track};

/// Most channels a single joint may declare (three positions and three rotations).
pub const MAX_JOINT_CHANNELS: usize = 6;

/// A coordinate axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Axis {
    /// The X axis.
    X,
    /// The Y axis.
    Y,
    /// The Z axis.
    Z,
}

impl Axis {
    /// The axis as an index (X = 0, Y = 1, Z = 2).
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }

    /// The unit vector along the axis.
    pub fn unit(self) -> DVec3 {
        match self {
            Axis::X => DVec3::X,
            Axis::Y => DVec3::Y,
            Axis::Z => DVec3::Z,
        }
    }

    fn letter(self) -> char {
        match self {
            Axis::X => 'X',
            Axis::Y => 'Y',
            Axis::Z => 'Z',
        }
    }
}

/// One BVH channel: a translation along or a rotation (degrees) about an axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// `Xposition`, `Yposition` or `Zposition`.
    Position(Axis),
    /// `Xrotation`, `Yrotation` or `Zrotation` (degrees in the file).
    Rotation(Axis),
}

impl Channel {
    /// Parses a channel name (case-insensitive, as some exporters vary the case).
    pub fn parse(name: &str) -> Option<Channel> {
        let lower = name.to_ascii_lowercase();
        let axis = match lower.chars().next()? {
            'x' => Axis::X,
            'y' => Axis::Y,
            'z' => Axis::Z,
            _ => return None,
        };
        match &lower[1..] {
            "position" => Some(Channel::Position(axis)),
            "rotation" => Some(Channel::Rotation(axis)),
            _ => None,
        }
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Channel::Position(a) => write!(f, "{}position", a.letter()),
            Channel::Rotation(a) => write!(f, "{}rotation", a.letter()),
        }
    }
}

/// An order of three distinct rotation axes, composed intrinsically (`ZXY` = `Rz·Rx·Ry`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct RotationOrder(pub [Axis; 3]);

impl RotationOrder {
    /// Every Tait–Bryan order.
    pub const ALL: [RotationOrder; 6] = [
        RotationOrder([Axis::X, Axis::Y, Axis::Z]),
        RotationOrder([Axis::X, Axis::Z, Axis::Y]),
        RotationOrder([Axis::Y, Axis::X, Axis::Z]),
        RotationOrder([Axis::Y, Axis::Z, Axis::X]),
        RotationOrder([Axis::Z, Axis::X, Axis::Y]),
        RotationOrder([Axis::Z, Axis::Y, Axis::X]),
    ];

    fn euler(self) -> EulerRot {
        use Axis::*;
        match self.0 {
            [X, Y, Z] => EulerRot::XYZ,
            [X, Z, Y] => EulerRot::XZY,
            [Y, X, Z] => EulerRot::YXZ,
            [Y, Z, X] => EulerRot::YZX,
            [Z, X, Y] => EulerRot::ZXY,
            _ => EulerRot::ZYX,
        }
    }

    /// The angles (radians, in this order's axis order) of rotation `q`.
    pub fn decompose(self, q: DQuat) -> [f64; 3] {
        let (a, b, c) = DMat3::from_quat(q.normalize()).to_euler(self.euler());
        [a, b, c]
    }

    /// The rotation of angles (radians) about this order's axes, composed intrinsically.
    pub fn compose(self, angles: [f64; 3]) -> DQuat {
        let mut q = DQuat::IDENTITY;
        for (axis, angle) in self.0.iter().zip(angles) {
            q *= DQuat::from_axis_angle(axis.unit(), angle);
        }
        q
    }
}

impl FromStr for RotationOrder {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let axes: Vec<Axis> = s
            .trim()
            .chars()
            .map(|c| match c.to_ascii_uppercase() {
                'X' => Some(Axis::X),
                'Y' => Some(Axis::Y),
                'Z' => Some(Axis::Z),
                _ => None,
            })
            .collect::<Option<_>>()
            .ok_or_else(|| Error::Invalid(format!("bad rotation order `{s}` (e.g. ZXY)")))?;
        RotationOrder::ALL
            .into_iter()
            .find(|o| o.0[..] == axes[..])
            .ok_or_else(|| {
                Error::Invalid(format!(
                    "bad rotation order `{s}`: three distinct axes, e.g. ZXY"
                ))
            })
    }
}

impl fmt::Display for RotationOrder {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for a in self.0 {
            write!(f, "{}", a.letter())?;
        }
        Ok(())
    }
}

/// One joint of a BVH hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhJoint {
    /// The joint's name as written in the file.
    pub name: String,
    /// Parent joint index (smaller than this joint's), `None` for a root.
    pub parent: Option<usize>,
    /// The `OFFSET` from the parent, in file units.
    pub offset: DVec3,
    /// The joint's channels in file order.
    pub channels: Vec<Channel>,
    /// Index of the joint's first channel in a frame row.
    pub first_channel: usize,
    /// Offsets of the joint's `End Site` blocks (usually zero or one).
    pub end_sites: Vec<DVec3>,
}

/// A BVH motion: its own hierarchy and the channel values of every frame (file units).
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    joints: Vec<BvhJoint>,
    frame_time: f64,
    channel_count: usize,
    data: Vec<f64>,
}

impl Bvh {
    /// Builds a motion from a hierarchy and frame-major channel data; checks sizes and
    /// recomputes every joint's `first_channel`.
    pub fn new(mut joints: Vec<BvhJoint>, frame_time: f64, data: Vec<f64>) -> Result<Bvh> {
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(Error::invalid_value(
                "BVH frame time",
                frame_time,
                "a positive number of seconds",
            ));
        }
        let mut count = 0;
        for (i, j) in joints.iter_mut().enumerate() {
            if j.parent.is_some_and(|p| p >= i) {
                return Err(Error::Invalid(format!(
                    "BVH joint `{}`: parent must come first",
                    j.name
                )));
            }
            j.first_channel = count;
            count += j.channels.len();
        }
        if joints.is_empty() {
            return Err(Error::Invalid("BVH without joints".into()));
        }
        if count == 0 && !data.is_empty() || count > 0 && !data.len().is_multiple_of(count) {
            return Err(Error::Invalid(format!(
                "BVH data of {} values is not a whole number of {count}-channel frames",
                data.len()
            )));
        }
        Ok(Bvh {
            joints,
            frame_time,
            channel_count: count,
            data,
        })
    }

    /// The joints in file order (parents first).
    pub fn joints(&self) -> &[BvhJoint] {
        &self.joints
    }
    /// The index of the joint called `name`.
    pub fn joint(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }
    /// Seconds per frame.
    pub fn frame_time(&self) -> f64 {
        self.frame_time
    }
    /// Total channels per frame.
    pub fn channel_count(&self) -> usize {
        self.channel_count
    }
    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.data.len().checked_div(self.channel_count).unwrap_or(0)
    }
    /// Duration from the first to the last frame, in seconds.
    pub fn duration(&self) -> f64 {
        self.frame_count().saturating_sub(1) as f64 * self.frame_time
    }
    /// The channel values of frame `k` (file units, degrees).
    pub fn frame(&self, k: usize) -> &[f64] {
        &self.data[k * self.channel_count..(k + 1) * self.channel_count]
    }
    /// Mutable channel values of frame `k`.
    pub fn frame_mut(&mut self, k: usize) -> &mut [f64] {
        &mut self.data[k * self.channel_count..(k + 1) * self.channel_count]
    }

    /// The local transform (file units) of joint `j` for channel values `frame`.
    pub fn local_transform(&self, j: usize, frame: &[f64]) -> Transform {
        let joint = &self.joints[j];
        let mut t = joint.offset;
        let mut q = DQuat::IDENTITY;
        for (c, &v) in joint
            .channels
            .iter()
            .zip(&frame[joint.first_channel..joint.first_channel + joint.channels.len()])
        {
            match c {
                Channel::Position(a) => t[a.index()] = v,
                Channel::Rotation(a) => q *= DQuat::from_axis_angle(a.unit(), v.to_radians()),
            }
        }
        Transform::new(q, t)
    }

    /// Global transforms of every joint at frame `k` into `globals` (one per joint).
    pub fn global_transforms(&self, k: usize, globals: &mut [Transform]) {
        let frame = self.frame(k);
        for j in 0..self.joints.len() {
            let local = self.local_transform(j, frame);
            globals[j] = match self.joints[j].parent {
                Some(p) => globals[p].mul(&local),
                None => local,
            };
        }
    }

    /// Global joint positions (file units) at frame `k`.
    pub fn joint_positions(&self, k: usize) -> Vec<DVec3> {
        let mut g = vec![Transform::IDENTITY; self.joints.len()];
        self.global_transforms(k, &mut g);
        g.iter().map(|t| t.translation).collect()
    }

    /// Global joint positions in the rest pose (every channel zero, offsets only).
    pub fn rest_positions(&self) -> Vec<DVec3> {
        let mut p: Vec<DVec3> = Vec::with_capacity(self.joints.len());
        for j in &self.joints {
            let base = j.parent.map_or(DVec3::ZERO, |i| p[i]);
            p.push(base + j.offset);
        }
        p
    }

    /// The same motion with every joint's rotation channels rewritten as three channels in
    /// `order` (after the joint's position channels); global poses are unchanged.
    pub fn with_rotation_order(&self, order: RotationOrder) -> Bvh {
        let mut joints = self.joints.clone();
        for j in &mut joints {
            let has_rot = j.channels.iter().any(|c| matches!(c, Channel::Rotation(_)));
            j.channels.retain(|c| matches!(c, Channel::Position(_)));
            if has_rot {
                j.channels
                    .extend(order.0.iter().map(|&a| Channel::Rotation(a)));
            }
        }
        let count: usize = joints.iter().map(|j| j.channels.len()).sum();
        let mut data = Vec::with_capacity(self.frame_count() * count);
        for k in 0..self.frame_count() {
            let frame = self.frame(k);
            for (old, new) in self.joints.iter().zip(&joints) {
                let values = &frame[old.first_channel..old.first_channel + old.channels.len()];
                let mut q = DQuat::IDENTITY;
                for (c, &v) in old.channels.iter().zip(values) {
                    match c {
                        Channel::Position(_) => data.push(v),
                        Channel::Rotation(a) => {
                            q *= DQuat::from_axis_angle(a.unit(), v.to_radians())
                        }
                    }
                }
                if new
                    .channels
                    .iter()
                    .any(|c| matches!(c, Channel::Rotation(_)))
                {
                    data.extend(order.decompose(q).map(f64::to_degrees));
                }
            }
        }
        // The joints and data were built consistently, so this cannot fail.
        Bvh::new(joints, self.frame_time, data).unwrap_or_else(|_| self.clone())
    }

    /// The BVH file text of this motion. Numbers use Rust's shortest round-trip form, so
    /// reading the text back gives the same values bit for bit.
    pub fn to_bvh_string(&self) -> String {
        let mut out = String::from("HIERARCHY\n");
        let children: Vec<Vec<usize>> = (0..self.joints.len())
            .map(|i| {
                (0..self.joints.len())
                    .filter(|&c| self.joints[c].parent == Some(i))
                    .collect()
            })
            .collect();
        // Iterative depth-first writing: (joint, entering?).
        for root in (0..self.joints.len()).filter(|&j| self.joints[j].parent.is_none()) {
            let mut stack = vec![(root, true, 0usize)];
            while let Some((j, enter, depth)) = stack.pop() {
                let pad = "\t".repeat(depth);
                let joint = &self.joints[j];
                if enter {
                    let kind = if depth == 0 { "ROOT" } else { "JOINT" };
                    let o = joint.offset;
                    let _ = writeln!(out, "{pad}{kind} {}\n{pad}{{", joint.name);
                    let _ = writeln!(out, "{pad}\tOFFSET {} {} {}", o.x, o.y, o.z);
                    let _ = write!(out, "{pad}\tCHANNELS {}", joint.channels.len());
                    for c in &joint.channels {
                        let _ = write!(out, " {c}");
                    }
                    out.push('\n');
                    stack.push((j, false, depth));
                    for &c in children[j].iter().rev() {
                        stack.push((c, true, depth + 1));
                    }
                } else {
                    for e in &joint.end_sites {
                        let _ = writeln!(
                            out,
                            "{pad}\tEnd Site\n{pad}\t{{\n{pad}\t\tOFFSET {} {} {}\n{pad}\t}}",
                            e.x, e.y, e.z
                        );
                    }
                    let _ = writeln!(out, "{pad}}}");
                }
            }
        }
        let _ = writeln!(
            out,
            "MOTION\nFrames: {}\nFrame Time: {}",
            self.frame_count(),
            self.frame_time
        );
        for k in 0..self.frame_count() {
            let mut first = true;
            for v in self.frame(k) {
                if !first {
                    out.push(' ');
                }
                first = false;
                let _ = write!(out, "{v}");
            }
            out.push('\n');
        }
        out
    }

    /// The BVH's own channels as a troupe sequence: one track per channel, named
    /// `JOINT.Xrotation` etc., with rotations in radians and positions multiplied by
    /// `scale` (file units to metres). Metadata records `rate`, `source` and `bvh_scale`.
    pub fn to_channel_sequence(&self, name: &str, scale: f64) -> Result<Sequence> {
        let mut seq = Sequence::new(name);
        seq.meta
            .insert("rate".into(), format!("{}", 1.0 / self.frame_time));
        seq.meta.insert("source".into(), "bvh".into());
        seq.meta.insert("bvh_scale".into(), format!("{scale}"));
        for j in &self.joints {
            for (i, c) in j.channels.iter().enumerate() {
                // Rotations are unwrapped (±360° jumps removed) so that tools that filter
                // or blend see a continuous curve; the rotations are the same.
                let mut last: Option<f64> = None;
                let keys = (0..self.frame_count())
                    .map(|k| {
                        let v = self.frame(k)[j.first_channel + i];
                        let v = match c {
                            Channel::Position(_) => v * scale,
                            Channel::Rotation(_) => {
                                let mut r = v.to_radians();
                                if let Some(p) = last {
                                    r -= std::f64::consts::TAU
                                        * ((r - p) / std::f64::consts::TAU).round();
                                }
                                last = Some(r);
                                r
                            }
                        };
                        Key::new(k as f64 * self.frame_time, v)
                    })
                    .collect();
                seq.add_track(Track::new(format!("{}.{c}", j.name), keys)?)?;
            }
        }
        Ok(seq)
    }

    /// The BVH motion of a channel sequence made by [`Bvh::to_channel_sequence`] (perhaps
    /// edited since) on this hierarchy: frames every `seq.frame_time()` from the
    /// sequence's start to its end; positions are divided by `scale`. A channel without a
    /// track keeps this motion's value at the same frame (its last frame past the end).
    pub fn with_channel_sequence(&self, seq: &Sequence, scale: f64) -> Result<Bvh> {
        let ft = seq.frame_time();
        let n = (seq.duration() / ft).round() as usize + 1;
        if n > 10_000_000 {
            return Err(Error::Invalid(format!("{n} frames is too many for a BVH")));
        }
        let mut data = Vec::with_capacity(n * self.channel_count);
        let tracks: Vec<Option<&Track>> = self
            .joints
            .iter()
            .flat_map(|j| {
                j.channels
                    .iter()
                    .map(move |c| seq.track(&format!("{}.{c}", j.name)))
            })
            .collect();
        let kinds: Vec<Channel> = self
            .joints
            .iter()
            .flat_map(|j| j.channels.clone())
            .collect();
        let mut cursors = vec![0usize; tracks.len()];
        for k in 0..n {
            let t = seq.start() + k as f64 * ft;
            for (c, track) in tracks.iter().enumerate() {
                let v = match track {
                    Some(tr) => match kinds[c] {
                        Channel::Position(_) => tr.value_at(t, &mut cursors[c]) / scale,
                        Channel::Rotation(_) => tr.value_at(t, &mut cursors[c]).to_degrees(),
                    },
                    None if self.frame_count() > 0 => self.frame(k.min(self.frame_count() - 1))[c],
                    None => 0.0,
                };
                data.push(v);
            }
        }
        Bvh::new(self.joints.clone(), ft, data)
    }
}

/// Reads a BVH file (bytes that are not UTF-8 are replaced, as names are all that could
/// hold them).
pub fn read_bvh(path: impl AsRef<Path>) -> Result<Bvh> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_bvh(
        &String::from_utf8_lossy(&bytes),
        &path.display().to_string(),
    )
}

/// Writes a BVH file.
pub fn write_bvh(path: impl AsRef<Path>, bvh: &Bvh) -> Result<()> {
    let path = path.as_ref();
    std::fs::write(path, bvh.to_bvh_string()).map_err(|e| Error::io(path, e))
}

/// Parses BVH text; `file` names the source in errors.
pub fn parse_bvh(text: &str, file: &str) -> Result<Bvh> {
    let err = |line: usize, message: String| Error::Parse {
        file: file.to_string(),
        line,
        message,
    };
    let lines: Vec<&str> = text.lines().collect();

    // HIERARCHY section, as tokens with their line numbers, up to MOTION.
    let mut tokens: Vec<(usize, &str)> = Vec::new();
    let mut motion_line = None;
    for (i, l) in lines.iter().enumerate() {
        let mut words = l.split_whitespace().peekable();
        if words.peek() == Some(&"MOTION") {
            motion_line = Some(i);
            break;
        }
        tokens.extend(words.map(|w| (i + 1, w)));
    }
    let last_line = lines.len().max(1);
    let mut toks = tokens.into_iter().peekable();
    match toks.next() {
        Some((_, "HIERARCHY")) => {}
        Some((n, t)) => return Err(err(n, format!("expected `HIERARCHY`, found `{t}`"))),
        None => return Err(err(1, "empty file: expected `HIERARCHY`".into())),
    }

    let mut joints: Vec<BvhJoint> = Vec::new();
    // Open blocks: Some(joint) for a joint, None for an End Site.
    let mut stack: Vec<Option<usize>> = Vec::new();
    let mut channel_count = 0usize;
    let mut pending: Option<(usize, Option<usize>, String)> = None; // a JOINT/ROOT/End Site awaiting `{`
    let number = |n: usize, s: &str, what: &str| -> Result<f64> {
        s.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| err(n, format!("{what}: `{s}` is not a finite number")))
    };
    while let Some((n, tok)) = toks.next() {
        if let Some((pn, parent, name)) = pending.take() {
            if tok != "{" {
                return Err(err(
                    n,
                    format!("expected `{{` after `{name}`, found `{tok}`"),
                ));
            }
            if name == "End Site" {
                stack.push(None);
                continue;
            }
            let _ = pn;
            joints.push(BvhJoint {
                name,
                parent,
                offset: DVec3::ZERO,
                channels: Vec::new(),
                first_channel: channel_count,
                end_sites: Vec::new(),
            });
            stack.push(Some(joints.len() - 1));
            continue;
        }
        match tok {
            "ROOT" | "JOINT" => {
                if tok == "ROOT" && !stack.is_empty() {
                    return Err(err(n, "`ROOT` inside another joint".into()));
                }
                if tok == "JOINT" && !matches!(stack.last(), Some(Some(_))) {
                    return Err(err(n, "`JOINT` outside a joint block".into()));
                }
                let name = match toks.next() {
                    Some((m, name)) if m == n && name != "{" => name.to_string(),
                    _ => return Err(err(n, format!("`{tok}` needs a name"))),
                };
                if joints.iter().any(|j| j.name == name) {
                    tracing::warn!("{file}:{n}: joint name `{name}` is used twice");
                }
                pending = Some((n, stack.last().copied().flatten(), name));
            }
            "End" => {
                match toks.next() {
                    Some((_, "Site")) => {}
                    _ => return Err(err(n, "expected `End Site`".into())),
                }
                if !matches!(stack.last(), Some(Some(_))) {
                    return Err(err(n, "`End Site` outside a joint block".into()));
                }
                pending = Some((n, None, "End Site".into()));
            }
            "OFFSET" => {
                let mut v = [0.0; 3];
                for x in &mut v {
                    let (m, s) = toks
                        .next()
                        .filter(|(m, _)| *m == n)
                        .ok_or_else(|| err(n, "`OFFSET` needs three numbers".into()))?;
                    *x = number(m, s, "OFFSET")?;
                }
                let offset = DVec3::from_array(v);
                match stack.last() {
                    Some(Some(j)) => joints[*j].offset = offset,
                    Some(None) => {
                        let owner = stack.iter().rev().find_map(|s| *s);
                        if let Some(j) = owner {
                            joints[j].end_sites.push(offset);
                        }
                    }
                    None => return Err(err(n, "`OFFSET` outside a block".into())),
                }
            }
            "CHANNELS" => {
                let Some(Some(j)) = stack.last().copied() else {
                    return Err(err(n, "`CHANNELS` outside a joint block".into()));
                };
                let (m, s) = toks
                    .next()
                    .filter(|(m, _)| *m == n)
                    .ok_or_else(|| err(n, "`CHANNELS` needs a count".into()))?;
                let count: usize = s
                    .parse()
                    .ok()
                    .filter(|c| *c <= MAX_JOINT_CHANNELS)
                    .ok_or_else(|| {
                        err(
                            m,
                            format!("channel count `{s}` is not a number from 0 to {MAX_JOINT_CHANNELS}"),
                        )
                    })?;
                if !joints[j].channels.is_empty() {
                    return Err(err(n, format!("joint `{}` has two CHANNELS lines", joints[j].name)));
                }
                let mut channels = Vec::with_capacity(count);
                for _ in 0..count {
                    let (m, s) = toks.next().filter(|(m, _)| *m == n).ok_or_else(|| {
                        err(n, format!("`CHANNELS {count}` lists fewer than {count} channels"))
                    })?;
                    let c = Channel::parse(s)
                        .ok_or_else(|| err(m, format!("unknown channel `{s}`")))?;
                    if channels.contains(&c) {
                        return Err(err(m, format!("channel `{s}` listed twice")));
                    }
                    channels.push(c);
                }
                if let Some((m, extra)) = toks.peek().copied() {
                    if m == n {
                        return Err(err(
                            n,
                            format!("`CHANNELS {count}` lists more than {count} channels (`{extra}`)"),
                        ));
                    }
                }
                joints[j].first_channel = channel_count;
                channel_count += count;
                joints[j].channels = channels;
            }
            "}" => {
                if stack.pop().is_none() {
                    return Err(err(n, "unmatched `}`".into()));
                }
            }
            other => {
                return Err(err(
                    n,
                    format!("unexpected `{other}` (expected ROOT, JOINT, End Site, OFFSET, CHANNELS, `}}` or MOTION)"),
                ))
            }
        }
    }
    if let Some((n, _, name)) = pending {
        return Err(err(n, format!("`{name}` has no block")));
    }
    if !stack.is_empty() {
        return Err(err(
            motion_line.map_or(last_line, |m| m + 1),
            format!("{} block(s) not closed before MOTION", stack.len()),
        ));
    }
    if joints.is_empty() {
        return Err(err(
            motion_line.map_or(last_line, |m| m + 1),
            "no ROOT in HIERARCHY".into(),
        ));
    }
    let Some(motion) = motion_line else {
        return Err(err(last_line, "no MOTION section".into()));
    };

    // MOTION header: `Frames: N` and `Frame Time: T` (the number may follow on its own).
    let mut rest = lines
        .iter()
        .enumerate()
        .skip(motion + 1)
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let after_motion = motion + 1;
    let (n, frames_line) = rest
        .next()
        .ok_or_else(|| err(after_motion, "expected `Frames: N` after MOTION".into()))?;
    let declared: u64 = frames_line
        .strip_prefix("Frames:")
        .map(str::trim)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| err(n, format!("expected `Frames: N`, found `{frames_line}`")))?;
    let (n, time_line) = rest
        .next()
        .ok_or_else(|| err(n, "expected `Frame Time: SECONDS`".into()))?;
    let frame_time = time_line
        .strip_prefix("Frame")
        .map(str::trim_start)
        .and_then(|s| s.strip_prefix("Time:"))
        .map(str::trim)
        .and_then(|s| s.parse::<f64>().ok())
        .filter(|t| t.is_finite() && *t > 0.0)
        .ok_or_else(|| {
            err(
                n,
                format!("expected `Frame Time: SECONDS` (positive), found `{time_line}`"),
            )
        })?;

    // Rows: never preallocate from the declared count, only from the text itself.
    let mut data = Vec::with_capacity(lines.len().saturating_sub(motion) * channel_count);
    let mut rows = 0usize;
    for (n, line) in rest {
        let mut count = 0;
        for s in line.split_whitespace() {
            count += 1;
            if count > channel_count {
                break;
            }
            data.push(number(n, s, "frame value")?);
        }
        if count != channel_count {
            return Err(err(
                n,
                format!(
                    "frame {} has {} values, the hierarchy declares {channel_count} channels",
                    rows + 1,
                    if count > channel_count {
                        format!("more than {channel_count}")
                    } else {
                        count.to_string()
                    }
                ),
            ));
        }
        rows += 1;
    }
    if rows as u64 != declared {
        tracing::warn!(
            "{file}: `Frames: {declared}` but {rows} data rows follow; using the {rows} rows"
        );
    }
    Bvh::new(joints, frame_time, data).map_err(|e| err(motion + 1, e.to_string()))
}

/// Writes a rig's motion (e.g. a troupe recording, via [`crate::gltf::Rig::from_sequence`])
/// as BVH: every joint gets three rotation channels in `order` (the root also three
/// position channels), offsets and positions are in file units of `units_per_metre`
/// (100 for centimetres), frames every `frame_time` seconds.
pub fn from_rig(
    rig: &crate::gltf::Rig,
    frame_time: f64,
    order: RotationOrder,
    units_per_metre: f64,
) -> Result<Bvh> {
    let root_moves = rig.moving.first() == Some(&0);
    let joints: Vec<BvhJoint> = (0..rig.names.len())
        .map(|j| {
            let mut channels = Vec::new();
            if j == 0 {
                channels.extend([Axis::X, Axis::Y, Axis::Z].map(Channel::Position));
            }
            channels.extend(order.0.map(Channel::Rotation));
            let leaf = !rig.parents.contains(&Some(j));
            BvhJoint {
                name: rig.names[j].clone(),
                parent: rig.parents[j],
                offset: rig.rest[j].translation * units_per_metre,
                channels,
                first_channel: 0,
                // BVH leaves end in an End Site; a zero one keeps the hierarchy valid.
                end_sites: if leaf { vec![DVec3::ZERO] } else { Vec::new() },
            }
        })
        .collect();
    let mut data = Vec::with_capacity(rig.rotations.len() * (rig.names.len() * 3 + 3));
    for (k, rotations) in rig.rotations.iter().enumerate() {
        let root = if root_moves {
            rig.translations[k][0]
        } else {
            rig.rest[0].translation
        };
        data.extend((root * units_per_metre).to_array());
        for q in rotations {
            data.extend(order.decompose(*q).map(f64::to_degrees));
        }
    }
    Bvh::new(joints, frame_time, data)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data(name: &str) -> String {
        format!(
            "{}/../../../shared/data/bvh/{name}",
            env!("CARGO_MANIFEST_DIR")
        )
    }

    /// Every BVH file shipped in `../shared/data/bvh`.
    pub(crate) fn shared_files() -> Vec<std::path::PathBuf> {
        let dir = data("");
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{dir}: {e}"))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "bvh"))
            .collect();
        files.sort();
        files
    }

    #[test]
    fn every_shared_file_imports_with_the_documented_shape() {
        // (file, joints, end sites, frames)
        let expected = [
            ("pybvhrepo_bvh_example.bvh", 24, 5, 75),
            ("pybvhrepo_bvh_test3.bvh", 60, 13, 100),
            ("pybvhrepo_cmu_12_01_walk.bvh", 31, 7, 524),
            ("pybvhrepo_rotation_first_root.bvh", 4, 2, 4),
            ("pymo_AV_8Walk_Meredith_HVHA_Rep1.bvh", 23, 7, 1064),
        ];
        let files = shared_files();
        assert_eq!(files.len(), expected.len());
        for (name, joints, ends, frames) in expected {
            let b = read_bvh(data(name)).unwrap();
            assert_eq!(b.joints().len(), joints, "{name}");
            let e: usize = b.joints().iter().map(|j| j.end_sites.len()).sum();
            assert_eq!(e, ends, "{name}");
            assert_eq!(b.frame_count(), frames, "{name}");
            for k in [0, frames - 1] {
                assert!(b.joint_positions(k).iter().all(|p| p.is_finite()));
            }
        }
    }

    #[test]
    fn rotation_before_position_and_root_offset_replacement() {
        let b = read_bvh(data("pybvhrepo_rotation_first_root.bvh")).unwrap();
        let root = &b.joints()[0];
        assert_eq!(root.channels[0], Channel::Rotation(Axis::Z));
        assert_eq!(root.channels[3], Channel::Position(Axis::X));
        let f = b.frame(0).to_vec();
        let p = b.joint_positions(0);
        assert_eq!(p[0], DVec3::new(f[3], f[4], f[5]));
        // The PyMO file's root OFFSET is replaced by its absolute position channels.
        let m = read_bvh(data("pymo_AV_8Walk_Meredith_HVHA_Rep1.bvh")).unwrap();
        assert_ne!(m.joints()[0].offset, DVec3::ZERO);
        let f = m.frame(10);
        assert_eq!(m.joint_positions(10)[0], DVec3::new(f[0], f[1], f[2]));
    }

    #[test]
    fn intrinsic_composition_in_listed_order() {
        let text = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT b\n{\nOFFSET 0 1 0\nCHANNELS 0\n}\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n90 90 0\n";
        let b = parse_bvh(text, "t").unwrap();
        // Rz(90)·Rx(90) applied to (0,1,0): Rx maps Y to Z, Rz leaves Z.
        let p = b.joint_positions(0)[1];
        assert!((p - DVec3::Z).length() < 1e-12, "{p}");
    }

    #[test]
    fn every_order_decomposes_and_composes_back() {
        let q = DQuat::from_axis_angle(DVec3::new(0.3, -0.5, 0.8).normalize(), 1.9);
        for o in RotationOrder::ALL {
            let back = o.compose(o.decompose(q));
            assert!(back.dot(q).abs() > 1.0 - 1e-14, "{o}");
            assert_eq!(o.to_string().parse::<RotationOrder>().unwrap(), o);
        }
        assert!("XXY".parse::<RotationOrder>().is_err());
    }

    /// Maximum distance between the global joint positions of two motions of one skeleton.
    pub(crate) fn max_position_difference(a: &Bvh, b: &Bvh) -> f64 {
        assert_eq!(a.frame_count(), b.frame_count());
        let mut worst: f64 = 0.0;
        for k in 0..a.frame_count() {
            for (p, q) in a.joint_positions(k).iter().zip(b.joint_positions(k)) {
                worst = worst.max((*p - q).length());
            }
        }
        worst
    }

    #[test]
    fn export_in_every_order_and_back_keeps_every_global_position() {
        for path in shared_files() {
            let original = read_bvh(&path).unwrap();
            let text = original.to_bvh_string();
            assert_eq!(parse_bvh(&text, "again").unwrap(), original, "{path:?}");
            for order in RotationOrder::ALL {
                let there =
                    parse_bvh(&original.with_rotation_order(order).to_bvh_string(), "x").unwrap();
                assert!(max_position_difference(&original, &there) < 1e-6);
                let first = original.joints()[0]
                    .channels
                    .iter()
                    .filter_map(|c| match c {
                        Channel::Rotation(a) => Some(*a),
                        _ => None,
                    })
                    .collect::<Vec<_>>();
                let back_order = RotationOrder([first[0], first[1], first[2]]);
                let back =
                    parse_bvh(&there.with_rotation_order(back_order).to_bvh_string(), "y").unwrap();
                let d = max_position_difference(&original, &back);
                assert!(d < 1e-6, "{path:?} via {order}: {d}");
            }
        }
    }

    #[test]
    fn channel_sequences_round_trip_through_troupe_units() {
        let b = read_bvh(data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        let seq = b.to_channel_sequence("walk", 0.01).unwrap();
        assert_eq!(seq.tracks().len(), b.channel_count());
        assert!((seq.frame_time() - b.frame_time()).abs() < 1e-12);
        let back = b.with_channel_sequence(&seq, 0.01).unwrap();
        assert_eq!(back.frame_count(), b.frame_count());
        assert!(max_position_difference(&b, &back) < 1e-6);
    }

    #[test]
    fn malformed_files_name_the_line() {
        let ok = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5 6\n";
        assert_eq!(parse_bvh(ok, "f").unwrap().frame_count(), 2);
        let cases = [
            ("", 1, "HIERARCHY"),
            ("HIERARCHY\nROOT a\n{\nOFFSET 0 x 0\n", 4, "not a finite"),
            (
                "HIERARCHY\nROOT a\n{\nCHANNELS 99999999999 X\n}\nMOTION\n",
                4,
                "channel count",
            ),
            (
                "HIERARCHY\nROOT a\n{\nCHANNELS 2 Xposition\n}\n",
                4,
                "fewer",
            ),
            (
                "HIERARCHY\nROOT a\n{\nCHANNELS 1 Wrotation\n}\n",
                4,
                "unknown channel",
            ),
            ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\n", 4, "not closed"),
            (&ok.replace("4 5 6", "4 5"), 11, "2 values"),
            (&ok.replace("4 5 6", "4 5 6 7"), 11, "more than 3"),
            (&ok.replace("4 5 6", "4 nan 6"), 11, "not a finite"),
            (&ok.replace("0.1", "0"), 9, "Frame Time"),
            (&ok.replace("Frames: 2", "Frames: two"), 8, "Frames"),
            (
                &ok.replace("MOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5 6\n", ""),
                6,
                "MOTION",
            ),
        ];
        for (text, line, needle) in cases {
            match parse_bvh(text, "f.bvh") {
                Err(Error::Parse {
                    file,
                    line: l,
                    message,
                }) => {
                    assert_eq!(file, "f.bvh");
                    assert_eq!(l, line, "{text:?}: {message}");
                    assert!(message.contains(needle), "{text:?}: {message}");
                }
                other => panic!("{text:?}: {other:?}"),
            }
        }
        // A wrong `Frames:` count is a warning; the rows are used.
        let more = ok.replace("Frames: 2", "Frames: 99999999999");
        assert_eq!(parse_bvh(&more, "f").unwrap().frame_count(), 2);
    }

    #[test]
    fn a_troupe_motion_exported_as_bvh_keeps_every_joint_position() {
        use crate::gltf::{fk_positions, Rig};
        let t = troupe_body::template::template("adult").unwrap();
        let skel = t.instantiate(t.default_params()).unwrap();
        let mut seq = Sequence::new("motion");
        seq.meta.insert("rate".into(), "50".into());
        for (d, dof) in skel.dofs().iter().enumerate() {
            let keys = (0..5)
                .map(|k| {
                    let v = ((d * 7 + k * 3) as f64).sin() * 0.4;
                    Key::new(k as f64 * 0.2, v.clamp(dof.min, dof.max))
                })
                .collect();
            seq.add_track(Track::new(dof.name.clone(), keys).unwrap())
                .unwrap();
        }
        let rig = Rig::from_sequence(&skel, &seq).unwrap();
        let order: RotationOrder = "ZXY".parse().unwrap();
        let bvh = from_rig(&rig, seq.frame_time(), order, 100.0).unwrap();
        let text = bvh.to_bvh_string();
        let back = parse_bvh(&text, "export.bvh").unwrap();
        // Read back onto the same body, the motion gives the same postures.
        assert!(crate::retarget::is_troupe_rig(&skel, &back));
        let replay = crate::retarget::troupe_named_motion(&skel, &back, "replay").unwrap();
        for k in [0, 13, 40] {
            let time = k as f64 * seq.frame_time();
            let q: Vec<f64> = skel
                .dofs()
                .iter()
                .map(|d| seq.track(&d.name).unwrap().value(time))
                .collect();
            let expected = fk_positions(&skel, &q);
            let q2: Vec<f64> = skel
                .dofs()
                .iter()
                .map(|d| replay.track(&d.name).unwrap().value(time))
                .collect();
            for (e, r) in expected.iter().zip(fk_positions(&skel, &q2)) {
                assert!(
                    (*e - r).length() < 1e-6,
                    "replayed posture at frame {k}: {e} vs {r}"
                );
            }
            let got = back.joint_positions(k);
            for (j, (e, g)) in expected.iter().zip(&got).enumerate() {
                assert!(
                    (*e - *g / 100.0).length() < 1e-6,
                    "frame {k} joint {}: {e} vs {}",
                    skel.joints()[j].name,
                    *g / 100.0
                );
            }
        }
    }
}
