//! `troupe view` (play a recording on an actor, in a window or into PNG frames) and
//! `troupe snapshot` (one picture of actors in given poses).

#[cfg(feature = "zenoh")]
mod remote;
#[cfg(not(feature = "zenoh"))]
use crate::net as remote;

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use troupe_actions::keyframe::replay;
use troupe_body::glam::DVec3;
use troupe_body::DofKind;
use troupe_motion::{ObjectMotion, Sequence};
use troupe_scene::playback::ObjectPlayback;
use troupe_scene::{ActorDesc, RunLimit, Scene, SceneConfig, Session};
use troupe_viewer::{
    parse_size, run_window, BodyStyle, Camera, DebugView, Frame, FrameWriter, Hand, HandState,
    OffscreenRenderer, RenderOptions, ViewerError, WindowOptions,
};

/// Options of `troupe view`.
#[derive(Args)]
#[command(
    about = "Play a recording (.trk, .bvh, .gltf, .glb) on actors: in a window, or headless into PNG frames",
    long_about = "Play a recording (.trk, .bvh, .gltf, .glb) on actors. With a display (DISPLAY or \
        WAYLAND_DISPLAY) it opens a window and loops the recording: left drag orbits, right \
        drag pans, the wheel zooms, Space pauses, `.` steps, `s` slow motion, Tab/1-9 follow an \
        actor, 0 frames all, b cycles skin/solids/bones, g grid, o overlays, l labels, Esc quits. With --frames, or without \
        a display, it plays the recording once headless and writes DIR/frame_000000.png, …"
)]
pub struct ViewArgs {
    /// The recording to play (.trk, possibly several actors; .bvh; or .gltf/.glb written by troupe).
    #[arg(required_unless_present = "zenoh")]
    file: Option<PathBuf>,
    /// Body template of the actor (when the recording does not name one).
    #[arg(long, default_value = "adult")]
    actor_template: String,
    /// Standing height of the actor in metres (when the recording does not tell one;
    /// default: the template's).
    #[arg(long, value_name = "METRES")]
    actor_height: Option<f64>,
    /// Picture or window size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    size: String,
    /// Write PNG frames into DIR instead of opening a window (default `frames` when there
    /// is no display).
    #[arg(long, value_name = "DIR")]
    frames: Option<PathBuf>,
    /// Write every N-th tick (headless).
    #[arg(long, default_value_t = 4, value_name = "N")]
    every: u64,
    /// Camera: fit, follow:NAME or fixed:EX,EY,EZ:TX,TY,TZ; fit and follow take
    /// `@YAW,PITCH[,DISTANCE]`. The default follows a lone actor at a steady distance and
    /// fits several.
    #[arg(long)]
    camera: Option<String>,
    /// How actors are drawn: the generated skin, the body solids, or bones.
    #[arg(long, value_enum, default_value_t = Look::Skin)]
    look: Look,
    /// Same as `--look bones`.
    #[arg(long)]
    bones: bool,
    /// Do not draw names and action labels above the heads.
    #[arg(long)]
    no_labels: bool,
    /// Headless: no multisampling (about 3× faster on CPU adapters, jagged edges).
    #[arg(long)]
    no_msaa: bool,
    /// Seconds to play headless (default, and at most: the recording's length).
    #[arg(long)]
    seconds: Option<f64>,
    /// Simulation ticks per second.
    #[arg(long, default_value_t = 100.0)]
    rate: f64,
    /// Debug drawing: `nav` draws the navigation mesh and the obstacles' footprints of
    /// the recorded objects (a recording holds no walls, plans or avoidance).
    #[arg(long, value_name = "CHANNEL", value_parser = parse_debug)]
    debug: Option<DebugView>,
    /// A render node: a scene published on Zenoh instead of a recording.
    #[command(flatten)]
    remote: remote::RemoteViewArgs,
}

