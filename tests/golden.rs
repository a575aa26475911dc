//! The golden test: every example scene, run for a fixed time with a fixed seed, records
//! postures whose SHA-256 equals the value committed in `tests/golden/examples.sha256`.
//!
//! It pins behaviour across refactors: a change that moves code must leave every value as
//! it is. A change that means to alter a recording runs
//! `TROUPE_BLESS=1 cargo test --test golden`, which rewrites the file, and says in its
//! commit message which examples changed and why.
//!
//! Each example also runs without a failed action or behavior, and the scenes run on two
//! threads with one actor per chunk record the same bytes as on one thread.
//!
//! `TROUPE_GOLDEN_BIN` runs another `troupe` binary instead of the one built for the test:
//! scripts/test.sh points it at a release build, which must record the same postures
//! (docs/navigation.md, "Determinism").

use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Simulated seconds of the recordings pinned (capture and the crowd never end by
/// themselves; the café's story takes about 30 s, see
/// [`every_example_with_a_story_runs_to_its_end`]).
const SECONDS: &str = "12";
/// Examples whose story never ends by itself: the crowd walks on for good, and a capture
/// follows its performer's recording or device for as long as it plays.
const OPEN_ENDED: [&str; 4] = [
    "crowd.lua",
    "performer_handover.lua",
    "performer_vrpn.lua",
    "vmc_handover.lua",
];
/// Most simulated seconds an example's story may take to end.
const STORY_SECONDS: &str = "120";
/// The seed every example runs with.
const SEED: &str = "7";
/// Where the committed values live, relative to the repository.
const VALUES: &str = "tests/golden/examples.sha256";

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The binary that records: `TROUPE_GOLDEN_BIN` if set, else the one built for the test.
fn troupe() -> PathBuf {
    std::env::var_os("TROUPE_GOLDEN_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_troupe")))
}

fn examples() -> Vec<PathBuf> {
    let mut found: Vec<PathBuf> = std::fs::read_dir(repo().join("scripts/examples"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().and_then(|e| e.to_str()) == Some("lua"))
        .collect();
    found.sort();
    found
}

/// Runs one example and returns the SHA-256 of its `.trk` recording, checking that no
/// action or behavior failed.
fn record(example: &Path, threads: &[&str]) -> String {
    let name = example.file_stem().unwrap().to_string_lossy();
    let dir = std::env::temp_dir().join(format!("troupe-golden-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let trk = dir.join(format!("{name}-{}.trk", threads.join("")));
    let mut args: Vec<&OsStr> = ["run", "--seconds", SECONDS, "--seed", SEED]
        .map(OsStr::new)
        .to_vec();
    args.extend(threads.iter().map(OsStr::new));
    args.extend([OsStr::new("--record"), trk.as_os_str()]);
    run_example(example, &args);
    let bytes = std::fs::read(&trk).unwrap();
    std::fs::remove_file(&trk).ok();
    format!("{:x}", Sha256::digest(&bytes))
}

/// Runs `troupe` with `args` and then `example`, checking that it succeeds with no action
/// or behavior failing; returns what it printed.
fn run_example(example: &Path, args: &[&OsStr]) -> String {
    let out = Command::new(troupe())
        .current_dir(repo())
        .args(args)
        .arg(example)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{}: {}",
        example.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    nothing_failed(&example.display().to_string(), &stdout);
    stdout
}

/// Asserts that the summary `troupe run` printed for example `name` counts no failed
/// action and names no failed behavior.
fn nothing_failed(name: &str, stdout: &str) {
    for line in stdout.lines().filter(|l| l.contains("actions:")) {
        assert!(line.trim_end().ends_with(" 0 failed"), "{name}: {line}");
    }
    assert!(!stdout.contains("behavior of"), "{name}: {stdout}");
}

fn committed() -> BTreeMap<String, String> {
    let text = std::fs::read_to_string(repo().join(VALUES)).unwrap_or_default();
    text.lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
        .map(|l| {
            let (hash, name) = l.split_once("  ").expect("`HASH  NAME` lines");
            (name.trim().to_string(), hash.trim().to_string())
        })
        .collect()
}

#[test]
fn every_example_records_its_committed_postures() {
    let examples = examples();
    assert!(examples.len() >= 10, "found {} examples", examples.len());
    let mut measured = BTreeMap::new();
    for example in &examples {
        let name = example.file_name().unwrap().to_string_lossy().into_owned();
        let one = record(example, &["--threads", "1"]);
        let two = record(example, &["--threads", "2", "--chunk", "1"]);
        assert_eq!(
            one, two,
            "{name}: 1 and 2 threads record different postures"
        );
        measured.insert(name, one);
    }
    std::fs::remove_dir_all(
        std::env::temp_dir().join(format!("troupe-golden-{}", std::process::id())),
    )
    .ok();
    if std::env::var_os("TROUPE_BLESS").is_some() {
        let mut text = format!(
            "# SHA-256 of each example's .trk recording: troupe run --seconds {SECONDS} --seed {SEED} --record\n"
        );
        for (name, hash) in &measured {
            text.push_str(&format!("{hash}  {name}\n"));
        }
        std::fs::write(repo().join(VALUES), text).unwrap();
        return;
    }
    let expected = committed();
    let mut wrong = Vec::new();
    for (name, hash) in &measured {
        match expected.get(name) {
            Some(want) if want == hash => {}
            Some(want) => wrong.push(format!("{name}: recorded {hash}, committed {want}")),
            None => wrong.push(format!("{name}: no committed value (recorded {hash})")),
        }
    }
    for name in expected.keys().filter(|n| !measured.contains_key(*n)) {
        wrong.push(format!("{name}: committed, but the example is gone"));
    }
    assert!(
        wrong.is_empty(),
        "recordings differ from {VALUES} (TROUPE_BLESS=1 rewrites it; say why in the commit):\n{}",
        wrong.join("\n")
    );
}

/// Every example that is not [`OPEN_ENDED`] runs until its scene is idle, within
/// [`STORY_SECONDS`], with no action or behavior failing: the 12 s recordings did not
/// show that the café's waiter, held 13 cm short of its path's end by the guest it
/// carried the cup to, waited for good while the guest's receive timed out.
#[test]
fn every_example_with_a_story_runs_to_its_end() {
    for example in examples() {
        let name = example.file_name().unwrap().to_string_lossy().into_owned();
        if OPEN_ENDED.contains(&name.as_str()) {
            continue;
        }
        let args = [
            "run",
            "--until-idle",
            "--max-seconds",
            STORY_SECONDS,
            "--seed",
            SEED,
        ]
        .map(OsStr::new);
        let stdout = run_example(&example, &args);
        assert!(
            !stdout.contains("before the scene was idle"),
            "{name} did not end within {STORY_SECONDS} s: {stdout}"
        );
    }
}
