//! End-to-end checks of the `troupe` command line.

mod common;

use common::{finishes, succeeds};
use std::path::PathBuf;
use std::process::Command;

fn troupe() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_troupe"));
    c.current_dir(env!("CARGO_MANIFEST_DIR"));
    c
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("troupe-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn version_help_and_templates() {
    let out = troupe().arg("--version").output().unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).starts_with("troupe "));
    let out = troupe().arg("--help").output().unwrap();
    assert!(String::from_utf8_lossy(&out.stdout).contains("templates"));
    let out = troupe().args(["templates", "--dofs"]).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    for needle in [
        "adult",
        "child",
        "107 DOFs",
        "right_hand",
        "r_elbow_flexion",
    ] {
        assert!(text.contains(needle), "missing {needle}");
    }
}

#[test]
fn run_records_byte_identical_postures_with_one_and_two_threads() {
    // Six seconds of the crowd example, recorded.
    let record = |seed: &str, threads: &str| {
        let path = temp(&format!("crowd-{seed}-{threads}.trk"));
        succeeds(
            troupe()
                .args(["run", "scripts/examples/crowd.lua", "--seconds", "6"])
                .args(["--seed", seed, "--threads", threads, "--record"])
                .arg(&path),
        );
        std::fs::read(&path).unwrap()
    };
    let one = record("3", "1");
    assert!(one.len() > 10_000);
    assert!(
        one == record("3", "2"),
        "recordings differ between 1 and 2 threads"
    );
    // A different seed gives a different scene.
    assert!(record("4", "1") != one);
}

#[test]
fn the_recording_and_trace_are_readable() {
    let trk = temp("greeting.trk");
    let json = temp("greeting.json");
    let out = troupe()
        .args(["run", "scripts/examples/greeting.lua", "--record"])
        .arg(&trk)
        .arg("--trace")
        .arg(&json)
        .output()
        .unwrap();
    assert!(out.status.success());
    let set = troupe_formats::trk::read_trk_set(&trk).unwrap();
    assert_eq!(
        set.iter().map(|s| s.name.as_str()).collect::<Vec<_>>(),
        ["ann", "bob"]
    );
    let trace: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let spans = trace["traceEvents"].as_array().unwrap();
    assert!(spans
        .iter()
        .any(|e| e["name"] == "keyframe active" && e["tid"] == 0));
    assert!(spans.iter().any(|e| e["args"]["name"] == "bob"));
}

#[test]
fn a_failing_behavior_makes_run_fail_and_is_reported() {
    let scene = temp("failing.lua");
    std::fs::write(
        &scene,
        "local a = troupe.actor{ name = 'a' }\nlocal b = troupe.actor{ name = 'b', at = {2,0,0} }\n\
         a:behave(function() wait(0.1); error('boom') end)\n\
         b:behave(function() wait(0.5) end)\n",
    )
    .unwrap();
    let out = troupe().arg("run").arg(&scene).output().unwrap();
    assert!(!out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("behavior of a failed"), "{text}");
    assert!(text.contains("failing.lua:3: boom"), "{text}");
}

#[test]
fn a_recording_of_an_unknown_format_is_refused_before_the_scene_runs() {
    // A scene that would print if it ran: the refusal comes first, in a moment.
    let scene = temp("long.lua");
    std::fs::write(&scene, "print('the scene ran')\n").unwrap();
    let out = troupe()
        .args(["run", "--seconds", "3600", "--record", "out.xyz"])
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!out.status.success());
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(
        stderr.contains("--record out.xyz") && stderr.contains(".xyz"),
        "{stderr}"
    );
    assert!(!stdout.contains("the scene ran"), "{stdout}");
}

