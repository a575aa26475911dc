//! `troupe bench`: runs the standard crowd scene headless, as fast as possible, for each
//! crowd size and thread count, and reports throughput, tick times, where the time goes
//! and memory.

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde_json::json;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};
use troupe_lua::{Director, ScriptLimits};
use troupe_scene::space::Walking;
use troupe_scene::SceneConfig;

/// The standard crowd scene; `BENCH.actors` sets its size.
const CROWD_SCENE: &str = include_str!("../scripts/bench/crowd.lua");
/// Where the scene lives in the repository, for error messages.
const CROWD_SCENE_NAME: &str = "scripts/bench/crowd.lua";

/// Options of `troupe bench`.
#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Crowd sizes to run, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "10,100,1000")]
    actors: Vec<usize>,
    /// Worker thread counts to run each size with, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "1,2")]
    threads: Vec<usize>,
    /// Simulated seconds measured per run (after the warm-up).
    #[arg(long, default_value_t = 10.0)]
    seconds: f64,
    /// Simulated seconds run before measuring, so every actor is under way.
    #[arg(long, default_value_t = 2.0)]
    warmup: f64,
    /// Tick rate in Hz.
    #[arg(long, default_value_t = 100.0)]
    rate: f64,
    /// Seed of the scene's random choices.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Navigation on (walks plan, avoid, give way, …), off (walks go straight to their
    /// goals), or `on,off` to run both side by side and print what navigation costs.
    #[arg(long, value_delimiter = ',', default_value = "on")]
    navigation: Vec<Navigation>,
    /// Don't time the tick phases (removes the profiling clock reads, about 1 %).
    #[arg(long)]
    no_phases: bool,
    /// Benchmark another Lua scene instead of the standard crowd; it reads its size from
    /// the global `BENCH.actors`.
    #[arg(long)]
    scene: Option<PathBuf>,
    /// Write the results as a JSON array, one object per run.
    #[arg(long)]
    json: Option<PathBuf>,
}

/// Whether the crowd's walks navigate (see [`Walking`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum Navigation {
    /// Walks plan round obstacles, avoid one another, give way, keep lanes, take new
    /// routes and turn their shoulders to pass.
    On,
    /// Walks go straight to their goals (`Walking::Straight`): the rest of the tick's
    /// work without navigation's.
    Off,
}

impl Navigation {
    fn walking(self) -> Walking {
        match self {
            Navigation::On => Walking::Navigated,
            Navigation::Off => Walking::Straight,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Navigation::On => "on",
            Navigation::Off => "off",
        }
    }
}

/// What one run measured.
struct RunResult {
    actors: usize,
    threads: usize,
    navigation: Navigation,
    ticks: usize,
    wall: Duration,
    tick_mean: Duration,
    tick_p99: Duration,
    /// The process's CPU time (user + system) over the measured ticks: on a machine
    /// shared with other work it moves far less with the load than the wall time does.
    cpu: Option<Duration>,
    /// Shares of the measured time: scripts, scheduling, generators, blend + FK, collision.
    phases: Option<[f64; 5]>,
    peak_rss: Option<u64>,
    /// Peak RSS growth over the process before the scene was built, per actor.
    bytes_per_actor: Option<f64>,
}

impl RunResult {
    fn actor_ticks_per_second(&self) -> f64 {
        (self.actors * self.ticks) as f64 / self.wall.as_secs_f64()
    }

    /// CPU time per actor-tick (µs), all threads together.
    fn cpu_per_actor_tick(&self) -> Option<f64> {
        self.cpu
            .map(|c| c.as_secs_f64() * 1e6 / (self.actors * self.ticks) as f64)
    }
}

const PHASE_NAMES: [&str; 5] = [
    "scripts",
    "scheduling",
    "generators",
    "blend_fk",
    "collision",
];

