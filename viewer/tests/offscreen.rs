//! Headless rendering on this machine's adapter (llvmpipe in CI): pixels are checked
//! against the same camera projection the renderer uses. These tests never skip: a
//! machine without any adapter fails them with the viewer's install hint.

use troupe_body::glam::Vec3;
use troupe_scene::{ActorDesc, Scene, SceneConfig};
use troupe_viewer::{
    BodyStyle, Camera, Frame, Hand, HandState, OffscreenRenderer, RenderOptions, RgbaImage, Sensor,
    BACKGROUND,
};

const W: u32 = 320;
const H: u32 = 240;

fn renderer() -> OffscreenRenderer {
    match OffscreenRenderer::new(W, H) {
        Ok(r) => {
            eprintln!("adapter: {}", r.adapter());
            r
        }
        Err(e) => panic!("{e}"),
    }
}

/// A front camera looking at the actor's chest from 4 m.
fn front() -> Camera {
    Camera::fixed(Vec3::new(0.0, 1.0, 4.0), Vec3::new(0.0, 0.9, 0.0))
}

fn posed(dofs: &[(&str, f64)]) -> Frame {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    let ann = scene.add_actor(&ActorDesc::new("ann")).unwrap();
    let sk = scene.actors()[ann].skeleton.clone();
    let values: Vec<_> = dofs
        .iter()
        .map(|(n, v)| (sk.dof(n).unwrap(), v.to_radians()))
        .collect();
    scene.set_dofs(ann, &values).unwrap();
    Frame::from_scene(&scene)
}

fn pixel_at(img: &RgbaImage, frame: &Frame, camera: &Camera, p: Vec3) -> [u8; 3] {
    let s = camera
        .project(frame, W, H, p)
        .expect("point in front of the camera");
    assert!(
        s.x >= 0.0 && s.y >= 0.0 && s.x < W as f32 && s.y < H as f32,
        "{p} projects outside the picture: {s}"
    );
    let px = img.get_pixel(s.x as u32, s.y as u32).0;
    [px[0], px[1], px[2]]
}

fn close(a: [u8; 3], b: [u8; 3], tol: i32) -> bool {
    a.iter()
        .zip(b)
        .all(|(x, y)| (*x as i32 - y as i32).abs() <= tol)
}

fn background_srgb() -> [u8; 3] {
    BACKGROUND.map(|c| (c * 255.0).round() as u8)
}

#[test]
fn silhouette_is_where_the_projection_says_and_background_elsewhere() {
    let mut r = renderer();
    let camera = front();
    let frame = posed(&[("r_shoulder_abduction", 80.0), ("l_elbow_flexion", 60.0)]);
    let img = r.render(&frame, &camera).unwrap();
    let empty = r.render(&Frame::default(), &camera).unwrap();
    assert_eq!((img.width(), img.height()), (W, H));
    let ann = frame.actor("ann").unwrap();
    for solid in [
        "head_neck",
        "up_torso",
        "down_torso",
        "r_thigh",
        "l_leg",
        "r_upper_arm",
        "r_forearm",
        "r_hand",
        "l_foot",
    ] {
        let c = ann.solid_center(solid).unwrap();
        let on = pixel_at(&img, &frame, &camera, c);
        let off = pixel_at(&empty, &frame, &camera, c);
        assert!(
            !close(on, off, 6),
            "{solid} at {c}: pixel {on:?} looks like the empty scene {off:?}"
        );
    }
    // The raised right hand is out to the side (the actor's right is the picture's left,
    // it faces the camera); where the hand hangs at rest there is only the floor now.
    let hand = pixel_at(&img, &frame, &camera, ann.solid_center("r_hand").unwrap());
    assert!(
        hand[0] > hand[2] + 30,
        "skin-coloured free hand, got {hand:?}"
    );
    let rest = posed(&[]);
    let rest_hand = rest.actor("ann").unwrap().solid_center("r_hand").unwrap();
    let s = camera.project(&frame, W, H, rest_hand).unwrap();
    let raised = camera
        .project(&frame, W, H, ann.solid_center("r_hand").unwrap())
        .unwrap();
    assert!(
        raised.x < s.x - 20.0 && raised.y < s.y - 20.0,
        "{raised} vs {s}"
    );
    assert!(close(
        pixel_at(&img, &frame, &camera, rest_hand),
        pixel_at(&empty, &frame, &camera, rest_hand),
        2
    ));
    // Sky in the top corners is the background colour; the floor at the bottom corners is
    // the same as in the empty scene.
    for (x, y) in [(2, 2), (W - 3, 2)] {
        let p = img.get_pixel(x, y).0;
        assert!(close([p[0], p[1], p[2]], background_srgb(), 2), "sky {p:?}");
    }
    for (x, y) in [(2, H - 3), (W - 3, H - 3), (W / 2, H - 3)] {
        assert_eq!(
            img.get_pixel(x, y),
            empty.get_pixel(x, y),
            "floor at {x},{y}"
        );
    }
    // The floor is not the sky.
    let floor = empty.get_pixel(W / 2, H - 3).0;
    assert!(!close([floor[0], floor[1], floor[2]], background_srgb(), 3));
}

