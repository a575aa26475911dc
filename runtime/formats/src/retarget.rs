//! Retargeting: plays a BVH motion on a troupe skeleton by mapping BVH joints onto
//! template joints and converting their rest-pose differences.
//!
//! Method (per frame): every mapped troupe joint takes the **global** orientation of its
//! BVH joint, corrected by a constant rotation `C_j` that turns the troupe bone's rest
//! direction (towards its first mapped descendant) onto the BVH bone's rest direction.
//! So a BVH in T-pose puts troupe's arms (which hang down at rest) in T-pose, and every
//! mapped bone points where the BVH bone points. BVH joints that are not mapped fold into
//! their mapped descendants (global orientations are used); unmapped troupe joints keep
//! zero DOFs. Each mapped joint's local rotation is then split onto its DOFs (Euler
//! decomposition in the DOFs' axis order; a joint with fewer than three rotation DOFs keeps
//! the leading angles — the swing — and drops the rest).
//!
//! Axes: the BVH is first turned into troupe's axes (Y up, facing +Z, left +X): its
//! skeleton's up is the rest direction from the root to the head, its left the side of the
//! left limbs; and when the frames stand that skeleton along another axis throughout (a
//! Z-up world), the world is stood upright too (`Axes`).
//!
//! Root translation is scaled by troupe's leg length over the BVH's, both measured along
//! the bones from the root to the ankles (a rest pose's splayed legs do not shorten them),
//! and the BVH's lowest ankle over the clip stands at troupe's rest ankle height, which
//! keeps the feet on the floor for any body size (`Ground`).

use crate::bvh::{read_bvh, Axis, Bvh, RotationOrder};
use crate::error::{Error, Result};
use glam::{DMat3, DQuat, DVec3};
use std::path::Path;
use troupe_body::kinematics::{forward_kinematics, solve_joint_angles};
use troupe_body::skeleton::{DofKind, Skeleton};
use troupe_body::transform::Transform;
use troupe_motion::sequence::{Key, Sequence, Track};

/// A BVH-joint → troupe-joint name map, in order (earlier entries win as bone targets).
#[derive(Clone, Debug, PartialEq)]
pub struct RetargetMap {
    /// A short name for metadata (`cmu`, `mixamo`, or the file it came from).
    pub name: String,
    /// `(BVH joint, troupe joint)` pairs.
    pub pairs: Vec<(String, String)>,
}

/// Limb joints: CMU and Mixamo rigs name them alike.
const LIMBS: &[(&str, &str)] = &[
    ("LeftUpLeg", "l_hip"),
    ("LeftLeg", "l_knee"),
    ("LeftFoot", "l_ankle"),
    ("LeftToeBase", "l_metatarsal"),
    ("RightUpLeg", "r_hip"),
    ("RightLeg", "r_knee"),
    ("RightFoot", "r_ankle"),
    ("RightToeBase", "r_metatarsal"),
    ("LeftShoulder", "l_sternoclavicular"),
    ("LeftArm", "l_shoulder"),
    ("LeftForeArm", "l_elbow"),
    ("LeftHand", "l_wrist"),
    ("RightShoulder", "r_sternoclavicular"),
    ("RightArm", "r_shoulder"),
    ("RightForeArm", "r_elbow"),
    ("RightHand", "r_wrist"),
];

/// The CMU spine (the limbs follow in [`LIMBS`]).
const CMU_SPINE: &[(&str, &str)] = &[
    ("Hips", "HumanoidRoot"),
    ("LowerBack", "vl5"),
    ("Spine", "vt12"),
    ("Spine1", "vt1"),
    ("Neck", "vc4"),
    ("Head", "skullbase"),
];

/// The Mixamo spine (the limbs follow in [`LIMBS`]).
const MIXAMO_SPINE: &[(&str, &str)] = &[
    ("Hips", "HumanoidRoot"),
    ("Spine", "vl5"),
    ("Spine1", "vt12"),
    ("Spine2", "vt1"),
    ("Neck", "vc4"),
    ("Head", "skullbase"),
];

impl RetargetMap {
    fn builtin(name: &str, spine: &[(&str, &str)]) -> RetargetMap {
        RetargetMap {
            name: name.into(),
            pairs: spine
                .iter()
                .chain(LIMBS)
                .map(|(a, b)| (a.to_string(), b.to_string()))
                .collect(),
        }
    }

    /// The map for CMU motion-capture BVH files (`LowerBack`, `LeftUpLeg`, …).
    pub fn cmu() -> RetargetMap {
        Self::builtin("cmu", CMU_SPINE)
    }

    /// The map for Mixamo rigs (`Spine`, `Spine1`, `Spine2`, …; a `mixamorig:` prefix on
    /// the BVH names is ignored when matching).
    pub fn mixamo() -> RetargetMap {
        Self::builtin("mixamo", MIXAMO_SPINE)
    }

    /// The built-in map that matches most of the BVH's joint names.
    pub fn detect(bvh: &Bvh) -> RetargetMap {
        let score = |m: &RetargetMap| {
            m.pairs
                .iter()
                .filter(|(b, _)| find_joint(bvh, b).is_some())
                .count()
        };
        let (cmu, mixamo) = (Self::cmu(), Self::mixamo());
        if score(&mixamo) > score(&cmu) {
            mixamo
        } else {
            cmu
        }
    }

    /// Parses a user map: one `BVH_JOINT TROUPE_JOINT` pair per line, `#` comments.
    pub fn parse(text: &str, file: &str) -> Result<RetargetMap> {
        let mut pairs = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("").trim();
            if line.is_empty() {
                continue;
            }
            let words: Vec<&str> = line.split_whitespace().collect();
            if words.len() != 2 {
                return Err(Error::Parse {
                    file: file.into(),
                    line: i + 1,
                    message: format!("expected `BVH_JOINT TROUPE_JOINT`, found `{line}`"),
                });
            }
            pairs.push((words[0].to_string(), words[1].to_string()));
        }
        Ok(RetargetMap {
            name: file.into(),
            pairs,
        })
    }

    /// Reads a user map file.
    pub fn read(path: impl AsRef<Path>) -> Result<RetargetMap> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::parse(&text, &path.display().to_string())
    }
}

/// A BVH joint by name, ignoring a `prefix:` (as Mixamo's `mixamorig:`) on either side.
fn find_joint(bvh: &Bvh, name: &str) -> Option<usize> {
    let bare = |s: &str| s.rsplit(':').next().unwrap_or(s).to_string();
    let want = bare(name);
    bvh.joints().iter().position(|j| bare(&j.name) == want)
}

/// One mapped joint, resolved.
struct Bound {
    bvh: usize,
    troupe: usize,
    /// Nearest mapped troupe ancestor (index into the bound list).
    parent: Option<usize>,
    /// Rest-pose correction `C_j`.
    correction: DQuat,
}

/// The rotation that takes `from` onto `to` by the shortest arc (identity if either is
/// too short to have a direction).
fn arc(from: DVec3, to: DVec3) -> DQuat {
    if from.length_squared() < 1e-18 || to.length_squared() < 1e-18 {
        return DQuat::IDENTITY;
    }
    DQuat::from_rotation_arc(from.normalize(), to.normalize())
}

fn is_ancestor(parents: impl Fn(usize) -> Option<usize>, a: usize, mut j: usize) -> bool {
    while let Some(p) = parents(j) {
        if p == a {
            return true;
        }
        j = p;
    }
    false
}

/// Principal axis and sign of a DOF axis (troupe's axes are ±X, ±Y or ±Z).
fn principal(axis: DVec3) -> (Axis, f64) {
    let a = axis.abs();
    let (ax, c) = if a.x >= a.y && a.x >= a.z {
        (Axis::X, axis.x)
    } else if a.y >= a.z {
        (Axis::Y, axis.y)
    } else {
        (Axis::Z, axis.z)
    };
    (ax, c.signum())
}

/// How closely a rest pose's up direction (root to head) must follow one axis — a cosine,
/// about 37° — for that axis to be the BVH skeleton's up.
const REST_UP_COS: f64 = 0.8;
/// How closely the mean up direction over a clip must follow another axis than the rest
/// pose's up, and how consistent it must be (the length of the mean of unit vectors),
/// for the motion's world to count as turned: a Y-up skeleton that the file's frames
/// stand along Z. Strict, so that a clip that only partly lies down keeps the rest up.
const WORLD_UP_COS: f64 = 0.9;
/// See [`WORLD_UP_COS`].
const WORLD_UP_CONSISTENCY: f64 = 0.8;
/// A world is not turned when the lowest joint's height along the skeleton's own up moves
/// over the clip less than this fraction of how it moves along the world's candidate up.
const FLOOR_STEADIER: f64 = 0.5;

