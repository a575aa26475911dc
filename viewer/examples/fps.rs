//! Headless rendering throughput: frames per second for 1, 10 and 50 actors, each look
//! side by side (the skin, then the solids), and what one actor's skin costs to build.
//!
//! ```text
//! cargo run -p troupe-viewer --release --example fps -- [--size 1280x720] [--frames 60]
//!     [--actors 1,10,50] [--looks skin,solids,bones] [--save DIR] [--no-msaa]
//!     [--no-grid] [--no-labels]
//! ```
//!
//! Each frame is a full `OffscreenRenderer::render`: instance and joint upload, draw,
//! multisample resolve and read-back into an image (PNG encoding excluded). Actors stand
//! on a grid, each in a different pose that changes every frame.

use std::time::Instant;
use troupe_body::glam::DVec3;
use troupe_scene::{ActorDesc, Scene, SceneConfig};
use troupe_viewer::{parse_size, BodyStyle, Camera, Frame, OffscreenRenderer, RenderOptions};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut size = (1280, 720);
    let mut frames = 60u32;
    let mut counts = vec![1usize, 10, 50];
    let mut looks = vec![BodyStyle::Skin, BodyStyle::Solids];
    let mut save = None;
    let (mut msaa, mut grid, mut labels) = (true, true, true);
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--size" => size = parse_size(&value()?)?,
            "--frames" => frames = value()?.parse()?,
            "--actors" => {
                counts = value()?
                    .split(',')
                    .map(|n| n.parse())
                    .collect::<Result<_, _>>()?
            }
            "--looks" => {
                looks = value()?
                    .split(',')
                    .map(|l| BodyStyle::parse(l).ok_or(format!("unknown look {l}")))
                    .collect::<Result<_, _>>()?
            }
            "--save" => save = Some(std::path::PathBuf::from(value()?)),
            "--no-msaa" => msaa = false,
            "--no-grid" => grid = false,
            "--no-labels" => labels = false,
            _ => return Err(format!("unknown argument {a}").into()),
        }
    }
    let mut renderer = OffscreenRenderer::new(size.0, size.1)?;
    renderer.set_multisampling(msaa);
    let skeleton = troupe_body::template::default_skeleton("adult")?;
    let start = Instant::now();
    let skin = troupe_body::Skin::build(&skeleton)?;
    println!(
        "skin of one adult: built in {:.0} ms, {} vertices, {} triangles ({} far, {} farthest), {:.1} MB",
        start.elapsed().as_secs_f64() * 1000.0,
        skin.positions.len(),
        skin.triangle_count(),
        skin.far_indices.len() / 3,
        skin.farthest_indices.len() / 3,
        skin.memory_bytes() as f64 / 1e6
    );
    println!(
        "adapter: {}; {}x{}, {} frames per run",
        renderer.adapter(),
        size.0,
        size.1,
        frames
    );
    for &n in &counts {
        let mut scene = Scene::new(SceneConfig::default())?;
        let side = (n as f64).sqrt().ceil() as usize;
        for i in 0..n {
            let mut d = ActorDesc::new(format!("a{i}"));
            d.at = DVec3::new(
                (i % side) as f64 * 1.2 - (side - 1) as f64 * 0.6,
                0.0,
                -((i / side) as f64) * 1.2,
            );
            d.facing_degrees = (i * 37 % 90) as f64 - 45.0;
            scene.add_actor(&d)?;
        }
        let sk = scene.actors()[0].skeleton.clone();
        let dofs = [
            sk.dof("r_shoulder_abduction")?,
            sk.dof("l_shoulder_flexion")?,
            sk.dof("r_elbow_flexion")?,
            sk.dof("l_hip_flexion")?,
            sk.dof("l_knee_flexion")?,
        ];
        let camera = Camera::fit();
        let pose = |scene: &mut Scene, t: f64| -> Result<(), troupe_scene::Error> {
            for a in 0..n {
                let phase = t + a as f64 * 0.7;
                let v: Vec<_> = dofs
                    .iter()
                    .enumerate()
                    .map(|(k, &d)| (d, 0.6 + 0.5 * (phase + k as f64).sin()))
                    .collect();
                scene.set_dofs(a, &v)?;
            }
            Ok(())
        };
        let mut line = format!("{n:>3} actors:");
        for &style in &looks {
            renderer.set_options(RenderOptions {
                grid,
                labels,
                style,
                ..RenderOptions::default()
            });
            // Warm-up: pipelines, meshes, skins and buffers are made on the first frame.
            pose(&mut scene, 0.0)?;
            let first = renderer.render(&Frame::from_scene(&scene), &camera)?;
            if let Some(dir) = &save {
                let file = format!("fps_{n}_actors_{style:?}.png").to_lowercase();
                troupe_viewer::save_png(&first, dir.join(file))?;
            }
            let start = Instant::now();
            for f in 0..frames {
                pose(&mut scene, f as f64 * 0.05)?;
                renderer.render(&Frame::from_scene(&scene), &camera)?;
            }
            let secs = start.elapsed().as_secs_f64();
            line += &format!(
                "  {style:?} {:>6.1} fps ({:.1} ms/frame)",
                frames as f64 / secs,
                secs * 1000.0 / frames as f64
            );
        }
        println!("{line}");
    }
    Ok(())
}
