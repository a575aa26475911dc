//! The native `.trk` track format: versioned text, one or more sequences of Hermite keys.
//!
//! ```text
//! troupe-trk 2
//! # comments and blank lines are ignored
//! sequence wave            # starts a sequence (optional before the first one)
//! loop true                # optional, default false
//! meta rate 100            # optional key/value metadata, kept as text
//! track r_shoulder_abduction
//! 0 0                      # time value            (default slope)
//! 0.5 1.2 0                # time value slope
//! end
//! track r_wrist_flexion linear   # version 2: an interpolation after the DOF name
//! 0 0
//! 1 0.4
//! end
//! ```
//!
//! A track's interpolation is `cubic` (the default, monotone: it never overshoots its
//! keys where slopes are not given), `hermite`, `linear` or `step` (see
//! [`Interpolation`]). Version 1 files have no interpolation word; their tracks are read
//! as `hermite`, the interpolation they were written for, so an old file plays as it did.
//!
//! Numbers are written in Rust's shortest round-trip form, so a sequence read back from
//! its own output is identical bit for bit.

use crate::error::{Error, Result};
use std::fmt::Write as _;
use std::path::Path;
use troupe_motion::sequence::{Interpolation, Key, Sequence, Track};

/// The version this build writes; it reads every version up to it.
pub const TRK_VERSION: u32 = 2;

/// The interpolation of a track that names none in a file of `version`: version 1 meant
/// the thesis's Hermite slopes.
fn default_interpolation(version: u32) -> Interpolation {
    if version == 1 {
        Interpolation::Hermite
    } else {
        Interpolation::Cubic
    }
}

/// Reads a file holding exactly one sequence.
pub fn read_trk(path: impl AsRef<Path>) -> Result<Sequence> {
    let path = path.as_ref();
    let mut set = read_trk_set(path)?;
    match set.len() {
        1 => Ok(set.remove(0)),
        n => Err(Error::Parse {
            file: path.display().to_string(),
            line: 1,
            message: format!("expected one sequence, found {n} (read it as a sequence set)"),
        }),
    }
}

/// Reads every sequence of a file.
pub fn read_trk_set(path: impl AsRef<Path>) -> Result<Vec<Sequence>> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut set = parse_trk(&text, &path.display().to_string())?;
    if set.len() == 1 && set[0].name.is_empty() {
        if let Some(stem) = path.file_stem() {
            set[0].name = stem.to_string_lossy().into_owned();
        }
    }
    Ok(set)
}

