//! Property-based fuzzing of the BVH and `.trk` readers: garbage, truncations, token
//! mutations and absurd counts must give `Error::Parse` with a sensible line number (or a
//! valid result) — never a panic, never a huge allocation from a declared count.
//!
//! Runs 512 cases per property by default; set `PROPTEST_CASES` for longer sessions.

use proptest::prelude::*;
use troupe_formats::bvh::parse_bvh;
use troupe_formats::trk::{parse_trk, parse_trk_file};
use troupe_formats::Error;

fn shared(name: &str) -> String {
    let path = format!(
        "{}/../../../shared/data/bvh/{name}",
        env!("CARGO_MANIFEST_DIR")
    );
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// A real file cut down to its hierarchy and a few frames (keeps each case fast).
fn seeds() -> Vec<String> {
    let mut out = Vec::new();
    for name in [
        "pybvhrepo_rotation_first_root.bvh",
        "pybvhrepo_bvh_example.bvh",
        "pybvhrepo_cmu_12_01_walk.bvh",
    ] {
        let text = shared(name);
        let lines: Vec<&str> = text.split_inclusive('\n').collect();
        let motion = lines
            .iter()
            .position(|l| l.trim_start().starts_with("MOTION"))
            .unwrap();
        out.push(lines[..(motion + 6).min(lines.len())].concat());
    }
    out
}

/// A version-2 recording with an interpolation word and an object block.
const TRK2: &str = "troupe-trk 2\nsequence ann\ntrack r_elbow_flexion step\n0 0\n1 1\nend\nobject cup\nshape frustum 0.03 0.04 0.1\nmass 0.3\ntrack x linear\n0 0\n1 0.5\nend\ntrack y linear\n0 0.9\nend\ntrack z\n0 0\nend\ntrack qx\n0 0\nend\ntrack qy\n0 0\nend\ntrack qz\n0 0\nend\ntrack qw\n0 1\nend\nheld 0.25 1 ann r_wrist\n";
const TRK: &str = "troupe-trk 1\n# a set\nsequence wave\nloop true\nmeta rate 100\nmeta source bvh\ntrack r_shoulder_abduction\n0 0\n0.5 1.2 0\n1 0\nend\nsequence other\ntrack x\n0 1\nend\n";

const GARBAGE: &[&str] = &[
    "",
    "nan",
    "inf",
    "-1",
    "99999999999",
    "18446744073709551616",
    "1e308",
    "{",
    "}",
    "JOINT",
    "End",
    "ROOT",
    "MOTION",
    "Frames:",
    "CHANNELS",
    "OFFSET",
    "Xrotation",
    "end",
    "track",
    "sequence",
    "\u{0}",
    "é",
    "\r",
];

fn check_line(result: Result<impl Sized, Error>, text: &str) -> Result<(), TestCaseError> {
    if let Err(e) = result {
        match e {
            Error::Parse { line, .. } => {
                let lines = text.lines().count().max(1);
                prop_assert!(line >= 1 && line <= lines + 1, "line {line} of {lines}");
            }
            other => prop_assert!(false, "not a parse error: {other:?}"),
        }
    }
    Ok(())
}

/// Applies `edits` (position, garbage index, kind) to the whitespace-separated tokens.
fn mutate(text: &str, edits: &[(usize, usize, u8)]) -> String {
    let mut tokens: Vec<String> = text
        .split_inclusive(|c: char| c.is_whitespace())
        .map(str::to_string)
        .collect();
    for &(pos, g, kind) in edits {
        if tokens.is_empty() {
            break;
        }
        let i = pos % tokens.len();
        let junk = GARBAGE[g % GARBAGE.len()];
        match kind % 4 {
            0 => tokens[i] = format!("{junk} "),
            1 => {
                tokens.remove(i);
            }
            2 => tokens.insert(i, format!("{junk}\n")),
            _ => {
                let t = tokens[i].clone();
                tokens.insert(i, t);
            }
        }
    }
    tokens.concat()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(
        std::env::var("PROPTEST_CASES").ok().and_then(|c| c.parse().ok()).unwrap_or(512)
    ))]

    #[test]
    fn bvh_reader_survives_arbitrary_text(text in "\\PC*") {
        check_line(parse_bvh(&text, "fuzz.bvh"), &text)?;
    }

    #[test]
    fn bvh_reader_survives_truncation(seed in 0usize..3, cut in 0.0f64..1.0) {
        let s = &seeds()[seed];
        let mut at = (s.len() as f64 * cut) as usize;
        while !s.is_char_boundary(at) { at -= 1; }
        check_line(parse_bvh(&s[..at], "cut.bvh"), &s[..at])?;
    }

    #[test]
    fn bvh_reader_survives_token_mutations(
        seed in 0usize..3,
        edits in proptest::collection::vec((any::<usize>(), any::<usize>(), any::<u8>()), 1..8),
    ) {
        let text = mutate(&seeds()[seed], &edits);
        check_line(parse_bvh(&text, "mut.bvh"), &text)?;
    }

    #[test]
    fn trk_reader_survives_arbitrary_text(text in "\\PC*") {
        check_line(parse_trk(&text, "fuzz.trk"), &text)?;
    }

    #[test]
    fn trk_reader_survives_mutations(
        edits in proptest::collection::vec((any::<usize>(), any::<usize>(), any::<u8>()), 1..8),
        cut in 0.0f64..1.0,
        version_2 in any::<bool>(),
    ) {
        let text = mutate(if version_2 { TRK2 } else { TRK }, &edits);
        let at = (text.len() as f64 * cut) as usize;
        let mut at = at.max(1).min(text.len());
        while !text.is_char_boundary(at) { at -= 1; }
        check_line(parse_trk(&text[..at], "mut.trk"), &text[..at])?;
        check_line(parse_trk(&text, "mut.trk"), &text)?;
        check_line(parse_trk_file(&text, "mut.trk"), &text)?;
    }
}

#[test]
fn absurd_declared_sizes_do_not_allocate() {
    let base = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n}\nMOTION\nFrames: 99999999999\nFrame Time: 0.01\n1 2 3\n";
    let b = parse_bvh(base, "big.bvh").unwrap();
    assert_eq!(b.frame_count(), 1);
    for (text, line) in [
        (
            base.replace("Frames: 99999999999", "Frames: 99999999999999999999999"),
            8,
        ),
        (base.replace("CHANNELS 3", "CHANNELS 4000000000"), 5),
        (base.replace("Frame Time: 0.01", "Frame Time: 1e-400"), 9),
    ] {
        match parse_bvh(&text, "big.bvh") {
            Err(Error::Parse { line: l, .. }) => assert_eq!(l, line, "{text}"),
            other => panic!("{text}: {other:?}"),
        }
    }
    // Deep nesting is handled without recursion.
    let mut deep = String::from("HIERARCHY\nROOT r\n{\n");
    for i in 0..20_000 {
        deep.push_str(&format!("JOINT j{i}\n{{\nOFFSET 0 1 0\n"));
    }
    assert!(matches!(
        parse_bvh(&deep, "deep.bvh"),
        Err(Error::Parse { .. })
    ));
}