#[test]
fn hands_are_tinted_by_grasp_state() {
    let mut r = renderer();
    let camera = front();
    let mut frame = posed(&[
        ("l_shoulder_abduction", 45.0),
        ("r_shoulder_abduction", 45.0),
    ]);
    let ann = frame.actor_mut("ann").unwrap();
    ann.set_hand(Hand::Left, HandState::Grasping);
    ann.set_hand(Hand::Right, HandState::Secure);
    let img = r.render(&frame, &camera).unwrap();
    let ann = frame.actor("ann").unwrap();
    let left = pixel_at(&img, &frame, &camera, ann.solid_center("l_hand").unwrap());
    let right = pixel_at(&img, &frame, &camera, ann.solid_center("r_hand").unwrap());
    assert!(
        left[2] as i32 > left[0] as i32 + 60 && left[2] > left[1],
        "grasping hand is blue, got {left:?}"
    );
    assert!(
        right[1] as i32 > right[0] as i32 + 60 && right[1] > right[2],
        "securely grasping hand is green, got {right:?}"
    );
    // With overlays off, both hands are skin again.
    r.set_options(RenderOptions {
        overlays: false,
        ..RenderOptions::default()
    });
    let plain = r.render(&frame, &camera).unwrap();
    for hand in ["l_hand", "r_hand"] {
        let p = pixel_at(&plain, &frame, &camera, ann.solid_center(hand).unwrap());
        assert!(
            p[0] > p[1] && p[1] > p[2],
            "{hand} is skin without overlays: {p:?}"
        );
    }
}

#[test]
fn sensors_are_dark_grey_and_light_grey_while_touching_and_ik_targets_show() {
    let mut r = renderer();
    let camera = front();
    let mut frame = posed(&[]);
    let idle = Vec3::new(-0.6, 1.2, 0.3);
    let touching = Vec3::new(0.6, 1.2, 0.3);
    let target = Vec3::new(0.0, 1.9, 0.3);
    frame.sensors.push(Sensor {
        position: idle,
        radius: 0.1,
        touching: false,
    });
    frame.sensors.push(Sensor {
        position: touching,
        radius: 0.1,
        touching: true,
    });
    frame.ik_targets.push(target);
    let img = r.render(&frame, &camera).unwrap();
    let grey = |p: [u8; 3]| {
        let (lo, hi) = (*p.iter().min().unwrap(), *p.iter().max().unwrap());
        assert!(hi - lo <= 4, "sensor should be grey, got {p:?}");
        p[1] as i32
    };
    let dark = grey(pixel_at(&img, &frame, &camera, idle));
    let light = grey(pixel_at(&img, &frame, &camera, touching));
    assert!(dark < 110, "idle sensor is dark grey ({dark})");
    assert!(
        light > dark + 80,
        "touching sensor is light grey ({light} vs {dark})"
    );
    let t = pixel_at(&img, &frame, &camera, target);
    assert!(
        t[0] as i32 > t[1] as i32 + 60 && t[2] as i32 > t[1] as i32 + 40,
        "IK target is magenta, got {t:?}"
    );
}

#[test]
fn bones_style_draws_through_the_joints() {
    let mut r = renderer();
    r.set_options(RenderOptions {
        style: BodyStyle::Bones,
        ..RenderOptions::default()
    });
    let camera = front();
    let frame = posed(&[("r_shoulder_abduction", 90.0), ("r_elbow_flexion", 90.0)]);
    let img = r.render(&frame, &camera).unwrap();
    let empty = r.render(&Frame::default(), &camera).unwrap();
    let ann = frame.actor("ann").unwrap();
    for joint in [
        "r_shoulder",
        "r_elbow",
        "r_wrist",
        "l_knee",
        "vt6",
        "skullbase",
    ] {
        let p = ann.joint_position(joint).unwrap();
        assert!(
            !close(
                pixel_at(&img, &frame, &camera, p),
                pixel_at(&empty, &frame, &camera, p),
                6
            ),
            "bone figure covers {joint}"
        );
    }
}