/// Options of `troupe snapshot`.
#[derive(Args)]
#[command(
    about = "Render one picture of actors in given poses (headless PNG)",
    long_about = "Render one picture of actors in given poses, headless, to a PNG file. Each \
        --pose adds one actor (none: one actor at rest). A pose is a comma-separated list of \
        DOF=VALUE (degrees for rotations, metres for translations; see `troupe templates \
        --dofs`), plus l_hand=/r_hand= free|grasping|secure (grasp-state tint), at=X:Z \
        (metres) and facing=DEGREES. Actors without at= stand in a row along X."
)]
pub struct SnapshotArgs {
    /// The PNG file to write.
    out: PathBuf,
    /// One actor's pose (repeat for more actors), e.g. `r_shoulder_abduction=80,r_hand=secure`.
    #[arg(long = "pose", value_name = "DOF=VALUE,...")]
    poses: Vec<String>,
    /// Body template of the actors.
    #[arg(long, default_value = "adult")]
    actor_template: String,
    /// Picture size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    size: String,
    /// Camera: fit, follow:NAME or fixed:EX,EY,EZ:TX,TY,TZ; fit and follow take
    /// `@YAW,PITCH[,DISTANCE]`.
    #[arg(long, default_value = "fit")]
    camera: String,
    /// How actors are drawn: the generated skin, the body solids, or bones.
    #[arg(long, value_enum, default_value_t = Look::Skin)]
    look: Look,
    /// Same as `--look bones`.
    #[arg(long)]
    bones: bool,
    /// Do not draw names above the heads.
    #[arg(long)]
    no_labels: bool,
    /// Metres between actors placed in a row.
    #[arg(long, default_value_t = 1.0)]
    spacing: f64,
}

/// One actor of a recording: its sequence and the body it was recorded on.
struct Performer {
    name: String,
    sequence: Sequence,
    template: String,
    height: Option<f64>,
}

/// What a recording holds: a performer per actor and the scene's objects (a `.trk` of
/// `troupe run --record` keeps them; other formats bring none).
struct Recording {
    performers: Vec<Performer>,
    objects: Vec<ObjectMotion>,
}

/// Reads a recording, once whatever its format: each sequence plays one actor, on the
/// template and height stored in its metadata (a `--record` `.trk`), or on the body a
/// BVH or glTF file troupe wrote was recorded from (its offsets tell the template and
/// height), else on `template` at `height` — which a foreign `.bvh` is retargeted onto.
fn load_recording(path: &Path, template: &str, height: Option<f64>) -> Result<Recording> {
    // The body a file of one actor plays on: the one it was recorded from, if it tells.
    let body = |recorded: Option<(String, f64)>| -> Result<(String, Option<f64>, _)> {
        let (template, height) = match recorded {
            Some((t, h)) => (t, Some(h)),
            None => (template.to_string(), height),
        };
        let t = troupe_body::template(&template)?;
        let mut params = t.default_params();
        if let Some(h) = height {
            params.height = h;
        }
        Ok((template, height, t.instantiate(params)?))
    };
    let (sequences, objects, template, height) = match troupe_formats::Format::of(path)? {
        troupe_formats::Format::Trk => {
            let file = troupe_formats::trk::read_trk_file(path)?;
            (file.sequences, file.objects, template.to_string(), height)
        }
        troupe_formats::Format::Bvh => {
            let bvh = troupe_formats::bvh::read_bvh(path)?;
            let (template, height, skeleton) = body(troupe_formats::retarget::recorded_body(&bvh))?;
            let seq = troupe_formats::retarget::motion_for(&skeleton, path, &bvh)?;
            (vec![seq], Vec::new(), template, height)
        }
        troupe_formats::Format::Gltf | troupe_formats::Format::Glb => {
            let gltf = troupe_formats::gltf::GltfFile::read(path)?;
            let (template, height, skeleton) = body(gltf.recorded_body())?;
            (vec![gltf.motion(&skeleton)?], Vec::new(), template, height)
        }
    };
    let performers = sequences
        .into_iter()
        .enumerate()
        .map(|(i, sequence)| Performer {
            name: if sequence.name.is_empty() {
                format!("actor{i}")
            } else {
                sequence.name.clone()
            },
            template: sequence
                .meta
                .get("template")
                .cloned()
                .unwrap_or_else(|| template.clone()),
            height: sequence
                .meta
                .get("height")
                .and_then(|h| h.parse().ok())
                .or(height),
            sequence,
        })
        .collect();
    Ok(Recording {
        performers,
        objects,
    })
}

