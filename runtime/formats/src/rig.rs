//! One rig type: a joint hierarchy with rest transforms and a motion sampled on it.
//!
//! A rig is what the skeletal writers take (glTF nodes and animation, BVH joints and
//! channels) and what a troupe body playing a sequence, or a BVH on its own hierarchy,
//! becomes. Its forward kinematics, [`chain_globals`], is the one every parent-first
//! hierarchy of local transforms here uses (rigs and BVH motions); troupe skeletons use
//! [`troupe_body::kinematics`].

use crate::error::{Error, Result};
use glam::{DQuat, DVec3};
use troupe_body::kinematics::local_transform;
use troupe_body::skeleton::{DofKind, Skeleton};
use troupe_body::transform::Transform;
use troupe_motion::object_motion::ObjectMotion;
use troupe_motion::sequence::Sequence;

/// Most frames a rig is sampled to, so that a sequence with an absurd duration or rate is
/// an error rather than an allocation that cannot succeed.
pub const MAX_FRAMES: usize = 10_000_000;

/// A rig and its motion, ready to write: joints in topological order with rest local
/// transforms, and per-frame local rotations (and translations of joints that move).
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    /// Joint names.
    pub names: Vec<String>,
    /// Parent index per joint (smaller than the joint's own).
    pub parents: Vec<Option<usize>>,
    /// Rest local transform per joint (metres).
    pub rest: Vec<Transform>,
    /// Frame times (seconds, increasing).
    pub times: Vec<f64>,
    /// `rotations[frame][joint]`.
    pub rotations: Vec<Vec<DQuat>>,
    /// Joints whose translation is animated, increasing, with `translations[frame][i]`
    /// for the i-th.
    pub moving: Vec<usize>,
    /// Animated translations (metres).
    pub translations: Vec<Vec<DVec3>>,
}

impl Rig {
    /// A troupe skeleton playing `seq` (sampled every `seq.frame_time()`; DOFs without a
    /// track stay at zero).
    pub fn from_sequence(skeleton: &Skeleton, seq: &Sequence) -> Result<Rig> {
        let mut bind = Vec::new();
        for t in seq.tracks() {
            bind.push((skeleton.dof(t.dof())?, t));
        }
        let ft = seq.frame_time();
        let n = sampled_frames(seq)?;
        let joints = skeleton.joints();
        let zero = vec![0.0; skeleton.dof_count()];
        let moving: Vec<usize> = (0..joints.len())
            .filter(|&j| {
                joints[j]
                    .dofs
                    .clone()
                    .any(|d| skeleton.dofs()[d].kind == DofKind::Translation)
            })
            .collect();
        let mut rig = Rig {
            names: joints.iter().map(|j| j.name.clone()).collect(),
            parents: joints.iter().map(|j| j.parent).collect(),
            rest: (0..joints.len())
                .map(|j| local_transform(skeleton, j, &zero))
                .collect(),
            times: Vec::with_capacity(n),
            rotations: Vec::with_capacity(n),
            moving: moving.clone(),
            translations: Vec::with_capacity(n),
        };
        let mut q = zero.clone();
        let mut cursors = vec![0usize; bind.len()];
        for k in 0..n {
            let t = seq.start() + k as f64 * ft;
            for (i, (d, track)) in bind.iter().enumerate() {
                q[*d] = track.value_at(t, &mut cursors[i]);
            }
            let locals: Vec<Transform> = (0..joints.len())
                .map(|j| local_transform(skeleton, j, &q))
                .collect();
            rig.times.push(t - seq.start());
            rig.rotations
                .push(locals.iter().map(|l| l.rotation).collect());
            rig.translations
                .push(moving.iter().map(|&j| locals[j].translation).collect());
        }
        Ok(rig)
    }

    /// An object's motion as a one-joint rig named after it, sampled at `start + t` for
    /// each `t` of `times` (so that it shares a troupe body's rig's frames): the joint's
    /// rotation and translation are the object's world pose.
    pub fn from_object(object: &ObjectMotion, start: f64, times: &[f64]) -> Rig {
        let poses: Vec<(DVec3, DQuat)> = times.iter().map(|t| object.pose_at(start + t)).collect();
        Rig {
            names: vec![object.name.clone()],
            parents: vec![None],
            rest: vec![Transform::IDENTITY],
            times: times.to_vec(),
            rotations: poses.iter().map(|p| vec![p.1]).collect(),
            moving: vec![0],
            translations: poses.iter().map(|p| vec![p.0]).collect(),
        }
    }

