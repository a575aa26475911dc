//! `troupe run`: load a Lua scene and run it headless, recording what was asked.

use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};
use troupe_lua::{Director, ScriptLimits};
use troupe_scene::pacing::Pacer;
use troupe_scene::record::PostureRecorder;
use troupe_scene::timeline::TimelineRecorder;
use troupe_scene::{SceneConfig, Status};

/// Options of `troupe run`.
#[derive(Args)]
pub struct RunArgs {
    /// The scene file (Lua).
    pub scene: PathBuf,
    /// Run this many ticks.
    #[arg(long, conflicts_with_all = ["seconds", "until_idle"])]
    pub ticks: Option<u64>,
    /// Run this many seconds of simulated time.
    #[arg(long, conflicts_with = "until_idle")]
    pub seconds: Option<f64>,
    /// Run until every behavior has returned and no action is active (the default),
    /// at most --max-seconds.
    #[arg(long)]
    pub until_idle: bool,
    /// Upper bound on simulated time for --until-idle.
    #[arg(long, default_value_t = 600.0)]
    pub max_seconds: f64,
    /// Ticks per second.
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// Pace ticks in real time instead of as fast as possible.
    #[arg(long)]
    pub realtime: bool,
    /// Worker threads for stepping actors.
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Actors a worker claims at a time (default: sized by the crowd; a second worker
    /// starts only above 16 actors). `--chunk 1` steps even two actors on two threads,
    /// to check that a small scene is bit-identical whatever the thread count.
    #[arg(long)]
    pub chunk: Option<usize>,
    /// Seed for the scene's random numbers.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Write every actor's postures: a sequence set to a `.trk` file, or one `.bvh` /
    /// `.gltf` (+ `.bin`) per actor (`NAME.ACTOR.bvh` when there are several).
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// Write the joint torques of the dynamics actions (simulate, servo, track), per DOF
    /// and tick, to a `.trk` file (one sequence per actor; `troupe seq plot` draws it).
    #[arg(long, value_name = "FILE.trk")]
    pub record_torques: Option<PathBuf>,
    /// Write the action timeline as Chrome trace-event JSON.
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// Write PNG frames of the run into DIR (headless, CPU rendering).
    #[arg(long, value_name = "DIR")]
    pub frames: Option<PathBuf>,
    /// With --frames: write every N-th tick.
    #[arg(long, default_value_t = 4, value_name = "N")]
    pub every: u64,
    /// Picture or window size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Camera: fit, follow:NAME or fixed:EX,EY,EZ:TX,TY,TZ (fit and follow take
    /// @YAW,PITCH[,DISTANCE]).
    #[arg(long, default_value = "fit")]
    pub camera: String,
    /// Show the run in a window (needs a display) instead of running headless.
    #[arg(long, conflicts_with_all = ["frames", "record", "record_torques", "trace", "realtime", "record_devices", "osc_out"])]
    pub view: bool,
    /// VM instructions one script resume may execute.
    #[arg(long, default_value_t = ScriptLimits::default().instructions)]
    pub instruction_budget: u64,
    /// Bytes one script resume may add to the Lua heap.
    #[arg(long, default_value_t = ScriptLimits::default().memory)]
    pub memory_limit: usize,
    /// Record every live device stream (timestamps + raw bytes) to FILE.rec.
    #[arg(long, value_name = "FILE.rec")]
    pub record_devices: Option<PathBuf>,
    /// Send every actor's joint poses and the action events over OSC (UDP) to HOST:PORT
    /// each tick (addresses in docs/devices.md).
    #[arg(long, value_name = "HOST:PORT")]
    pub osc_out: Option<String>,
}

/// Runs the scene and prints the summary.
pub fn run(args: RunArgs) -> Result<ExitCode> {
    let config = SceneConfig {
        rate: args.rate,
        threads: args.threads,
        seed: args.seed,
    };
    let limits = ScriptLimits {
        instructions: args.instruction_budget,
        memory: args.memory_limit,
    };
    if let Some(path) = &args.record_torques {
        if !path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("trk"))
        {
            bail!(
                "--record-torques {}: torques are written as a .trk file",
                path.display()
            );
        }
    }
    for path in [&args.record, &args.record_torques, &args.trace]
        .into_iter()
        .flatten()
    {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
        }
    }
    let (mut director, devices) =
        crate::devices::director(config, limits, args.record_devices.as_deref())?;
    director.with_scene_mut(|s| s.set_chunk_size(args.chunk));
    let osc_out = match &args.osc_out {
        Some(t) => Some(troupe_drivers::osc::OscSender::new(t).map_err(|e| anyhow::anyhow!(e))?),
        None => None,
    };
    let torques = args.record_torques.as_ref().map(|_| {
        let log = troupe_actions::dynamics::TorqueLog::new();
        log.install(director.lua());
        log
    });
    director
        .load_file(&args.scene)
        .with_context(|| format!("loading {}", args.scene.display()))?;
    let dt = 1.0 / args.rate;
    let max_ticks = match (args.ticks, args.seconds) {
        (Some(t), _) => t,
        (None, Some(s)) => {
            if !(s.is_finite() && s >= 0.0) {
                bail!("--seconds must be a number ≥ 0");
            }
            (s / dt).round() as u64
        }
        (None, None) => (args.max_seconds / dt).ceil() as u64,
    };
    let until_idle = args.until_idle || (args.ticks.is_none() && args.seconds.is_none());

    if args.view {
        return view_run(director, &args);
    }
    let mut frames = match &args.frames {
        Some(dir) => Some(troupe_viewer::FrameWriter::new(
            dir,
            troupe_viewer::parse_size(&args.size)?,
            args.camera.parse()?,
            args.every,
        )?),
        None => None,
    };
    if let Some(f) = frames.as_mut() {
        f.tick(&director.scene())?;
    }
    let mut recorder = args.record.as_ref().map(|_| PostureRecorder::new());
    let mut timeline = args.trace.as_ref().map(|_| TimelineRecorder::new());
    if let Some(r) = recorder.as_mut() {
        r.sample(&director.scene());
    }
    let mut pacer = args
        .realtime
        .then(|| Pacer::new(Duration::from_secs_f64(dt)));
    let mut counts = vec![[0usize; 3]; director.scene().actors().len()];
    let started = Instant::now();
    let mut ticks = 0;
    let mut osc_failures = 0u64;
    while ticks < max_ticks {
        if until_idle && ticks > 0 && director.is_idle() {
            break;
        }
        let events = director.tick();
        devices.end_tick();
        ticks += 1;
        let scene = director.scene();
        if let Some(o) = &osc_out {
            // A lost datagram must not end the run: say so once, count the rest.
            if let Err(e) = o.send(&scene, &events) {
                if osc_failures == 0 {
                    tracing::warn!("--osc-out: {e} (further failures are counted)");
                }
                osc_failures += 1;
            }
        }
        if counts.len() < scene.actors().len() {
            counts.resize(scene.actors().len(), [0; 3]);
        }
        for e in &events {
            match e.status {
                Status::Completed => counts[e.actor][0] += 1,
                Status::Cancelled => counts[e.actor][1] += 1,
                Status::Failed => counts[e.actor][2] += 1,
                _ => {}
            }
        }
        if let Some(r) = recorder.as_mut() {
            r.sample(&scene);
        }
        if let Some(t) = timeline.as_mut() {
            t.record(&scene, &events);
        }
        if let Some(f) = frames.as_mut() {
            f.tick(&scene)?;
        }
        drop(scene);
        if let Some(p) = pacer.as_mut() {
            p.wait();
        }
    }
    let wall = started.elapsed();
    let scene = director.scene();
    println!(
        "ran {} for {ticks} ticks: {:.2} s simulated in {:.3} s wall ({} actors, {} thread{})",
        args.scene.display(),
        scene.time(),
        wall.as_secs_f64(),
        scene.actors().len(),
        args.threads,
        if args.threads == 1 { "" } else { "s" }
    );
    if let Some(p) = &pacer {
        println!(
            "real time: {} overruns (worst {:.1} ms late)",
            p.overruns(),
            p.worst_lateness().as_secs_f64() * 1e3
        );
    }
    for (i, actor) in scene.actors().iter().enumerate() {
        let [done, cancelled, failed] = counts[i];
        println!(
            "  {:<12} actions: {done} completed, {cancelled} cancelled, {failed} failed",
            actor.name
        );
    }
    drop(scene);
    devices.finish()?;
    if osc_failures > 0 {
        println!("--osc-out: {osc_failures} sends failed");
    }
    let reports = director.behaviors();
    let mut failed = 0;
    for r in &reports {
        if let Some(err) = &r.error {
            failed += 1;
            println!(
                "  behavior of {} failed: {}",
                r.actor,
                err.lines().next().unwrap_or("")
            );
            for line in err.lines().skip(1) {
                println!("      {line}");
            }
        }
    }
    let still = reports.iter().filter(|r| r.status == "running").count();
    if until_idle && still > 0 {
        println!("  stopped at --max-seconds with {still} behavior(s) still running");
    }
    let scene = director.scene();
    if let (Some(path), Some(r)) = (&args.record, &recorder) {
        let written = write_recording(path, &r.sequences(&scene), &scene)?;
        let list: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        println!(
            "recorded {} ticks of postures to {}",
            r.len(),
            list.join(", ")
        );
    }
    if let (Some(path), Some(log)) = (&args.record_torques, &torques) {
        let set = log.sequences(&scene);
        if set.is_empty() {
            println!(
                "no dynamics action ran: no torques to record to {}",
                path.display()
            );
        } else {
            troupe_formats::trk::write_trk(path, &set)?;
            println!(
                "recorded {} joint torques ({} actor(s)) to {}",
                log.len(),
                set.len(),
                path.display()
            );
        }
    }
    if let (Some(dir), Some(f)) = (&args.frames, frames.as_mut()) {
        println!(
            "wrote {} frames to {} (rendered on {})",
            f.written(),
            dir.display(),
            f.renderer_mut().adapter()
        );
    }
    if let (Some(path), Some(t)) = (&args.trace, timeline.as_mut()) {
        let json = serde_json::to_string(&t.to_json(&scene))?;
        std::fs::write(path, json).with_context(|| format!("writing {}", path.display()))?;
        println!(
            "wrote the action timeline to {} (open in Perfetto or chrome://tracing)",
            path.display()
        );
    }
    Ok(if failed > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// Writes a recording by the file's extension: `.trk` holds every actor; `.bvh` and
/// `.gltf` hold one actor each, so a scene of several actors writes `NAME.ACTOR.EXT`.
fn write_recording(
    path: &std::path::Path,
    sequences: &[troupe_motion::Sequence],
    scene: &troupe_scene::Scene,
) -> Result<Vec<PathBuf>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext == "trk" {
        troupe_formats::trk::write_trk(path, sequences)?;
        return Ok(vec![path.to_path_buf()]);
    }
    if ext != "bvh" && ext != "gltf" {
        bail!(
            "--record {}: use a .trk, .bvh or .gltf file",
            path.display()
        );
    }
    let mut written = Vec::new();
    for (seq, actor) in sequences.iter().zip(scene.actors()) {
        let out = if sequences.len() == 1 {
            path.to_path_buf()
        } else {
            let stem = path.file_stem().unwrap_or_default().to_string_lossy();
            path.with_file_name(format!("{stem}.{}.{ext}", actor.name))
        };
        let rig = troupe_formats::gltf::Rig::from_sequence(&actor.skeleton, seq)?;
        if ext == "bvh" {
            let order = "ZXY".parse()?;
            let bvh = troupe_formats::bvh::from_rig(&rig, seq.frame_time(), order, 100.0)?;
            troupe_formats::bvh::write_bvh(&out, &bvh)?;
        } else {
            troupe_formats::gltf::write_gltf(&out, &rig, &actor.name)?;
        }
        written.push(out);
    }
    Ok(written)
}

