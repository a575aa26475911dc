//! `troupe run`: load a Lua scene and run it headless, recording what was asked.

use crate::observers::{RecordFile, TorqueFile, TraceFile};
use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use troupe_lua::{Director, LuaSession, LuaSessionExt, ScriptLimits};
use troupe_scene::pacing::Pacer;
use troupe_scene::tally::ActionTally;
use troupe_scene::{ObserverHandle, RunLimit, SceneConfig};

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
    /// Show the run in a window (needs a display) instead of running headless; --record,
    /// --trace, --osc-out and --record-devices work as in a headless run.
    #[arg(long, conflicts_with_all = ["frames", "realtime"])]
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
    /// Recording and replaying received messages.
    #[command(flatten)]
    pub messages: crate::messages::MessageArgs,
    /// Publishing on Zenoh (`--zenoh …`).
    #[cfg(feature = "zenoh")]
    #[command(flatten)]
    pub zenoh: crate::net::ZenohArgs,
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
    // Everything that can be refused is checked before devices open and a scene loads.
    let dt = 1.0 / args.rate;
    let limit = RunLimit {
        ticks: match (args.ticks, args.seconds) {
            (Some(t), _) => t,
            (None, Some(s)) => {
                if !(s.is_finite() && s >= 0.0) {
                    bail!("--seconds must be a number ≥ 0");
                }
                (s / dt).round() as u64
            }
            (None, None) => (args.max_seconds / dt).ceil() as u64,
        },
        until_idle: args.until_idle || (args.ticks.is_none() && args.seconds.is_none()),
    };
    let size = troupe_viewer::parse_size(&args.size)?;
    let camera: troupe_viewer::Camera = args.camera.parse()?;
    if args.view && !crate::view::has_display() {
        bail!("--view needs a display (DISPLAY or WAYLAND_DISPLAY); run headless with --frames DIR instead");
    }
    let osc_out = match &args.osc_out {
        Some(target) => {
            Some(troupe_drivers::osc::OscOut::new(target).map_err(|e| anyhow::anyhow!(e))?)
        }
        None => None,
    };
    let frames = match &args.frames {
        Some(dir) => Some(troupe_viewer::FrameWriter::new(
            dir,
            size,
            camera.clone(),
            args.every,
        )?),
        None => None,
    };

    let replay_messages = args.messages.replay()?;
    #[cfg(feature = "zenoh")]
    let (config, zenoh) = args.zenoh.open(config)?;
    let (mut session, devices) =
        crate::devices::session(config, limits, args.record_devices.as_deref())?;
    session.scene_mut().set_chunk_size(args.chunk);
    let tally = session.observe(ActionTally::new());
    session.observe(devices);
    #[cfg(feature = "zenoh")]
    zenoh.install_remote_ports(&session);
    if let Err(e) = session.load_file(&args.scene) {
        // Devices the scene opened before it failed still close and report.
        for line in session.finish().unwrap_or_default() {
            println!("{line}");
        }
        return Err(anyhow::Error::new(e).context(format!("loading {}", args.scene.display())));
    }
    // What every run, headless or in a window, attaches to its session.
    if let Some(osc) = osc_out {
        session.observe(osc);
    }
    args.messages.attach(&mut session, replay_messages);
    #[cfg(feature = "zenoh")]
    zenoh.attach(&mut session);
    if let Some(path) = &args.record {
        session.observe(RecordFile::new(path));
    }
    if let Some(path) = &args.record_torques {
        session.observe(TorqueFile::new(path));
    }
    if let Some(path) = &args.trace {
        session.observe(TraceFile::new(path));
    }
    if let Some(frames) = frames {
        session.observe(frames);
    }
    // Pacing comes last: it waits once everything else has seen the tick.
    if args.realtime {
        session.observe(Pacer::new(Duration::from_secs_f64(dt)));
    }
    if args.view {
        return view_run(session, tally, limit, size, camera, &args);
    }
    let started = Instant::now();
    let ran = session.run(limit);
    let wall = started.elapsed();
    let ticks = session.scene().tick();
    println!(
        "ran {} for {ticks} ticks: {:.2} s simulated in {:.3} s wall ({} actors, {} thread{})",
        args.scene.display(),
        session.scene().time(),
        wall.as_secs_f64(),
        session.scene().actors().len(),
        args.threads,
        if args.threads == 1 { "" } else { "s" }
    );
    report(session, tally, limit, ran.map(drop))
}