#[test]
fn bad_scene_files_give_clear_errors() {
    let out = troupe()
        .args(["run", "no/such/scene.lua"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/scene.lua"));
    let scene = temp("syntax.lua");
    std::fs::write(&scene, "troupe.actor{ name = 'a' \n").unwrap();
    let out = troupe().arg("run").arg(&scene).output().unwrap();
    assert!(!out.status.success());
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("syntax.lua:"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Durations, chunks and picture names a user could only mean by mistake are refused
/// before anything runs (`--seconds 1e300` ran for ever; `render out.jpg` wrote PNG).
#[test]
fn impossible_durations_chunks_and_picture_names_are_refused() {
    let scene = "scripts/examples/greeting.lua";
    let refused = |args: &[&str], needle: &str| {
        let out = troupe().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(needle),
            "{args:?}: {err}"
        );
    };
    refused(
        &["run", "--seconds", "1e300", scene],
        "a duration is from 0 to 1e9 s",
    );
    refused(
        &["run", "--seconds=-1", scene],
        "a duration is from 0 to 1e9 s",
    );
    refused(
        &["run", "--max-seconds=-1", scene],
        "a duration is from 0 to 1e9 s",
    );
    refused(
        &["run", "--chunk", "0", scene],
        "a chunk is a whole number of actors, at least 1",
    );
    refused(
        &["test", "--timeout=-1", "scripts/tests/waits.lua"],
        "a duration is from 0",
    );
    refused(
        &["test", "--chunk", "0", "scripts/tests/waits.lua"],
        "at least 1",
    );
    refused(
        &["render", "--at", "1e12", scene, "out.png"],
        "a duration is from 0",
    );
    refused(
        &["render", scene, "out.jpg"],
        "troupe writes PNG pictures: name the file .png",
    );
    refused(&["snapshot", "out.txt"], "troupe writes PNG pictures");
    let out = troupe()
        .args([
            "test",
            "--filter",
            "no such test",
            "scripts/tests/waits.lua",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("(check the paths and --filter)"), "{err}");
}

/// An export into a folder that does not exist yet makes it, as `run --record` does.
#[test]
fn export_makes_its_folder() {
    let dir = temp("export_folder");
    let _ = std::fs::remove_dir_all(&dir);
    let out = dir.join("deeper").join("adult.urdf");
    succeeds(troupe().args(["export", "urdf"]).arg(&out));
    assert!(std::fs::metadata(&out).unwrap().len() > 1000);
}

#[test]
fn scenario_tests_pass_and_report_counts() {
    // One file of the suite: scripts/test.sh runs the whole of it, on 1 and on 2 threads
    // (the plaza alone takes minutes in this build).
    let out = troupe()
        .args(["test", "scripts/tests/waits.lua"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.lines().last().unwrap().ends_with(" passed, 0 failed"));
    let failing = temp("failing_test.lua");
    std::fs::write(&failing, "test('fails', function() run(0.1); expect(false, 'nope') end)\ntest('passes', function() end)\n").unwrap();
    let out = troupe().arg("test").arg(&failing).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!out.status.success());
    assert!(text.contains("expectation failed: nope"), "{text}");
    assert!(text.contains("1 passed, 1 failed"), "{text}");
}

#[test]
fn render_and_frames_draw_example_scenes() {
    let png = temp("tableau.png");
    succeeds(
        troupe()
            .args(["render", "scripts/examples/tableau.lua"])
            .arg(&png)
            .args(["--at", "1.2", "--size", "320x180", "--no-labels"]),
    );
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    let dir = temp("frames");
    succeeds(
        troupe()
            .args([
                "run",
                "scripts/examples/greeting.lua",
                "--seconds",
                "1",
                "--every",
                "50",
                "--size",
                "160x90",
                "--frames",
            ])
            .arg(&dir),
    );
    // Ticks 0, 50 and 100 of one second at 100 Hz.
    assert!(dir.join("frame_000002.png").is_file());
    assert!(!dir.join("frame_000003.png").exists());
    let out = troupe()
        .args([
            "render",
            "scripts/examples/tableau.lua",
            "x.png",
            "--at",
            "-1",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
}

#[test]
fn recordings_play_back_in_view_whatever_their_format() {
    for ext in ["trk", "gltf", "bvh"] {
        let rec = temp(&format!("replay.{ext}"));
        succeeds(
            troupe()
                .args([
                    "run",
                    "scripts/examples/greeting.lua",
                    "--seconds",
                    "0.5",
                    "--record",
                ])
                .arg(&rec),
        );
        // Two actors: a .trk holds both, .gltf and .bvh write one file per actor.
        let file = if ext == "trk" {
            rec.clone()
        } else {
            rec.with_file_name(format!("replay.ann.{ext}"))
        };
        let frames = temp(&format!("replay-frames-{ext}"));
        let out = troupe()
            .arg("view")
            .arg(&file)
            .args(["--size", "96x64", "--every", "25", "--no-msaa", "--frames"])
            .arg(&frames)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{ext}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(frames.join("frame_000001.png").is_file(), "{ext}");
    }
}

#[test]
fn bench_runs_the_crowd_and_writes_one_json_object_per_run() {
    let json = temp("bench.json");
    let out = succeeds(
        troupe()
            .args(["bench", "--actors", "3,6", "--threads", "1,2"])
            .args(["--seconds", "0.5", "--warmup", "0.2", "--json"])
            .arg(&json),
    );
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("actor-ticks/s"), "{table}");
    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let runs = runs.as_array().unwrap();
    assert_eq!(runs.len(), 4);
    let mut seen = Vec::new();
    for run in runs {
        for field in [
            "actor_ticks_per_second",
            "tick_mean_us",
            "tick_p99_us",
            "peak_rss_bytes",
        ] {
            let v = run[field]
                .as_f64()
                .unwrap_or_else(|| panic!("{field} in {run}"));
            assert!(v > 0.0, "{field} = {v}");
        }
        assert_eq!(run["ticks"], 50);
        let shares = run["phase_shares"].as_object().unwrap();
        let total: f64 = shares.values().map(|s| s.as_f64().unwrap()).sum();
        assert!((total - 1.0).abs() < 1e-6, "phase shares sum to {total}");
        seen.push((
            run["actors"].as_u64().unwrap(),
            run["threads"].as_u64().unwrap(),
        ));
    }
    assert_eq!(seen, [(3, 1), (3, 2), (6, 1), (6, 2)]);

    // Bad sizes are refused before anything runs.
    let out = troupe().args(["bench", "--actors", "0"]).output().unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--actors"));
}

#[test]
fn bench_runs_the_crowd_with_navigation_on_and_off_side_by_side() {
    let json = temp("bench_navigation.json");
    let out = succeeds(
        troupe()
            .args(["bench", "--actors", "4", "--threads", "1"])
            .args([
                "--navigation",
                "on,off",
                "--seconds",
                "0.5",
                "--warmup",
                "0.2",
            ])
            .arg("--json")
            .arg(&json),
    );
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("CPU/at"), "{table}");
    assert!(
        table.contains("navigation, 4 actors on 1 thr:") && table.contains("µs of CPU"),
        "{table}"
    );
    let runs: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let runs = runs.as_array().unwrap();
    let navigation: Vec<&str> = runs
        .iter()
        .map(|r| r["navigation"].as_str().unwrap())
        .collect();
    assert_eq!(navigation, ["on", "off"]);
    for run in runs {
        let cpu = run["cpu_per_actor_tick_us"].as_f64().unwrap();
        assert!(cpu > 0.0, "{run}");
    }
    // Anything but on and off is refused, naming the option.
    let out = troupe()
        .args(["bench", "--navigation", "maybe"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--navigation"));
}

#[test]
fn run_records_joint_torques_that_seq_plot_draws() {
    // Fig. 3-8/3-9: an arm held forward by servos; the recorded shoulder torque is the
    // one inverse dynamics predicts for the still posture.
    let scene = temp("torques.lua");
    std::fs::write(
        &scene,
        "local ann = troupe.actor{ name = 'ann' }\n\
         ann:pose{ r_shoulder_flexion = 1.2, r_elbow_flexion = 0.5 }\n\
         ann:servo{ target = { r_shoulder_flexion = 1.2, r_elbow_flexion = 0.5 }, duration = 1 }\n\
         local bob = troupe.actor{ name = 'bob', at = {2, 0, 0} }\n\
         bob:simulate{ duration = 0.5 }\n",
    )
    .unwrap();
    let trk = temp("torques.trk");
    let record = |threads: &str| {
        let out = succeeds(
            troupe()
                .args([
                    "run",
                    "--seconds",
                    "1.5",
                    "--threads",
                    threads,
                    "--chunk",
                    "1",
                ])
                .arg("--record-torques")
                .arg(&trk)
                .arg(&scene),
        );
        let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
        assert!(stdout.contains("joint torques"), "{stdout}");
        std::fs::read(&trk).unwrap()
    };
    let two = record("2");
    assert!(record("1") == two, "torques differ between 1 and 2 threads");
    let set = troupe_formats::trk::read_trk_set(&trk).unwrap();
    assert_eq!(
        set.iter().map(|s| s.name.as_str()).collect::<Vec<_>>(),
        ["ann", "bob"]
    );
    let seq = &set[0];
    assert_eq!(seq.name, "ann");
    assert_eq!(seq.meta.get("quantity").map(String::as_str), Some("torque"));
    let shoulder = seq.track("r_shoulder_flexion").expect("a shoulder track");
    // One key per tick of the action (1 s at 100 Hz).
    assert!(
        (99..=101).contains(&shoulder.keys().len()),
        "{}",
        shoulder.keys().len()
    );
    let s = troupe_body::template::default_skeleton("adult").unwrap();
    let n = s.dof_count();
    let mut q = vec![0.0; n];
    q[s.dof("r_shoulder_flexion").unwrap()] = 1.2;
    q[s.dof("r_elbow_flexion").unwrap()] = 0.5;
    let ext = troupe_body::dynamics::ExternalForces::new(&s);
    let tau =
        troupe_body::dynamics::inverse_dynamics(&s, &q, &vec![0.0; n], &vec![0.0; n], &ext, true)
            .unwrap();
    let predicted = tau[s.dof("r_shoulder_flexion").unwrap()];
    let recorded = shoulder.keys().last().unwrap().value;
    assert!(predicted.abs() > 1.0, "the arm's weight: {predicted} N·m");
    assert!(
        (recorded - predicted).abs() < 0.02 * predicted.abs(),
        "recorded {recorded} N·m, inverse dynamics {predicted} N·m"
    );
    // DOFs the action did not simulate have no track.
    assert!(seq.track("l_knee_flexion").is_none());
    let png = temp("torques.png");
    succeeds(
        troupe()
            .args(["seq", "plot"])
            .arg(&trk)
            .arg(&png)
            .args(["--dofs", "r_shoulder_flexion,r_elbow_flexion"]),
    );
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
    // Torques are written as .trk only.
    let out = troupe()
        .args(["run", "--seconds", "0.1", "--record-torques", "x.bvh"])
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains(".trk"));
}

#[test]
fn a_zero_tick_run_records_the_starting_postures() {
    let trk = temp("zero.trk");
    let out = succeeds(
        troupe()
            .args([
                "run",
                "scripts/examples/greeting.lua",
                "--ticks",
                "0",
                "--record",
            ])
            .arg(&trk),
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("recorded 1 ticks of postures"), "{text}");
    let set = troupe_formats::trk::read_trk_set(&trk).unwrap();
    assert_eq!(set.len(), 2, "ann and bob");
}

/// Ctrl-C stops a run between two ticks and still writes its recording (it threw the
/// whole recording away: a performer's run ends with Ctrl-C).
#[cfg(unix)]
#[test]
fn ctrl_c_stops_a_run_and_keeps_its_recording() {
    let scene = temp("ctrl_c.lua");
    std::fs::write(
        &scene,
        "local ann = troupe.actor{ name = 'ann' }\nann:walk{ velocity = 1.0 }\n\
         ann:behave(function() wait(0.3); print('ticking') end)\n",
    )
    .unwrap();
    let record = temp("ctrl_c.trk");
    let _ = std::fs::remove_file(&record);
    let mut child = troupe()
        .args(["run", "--seconds", "1000", "--realtime", "--record"])
        .arg(&record)
        .arg(&scene)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupted once it ticks (the behavior's print), however slow the machine.
    use std::io::BufRead;
    let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
    let mut log = String::new();
    for line in stderr.lines() {
        let line = line.unwrap();
        log.push_str(&line);
        if line.contains("ticking") {
            break;
        }
    }
    assert!(log.contains("ticking"), "{log}");
    // SAFETY: sending a signal to our own child process.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let out = child.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(130), "{stdout}\n{log}");
    assert!(stdout.contains("interrupted (Ctrl-C) at "), "{stdout}");
    let info = succeeds(troupe().args(["seq", "info"]).arg(&record));
    let info = String::from_utf8_lossy(&info.stdout);
    assert!(info.contains("ann"), "{info}");
    let ticks: u64 = stdout
        .split("recorded ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no recorded ticks in {stdout}"));
    assert!(
        ticks > 10 && ticks < 100_000,
        "{ticks} ticks recorded:\n{stdout}"
    );
}

#[test]
fn warn_logs_a_warning_with_the_actors_name() {
    let scene = temp("warn.lua");
    std::fs::write(
        &scene,
        "local ann = troupe.actor{ name = 'ann' }\n\
         warn('@on')\n\
         ann:behave(function() warn('careful: ', 3, ' cups') end)\n",
    )
    .unwrap();
    let out = succeeds(troupe().args(["run", "--seconds", "0.1"]).arg(&scene));
    let log = String::from_utf8_lossy(&out.stdout) + String::from_utf8_lossy(&out.stderr);
    assert!(
        log.contains("WARN") && log.contains("careful: 3 cups") && log.contains("actor=ann"),
        "{log}"
    );
    assert!(!log.contains("@on"), "{log}");
}

/// A time past what a scene or recording holds is refused at once: `render --at 1e9`
/// simulated for days, `view --seconds 1e9` wrote pictures until the disk was full.
#[test]
fn times_past_a_scene_or_a_recording_are_refused_at_once() {
    let refused = |args: &[&str], needle: &str| {
        let child = troupe()
            .args(args)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let out = finishes(child, 60, &format!("{args:?}"));
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            !out.status.success() && err.contains(needle),
            "{args:?}: {err}"
        );
    };
    let scene = "scripts/examples/greeting.lua";
    refused(
        &["render", scene, "never.png", "--at", "1e9"],
        "--at 1000000000 s is past --max-seconds (600 s)",
    );
    refused(
        &[
            "render",
            scene,
            "never.png",
            "--at",
            "20",
            "--max-seconds",
            "10",
        ],
        "past --max-seconds (10 s)",
    );
    let trk = temp("short.trk");
    succeeds(
        troupe()
            .args(["run", scene, "--seconds", "0.5", "--record"])
            .arg(&trk),
    );
    let frames = temp("never-frames");
    let (trk, frames) = (trk.display().to_string(), frames.display().to_string());
    refused(
        &["view", &trk, "--frames", &frames, "--seconds", "1e9"],
        "plays for 0.50 s",
    );
    refused(
        &["view", &trk, "--frames", &frames, "--seconds", "inf"],
        "plays for 0.50 s",
    );
}