/// Parses `--debug CHANNEL[,CHANNEL]` (channels: `nav`).
pub(crate) fn parse_debug(list: &str) -> Result<DebugView, ViewerError> {
    DebugView::parse(list)
}

pub(crate) fn has_display() -> bool {
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|v| std::env::var_os(v).is_some_and(|s| !s.is_empty()))
}

/// How actors are drawn (`--look`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Look {
    /// The generated skin: a smooth body with hands and a face.
    #[default]
    Skin,
    /// The body solids (thesis 3.1).
    Solids,
    /// A stick figure.
    Bones,
}

/// The viewer's body style for `--look`; `--bones` (kept for old command lines) wins.
pub(crate) fn body_style(look: Look, bones: bool) -> BodyStyle {
    match (look, bones) {
        (_, true) | (Look::Bones, _) => BodyStyle::Bones,
        (Look::Solids, _) => BodyStyle::Solids,
        (Look::Skin, _) => BodyStyle::Skin,
    }
}

fn render_options(look: Look, bones: bool, labels: bool) -> RenderOptions {
    RenderOptions {
        labels,
        style: body_style(look, bones),
        ..RenderOptions::default()
    }
}

/// Runs `troupe view`.
pub fn run(args: ViewArgs) -> Result<ExitCode> {
    if let Some(prefix) = &args.remote.zenoh {
        return remote::run(&args, prefix);
    }
    let file = args
        .file
        .as_deref()
        .ok_or_else(|| anyhow!("troupe view: give a recording to play"))?;
    let size = parse_size(&args.size)?;
    let Recording {
        performers,
        objects,
    } = load_recording(file, &args.actor_template, args.actor_height)?;
    let mut scene = Scene::new(SceneConfig {
        rate: args.rate,
        ..SceneConfig::default()
    })?;
    let object_length = objects.iter().map(|o| o.pose.end()).fold(0.0, f64::max);
    let playback = ObjectPlayback::install(&mut scene, objects)
        .with_context(|| format!("{}: recorded objects", file.display()))?;
    let mut length: f64 = 0.0;
    for p in &performers {
        let desc = ActorDesc {
            template: p.template.clone(),
            height: p.height,
            ..ActorDesc::new(p.name.clone())
        };
        let actor = scene.add_actor(&desc)?;
        // In step with the recorded run: the first frame shows its first posture.
        let (_, played) =
            replay(&mut scene, actor, &p.sequence, Some(true)).with_context(|| {
                format!(
                    "{}: `{}` on template {}",
                    file.display(),
                    p.name,
                    p.template
                )
            })?;
        length = length.max(played);
    }
    length = length.max(object_length);
    let camera: Camera = match &args.camera {
        Some(c) => c.parse()?,
        None if performers.len() == 1 => format!("follow:{}", performers[0].name).parse()?,
        None => Camera::fit(),
    };
    check_camera(&camera, &scene)?;

    let headless_dir = match (&args.frames, has_display()) {
        (Some(dir), _) => Some(dir.clone()),
        (None, false) => {
            eprintln!("troupe view: no display (DISPLAY/WAYLAND_DISPLAY unset): writing PNG frames to frames/");
            Some(PathBuf::from("frames"))
        }
        (None, true) => None,
    };
    if let Some(dir) = headless_dir {
        let seconds = args.seconds.unwrap_or(length);
        // Past its end a recording holds still: every further tick would write the same
        // picture again (`--seconds 1e9` filled the disk).
        if !(0.0..=length + 1.0 / args.rate).contains(&seconds) {
            bail!(
                "--seconds {seconds}: {} plays for {length:.2} s; its frames end there",
                file.display()
            );
        }
        let options = render_options(args.look, args.bones, !args.no_labels);
        let mut writer = FrameWriter::new(&dir, size, camera, args.every)?;
        writer.renderer_mut().set_options(options);
        writer.renderer_mut().set_multisampling(!args.no_msaa);
        writer.set_debug(args.debug.unwrap_or_default());
        return write_frames(with_objects(Session::new(scene), playback), writer, seconds);
    }
    let options = WindowOptions {
        title: format!("troupe view {}", file.display()),
        size,
        camera: camera.clone(),
        render: render_options(args.look, args.bones, !args.no_labels),
        tick_seconds: scene.dt(),
        close_after_frames: None,
    };
    // The session moves to the simulation thread; keep nothing else that needs it.
    let mut session = with_objects(Session::new(scene), playback);
    let debug = args.debug.unwrap_or_default();
    let result = run_window(options, move || {
        // No observer can fail here; a tick always happens.
        let _ = session.tick();
        Frame::from_scene(session.scene()).with_debug(session.scene(), debug)
    });
    match result {
        Ok(()) => Ok(ExitCode::SUCCESS),
        Err(e @ ViewerError::NoDisplay { .. }) => {
            Err(anyhow!(e).context("troupe view: use --frames DIR to render headless"))
        }
        Err(e) => Err(e.into()),
    }
}