/// Runs the benchmark and prints the table.
pub fn run(args: BenchArgs) -> Result<ExitCode> {
    if args.actors.is_empty() || args.actors.contains(&0) {
        bail!("--actors needs one or more crowd sizes ≥ 1");
    }
    if args.threads.is_empty() || args.threads.iter().any(|&t| t == 0 || t > 256) {
        bail!("--threads needs one or more thread counts from 1 to 256");
    }
    for (name, value) in [("--seconds", args.seconds), ("--warmup", args.warmup)] {
        if !(value.is_finite() && value >= 0.0) {
            bail!("{name} must be a number ≥ 0, got {value}");
        }
    }
    if !(args.seconds > 0.0 && args.rate.is_finite() && args.rate > 0.0) {
        bail!("--seconds and --rate must be > 0");
    }
    let measured = (args.seconds * args.rate).round().max(1.0) as usize;
    let warmup = (args.warmup * args.rate).round() as usize;
    if args.navigation.is_empty() {
        bail!("--navigation needs on, off or both");
    }
    // Navigation on and off run one after the other for each size and thread count, so
    // that a change in the machine's load touches both alike.
    let runs: Vec<(usize, usize, Navigation)> = args
        .actors
        .iter()
        .flat_map(|&a| args.threads.iter().map(move |&t| (a, t)))
        .flat_map(|(a, t)| args.navigation.iter().map(move |&n| (a, t, n)))
        .collect();
    let total: u64 = runs
        .iter()
        .map(|&(a, _, _)| (a * (measured + warmup)) as u64)
        .sum();
    let bar = ProgressBar::new(total).with_style(
        ProgressStyle::with_template("{msg:>24} [{bar:30}] {percent:>3}% eta {eta}")
            .context("progress bar template")?
            .progress_chars("=> "),
    );
    let mut results = Vec::new();
    for &(actors, threads, navigation) in &runs {
        let nav = navigation.name();
        bar.set_message(format!("{actors} actors, {threads} thr, nav {nav}"));
        let result = run_one(&args, (actors, threads, navigation), warmup, measured, &bar)
            .with_context(|| {
                format!("crowd of {actors} actors on {threads} threads, navigation {nav}")
            })?;
        results.push(result);
    }
    bar.finish_and_clear();

    print_table(&args, &results);
    if let Some(path) = &args.json {
        write_json(path, &args, &results)?;
        println!("wrote {}", path.display());
    }
    Ok(ExitCode::SUCCESS)
}

fn run_one(
    args: &BenchArgs,
    (actors, threads, navigation): (usize, usize, Navigation),
    warmup: usize,
    measured: usize,
    bar: &ProgressBar,
) -> Result<RunResult> {
    memory::release_free_heap();
    memory::reset_peak();
    let baseline = memory::current_rss();

    let config = SceneConfig {
        rate: args.rate,
        threads,
        seed: args.seed,
    };
    let mut session = Director::session(
        config,
        troupe_actions::action_kinds(),
        ScriptLimits::default(),
    )?;
    let (director, scene) = session.script_and_scene();
    scene.set_walking(navigation.walking());
    {
        let lua = director.lua();
        let bench = lua.create_table()?;
        bench.set("actors", actors)?;
        lua.globals().set("BENCH", bench)?;
    }
    match &args.scene {
        Some(path) => director.load_file(scene, path)?,
        None => director.load_str(scene, CROWD_SCENE, CROWD_SCENE_NAME)?,
    }

    for _ in 0..warmup {
        session.tick()?;
        bar.inc(actors as u64);
    }
    let profiling = !args.no_phases;
    session.scene_mut().set_profiling(profiling);
    session.scene_mut().take_profile();
    session.set_phase_timing(profiling);
    session.take_phase_times();
    let mut tick_times = Vec::with_capacity(measured);
    let cpu_before = cpu::used();
    let started = Instant::now();
    for _ in 0..measured {
        let t0 = Instant::now();
        session.tick()?;
        tick_times.push(t0.elapsed());
        bar.inc(actors as u64);
    }
    let wall = started.elapsed();
    let cpu = cpu::used()
        .zip(cpu_before)
        .and_then(|(after, before)| after.checked_sub(before));
    let profile = session.scene_mut().take_profile();
    let scripts = session.take_phase_times().script;
    let peak_rss = memory::peak_rss();

    // A benchmark whose behaviors died measures an idle crowd: refuse to report it.
    let failed: Vec<_> = session
        .script()
        .behaviors(session.scene())
        .into_iter()
        .filter_map(|r| r.error.map(|e| format!("{}: {}", r.actor, e)))
        .collect();
    if let Some(first) = failed.first() {
        bail!("{} behaviors failed, first {first}", failed.len());
    }

    tick_times.sort_unstable();
    let total: Duration = tick_times.iter().sum();
    let p99 = tick_times[((tick_times.len() * 99).div_ceil(100)).saturating_sub(1)];
    let phases = profiling.then(|| {
        let (_, generators, blend_fk, collision) = profile.split_wall();
        let total = total.as_secs_f64();
        // Scheduling is everything else: admission and transitions, fork/join, publish
        // and the director's event bookkeeping.
        let scheduling =
            (total - scripts.as_secs_f64()) - (generators + blend_fk + collision).as_secs_f64();
        [
            scripts.as_secs_f64() / total,
            scheduling.max(0.0) / total,
            generators.as_secs_f64() / total,
            blend_fk.as_secs_f64() / total,
            collision.as_secs_f64() / total,
        ]
    });
    Ok(RunResult {
        actors,
        threads,
        navigation,
        ticks: measured,
        wall,
        tick_mean: Duration::from_secs_f64(total.as_secs_f64() / measured as f64),
        tick_p99: p99,
        cpu,
        phases,
        peak_rss,
        bytes_per_actor: peak_rss
            .zip(baseline)
            .map(|(peak, base)| peak.saturating_sub(base) as f64 / actors as f64),
    })
}