/// Prints what a run did, lets every observer write its output (even after an error, so
/// nothing recorded is lost), and returns the exit code.
fn report(
    mut session: LuaSession,
    tally: ObserverHandle<ActionTally>,
    limit: RunLimit,
    ran: troupe_scene::Result<()>,
) -> Result<ExitCode> {
    println!("{}", session.observer(tally).summary(session.scene()));
    let reports = session.script().behaviors(session.scene());
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
    if limit.until_idle && still > 0 {
        println!("  stopped at --max-seconds with {still} behavior(s) still running");
    }
    let finished = session.finish();
    for line in finished.iter().flatten() {
        println!("{line}");
    }
    ran?;
    finished?;
    Ok(if failed > 0 {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

/// `--view`: the session runs on the window's simulation thread until the window closes
/// or the run's limit is reached; it records, traces and sends OSC like a headless run.
fn view_run(
    session: LuaSession,
    tally: ObserverHandle<ActionTally>,
    limit: RunLimit,
    size: (u32, u32),
    camera: troupe_viewer::Camera,
    args: &RunArgs,
) -> Result<ExitCode> {
    let options = troupe_viewer::WindowOptions {
        title: format!("troupe run {}", args.scene.display()),
        size,
        camera,
        tick_seconds: 1.0 / args.rate,
        ..Default::default()
    };
    // The window keeps showing the last frame once the run is over; the first error
    // stops the ticks and is reported when the window closes. The session comes back
    // through the mutex to write its outputs.
    struct Windowed {
        session: LuaSession,
        ticks: u64,
        outcome: troupe_scene::Result<()>,
    }
    let shared = Arc::new(Mutex::new(Windowed {
        session,
        ticks: 0,
        outcome: Ok(()),
    }));
    let sim = shared.clone();
    let shown = troupe_viewer::run_window(options, move || {
        let mut w = sim.lock().unwrap_or_else(|e| e.into_inner());
        let over =
            w.ticks >= limit.ticks || (limit.until_idle && w.ticks > 0 && w.session.is_idle());
        if !over && w.outcome.is_ok() {
            w.outcome = w.session.tick().map(drop);
            w.ticks += 1;
        }
        troupe_viewer::Frame::from_scene(w.session.scene())
    });
    let Windowed {
        session, outcome, ..
    } = Arc::try_unwrap(shared)
        .map_err(|_| anyhow::anyhow!("the simulation thread still holds the session"))?
        .into_inner()
        .unwrap_or_else(|e| e.into_inner());
    println!(
        "ran {} for {} ticks in a window: {:.2} s simulated",
        args.scene.display(),
        session.scene().tick(),
        session.scene().time()
    );
    let code = report(session, tally, limit, outcome)?;
    shown?;
    Ok(code)
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
    let mut session = Director::session(
        config,
        troupe_actions::action_kinds(),
        ScriptLimits::default(),
    )?;
    session
        .load_file(&args.scene)
        .with_context(|| format!("loading {}", args.scene.display()))?;
    let ticks = (args.at * args.rate).round() as u64;
    session.run(RunLimit {
        ticks,
        until_idle: false,
    })?;
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
    let frame = troupe_viewer::Frame::from_scene(session.scene());
    renderer.save_png(&frame, &camera, &args.out)?;
    println!(
        "rendered {} at t = {:.2} s to {}",
        args.scene.display(),
        session.scene().time(),
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
