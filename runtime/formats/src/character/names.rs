//! Which troupe joint a character's bone follows, by name: the VRM humanoid bone names
//! are the common vocabulary (VRM files name their bones with them; Mixamo's names are
//! translated into them; a user's `bones` map uses them as keys), then each VRM bone
//! names its troupe joint. H-Anim names are troupe's own joint names.

/// VRM 1.0 humanoid bones and the troupe joint each follows (the joint whose world
/// rotation is the bone's: `leftFoot` turns with the subtalar joint below the ankle).
pub const VRM_BONES: &[(&str, &str)] = &[
    ("hips", "sacroiliac"),
    ("spine", "vl5"),
    ("chest", "vt12"),
    ("upperChest", "vt1"),
    ("neck", "vc4"),
    ("head", "skullbase"),
    ("leftEye", "l_eyeball_joint"),
    ("rightEye", "r_eyeball_joint"),
    ("leftUpperLeg", "l_hip"),
    ("leftLowerLeg", "l_knee"),
    ("leftFoot", "l_subtalar"),
    ("leftToes", "l_metatarsal"),
    ("rightUpperLeg", "r_hip"),
    ("rightLowerLeg", "r_knee"),
    ("rightFoot", "r_subtalar"),
    ("rightToes", "r_metatarsal"),
    ("leftShoulder", "l_sternoclavicular"),
    ("leftUpperArm", "l_shoulder"),
    ("leftLowerArm", "l_elbow"),
    ("leftHand", "l_wrist"),
    ("rightShoulder", "r_sternoclavicular"),
    ("rightUpperArm", "r_shoulder"),
    ("rightLowerArm", "r_elbow"),
    ("rightHand", "r_wrist"),
    ("leftThumbMetacarpal", "l_thumb1"),
    ("leftThumbProximal", "l_thumb2"),
    ("leftThumbDistal", "l_thumb3"),
    ("leftIndexProximal", "l_index1"),
    ("leftIndexIntermediate", "l_index2"),
    ("leftIndexDistal", "l_index3"),
    ("leftMiddleProximal", "l_middle1"),
    ("leftMiddleIntermediate", "l_middle2"),
    ("leftMiddleDistal", "l_middle3"),
    ("leftRingProximal", "l_ring1"),
    ("leftRingIntermediate", "l_ring2"),
    ("leftRingDistal", "l_ring3"),
    ("leftLittleProximal", "l_pinky1"),
    ("leftLittleIntermediate", "l_pinky2"),
    ("leftLittleDistal", "l_pinky3"),
    ("rightThumbMetacarpal", "r_thumb1"),
    ("rightThumbProximal", "r_thumb2"),
    ("rightThumbDistal", "r_thumb3"),
    ("rightIndexProximal", "r_index1"),
    ("rightIndexIntermediate", "r_index2"),
    ("rightIndexDistal", "r_index3"),
    ("rightMiddleProximal", "r_middle1"),
    ("rightMiddleIntermediate", "r_middle2"),
    ("rightMiddleDistal", "r_middle3"),
    ("rightRingProximal", "r_ring1"),
    ("rightRingIntermediate", "r_ring2"),
    ("rightRingDistal", "r_ring3"),
    ("rightLittleProximal", "r_pinky1"),
    ("rightLittleIntermediate", "r_pinky2"),
    ("rightLittleDistal", "r_pinky3"),
];

/// The VRM humanoid bones a character must have (VRM 1.0's required set).
pub const REQUIRED: &[&str] = &[
    "hips",
    "spine",
    "head",
    "leftUpperArm",
    "leftLowerArm",
    "leftHand",
    "rightUpperArm",
    "rightLowerArm",
    "rightHand",
    "leftUpperLeg",
    "leftLowerLeg",
    "leftFoot",
    "rightUpperLeg",
    "rightLowerLeg",
    "rightFoot",
];

/// VRM 0.x thumb bones, one joint further out than VRM 1.0's of the same name.
pub const VRM0_THUMBS: &[(&str, &str)] = &[
    ("leftThumbProximal", "leftThumbMetacarpal"),
    ("leftThumbIntermediate", "leftThumbProximal"),
    ("leftThumbDistal", "leftThumbDistal"),
    ("rightThumbProximal", "rightThumbMetacarpal"),
    ("rightThumbIntermediate", "rightThumbProximal"),
    ("rightThumbDistal", "rightThumbDistal"),
];