/// `--view`: the scene runs on the window's simulation thread until the window closes.
fn view_run(mut director: Director, args: &RunArgs) -> Result<ExitCode> {
    if !crate::view::has_display() {
        bail!("--view needs a display (DISPLAY or WAYLAND_DISPLAY); run headless with --frames DIR instead");
    }
    let options = troupe_viewer::WindowOptions {
        title: format!("troupe run {}", args.scene.display()),
        size: troupe_viewer::parse_size(&args.size)?,
        camera: args.camera.parse()?,
        tick_seconds: 1.0 / args.rate,
        ..Default::default()
    };
    troupe_viewer::run_window(options, move || {
        director.tick();
        troupe_viewer::Frame::from_scene(&director.scene())
    })?;
    Ok(ExitCode::SUCCESS)
}

/// Options of `troupe render`.
#[derive(Args)]
pub struct RenderArgs {
    /// The scene file (Lua).
    pub scene: PathBuf,
    /// The PNG file to write.
    pub out: PathBuf,
    /// Simulated time of the picture, in seconds.
    #[arg(long, default_value_t = 0.0)]
    pub at: f64,
    /// Picture size, WIDTHxHEIGHT.
    #[arg(long, default_value = "1280x720")]
    pub size: String,
    /// Camera: fit, follow:NAME or fixed:EX,EY,EZ:TX,TY,TZ.
    #[arg(long, default_value = "fit")]
    pub camera: String,
    /// Ticks per second.
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// Seed for the scene's random numbers.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Do not draw names and action labels above the heads.
    #[arg(long)]
    pub no_labels: bool,
    /// Draw actors as bones instead of solids.
    #[arg(long)]
    pub bones: bool,
}