fn print_table(args: &BenchArgs, results: &[RunResult]) {
    println!(
        "troupe bench: {}, {} Hz, {} s measured after {} s warm-up, seed {}",
        scene_name(args),
        args.rate,
        args.seconds,
        args.warmup,
        args.seed
    );
    println!("machine: {}", machine_description());
    println!(
        "{:>7} {:>3} {:>3} {:>13} {:>8} {:>10} {:>10} {:>7} {:>8}  {:>7} {:>7} {:>7} {:>7} {:>7}  {:>9} {:>9}",
        "actors",
        "thr",
        "nav",
        "actor-ticks/s",
        "speedup",
        "mean tick",
        "p99 tick",
        "×rt",
        "CPU/at",
        "scripts",
        "sched",
        "gens",
        "blendFK",
        "collis",
        "peak RSS",
        "per actor"
    );
    for r in results {
        let single = results
            .iter()
            .find(|o| o.actors == r.actors && o.threads == 1 && o.navigation == r.navigation)
            .map(|o| o.actor_ticks_per_second());
        let speedup = single
            .map(|s| format!("{:.2}×", r.actor_ticks_per_second() / s))
            .unwrap_or_else(|| "-".into());
        let phases = match r.phases {
            Some(p) => p
                .iter()
                .map(|s| format!("{:>6.1}%", s * 100.0))
                .collect::<Vec<_>>(),
            None => vec![format!("{:>7}", "-"); 5],
        };
        println!(
            "{:>7} {:>3} {:>3} {:>13.0} {:>8} {:>8.1}µs {:>8.1}µs {:>7.1} {:>8}  {} {} {} {} {}  {:>9} {:>9}",
            r.actors,
            r.threads,
            r.navigation.name(),
            r.actor_ticks_per_second(),
            speedup,
            r.tick_mean.as_secs_f64() * 1e6,
            r.tick_p99.as_secs_f64() * 1e6,
            r.actor_ticks_per_second() / (r.actors as f64 * args.rate),
            r.cpu_per_actor_tick()
                .map_or_else(|| "-".into(), |c| format!("{c:.2}µs")),
            phases[0],
            phases[1],
            phases[2],
            phases[3],
            phases[4],
            r.peak_rss.map(format_bytes).unwrap_or_else(|| "-".into()),
            r.bytes_per_actor
                .map(|b| format_bytes(b as u64))
                .unwrap_or_else(|| "-".into()),
        );
    }
    println!(
        "(×rt: how many times faster than real time; speedup: against 1 thread; CPU/at: CPU time per actor-tick, all threads)"
    );
    print_navigation_cost(results);
}

/// For each size and thread count run with navigation on and off: how much navigation
/// lowers the throughput, and its cost per actor-tick: the difference of the two runs'
/// CPU time per actor-tick (or of their wall time per actor-tick, times the threads),
/// and the drop of throughput that cost alone would make (from CPU times: what a machine
/// without other work would see).
fn print_navigation_cost(results: &[RunResult]) {
    for on in results.iter().filter(|r| r.navigation == Navigation::On) {
        let Some(off) = results.iter().find(|o| {
            o.navigation == Navigation::Off && o.actors == on.actors && o.threads == on.threads
        }) else {
            continue;
        };
        let (a, b) = (on.actor_ticks_per_second(), off.actor_ticks_per_second());
        let wall = on.threads as f64 * (1.0 / a - 1.0 / b) * 1e6;
        let cpu = on.cpu_per_actor_tick().zip(off.cpu_per_actor_tick());
        let cost = cpu.map_or(wall, |(c_on, c_off)| c_on - c_off);
        let by_cpu = cpu.map_or_else(String::new, |(c_on, c_off)| {
            format!(" ({:+.1} % by CPU time)", (c_off / c_on - 1.0) * 100.0)
        });
        println!(
            "navigation, {} actors on {} thr: {cost:.2} µs of CPU per actor-tick; actor-ticks/s {:+.1} % against off{by_cpu}",
            on.actors,
            on.threads,
            (a / b - 1.0) * 100.0,
        );
    }
}

