//! The VRM humanoid bones troupe fills, each with its VRM parent and the template joint
//! whose segment it is (the table of `docs/devices.md`).
//!
//! Names are Unity's `HumanBodyBones`, which the VMC protocol sends. A VRM bone may span
//! several template joints: the chain from its joint up to (not including) its VRM
//! parent's joint. Those joints share the bone's rotation when a stream is received
//! (`Foot` moves the ankle and the subtalar joint, `UpperChest` vt6 and vt1). The pelvis
//! (`sacroiliac`) rotates with the whole body in VRM: `Hips` is its segment, and a
//! receiver puts that rotation on the root, with the pelvis joint held straight.

/// One VRM humanoid bone and the template joint that carries it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VrmBone {
    /// Unity `HumanBodyBones` name, as VMC sends it.
    pub name: &'static str,
    /// The VRM parent bone (`None` for `Hips`, whose parent is the VMC root).
    pub parent: Option<&'static str>,
    /// The template joint whose segment the bone is.
    pub joint: &'static str,
}

const fn bone(name: &'static str, parent: &'static str, joint: &'static str) -> VrmBone {
    VrmBone {
        name,
        parent: Some(parent),
        joint,
    }
}

/// Every VRM humanoid bone troupe fills, parents before children.
pub const VRM_BONES: &[VrmBone] = &[
    VrmBone {
        name: "Hips",
        parent: None,
        joint: "sacroiliac",
    },
    bone("LeftUpperLeg", "Hips", "l_hip"),
    bone("LeftLowerLeg", "LeftUpperLeg", "l_knee"),
    bone("LeftFoot", "LeftLowerLeg", "l_subtalar"),
    bone("LeftToes", "LeftFoot", "l_metatarsal"),
    bone("RightUpperLeg", "Hips", "r_hip"),
    bone("RightLowerLeg", "RightUpperLeg", "r_knee"),
    bone("RightFoot", "RightLowerLeg", "r_subtalar"),
    bone("RightToes", "RightFoot", "r_metatarsal"),
    bone("Spine", "Hips", "vl5"),
    bone("Chest", "Spine", "vt12"),
    bone("UpperChest", "Chest", "vt1"),
    bone("Neck", "UpperChest", "vc4"),
    bone("Head", "Neck", "skullbase"),
    bone("LeftEye", "Head", "l_eyeball_joint"),
    bone("RightEye", "Head", "r_eyeball_joint"),
    bone("LeftShoulder", "UpperChest", "l_sternoclavicular"),
    bone("LeftUpperArm", "LeftShoulder", "l_shoulder"),
    bone("LeftLowerArm", "LeftUpperArm", "l_elbow"),
    bone("LeftHand", "LeftLowerArm", "l_wrist"),
    bone("RightShoulder", "UpperChest", "r_sternoclavicular"),
    bone("RightUpperArm", "RightShoulder", "r_shoulder"),
    bone("RightLowerArm", "RightUpperArm", "r_elbow"),
    bone("RightHand", "RightLowerArm", "r_wrist"),
    bone("LeftThumbProximal", "LeftHand", "l_thumb1"),
    bone("LeftThumbIntermediate", "LeftThumbProximal", "l_thumb2"),
    bone("LeftThumbDistal", "LeftThumbIntermediate", "l_thumb3"),
    bone("LeftIndexProximal", "LeftHand", "l_index1"),
    bone("LeftIndexIntermediate", "LeftIndexProximal", "l_index2"),
    bone("LeftIndexDistal", "LeftIndexIntermediate", "l_index3"),
    bone("LeftMiddleProximal", "LeftHand", "l_middle1"),
    bone("LeftMiddleIntermediate", "LeftMiddleProximal", "l_middle2"),
    bone("LeftMiddleDistal", "LeftMiddleIntermediate", "l_middle3"),
    bone("LeftRingProximal", "LeftHand", "l_ring1"),
    bone("LeftRingIntermediate", "LeftRingProximal", "l_ring2"),
    bone("LeftRingDistal", "LeftRingIntermediate", "l_ring3"),
    bone("LeftLittleProximal", "LeftHand", "l_pinky1"),
    bone("LeftLittleIntermediate", "LeftLittleProximal", "l_pinky2"),
    bone("LeftLittleDistal", "LeftLittleIntermediate", "l_pinky3"),
    bone("RightThumbProximal", "RightHand", "r_thumb1"),
    bone("RightThumbIntermediate", "RightThumbProximal", "r_thumb2"),
    bone("RightThumbDistal", "RightThumbIntermediate", "r_thumb3"),
    bone("RightIndexProximal", "RightHand", "r_index1"),
    bone("RightIndexIntermediate", "RightIndexProximal", "r_index2"),
    bone("RightIndexDistal", "RightIndexIntermediate", "r_index3"),
    bone("RightMiddleProximal", "RightHand", "r_middle1"),
    bone(
        "RightMiddleIntermediate",
        "RightMiddleProximal",
        "r_middle2",
    ),
    bone("RightMiddleDistal", "RightMiddleIntermediate", "r_middle3"),
    bone("RightRingProximal", "RightHand", "r_ring1"),
    bone("RightRingIntermediate", "RightRingProximal", "r_ring2"),
    bone("RightRingDistal", "RightRingIntermediate", "r_ring3"),
    bone("RightLittleProximal", "RightHand", "r_pinky1"),
    bone("RightLittleIntermediate", "RightLittleProximal", "r_pinky2"),
    bone("RightLittleDistal", "RightLittleIntermediate", "r_pinky3"),
];

/// The VRM humanoid bones troupe has no joint for: accepted on input and ignored
/// (`Jaw`; `LastBone` is Unity's end marker that some senders include).
pub const IGNORED_BONES: &[&str] = &["Jaw", "LastBone"];

/// The index in [`VRM_BONES`] of a bone name.
pub fn bone_index(name: &str) -> Option<usize> {
    VRM_BONES.iter().position(|b| b.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parents_come_first_and_every_joint_exists() {
        let sk = troupe_body::template::default_skeleton("adult").unwrap();
        for (i, b) in VRM_BONES.iter().enumerate() {
            if let Some(p) = b.parent {
                assert!(bone_index(p).unwrap() < i, "{} before its parent", b.name);
            }
            assert!(sk.joint(b.joint).is_ok(), "{} → {}", b.name, b.joint);
        }
        assert_eq!(VRM_BONES.len(), 54);
    }
}
