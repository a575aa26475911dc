//! troupe's inverse dynamics agrees with an independent RNEA — Pinocchio's — run on the
//! URDF troupe exports of the same body, for a fixed and a free root, at random states;
//! and Pinocchio's forward dynamics (ABA) on that file gives back the accelerations.
//!
//! Pinocchio is the PyPI package `pin`, which `scripts/setup.sh` installs into
//! `.tools/python`; without it the test prints why and checks nothing. The comparison
//! itself is `scripts/pinocchio/urdf_dynamics.py`.

use std::path::{Path, PathBuf};
use std::process::Command;
use troupe_body::dynamics::{inverse_dynamics, ExternalForces, Model, GRAVITY};
use troupe_body::math::draws;
use troupe_body::template::template;
use troupe_formats::urdf::urdf;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Reproducible draws in [lo, hi) from `draws`'s draws in [0, 1).
fn within(draw: &mut impl FnMut() -> f64, lo: f64, hi: f64) -> f64 {
    lo + (hi - lo) * draw()
}

/// Runs the comparison for `template_name` and returns Pinocchio's report.
fn compare(python: &Path, template_name: &str, fixed_root: bool, dir: &Path) -> serde_json::Value {
    let t = template(template_name).unwrap();
    let skeleton = t.instantiate(t.default_params()).unwrap();
    let tag = format!(
        "{template_name}-{}",
        if fixed_root { "fixed" } else { "free" }
    );
    let urdf_path = dir.join(format!("{tag}.urdf"));
    std::fs::write(&urdf_path, urdf(&skeleton, fixed_root).unwrap()).unwrap();
    let model = Model::new(&skeleton).unwrap();
    let n = skeleton.dof_count();
    let root = model.root_dofs();
    let mut draw = draws(if fixed_root { 11 } else { 29 });
    let mut states = Vec::new();
    for _ in 0..8 {
        let (mut q, mut qd, mut qdd) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for (i, d) in skeleton.dofs().iter().enumerate() {
            // A fixed root stands where the URDF fixes it: at the rest pose.
            if fixed_root && root.contains(&i) {
                continue;
            }
            let (lo, hi) = if d.min.is_finite() && d.max.is_finite() {
                (d.min, d.max)
            } else {
                (-1.0, 1.0)
            };
            q[i] = within(&mut draw, lo, hi);
            qd[i] = within(&mut draw, -2.0, 2.0);
            qdd[i] = within(&mut draw, -5.0, 5.0);
        }
        let ext = ExternalForces::new(&skeleton);
        let tau = inverse_dynamics(&skeleton, &q, &qd, &qdd, &ext, fixed_root).unwrap();
        states.push(serde_json::json!({ "q": q, "qd": qd, "qdd": qdd, "tau": tau }));
    }
    let case = serde_json::json!({
        "urdf": urdf_path,
        "fixed_root": fixed_root,
        "gravity": -GRAVITY.y,
        "dofs": skeleton.dofs().iter().map(|d| d.name.clone()).collect::<Vec<_>>(),
        "states": states,
    });
    let case_path = dir.join(format!("{tag}.json"));
    std::fs::write(&case_path, case.to_string()).unwrap();
    let out = Command::new(python)
        .arg(repo().join("scripts/pinocchio/urdf_dynamics.py"))
        .arg(&case_path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{tag}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    println!("{tag}: {report}");
    report
}

#[test]
fn inverse_dynamics_equals_pinocchio_rnea_on_the_exported_urdf() {
    let python = repo().join(".tools/python/bin/python");
    let has_pin = Command::new(&python)
        .args(["-c", "import pinocchio"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !has_pin {
        println!(
            "skipped: Pinocchio is not installed (scripts/setup.sh installs the PyPI package `pin` into {})",
            python.display()
        );
        return;
    }
    let dir = std::env::temp_dir().join(format!("troupe-pinocchio-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, fixed) in [
        ("adult", true),
        ("adult", false),
        ("child", true),
        ("child", false),
    ] {
        let report = compare(&python, name, fixed, &dir);
        let worst = report["torque"]["relative"].as_f64().unwrap();
        assert!(worst <= 1e-9, "{name} fixed_root={fixed}: {report}");
        assert_eq!(
            report["aba_finite"], true,
            "{name} fixed_root={fixed}: {report}"
        );
        let aba = report["aba_relative"].as_f64().unwrap();
        assert!(aba <= 1e-6, "{name} fixed_root={fixed}: {report}");
    }
    std::fs::remove_dir_all(dir).ok();
}