/// The signed principal axis (±X, ±Y or ±Z) nearest `v`, if the cosine between them is at
/// least `min_cos`.
fn nearest_axis(v: DVec3, min_cos: f64) -> Option<DVec3> {
    if v.length_squared() < 1e-18 {
        return None;
    }
    let n = v.normalize();
    let (ax, _) = principal(n);
    let c = n[ax.index()];
    (c.abs() >= min_cos).then(|| ax.unit() * c.signum())
}

/// `+X`, `-Z`, …: the name of a signed principal axis.
fn axis_label(v: DVec3) -> String {
    let (ax, sign) = principal(v);
    let letter = ["X", "Y", "Z"][ax.index()];
    format!("{}{letter}", if sign < 0.0 { '-' } else { '+' })
}

/// The shortest turn of the principal axis `up` onto +Y (a half turn about Z for −Y, so
/// that the facing is kept).
fn upright(up: DVec3) -> DQuat {
    if up.dot(DVec3::Y) < -0.5 {
        DQuat::from_rotation_z(std::f64::consts::PI)
    } else {
        DQuat::from_rotation_arc(up, DVec3::Y)
    }
}

/// The rotation taking a body whose up is the principal axis `up` and whose left side lies
/// towards `lateral` onto troupe's axes (up +Y, left +X, facing +Z); without a usable
/// `lateral`, the shortest turn of `up` onto +Y.
fn to_troupe_axes(up: DVec3, lateral: DVec3) -> DQuat {
    let flat = lateral - up * lateral.dot(up);
    if flat.length() <= 0.1 * lateral.length() {
        return upright(up);
    }
    match nearest_axis(flat, 0.0) {
        // Columns: where troupe's X, Y, Z lie in the file; its inverse turns the file.
        Some(left) => DQuat::from_mat3(&DMat3::from_cols(left, up, left.cross(up))).inverse(),
        None => upright(up),
    }
}

/// The mapped joints that tell a body's up and left, as BVH joint indices.
struct Landmarks {
    /// `(from, to)`: the root and the mapped joint highest above it in troupe's rest pose
    /// (the head), or, when nothing mapped is well above the root, the lowest mapped joint
    /// and the root.
    up: (usize, usize),
    /// Mapped joints on troupe's left side (+X) at rest.
    left: Vec<usize>,
    /// Mapped joints on troupe's right side at rest.
    right: Vec<usize>,
}

impl Landmarks {
    /// The landmarks of `pairs` (troupe joint, BVH joint, map order), by troupe's rest pose.
    fn find(pairs: &[(usize, usize, usize)], root: usize, rest: &[Transform]) -> Option<Self> {
        let root_b = pairs.iter().find(|p| p.0 == root)?.1;
        let at = rest[root].translation;
        let height = |p: &&(usize, usize, usize)| rest[p.0].translation.y - at.y;
        let far = 0.1 * at.y.abs();
        let top = pairs
            .iter()
            .max_by(|a, b| height(a).total_cmp(&height(b)))?;
        let bottom = pairs
            .iter()
            .min_by(|a, b| height(a).total_cmp(&height(b)))?;
        let up = if height(&top) > far {
            (root_b, top.1)
        } else if -height(&bottom) > far {
            (bottom.1, root_b)
        } else {
            return None;
        };
        let side = |sign: f64| {
            pairs
                .iter()
                .filter(|p| sign * (rest[p.0].translation.x - at.x) > 0.02)
                .map(|p| p.1)
                .collect()
        };
        Some(Landmarks {
            up,
            left: side(1.0),
            right: side(-1.0),
        })
    }

    /// The body's up direction, given the joints' positions.
    fn up(&self, pos: impl Fn(usize) -> DVec3) -> DVec3 {
        pos(self.up.1) - pos(self.up.0)
    }

    /// From the mean of the right-side joints to that of the left (zero without both).
    fn lateral(&self, pos: impl Fn(usize) -> DVec3) -> DVec3 {
        if self.left.is_empty() || self.right.is_empty() {
            return DVec3::ZERO;
        }
        let mean = |js: &[usize]| js.iter().map(|&j| pos(j)).sum::<DVec3>() / js.len() as f64;
        mean(&self.left) - mean(&self.right)
    }
}

/// How a BVH's axes turn into troupe's (Y up, facing +Z, left +X). Files differ: CMU and
/// Mixamo share troupe's axes, others build their skeleton Z-up, and some pose a Y-up
/// skeleton standing along Z in every frame.
struct Axes {
    /// Turns the BVH skeleton's rest pose into troupe's axes: its up (root to head) onto
    /// +Y, its left side onto +X.
    skeleton: DQuat,
    /// Then turns the motion's world upright when the frames stand the body along another
    /// axis than its rest pose does; it then faces +Z at the first frame.
    world: DQuat,
}

impl Axes {
    /// Reads the axes from the rest pose and the frames; an error when the rest pose does
    /// not tell which way is up.
    fn detect(
        bvh: &Bvh,
        map: &RetargetMap,
        pairs: &[(usize, usize, usize)],
        root: usize,
        rest: &[Transform],
    ) -> Result<Axes> {
        let fail = |message: String| Error::Retarget {
            map: map.name.clone(),
            message,
        };
        let marks = Landmarks::find(pairs, root, rest).ok_or_else(|| {
            fail(
                "maps no joint well above or below the root, so cannot tell which way is up".into(),
            )
        })?;
        let bvh_rest = bvh.rest_positions();
        let up_rest = marks.up(|j| bvh_rest[j]);
        let up = nearest_axis(up_rest, REST_UP_COS).ok_or_else(|| {
            fail(format!(
                "cannot tell which axis is up: the rest pose's root-to-head direction \
                 ({:.3}, {:.3}, {:.3}) is near none of ±X, ±Y, ±Z",
                up_rest.x, up_rest.y, up_rest.z
            ))
        })?;
        let skeleton = to_troupe_axes(up, marks.lateral(|j| bvh_rest[j]));

        let mut g = vec![Transform::IDENTITY; bvh.joints().len()];
        let mut mean = DVec3::ZERO;
        for k in 0..bvh.frame_count() {
            bvh.global_transforms(k, &mut g);
            let v = skeleton * marks.up(|j| g[j].translation);
            if v.length_squared() > 1e-18 {
                mean += v.normalize();
            }
        }
        mean /= bvh.frame_count().max(1) as f64;
        // A body lying along an axis throughout (crawling, lying, swimming) points its
        // head along it as consistently as a turned world does: not turned when the
        // floor says otherwise, the lowest joint much steadier along the skeleton's own
        // up than along that axis (a clip that stays in place says nothing either way).
        let world = match nearest_axis(mean, WORLD_UP_COS) {
            Some(a)
                if mean.length() >= WORLD_UP_CONSISTENCY
                    && a != DVec3::Y
                    && floor_spread(bvh, skeleton, DVec3::Y, &mut g)
                        >= FLOOR_STEADIER * floor_spread(bvh, skeleton, a, &mut g) =>
            {
                let stand = upright(a);
                bvh.global_transforms(0, &mut g);
                let lateral = stand * skeleton * marks.lateral(|j| g[j].translation);
                let yaw = nearest_axis(DVec3::new(lateral.x, 0.0, lateral.z), 0.0)
                    .map_or(DQuat::IDENTITY, |l| {
                        DQuat::from_rotation_y(-f64::atan2(-l.z, l.x))
                    });
                yaw * stand
            }
            _ => DQuat::IDENTITY,
        };
        Ok(Axes { skeleton, world })
    }

    /// Turns a frame's global transforms (BVH world, BVH joint frames) into troupe's axes.
    fn turn(&self, globals: &mut [Transform]) {
        let whole = self.world * self.skeleton;
        let back = self.skeleton.inverse();
        for g in globals {
            g.rotation = whole * g.rotation * back;
            g.translation = whole * g.translation;
        }
    }

