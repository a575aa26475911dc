//! End to end: the skinned characters `troupe export gltf` writes and the skinned
//! recordings of `troupe run --record OUT.glb|.gltf` pass the Khronos glTF validator with
//! no error and no warning, and a bad template or extension is refused with a message.
//!
//! The validator is the npm package `gltf-validator`, which `scripts/setup.sh` installs
//! into `.tools/node`; without node or that package the validation prints why and is
//! skipped (the files are still written and checked for their skin).

use std::path::{Path, PathBuf};
use std::process::Command;

fn troupe() -> Command {
    Command::new(env!("CARGO_BIN_EXE_troupe"))
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("troupe-skin-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The JSON of a `.gltf` file, or of a `.glb`'s JSON chunk.
fn document(path: &Path) -> serde_json::Value {
    let bytes = std::fs::read(path).unwrap();
    let json = if bytes.starts_with(b"glTF") {
        let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        &bytes[20..20 + len]
    } else {
        &bytes[..]
    };
    serde_json::from_slice(json).unwrap()
}

fn validate(files: &[PathBuf]) {
    let modules = repo().join(".tools/node/node_modules");
    if Command::new("node").arg("--version").output().is_err()
        || !modules.join("gltf-validator").is_dir()
    {
        println!("skipped validation: node or the gltf-validator package is missing (scripts/setup.sh installs it)");
        return;
    }
    let out = Command::new("node")
        .arg(repo().join("scripts/validate-gltf.js"))
        .args(files)
        .env("NODE_PATH", &modules)
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&out.stdout);
    println!("{report}{}", String::from_utf8_lossy(&out.stderr));
    assert!(
        out.status.success(),
        "the validator reports problems:\n{report}"
    );
}

#[test]
fn exported_and_recorded_characters_carry_a_valid_skin() {
    let dir = temp_dir("export");
    let adult = dir.join("adult.glb");
    let child = dir.join("child.gltf");
    for args in [
        vec!["export", "gltf", adult.to_str().unwrap()],
        vec![
            "export",
            "gltf",
            child.to_str().unwrap(),
            "--template",
            "child",
            "--height",
            "1.1",
        ],
    ] {
        let out = troupe().args(&args).output().unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert!(dir.join("child.bin").is_file());
    let record = dir.join("wave.glb");
    let scene = repo().join("scripts/examples/greeting.lua");
    let out = troupe()
        .args(["run", scene.to_str().unwrap(), "--seconds", "1", "--record"])
        .arg(&record)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "glb" || e == "gltf"))
        .collect();
    files.sort();
    assert!(files.len() >= 3, "{files:?}");
    for f in &files {
        let doc = document(f);
        let skinned = doc["nodes"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|n| n.get("mesh").is_some() && n.get("skin").is_some())
            .count();
        assert_eq!(skinned, 1, "{}: one skinned mesh node", f.display());
        let attributes = &doc["meshes"][0]["primitives"][0]["attributes"];
        for a in ["POSITION", "NORMAL", "JOINTS_0", "WEIGHTS_0"] {
            assert!(attributes.get(a).is_some(), "{}: {a}", f.display());
        }
    }
    validate(&files);
    std::fs::remove_dir_all(dir).ok();
}

#[test]
fn export_refuses_a_bad_template_or_extension() {
    let dir = temp_dir("bad");
    let out = troupe()
        .args(["export", "gltf"])
        .arg(dir.join("x.glb"))
        .args(["--template", "giant"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown body template `giant`"));
    let out = troupe()
        .args(["export", "gltf"])
        .arg(dir.join("x.bvh"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("x.bvh") && err.contains(".gltf or .glb"),
        "{err}"
    );
    std::fs::remove_dir_all(dir).ok();
}
