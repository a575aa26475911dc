//! BVH motions and rigs, both ways: a BVH on its own hierarchy as a [`Rig`] (for glTF), and
//! a rig's motion (a troupe recording) as BVH.

use super::channel::{Axis, Channel, RotationOrder};
use super::motion::{Bvh, BvhJoint};
use crate::error::Result;
use crate::rig::Rig;
use glam::{DQuat, DVec3};
use troupe_body::transform::Transform;

impl Rig {
    /// A BVH motion on its own hierarchy; lengths are multiplied by `scale` (metres per
    /// file unit). End sites become leaf joints named `<joint>_end`.
    pub fn from_bvh(bvh: &Bvh, scale: f64) -> Rig {
        let joints = bvh.joints();
        let mut names: Vec<String> = joints.iter().map(|j| j.name.clone()).collect();
        let mut parents: Vec<Option<usize>> = joints.iter().map(|j| j.parent).collect();
        let mut rest: Vec<Transform> = joints
            .iter()
            .map(|j| Transform::from_translation(j.offset * scale))
            .collect();
        let mut ends = Vec::new();
        for (j, jt) in joints.iter().enumerate() {
            for (e, off) in jt.end_sites.iter().enumerate() {
                let suffix = if e == 0 {
                    String::new()
                } else {
                    format!("{e}")
                };
                names.push(format!("{}_end{suffix}", jt.name));
                parents.push(Some(j));
                rest.push(Transform::from_translation(*off * scale));
                ends.push(j);
            }
        }
        let moving: Vec<usize> = (0..joints.len())
            .filter(|&j| {
                joints[j]
                    .channels
                    .iter()
                    .any(|c| matches!(c, Channel::Position(_)))
            })
            .collect();
        let n = bvh.frame_count();
        let mut rig = Rig {
            names,
            parents,
            rest,
            times: (0..n).map(|k| k as f64 * bvh.frame_time()).collect(),
            rotations: Vec::with_capacity(n),
            moving: moving.clone(),
            translations: Vec::with_capacity(n),
        };
        for k in 0..n {
            let frame = bvh.frame(k);
            let locals: Vec<Transform> = (0..joints.len())
                .map(|j| bvh.local_transform(j, frame))
                .collect();
            let mut rots: Vec<DQuat> = locals.iter().map(|l| l.rotation).collect();
            rots.extend(ends.iter().map(|_| DQuat::IDENTITY));
            rig.rotations.push(rots);
            rig.translations.push(
                moving
                    .iter()
                    .map(|&j| locals[j].translation * scale)
                    .collect(),
            );
        }
        rig
    }
}

/// Writes a rig's motion (e.g. a troupe recording, via [`Rig::from_sequence`])
/// as BVH: every joint gets three rotation channels in `order` (the root also three
/// position channels), offsets and positions are in file units of `units_per_metre`
/// (100 for centimetres), frames every `frame_time` seconds.
pub fn from_rig(
    rig: &Rig,
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
    use crate::bvh::fixtures::data;
    use crate::bvh::read_bvh;

    #[test]
    fn a_bvh_rig_has_the_bvh_joint_positions() {
        let bvh = read_bvh(data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        let rig = Rig::from_bvh(&bvh, 0.056444);
        assert_eq!(rig.names.len(), 31 + 7);
        for k in [0, 100, 523] {
            for (a, b) in rig.positions(k).iter().zip(bvh.joint_positions(k)) {
                assert!((*a - b * 0.056444).length() < 1e-9);
            }
        }
    }
}
