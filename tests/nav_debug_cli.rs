//! `--debug nav` end to end: `troupe render` of a walk round a table draws the walk's
//! planned path where it projects (checked against the plan of the same scene run here),
//! and not without the option; an unknown channel is a clear error. Headless, on this
//! machine's adapter.

use std::path::{Path, PathBuf};
use std::process::Command;
use troupe_body::glam::Vec3;
use troupe_lua::{Director, LuaSessionExt, ScriptLimits};
use troupe_scene::{RunLimit, SceneConfig};
use troupe_viewer::{Camera, Frame, NAV_PATH};

const SCENE: &str = r#"
troupe.object{ name = "table", shape = "box", size = {2, 0.75, 1}, at = {0, 0.375, 2}, mass = 30 }
local ann = troupe.actor{ name = "ann", at = {0, 0, 0} }
ann:behave(function(self) self:walk{ to = {0, 0, 4} }:wait() end)
"#;
const CAMERA: &str = "fixed:0,7,-2.5:0,0,2";
const SIZE: (u32, u32) = (480, 360);
const AT: f64 = 0.5;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("troupe-nav-debug-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn render(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_troupe"))
        .arg("render")
        .args([scene.to_str().unwrap(), out.to_str().unwrap()])
        .args(["--at", &AT.to_string(), "--camera", CAMERA, "--no-labels"])
        .args([
            "--size",
            &format!("{}x{}", SIZE.0, SIZE.1),
            "--look",
            "bones",
        ])
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn render_debug_nav_draws_the_planned_path_where_it_projects() {
    let dir = temp_dir("render");
    let scene_file = dir.join("table.lua");
    std::fs::write(&scene_file, SCENE).unwrap();
    let (with, without) = (dir.join("nav.png"), dir.join("plain.png"));
    for (out, extra) in [(&with, vec!["--debug", "nav"]), (&without, vec![])] {
        let o = render(&scene_file, out, &extra);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    // The same scene, run here to the same tick: the plan the picture should show.
    let mut session = Director::session(
        SceneConfig::default(),
        troupe_actions::action_kinds(),
        ScriptLimits::default(),
    )
    .unwrap();
    session.load_str(SCENE, "table.lua").unwrap();
    session
        .run(RunLimit {
            ticks: (AT * 100.0).round() as u64,
            until_idle: false,
        })
        .unwrap();
    let scene = session.scene();
    let nav = scene.navigation();
    assert_eq!(nav.len(), 1, "ann walks");
    let path = &nav[0].1.path;
    // The plan goes round the table (2 m wide, centred on the straight line).
    assert!(path.iter().any(|p| p.x.abs() > 1.2), "{path:?}");
    let frame = Frame::from_scene(scene);
    let camera: Camera = CAMERA.parse().unwrap();
    let (with, without) = (
        image::open(&with).unwrap().to_rgb8(),
        image::open(&without).unwrap().to_rgb8(),
    );
    let colour = NAV_PATH.map(|c| (c * 255.0).round() as i32);
    let is_path = |img: &image::RgbImage, x: u32, y: u32| {
        let p = img.get_pixel(x, y).0;
        (0..3).all(|i| (p[i] as i32 - colour[i]).abs() <= 8)
    };
    let (mut seen, mut absent, mut points) = (0, 0, 0);
    for p in path.iter().step_by(3) {
        let s = camera
            .project(
                &frame,
                SIZE.0,
                SIZE.1,
                Vec3::new(p.x as f32, 0.03, p.y as f32),
            )
            .unwrap();
        let (x, y) = (s.x as u32, s.y as u32);
        assert!(x < SIZE.0 && y < SIZE.1, "{p} projects outside the picture");
        points += 1;
        seen += usize::from(is_path(&with, x, y));
        absent += usize::from(!is_path(&without, x, y));
    }
    // The body and the table hide a few points of the path; most are drawn.
    assert!(
        seen * 10 >= points * 8,
        "{seen} of {points} path points drawn"
    );
    assert_eq!(absent, points, "no path colour without --debug nav");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_unknown_debug_channel_is_refused_by_name() {
    for command in [
        vec!["render", "scene.lua", "out.png"],
        vec!["run", "scene.lua"],
        vec!["view", "rec.trk"],
    ] {
        let o = Command::new(env!("CARGO_BIN_EXE_troupe"))
            .args(&command)
            .args(["--debug", "nav,paths"])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{command:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("unknown debug channel `paths` (known: nav)"),
            "{command:?}: {err}"
        );
    }
}

#[test]
fn the_navigation_view_is_the_same_with_one_and_two_threads() {
    let overlay = |threads: usize| {
        let config = SceneConfig {
            threads,
            seed: 7,
            ..SceneConfig::default()
        };
        let mut session = Director::session(
            config,
            troupe_actions::action_kinds(),
            ScriptLimits::default(),
        )
        .unwrap();
        session.scene_mut().set_chunk_size(Some(1));
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/examples/shared_space.lua");
        session.load_file(&scene).unwrap();
        session
            .run(RunLimit {
                ticks: 300,
                until_idle: false,
            })
            .unwrap();
        troupe_viewer::NavOverlay::from_scene(session.scene())
    };
    let one = overlay(1);
    // Six walkers swap across a circle and one walks to a greeting: all of them plan,
    // and some of them are avoiding one another at 3 s.
    assert!(one.walkers.len() >= 6, "{}", one.walkers.len());
    assert!(one
        .walkers
        .iter()
        .any(|w| w.velocities.is_some_and(|(p, c)| (p - c).length() > 0.05)));
    assert!(one == overlay(2), "the view differs with two threads");
}
