//! The `troupe` command line.

mod templates;
mod view;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// troupe animates articulated virtual humans: Lua behaviors, live devices, scheduled actions.
#[derive(Parser)]
#[command(name = "troupe", version, about, long_about = None)]
struct Cli {
    /// Log filter (tracing env-filter syntax), e.g. `info` or `troupe=debug`.
    #[arg(long, global = true, default_value = "warn,wgpu_hal::gles::egl=off")]
    log: String,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the body templates with their DOF counts and scopes.
    Templates(templates::TemplatesArgs),
    View(view::ViewArgs),
    Snapshot(view::SnapshotArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let filter = tracing_subscriber::EnvFilter::try_new(&cli.log)
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn"));
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .init();
    let result = match cli.command {
        Command::Templates(args) => templates::run(args),
        Command::View(args) => view::run(args),
        Command::Snapshot(args) => view::snapshot(args),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            eprintln!("troupe: {err:#}");
            ExitCode::FAILURE
        }
    }
}
