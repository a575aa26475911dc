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
    #[arg(long, conflicts_with = "until_idle", value_parser = seconds)]
    pub seconds: Option<f64>,
    /// Run until every behavior has returned and no action is active (the default),
    /// at most --max-seconds.
    #[arg(long)]
    pub until_idle: bool,
    /// Upper bound on simulated time for --until-idle.
    #[arg(long, default_value_t = 600.0, value_parser = seconds)]
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
    #[arg(long, value_parser = chunk)]
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
    /// `@YAW,PITCH[,DISTANCE]`).
    #[arg(long, default_value = "fit")]
    pub camera: String,
    /// Show the run in a window (needs a display) instead of running headless; --record,
    /// --trace, --osc-out and --record-devices work as in a headless run.
    #[arg(long, conflicts_with_all = ["frames", "realtime"])]
    pub view: bool,
    /// With --view: reload the scene when it, or a file it read, changes, and run it back
    /// to the same simulated time; a broken edit shows its error over the last good scene.
    #[arg(long, requires = "view", conflicts_with_all = ["record", "record_torques", "trace", "record_devices", "osc_out"])]
    pub watch: bool,
    /// VM instructions one script resume may execute.
    #[arg(long, default_value_t = ScriptLimits::default().instructions)]
    pub instruction_budget: u64,
    /// Bytes one script resume may add to the Lua heap.
    #[arg(long, default_value_t = ScriptLimits::default().memory)]
    pub memory_limit: usize,
    /// Bytes the scene's whole Lua heap may hold (all behaviors, handlers and globals).
    #[arg(long, default_value_t = ScriptLimits::default().heap)]
    pub lua_memory: usize,
    /// Record every live device stream (timestamps + raw bytes) to FILE.rec.
    #[arg(long, value_name = "FILE.rec")]
    pub record_devices: Option<PathBuf>,
    /// Send every actor's joint poses and the action events over OSC (UDP) to HOST:PORT
    /// each tick (addresses in docs/devices.md).
    #[arg(long, value_name = "HOST:PORT")]
    pub osc_out: Option<String>,
    /// Replay a --record-devices recording in place of the scene's live and relayed
    /// devices (`port`, `zenoh`, a VRPN `device`) and of its messages from outside: each
    /// reading and message at the tick the recorded run took it, so the postures are the
    /// recorded run's bit for bit.
    #[arg(long, value_name = "FILE.rec")]
    pub replay_devices: Option<PathBuf>,
    /// Publishing on Zenoh (`--zenoh …`).
    #[command(flatten)]
    pub zenoh: crate::net::ZenohArgs,
    /// Send an actor (default: the first) as a VMC stream to a Marionette at HOST:PORT
    /// (default port 39539); repeatable (docs/devices.md, "VMC").
    #[arg(long, value_name = "HOST:PORT[=ACTOR]")]
    pub vmc_out: Vec<String>,
    /// Frames per second of scene time of every --vmc-out stream.
    #[arg(long, default_value_t = troupe_drivers::vmc::output::DEFAULT_RATE, value_name = "HZ")]
    pub vmc_rate: f64,
    /// Debug drawing in --frames and --view: `nav` draws the navigation mesh, the
    /// obstacles' footprints, each walker's planned path and its avoidance velocities.
    #[arg(long, value_name = "CHANNEL", value_parser = crate::view::parse_debug)]
    pub debug: Option<troupe_viewer::DebugView>,
}