    /// The file's axis that becomes troupe's `axis`.
    fn file_axis(&self, axis: DVec3) -> String {
        axis_label((self.world * self.skeleton).inverse() * axis)
    }
}

/// How far the lowest joint's height along `axis` (in the skeleton's turned axes) moves
/// over the clip: little along the floor's normal. A body lying along an axis throughout
/// (crawling, lying, swimming) points its head along it as consistently as a turned world
/// does; its floor tells them apart.
fn floor_spread(bvh: &Bvh, skeleton: DQuat, axis: DVec3, g: &mut [Transform]) -> f64 {
    let (mut low, mut high) = (f64::INFINITY, f64::NEG_INFINITY);
    for k in 0..bvh.frame_count() {
        bvh.global_transforms(k, g);
        let lowest = g
            .iter()
            .map(|t| (skeleton * t.translation).dot(axis))
            .fold(f64::INFINITY, f64::min);
        low = low.min(lowest);
        high = high.max(lowest);
    }
    high - low
}

/// How BVH lengths scale onto troupe's and where the BVH body's floor is.
struct Ground {
    /// Metres of troupe per BVH unit.
    scale: f64,
    /// The BVH joint mapped onto troupe's root.
    root_bvh: usize,
    /// The BVH height (file units, troupe's axes) that stands on troupe's floor.
    bvh_floor: f64,
    /// The troupe height (metres) it stands at.
    troupe_floor: f64,
    /// troupe's mapped ankles, on whose lowest stance [`settle`] stands the root.
    ankles: Vec<usize>,
}

/// The length of the chain from joint `j` up to its ancestor `top` (`None` if `top` is
/// not an ancestor).
fn chain_length(
    parent: impl Fn(usize) -> Option<usize>,
    length: impl Fn(usize) -> f64,
    top: usize,
    mut j: usize,
) -> Option<f64> {
    let mut sum = 0.0;
    while j != top {
        sum += length(j);
        j = parent(j)?;
    }
    Some(sum)
}

impl Ground {
    /// Scale: the legs' length from the root down the chain to the ankles (the root's
    /// height above the hips plus the hip-to-ankle bone lengths), troupe's over the BVH's.
    /// The bone lengths, not the rest hip height, because a rest pose may splay or bend
    /// the legs (CMU's). Floor: the BVH's lowest ankle over the clip stands at troupe's
    /// rest ankle height, since a body of other feet has its ankles elsewhere above the
    /// soles ([`settle`] then makes it exact for troupe's own legs). Without mapped legs: the rest hip height over the lowest
    /// rest joint, and the file's y = 0 at troupe's lowest rest joint.
    fn measure(
        skeleton: &Skeleton,
        bvh: &Bvh,
        pairs: &[(usize, usize, usize)],
        root: usize,
        rest: &[Transform],
        bvh_rest: &[DVec3],
        axes: &Axes,
    ) -> Ground {
        let root_bvh = pairs.iter().find(|p| p.0 == root).map_or(0, |p| p.1);
        let bvh_of = |t: usize| pairs.iter().find(|p| p.0 == t).map(|p| p.1);
        let bvh_parent = |j: usize| bvh.joints()[j].parent;
        let troupe_parent = |j: usize| skeleton.joints()[j].parent;
        let mut legs = (0.0, 0.0);
        let mut ankles = Vec::new();
        for side in ["l_", "r_"] {
            let (Ok(hip), Ok(ankle)) = (
                skeleton.joint(&format!("{side}hip")),
                skeleton.joint(&format!("{side}ankle")),
            ) else {
                continue;
            };
            let Some(b_ankle) = bvh_of(ankle) else {
                continue;
            };
            ankles.push((ankle, b_ankle));
            let Some(b_hip) = bvh_of(hip) else {
                continue;
            };
            let t_leg = chain_length(
                troupe_parent,
                |j| skeleton.joints()[j].offset.length(),
                hip,
                ankle,
            );
            let b_leg = chain_length(
                bvh_parent,
                |j| bvh.joints()[j].offset.length(),
                b_hip,
                b_ankle,
            );
            if let (Some(t), Some(b)) = (t_leg, b_leg) {
                legs.0 += rest[root].translation.y - rest[hip].translation.y + t;
                legs.1 += bvh_rest[root_bvh].y - bvh_rest[b_hip].y + b;
            }
        }
        let troupe_low = rest
            .iter()
            .map(|g| g.translation.y)
            .fold(f64::INFINITY, f64::min);
        let scale = if legs.1 > 1e-9 && legs.0 > 0.0 {
            legs.0 / legs.1
        } else {
            let mut bvh_low = bvh_rest.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
            for (j, jt) in bvh.joints().iter().enumerate() {
                for e in &jt.end_sites {
                    bvh_low = bvh_low.min(bvh_rest[j].y + (axes.skeleton * *e).y);
                }
            }
            let bvh_hip = bvh_rest[root_bvh].y - bvh_low;
            if bvh_hip > 1e-9 {
                (rest[root].translation.y - troupe_low) / bvh_hip
            } else {
                0.01
            }
        };
        let (mut bvh_floor, mut troupe_floor) = (0.0, troupe_low);
        if !ankles.is_empty() && bvh.frame_count() > 0 {
            let mut g = vec![Transform::IDENTITY; bvh.joints().len()];
            bvh_floor = f64::INFINITY;
            for k in 0..bvh.frame_count() {
                bvh.global_transforms(k, &mut g);
                axes.turn(&mut g);
                for &(_, b) in &ankles {
                    bvh_floor = bvh_floor.min(g[b].translation.y);
                }
            }
            troupe_floor = ankles
                .iter()
                .map(|&(t, _)| rest[t].translation.y)
                .fold(f64::INFINITY, f64::min);
        }
        Ground {
            scale,
            root_bvh,
            bvh_floor,
            troupe_floor,
            ankles: ankles.iter().map(|&(t, _)| t).collect(),
        }
    }
}

/// How long an ankle must stay at a height for it to count as standing there: a
/// step's stance lasts several times longer, while a lone frame (CMU files start with a
/// calibration pose, legs straightened, lower than any step) or a glitch does not.
const STANCE_SECONDS: f64 = 0.1;

/// Raises or lowers the root (`values`: per DOF, per frame `frame_time` apart) so that
/// troupe's ankles stand at their rest height where they stand lowest: the lowest
/// height the lower ankle keeps for [`STANCE_SECONDS`]. troupe's legs follow the BVH's
/// bones only as far as its joints can (a one-DOF knee, a two-DOF ankle), with its own
/// proportions and within its DOF limits, so the BVH's ankle height scaled is off by
/// about a centimetre (the CMU walk on an adult: 9 mm); troupe's own forward
/// kinematics, with the DOFs clamped as an actor plays them, is not.
fn settle(
    skeleton: &Skeleton,
    ground: &Ground,
    frame_time: f64,
    values: &mut [Vec<f64>],
    used: &[bool],
    translations: &[(usize, Axis, f64)],
) {
    let frames = values.iter().map(Vec::len).max().unwrap_or(0);
    if ground.ankles.is_empty() || frames == 0 {
        return;
    }
    let mut q = vec![0.0; skeleton.dof_count()];
    let mut g = vec![Transform::IDENTITY; skeleton.joints().len()];
    let mut lower = Vec::with_capacity(frames);
    for k in 0..frames {
        // Within the DOF limits, as an actor plays it.
        for (d, v) in values.iter().enumerate() {
            if used[d] {
                q[d] = skeleton.dofs()[d].clamp(v[k]);
            }
        }
        forward_kinematics(skeleton, &q, &mut g);
        let low = ground.ankles.iter().map(|&a| g[a].translation.y);
        lower.push(low.fold(f64::INFINITY, f64::min));
    }
    let window = ((STANCE_SECONDS / frame_time).round() as usize).clamp(1, frames);
    let stance = lower
        .windows(window)
        .map(|w| w.iter().copied().fold(f64::NEG_INFINITY, f64::max))
        .fold(f64::INFINITY, f64::min);
    let shift = ground.troupe_floor - stance;
    for &(d, ax, sign) in translations {
        if ax == Axis::Y {
            for v in &mut values[d] {
                *v += sign * shift;
            }
        }
    }
}

/// A joint a map resolves: `(troupe joint, BVH joint, map order)`.
type Pair = (usize, usize, usize);

