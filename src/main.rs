//! The `troupe` command line.

mod export;
mod run;
mod scenario;
mod templates;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// troupe animates articulated virtual humans: Lua behaviors, live devices, scheduled actions.
#[derive(Parser)]
#[command(name = "troupe", version, about, long_about = None)]
struct Cli {
    /// Log filter (tracing env-filter syntax), e.g. `info` or `troupe=debug`.
    #[arg(long, global = true, default_value = "warn,lua=info")]
    log: String,
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// List the body templates with their DOF counts and scopes.
    Templates(templates::TemplatesArgs),
    /// Run a Lua scene headless (record postures, write the action timeline).
    Run(run::RunArgs),
    /// Run Lua scenario tests (default scripts/tests/).
    Test(scenario::TestArgs),
    /// Export a body template to another format (URDF).
    Export(export::ExportArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let filter = tracing_subscriber::EnvFilter::try_new(&cli.log)
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
        Command::Test(args) => scenario::run(args),
        Command::Export(args) => export::run(args),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            eprintln!("troupe: {err:#}");
            ExitCode::FAILURE
        }
    }
}
