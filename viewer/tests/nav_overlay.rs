//! The navigation debug view (`--debug nav`): gathered from a scene, and drawn where the
//! camera projects it, hidden by what stands in front of it. Rendered headless on this
//! machine's adapter (llvmpipe in CI).

use troupe_body::glam::{DQuat, DVec3, Vec2, Vec3};
use troupe_body::solid::Shape;
use troupe_scene::space::CLEARANCE;
use troupe_scene::{ActorDesc, Object, Scene, SceneConfig};
use troupe_viewer::{
    Camera, DebugView, Frame, NavOverlay, NavWalker, OffscreenRenderer, RenderOptions, RgbaImage,
    NAV_CHOSEN, NAV_PATH, NAV_PREFERRED,
};

const W: u32 = 640;
const H: u32 = 480;

fn srgb(c: [f32; 3]) -> [u8; 3] {
    c.map(|v| (v * 255.0).round() as u8)
}

fn close(a: [u8; 3], b: [u8; 3], tol: i32) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (*x as i32 - y as i32).abs() <= tol)
}

/// The colour of the picture where `p` projects.
fn pixel(img: &RgbaImage, frame: &Frame, camera: &Camera, p: Vec3) -> [u8; 3] {
    let s = camera
        .project(frame, W, H, p)
        .expect("in front of the camera");
    assert!(
        s.x >= 0.0 && s.y >= 0.0 && s.x < W as f32 && s.y < H as f32,
        "{p}: {s}"
    );
    let px = img.get_pixel(s.x as u32, s.y as u32).0;
    [px[0], px[1], px[2]]
}

/// A walker at (-2, 0) whose path runs along x to (2, 0), with a box standing on the
/// path at x = 0.8; it preferred to go towards +z and chose -z.
fn scene_and_overlay() -> (Frame, Camera) {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    scene
        .add_object(Object {
            name: "crate".into(),
            shape: Shape::Box {
                half_extents: DVec3::new(0.2, 0.4, 0.2),
            },
            position: DVec3::new(0.8, 0.4, 0.0),
            rotation: DQuat::IDENTITY,
            mass: 5.0,
        })
        .unwrap();
    let mut frame = Frame::from_scene(&scene);
    frame.nav = Some(NavOverlay {
        walkers: vec![NavWalker {
            actor: 0,
            position: Vec2::new(-2.0, 0.0),
            path: (0..=40)
                .map(|k| Vec2::new(-2.0 + 0.1 * k as f32, 0.0))
                .collect(),
            goal: Vec2::new(2.0, 0.0),
            velocities: Some((Vec2::new(0.0, 1.2), Vec2::new(0.0, -1.2))),
        }],
        ..NavOverlay::default()
    });
    (frame, Camera::fixed(Vec3::new(0.0, 5.0, 5.0), Vec3::ZERO))
}

#[test]
fn the_path_is_drawn_where_it_projects_and_hidden_behind_a_box() {
    let mut r = OffscreenRenderer::new(W, H).unwrap_or_else(|e| panic!("{e}"));
    let (frame, camera) = scene_and_overlay();
    let drawn = r.render(&frame, &camera).unwrap();
    let plain = r
        .render(
            &Frame {
                nav: None,
                ..frame.clone()
            },
            &camera,
        )
        .unwrap();
    let path = srgb(NAV_PATH);
    for x in [-1.5, -1.0, -0.5, 0.0, 1.5] {
        let p = Vec3::new(x, 0.03, 0.0);
        let (with, without) = (
            pixel(&drawn, &frame, &camera, p),
            pixel(&plain, &frame, &camera, p),
        );
        assert!(
            close(with, path, 6),
            "x = {x}: {with:?}, the path is {path:?}"
        );
        assert!(
            !close(without, path, 40),
            "x = {x}: {without:?} without --debug nav"
        );
    }
    // Under the box, the path is hidden (depth-tested): the box is drawn there.
    let under = Vec3::new(0.8, 0.03, 0.0);
    assert!(!close(pixel(&drawn, &frame, &camera, under), path, 40));
    assert_eq!(
        pixel(&drawn, &frame, &camera, under),
        pixel(&plain, &frame, &camera, under)
    );
    // The velocities: arrows from the walker, 1.2 m long.
    let chosen = pixel(&drawn, &frame, &camera, Vec3::new(-2.0, 0.04, -0.7));
    assert!(close(chosen, srgb(NAV_CHOSEN), 6), "{chosen:?}");
    let preferred = pixel(&drawn, &frame, &camera, Vec3::new(-2.0, 0.04, 0.7));
    assert!(close(preferred, srgb(NAV_PREFERRED), 6), "{preferred:?}");
    // Overlays off (the window's `o`): no debug lines either.
    r.set_options(RenderOptions {
        overlays: false,
        ..RenderOptions::default()
    });
    let hidden = r.render(&frame, &camera).unwrap();
    assert!(!close(
        pixel(&hidden, &frame, &camera, Vec3::new(-1.0, 0.03, 0.0)),
        path,
        40
    ));
}

#[test]
fn the_overlay_of_a_scene_holds_its_mesh_and_inflated_footprints() {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    scene.add_actor(&ActorDesc::new("ann")).unwrap();
    scene
        .add_object(Object {
            name: "table".into(),
            shape: Shape::Box {
                half_extents: DVec3::new(1.0, 0.375, 0.5),
            },
            position: DVec3::new(0.0, 0.375, 3.0),
            rotation: DQuat::IDENTITY,
            mass: 30.0,
        })
        .unwrap();
    let frame = Frame::from_scene(&scene).with_debug(&scene, DebugView::parse("nav").unwrap());
    let nav = frame.nav.expect("asked for");
    assert!((nav.radius - 0.28).abs() < 0.01, "{}", nav.radius);
    assert_eq!(nav.footprints.len(), 1);
    assert_eq!(nav.footprints[0].len(), 4);
    // The inflated outline keeps the radius and the clearance from the table: its
    // corners lie at that distance or at most 2 % further (the sides of its rounded
    // corners touch the circle).
    let keep = nav.radius + CLEARANCE as f32;
    for p in &nav.inflated[0] {
        let outside = Vec2::new(
            (p.x.abs() - 1.0).max(0.0),
            ((p.y - 3.0).abs() - 0.5).max(0.0),
        );
        let d = outside.length();
        assert!(d > keep - 1e-3 && d < keep * 1.02 + 1e-3, "{p}");
    }
    // The mesh is cut round the table: some edge ends on its inflated outline.
    assert!(nav.mesh.len() >= 8);
    assert!(nav.mesh.iter().flatten().any(|p| {
        let outside = Vec2::new(
            (p.x.abs() - 1.0).max(0.0),
            ((p.y - 3.0).abs() - 0.5).max(0.0),
        );
        (outside.length() - keep).abs() < 0.02
    }));
    // Nobody walks: no paths.
    assert!(nav.walkers.is_empty());
    // Without the channel, nothing is gathered.
    assert!(Frame::from_scene(&scene)
        .with_debug(&scene, DebugView::default())
        .nav
        .is_none());
}

#[test]
fn an_unknown_debug_channel_is_a_clear_error() {
    let e = DebugView::parse("nav,paths").unwrap_err().to_string();
    assert_eq!(e, "unknown debug channel `paths` (known: nav)");
    assert!(DebugView::parse("nav").unwrap().nav);
}