#[test]
fn fit_camera_frames_every_actor() {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    for (i, x) in [-3.0, 0.0, 3.0].into_iter().enumerate() {
        let mut d = ActorDesc::new(format!("a{i}"));
        d.at = troupe_body::glam::DVec3::new(x, 0.0, 0.0);
        scene.add_actor(&d).unwrap();
    }
    let frame = Frame::from_scene(&scene);
    let camera = Camera::fit();
    let mut r = renderer();
    let img = r.render(&frame, &camera).unwrap();
    for a in &frame.actors {
        for p in a.points() {
            let s = camera.project(&frame, W, H, p).unwrap();
            assert!(
                s.x >= 0.0 && s.x < W as f32 && s.y >= 0.0 && s.y < H as f32,
                "{} point {p} outside the picture at {s}",
                a.name
            );
        }
        let head = a.solid_center("head_neck").unwrap();
        let p = pixel_at(&img, &frame, &camera, head);
        assert!(
            p[0] > p[2] + 30,
            "{}'s head is skin-coloured: {p:?}",
            a.name
        );
    }
}

#[test]
fn names_and_labels_are_drawn_above_the_head() {
    let mut r = renderer();
    let camera = front();
    let mut frame = posed(&[("r_shoulder_abduction", 170.0)]);
    frame
        .actor_mut("ann")
        .unwrap()
        .labels
        .push("keyframe (active)".into());
    let with = r.render(&frame, &camera).unwrap();
    r.set_options(RenderOptions {
        labels: false,
        ..RenderOptions::default()
    });
    let without = r.render(&frame, &camera).unwrap();
    let ann = frame.actor("ann").unwrap();
    let top = ann.label_anchor().unwrap();
    assert!(top.y > ann.joint_position("skullbase").unwrap().y + 0.12);
    let anchor = camera.project(&frame, W, H, top).unwrap();
    // Two lines of 9 pixels (scale 1 below 400 pixels high) end at the anchor.
    let (ax, ay) = (anchor.x as u32, anchor.y as u32);
    let (mut changed, mut white) = (0, 0);
    for y in ay - 18..ay {
        for x in ax - 50..ax + 50 {
            let (a, b) = (with.get_pixel(x, y), without.get_pixel(x, y));
            changed += (a != b) as u32;
            white += a.0[..3].iter().all(|&c| c > 240) as u32;
        }
    }
    assert!(
        changed > 300,
        "label panel drawn ({changed} pixels changed)"
    );
    assert!(white > 60, "white glyphs drawn ({white} pixels)");
    // Labels never cover the body.
    let head = ann.solid_center("head_neck").unwrap();
    assert_eq!(
        pixel_at(&with, &frame, &camera, head),
        pixel_at(&without, &frame, &camera, head)
    );
}

#[test]
fn png_files_round_trip() {
    let dir = std::env::temp_dir().join(format!("troupe-viewer-test-{}", std::process::id()));
    let path = dir.join("sub/ann.png");
    let mut r = renderer();
    let frame = posed(&[("r_elbow_flexion", 45.0)]);
    r.save_png(&frame, &front(), &path).unwrap();
    let back = image::open(&path).unwrap().to_rgba8();
    assert_eq!(back, r.render(&frame, &front()).unwrap());
    std::fs::remove_dir_all(&dir).unwrap();
}

#[cfg(target_os = "linux")]
#[test]
fn missing_adapter_is_one_clear_error() {
    // Linux has no DirectX 12: asking only for it is what a machine without any driver sees.
    let err = match OffscreenRenderer::with_backends(64, 64, troupe_viewer::Backends::DX12) {
        Ok(_) => panic!("DX12 adapter on Linux?"),
        Err(e) => e.to_string(),
    };
    assert!(err.contains("no graphics adapter"), "{err}");
    assert!(err.contains("mesa-vulkan-drivers libvulkan1"), "{err}");
    assert!(err.contains("libegl1"), "{err}");
    assert!(
        err.contains("simulation itself runs without the viewer"),
        "{err}"
    );
}

