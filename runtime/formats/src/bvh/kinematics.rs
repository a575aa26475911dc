//! Forward kinematics of a BVH motion: a joint's local transform is `translate(t) · R`,
//! composed down the hierarchy by the rig FK, [`chain_globals`].

use super::channel::Channel;
use super::motion::Bvh;
use crate::rig::chain_globals;
use glam::{DQuat, DVec3};
use troupe_body::transform::Transform;

impl Bvh {
    /// The local transform (file units) of joint `j` for channel values `frame`.
    pub fn local_transform(&self, j: usize, frame: &[f64]) -> Transform {
        let joint = &self.joints()[j];
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
        chain_globals(
            &mut globals[..self.joints().len()],
            |j| self.joints()[j].parent,
            |j| self.local_transform(j, frame),
        );
    }

    /// Global joint positions (file units) at frame `k`.
    pub fn joint_positions(&self, k: usize) -> Vec<DVec3> {
        let mut g = vec![Transform::IDENTITY; self.joints().len()];
        self.global_transforms(k, &mut g);
        g.iter().map(|t| t.translation).collect()
    }

    /// Global joint positions in the rest pose (every channel zero, offsets only).
    pub fn rest_positions(&self) -> Vec<DVec3> {
        let mut p: Vec<DVec3> = Vec::with_capacity(self.joints().len());
        for j in self.joints() {
            let base = j.parent.map_or(DVec3::ZERO, |i| p[i]);
            p.push(base + j.offset);
        }
        p
    }
}

#[cfg(test)]
mod tests {
    use crate::bvh::parse_bvh;
    use glam::DVec3;

    #[test]
    fn intrinsic_composition_in_listed_order() {
        let text = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\nJOINT b\n{\nOFFSET 0 1 0\nCHANNELS 0\n}\n}\nMOTION\nFrames: 1\nFrame Time: 0.1\n90 90 0\n";
        let b = parse_bvh(text, "t").unwrap();
        // Rz(90)·Rx(90) applied to (0,1,0): Rx maps Y to Z, Rz leaves Z.
        let p = b.joint_positions(0)[1];
        assert!((p - DVec3::Z).length() < 1e-12, "{p}");
    }
}
