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

/// CesiumMan's bones for troupe's joints (`bones` in Lua, `--bones` on the command line).
const CESIUM_BONES: [(&str, &str); 17] = [
    ("hips", "Skeleton_torso_joint_1"),
    ("spine", "Skeleton_torso_joint_2"),
    ("upperChest", "torso_joint_3"),
    ("neck", "Skeleton_neck_joint_1"),
    ("head", "Skeleton_neck_joint_2"),
    ("leftUpperArm", "Skeleton_arm_joint_L__4_"),
    ("leftLowerArm", "Skeleton_arm_joint_L__3_"),
    ("leftHand", "Skeleton_arm_joint_L__2_"),
    ("rightUpperArm", "Skeleton_arm_joint_R"),
    ("rightLowerArm", "Skeleton_arm_joint_R__2_"),
    ("rightHand", "Skeleton_arm_joint_R__3_"),
    ("leftUpperLeg", "leg_joint_L_1"),
    ("leftLowerLeg", "leg_joint_L_2"),
    ("leftFoot", "leg_joint_L_3"),
    ("rightUpperLeg", "leg_joint_R_1"),
    ("rightLowerLeg", "leg_joint_R_2"),
    ("rightFoot", "leg_joint_R_3"),
];

/// Runs `command`, failing the test with its error output unless it succeeds.
fn succeeds(command: &mut Command) {
    let out = command.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Renders a scene holding one actor made with `options` (Lua table fields) and returns
/// its pixels.
fn render(name: &str, options: &str) -> image::RgbaImage {
    render_from(name, Some(options), "follow:cesium@0,10,2.5")
}

/// Renders, with camera `camera`, a scene holding one actor made with `options` (Lua
/// table fields), or nobody for `None`, and returns its pixels.
fn render_from(name: &str, options: Option<&str>, camera: &str) -> image::RgbaImage {
    let dir = temp_dir();
    let scene = dir.join(format!("{name}.lua"));
    let actor = options.map_or_else(String::new, |options| {
        format!("troupe.actor{{ name = \"cesium\", height = 1.75{options} }}\n")
    });
    std::fs::write(&scene, actor).unwrap();
    let png = dir.join(format!("{name}.png"));
    succeeds(
        troupe()
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
                camera,
                "--no-labels",
            ]),
    );
    image::open(&png).unwrap().to_rgba8()
}

/// The `look` and `bones` options that dress the actor in the character file `file`.
fn cesium_look(file: &std::path::Path) -> String {
    format!(
        ", look = {:?}, bones = {{ {} }}",
        file.display().to_string(),
        CESIUM_BONES
            .map(|(key, node)| format!("{key} = {node:?}"))
            .join(", ")
    )
}

/// The green of the Cesium logo on CesiumMan's face.
fn logo_green(p: &image::Rgba<u8>) -> bool {
    let [r, g, b, _] = p.0.map(i32::from);
    g > r + 40 && g > b + 20
}

#[test]
fn a_dressed_actor_is_drawn_as_its_character() {
    let look = cesium_look(&repo().join("tests/assets/characters/CesiumMan.glb"));
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
fn a_characters_back_faces_are_drawn_only_when_its_file_asks() {
    // CesiumMan's material is single-sided, so seen from inside its chest, looking out
    // through its back, nothing of it is drawn: the picture is the empty scene's. Made
    // double-sided, its inside fills the picture.
    let cesium = repo().join("tests/assets/characters/CesiumMan.glb");
    let bytes = std::fs::read(&cesium).unwrap();
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut json = glb_json(&cesium);
    for material in json["materials"].as_array_mut().unwrap() {
        material["doubleSided"] = serde_json::Value::Bool(true);
    }
    let mut text = json.to_string().into_bytes();
    text.resize(text.len().next_multiple_of(4), b' ');
    let binary = &bytes[20 + len..];
    let mut glb = b"glTF".to_vec();
    glb.extend(2u32.to_le_bytes());
    glb.extend(((20 + text.len() + binary.len()) as u32).to_le_bytes());
    glb.extend((text.len() as u32).to_le_bytes());
    glb.extend(b"JSON");
    glb.extend(text);
    glb.extend(binary);
    let double = temp_dir().join("double_sided.glb");
    std::fs::write(&double, glb).unwrap();
    let inside = "fixed:0,1.1,0:0,1.1,-4";
    let empty = render_from("empty_inside", None, inside);
    let differing = |img: &image::RgbaImage| {
        img.pixels()
            .zip(empty.pixels())
            .filter(|(a, b)| a != b)
            .count()
    };
    let single = render_from("single_inside", Some(&cesium_look(&cesium)), inside);
    let both = render_from("double_inside", Some(&cesium_look(&double)), inside);
    let all = empty.pixels().len();
    assert_eq!(
        differing(&single),
        0,
        "the single-sided character's inside is drawn"
    );
    assert!(
        differing(&both) * 2 > all,
        "the double-sided character's inside covers {} of {all} pixels",
        differing(&both)
    );
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

/// The JSON chunk of a binary glTF file.
fn glb_json(path: &std::path::Path) -> serde_json::Value {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(&bytes[..4], b"glTF", "{} is a .glb", path.display());
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + len]).unwrap()
}