/// The mapped joints of `map` in troupe's topological order, and troupe's root; an error
/// when a troupe joint is mapped twice or the root is not mapped.
fn resolve_pairs(skeleton: &Skeleton, bvh: &Bvh, map: &RetargetMap) -> Result<(Vec<Pair>, usize)> {
    let mut pairs: Vec<Pair> = Vec::new();
    for (order, (b, t)) in map.pairs.iter().enumerate() {
        let Some(bi) = find_joint(bvh, b) else {
            tracing::debug!("retarget map `{}`: BVH has no joint `{b}`", map.name);
            continue;
        };
        let ti = skeleton.joint(t)?;
        if pairs.iter().any(|p| p.0 == ti) {
            return Err(Error::Retarget {
                map: map.name.clone(),
                message: format!("troupe joint `{t}` mapped twice"),
            });
        }
        pairs.push((ti, bi, order));
    }
    let root = skeleton
        .joints()
        .iter()
        .position(|j| j.parent.is_none())
        .unwrap_or(0);
    if !pairs.iter().any(|p| p.0 == root) {
        return Err(Error::Retarget {
            map: map.name.clone(),
            message: format!(
                "does not map the BVH onto troupe's root `{}`",
                skeleton.joints()[root].name
            ),
        });
    }
    pairs.sort_by_key(|p| p.0);
    Ok((pairs, root))
}

/// Global rest transforms of `skeleton` (every DOF at zero).
fn rest_globals(skeleton: &Skeleton) -> Vec<Transform> {
    let mut rest = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &vec![0.0; skeleton.dof_count()], &mut rest);
    rest
}

/// Retargets `bvh` onto `skeleton` with `map`; `name` names the sequence. The result has
/// one track per DOF of every mapped troupe joint (radians; root translation in metres),
/// one key per BVH frame, and metadata `rate`, `source = bvh`, `retarget_map`, `bvh_scale`
/// (metres per file unit), `bvh_up` and `bvh_forward` (the file's axes, e.g. `+Z`, that
/// became troupe's up and forward). An error if the BVH's rest pose does not tell which way
/// is up.
pub fn retarget(skeleton: &Skeleton, bvh: &Bvh, map: &RetargetMap, name: &str) -> Result<Sequence> {
    let troupe_parent = |j: usize| skeleton.joints()[j].parent;
    let bvh_parent = |j: usize| bvh.joints()[j].parent;
    let (pairs, root) = resolve_pairs(skeleton, bvh, map)?;

    // Rest positions of both skeletons (troupe in metres, BVH in file units).
    let rest = rest_globals(skeleton);
    // The BVH's rest pose turned into troupe's axes (see [`Axes`]).
    let axes = Axes::detect(bvh, map, &pairs, root, &rest)?;
    let bvh_rest: Vec<DVec3> = bvh
        .rest_positions()
        .into_iter()
        .map(|p| axes.skeleton * p)
        .collect();

    let mut bound: Vec<Bound> = Vec::new();
    for (k, &(t, b, _)) in pairs.iter().enumerate() {
        let parent = (0..k)
            .rev()
            .find(|&i| is_ancestor(troupe_parent, pairs[i].0, t));
        // Bone target: the closest mapped troupe descendant whose BVH joint descends from
        // this BVH joint; ties go to the earlier map entry.
        let child = pairs
            .iter()
            .filter(|p| is_ancestor(troupe_parent, t, p.0) && is_ancestor(bvh_parent, b, p.1))
            .min_by_key(|p| {
                let depth = std::iter::successors(Some(p.0), |&j| troupe_parent(j))
                    .take_while(|&j| j != t)
                    .count();
                (depth, p.2)
            });
        let correction = match child {
            Some(&(tc, bc, _)) if t != root => arc(
                rest[tc].translation - rest[t].translation,
                bvh_rest[bc] - bvh_rest[b],
            ),
            // A leaf inherits its parent's correction (a hand continues its forearm).
            _ => parent.map_or(DQuat::IDENTITY, |p| bound[p].correction),
        };
        bound.push(Bound {
            bvh: b,
            troupe: t,
            parent,
            correction,
        });
    }

    let ground = Ground::measure(skeleton, bvh, &pairs, root, &rest, &bvh_rest, &axes);
    let (scale, root_b) = (ground.scale, ground.root_bvh);
    let root_offset = skeleton.joints()[root].offset;

    // Per-DOF decomposition plans.
    struct Plan {
        dofs: Vec<(usize, f64)>,
        order: RotationOrder,
    }
    let mut plans = Vec::new();
    let mut translations = Vec::new();
    for bj in &bound {
        let joint = &skeleton.joints()[bj.troupe];
        let mut axes = Vec::new();
        let mut dofs = Vec::new();
        for d in joint.dofs.clone() {
            let dof = &skeleton.dofs()[d];
            let (ax, sign) = principal(dof.axis);
            match dof.kind {
                DofKind::Rotation => {
                    if axes.contains(&ax) {
                        return Err(Error::Retarget {
                            map: map.name.clone(),
                            message: format!(
                                "joint `{}` has two rotation DOFs about one axis",
                                joint.name
                            ),
                        });
                    }
                    axes.push(ax);
                    dofs.push((d, sign));
                }
                DofKind::Translation => translations.push((d, ax, sign)),
            }
        }
        for ax in [Axis::X, Axis::Y, Axis::Z] {
            if !axes.contains(&ax) {
                axes.push(ax);
            }
        }
        plans.push(Plan {
            dofs,
            order: RotationOrder([axes[0], axes[1], axes[2]]),
        });
    }

    let frames = bvh.frame_count();
    let mut values: Vec<Vec<f64>> = vec![Vec::with_capacity(frames); skeleton.dof_count()];
    let mut used = vec![false; skeleton.dof_count()];
    let mut gb = vec![Transform::IDENTITY; bvh.joints().len()];
    let mut gt = vec![DQuat::IDENTITY; bound.len()];
    for k in 0..frames {
        bvh.global_transforms(k, &mut gb);
        axes.turn(&mut gb);
        for (i, bj) in bound.iter().enumerate() {
            // Target global orientation; the parent is the orientation troupe really
            // reaches (a joint with fewer than three DOFs cannot follow exactly, and its
            // children make up for it).
            let target = gb[bj.bvh].rotation * bj.correction;
            let parent = bj.parent.map_or(DQuat::IDENTITY, |p| gt[p]);
            let local = parent.inverse() * target;
            let mut angles = plans[i].order.decompose(local);
            for (n, &(d, sign)) in plans[i].dofs.iter().enumerate() {
                values[d].push(sign * angles[n]);
                used[d] = true;
            }
            for a in angles.iter_mut().skip(plans[i].dofs.len()) {
                *a = 0.0;
            }
            gt[i] = parent * plans[i].order.compose(angles);
        }
        // The BVH's floor height carries troupe's (see [`Ground`]).
        let p = gb[root_b].translation * scale
            + DVec3::new(0.0, ground.troupe_floor - scale * ground.bvh_floor, 0.0)
            - root_offset;
        for &(d, ax, sign) in &translations {
            values[d].push(sign * p[ax.index()]);
            used[d] = true;
        }
    }

    // Rotations continue across ±π (the decomposition wraps them), before the settling
    // clamps them to their limits as an actor will.
    for (d, v) in values.iter_mut().enumerate() {
        if skeleton.dofs()[d].kind == DofKind::Rotation {
            for k in 1..v.len() {
                let p = v[k - 1];
                v[k] -= std::f64::consts::TAU * ((v[k] - p) / std::f64::consts::TAU).round();
            }
        }
    }
    settle(
        skeleton,
        &ground,
        bvh.frame_time(),
        &mut values,
        &used,
        &translations,
    );

    let mut seq = Sequence::new(name);
    seq.meta
        .insert("rate".into(), format!("{}", 1.0 / bvh.frame_time()));
    seq.meta.insert("source".into(), "bvh".into());
    seq.meta.insert("retarget_map".into(), map.name.clone());
    seq.meta.insert("bvh_scale".into(), format!("{scale}"));
    seq.meta.insert("bvh_up".into(), axes.file_axis(DVec3::Y));
    seq.meta
        .insert("bvh_forward".into(), axes.file_axis(DVec3::Z));
    for (d, v) in values.into_iter().enumerate() {
        if !used[d] || v.is_empty() {
            continue;
        }
        let keys = v
            .into_iter()
            .enumerate()
            .map(|(k, x)| Key::new(k as f64 * bvh.frame_time(), x))
            .collect();
        seq.add_track(Track::new(skeleton.dofs()[d].name.clone(), keys)?)?;
    }
    Ok(seq)
}

