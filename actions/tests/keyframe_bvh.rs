//! A BVH motion retargeted onto the adult template plays through the Keyframe generator.

use std::path::Path;
use troupe_actions::Keyframe;
use troupe_body::template;
use troupe_formats::retarget::load_sequence_for;

#[test]
fn retargeted_cmu_walk_binds_to_the_keyframe_generator() {
    let t = template("adult").unwrap();
    let skeleton = t.instantiate(t.default_params()).unwrap();
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../shared/data/bvh/pybvhrepo_cmu_12_01_walk.bvh"
    );
    let seq = load_sequence_for(&skeleton, Path::new(path)).unwrap();
    let k = Keyframe::new(&skeleton, &seq, None, None).unwrap();
    assert!((k.length() - 523.0 / 120.0).abs() < 1e-3, "{}", k.length());
    let scope = k.scope();
    for dof in [
        "root_x",
        "root_yaw",
        "l_hip_flexion",
        "r_knee_flexion",
        "l_shoulder_abduction",
    ] {
        assert!(scope.contains(skeleton.dof(dof).unwrap()), "{dof}");
    }
    // Fingers are not in the CMU rig: their DOFs stay with whoever else drives them.
    assert!(!scope.contains(skeleton.dof("l_index1_flexion").unwrap()));
}
