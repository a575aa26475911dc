//! End to end: `troupe run scripts/examples/performer_handover.lua` (a replayed glove, no
//! hardware) hands the ball to the performer and back, with 1 and 2 threads alike.

use std::process::Command;

fn run(threads: &str) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_troupe"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args([
            "run",
            "scripts/examples/performer_handover.lua",
            "--seconds",
            "12",
            "--threads",
            threads,
            // One actor per chunk: the two actors are stepped on both threads.
            "--chunk",
            "1",
        ])
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "troupe run failed:\n{text}");
    text
}

/// The lines the scene prints (hand states and outcomes), in order.
fn story(text: &str) -> Vec<String> {
    text.lines()
        .filter_map(|l| l.split_once("lua: ").map(|(_, m)| m.to_string()))
        .collect()
}

#[test]
fn the_example_hands_the_ball_to_the_performer_and_back() {
    let one = run("1");
    let lines = story(&one);
    let want = [
        "pat's hand GRASPING_IN_PROGRESS (ball)",
        "pat's hand SECURE_GRASP (ball)",
        "give: completed, the ball is held by pat",
        "receive: completed, the ball is held by ann",
        "pat's hand FREE_HAND",
    ];
    let mut at = 0;
    for l in &lines {
        if at < want.len() && l.contains(want[at]) {
            at += 1;
        }
    }
    assert_eq!(at, want.len(), "the story, in order, in:\n{one}");
    assert_eq!(lines, story(&run("2")), "the same with 2 threads");
}