    /// Turns the whole rig by `rotation` about the origin: each root's rest transform and
    /// motion, so that every joint's global transform, at rest and in every frame, is
    /// turned.
    pub fn turn(&mut self, rotation: DQuat) {
        let turned =
            |t: &Transform| Transform::new(rotation * t.rotation, rotation * t.translation);
        for j in (0..self.names.len()).filter(|&j| self.parents[j].is_none()) {
            self.rest[j] = turned(&self.rest[j]);
            for frame in &mut self.rotations {
                frame[j] = rotation * frame[j];
            }
            if let Some(i) = self.moving.iter().position(|&m| m == j) {
                for frame in &mut self.translations {
                    frame[i] = rotation * frame[i];
                }
            }
        }
    }

    /// Global rest transforms of every joint.
    pub fn rest_globals(&self) -> Vec<Transform> {
        let mut g = vec![Transform::IDENTITY; self.rest.len()];
        chain_globals(&mut g, |j| self.parents[j], |j| self.rest[j]);
        g
    }

    /// Global transforms of every joint at frame `k`.
    pub fn globals(&self, k: usize) -> Vec<Transform> {
        let mut locals: Vec<Transform> = (0..self.names.len())
            .map(|j| Transform::new(self.rotations[k][j], self.rest[j].translation))
            .collect();
        for (i, &j) in self.moving.iter().enumerate() {
            locals[j].translation = self.translations[k][i];
        }
        let mut g = vec![Transform::IDENTITY; locals.len()];
        chain_globals(&mut g, |j| self.parents[j], |j| locals[j]);
        g
    }

    /// Global joint positions at frame `k`.
    pub fn positions(&self, k: usize) -> Vec<DVec3> {
        self.globals(k).iter().map(|t| t.translation).collect()
    }
}

/// How many frames `seq` has when sampled every `seq.frame_time()` from its start to its
/// end, at most [`MAX_FRAMES`].
pub fn sampled_frames(seq: &Sequence) -> Result<usize> {
    // Up to the last key: a duration that is not a whole number of frames gets one more
    // (which holds the last key's value), rather than losing its end.
    let n = (seq.duration() / seq.frame_time() - 1e-9).ceil().max(0.0) as usize + 1;
    if n > MAX_FRAMES {
        return Err(Error::invalid_value(
            "frame count",
            n as f64,
            format!("at most {MAX_FRAMES}"),
        ));
    }
    Ok(n)
}