/// The session with the recorded objects moving, if there are any.
fn with_objects(mut session: Session, playback: ObjectPlayback) -> Session {
    if !playback.is_empty() {
        session.add_input(Box::new(playback));
    }
    session
}

/// Plays the session headless for `seconds`, writing pictures.
fn write_frames(mut session: Session, writer: FrameWriter, seconds: f64) -> Result<ExitCode> {
    let ticks = (seconds * session.scene().config().rate).ceil() as u64;
    session.observe(writer);
    let ran = session.run(RunLimit {
        ticks,
        until_idle: false,
    });
    // The frames written before an error stay, and are reported.
    for line in session.finish()? {
        println!("{line} over {seconds:.2} s");
    }
    ran?;
    Ok(ExitCode::SUCCESS)
}

/// One `--pose` parsed: DOF values by name plus placement and hand states.
#[derive(Default)]
struct Pose {
    dofs: Vec<(String, f64)>,
    hands: Vec<(Hand, HandState)>,
    at: Option<(f64, f64)>,
    facing: Option<f64>,
}

fn parse_pose(spec: &str) -> Result<Pose> {
    let mut pose = Pose::default();
    for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (key, value) = item
            .split_once('=')
            .ok_or_else(|| anyhow!("--pose `{item}`: expected NAME=VALUE"))?;
        let (key, value) = (key.trim(), value.trim());
        let number = |v: &str| -> Result<f64> {
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| anyhow!("--pose `{item}`: `{v}` is not a number"))
        };
        match key {
            "l_hand" | "r_hand" => {
                let state = HandState::parse(value).ok_or_else(|| {
                    anyhow!("--pose `{item}`: hand state must be free, grasping or secure")
                })?;
                let hand = if key == "l_hand" {
                    Hand::Left
                } else {
                    Hand::Right
                };
                pose.hands.push((hand, state));
            }
            "at" => {
                let (x, z) = value
                    .split_once(':')
                    .ok_or_else(|| anyhow!("--pose `{item}`: expected at=X:Z"))?;
                pose.at = Some((number(x)?, number(z)?));
            }
            "facing" => pose.facing = Some(number(value)?),
            dof => pose.dofs.push((dof.to_string(), number(value)?)),
        }
    }
    Ok(pose)
}

