//! The `troupe` command line.

mod bench;
mod devices;
mod export;
mod interrupt;
mod lua_defs;
#[cfg(feature = "zenoh")]
mod net;
#[cfg(not(feature = "zenoh"))]
#[path = "without_zenoh.rs"]
mod net;
// Its test runs in the default build too (building without the feature is costly).
mod observers;
#[cfg(feature = "zenoh")]
mod relay;
mod run;
mod scenario;
mod seq;
mod templates;
mod view;
mod watch;
#[cfg(all(test, feature = "zenoh"))]
#[allow(dead_code)]
mod without_zenoh;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// troupe animates articulated virtual humans: Lua behaviors, live devices, scheduled actions.
#[derive(Parser)]
#[command(name = "troupe", version, about, long_about = None)]
struct Cli {
    /// Log filter (tracing env-filter syntax), e.g. `info` or `troupe=debug`.
    /// Default: warnings, and what scripts print; `troupe test` leaves out the log lines
    /// of behaviors that fail, since each test's report says what failed.
    #[arg(long, global = true)]
    log: Option<String>,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
// Parsed once per process: the size of the largest variant (`run`'s options) costs nothing.
#[allow(clippy::large_enum_variant)]
enum Command {
    /// List the body templates with their DOF counts and scopes.
    Templates(templates::TemplatesArgs),
    /// Run a Lua scene: headless by default (record, trace, PNG frames), or --view in a window.
    Run(run::RunArgs),
    /// Render a Lua scene at a given time to one PNG (headless).
    Render(run::RenderArgs),
    /// Run Lua scenario tests (default scripts/tests/).
    Test(scenario::TestArgs),
    /// Inspect, convert and edit motion sequences (.trk, BVH, glTF out); plot curves.
    Seq(seq::SeqArgs),
    /// Play a recording (.trk, .bvh, .gltf) on actors, in a window or headless to PNG frames.
    View(view::ViewArgs),
    /// Render actors in given poses to one PNG.
    Snapshot(view::SnapshotArgs),
    /// Measure the runtime: the standard crowd scene at several sizes and thread counts.
    Bench(bench::BenchArgs),
    /// Export a body template to another format (URDF).
    Export(export::ExportArgs),
    /// List serial ports and HID devices; probe a device; make a glove calibration.
    Devices(devices::DevicesArgs),
    /// Emulate a Flock of Birds or a CyberGlove on a pseudo-terminal (prints its path), or a VMC sender.
    Emulate(devices::EmulateArgs),
    /// Serve a device on Zenoh for a performer on another machine (needs the zenoh feature).
    #[cfg(feature = "zenoh")]
    Relay(relay::RelayArgs),
    /// Serve a device on Zenoh for a performer on another machine (needs the zenoh feature).
    #[cfg(not(feature = "zenoh"))]
    Relay(net::RelayArgs),
    /// Write the EmmyLua / LuaLS definition file of the Lua API (for editors and checkers).
    LuaDefs(lua_defs::LuaDefsArgs),
}

fn main() -> ExitCode {
    // Piping output into `head` should end the program quietly, as other tools do.
    #[cfg(unix)]
    // SAFETY: restoring the default SIGPIPE action before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let default_log = match cli.command {
        Command::Test(_) => "warn,lua=info,troupe_lua=off,wgpu_hal::gles::egl=off",
        _ => "warn,lua=info,wgpu_hal::gles::egl=off",
    };
    let filter = tracing_subscriber::EnvFilter::try_new(cli.log.as_deref().unwrap_or(default_log))
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn"));
    use std::io::IsTerminal;
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(std::io::stderr().is_terminal())
        .without_time()
        .init();
    let result = match cli.command {
        Command::Templates(args) => templates::run(args),
        Command::Run(args) => run::run(args),
        Command::Render(args) => run::render(args),
        Command::Test(args) => scenario::run(args),
        Command::Seq(args) => seq::run(args),
        Command::View(args) => view::run(args),
        Command::Snapshot(args) => view::snapshot(args),
        Command::Export(args) => export::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Devices(args) => devices::run(args),
        Command::Emulate(args) => devices::emulate(args),
        #[cfg(feature = "zenoh")]
        Command::Relay(args) => relay::run(args),
        #[cfg(not(feature = "zenoh"))]
        Command::Relay(args) => net::relay(args),
        Command::LuaDefs(args) => lua_defs::run(args),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            eprintln!("troupe: {err:#}");
            ExitCode::FAILURE
        }
    }
}
