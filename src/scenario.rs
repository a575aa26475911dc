//! `troupe test`: Lua scenario tests, each in a fresh scene.

use anyhow::{Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use troupe_lua::{LuaSession, LuaSessionExt, ScriptLimits};
use troupe_scene::SceneConfig;

/// Options of `troupe test`.
#[derive(Args)]
pub struct TestArgs {
    /// Test files or folders (default `scripts/tests/`).
    pub paths: Vec<PathBuf>,
    /// Longest a test may run, in simulated seconds.
    #[arg(long, default_value_t = 120.0)]
    pub timeout: f64,
    /// Worker threads for stepping actors.
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Actors a worker claims at a time (default: sized by the crowd; a second worker
    /// starts only above 16 actors). `--chunk 1` steps even two actors on two threads,
    /// to check that a small scene is bit-identical whatever the thread count.
    #[arg(long)]
    pub chunk: Option<usize>,
}

fn collect(paths: &[PathBuf]) -> Result<Vec<PathBuf>> {
    let defaults = [PathBuf::from("scripts/tests")];
    let paths = if paths.is_empty() {
        &defaults[..]
    } else {
        paths
    };
    let mut files = Vec::new();
    for p in paths {
        if p.is_dir() {
            let mut found: Vec<PathBuf> = std::fs::read_dir(p)
                .with_context(|| format!("reading {}", p.display()))?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|f| f.extension().is_some_and(|x| x == "lua"))
                .collect();
            found.sort();
            files.extend(found);
        } else if p.is_file() {
            files.push(p.clone());
        } else {
            anyhow::bail!("{}: no such file or folder", p.display());
        }
    }
    Ok(files)
}

fn session(file: &Path, threads: usize, chunk: Option<usize>) -> Result<LuaSession> {
    let config = SceneConfig {
        threads,
        ..SceneConfig::default()
    };
    // Performers (troupe.performer, capture) are available to scenario tests too.
    let (mut session, _devices) = crate::devices::session(config, ScriptLimits::default(), None)?;
    session.scene_mut().set_chunk_size(chunk);
    session.load_file(file)?;
    Ok(session)
}

/// Runs every test and prints one line each, then `N passed, N failed`.
pub fn run(args: TestArgs) -> Result<ExitCode> {
    let (mut passed, mut failed) = (0, 0);
    for file in collect(&args.paths)? {
        let names = match session(&file, args.threads, args.chunk) {
            Ok(s) => s.script().test_names(),
            Err(e) => {
                println!("FAIL {}: {e:#}", file.display());
                failed += 1;
                continue;
            }
        };
        for (index, name) in names.iter().enumerate() {
            match run_one(&file, index, args.timeout, args.threads, args.chunk) {
                Ok(seconds) => {
                    passed += 1;
                    println!(
                        "ok   {} › {name} ({seconds:.2} s simulated)",
                        file.display()
                    );
                }
                Err(msg) => {
                    failed += 1;
                    println!("FAIL {} › {name}", file.display());
                    for line in msg.lines() {
                        println!("       {line}");
                    }
                }
            }
        }
    }
    println!("{passed} passed, {failed} failed");
    Ok(if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn run_one(
    file: &Path,
    index: usize,
    timeout: f64,
    threads: usize,
    chunk: Option<usize>,
) -> Result<f64, String> {
    let mut s = session(file, threads, chunk).map_err(|e| format!("{e:#}"))?;
    s.script_and_scene()
        .0
        .start_test(index)
        .map_err(|e| e.to_string())?;
    let rate = s.scene().config().rate;
    let max_ticks = (timeout * rate).ceil() as u64;
    for _ in 0..=max_ticks {
        s.tick().map_err(|e| e.to_string())?;
        let test = s
            .script()
            .behaviors(s.scene())
            .into_iter()
            .find(|b| b.actor == "test");
        match test {
            Some(b) if b.status == "failed" => return Err(b.error.unwrap_or_default()),
            Some(b) if b.status == "done" => return Ok(s.scene().time()),
            _ => {}
        }
    }
    Err(format!("timed out after {timeout} simulated seconds"))
}
