//! Every head shows a face (two eyes, a nose) in every body style, turning with the head:
//! a look to the side is visible in a picture.

use troupe_body::glam::Vec3;
use troupe_scene::{ActorDesc, Scene, SceneConfig};
use troupe_viewer::{BodyStyle, Camera, Frame, OffscreenRenderer, RenderOptions, RgbaImage};

const W: u32 = 240;
const H: u32 = 180;

fn head_turned(degrees: f64) -> Frame {
    let mut scene = Scene::new(SceneConfig::default()).unwrap();
    let ann = scene.add_actor(&ActorDesc::new("ann")).unwrap();
    let sk = scene.actors()[ann].skeleton.clone();
    let torsion = sk.dof("skullbase_torsion").unwrap();
    scene
        .set_dofs(ann, &[(torsion, degrees.to_radians())])
        .unwrap();
    Frame::from_scene(&scene)
}

/// The centre (x) of the dark eye pixels and how many there are.
fn dark_pixels(img: &RgbaImage) -> (f32, usize) {
    let (mut sum, mut n) = (0.0, 0);
    for (x, _, p) in img.enumerate_pixels() {
        if p.0[..3].iter().all(|&c| c < 40) {
            sum += x as f32;
            n += 1;
        }
    }
    (if n > 0 { sum / n as f32 } else { f32::NAN }, n)
}

#[test]
fn eyes_show_in_solids_and_bones_and_move_when_the_head_turns() {
    let mut r = OffscreenRenderer::new(W, H).expect("an adapter");
    let head = head_turned(0.0).actors[0]
        .joint_position("skullbase")
        .unwrap();
    let camera = Camera::fixed(
        head + Vec3::new(0.0, 0.08, 0.9),
        head + Vec3::new(0.0, 0.08, 0.0),
    );
    for style in [BodyStyle::Solids, BodyStyle::Bones] {
        r.set_options(RenderOptions {
            labels: false,
            style,
            ..Default::default()
        });
        let ahead = r.render(&head_turned(0.0), &camera).unwrap();
        let (x_ahead, n) = dark_pixels(&ahead);
        assert!(n > 20, "{style:?}: eyes are drawn ({n} dark pixels)");
        assert!(
            (x_ahead - W as f32 / 2.0).abs() < 10.0,
            "{style:?}: centred, {x_ahead}"
        );
        // Torsion to the actor's left (+X), which is the picture's right seen from the front.
        let turned = r.render(&head_turned(45.0), &camera).unwrap();
        let (x_turned, _) = dark_pixels(&turned);
        assert!(
            x_turned > x_ahead + 5.0,
            "{style:?}: the eyes follow the head: {x_ahead} → {x_turned}"
        );
    }
}