/// Mixamo bone names (after a `mixamorig:` prefix) and their VRM humanoid bones.
const MIXAMO: &[(&str, &str)] = &[
    ("Hips", "hips"),
    ("Spine", "spine"),
    ("Spine1", "chest"),
    ("Spine2", "upperChest"),
    ("Neck", "neck"),
    ("Head", "head"),
    ("LeftEye", "leftEye"),
    ("RightEye", "rightEye"),
    ("LeftUpLeg", "leftUpperLeg"),
    ("LeftLeg", "leftLowerLeg"),
    ("LeftFoot", "leftFoot"),
    ("LeftToeBase", "leftToes"),
    ("RightUpLeg", "rightUpperLeg"),
    ("RightLeg", "rightLowerLeg"),
    ("RightFoot", "rightFoot"),
    ("RightToeBase", "rightToes"),
    ("LeftShoulder", "leftShoulder"),
    ("LeftArm", "leftUpperArm"),
    ("LeftForeArm", "leftLowerArm"),
    ("LeftHand", "leftHand"),
    ("RightShoulder", "rightShoulder"),
    ("RightArm", "rightUpperArm"),
    ("RightForeArm", "rightLowerArm"),
    ("RightHand", "rightHand"),
];

/// Mixamo's finger bones: `LeftHandIndex1` is `leftIndexProximal`, and so on.
const MIXAMO_FINGERS: &[(&str, [&str; 3])] = &[
    ("Thumb", ["ThumbMetacarpal", "ThumbProximal", "ThumbDistal"]),
    (
        "Index",
        ["IndexProximal", "IndexIntermediate", "IndexDistal"],
    ),
    (
        "Middle",
        ["MiddleProximal", "MiddleIntermediate", "MiddleDistal"],
    ),
    ("Ring", ["RingProximal", "RingIntermediate", "RingDistal"]),
    (
        "Pinky",
        ["LittleProximal", "LittleIntermediate", "LittleDistal"],
    ),
];

/// H-Anim 2.0 joint names that troupe calls otherwise.
const HANIM_ALIASES: &[(&str, &str)] = &[
    ("l_talocrural", "l_ankle"),
    ("r_talocrural", "r_ankle"),
    ("l_radiocarpal", "l_wrist"),
    ("r_radiocarpal", "r_wrist"),
    ("humanoid_root", "HumanoidRoot"),
];

/// The troupe joint of a VRM humanoid bone name (exact, as VRM spells it).
pub fn vrm_joint(bone: &str) -> Option<&'static str> {
    VRM_BONES.iter().find(|(b, _)| *b == bone).map(|(_, j)| *j)
}

/// The VRM humanoid bone of a Mixamo bone name (`mixamorig:LeftForeArm`; any prefix up
/// to a `:` is ignored).
pub fn mixamo_bone(name: &str) -> Option<String> {
    let bare = name.rsplit(':').next().unwrap_or(name);
    if let Some((_, vrm)) = MIXAMO.iter().find(|(m, _)| *m == bare) {
        return Some((*vrm).to_string());
    }
    let (side, rest) = if let Some(r) = bare.strip_prefix("LeftHand") {
        ("left", r)
    } else {
        ("right", bare.strip_prefix("RightHand")?)
    };
    let (finger, vrm) = MIXAMO_FINGERS.iter().find(|(f, _)| rest.starts_with(f))?;
    let k: usize = rest[finger.len()..].parse().ok()?;
    Some(format!("{side}{}", vrm.get(k.checked_sub(1)?)?))
}

/// The troupe joint an H-Anim joint name stands for: troupe's joint names are H-Anim's
/// (`l_elbow`, `vt12`, `skullbase`), matched without regard to case, plus H-Anim 2.0's
/// names that differ (`l_talocrural`, `l_radiocarpal`).
pub fn hanim_joint<'a>(name: &str, troupe_joints: &'a [&'a str]) -> Option<&'a str> {
    let name = HANIM_ALIASES
        .iter()
        .find(|(h, _)| h.eq_ignore_ascii_case(name))
        .map_or(name, |(_, t)| *t);
    troupe_joints
        .iter()
        .copied()
        .find(|j| j.eq_ignore_ascii_case(name))
}
