//! End to end: an actor dressed in a user's character (`troupe.actor{ look = … }`) is
//! drawn with the character's own mesh and colours, and a bad look stops the scene with
//! a message naming the file.

use std::path::PathBuf;
use std::process::Command;

fn troupe() -> Command {
    Command::new(env!("CARGO_BIN_EXE_troupe"))
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("troupe-character-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Renders a scene holding one actor made with `options` (Lua table fields) and returns
/// its pixels.
fn render(name: &str, options: &str) -> image::RgbaImage {
    let dir = temp_dir();
    let scene = dir.join(format!("{name}.lua"));
    std::fs::write(
        &scene,
        format!("troupe.actor{{ name = \"cesium\", height = 1.75{options} }}\n"),
    )
    .unwrap();
    let png = dir.join(format!("{name}.png"));
    let out = troupe()
        .current_dir(repo())
        .args(["render"])
        .arg(&scene)
        .arg(&png)
        .args([
            "--at",
            "0",
            "--size",
            "320x240",
            "--camera",
            "follow:cesium@0,10,2.5",
            "--no-labels",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    image::open(&png).unwrap().to_rgba8()
}

/// The green of the Cesium logo on CesiumMan's face.
fn logo_green(p: &image::Rgba<u8>) -> bool {
    let [r, g, b, _] = p.0.map(i32::from);
    g > r + 40 && g > b + 20
}

#[test]
fn a_dressed_actor_is_drawn_as_its_character() {
    let look = format!(
        ", look = {:?}, bones = {{ hips = \"Skeleton_torso_joint_1\", spine = \"Skeleton_torso_joint_2\", \
         upperChest = \"torso_joint_3\", neck = \"Skeleton_neck_joint_1\", head = \"Skeleton_neck_joint_2\", \
         leftUpperArm = \"Skeleton_arm_joint_L__4_\", leftLowerArm = \"Skeleton_arm_joint_L__3_\", \
         leftHand = \"Skeleton_arm_joint_L__2_\", rightUpperArm = \"Skeleton_arm_joint_R\", \
         rightLowerArm = \"Skeleton_arm_joint_R__2_\", rightHand = \"Skeleton_arm_joint_R__3_\", \
         leftUpperLeg = \"leg_joint_L_1\", leftLowerLeg = \"leg_joint_L_2\", leftFoot = \"leg_joint_L_3\", \
         rightUpperLeg = \"leg_joint_R_1\", rightLowerLeg = \"leg_joint_R_2\", rightFoot = \"leg_joint_R_3\" }}",
        repo().join("tests/assets/characters/CesiumMan.glb").display().to_string()
    );
    let dressed = render("dressed", &look);
    let plain = render("plain", "");
    let differ = dressed
        .pixels()
        .zip(plain.pixels())
        .filter(|(a, b)| a != b)
        .count();
    assert!(
        differ * 20 > dressed.pixels().len(),
        "only {differ} pixels differ between the character and the generated skin"
    );
    let green = dressed.pixels().filter(|p| logo_green(p)).count();
    assert!(
        green > 50,
        "CesiumMan's face shows its logo: {green} green pixels"
    );
    assert_eq!(plain.pixels().filter(|p| logo_green(p)).count(), 0);
}

#[test]
fn a_bad_look_stops_the_scene_naming_the_file() {
    let dir = temp_dir();
    let scene = dir.join("bad.lua");
    let vrm = repo().join("tests/assets/characters/VRM1_humanoid_no_skin.vrm");
    std::fs::write(
        &scene,
        format!(
            "troupe.actor{{ name = \"x\", look = {:?} }}\n",
            vrm.display().to_string()
        ),
    )
    .unwrap();
    let out = troupe()
        .args(["run", "--seconds", "0.1"])
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("VRM1_humanoid_no_skin.vrm") && err.contains("no skin"),
        "{err}"
    );
}