/// Whether every joint of `bvh` is a joint of `skeleton` by name, root included (a BVH
/// that troupe wrote from one of its own bodies).
pub fn is_troupe_rig(skeleton: &Skeleton, bvh: &Bvh) -> bool {
    bvh.joints()
        .first()
        .is_some_and(|j| j.name == skeleton.joints()[0].name)
        && bvh.joints().iter().all(|j| skeleton.joint(&j.name).is_ok())
}

/// Metres per unit of the BVH files troupe writes (centimetres).
const TROUPE_BVH_METRES_PER_UNIT: f64 = 0.01;

/// The template and standing height of the troupe body that a BVH on troupe's own
/// hierarchy was recorded from: the template (at the height its root's rest offset gives)
/// whose joint offsets all match the file's within 1e-6 m. `None` for any other BVH.
pub fn recorded_body(bvh: &Bvh) -> Option<(String, f64)> {
    let root = bvh.joints().first()?.offset.y * TROUPE_BVH_METRES_PER_UNIT;
    troupe_body::template::templates()
        .into_iter()
        .find_map(|t| {
            let at_default = t.instantiate(t.default_params()).ok()?;
            let height = t.default_height * root / at_default.joints().first()?.offset.y;
            let mut params = t.default_params();
            params.height = height;
            let s = t.instantiate(params).ok()?;
            let same = is_troupe_rig(&s, bvh)
                && bvh.joints().iter().all(|j| {
                    s.joint(&j.name).is_ok_and(|i| {
                        (s.joints()[i].offset - j.offset * TROUPE_BVH_METRES_PER_UNIT).length()
                            < 1e-6
                    })
                });
            same.then(|| (t.name.to_string(), height))
        })
}

/// Reads a BVH on troupe's own hierarchy (as `troupe run --record OUT.bvh` writes it, in
/// centimetres) back without retargeting: each joint's rotation becomes its DOF angles,
/// the root's position its translation DOFs. A recording of a body of another size than
/// `skeleton` has its root translation scaled by the ratio of the two root heights (as
/// retargeting scales a foreign file's), so the feet stay on the floor; on a body of the
/// recorded size the postures are replayed exactly.
pub fn troupe_named_motion(skeleton: &Skeleton, bvh: &Bvh, name: &str) -> Result<Sequence> {
    let recorded_root = bvh.joints().first().map_or(0.0, |j| j.offset.y);
    let root_height = skeleton.joints()[0].offset.y;
    // A file whose root offset says nothing of a height (zero) keeps centimetres.
    let metres_per_unit = if recorded_root > 1e-9 && root_height > 1e-9 {
        root_height / recorded_root
    } else {
        TROUPE_BVH_METRES_PER_UNIT
    };
    let n = skeleton.dof_count();
    let joints: Vec<usize> = bvh
        .joints()
        .iter()
        .map(|j| skeleton.joint(&j.name))
        .collect::<troupe_body::Result<_>>()?;
    let mut q = vec![0.0; n];
    let mut values: Vec<Vec<f64>> = vec![Vec::with_capacity(bvh.frame_count()); n];
    for k in 0..bvh.frame_count() {
        let frame = bvh.frame(k);
        for (b, &j) in joints.iter().enumerate() {
            let local = bvh.local_transform(b, frame);
            solve_joint_angles(skeleton, j, local.rotation, &mut q);
            if j == 0 {
                let t = local.translation * metres_per_unit - skeleton.joints()[0].offset;
                for d in skeleton.joints()[0].dofs.clone() {
                    let dof = &skeleton.dofs()[d];
                    if dof.kind == DofKind::Translation {
                        q[d] = t.dot(dof.axis);
                    }
                }
            }
        }
        for (d, v) in q.iter().enumerate() {
            values[d].push(*v);
        }
    }
    let mut seq = Sequence::new(name);
    seq.meta.insert(
        "rate".into(),
        format!("{}", (1.0 / bvh.frame_time()).round()),
    );
    seq.meta.insert("source".into(), "bvh".into());
    seq.meta
        .insert("bvh_scale".into(), metres_per_unit.to_string());
    let driven: Vec<usize> = joints
        .iter()
        .flat_map(|&j| skeleton.joints()[j].dofs.clone())
        .collect();
    for d in driven {
        let track = Track::from_samples(
            skeleton.dofs()[d].name.clone(),
            0.0,
            bvh.frame_time(),
            &values[d],
        )?;
        seq.add_track(track)?;
    }
    Ok(seq)
}

/// Reads a BVH file to play on `skeleton`: a BVH on troupe's own hierarchy is read back
/// exactly ([`troupe_named_motion`]); any other is retargeted with the map in `<file>.map`
/// beside it if that exists, else the built-in map (CMU or Mixamo) that matches its joint
/// names best. (Other formats: [`crate::load_sequence`].)
pub fn load_sequence_for(skeleton: &Skeleton, path: &Path) -> Result<Sequence> {
    motion_for(skeleton, path, &read_bvh(path)?)
}

/// The motion of `bvh`, read from `path`, to play on `skeleton`, as [`load_sequence_for`]
/// makes it: for a caller that has read the file already (the path names the sequence
/// and the `.map` beside it).
pub fn motion_for(skeleton: &Skeleton, path: &Path, bvh: &Bvh) -> Result<Sequence> {
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    if is_troupe_rig(skeleton, bvh) {
        return troupe_named_motion(skeleton, bvh, &name);
    }
    let map = map_for(path, bvh)?;
    retarget(skeleton, bvh, &map, &name).map_err(|e| match e {
        // The map's name alone does not say which file would not retarget.
        Error::Retarget { .. } => Error::Invalid(format!("{}: {e}", path.display())),
        e => e,
    })
}

/// The map a BVH file `path` (read as `bvh`) is retargeted with by default: the `.map`
/// beside it if that exists, else the built-in map that matches its joint names best.
pub fn map_for(path: &Path, bvh: &Bvh) -> Result<RetargetMap> {
    let user = path.with_extension("map");
    if user.is_file() {
        RetargetMap::read(&user)
    } else {
        Ok(RetargetMap::detect(bvh))
    }
}

/// A BVH's axes as retargeting reads them (see `Axes`): which of the file's axes are its
/// figure's up and forward, and the turn onto troupe's and glTF's (Y up, facing +Z).
#[derive(Clone, Debug, PartialEq)]
pub struct BvhAxes {
    /// The file's axis that is up, e.g. `+Z` (recorded as `bvh_up` by [`retarget`]).
    pub up: String,
    /// The file's axis the figure faces, e.g. `+Y` (`bvh_forward`).
    pub forward: String,
    /// The rotation taking the file's world into troupe's axes.
    pub turn: DQuat,
}

impl BvhAxes {
    /// Whether the file already has troupe's axes (up `+Y`, forward `+Z`).
    pub fn is_troupes(&self) -> bool {
        self.up == "+Y" && self.forward == "+Z"
    }
}

