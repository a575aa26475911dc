//! The hand-written BVH reader: tolerant of what real files contain, and precise about
//! what is wrong with the ones it refuses (file, line, what was expected). It is fuzzed
//! (`tests/fuzz_readers.rs`).

use super::channel::{Channel, MAX_JOINT_CHANNELS};
use super::motion::{Bvh, BvhJoint};
use crate::error::{Error, Result};
use glam::DVec3;
use std::path::Path;

/// Reads a BVH file (bytes that are not UTF-8 are replaced, as names are all that could
/// hold them).
pub fn read_bvh(path: impl AsRef<Path>) -> Result<Bvh> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_bvh(
        &String::from_utf8_lossy(&bytes),
        &path.display().to_string(),
    )
}

/// Parses BVH text; `file` names the source in errors.
pub fn parse_bvh(text: &str, file: &str) -> Result<Bvh> {
    let err = |line: usize, message: String| Error::Parse {
        file: file.to_string(),
        line,
        message,
    };
    let lines: Vec<&str> = text.lines().collect();

    // HIERARCHY section, as tokens with their line numbers, up to MOTION.
    let mut tokens: Vec<(usize, &str)> = Vec::new();
    let mut motion_line = None;
    for (i, l) in lines.iter().enumerate() {
        let mut words = l.split_whitespace().peekable();
        if words.peek() == Some(&"MOTION") {
            motion_line = Some(i);
            break;
        }
        tokens.extend(words.map(|w| (i + 1, w)));
    }
    let last_line = lines.len().max(1);
    let mut toks = tokens.into_iter().peekable();
    match toks.next() {
        Some((_, "HIERARCHY")) => {}
        Some((n, t)) => return Err(err(n, format!("expected `HIERARCHY`, found `{t}`"))),
        None => return Err(err(1, "empty file: expected `HIERARCHY`".into())),
    }

    let mut joints: Vec<BvhJoint> = Vec::new();
    // Open blocks: Some(joint) for a joint, None for an End Site.
    let mut stack: Vec<Option<usize>> = Vec::new();
    let mut channel_count = 0usize;
    let mut pending: Option<(usize, Option<usize>, String)> = None; // a JOINT/ROOT/End Site awaiting `{`
    let number = |n: usize, s: &str, what: &str| -> Result<f64> {
        s.parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| err(n, format!("{what}: `{s}` is not a finite number")))
    };
    while let Some((n, tok)) = toks.next() {
        if let Some((pn, parent, name)) = pending.take() {
            if tok != "{" {
                return Err(err(
                    n,
                    format!("expected `{{` after `{name}`, found `{tok}`"),
                ));
            }
            if name == "End Site" {
                stack.push(None);
                continue;
            }
            let _ = pn;
            joints.push(BvhJoint {
                name,
                parent,
                offset: DVec3::ZERO,
                channels: Vec::new(),
                first_channel: channel_count,
                end_sites: Vec::new(),
            });
            stack.push(Some(joints.len() - 1));
            continue;
        }
        match tok {
            "ROOT" | "JOINT" => {
                if tok == "ROOT" && !stack.is_empty() {
                    return Err(err(n, "`ROOT` inside another joint".into()));
                }
                if tok == "JOINT" && !matches!(stack.last(), Some(Some(_))) {
                    return Err(err(n, "`JOINT` outside a joint block".into()));
                }
                let name = match toks.next() {
                    Some((m, name)) if m == n && name != "{" => name.to_string(),
                    _ => return Err(err(n, format!("`{tok}` needs a name"))),
                };
                if joints.iter().any(|j| j.name == name) {
                    tracing::warn!("{file}:{n}: joint name `{name}` is used twice");
                }
                pending = Some((n, stack.last().copied().flatten(), name));
            }
            "End" => {
                match toks.next() {
                    Some((_, "Site")) => {}
                    _ => return Err(err(n, "expected `End Site`".into())),
                }
                if !matches!(stack.last(), Some(Some(_))) {
                    return Err(err(n, "`End Site` outside a joint block".into()));
                }
                pending = Some((n, None, "End Site".into()));
            }
            "OFFSET" => {
                let mut v = [0.0; 3];
                for x in &mut v {
                    let (m, s) = toks
                        .next()
                        .filter(|(m, _)| *m == n)
                        .ok_or_else(|| err(n, "`OFFSET` needs three numbers".into()))?;
                    *x = number(m, s, "OFFSET")?;
                }
                let offset = DVec3::from_array(v);
                match stack.last() {
                    Some(Some(j)) => joints[*j].offset = offset,
                    Some(None) => {
                        let owner = stack.iter().rev().find_map(|s| *s);
                        if let Some(j) = owner {
                            joints[j].end_sites.push(offset);
                        }
                    }
                    None => return Err(err(n, "`OFFSET` outside a block".into())),
                }
            }
            "CHANNELS" => {
                let Some(Some(j)) = stack.last().copied() else {
                    return Err(err(n, "`CHANNELS` outside a joint block".into()));
                };
                let (m, s) = toks
                    .next()
                    .filter(|(m, _)| *m == n)
                    .ok_or_else(|| err(n, "`CHANNELS` needs a count".into()))?;
                let count: usize = s
                    .parse()
                    .ok()
                    .filter(|c| *c <= MAX_JOINT_CHANNELS)
                    .ok_or_else(|| {
                        err(
                            m,
                            format!("channel count `{s}` is not a number from 0 to {MAX_JOINT_CHANNELS}"),
                        )
                    })?;
                if !joints[j].channels.is_empty() {
                    return Err(err(n, format!("joint `{}` has two CHANNELS lines", joints[j].name)));
                }
                let mut channels = Vec::with_capacity(count);
                for _ in 0..count {
                    let (m, s) = toks.next().filter(|(m, _)| *m == n).ok_or_else(|| {
                        err(n, format!("`CHANNELS {count}` lists fewer than {count} channels"))
                    })?;
                    let c = Channel::parse(s)
                        .ok_or_else(|| err(m, format!("unknown channel `{s}`")))?;
                    if channels.contains(&c) {
                        return Err(err(m, format!("channel `{s}` listed twice")));
                    }
                    channels.push(c);
                }
                if let Some((m, extra)) = toks.peek().copied() {
                    if m == n {
                        return Err(err(
                            n,
                            format!("`CHANNELS {count}` lists more than {count} channels (`{extra}`)"),
                        ));
                    }
                }
                joints[j].first_channel = channel_count;
                channel_count += count;
                joints[j].channels = channels;
            }
            "}" => {
                if stack.pop().is_none() {
                    return Err(err(n, "unmatched `}`".into()));
                }
            }
            other => {
                return Err(err(
                    n,
                    format!("unexpected `{other}` (expected ROOT, JOINT, End Site, OFFSET, CHANNELS, `}}` or MOTION)"),
                ))
            }
        }
    }
    if let Some((n, _, name)) = pending {
        return Err(err(n, format!("`{name}` has no block")));
    }
    if !stack.is_empty() {
        return Err(err(
            motion_line.map_or(last_line, |m| m + 1),
            format!("{} block(s) not closed before MOTION", stack.len()),
        ));
    }
    if joints.is_empty() {
        return Err(err(
            motion_line.map_or(last_line, |m| m + 1),
            "no ROOT in HIERARCHY".into(),
        ));
    }
    let Some(motion) = motion_line else {
        return Err(err(last_line, "no MOTION section".into()));
    };

    // MOTION header: `Frames: N` and `Frame Time: T` (the number may follow on its own).
    let mut rest = lines
        .iter()
        .enumerate()
        .skip(motion + 1)
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());
    let after_motion = motion + 1;
    let (n, frames_line) = rest
        .next()
        .ok_or_else(|| err(after_motion, "expected `Frames: N` after MOTION".into()))?;
    let declared: u64 = frames_line
        .strip_prefix("Frames:")
        .map(str::trim)
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| err(n, format!("expected `Frames: N`, found `{frames_line}`")))?;
    let (n, time_line) = rest
        .next()
        .ok_or_else(|| err(n, "expected `Frame Time: SECONDS`".into()))?;
    let frame_time = time_line
        .strip_prefix("Frame")
        .map(str::trim_start)
        .and_then(|s| s.strip_prefix("Time:"))
        .map(str::trim)
        .and_then(|s| s.parse::<f64>().ok())
        .filter(|t| t.is_finite() && *t > 0.0)
        .ok_or_else(|| {
            err(
                n,
                format!("expected `Frame Time: SECONDS` (positive), found `{time_line}`"),
            )
        })?;

    // Rows: never preallocate from the declared count, only from the text itself.
    let mut data = Vec::with_capacity(lines.len().saturating_sub(motion) * channel_count);
    let mut rows = 0usize;
    for (n, line) in rest {
        let mut count = 0;
        for s in line.split_whitespace() {
            count += 1;
            if count > channel_count {
                break;
            }
            data.push(number(n, s, "frame value")?);
        }
        if count != channel_count {
            return Err(err(
                n,
                format!(
                    "frame {} has {} values, the hierarchy declares {channel_count} channels",
                    rows + 1,
                    if count > channel_count {
                        format!("more than {channel_count}")
                    } else {
                        count.to_string()
                    }
                ),
            ));
        }
        rows += 1;
    }
    if rows as u64 != declared {
        tracing::warn!(
            "{file}: `Frames: {declared}` but {rows} data rows follow; using the {rows} rows"
        );
    }
    Bvh::new(joints, frame_time, data).map_err(|e| err(motion + 1, e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::fixtures::{data, shared_files};
    use crate::bvh::Axis;
    use crate::error::assert_parse_error;

    #[test]
    fn every_shared_file_imports_with_the_documented_shape() {
        // (file, joints, end sites, frames)
        let expected = [
            ("pybvhrepo_bvh_example.bvh", 24, 5, 75),
            ("pybvhrepo_bvh_test3.bvh", 60, 13, 100),
            ("pybvhrepo_cmu_12_01_walk.bvh", 31, 7, 524),
            ("pybvhrepo_rotation_first_root.bvh", 4, 2, 4),
            ("pymo_AV_8Walk_Meredith_HVHA_Rep1.bvh", 23, 7, 1064),
        ];
        let files = shared_files();
        assert_eq!(files.len(), expected.len());
        for (name, joints, ends, frames) in expected {
            let b = read_bvh(data(name)).unwrap();
            assert_eq!(b.joints().len(), joints, "{name}");
            let e: usize = b.joints().iter().map(|j| j.end_sites.len()).sum();
            assert_eq!(e, ends, "{name}");
            assert_eq!(b.frame_count(), frames, "{name}");
            for k in [0, frames - 1] {
                assert!(b.joint_positions(k).iter().all(|p| p.is_finite()));
            }
        }
    }

    #[test]
    fn rotation_before_position_and_root_offset_replacement() {
        let b = read_bvh(data("pybvhrepo_rotation_first_root.bvh")).unwrap();
        let root = &b.joints()[0];
        assert_eq!(root.channels[0], Channel::Rotation(Axis::Z));
        assert_eq!(root.channels[3], Channel::Position(Axis::X));
        let f = b.frame(0).to_vec();
        let p = b.joint_positions(0);
        assert_eq!(p[0], DVec3::new(f[3], f[4], f[5]));
        // The PyMO file's root OFFSET is replaced by its absolute position channels.
        let m = read_bvh(data("pymo_AV_8Walk_Meredith_HVHA_Rep1.bvh")).unwrap();
        assert_ne!(m.joints()[0].offset, DVec3::ZERO);
        let f = m.frame(10);
        assert_eq!(m.joint_positions(10)[0], DVec3::new(f[0], f[1], f[2]));
    }

    #[test]
    fn malformed_files_name_the_line() {
        let ok = "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 3 Xposition Yposition Zposition\n}\nMOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5 6\n";
        assert_eq!(parse_bvh(ok, "f").unwrap().frame_count(), 2);
        let cases = [
            ("", 1, "HIERARCHY"),
            ("HIERARCHY\nROOT a\n{\nOFFSET 0 x 0\n", 4, "not a finite"),
            (
                "HIERARCHY\nROOT a\n{\nCHANNELS 99999999999 X\n}\nMOTION\n",
                4,
                "channel count",
            ),
            (
                "HIERARCHY\nROOT a\n{\nCHANNELS 2 Xposition\n}\n",
                4,
                "fewer",
            ),
            (
                "HIERARCHY\nROOT a\n{\nCHANNELS 1 Wrotation\n}\n",
                4,
                "unknown channel",
            ),
            ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\n", 4, "not closed"),
            (&ok.replace("4 5 6", "4 5"), 11, "2 values"),
            (&ok.replace("4 5 6", "4 5 6 7"), 11, "more than 3"),
            (&ok.replace("4 5 6", "4 nan 6"), 11, "not a finite"),
            (&ok.replace("0.1", "0"), 9, "Frame Time"),
            (&ok.replace("Frames: 2", "Frames: two"), 8, "Frames"),
            (
                &ok.replace("MOTION\nFrames: 2\nFrame Time: 0.1\n1 2 3\n4 5 6\n", ""),
                6,
                "MOTION",
            ),
        ];
        for (text, line, needle) in cases {
            assert_parse_error(parse_bvh(text, "f.bvh"), text, "f.bvh", line, needle);
        }
        // A wrong `Frames:` count is a warning; the rows are used.
        let more = ok.replace("Frames: 2", "Frames: 99999999999");
        assert_eq!(parse_bvh(&more, "f").unwrap().frame_count(), 2);
    }
}
