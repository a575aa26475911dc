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
//! Root translation is scaled by troupe's hip height over the BVH's rest hip height (hips
//! above the lowest rest joint), which keeps the feet on the floor for a different body
//! size; the BVH's floor (y = 0) is taken to be where troupe's lowest rest joint stands. BVH and troupe share their axes (Y up, facing +Z, left +X).

use crate::bvh::{read_bvh, Axis, Bvh, RotationOrder};
use crate::error::{Error, Result};
use glam::{DQuat, DVec3};
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

/// Retargets `bvh` onto `skeleton` with `map`; `name` names the sequence. The result has
/// one track per DOF of every mapped troupe joint (radians; root translation in metres),
/// one key per BVH frame, and metadata `rate`, `source = bvh`, `retarget_map`, `bvh_scale`.
pub fn retarget(skeleton: &Skeleton, bvh: &Bvh, map: &RetargetMap, name: &str) -> Result<Sequence> {
    let troupe_parent = |j: usize| skeleton.joints()[j].parent;
    let bvh_parent = |j: usize| bvh.joints()[j].parent;
    // Resolve names, keep troupe topological order.
    let mut pairs: Vec<(usize, usize, usize)> = Vec::new(); // (troupe, bvh, map order)
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

    // Rest positions of both skeletons (troupe in metres, BVH in file units).
    let mut rest = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &vec![0.0; skeleton.dof_count()], &mut rest);
    let bvh_rest = bvh.rest_positions();

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

    // Root translation scale: troupe's root height over the BVH's rest hip height.
    let troupe_low = rest
        .iter()
        .map(|g| g.translation.y)
        .fold(f64::INFINITY, f64::min);
    let root_b = bound.iter().find(|b| b.troupe == root).map_or(0, |b| b.bvh);
    let mut bvh_low = bvh_rest.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
    for (j, jt) in bvh.joints().iter().enumerate() {
        for e in &jt.end_sites {
            bvh_low = bvh_low.min(bvh_rest[j].y + e.y);
        }
    }
    let bvh_hip = bvh_rest[root_b].y - bvh_low;
    let scale = if bvh_hip > 1e-9 {
        (rest[root].translation.y - troupe_low) / bvh_hip
    } else {
        0.01
    };
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
        // The BVH floor (y = 0) carries the troupe body's lowest rest joint height.
        let p = gb[root_b].translation * scale + DVec3::new(0.0, troupe_low, 0.0) - root_offset;
        for &(d, ax, sign) in &translations {
            values[d].push(sign * p[ax.index()]);
            used[d] = true;
        }
    }

    let mut seq = Sequence::new(name);
    seq.meta
        .insert("rate".into(), format!("{}", 1.0 / bvh.frame_time()));
    seq.meta.insert("source".into(), "bvh".into());
    seq.meta.insert("retarget_map".into(), map.name.clone());
    seq.meta.insert("bvh_scale".into(), format!("{scale}"));
    for (d, v) in values.into_iter().enumerate() {
        if !used[d] || v.is_empty() {
            continue;
        }
        let mut last: Option<f64> = None;
        let rotation = skeleton.dofs()[d].kind == DofKind::Rotation;
        let keys = v
            .into_iter()
            .enumerate()
            .map(|(k, mut x)| {
                if rotation {
                    if let Some(p) = last {
                        x -= std::f64::consts::TAU * ((x - p) / std::f64::consts::TAU).round();
                    }
                    last = Some(x);
                }
                Key::new(k as f64 * bvh.frame_time(), x)
            })
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

/// Reads a BVH on troupe's own hierarchy (as `troupe run --record OUT.bvh` writes it, in
/// centimetres) back without retargeting: each joint's rotation becomes its DOF angles,
/// the root's position its translation DOFs.
pub fn troupe_named_motion(skeleton: &Skeleton, bvh: &Bvh, name: &str) -> Result<Sequence> {
    const METRES_PER_UNIT: f64 = 0.01;
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
                let t = local.translation * METRES_PER_UNIT - skeleton.joints()[0].offset;
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
        .insert("bvh_scale".into(), METRES_PER_UNIT.to_string());
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
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let bvh = read_bvh(path)?;
    if is_troupe_rig(skeleton, &bvh) {
        return troupe_named_motion(skeleton, &bvh, &name);
    }
    let user = path.with_extension("map");
    let map = if user.is_file() {
        RetargetMap::read(&user)?
    } else {
        RetargetMap::detect(&bvh)
    };
    retarget(skeleton, &bvh, &map, &name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::{from_rig, parse_bvh};
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
        // Feet stay near the floor: the lowest ankle over the walk is near its rest height.
        let rest_ankle = fk(&s, &Sequence::new("rest"), 0.0)[s.joint("l_ankle").unwrap()]
            .translation
            .y;
        let low = (0..bvh.frame_count())
            .step_by(10)
            .map(|k| {
                let g = fk(&s, &seq, k as f64 * bvh.frame_time());
                g[s.joint("l_ankle").unwrap()]
                    .translation
                    .y
                    .min(g[s.joint("r_ankle").unwrap()].translation.y)
            })
            .fold(f64::INFINITY, f64::min);
        assert!((low - rest_ankle).abs() < 0.08, "{low} vs {rest_ankle}");
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
