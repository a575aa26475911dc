//! The live window under a real display (e.g. `xvfb-run cargo test`). Without DISPLAY or
//! WAYLAND_DISPLAY this test skips: CI is headless and covers rendering offscreen.

use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use troupe_scene::{ActorDesc, Scene, SceneConfig};
use troupe_viewer::{run_window, Frame, WindowOptions};

fn has_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

#[test]
fn window_plays_a_scene_and_closes() {
    if !has_display() {
        eprintln!("skipped: no DISPLAY or WAYLAND_DISPLAY (run under xvfb-run to test the window)");
        return;
    }
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    let ann = scene.add_actor(&ActorDesc::new("ann")).unwrap();
    let elbow = scene.actors()[ann].skeleton.dof("r_elbow_flexion").unwrap();
    let steps = Arc::new(AtomicU64::new(0));
    let counter = steps.clone();
    let options = WindowOptions {
        title: "troupe window test".into(),
        size: (320, 240),
        close_after_frames: Some(20),
        ..WindowOptions::default()
    };
    run_window(options, move || {
        let n = counter.fetch_add(1, Ordering::Relaxed);
        scene
            .set_dofs(ann, &[(elbow, (n as f64 * 0.05).sin().abs())])
            .unwrap();
        scene.step();
        Frame::from_scene(&scene)
    })
    .unwrap();
    assert!(steps.load(Ordering::Relaxed) > 0, "the simulation ran");
}