#[test]
fn bad_sizes_are_refused() {
    assert!(OffscreenRenderer::new(0, 10).is_err());
    assert_eq!(troupe_viewer::parse_size("1280x720").unwrap(), (1280, 720));
    assert!(troupe_viewer::parse_size("1280").is_err());
    assert!(troupe_viewer::parse_size("0x5").is_err());
}

#[test]
fn multisampling_can_be_turned_off_and_on() {
    let mut r = renderer();
    let camera = front();
    let frame = posed(&[]);
    let torso = frame
        .actor("ann")
        .unwrap()
        .solid_center("down_torso")
        .unwrap();
    r.set_multisampling(false);
    assert_eq!(r.adapter().samples, 1);
    let img = r.render(&frame, &camera).unwrap();
    let empty = r.render(&Frame::default(), &camera).unwrap();
    assert!(!close(
        pixel_at(&img, &frame, &camera, torso),
        pixel_at(&empty, &frame, &camera, torso),
        6
    ));
    r.set_multisampling(true);
    assert!(r.render(&frame, &camera).is_ok());
}

#[test]
fn the_skin_look_is_the_default_and_bares_the_forearms() {
    assert_eq!(RenderOptions::default().style, BodyStyle::Skin);
    let camera = front();
    let frame = posed(&[("r_shoulder_abduction", 80.0), ("r_elbow_flexion", 30.0)]);
    let ann = frame.actor("ann").unwrap();
    let forearm = ann.solid_center("r_forearm").unwrap();
    let chest = ann.solid_center("up_torso").unwrap();
    let mut r = renderer();
    let skin = r.render(&frame, &camera).unwrap();
    r.set_options(RenderOptions {
        style: BodyStyle::Solids,
        ..RenderOptions::default()
    });
    let solids = r.render(&frame, &camera).unwrap();
    // The skin follows the raised forearm, which is bare (skin-coloured: red well above
    // blue); the solids draw it in the first actor's teal shirt.
    let bare = pixel_at(&skin, &frame, &camera, forearm);
    assert!(bare[0] > bare[2] + 30, "bare forearm, got {bare:?}");
    let sleeve = pixel_at(&solids, &frame, &camera, forearm);
    assert!(
        sleeve[2] > sleeve[0],
        "shirt-coloured forearm solid, got {sleeve:?}"
    );
    // Both looks dress the chest in the same shirt.
    let (a, b) = (
        pixel_at(&skin, &frame, &camera, chest),
        pixel_at(&solids, &frame, &camera, chest),
    );
    assert!(
        a[2] > a[0] && b[2] > b[0],
        "teal shirt in both looks: {a:?} {b:?}"
    );
}

#[test]
fn a_skeleton_the_skin_cannot_dress_is_drawn_as_solids() {
    use std::sync::Arc;
    use troupe_body::glam::{DQuat, DVec3};
    use troupe_body::skeleton::SkeletonBuilder;
    use troupe_body::{Shape, Solid, Transform};
    // A lone box on a pole: no head, no hands, nothing the skin's volumes need.
    let mut b = SkeletonBuilder::new("pole");
    b.joint("base", None, DVec3::ZERO).unwrap();
    let shape = Shape::Box {
        half_extents: DVec3::new(0.2, 0.4, 0.2),
    };
    b.solid(
        "base",
        Solid::new(
            "block",
            shape,
            DVec3::new(0.0, 0.9, 0.0),
            DQuat::IDENTITY,
            5.0,
        ),
    )
    .unwrap();
    let skeleton = Arc::new(b.build().unwrap());
    let mut frame = posed(&[]);
    frame.actors[0].skeleton = skeleton;
    frame.actors[0].globals = vec![Transform::IDENTITY];
    let camera = front();
    let mut r = renderer();
    let img = r.render(&frame, &camera).unwrap();
    let empty = r.render(&Frame::default(), &camera).unwrap();
    let p = Vec3::new(0.0, 0.9, 0.0);
    assert!(
        !close(
            pixel_at(&img, &frame, &camera, p),
            pixel_at(&empty, &frame, &camera, p),
            6
        ),
        "the block is drawn"
    );
}