/// `troupe render`: runs a scene headless up to `--at` and writes one picture.
pub fn render(args: RenderArgs) -> Result<ExitCode> {
    if !(args.at.is_finite() && args.at >= 0.0) {
        bail!("--at must be a number of seconds ≥ 0");
    }
    let size = troupe_viewer::parse_size(&args.size)?;
    let camera: troupe_viewer::Camera = args.camera.parse()?;
    let config = SceneConfig {
        rate: args.rate,
        threads: 1,
        seed: args.seed,
    };
    let mut director = Director::new(
        config,
        troupe_actions::action_kinds(),
        ScriptLimits::default(),
    )?;
    director
        .load_file(&args.scene)
        .with_context(|| format!("loading {}", args.scene.display()))?;
    let ticks = (args.at * args.rate).round() as u64;
    for _ in 0..ticks {
        director.tick();
    }
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let mut renderer = troupe_viewer::OffscreenRenderer::new(size.0, size.1)?;
    renderer.set_options(troupe_viewer::RenderOptions {
        labels: !args.no_labels,
        style: if args.bones {
            troupe_viewer::BodyStyle::Bones
        } else {
            troupe_viewer::BodyStyle::Solids
        },
        ..Default::default()
    });
    let frame = troupe_viewer::Frame::from_scene(&director.scene());
    renderer.save_png(&frame, &camera, &args.out)?;
    println!(
        "rendered {} at t = {:.2} s to {}",
        args.scene.display(),
        director.scene().time(),
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