/// Parses `.trk` text; `file` names the source in errors.
pub fn parse_trk(text: &str, file: &str) -> Result<Vec<Sequence>> {
    let err = |line: usize, message: String| Error::Parse {
        file: file.to_string(),
        line,
        message,
    };
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty());

    let (n, header) = lines
        .next()
        .ok_or_else(|| err(1, "empty file: expected `troupe-trk 1`".into()))?;
    let version = header
        .strip_prefix("troupe-trk")
        .map(str::trim)
        .and_then(|v| v.parse::<u32>().ok())
        .ok_or_else(|| {
            err(
                n,
                format!("expected `troupe-trk {TRK_VERSION}`, found `{header}`"),
            )
        })?;
    if version == 0 || version > TRK_VERSION {
        return Err(err(
            n,
            format!("unsupported .trk version {version} (this build reads up to {TRK_VERSION})"),
        ));
    }

    let mut set: Vec<Sequence> = Vec::new();
    let mut current: Option<Sequence> = None;
    let mut track: Option<(usize, String, Interpolation, Vec<Key>)> = None;
    for (n, line) in lines {
        if let Some((start, dof, interpolation, keys)) = track.as_mut() {
            if line == "end" {
                let (start, dof, keys) = (*start, std::mem::take(dof), std::mem::take(keys));
                let interpolation = *interpolation;
                track = None;
                let t = Track::new(dof, keys)
                    .map_err(|e| err(start, e.to_string()))?
                    .with_interpolation(interpolation);
                let seq = current.get_or_insert_with(Sequence::default);
                seq.add_track(t).map_err(|e| err(start, e.to_string()))?;
                continue;
            }
            let fields: Vec<&str> = line.split_whitespace().collect();
            if !(2..=3).contains(&fields.len()) {
                return Err(err(
                    n,
                    format!("expected `time value [slope]` or `end`, found `{line}`"),
                ));
            }
            let number = |s: &str, what: &str| {
                s.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| err(n, format!("{what} `{s}` is not a finite number")))
            };
            let time = number(fields[0], "time")?;
            let value = number(fields[1], "value")?;
            let slope = fields.get(2).map(|s| number(s, "slope")).transpose()?;
            keys.push(Key { time, value, slope });
            continue;
        }
        let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let rest = rest.trim();
        match word {
            "sequence" => {
                if let Some(seq) = current.take() {
                    set.push(seq);
                }
                current = Some(Sequence::new(rest));
            }
            "loop" => {
                let looping = match rest {
                    "true" => true,
                    "false" => false,
                    _ => {
                        return Err(err(
                            n,
                            format!("expected `loop true` or `loop false`, found `{line}`"),
                        ))
                    }
                };
                current.get_or_insert_with(Sequence::default).looping = looping;
            }
            "meta" => {
                let (key, value) = rest
                    .split_once(char::is_whitespace)
                    .ok_or_else(|| err(n, "expected `meta KEY VALUE`".into()))?;
                current
                    .get_or_insert_with(Sequence::default)
                    .meta
                    .insert(key.to_string(), value.trim().to_string());
            }
            "track" => {
                let words: Vec<&str> = rest.split_whitespace().collect();
                let interpolation = match words[..] {
                    [_] => default_interpolation(version),
                    [_, name] if version >= 2 => {
                        Interpolation::from_name(name).ok_or_else(|| {
                            err(
                                n,
                                format!(
                                    "unknown interpolation `{name}` (expected cubic, hermite, linear or step)"
                                ),
                            )
                        })?
                    }
                    _ if version >= 2 => {
                        return Err(err(
                            n,
                            format!("expected `track DOF_NAME [INTERPOLATION]`, found `{line}`"),
                        ))
                    }
                    _ => return Err(err(n, format!("expected `track DOF_NAME`, found `{line}`"))),
                };
                track = Some((n, words[0].to_string(), interpolation, Vec::new()));
            }
            _ => {
                return Err(err(
                    n,
                    format!("unexpected `{word}` (expected sequence, loop, meta or track)"),
                ));
            }
        }
    }
    if let Some((start, dof, _, _)) = track {
        return Err(err(start, format!("track `{dof}` is not closed by `end`")));
    }
    if let Some(seq) = current {
        set.push(seq);
    }
    if set.is_empty() {
        return Err(err(1, "no sequence in file".into()));
    }
    Ok(set)
}

/// Writes sequences as `.trk` text.
pub fn format_trk(set: &[Sequence]) -> String {
    let mut out = format!("troupe-trk {TRK_VERSION}\n");
    for seq in set {
        // `writeln!` into a String cannot fail.
        let _ = writeln!(out, "sequence {}", seq.name);
        if seq.looping {
            out.push_str("loop true\n");
        }
        for (k, v) in &seq.meta {
            let _ = writeln!(out, "meta {k} {v}");
        }
        for track in seq.tracks() {
            match track.interpolation() {
                Interpolation::Cubic => {
                    let _ = writeln!(out, "track {}", track.dof());
                }
                other => {
                    let _ = writeln!(out, "track {} {}", track.dof(), other.name());
                }
            }
            for key in track.keys() {
                match key.slope {
                    Some(s) => {
                        let _ = writeln!(out, "{} {} {}", key.time, key.value, s);
                    }
                    None => {
                        let _ = writeln!(out, "{} {}", key.time, key.value);
                    }
                }
            }
            out.push_str("end\n");
        }
    }
    out
}