/// Runs the scene and prints the summary.
pub fn run(args: RunArgs) -> Result<ExitCode> {
    // From the start, so that a Ctrl-C while the scene loads stops before the first tick
    // (a window's run ends when its window closes).
    if !args.view {
        crate::interrupt::catch();
    }
    let config = SceneConfig {
        rate: args.rate,
        threads: args.threads,
        seed: args.seed,
    };
    let limits = ScriptLimits {
        instructions: args.instruction_budget,
        memory: args.memory_limit,
        heap: args.lua_memory,
    };
    // A recording's format is known from its name: refused now, not after the whole run.
    if let Some(path) = &args.record {
        troupe_formats::Format::of(path).with_context(|| format!("--record {}", path.display()))?;
    }
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
            (None, Some(s)) => (s / dt).round() as u64,
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
    let mut vmc_out = troupe_drivers::vmc::VmcOut::default();
    for spec in &args.vmc_out {
        vmc_out.streams.push(
            troupe_drivers::vmc::VmcStream::parse(spec, args.vmc_rate)
                .map_err(|e| anyhow::anyhow!("--vmc-out {spec}: {e}"))?,
        );
    }
    let debug = args.debug.unwrap_or_default();
    let frames = match &args.frames {
        Some(dir) => {
            let mut writer =
                troupe_viewer::FrameWriter::new(dir, size, camera.clone(), args.every)?;
            writer.set_debug(debug);
            Some(writer)
        }
        None => None,
    };

    if args.watch {
        let run = crate::watch::WatchedRun {
            scene: args.scene.clone(),
            chunk: args.chunk,
            ticks: limit.ticks,
            debug,
        };
        return crate::watch::view(run, config, limits, size, camera);
    }
    let replay = match &args.replay_devices {
        Some(path) => Some(
            troupe_drivers::record::DeviceReplay::from_file(path)
                .map_err(|e| anyhow::anyhow!("--replay-devices: {e}"))?,
        ),
        None => None,
    };
    let (config, zenoh) = args.zenoh.open(config)?;
    let record_devices = args.record_devices.as_deref();
    let recorder = crate::devices::recorder(record_devices, zenoh.replicates())?;
    let (mut session, devices) =
        crate::devices::session_recording(config, limits, recorder.clone(), record_devices)?;
    session.scene_mut().set_chunk_size(args.chunk);
    let tally = session.observe(ActionTally::new());
    session.observe(devices);
    if let Some(replay) = &replay {
        session.lua().set_app_data(replay.clone());
    }
    zenoh.install(&session);
    if let Err(e) = session.load_file(&args.scene) {
        // Devices the scene opened before it failed still close and report.
        for line in session.finish().unwrap_or_default() {
            println!("{line}");
        }
        return Err(anyhow::Error::new(e).context(format!("loading {}", args.scene.display())));
    }
    warn_of_tests(&session, &args.scene);
    crate::view::check_camera(&camera, session.scene())?;
    // What every run, headless or in a window, attaches to its session.
    if let Some(osc) = osc_out {
        session.observe(osc);
    }
    if let Some(replay) = &replay {
        session.add_input(Box::new(replay.messages()));
    }
    // Messages from outside go in the recording with the device streams (before the
    // publisher, which sends each tick's chunks to followers).
    if let Some(recorder) = &recorder {
        session.observe(troupe_drivers::record::RecordMessages(recorder.clone()));
    }
    zenoh.attach(&mut session, recorder);
    if !vmc_out.streams.is_empty() {
        session.observe(vmc_out);
    }
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
    let ran = session.run_while(limit, || !crate::interrupt::requested());
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

/// What kept an `--until-idle` run from ending before `--max-seconds`: the behaviors
/// still running and every action not yet ended, with its actor and since when.
fn print_still_running(session: &LuaSession, reports: &[troupe_lua::BehaviorReport]) {
    let scene = session.scene();
    let behaviors: Vec<&str> = reports
        .iter()
        .filter(|r| r.status == "running")
        .map(|r| r.actor.as_str())
        .collect();
    let actions: Vec<String> = (0..scene.actors().len())
        .flat_map(|a| scene.actions_of(a))
        .filter(|a| !a.status.is_final())
        .map(|a| {
            format!(
                "{} of {} ({}{})",
                a.kind,
                scene.actors()[a.actor].name,
                a.status.name(),
                a.started_at
                    .map(|t| format!(" since {t:.2} s"))
                    .unwrap_or_default()
            )
        })
        .collect();
    println!(
        "  stopped at --max-seconds ({:.2} s) before the scene was idle:",
        scene.time()
    );
    if !behaviors.is_empty() {
        println!(
            "    {} behavior(s) still running: {}",
            behaviors.len(),
            behaviors.join(", ")
        );
    }
    if !actions.is_empty() {
        println!("    {} action(s) still running:", actions.len());
        for a in actions {
            println!("      {a}");
        }
    }
}

/// A scene that registers tests is probably meant for `troupe test`: say so, since `run`
/// does not run them.
fn warn_of_tests(session: &LuaSession, scene: &std::path::Path) {
    let names = session.script().test_names();
    if !names.is_empty() {
        eprintln!(
            "troupe: warning: {} defines {} test(s) (\"{}\"{}); `troupe run` does not run \
             tests: use `troupe test {}`",
            scene.display(),
            names.len(),
            names[0],
            if names.len() > 1 { ", …" } else { "" },
            scene.display()
        );
    }
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
    if limit.until_idle && !session.is_idle() {
        print_still_running(&session, &reports);
    }
    let interrupted = crate::interrupt::requested();
    if interrupted {
        println!(
            "  interrupted (Ctrl-C) at {:.2} s: stopped there, writing what was recorded",
            session.scene().time()
        );
    }
    let finished = session.finish();
    for line in finished.iter().flatten() {
        println!("{line}");
    }
    ran?;
    finished?;
    // A Ctrl-C while the recordings were written still ends the run as interrupted.
    let interrupted = interrupted || crate::interrupt::requested();
    Ok(if interrupted {
        ExitCode::from(crate::interrupt::EXIT_CODE)
    } else if failed > 0 {
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
    let debug = args.debug.unwrap_or_default();
    let shown = troupe_viewer::run_window(options, move || {
        let mut w = sim.lock().unwrap_or_else(|e| e.into_inner());
        let over =
            w.ticks >= limit.ticks || (limit.until_idle && w.ticks > 0 && w.session.is_idle());
        if !over && w.outcome.is_ok() {
            w.outcome = w.session.tick().map(drop);
            w.ticks += 1;
        }
        troupe_viewer::Frame::from_scene(w.session.scene()).with_debug(w.session.scene(), debug)
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
    /// Simulated time of the picture, in seconds (at most --max-seconds).
    #[arg(long, default_value_t = 0.0, value_parser = seconds)]
    pub at: f64,
    /// Latest --at accepted: the picture's time is reached by simulating every tick
    /// before it, so a slip (`--at 1e9`) would run for days.
    #[arg(long, default_value_t = 600.0, value_parser = seconds)]
    pub max_seconds: f64,
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
    /// How actors are drawn: the generated skin, the body solids, or bones.
    #[arg(long, value_enum, default_value_t = crate::view::Look::Skin)]
    pub look: crate::view::Look,
    /// Same as `--look bones`.
    #[arg(long)]
    pub bones: bool,
    /// Debug drawing: `nav` draws the navigation mesh, the obstacles' footprints, each
    /// walker's planned path and its avoidance velocities.
    #[arg(long, value_name = "CHANNEL", value_parser = crate::view::parse_debug)]
    pub debug: Option<troupe_viewer::DebugView>,
}

/// The longest simulated time a command line may ask for (about 31 years): more is a
/// slip (`--seconds 1e300` ran for ever).
const LONGEST: f64 = 1e9;

/// A command-line duration: seconds, ≥ 0 and at most [`LONGEST`].
pub fn seconds(text: &str) -> std::result::Result<f64, String> {
    let s: f64 = text
        .parse()
        .map_err(|_| format!("`{text}` is not a number of seconds"))?;
    if !(0.0..=LONGEST).contains(&s) {
        return Err(format!("{text} s: a duration is from 0 to {LONGEST:e} s"));
    }
    Ok(s)
}

/// A command-line `--chunk`: actors a worker claims at a time, at least 1.
pub fn chunk(text: &str) -> std::result::Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!(
            "`{text}`: a chunk is a whole number of actors, at least 1"
        )),
    }
}

/// `troupe render`: runs a scene headless up to `--at` and writes one picture.
pub fn render(args: RenderArgs) -> Result<ExitCode> {
    crate::view::png_path(&args.out)?;
    if args.at > args.max_seconds {
        bail!(
            "--at {} s is past --max-seconds ({} s): rendering a time means simulating the \
             whole scene up to it; raise --max-seconds to render later",
            args.at,
            args.max_seconds
        );
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
    crate::view::check_camera(&camera, session.scene())?;
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
        style: crate::view::body_style(args.look, args.bones),
        ..Default::default()
    });
    let frame = troupe_viewer::Frame::from_scene(session.scene())
        .with_debug(session.scene(), args.debug.unwrap_or_default());
    renderer.save_png(&frame, &camera, &args.out)?;
    println!(
        "rendered {} at t = {:.2} s to {}",
        args.scene.display(),
        session.scene().time(),
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