/// The row, in each column of `img` within `columns`, where the shirt above gives way
/// to the trousers below (green high above, low below), scanning down from row `top` to
/// row `bottom`; `None` for a column without both.
fn waistband_rows(
    img: &RgbaImage,
    columns: std::ops::Range<u32>,
    (top, bottom): (u32, u32),
) -> Vec<Option<u32>> {
    let green = |x: u32, y: u32| img.get_pixel(x, y).0[1] as i32;
    columns
        .map(|x| {
            let shirt = green(x, top);
            let trousers = green(x, bottom);
            if shirt - trousers < 40 {
                return None;
            }
            let middle = (shirt + trousers) / 2;
            (top..bottom).find(|&y| green(x, y) < middle)
        })
        .collect()
}

#[test]
fn the_edges_between_the_skins_regions_run_smoothly_between_the_vertices() {
    // Close up on the waistband from the front: each pixel column across the belly is
    // about 2 mm of skin, a triangle there 1-2 cm across.
    let camera = Camera::fixed(Vec3::new(0.0, 0.93, 0.75), Vec3::new(0.0, 0.93, 0.0));
    let frame = posed(&[]);
    let img = renderer().render(&frame, &camera).unwrap();
    let rows = waistband_rows(&img, W / 2 - 40..W / 2 + 40, (20, 130));
    let found: Vec<u32> = rows.iter().flatten().copied().collect();
    assert!(
        found.len() == rows.len(),
        "the waistband crosses every column of the belly: {rows:?}"
    );
    // Along the volumes' own boundary the edge is a smooth curve: neighbouring columns
    // find it within a pixel of each other (coloured by vertex, it zigzagged a triangle
    // high and blurred across one).
    let steps: Vec<i64> = found
        .windows(2)
        .map(|w| w[1] as i64 - w[0] as i64)
        .collect();
    let worst = steps.iter().map(|s| s.abs()).max().unwrap();
    let spread = found.iter().max().unwrap() - found.iter().min().unwrap();
    eprintln!("waistband rows {found:?}: worst step {worst} px, spread {spread} px");
    assert!(worst <= 1, "the waistband zigzags by {worst} px: {found:?}");
}

#[test]
fn far_away_the_edges_between_the_skins_regions_stay_sharp() {
    // The whole body in 240 pixels is drawn with the coarse level of detail, coloured
    // by vertex: each of its triangles at the waist is 4-5 cm, 3-4 pixels, across. From
    // twice as far (under 150 pixels), with the coarsest level.
    for distance in [2.6f32, 5.2] {
        let camera = Camera::fixed(Vec3::new(0.0, 0.9, distance), Vec3::new(0.0, 0.9, 0.0));
        let frame = posed(&[]);
        let img = renderer().render(&frame, &camera).unwrap();
        let green = |x: u32, y: u32| img.get_pixel(x, y).0[1] as i32;
        // From 2.6 m: the shirt 13 rows above the waistband, the hips 13 rows below it,
        // the belly 28 columns wide; half of each from twice as far.
        let k = |n: u32| (n as f32 * 2.6 / distance).round() as u32;
        let (top, bottom) = (H / 2 - k(28), H / 2 - k(2));
        // Down each column across the belly, the rows between the shirt's green and the
        // trousers' (more than a fifth of the way from either): the edge's width.
        let widths: Vec<usize> = (W / 2 - k(14)..W / 2 + k(14))
            .filter_map(|x| {
                let (shirt, trousers) = (green(x, top), green(x, bottom));
                if shirt - trousers < 40 {
                    return None;
                }
                let margin = (shirt - trousers) / 5;
                Some(
                    (top..bottom)
                        .filter(|&y| {
                            let g = green(x, y);
                            g < shirt - margin && g > trousers + margin
                        })
                        .count(),
                )
            })
            .collect();
        assert!(
            widths.len() as u32 >= k(20),
            "{distance} m: the waistband crosses the belly: {widths:?}"
        );
        let widest = *widths.iter().max().unwrap();
        let mean = widths.iter().sum::<usize>() as f64 / widths.len() as f64;
        eprintln!(
            "{distance} m: the waistband {mean:.2} rows wide on average, at most {widest}: {widths:?}"
        );
        assert!(
            widest <= 2,
            "{distance} m: the waistband blurs over {widest} rows: {widths:?}"
        );
    }
}