/// The names of a glTF document's nodes.
fn node_names(json: &serde_json::Value) -> Vec<&str> {
    json["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n["name"].as_str())
        .collect()
}

#[test]
fn a_dressed_actor_is_recorded_and_exported_as_its_character() {
    let dir = temp_dir();
    let out = dir.join("character.glb");
    succeeds(
        troupe()
            .current_dir(repo())
            .args([
                "run",
                "scripts/examples/character.lua",
                "--seconds",
                "1",
                "--record",
            ])
            .arg(&out),
    );
    // CesiumMan's actor: its 19 bones as the skin's joints, its mesh marked as a user's
    // character, its bones animated.
    let cesium = glb_json(&dir.join("character.cesium.glb"));
    assert_eq!(cesium["skins"][0]["joints"].as_array().unwrap().len(), 19);
    let names = node_names(&cesium);
    assert!(names.contains(&"Skeleton_arm_joint_R__3_") && !names.contains(&"r_wrist"));
    let mesh_node = cesium["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|n| n.get("mesh").is_some())
        .unwrap();
    assert!(mesh_node["extras"]["troupe_character"]["source"]
        .as_str()
        .unwrap()
        .ends_with("CesiumMan.glb"));
    assert!(
        cesium["animations"][0]["channels"]
            .as_array()
            .unwrap()
            .len()
            > 10
    );
    // Ann keeps troupe's skeleton and generated skin.
    let ann = glb_json(&dir.join("character.ann.glb"));
    assert!(node_names(&ann).contains(&"r_wrist") && node_names(&ann).contains(&"ann skin"));
    // The same with two threads and chunks of one action: the same bytes.
    let again = dir.join("again.glb");
    succeeds(
        troupe()
            .current_dir(repo())
            .args(["run", "scripts/examples/character.lua", "--seconds", "1"])
            .args(["--threads", "2", "--chunk", "1", "--record"])
            .arg(&again),
    );
    assert!(
        std::fs::read(dir.join("again.cesium.glb")).unwrap()
            == std::fs::read(dir.join("character.cesium.glb")).unwrap()
    );
    // Played back as a troupe motion, CesiumMan's file is refused with a reason.
    let view = troupe()
        .args(["seq", "convert"])
        .arg(dir.join("character.cesium.glb"))
        .arg(dir.join("back.trk"))
        .args(["--template", "adult"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&view.stderr);
    assert!(
        !view.status.success() && err.contains("user's character"),
        "{err}"
    );

    // `troupe export gltf --look`, with the map given as `--bones`.
    let bones = CESIUM_BONES
        .map(|(key, node)| format!("{key}={node}"))
        .join(",");
    for (pose, animated) in [("rest", true), ("bind", false)] {
        let file = dir.join(format!("cesium_{pose}.glb"));
        succeeds(
            troupe()
                .current_dir(repo())
                .args(["export", "gltf"])
                .arg(&file)
                .args([
                    "--look",
                    "tests/assets/characters/CesiumMan.glb",
                    "--bones",
                    &bones,
                ])
                .args(["--pose", pose]),
        );
        let json = glb_json(&file);
        assert_eq!(json["skins"][0]["joints"].as_array().unwrap().len(), 19);
        assert_eq!(json.get("animations").is_some(), animated, "{pose}");
    }
    // A map that names a node the file lacks is refused, naming it.
    let export = troupe()
        .current_dir(repo())
        .args(["export", "gltf"])
        .arg(dir.join("bad.glb"))
        .args([
            "--look",
            "tests/assets/characters/CesiumMan.glb",
            "--bones",
            "hips=Pelvis",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&export.stderr);
    assert!(
        !export.status.success() && err.contains("`Pelvis`"),
        "{err}"
    );
}
