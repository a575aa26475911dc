//! `troupe test` as CI uses it: failures it must not miss, selection, sharding, JUnit,
//! and `troupe run`'s warning about tests.

use std::process::{Command, Output};

fn troupe(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_troupe"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .output()
        .unwrap()
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

const FIXTURES: &str = "tests/fixtures/runner";

#[test]
fn a_behavior_error_fails_the_test_with_its_place() {
    let out = troupe(&["test", "tests/fixtures/runner/behavior_error.lua"]);
    assert!(!out.status.success(), "{}", stdout(&out));
    let text = stdout(&out);
    assert!(text.contains("0 passed, 1 failed"), "{text}");
    assert!(
        text.contains("behavior of a failed: tests/fixtures/runner/behavior_error.lua:4: boom"),
        "{text}"
    );
}

#[test]
fn a_handler_error_fails_the_test() {
    let out = troupe(&["test", "tests/fixtures/runner/handler_error.lua"]);
    assert!(!out.status.success());
    let text = stdout(&out);
    assert!(text.contains("in an event handler"), "{text}");
    assert!(text.contains("handler_error.lua:4: handler boom"), "{text}");
}

#[test]
fn filter_and_list_select_tests_and_an_empty_selection_is_an_error() {
    let many = format!("{FIXTURES}/many.lua");
    let out = troupe(&["test", &many, "--list"]);
    assert!(out.status.success());
    assert_eq!(stdout(&out).lines().count(), 5, "{}", stdout(&out));
    let out = troupe(&["test", &many, "--filter", "case 3"]);
    assert!(out.status.success());
    let text = stdout(&out);
    assert!(
        text.contains("case 3") && !text.contains("case 2"),
        "{text}"
    );
    assert!(text.contains("1 passed, 0 failed"), "{text}");
    let out = troupe(&["test", &many, "--filter", "no such test"]);
    assert!(!out.status.success());
    assert!(
        stderr(&out).contains("no tests selected"),
        "{}",
        stderr(&out)
    );
}

#[test]
fn shards_split_the_tests_once_and_deterministically() {
    let many = format!("{FIXTURES}/many.lua");
    let mut seen = Vec::new();
    for shard in ["1/2", "2/2"] {
        let out = troupe(&["test", &many, "--list", "--shard", shard]);
        assert!(out.status.success());
        let names: Vec<String> = stdout(&out)
            .lines()
            .filter(|l| l.contains('›'))
            .map(String::from)
            .collect();
        let again = troupe(&["test", &many, "--list", "--shard", shard]);
        assert_eq!(stdout(&out), stdout(&again), "the same slice every time");
        seen.extend(names);
    }
    seen.sort();
    assert_eq!(seen.len(), 5, "{seen:?}");
    seen.dedup();
    assert_eq!(seen.len(), 5, "each test in one shard only");
    for bad in ["0/2", "3/2", "x"] {
        let out = troupe(&["test", &many, "--shard", bad]);
        assert!(!out.status.success(), "--shard {bad} refused");
    }
}

#[test]
fn junit_xml_names_every_test_and_failure() {
    let dir = std::env::temp_dir().join(format!("troupe-junit-{}", std::process::id()));
    let path = dir.join("report.xml");
    let out = troupe(&[
        "test",
        &format!("{FIXTURES}/many.lua"),
        &format!("{FIXTURES}/behavior_error.lua"),
        "--junit",
        path.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let xml = std::fs::read_to_string(&path).unwrap();
    let doc = roxmltree::Document::parse(&xml).expect("well-formed XML");
    let cases: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("testcase"))
        .collect();
    assert_eq!(cases.len(), 6, "{xml}");
    let failures: Vec<_> = doc
        .descendants()
        .filter(|n| n.has_tag_name("failure"))
        .collect();
    assert_eq!(failures.len(), 1, "{xml}");
    assert!(failures[0].attribute("message").unwrap().contains("boom"));
    let suites = doc
        .descendants()
        .filter(|n| n.has_tag_name("testsuite"))
        .count();
    assert_eq!(suites, 2, "one suite per file");
    read_by_junitparser(&path);
    std::fs::remove_dir_all(&dir).ok();
}

/// The report as an independent JUnit reader (junitparser, from PyPI) sees it: two suites,
/// six cases, one failure. Skipped with a note when scripts/setup.sh has not installed it.
fn read_by_junitparser(path: &std::path::Path) {
    let python = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(".tools/python/bin/python");
    let available = Command::new(&python)
        .args(["-c", "import junitparser"])
        .output()
        .is_ok_and(|o| o.status.success());
    if !available {
        eprintln!("junitparser is not installed (scripts/setup.sh installs it): skipped");
        return;
    }
    let script = "import sys\n\
        from junitparser import JUnitXml, Failure\n\
        xml = JUnitXml.fromfile(sys.argv[1])\n\
        suites = list(xml)\n\
        cases = [c for s in suites for c in s]\n\
        failed = [c for c in cases if any(isinstance(r, Failure) for r in c.result)]\n\
        print(len(suites), len(cases), len(failed), failed[0].name)\n";
    let out = Command::new(&python)
        .arg("-c")
        .arg(script)
        .arg(path)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(text.trim(), "2 6 1 a failing behavior fails its test");
}

#[test]
fn run_warns_when_a_scene_defines_tests() {
    let out = troupe(&["run", &format!("{FIXTURES}/many.lua"), "--seconds", "0.1"]);
    assert!(out.status.success());
    let err = stderr(&out);
    assert!(err.contains("defines 5 test(s)"), "{err}");
    assert!(err.contains("troupe test"), "{err}");
}

#[test]
fn a_tests_own_timeout_replaces_the_default() {
    // With a default of 2.5 s, the test that has 5 s of its own passes where the default
    // would stop it, and the one that has 2 s fails at 2 s.
    let out = troupe(&[
        "test",
        "tests/fixtures/runner/timeouts.lua",
        "--timeout",
        "2.5",
    ]);
    let text = stdout(&out);
    assert!(!out.status.success(), "{text}");
    assert!(
        text.contains(
            "ok   tests/fixtures/runner/timeouts.lua › needs 3 simulated seconds and has 5"
        ),
        "{text}"
    );
    assert!(
        text.contains(
            "FAIL tests/fixtures/runner/timeouts.lua › needs 3 simulated seconds and has 2"
        ),
        "{text}"
    );
    assert!(
        text.contains("timed out after 2 simulated seconds"),
        "{text}"
    );
    assert!(
        text.contains("ok   tests/fixtures/runner/timeouts.lua › a bad timeout is refused"),
        "{text}"
    );
    assert!(text.contains("2 passed, 1 failed"), "{text}");
}