#[test]
fn back_faces_are_not_drawn() {
    // The generated skin and the solids are closed, so only their outsides can be seen
    // and their back faces are culled (a third or more of a frame's time). From inside
    // the chest, looking out through it, nothing of the body is drawn in either look:
    // the picture's middle is as in an empty scene.
    let frame = posed(&[]);
    let chest = frame
        .actor("ann")
        .unwrap()
        .solid_center("up_torso")
        .unwrap();
    let camera = Camera::fixed(chest, chest + Vec3::new(0.0, 0.3, 4.0));
    let mut r = renderer();
    for style in [BodyStyle::Skin, BodyStyle::Solids] {
        r.set_options(RenderOptions {
            labels: false,
            style,
            ..RenderOptions::default()
        });
        let img = r.render(&frame, &camera).unwrap();
        let empty = r.render(&Frame::default(), &camera).unwrap();
        let (middle, sky) = (
            img.get_pixel(W / 2, H / 2).0,
            empty.get_pixel(W / 2, H / 2).0,
        );
        assert!(
            close(
                [middle[0], middle[1], middle[2]],
                [sky[0], sky[1], sky[2]],
                6
            ),
            "{style:?}: seen from inside, the chest is drawn: {middle:?} where the empty scene has {sky:?}"
        );
    }
}

/// The topmost row in columns `columns` of `img` that is not the background.
fn top_row(img: &RgbaImage, columns: std::ops::Range<u32>) -> Option<u32> {
    let background = background_srgb();
    (0..H).find(|&y| {
        columns.clone().any(|x| {
            let p = img.get_pixel(x, y).0;
            !close([p[0], p[1], p[2]], background, 12)
        })
    })
}

#[test]
fn actors_of_every_height_share_one_skin_drawn_at_their_own_size() {
    // Two heights of one template: the skin is made once, at the template's height, and
    // drawn scaled (`troupe_body::skin::SkinLibrary`); each head must be drawn where its
    // own body's is, as the solids draw it.
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    for (name, height, x) in [("short", 1.45, -0.6), ("tall", 2.05, 0.6)] {
        let mut desc = ActorDesc::new(name);
        desc.height = Some(height);
        desc.at = troupe_body::glam::DVec3::new(x, 0.0, 0.0);
        scene.add_actor(&desc).unwrap();
    }
    let frame = Frame::from_scene(&scene);
    let camera = Camera::fixed(Vec3::new(0.0, 1.2, 5.0), Vec3::new(0.0, 1.0, 0.0));
    let mut r = renderer();
    let plain = RenderOptions {
        labels: false,
        grid: false,
        ..RenderOptions::default()
    };
    r.set_options(plain);
    let skin = r.render(&frame, &camera).unwrap();
    r.set_options(RenderOptions {
        style: BodyStyle::Solids,
        ..plain
    });
    let solids = r.render(&frame, &camera).unwrap();
    let mut tops = Vec::new();
    for name in ["short", "tall"] {
        let head = frame
            .actor(name)
            .unwrap()
            .solid_center("head_neck")
            .unwrap();
        let at = camera.project(&frame, W, H, head).unwrap();
        let columns = (at.x as u32).saturating_sub(3)..(at.x as u32 + 4);
        let (a, b) = (
            top_row(&skin, columns.clone()).unwrap(),
            top_row(&solids, columns).unwrap(),
        );
        assert!(
            a.abs_diff(b) <= 2,
            "{name}: the skin's head starts at row {a}, the solids' at {b}"
        );
        tops.push(a);
    }
    // And each body is drawn at its own size: the picture's halves (one actor each)
    // hold areas in the ratio of the heights squared, as in the solids.
    let area = |img: &RgbaImage, columns: std::ops::Range<u32>| {
        let background = background_srgb();
        columns
            .flat_map(|x| (0..H).map(move |y| (x, y)))
            .filter(|&(x, y)| {
                let p = img.get_pixel(x, y).0;
                !close([p[0], p[1], p[2]], background, 12)
            })
            .count() as f64
    };
    let ratio = area(&skin, W / 2..W) / area(&skin, 0..W / 2);
    let want = (2.05f64 / 1.45).powi(2);
    eprintln!("heads start at rows {tops:?}; the tall actor covers {ratio:.3} times the short one's pixels (heights squared: {want:.3})");
    assert!(
        (ratio / want - 1.0).abs() < 0.1,
        "the tall actor covers {ratio:.2} times the short one's pixels, not about {want:.2}"
    );
}