const NAMES: [&str; 8] = ["ann", "bob", "cleo", "dan", "eve", "finn", "gus", "hal"];

/// Runs `troupe snapshot`.
pub fn snapshot(args: SnapshotArgs) -> Result<ExitCode> {
    png_path(&args.out)?;
    let size = parse_size(&args.size)?;
    let camera: Camera = args.camera.parse()?;
    if !args.spacing.is_finite() {
        bail!("--spacing must be a finite number of metres");
    }
    let specs = if args.poses.is_empty() {
        vec![String::new()]
    } else {
        args.poses.clone()
    };
    let poses = specs
        .iter()
        .map(|s| parse_pose(s))
        .collect::<Result<Vec<_>>>()?;
    let mut scene = Scene::new(SceneConfig::default())?;
    let n = poses.len();
    for (i, pose) in poses.iter().enumerate() {
        let name = NAMES
            .get(i)
            .map(|s| s.to_string())
            .unwrap_or_else(|| format!("actor{}", i + 1));
        let mut desc = ActorDesc::new(&name);
        desc.template = args.actor_template.clone();
        let (x, z) = pose
            .at
            .unwrap_or(((i as f64 - (n - 1) as f64 / 2.0) * args.spacing, 0.0));
        desc.at = DVec3::new(x, 0.0, z);
        desc.facing_degrees = pose.facing.unwrap_or(0.0);
        let actor = scene.add_actor(&desc)?;
        let skeleton = scene.actors()[actor].skeleton.clone();
        let mut values = Vec::new();
        for (dof_name, v) in &pose.dofs {
            let d = skeleton.dof(dof_name)?;
            let value = match skeleton.dofs()[d].kind {
                DofKind::Rotation => v.to_radians(),
                DofKind::Translation => *v,
            };
            values.push((d, value));
        }
        scene.set_dofs(actor, &values)?;
    }
    check_camera(&camera, &scene)?;
    // A snapshot is a session that never ticks: the posed scene is its only frame.
    let session = Session::new(scene);
    let mut frame = Frame::from_scene(session.scene());
    for (actor, pose) in frame.actors.iter_mut().zip(&poses) {
        for &(hand, state) in &pose.hands {
            actor.set_hand(hand, state);
        }
    }
    let mut renderer = OffscreenRenderer::new(size.0, size.1)?;
    renderer.set_options(render_options(args.look, args.bones, !args.no_labels));
    renderer.save_png(&frame, &camera, &args.out)?;
    println!(
        "wrote {} ({}x{}, {} actor{}) on {}",
        args.out.display(),
        size.0,
        size.1,
        n,
        if n == 1 { "" } else { "s" },
        renderer.adapter()
    );
    Ok(ExitCode::SUCCESS)
}

/// Refuses an output picture not named `.png`: troupe writes PNG, and a `.jpg` of PNG
/// data is read wrongly by other tools.
pub fn png_path(out: &std::path::Path) -> Result<()> {
    let png = out
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if !png {
        bail!(
            "{}: troupe writes PNG pictures: name the file .png",
            out.display()
        );
    }
    Ok(())
}

/// A camera that follows an actor the scene lacks is refused, naming the actors there are.
pub(crate) fn check_camera(camera: &Camera, scene: &Scene) -> Result<()> {
    if let troupe_viewer::Focus::Actor(name) = &camera.focus {
        let actors = scene.actors();
        if !actors.iter().any(|a| a.name == *name) {
            let names: Vec<&str> = actors.iter().map(|a| a.name.as_str()).collect();
            bail!(
                "--camera follow:{name}: the scene has no actor `{name}` (actors: {})",
                if names.is_empty() {
                    "none".into()
                } else {
                    names.join(", ")
                }
            );
        }
    }
    Ok(())
}
