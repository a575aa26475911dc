//! `troupe test`: Lua scenario tests, each in a fresh scene.

use anyhow::{bail, Context, Result};
use clap::Args;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::{Duration, Instant};
use troupe_lua::{LuaSession, LuaSessionExt, ScriptLimits};
use troupe_scene::SceneConfig;

/// Options of `troupe test`.
#[derive(Args)]
pub struct TestArgs {
    /// Test files or folders (default `scripts/tests/`).
    pub paths: Vec<PathBuf>,
    /// Longest a test may run, in simulated seconds (a test's own `timeout` replaces it).
    #[arg(long, default_value_t = 120.0, value_parser = crate::run::seconds)]
    pub timeout: f64,
    /// Worker threads for stepping actors.
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Actors a worker claims at a time (default: sized by the crowd; a second worker
    /// starts only above 16 actors). `--chunk 1` steps even two actors on two threads,
    /// to check that a small scene is bit-identical whatever the thread count.
    #[arg(long, value_parser = crate::run::chunk)]
    pub chunk: Option<usize>,
    /// Run only the tests whose `FILE › NAME` contains PATTERN.
    #[arg(long, value_name = "PATTERN")]
    pub filter: Option<String>,
    /// List the selected tests (one `FILE › NAME` a line) instead of running them.
    #[arg(long)]
    pub list: bool,
    /// Also write the results as JUnit XML to FILE (for CI systems).
    #[arg(long, value_name = "FILE")]
    pub junit: Option<PathBuf>,
    /// Run slice I of N (1-based): every N-th selected test, in file and registration
    /// order, so that N machines together run each test once.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<Shard>,
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

/// One test of a file: where it is and what it is called.
struct TestId {
    file: PathBuf,
    index: usize,
    name: String,
}

impl TestId {
    /// `file › name`, as the report lines and `--list` print it.
    fn label(&self) -> String {
        format!("{} › {}", self.file.display(), self.name)
    }
}

/// Which slice of the tests `--shard I/N` runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shard {
    /// 1-based.
    index: usize,
    count: usize,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Shard, String> {
        let bad = || format!("`{s}`: a shard is I/N with 1 ≤ I ≤ N, e.g. 2/4");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || count == 0 || index > count {
            return Err(bad());
        }
        Ok(Shard { index, count })
    }
}

impl Shard {
    /// Whether the test at `position` (in the sorted order of all selected tests) is
    /// this shard's: every N-th, so that shards stay balanced whatever the files hold.
    fn holds(&self, position: usize) -> bool {
        position % self.count == self.index - 1
    }
}

/// How a file's tests went: a file that does not load counts as one failure.
enum Outcome {
    Passed { simulated: f64 },
    Failed(String),
}

/// Runs the selected tests and prints one line each, then `N passed, N failed`.
pub fn run(args: TestArgs) -> Result<ExitCode> {
    let files = collect(&args.paths)?;
    // Every test of every file, in file order then registration order: the order that
    // --shard slices, the same on every machine.
    let mut selected = Vec::new();
    let mut broken = Vec::new();
    for file in files {
        match session(&file, args.threads, args.chunk) {
            Ok(s) => selected.extend(s.script().test_names().into_iter().enumerate().map(
                |(index, name)| TestId {
                    file: file.clone(),
                    index,
                    name,
                },
            )),
            Err(e) => broken.push((file, format!("{e:#}"))),
        }
    }
    if let Some(pattern) = &args.filter {
        selected.retain(|t| t.label().contains(pattern.as_str()));
        broken.retain(|(f, _)| f.display().to_string().contains(pattern.as_str()));
    }
    if selected.is_empty() && broken.is_empty() {
        bail!(
            "no tests selected{}: a run that tests nothing is refused (check the paths and --filter)",
            args.filter
                .as_ref()
                .map(|p| format!(" (--filter {p:?})"))
                .unwrap_or_default()
        );
    }
    let total = selected.len();
    if let Some(shard) = args.shard {
        selected = selected
            .into_iter()
            .enumerate()
            .filter(|(i, _)| shard.holds(*i))
            .map(|(_, t)| t)
            .collect();
        // A file that does not load belongs to the first shard, so that it fails once.
        if shard.index != 1 {
            broken.clear();
        }
        println!(
            "shard {}/{}: {} of {total} tests",
            shard.index,
            shard.count,
            selected.len()
        );
    }
    if args.list {
        for t in &selected {
            println!("{}", t.label());
        }
        for (file, _) in &broken {
            println!("{} (does not load)", file.display());
        }
        return Ok(ExitCode::SUCCESS);
    }
    let mut results = Vec::new();
    for (file, error) in broken {
        println!("FAIL {}: {error}", file.display());
        let id = TestId {
            file,
            index: 0,
            name: "(loading the file)".into(),
        };
        results.push((id, Outcome::Failed(error), Duration::ZERO));
    }
    for t in selected {
        let started = Instant::now();
        let outcome = match run_one(&t.file, t.index, args.timeout, args.threads, args.chunk) {
            Ok(simulated) => {
                println!("ok   {} ({simulated:.2} s simulated)", t.label());
                Outcome::Passed { simulated }
            }
            Err(msg) => {
                println!("FAIL {}", t.label());
                for line in msg.lines() {
                    println!("       {line}");
                }
                Outcome::Failed(msg)
            }
        };
        results.push((t, outcome, started.elapsed()));
    }
    let failed = results
        .iter()
        .filter(|(_, o, _)| matches!(o, Outcome::Failed(_)))
        .count();
    println!("{} passed, {failed} failed", results.len() - failed);
    if let Some(path) = &args.junit {
        write_junit(path, &results)?;
    }
    Ok(if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

/// Writes the results as JUnit XML: one test suite per file, one test case per test.
fn write_junit(path: &Path, results: &[(TestId, Outcome, Duration)]) -> Result<()> {
    use quick_junit::{NonSuccessKind, Report, TestCase, TestCaseStatus, TestSuite};
    let mut report = Report::new("troupe test");
    let mut suites: Vec<TestSuite> = Vec::new();
    for (id, outcome, wall) in results {
        let suite_name = id.file.display().to_string();
        if suites.last().is_none_or(|s| s.name.as_str() != suite_name) {
            suites.push(TestSuite::new(suite_name.clone()));
        }
        let status = match outcome {
            Outcome::Passed { .. } => TestCaseStatus::success(),
            Outcome::Failed(msg) => {
                let mut status = TestCaseStatus::non_success(NonSuccessKind::Failure);
                status
                    .set_message(msg.lines().next().unwrap_or_default())
                    .set_description(msg.as_str());
                status
            }
        };
        let mut case = TestCase::new(id.name.as_str(), status);
        case.set_classname(suite_name).set_time(*wall);
        if let Outcome::Passed { simulated } = outcome {
            case.add_property(("simulated_seconds", format!("{simulated:.2}").as_str()));
        }
        if let Some(suite) = suites.last_mut() {
            suite.add_test_case(case);
        }
    }
    report.add_test_suites(suites);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    let file =
        std::fs::File::create(path).with_context(|| format!("writing {}", path.display()))?;
    report
        .serialize(std::io::BufWriter::new(file))
        .with_context(|| format!("writing {}", path.display()))
}

/// Runs test `index` of `file` in a fresh scene: it passes when its function returns and
/// nothing else failed meanwhile (a behavior it did not wait for, an event handler); it
/// fails with the first error, or at the timeout.
fn run_one(
    file: &Path,
    index: usize,
    timeout: f64,
    threads: usize,
    chunk: Option<usize>,
) -> Result<f64, String> {
    let mut s = session(file, threads, chunk).map_err(|e| format!("{e:#}"))?;
    // A test's own timeout (`test(name, fn, { timeout })`) replaces the default.
    let timeout = s
        .script_and_scene()
        .0
        .start_test(index)
        .map_err(|e| e.to_string())?
        .unwrap_or(timeout);
    let rate = s.scene().config().rate;
    let max_ticks = (timeout * rate).ceil() as u64;
    for _ in 0..=max_ticks {
        s.tick().map_err(|e| e.to_string())?;
        let reports = s.script().behaviors(s.scene());
        // A failure the test waited for (`handle:wait()`) is the test's to judge.
        if let Some(failure) = reports
            .iter()
            .find(|b| b.status == "failed" && (b.actor == "test" || !b.awaited))
        {
            let error = failure.error.clone().unwrap_or_default();
            return Err(if failure.actor == "test" {
                error
            } else {
                format!("behavior of {} failed: {error}", failure.actor)
            });
        }
        if reports
            .iter()
            .any(|b| b.actor == "test" && b.status == "done")
        {
            return Ok(s.scene().time());
        }
    }
    Err(format!("timed out after {timeout} simulated seconds"))
}