fn write_json(path: &PathBuf, args: &BenchArgs, results: &[RunResult]) -> Result<()> {
    let runs: Vec<_> = results
        .iter()
        .map(|r| {
            let phases = r.phases.map(|p| {
                PHASE_NAMES
                    .iter()
                    .zip(p)
                    .map(|(n, s)| (n.to_string(), json!(s)))
                    .collect::<serde_json::Map<_, _>>()
            });
            json!({
                "scene": scene_name(args),
                "actors": r.actors,
                "threads": r.threads,
                "navigation": r.navigation.name(),
                "rate_hz": args.rate,
                "seed": args.seed,
                "ticks": r.ticks,
                "wall_seconds": r.wall.as_secs_f64(),
                "actor_ticks_per_second": r.actor_ticks_per_second(),
                "tick_mean_us": r.tick_mean.as_secs_f64() * 1e6,
                "tick_p99_us": r.tick_p99.as_secs_f64() * 1e6,
                "cpu_per_actor_tick_us": r.cpu_per_actor_tick(),
                "phase_shares": phases,
                "peak_rss_bytes": r.peak_rss,
                "bytes_per_actor": r.bytes_per_actor,
                "machine": machine_description(),
            })
        })
        .collect();
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let text = serde_json::to_string_pretty(&runs)?;
    std::fs::write(path, text + "\n").with_context(|| format!("writing {}", path.display()))
}

fn scene_name(args: &BenchArgs) -> String {
    match &args.scene {
        Some(path) => path.display().to_string(),
        None => format!("standard crowd scene ({CROWD_SCENE_NAME})"),
    }
}

fn format_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= 1024.0 * 1024.0 * 1024.0 {
        format!("{:.2} GiB", b / (1024.0 * 1024.0 * 1024.0))
    } else if b >= 1024.0 * 1024.0 {
        format!("{:.1} MiB", b / (1024.0 * 1024.0))
    } else {
        format!("{:.0} KiB", b / 1024.0)
    }
}

/// "2 cores, AMD EPYC …": the logical CPUs and the CPU model.
fn machine_description() -> String {
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|info| {
            info.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    format!("{cores} logical CPUs, {model}")
}

/// The process's CPU time.
mod cpu {
    use std::time::Duration;

    /// CPU time (user + system, every thread) the process has used so far; `None` where
    /// the system does not say.
    pub fn used() -> Option<Duration> {
        #[cfg(unix)]
        {
            let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
            // SAFETY: getrusage fills the rusage it is pointed at and reads nothing else.
            if unsafe { libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) } != 0 {
                return None;
            }
            // SAFETY: getrusage returned 0, so it wrote the whole struct.
            let usage = unsafe { usage.assume_init() };
            let time = |t: libc::timeval| {
                Duration::from_secs(t.tv_sec.max(0) as u64)
                    + Duration::from_micros(t.tv_usec.max(0) as u64)
            };
            Some(time(usage.ru_utime) + time(usage.ru_stime))
        }
        #[cfg(not(unix))]
        None
    }
}

/// Process memory figures from Linux's /proc; `None` elsewhere.
mod memory {
    /// Resident set size now, in bytes.
    pub fn current_rss() -> Option<u64> {
        status_kib("VmRSS:").map(|k| k * 1024)
    }

    /// The highest resident set size since the last [`reset_peak`], in bytes.
    pub fn peak_rss() -> Option<u64> {
        status_kib("VmHWM:").map(|k| k * 1024)
    }

    /// Resets the peak to the current RSS (Linux ≥ 4.0: writing 5 to clear_refs), so
    /// each run reports its own peak rather than the largest earlier run's.
    pub fn reset_peak() {
        // Without it the peak stays monotonic; the figures then say so by being larger.
        let _ = std::fs::write("/proc/self/clear_refs", "5");
    }

    /// Hands the allocator's free memory back to the system, so the RSS a run starts
    /// from is not inflated by the previous run's freed heap.
    pub fn release_free_heap() {
        #[cfg(all(target_os = "linux", target_env = "gnu"))]
        // SAFETY: malloc_trim only returns free pages; it has no preconditions.
        unsafe {
            libc::malloc_trim(0);
        }
    }

    fn status_kib(field: &str) -> Option<u64> {
        let status = std::fs::read_to_string("/proc/self/status").ok()?;
        let line = status.lines().find(|l| l.starts_with(field))?;
        line[field.len()..]
            .trim()
            .trim_end_matches("kB")
            .trim()
            .parse()
            .ok()
    }
}
