//! Khronos' CesiumMan (tests/assets/characters/), shared by the tests that dress it.

use std::path::PathBuf;

/// A file of the third-party characters in `tests/assets/characters/`.
pub fn asset(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/assets/characters")
        .join(name)
}

/// The VRM humanoid bones of CesiumMan, whose joints have names of their own.
pub const CESIUM_BONES: [(&str, &str); 19] = [
    ("hips", "Skeleton_torso_joint_1"),
    ("spine", "Skeleton_torso_joint_2"),
    ("upperChest", "torso_joint_3"),
    ("neck", "Skeleton_neck_joint_1"),
    ("head", "Skeleton_neck_joint_2"),
    ("rightUpperArm", "Skeleton_arm_joint_R"),
    ("rightLowerArm", "Skeleton_arm_joint_R__2_"),
    ("rightHand", "Skeleton_arm_joint_R__3_"),
    ("leftUpperArm", "Skeleton_arm_joint_L__4_"),
    ("leftLowerArm", "Skeleton_arm_joint_L__3_"),
    ("leftHand", "Skeleton_arm_joint_L__2_"),
    ("rightUpperLeg", "leg_joint_R_1"),
    ("rightLowerLeg", "leg_joint_R_2"),
    ("rightFoot", "leg_joint_R_3"),
    ("rightToes", "leg_joint_R_5"),
    ("leftUpperLeg", "leg_joint_L_1"),
    ("leftLowerLeg", "leg_joint_L_2"),
    ("leftFoot", "leg_joint_L_3"),
    ("leftToes", "leg_joint_L_5"),
];

/// The `bones` map a user gives for CesiumMan.
pub fn cesium_map() -> Vec<(String, String)> {
    CESIUM_BONES
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect()
}
