//! The worked examples of the docs work as written: docs/first-behavior.md's Lua blocks,
//! saved as the tutorial says, run, render, print what it says and pass their test;
//! docs/navigation.md's room prints what the page says it prints.

use std::path::Path;
use std::process::{Command, Output};

fn troupe(dir: &Path, args: &[&str]) -> Output {
    let out = Command::new(env!("CARGO_BIN_EXE_troupe"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "troupe {args:?}: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The text of `docs/PAGE`.
fn page(page: &str) -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("docs")
            .join(page),
    )
    .unwrap()
}

/// The code blocks of `doc` that open with FENCE (```lua, or ``` for plain text), in order.
fn blocks(doc: &str, fence: &str) -> Vec<String> {
    doc.split(&format!("{fence}\n"))
        .skip(1)
        .map(|b| b.split("```").next().unwrap().to_string())
        .collect()
}

/// The ```lua blocks of the tutorial, in order.
fn lua_blocks() -> Vec<String> {
    blocks(&page("first-behavior.md"), "```lua")
}

#[test]
fn the_tutorial_runs_as_written() {
    let blocks = lua_blocks();
    assert_eq!(
        blocks.len(),
        5,
        "step 1, step 2, step 4, step 5 and the test"
    );
    // Run from an empty folder outside the repository: the standard library is built in.
    let dir = std::env::temp_dir().join(format!("troupe-tutorial-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("greet.lua"), &blocks[0]).unwrap();
    let out = troupe(&dir, &["run", "greet.lua"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("ran greet.lua for 101 ticks"), "{text}");

    std::fs::write(dir.join("greet.lua"), format!("{}{}", blocks[1], blocks[2])).unwrap();
    let out = troupe(&dir, &["run", "greet.lua"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("ann          actions: 2 completed, 1 cancelled, 0 failed"),
        "{text}"
    );
    assert!(
        text.contains("bob          actions: 1 completed"),
        "bob nodded: {text}"
    );
    troupe(
        &dir,
        &[
            "render",
            "greet.lua",
            "ann.png",
            "--at",
            "4",
            "--camera",
            "fit",
            "--size",
            "320x180",
        ],
    );
    assert!(dir.join("ann.png").is_file());

    // Step 5 prints, word for word, what the tutorial says it prints.
    std::fs::write(dir.join("door.lua"), &blocks[3]).unwrap();
    let out = troupe(&dir, &["run", "door.lua"]);
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let tutorial = page("first-behavior.md");
    let printed = tutorial
        .split("troupe run door.lua")
        .nth(1)
        .and_then(|after| after.split("prints").nth(1))
        .expect("the tutorial says what door.lua prints");
    for line in self::blocks(printed, "```")[0].lines() {
        assert!(text.contains(line), "no `{line}` in:\n{text}");
    }
    assert!(
        text.contains("ann          actions: 1 completed, 0 cancelled, 1 failed"),
        "{text}"
    );

    std::fs::write(dir.join("greet_test.lua"), &blocks[4]).unwrap();
    let out = troupe(&dir, &["test", "greet_test.lua"]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("1 passed, 0 failed"));
    troupe(&dir, &["lua-defs", "types/troupe.d.lua"]);
    assert!(dir.join("types/troupe.d.lua").is_file());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_navigation_guides_room_prints_what_the_guide_says() {
    let doc = page("navigation.md");
    let scene = &blocks(&doc, "```lua")[0];
    // The plain block after "it prints": the lines the run must print.
    let printed = doc
        .split("it prints")
        .nth(1)
        .expect("the guide says what it prints");
    let expected = &blocks(printed, "```")[0];
    let dir = std::env::temp_dir().join(format!("troupe-nav-guide-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("room.lua"), scene).unwrap();
    for threads in ["1", "2"] {
        let out = troupe(
            &dir,
            &["run", "room.lua", "--seconds", "25", "--threads", threads],
        );
        let text = format!(
            "{}{}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        );
        for line in expected.lines() {
            assert!(
                text.contains(line),
                "{threads} thread(s): no `{line}` in:\n{text}"
            );
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}