/// Forward kinematics of a parent-first hierarchy: `globals[j] = globals[parent(j)] ·
/// local(j)`, a root's global being its local.
pub fn chain_globals(
    globals: &mut [Transform],
    parent: impl Fn(usize) -> Option<usize>,
    mut local: impl FnMut(usize) -> Transform,
) {
    for j in 0..globals.len() {
        let l = local(j);
        globals[j] = match parent(j) {
            Some(p) => globals[p].mul(&l),
            None => l,
        };
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use troupe_body::kinematics::forward_kinematics;
    use troupe_body::template::template;
    use troupe_motion::sequence::{Key, Track};

    /// Global joint positions of a troupe skeleton at posture `q`.
    pub(crate) fn fk_positions(skeleton: &Skeleton, q: &[f64]) -> Vec<DVec3> {
        let mut g = vec![Transform::IDENTITY; skeleton.joints().len()];
        forward_kinematics(skeleton, q, &mut g);
        g.iter().map(|t| t.translation).collect()
    }

    /// The adult body at its default size.
    pub(crate) fn adult() -> Skeleton {
        let t = template("adult").unwrap();
        t.instantiate(t.default_params()).unwrap()
    }

    /// A sequence moving every DOF of `skeleton` within its limits: `keys` keys `step`
    /// seconds apart, at `rate` Hz.
    pub(crate) fn every_dof_moving(
        skeleton: &Skeleton,
        keys: usize,
        step: f64,
        rate: &str,
    ) -> Sequence {
        let mut seq = Sequence::new("motion");
        seq.meta.insert("rate".into(), rate.into());
        for (d, dof) in skeleton.dofs().iter().enumerate() {
            let keys = (0..keys)
                .map(|k| {
                    let v = ((d * 7 + k * 3) as f64).sin() * 0.4;
                    Key::new(k as f64 * step, v.clamp(dof.min, dof.max))
                })
                .collect();
            seq.add_track(Track::new(dof.name.clone(), keys).unwrap())
                .unwrap();
        }
        seq
    }

    /// The posture of `seq` at `time` on `skeleton` (DOFs without a track at zero).
    pub(crate) fn posture(skeleton: &Skeleton, seq: &Sequence, time: f64) -> Vec<f64> {
        skeleton
            .dofs()
            .iter()
            .map(|d| seq.track(&d.name).map(|t| t.value(time)).unwrap_or(0.0))
            .collect()
    }

    #[test]
    fn a_hand_keyed_sequence_is_sampled_finely_and_to_its_last_key() {
        let s = adult();
        let mut seq = Sequence::new("keys");
        let keys = vec![Key::new(0.0, 0.0), Key::new(0.3, 0.8), Key::new(1.0, 1.2)];
        seq.add_track(Track::new("l_elbow_flexion", keys).unwrap())
            .unwrap();
        let rig = Rig::from_sequence(&s, &seq).unwrap();
        // Every 10 ms (not every 0.3 s, the keys' spacing: that cut the last 0.1 s off and
        // turned the curve into straight lines), up to the last key.
        assert_eq!(rig.times.len(), 101);
        assert!((rig.times[100] - 1.0).abs() < 1e-9, "{}", rig.times[100]);
        let elbow = s.dof("l_elbow_flexion").unwrap();
        let at = |k: usize| {
            let mut q = vec![0.0; s.dof_count()];
            q[elbow] = seq.tracks()[0].value(rig.times[k]);
            fk_positions(&s, &q)
        };
        for k in [13, 50, 100] {
            for (a, b) in rig.positions(k).iter().zip(&at(k)) {
                assert!((*a - *b).length() < 1e-9, "frame {k}: {a} {b}");
            }
        }
        // A rate that does not divide the duration gets a last frame past it, holding the
        // last key, rather than losing the end.
        seq.meta.insert("rate".into(), "3.5".into());
        let rig = Rig::from_sequence(&s, &seq).unwrap();
        assert_eq!(rig.times.len(), 5);
        assert!(rig.times[4] > 1.0 && rig.times[3] < 1.0);
        assert_eq!(rig.positions(4), at_time(&s, &seq, 1.0));
    }

    /// Joint positions of `seq` at `time` on `skeleton`.
    fn at_time(skeleton: &Skeleton, seq: &Sequence, time: f64) -> Vec<DVec3> {
        fk_positions(skeleton, &posture(skeleton, seq, time))
    }

    #[test]
    fn a_troupe_rig_reproduces_forward_kinematics() {
        let s = adult();
        let mut seq = Sequence::new("wave");
        for (dof, v) in [
            ("l_shoulder_abduction", 1.2),
            ("root_x", 0.5),
            ("l_elbow_flexion", 0.8),
        ] {
            seq.add_track(Track::new(dof, vec![Key::new(0.0, 0.0), Key::new(1.0, v)]).unwrap())
                .unwrap();
        }
        seq.meta.insert("rate".into(), "10".into());
        let rig = Rig::from_sequence(&s, &seq).unwrap();
        assert_eq!(rig.times.len(), 11);
        let want = fk_positions(&s, &posture(&s, &seq, 0.7));
        for (a, b) in rig.positions(7).iter().zip(&want) {
            assert!((*a - *b).length() < 1e-9, "{a} {b}");
        }
        // At rest, the globals are the rest globals.
        let rest = Rig::from_sequence(&s, &Sequence::new("rest")).unwrap();
        assert_eq!(rest.globals(0), rest.rest_globals());
    }

    #[test]
    fn a_turned_rig_turns_every_joint_at_rest_and_in_every_frame() {
        let s = adult();
        let rig = Rig::from_sequence(&s, &every_dof_moving(&s, 3, 0.5, "4")).unwrap();
        let q = DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2) * DQuat::from_rotation_z(0.3);
        let mut turned = rig.clone();
        turned.turn(q);
        let close = |a: &Transform, b: &Transform| {
            (a.translation - b.translation).length() < 1e-12
                && a.rotation.abs_diff_eq(b.rotation, 1e-12)
        };
        let check = |a: Vec<Transform>, b: Vec<Transform>| {
            for (j, (a, b)) in a.iter().zip(&b).enumerate() {
                let want = Transform::new(q * b.rotation, q * b.translation);
                assert!(close(a, &want), "{}: {a:?} vs {want:?}", rig.names[j]);
            }
        };
        check(turned.rest_globals(), rig.rest_globals());
        for k in 0..rig.times.len() {
            check(turned.globals(k), rig.globals(k));
        }
    }
}