/// The axes of `bvh` as [`retarget`] with `map` finds them — on the adult template, whose
/// rest pose says which mapped joints are high and which are on the left (any template
/// says the same) — for a BVH written on its own hierarchy (glTF is Y up, facing +Z). An
/// error when `map` does not fit the file or its rest pose does not tell which way is up.
pub fn bvh_axes(bvh: &Bvh, map: &RetargetMap) -> Result<BvhAxes> {
    let template = troupe_body::template::template("adult")?;
    let skeleton = template.instantiate(template.default_params())?;
    let (pairs, root) = resolve_pairs(&skeleton, bvh, map)?;
    let axes = Axes::detect(bvh, map, &pairs, root, &rest_globals(&skeleton))?;
    Ok(BvhAxes {
        up: axes.file_axis(DVec3::Y),
        forward: axes.file_axis(DVec3::Z),
        turn: axes.world * axes.skeleton,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{from_rig, parse_bvh, Channel};
    use crate::rig::tests::{adult, every_dof_moving, fk_positions, posture};
    use crate::rig::Rig;

    fn data(name: &str) -> std::path::PathBuf {
        format!(
            "{}/../../../shared/data/bvh/{name}",
            env!("CARGO_MANIFEST_DIR")
        )
        .into()
    }

    fn fk(s: &Skeleton, seq: &Sequence, t: f64) -> Vec<Transform> {
        let mut q = vec![0.0; s.dof_count()];
        for tr in seq.tracks() {
            q[s.dof(tr.dof()).unwrap()] = tr.value(t);
        }
        let mut g = vec![Transform::IDENTITY; s.joints().len()];
        forward_kinematics(s, &q, &mut g);
        g
    }

    fn angle(a: DVec3, b: DVec3) -> f64 {
        a.normalize()
            .dot(b.normalize())
            .clamp(-1.0, 1.0)
            .acos()
            .to_degrees()
    }

    /// A template's skeleton at `height` (its default height when `None`).
    fn body(template: &str, height: Option<f64>) -> Skeleton {
        let t = troupe_body::template::template(template).unwrap();
        let mut params = t.default_params();
        if let Some(h) = height {
            params.height = h;
        }
        t.instantiate(params).unwrap()
    }

    /// The lowest ankle height over every frame of a retargeted clip, as an actor plays it
    /// (DOFs within their limits), and troupe's rest ankle height.
    fn lowest_ankle(s: &Skeleton, seq: &Sequence, bvh: &Bvh) -> (f64, f64) {
        let ankles = [s.joint("l_ankle").unwrap(), s.joint("r_ankle").unwrap()];
        let rest = fk(s, &Sequence::new("rest"), 0.0)[ankles[0]].translation.y;
        let fk = |s: &Skeleton, seq: &Sequence, t: f64| {
            let mut q = vec![0.0; s.dof_count()];
            for tr in seq.tracks() {
                let d = s.dof(tr.dof()).unwrap();
                q[d] = s.dofs()[d].clamp(tr.value(t));
            }
            let mut g = vec![Transform::IDENTITY; s.joints().len()];
            forward_kinematics(s, &q, &mut g);
            g
        };
        // From frame 1: CMU's frame 0 is a calibration pose (legs straightened, whole
        // degrees), lower than any step of the walk.
        let low = (1..bvh.frame_count())
            .map(|k| {
                let g = fk(s, seq, k as f64 * bvh.frame_time());
                ankles
                    .iter()
                    .map(|&a| g[a].translation.y)
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(f64::INFINITY, f64::min);
        (low, rest)
    }

    /// `bvh` turned by `turn`, a quarter-turn rotation (every axis onto a signed axis):
    /// the same motion in other axes, as a file written Z-up would hold it.
    fn turned(bvh: &Bvh, turn: DQuat) -> Bvh {
        let onto = |a: Axis| principal(turn * a.unit());
        let mut joints = bvh.joints().to_vec();
        let mut signs = Vec::new();
        for j in &mut joints {
            j.offset = turn * j.offset;
            for e in &mut j.end_sites {
                *e = turn * *e;
            }
            for c in &mut j.channels {
                let (ax, sign) = match *c {
                    Channel::Position(a) | Channel::Rotation(a) => onto(a),
                };
                *c = match *c {
                    Channel::Position(_) => Channel::Position(ax),
                    Channel::Rotation(_) => Channel::Rotation(ax),
                };
                signs.push(sign);
            }
        }
        let data = (0..bvh.frame_count())
            .flat_map(|k| bvh.frame(k).iter().zip(&signs).map(|(v, s)| v * s))
            .collect();
        Bvh::new(joints, bvh.frame_time(), data).unwrap()
    }

    #[test]
    fn a_z_up_turn_of_the_cmu_walk_retargets_as_the_y_up_original() {
        let s = adult();
        let bvh = read_bvh(data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        let map = RetargetMap::cmu();
        let original = retarget(&s, &bvh, &map, "walk").unwrap();
        assert_eq!(
            (
                original.meta["bvh_up"].as_str(),
                original.meta["bvh_forward"].as_str()
            ),
            ("+Y", "+Z")
        );
        // Y onto Z and Z onto -Y: a Z-up file whose body faces -Y, as Blender's.
        let z_up = turned(&bvh, DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2));
        assert!(z_up.rest_positions()[z_up.joint("Head").unwrap()].z > 5.0);
        let seq = retarget(&s, &z_up, &map, "walk").unwrap();
        for k in (0..bvh.frame_count()).step_by(23) {
            let t = k as f64 * bvh.frame_time();
            let (a, b) = (fk(&s, &original, t), fk(&s, &seq, t));
            for (j, (a, b)) in a.iter().zip(&b).enumerate() {
                let d = (a.translation - b.translation).length();
                assert!(d < 1e-9, "frame {k} {}: {d} m", s.joints()[j].name);
            }
        }
        assert_eq!(
            (
                seq.meta["bvh_up"].as_str(),
                seq.meta["bvh_forward"].as_str()
            ),
            ("+Z", "-Y")
        );
        assert_eq!(seq.meta["bvh_scale"], original.meta["bvh_scale"]);
    }

    #[test]
    fn a_bvh_on_its_own_hierarchy_turned_by_its_axes_stands_as_the_y_up_original() {
        let walk = read_bvh(data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        let map = RetargetMap::cmu();
        let axes = bvh_axes(&walk, &map).unwrap();
        assert!(axes.is_troupes(), "{axes:?}");
        assert!(axes.turn.abs_diff_eq(DQuat::IDENTITY, 1e-12), "{axes:?}");
        // The walk turned Z up (facing -Y, as Blender's files) and turned back by its
        // axes is the original, joint for joint, in every frame.
        let z_up = turned(&walk, DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2));
        let axes = bvh_axes(&z_up, &map).unwrap();
        assert_eq!((axes.up.as_str(), axes.forward.as_str()), ("+Z", "-Y"));
        assert!(!axes.is_troupes());
        let want = Rig::from_bvh(&walk, 0.056444);
        let mut rig = Rig::from_bvh(&z_up, 0.056444);
        rig.turn(axes.turn);
        for k in (0..walk.frame_count()).step_by(17) {
            for (j, (a, b)) in rig.positions(k).iter().zip(want.positions(k)).enumerate() {
                assert!(
                    (*a - b).length() < 1e-9,
                    "frame {k} {}: {a} vs {b}",
                    rig.names[j]
                );
            }
        }
    }

    #[test]
    fn z_up_files_turned_by_their_axes_stand_up_facing_z() {
        // pybvh's example (a Z-up skeleton) and test3 (a Y-up skeleton the frames stand
        // along Z): the file's +Z becomes +Y, and the body faces +Z (left on +X).
        for file in ["pybvhrepo_bvh_example.bvh", "pybvhrepo_bvh_test3.bvh"] {
            let bvh = read_bvh(data(file)).unwrap();
            let axes = bvh_axes(&bvh, &RetargetMap::detect(&bvh)).unwrap();
            assert_eq!(axes.up, "+Z", "{file}");
            let mut rig = Rig::from_bvh(&bvh, 0.01);
            rig.turn(axes.turn);
            let joint = |name: &str| rig.names.iter().position(|n| n == name).unwrap();
            let (hips, head) = (joint("Hips"), joint("Head"));
            let (left, right) = (joint("LeftUpLeg"), joint("RightUpLeg"));
            for k in (0..bvh.frame_count()).step_by(9) {
                let p = rig.positions(k);
                let up = p[head] - p[hips];
                assert!(
                    angle(up, DVec3::Y) < 30.0,
                    "{file} frame {k}: hips to head {up}"
                );
            }
            let p = rig.positions(0);
            let lateral = p[left] - p[right];
            assert!(
                angle(lateral, DVec3::X) < 30.0,
                "{file}: right to left {lateral}"
            );
        }
        // A file whose joints no map knows keeps its axes: which way is up is unknown.
        let two = parse_bvh(crate::bvh::fixtures::TWO_ROOTS, "two.bvh").unwrap();
        let err = bvh_axes(&two, &RetargetMap::detect(&two)).unwrap_err();
        assert!(err.to_string().contains("does not map"), "{err}");
    }

    #[test]
    fn a_z_up_file_stands_on_the_floor_facing_forward() {
        // pybvh's example: the spine's OFFSETs run along +Z, the toes along +Y.
        let s = adult();
        let path = data("pybvhrepo_bvh_example.bvh");
        let bvh = read_bvh(&path).unwrap();
        let seq = load_sequence_for(&s, &path).unwrap();
        let (root, head) = (0, s.joint("skullbase").unwrap());
        let rest = fk(&s, &Sequence::new("rest"), 0.0);
        let mut gb = vec![Transform::IDENTITY; bvh.joints().len()];
        for k in 0..bvh.frame_count() {
            let g = fk(&s, &seq, k as f64 * bvh.frame_time());
            // Upright, at about its standing height (it sways and kicks).
            let up = g[head].translation - g[root].translation;
            assert!(angle(up, DVec3::Y) < 30.0, "frame {k}: root to head {up}");
            let dy = g[root].translation.y - rest[root].translation.y;
            assert!(dy.abs() < 0.1, "frame {k}: root {dy} m off its rest height");
            // Facing where the file's hips face (+Y at rest), in troupe's axes: the file's
            // left (-X) is troupe's +X, its up (+Z) troupe's +Y, its +Y troupe's +Z.
            bvh.global_transforms(k, &mut gb);
            let f = gb[0].rotation * DVec3::Y;
            let want = DVec3::new(-f.x, f.z, f.y);
            let facing = g[root].rotation * DVec3::Z;
            assert!(
                angle(facing, want) < 1e-6,
                "frame {k}: facing {facing}, file {want}"
            );
            if k == 0 {
                assert!(
                    angle(facing, DVec3::Z) < 10.0,
                    "facing {facing} at the start"
                );
            }
        }
        let (low, rest_ankle) = lowest_ankle(&s, &seq, &bvh);
        assert!((low - rest_ankle).abs() < 0.01, "{low} vs {rest_ankle}");
        assert_eq!(
            (
                seq.meta["bvh_up"].as_str(),
                seq.meta["bvh_forward"].as_str()
            ),
            ("+Z", "+Y")
        );
    }

    #[test]
    fn a_y_up_skeleton_posed_along_z_stands_up() {
        // pybvh's test3: a Y-up rest pose whose frames turn the root to stand along +Z.
        let s = adult();
        let path = data("pybvhrepo_bvh_test3.bvh");
        let bvh = read_bvh(&path).unwrap();
        let seq = load_sequence_for(&s, &path).unwrap();
        let (root, head) = (0, s.joint("skullbase").unwrap());
        for k in (0..bvh.frame_count()).step_by(9) {
            let g = fk(&s, &seq, k as f64 * bvh.frame_time());
            let up = g[head].translation - g[root].translation;
            assert!(angle(up, DVec3::Y) < 20.0, "frame {k}: root to head {up}");
            let facing = g[root].rotation * DVec3::Z;
            assert!(angle(facing, DVec3::Z) < 30.0, "frame {k}: facing {facing}");
        }
        let (low, rest_ankle) = lowest_ankle(&s, &seq, &bvh);
        assert!((low - rest_ankle).abs() < 0.01, "{low} vs {rest_ankle}");
        assert_eq!(seq.meta["bvh_up"], "+Z");
    }

    #[test]
    fn a_body_lying_along_z_in_a_y_up_world_is_not_stood_up() {
        // Crawling forward along +Z, head first, in an ordinary Y-up file: its head points
        // along +Z as consistently as bvh_test3's turned world, but its floor is Y.
        let joint = |name: &str, offset: &str, inner: &str| {
            format!("JOINT {name}\n{{\nOFFSET {offset}\nCHANNELS 3 Zrotation Xrotation Yrotation\n{inner}}}\n")
        };
        let end = "End Site\n{\nOFFSET 0 -2 0\n}\n";
        let leg = |side: &str, x: &str| {
            joint(
                &format!("{side}UpLeg"),
                &format!("{x} -2 0"),
                &joint(
                    &format!("{side}Leg"),
                    "0 -8 0",
                    &joint(&format!("{side}Foot"), "0 -8 0", end),
                ),
            )
        };
        let head = joint(
            "Neck",
            "0 6 0",
            &joint("Head", "0 2 0", "End Site\n{\nOFFSET 0 3 0\n}\n"),
        );
        let spine = joint("Spine", "0 4 0", &head);
        let mut text = format!(
            "HIERARCHY\nROOT Hips\n{{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n{spine}{}{}}}\nMOTION\nFrames: 20\nFrame Time: 0.1\n",
            leg("Left", "2"),
            leg("Right", "-2")
        );
        for k in 0..20 {
            // Root 2 units above the floor, lying face down (90° about X), crawling on.
            text.push_str(&format!(
                "0 2 {} 0 90 0{}\n",
                1.5 * k as f64,
                " 0 0 0".repeat(9)
            ));
        }
        let path = std::env::temp_dir().join(format!("troupe-crawl-{}.bvh", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let seq = load_sequence_for(&adult(), &path).unwrap();
        std::fs::remove_file(&path).unwrap();
        assert_eq!(seq.meta["bvh_up"], "+Y", "{:?}", seq.meta);
        let s = adult();
        let g = fk(&s, &seq, 1.0);
        let up = g[s.joint("skullbase").unwrap()].translation - g[0].translation;
        assert!(angle(up, DVec3::Y) > 70.0, "still lying: root to head {up}");
    }

    #[test]
    fn a_rest_pose_without_an_up_axis_is_an_error_naming_the_file() {
        // The spine leans 45° between Y and Z: neither is up.
        let text = "HIERARCHY\nROOT Hips\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\nJOINT Spine\n{\nOFFSET 0 10 10\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT Head\n{\nOFFSET 0 10 10\nCHANNELS 3 Zrotation Xrotation Yrotation\nEnd Site\n{\nOFFSET 0 5 5\n}\n}\n}\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0 0 0 0 0 0 0 0 0 0\n";
        let path = std::env::temp_dir().join(format!("troupe-leaning-{}.bvh", std::process::id()));
        std::fs::write(&path, text).unwrap();
        let err = load_sequence_for(&adult(), &path).unwrap_err().to_string();
        std::fs::remove_file(&path).unwrap();
        assert!(err.contains(&path.display().to_string()), "{err}");
        assert!(err.contains("cannot tell which axis is up"), "{err}");
    }

    #[test]
    fn real_files_keep_their_feet_on_the_floor() {
        // Every shipped file that stands on a floor, on bodies of three sizes: the clip's
        // lowest ankle, as an actor plays it, is where a standing ankle is (asked: within
        // 1 cm; the BVH's ankle height scaled alone is 9 mm off for the CMU walk).
        let files = [
            "pybvhrepo_cmu_12_01_walk.bvh",
            "pymo_AV_8Walk_Meredith_HVHA_Rep1.bvh",
            "pybvhrepo_bvh_example.bvh",
            "pybvhrepo_bvh_test3.bvh",
        ];
        let bodies = [("adult", None), ("child", None), ("adult", Some(1.95))];
        for file in files {
            let bvh = read_bvh(data(file)).unwrap();
            for (template, height) in bodies {
                let s = body(template, height);
                let seq = load_sequence_for(&s, &data(file)).unwrap();
                let (low, rest) = lowest_ankle(&s, &seq, &bvh);
                assert!(
                    (low - rest).abs() < 0.003,
                    "{file} on {template} {height:?}: lowest ankle {low:.3} m, standing {rest:.3} m"
                );
            }
        }
    }

    #[test]
    fn the_cmu_scale_is_the_legs_along_their_bones() {
        // CMU's rest legs splay outwards, so its rest hips stand 14.98 units above its
        // toes while its legs measure 15.57 (left) and 15.47 (right) units from the hips
        // down the bones to the ankles (and the walk's hips ride 16.2 above its floor).
        // troupe's adult measures 0.894 m from the root down to the ankles.
        let s = adult();
        let seq = load_sequence_for(&s, &data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        let scale: f64 = seq.meta["bvh_scale"].parse().unwrap();
        assert!((scale - 0.894 / 15.52).abs() < 1e-4, "{scale}");
        // So the walking root rides about at troupe's standing root height (a little
        // lower: the knees bend), not the 8 cm higher the rest hip height gave.
        let root_y = seq.track("root_y").unwrap();
        let mean = root_y.keys().iter().map(|k| k.value).sum::<f64>() / root_y.keys().len() as f64;
        assert!(
            mean.abs() < 0.03,
            "root {mean} m above its rest height on average"
        );
    }

    #[test]
    fn cmu_walk_bones_point_where_the_bvh_bones_point() {
        let s = adult();
        let path = data("pybvhrepo_cmu_12_01_walk.bvh");
        let seq = load_sequence_for(&s, &path).unwrap();
        assert_eq!(seq.meta["retarget_map"], "cmu");
        let bvh = read_bvh(&path).unwrap();
        for tr in seq.tracks() {
            assert!(s.dof(tr.dof()).is_ok());
            assert_eq!(tr.keys().len(), bvh.frame_count());
        }
        // Bones of 3-DOF joints follow exactly; 1- and 2-DOF joints approximately.
        let bones = [
            ("l_hip", "l_knee", "LeftUpLeg", "LeftLeg", 1.0),
            ("r_hip", "r_knee", "RightUpLeg", "RightLeg", 1.0),
            ("l_shoulder", "l_elbow", "LeftArm", "LeftForeArm", 1.0),
            ("r_shoulder", "r_elbow", "RightArm", "RightForeArm", 1.0),
            ("l_knee", "l_ankle", "LeftLeg", "LeftFoot", 15.0),
            ("l_elbow", "l_wrist", "LeftForeArm", "LeftHand", 20.0),
        ];
        let mut gb = vec![Transform::IDENTITY; bvh.joints().len()];
        for k in (0..bvh.frame_count()).step_by(37) {
            let t = k as f64 * bvh.frame_time();
            let g = fk(&s, &seq, t);
            bvh.global_transforms(k, &mut gb);
            for (a, b, ba, bb, tol) in bones {
                let (a, b) = (s.joint(a).unwrap(), s.joint(b).unwrap());
                let (ba, bb) = (bvh.joint(ba).unwrap(), bvh.joint(bb).unwrap());
                let d = angle(
                    g[b].translation - g[a].translation,
                    gb[bb].translation - gb[ba].translation,
                );
                assert!(d < tol, "frame {k} bone {a}->{b}: {d}°");
            }
        }
        // Feet stay near the floor: the lowest ankle over the walk (from frame 1: frame 0
        // is a calibration pose) is near its rest height.
        let rest_ankle = fk(&s, &Sequence::new("rest"), 0.0)[s.joint("l_ankle").unwrap()]
            .translation
            .y;
        let low = (1..bvh.frame_count())
            .step_by(10)
            .map(|k| {
                let g = fk(&s, &seq, k as f64 * bvh.frame_time());
                g[s.joint("l_ankle").unwrap()]
                    .translation
                    .y
                    .min(g[s.joint("r_ankle").unwrap()].translation.y)
            })
            .fold(f64::INFINITY, f64::min);
        assert!((low - rest_ankle).abs() < 0.01, "{low} vs {rest_ankle}");
    }

    #[test]
    fn t_pose_rest_maps_to_raised_arms() {
        let text = "HIERARCHY\nROOT Hips\n{\nOFFSET 0 90 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\nJOINT LeftUpLeg\n{\nOFFSET 10 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT LeftLeg\n{\nOFFSET 0 -45 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nEnd Site\n{\nOFFSET 0 -45 0\n}\n}\n}\nJOINT Spine\n{\nOFFSET 0 10 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT LeftArm\n{\nOFFSET 15 40 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT LeftForeArm\n{\nOFFSET 30 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nEnd Site\n{\nOFFSET 25 0 0\n}\n}\n}\n}\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n0 90 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n";
        let bvh = crate::bvh::parse_bvh(text, "t").unwrap();
        let s = adult();
        let map = RetargetMap::parse(
            "Hips HumanoidRoot\nLeftUpLeg l_hip\nLeftLeg l_knee\nLeftArm l_shoulder\nLeftForeArm l_elbow # forearm\n",
            "user.map",
        )
        .unwrap();
        let seq = retarget(&s, &bvh, &map, "t").unwrap();
        let g = fk(&s, &seq, 0.0);
        let arm = g[s.joint("l_elbow").unwrap()].translation
            - g[s.joint("l_shoulder").unwrap()].translation;
        assert!(angle(arm, DVec3::X) < 1e-6, "{arm}");
        let abduction = seq.track("l_shoulder_abduction").unwrap().value(0.0);
        assert!((abduction.to_degrees() - 90.0).abs() < 1e-6, "{abduction}");
        // The root stands at troupe's height: BVH hips 90 above the feet → troupe's root.
        assert!(seq.track("root_y").unwrap().value(0.0).abs() < 1e-9);
        assert!(RetargetMap::parse("a b c\n", "m").is_err());
    }

    /// A troupe recording of `skeleton` standing and moving its root 1 m forward while
    /// raising an arm, written as troupe writes BVH and read back.
    fn recorded_bvh(skeleton: &Skeleton) -> Bvh {
        let mut seq = Sequence::new("rec");
        seq.meta.insert("rate".into(), "10".into());
        for (dof, v) in [("root_z", 1.0), ("r_shoulder_abduction", 1.2)] {
            let keys = vec![Key::new(0.0, 0.0), Key::new(2.0, v)];
            seq.add_track(Track::new(dof, keys).unwrap()).unwrap();
        }
        let rig = Rig::from_sequence(skeleton, &seq).unwrap();
        let order: RotationOrder = "ZXY".parse().unwrap();
        let bvh = from_rig(&rig, 0.1, order, 100.0).unwrap();
        parse_bvh(&bvh.to_bvh_string(), "rec.bvh").unwrap()
    }

    #[test]
    fn a_troupe_recording_keeps_its_feet_on_the_floor_on_a_body_of_another_size() {
        let tall = body("adult", Some(1.95));
        let bvh = recorded_bvh(&tall);
        let tall_root = tall.joints()[0].offset.y;
        for s in [adult(), body("child", None), body("adult", Some(1.5))] {
            let seq = troupe_named_motion(&s, &bvh, "rec").unwrap();
            let rest = fk(&s, &Sequence::new("rest"), 0.0);
            let ankle = s.joint("l_ankle").unwrap();
            for k in 0..bvh.frame_count() {
                let g = fk(&s, &seq, k as f64 * 0.1);
                let dy = g[ankle].translation.y - rest[ankle].translation.y;
                assert!(
                    dy.abs() < 1e-9,
                    "frame {k}: the ankle is {dy} m off the floor"
                );
            }
            // The walk is scaled as the body is.
            let ratio = s.joints()[0].offset.y / tall_root;
            let z = seq.track("root_z").unwrap().value(2.0);
            assert!((z - ratio).abs() < 1e-9, "{z} vs {ratio}");
        }
        // On its own size it replays the recording exactly.
        let seq = troupe_named_motion(&tall, &bvh, "rec").unwrap();
        assert!(seq.track("root_y").unwrap().value(1.0).abs() < 1e-9);
        assert!((seq.track("root_z").unwrap().value(2.0) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn the_recorded_body_is_read_from_a_troupe_bvh() {
        for (template, height) in [("adult", 1.95), ("adult", 1.75), ("child", 1.3)] {
            let bvh = recorded_bvh(&body(template, Some(height)));
            let (t, h) = recorded_body(&bvh).unwrap();
            assert_eq!(t, template);
            assert!((h - height).abs() < 1e-9, "{h} vs {height}");
        }
        let cmu = read_bvh(data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        assert_eq!(recorded_body(&cmu), None);
    }

    #[test]
    fn a_troupe_motion_exported_as_bvh_keeps_every_joint_position() {
        let skel = adult();
        let seq = every_dof_moving(&skel, 5, 0.2, "50");
        let rig = Rig::from_sequence(&skel, &seq).unwrap();
        let order: RotationOrder = "ZXY".parse().unwrap();
        let bvh = from_rig(&rig, seq.frame_time(), order, 100.0).unwrap();
        let back = parse_bvh(&bvh.to_bvh_string(), "export.bvh").unwrap();
        // Read back onto the same body, the motion gives the same postures.
        assert!(is_troupe_rig(&skel, &back));
        let replay = troupe_named_motion(&skel, &back, "replay").unwrap();
        for k in [0, 13, 40] {
            let time = k as f64 * seq.frame_time();
            let expected = fk_positions(&skel, &posture(&skel, &seq, time));
            let replayed = fk_positions(&skel, &posture(&skel, &replay, time));
            for (e, r) in expected.iter().zip(replayed) {
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