/// Writes sequences to a `.trk` file.
pub fn write_trk(path: impl AsRef<Path>, set: &[Sequence]) -> Result<()> {
    let path = path.as_ref();
    std::fs::write(path, format_trk(set)).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::error::assert_parse_error;
    use proptest::prelude::*;

    const WAVE: &str = "troupe-trk 2\n# a wave\nsequence wave\nloop true\nmeta rate 100\ntrack r_shoulder_abduction\n0 0\n0.5 1.2 0\n1 0\nend\n";

    #[test]
    fn parses_and_round_trips() {
        let set = parse_trk(WAVE, "wave.trk").unwrap();
        assert_eq!(set.len(), 1);
        let s = &set[0];
        assert_eq!(s.name, "wave");
        assert!(s.looping);
        assert_eq!(s.meta["rate"], "100");
        assert_eq!(s.tracks()[0].keys()[1], Key::with_slope(0.5, 1.2, 0.0));
        assert_eq!(parse_trk(&format_trk(&set), "again").unwrap(), set);
    }

    #[test]
    fn errors_name_file_and_line() {
        let cases = [
            ("", 1, "empty file"),
            ("troupe-trk 9\n", 1, "unsupported"),
            (
                "troupe-trk 2\ntrack x spline\n0 1\nend\n",
                2,
                "unknown interpolation `spline`",
            ),
            (
                "troupe-trk 1\ntrack x linear\n0 1\nend\n",
                2,
                "expected `track DOF_NAME`",
            ),
            (
                "troupe-trk 2\ntrack x linear y\n0 1\nend\n",
                2,
                "[INTERPOLATION]",
            ),
            ("troupe-trk 1\ntrack x\n0 zero\nend\n", 3, "value `zero`"),
            ("troupe-trk 1\ntrack x\n0 1\n", 2, "not closed"),
            (
                "troupe-trk 1\ntrack x\n1 1\n0 1\nend\n",
                2,
                "does not follow",
            ),
            ("troupe-trk 1\nbogus\n", 2, "unexpected"),
            ("troupe-trk 1\ntrack x\n0 inf\nend\n", 3, "finite"),
        ];
        for (text, line, needle) in cases {
            assert_parse_error(parse_trk(text, "f.trk"), text, "f.trk", line, needle);
        }
    }

    #[test]
    fn interpolation_is_per_track_and_version_1_reads_as_hermite() {
        let v2 = "troupe-trk 2\ntrack a\n0 0\n1 1\n2 1\nend\ntrack b step\n0 0\n1 1\nend\n";
        let set = parse_trk(v2, "v2.trk").unwrap();
        let (a, b) = (&set[0].tracks()[0], &set[0].tracks()[1]);
        assert_eq!(a.interpolation(), Interpolation::Cubic);
        assert_eq!(b.interpolation(), Interpolation::Step);
        assert_eq!(b.value(0.99), 0.0);
        assert_eq!(parse_trk(&format_trk(&set), "again").unwrap(), set);
        assert!(format_trk(&set).contains("track b step\n"));
        // The same keys in a version-1 file keep the overshoot they were written with.
        let v1 = parse_trk(
            &v2.replace("troupe-trk 2", "troupe-trk 1")
                .replace(" step", ""),
            "v1.trk",
        )
        .unwrap();
        assert_eq!(v1[0].tracks()[0].interpolation(), Interpolation::Hermite);
        assert!(v1[0].tracks()[0].value(1.5) > 1.0);
        assert_eq!(a.value(1.5), 1.0);
    }

    proptest! {
        #[test]
        fn any_sequence_round_trips_exactly(
            tracks in proptest::collection::vec(
                proptest::collection::vec((0.001f64..10.0, -1e6f64..1e6, proptest::option::of(-1e3f64..1e3)), 1..20),
                1..5),
            looping in any::<bool>(),
            interpolation in proptest::sample::select(Interpolation::ALL.to_vec()))
        {
            let mut seq = Sequence::new("s");
            seq.looping = looping;
            for (i, keys) in tracks.iter().enumerate() {
                let mut t = 0.0;
                let keys = keys.iter().map(|(dt, v, s)| { t += dt; Key { time: t, value: *v, slope: *s } }).collect();
                let track = Track::new(format!("dof{i}"), keys).unwrap();
                seq.add_track(track.with_interpolation(interpolation)).unwrap();
            }
            let set = vec![seq];
            prop_assert_eq!(parse_trk(&format_trk(&set), "p").unwrap(), set);
        }
    }
}
