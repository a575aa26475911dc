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
//! its own output is identical bit for bit. Names that are not plain words are written in
//! double quotes (`sequence "Ann Lee"`, `held 1 2 "take#2" r_wrist`; see `words.rs`).

mod words;

use crate::error::{Error, Result};
use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;
use troupe_body::glam::DVec3;
use troupe_body::solid::Shape;
use troupe_motion::object_motion::{Hold, ObjectMotion};
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
        n => {
            let names: Vec<String> = set.iter().map(|s| format!("`{}`", s.name)).collect();
            Err(Error::Parse {
                file: path.display().to_string(),
                line: 1,
                message: format!(
                    "expected one sequence, found {n} ({}): a recording of several actors \
                     holds one per actor (`actor:play(FILE, {{ part = NAME }})` plays one)",
                    names.join(", ")
                ),
            })
        }
    }
}

/// Reads every sequence of a file (its objects, if any, are left out: see
/// [`read_trk_file`]).
pub fn read_trk_set(path: impl AsRef<Path>) -> Result<Vec<Sequence>> {
    let path = path.as_ref();
    sequences_only(read_trk_file(path)?, &path.display().to_string())
}

/// The sequences of a parsed file; a file of objects only is an error naming `file`.
fn sequences_only(parsed: TrkFile, file: &str) -> Result<Vec<Sequence>> {
    if parsed.sequences.is_empty() {
        return Err(Error::Parse {
            file: file.to_string(),
            line: 1,
            message: "no sequence in file (it holds objects only)".into(),
        });
    }
    Ok(parsed.sequences)
}

/// Reads a whole file: its sequences and its objects.
pub fn read_trk_file(path: impl AsRef<Path>) -> Result<TrkFile> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let mut file = parse_trk_file(&text, &path.display().to_string())?;
    let set = &mut file.sequences;
    if set.len() == 1 && set[0].name.is_empty() {
        if let Some(stem) = path.file_stem() {
            set[0].name = stem.to_string_lossy().into_owned();
        }
    }
    Ok(file)
}

/// What a `.trk` file holds: sequences (one per actor in a recording) and, from version
/// 2, the recorded objects.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TrkFile {
    /// The sequences, in file order.
    pub sequences: Vec<Sequence>,
    /// The objects, in file order.
    pub objects: Vec<ObjectMotion>,
}

/// Parses `.trk` text into its sequences (objects left out); `file` names the source in
/// errors.
pub fn parse_trk(text: &str, file: &str) -> Result<Vec<Sequence>> {
    sequences_only(parse_trk_file(text, file)?, file)
}

/// An object block being read.
struct ObjectDraft {
    line: usize,
    shape: Option<Shape>,
    mass: Option<f64>,
    pose: Sequence,
    holds: Vec<Hold>,
}

/// The block that statements apply to.
enum Block {
    Sequence(Sequence),
    Object(ObjectDraft),
}

/// Parses `.trk` text, sequences and objects; `file` names the source in errors.
pub fn parse_trk_file(text: &str, file: &str) -> Result<TrkFile> {
    let err = |line: usize, message: String| Error::Parse {
        file: file.to_string(),
        line,
        message,
    };
    // A byte-order mark is no part of the header (editors on Windows write one).
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, words::strip_comment(l).map(str::trim)))
        .filter(|(_, l)| l.as_ref().map_or(true, |l| !l.is_empty()));

    let (n, header) = lines.next().ok_or_else(|| {
        err(
            1,
            format!("empty file: expected `troupe-trk {TRK_VERSION}`"),
        )
    })?;
    let header = header.map_err(|m| err(n, m))?;
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

    let mut out = TrkFile::default();
    let mut current: Option<Block> = None;
    let mut track: Option<(usize, String, Interpolation, Vec<Key>)> = None;
    // The line of each named block, by kind and name: a name is one actor or object.
    let mut seen: HashMap<(&str, String), usize> = HashMap::new();
    // Closes the current block into `out`.
    let close = |block: Option<Block>, out: &mut TrkFile| -> Result<()> {
        match block {
            None => {}
            Some(Block::Sequence(seq)) => out.sequences.push(seq),
            Some(Block::Object(o)) => {
                let name = o.pose.name.clone();
                let (Some(shape), Some(mass)) = (o.shape, o.mass) else {
                    return Err(err(
                        o.line,
                        format!("object `{name}` needs a `shape` and a `mass` line"),
                    ));
                };
                let object = ObjectMotion {
                    name,
                    shape,
                    mass,
                    pose: o.pose,
                    holds: o.holds,
                };
                object.validate().map_err(|e| err(o.line, e.to_string()))?;
                out.objects.push(object);
            }
        }
        Ok(())
    };
    for (n, line) in lines {
        let line = line.map_err(|m| err(n, m))?;
        if let Some((start, dof, interpolation, keys)) = track.as_mut() {
            if line == "end" {
                let (start, dof, keys) = (*start, std::mem::take(dof), std::mem::take(keys));
                let interpolation = *interpolation;
                track = None;
                let t = Track::new(dof, keys)
                    .map_err(|e| err(start, e.to_string()))?
                    .with_interpolation(interpolation);
                let seq = match current.get_or_insert_with(|| Block::Sequence(Sequence::default()))
                {
                    Block::Sequence(seq) => seq,
                    Block::Object(o) => &mut o.pose,
                };
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
            let time = number(fields[0], "time").map_err(|m| err(n, m))?;
            let value = number(fields[1], "value").map_err(|m| err(n, m))?;
            let slope = fields
                .get(2)
                .map(|s| number(s, "slope"))
                .transpose()
                .map_err(|m| err(n, m))?;
            keys.push(Key { time, value, slope });
            continue;
        }
        let (word, rest) = line.split_once(char::is_whitespace).unwrap_or((line, ""));
        let rest = rest.trim();
        let in_object = matches!(current, Some(Block::Object(_)));
        match word {
            // Objects came with version 2.
            "sequence" | "object" if word == "sequence" || version >= 2 => {
                let name = block_name(word, rest).map_err(|m| err(n, m))?;
                close(current.take(), &mut out)?;
                let earlier = match seen.get(&(word, name.clone())) {
                    Some(line) => Some(format!("line {line}")),
                    // Only the unnamed sequence before the first `sequence` line is not
                    // in `seen`.
                    None if word == "sequence" && out.sequences.iter().any(|s| s.name == name) => {
                        Some("the unnamed sequence before the first `sequence` line".into())
                    }
                    None => None,
                };
                if let Some(earlier) = earlier {
                    return Err(err(
                        n,
                        format!("a second {word} named `{name}` (the first: {earlier}): each {word} of a file has a name of its own"),
                    ));
                }
                seen.insert((word, name.clone()), n);
                current = Some(if word == "sequence" {
                    Block::Sequence(Sequence::new(name))
                } else {
                    Block::Object(ObjectDraft {
                        line: n,
                        shape: None,
                        mass: None,
                        pose: Sequence::new(name),
                        holds: Vec::new(),
                    })
                });
            }
            "loop" | "meta" if in_object => {
                return Err(err(
                    n,
                    format!("`{word}` belongs to a sequence, not an object"),
                ));
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
                sequence_of(&mut current).looping = looping;
            }
            "meta" => {
                let (key, value) = words::split_word(rest)
                    .map_err(|m| err(n, m))?
                    .filter(|(_, value)| !value.trim().is_empty())
                    .ok_or_else(|| err(n, "expected `meta KEY VALUE`".into()))?;
                let value = words::text(value).map_err(|m| err(n, m))?;
                sequence_of(&mut current).meta.insert(key, value);
            }
            "shape" | "mass" | "held" => {
                let Some(Block::Object(o)) = current.as_mut() else {
                    return Err(err(n, format!("`{word}` belongs to an `object` block")));
                };
                match word {
                    "shape" => o.shape = Some(parse_shape(rest).map_err(|m| err(n, m))?),
                    "mass" => {
                        let mass = number(rest, "mass").map_err(|m| err(n, m))?;
                        if mass <= 0.0 {
                            return Err(err(n, format!("mass `{rest}` must be > 0")));
                        }
                        o.mass = Some(mass);
                    }
                    _ => o.holds.push(parse_hold(rest).map_err(|m| err(n, m))?),
                }
            }
            "track" => {
                let words = words::words(rest).map_err(|m| err(n, m))?;
                let interpolation = match &words[..] {
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
                track = Some((n, words[0].clone(), interpolation, Vec::new()));
            }
            _ => {
                let expected = if version >= 2 {
                    "sequence, object, loop, meta, shape, mass, held or track"
                } else {
                    "sequence, loop, meta or track"
                };
                return Err(err(n, format!("unexpected `{word}` (expected {expected})")));
            }
        }
    }
    if let Some((start, dof, _, _)) = track {
        return Err(err(start, format!("track `{dof}` is not closed by `end`")));
    }
    close(current.take(), &mut out)?;
    if out.sequences.is_empty() && out.objects.is_empty() {
        return Err(err(1, "no sequence in file".into()));
    }
    Ok(out)
}

/// The name on a `sequence` or `object` line (`word`), `rest` following the word.
fn block_name(word: &str, rest: &str) -> std::result::Result<String, String> {
    // A bare name is the rest of the line: older files wrote names with spaces so.
    let name = words::text(rest)?;
    if word == "object" && rest.trim().is_empty() {
        return Err("expected `object NAME`".into());
    }
    Ok(name)
}

/// The sequence that `loop` and `meta` apply to (an unnamed one before the first block).
fn sequence_of(current: &mut Option<Block>) -> &mut Sequence {
    match current.get_or_insert_with(|| Block::Sequence(Sequence::default())) {
        Block::Sequence(seq) => seq,
        // Callers check that the block is not an object.
        Block::Object(o) => &mut o.pose,
    }
}

/// A finite number, or a message naming `what`.
fn number(s: &str, what: &str) -> std::result::Result<f64, String> {
    s.parse::<f64>()
        .ok()
        .filter(|v| v.is_finite())
        .ok_or_else(|| format!("{what} `{s}` is not a finite number"))
}

/// `KIND SIZES…` of a `shape` line: `box SX SY SZ` (full sizes), `sphere R`,
/// `cylinder R H`, `frustum R_BOTTOM R_TOP H`, `ellipsoid RX RY RZ` (metres, > 0).
fn parse_shape(rest: &str) -> std::result::Result<Shape, String> {
    let words: Vec<&str> = rest.split_whitespace().collect();
    let Some((&kind, sizes)) = words.split_first() else {
        return Err("expected `shape KIND SIZES…`".into());
    };
    let sizes = sizes
        .iter()
        .map(|s| {
            number(s, "size").and_then(|v| {
                if v > 0.0 {
                    Ok(v)
                } else {
                    Err(format!("size `{s}` must be > 0"))
                }
            })
        })
        .collect::<std::result::Result<Vec<f64>, String>>()?;
    let shape = match (kind, &sizes[..]) {
        ("box", &[x, y, z]) => Shape::Box {
            half_extents: DVec3::new(x, y, z) / 2.0,
        },
        ("sphere", &[radius]) => Shape::Sphere { radius },
        ("cylinder", &[radius, height]) => Shape::Cylinder { radius, height },
        ("frustum", &[bottom_radius, top_radius, height]) => Shape::Frustum {
            bottom_radius,
            top_radius,
            height,
        },
        ("ellipsoid", &[x, y, z]) => Shape::Ellipsoid {
            radii: DVec3::new(x, y, z),
        },
        _ => {
            return Err(format!(
                "expected `shape box SX SY SZ`, `sphere R`, `cylinder R H`, `frustum RB RT H` or `ellipsoid RX RY RZ`, found `shape {rest}`"
            ))
        }
    };
    Ok(shape)
}

/// The `shape` line of `shape` (see [`parse_shape`]).
pub(crate) fn format_shape(shape: &Shape) -> String {
    match *shape {
        Shape::Box { half_extents: h } => format!("box {} {} {}", 2.0 * h.x, 2.0 * h.y, 2.0 * h.z),
        Shape::Sphere { radius } => format!("sphere {radius}"),
        Shape::Cylinder { radius, height } => format!("cylinder {radius} {height}"),
        Shape::Frustum {
            bottom_radius,
            top_radius,
            height,
        } => format!("frustum {bottom_radius} {top_radius} {height}"),
        Shape::Ellipsoid { radii: r } => format!("ellipsoid {} {} {}", r.x, r.y, r.z),
    }
}

/// `FROM TO ACTOR JOINT` of a `held` line.
fn parse_hold(rest: &str) -> std::result::Result<Hold, String> {
    let [from, to, actor, joint] = &words::words(rest)?[..] else {
        return Err(format!(
            "expected `held FROM TO ACTOR JOINT`, found `held {rest}`"
        ));
    };
    let (from, to) = (number(from, "time")?, number(to, "time")?);
    if to < from {
        return Err(format!(
            "held from {from} to {to}: the end is before the start"
        ));
    }
    Ok(Hold {
        from,
        to,
        actor: actor.clone(),
        joint: joint.clone(),
    })
}

/// Writes sequences as `.trk` text.
pub fn format_trk(set: &[Sequence]) -> String {
    let mut out = format!("troupe-trk {TRK_VERSION}\n");
    for seq in set {
        // `writeln!` into a String cannot fail.
        let _ = writeln!(out, "sequence {}", words::name_word(&seq.name));
        if seq.looping {
            out.push_str("loop true\n");
        }
        for (k, v) in &seq.meta {
            let _ = writeln!(out, "meta {} {}", words::name_word(k), words::text_field(v));
        }
        format_tracks(&mut out, seq);
    }
    out
}

/// Writes sequences and objects as `.trk` text.
pub fn format_trk_file(file: &TrkFile) -> String {
    let mut out = format_trk(&file.sequences);
    for object in &file.objects {
        let _ = writeln!(out, "object {}", words::name_word(&object.name));
        let _ = writeln!(out, "shape {}", format_shape(&object.shape));
        let _ = writeln!(out, "mass {}", object.mass);
        format_tracks(&mut out, &object.pose);
        for h in &object.holds {
            let _ = writeln!(
                out,
                "held {} {} {} {}",
                h.from,
                h.to,
                words::name_word(&h.actor),
                words::name_word(&h.joint)
            );
        }
    }
    out
}

/// The `track … end` blocks of `seq`.
fn format_tracks(out: &mut String, seq: &Sequence) {
    for track in seq.tracks() {
        let dof = words::name_word(track.dof());
        match track.interpolation() {
            Interpolation::Cubic => {
                let _ = writeln!(out, "track {dof}");
            }
            other => {
                let _ = writeln!(out, "track {dof} {}", other.name());
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

/// Writes a whole file (sequences and objects) to `path`; two sequences or two objects of
/// one name are an error (the file could not be read back).
pub fn write_trk_file(path: impl AsRef<Path>, file: &TrkFile) -> Result<()> {
    let path = path.as_ref();
    unique_names(path, "sequence", file.sequences.iter().map(|s| &s.name))?;
    unique_names(path, "object", file.objects.iter().map(|o| &o.name))?;
    std::fs::write(path, format_trk_file(file)).map_err(|e| Error::io(path, e))
}

/// Writes sequences to a `.trk` file; two of one name are an error (the file could not be
/// read back).
pub fn write_trk(path: impl AsRef<Path>, set: &[Sequence]) -> Result<()> {
    let path = path.as_ref();
    unique_names(path, "sequence", set.iter().map(|s| &s.name))?;
    std::fs::write(path, format_trk(set)).map_err(|e| Error::io(path, e))
}

/// An error naming `path` when two of `names` (of `kind`s) are equal.
fn unique_names<'a>(
    path: &Path,
    kind: &str,
    names: impl IntoIterator<Item = &'a String>,
) -> Result<()> {
    let mut seen = std::collections::HashSet::new();
    for name in names {
        if !seen.insert(name) {
            return Err(Error::Invalid(format!(
                "{}: two {kind}s named `{name}`: a .trk names each {kind} once",
                path.display()
            )));
        }
    }
    Ok(())
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

    const WITH_OBJECT: &str = "troupe-trk 2\nsequence ann\ntrack r_elbow_flexion\n0 0\n1 1\nend\n\
        object cup\nshape cylinder 0.04 0.1\nmass 0.3\n\
        track x linear\n0 0\n1 0.5\nend\ntrack y linear\n0 0.9\nend\ntrack z linear\n0 0\nend\n\
        track qx linear\n0 0\nend\ntrack qy linear\n0 0\nend\ntrack qz linear\n0 0\nend\ntrack qw linear\n0 1\nend\n\
        held 0.25 1 ann r_wrist\n";

    #[test]
    fn objects_are_read_written_and_left_out_of_the_sequences() {
        let file = parse_trk_file(WITH_OBJECT, "rec.trk").unwrap();
        assert_eq!(file.sequences.len(), 1);
        let cup = &file.objects[0];
        assert_eq!(cup.name, "cup");
        assert_eq!(
            cup.shape,
            Shape::Cylinder {
                radius: 0.04,
                height: 0.1
            }
        );
        assert_eq!(cup.mass, 0.3);
        assert_eq!(cup.pose_at(0.5).0, DVec3::new(0.25, 0.9, 0.0));
        assert_eq!(
            cup.holder_at(0.5)
                .map(|h| (h.actor.as_str(), h.joint.as_str())),
            Some(("ann", "r_wrist"))
        );
        assert_eq!(
            parse_trk_file(&format_trk_file(&file), "again").unwrap(),
            file
        );
        // Readers of sequences only see the actors, and refuse a file of objects only.
        assert_eq!(parse_trk(WITH_OBJECT, "rec.trk").unwrap(), file.sequences);
        let objects_only =
            WITH_OBJECT.replace("sequence ann\ntrack r_elbow_flexion\n0 0\n1 1\nend\n", "");
        assert_eq!(
            parse_trk_file(&objects_only, "o.trk").unwrap().objects,
            file.objects
        );
        assert_parse_error(
            parse_trk(&objects_only, "o.trk"),
            &objects_only,
            "o.trk",
            1,
            "objects only",
        );
        // Every shape round-trips.
        for shape in [
            Shape::Box {
                half_extents: DVec3::new(0.1, 0.2, 0.3),
            },
            Shape::Sphere { radius: 0.2 },
            Shape::Frustum {
                bottom_radius: 0.03,
                top_radius: 0.04,
                height: 0.1,
            },
            Shape::Ellipsoid {
                radii: DVec3::new(0.1, 0.2, 0.3),
            },
        ] {
            assert_eq!(parse_shape(&format_shape(&shape)), Ok(shape));
        }
    }

    #[test]
    fn bad_objects_are_errors_naming_the_line() {
        let cases = [
            (
                WITH_OBJECT.replace("shape cylinder 0.04 0.1", "shape cylinder 0.04"),
                8,
                "expected `shape box",
            ),
            (
                WITH_OBJECT.replace("shape cylinder 0.04 0.1", "shape cone 1 2"),
                8,
                "found `shape cone",
            ),
            (
                WITH_OBJECT.replace("0.04 0.1", "-0.04 0.1"),
                8,
                "must be > 0",
            ),
            (WITH_OBJECT.replace("mass 0.3", "mass 0"), 9, "must be > 0"),
            (
                WITH_OBJECT.replace("mass 0.3\n", ""),
                7,
                "needs a `shape` and a `mass`",
            ),
            (
                WITH_OBJECT.replace("track qw linear\n0 1\nend\n", ""),
                7,
                "no `qw` track",
            ),
            (
                WITH_OBJECT.replace("held 0.25 1 ann r_wrist", "held 1 0.25 ann r_wrist"),
                32,
                "before the start",
            ),
            (
                WITH_OBJECT.replace("held 0.25 1 ann r_wrist", "held 0.25 ann"),
                32,
                "held FROM TO ACTOR JOINT",
            ),
            (
                WITH_OBJECT.replace("mass 0.3", "meta a b"),
                9,
                "belongs to a sequence",
            ),
            (
                WITH_OBJECT.replace("troupe-trk 2", "troupe-trk 1"),
                7,
                "unexpected `object`",
            ),
            (
                "troupe-trk 2\nsequence a\nmass 1\n".to_string(),
                3,
                "belongs to an `object` block",
            ),
        ];
        for (text, line, needle) in cases {
            assert_parse_error(parse_trk_file(&text, "f.trk"), &text, "f.trk", line, needle);
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

    /// A recording whose names are not plain words: spaces, `#`, a name with spaces at
    /// its ends beside the same name without, accents, quotes.
    fn odd_names() -> TrkFile {
        let mut file = parse_trk_file(WITH_OBJECT, "rec.trk").unwrap();
        let ann = file.sequences[0].clone();
        file.sequences.clear();
        for name in ["Ann Lee", "take#2", " lead ", "lead", "say \"hi\"", "", "é"] {
            let mut seq = ann.clone();
            seq.name = name.into();
            file.sequences.push(seq);
        }
        file.sequences[0]
            .meta
            .insert("retarget_map".into(), "/maps/take#2.map".into());
        file.sequences[0].meta.insert("empty".into(), String::new());
        file.sequences[0]
            .meta
            .insert("source".into(), "troupe run".into());
        file.sequences[0]
            .meta
            .insert("two words".into(), " spaced ".into());
        let cup = file.objects[0].clone();
        file.objects.clear();
        for (name, holder) in [("cup é", "Ann Lee"), ("my cup", "take#2"), ("#", " lead ")] {
            let mut object = cup.clone();
            object.name = name.into();
            object.pose.name = name.into();
            object.holds[0].actor = holder.into();
            file.objects.push(object);
        }
        file
    }

    #[test]
    fn names_that_are_not_plain_words_are_quoted_and_read_back() {
        let file = odd_names();
        let text = format_trk_file(&file);
        assert_eq!(parse_trk_file(&text, "odd.trk").unwrap(), file, "{text}");
        for line in [
            "sequence \"Ann Lee\"\n",
            "sequence \"take#2\"\n",
            "sequence \" lead \"\n",
            "sequence lead\n",
            "sequence \"say \\\"hi\\\"\"\n",
            "sequence \"\"\n",
            "sequence é\n",
            "meta retarget_map \"/maps/take#2.map\"\n",
            "meta empty \"\"\n",
            "meta \"two words\" \" spaced \"\n",
            "meta source troupe run\n",
            "object \"cup é\"\n",
            "object \"#\"\n",
            "held 0.25 1 \"Ann Lee\" r_wrist\n",
            "held 0.25 1 \"take#2\" r_wrist\n",
        ] {
            assert!(text.contains(line), "no {line:?} in\n{text}");
        }
        // Plain names are written as before.
        assert_eq!(
            format_trk_file(&parse_trk_file(WITH_OBJECT, "rec.trk").unwrap()),
            WITH_OBJECT
        );
    }

    #[test]
    fn older_files_read_as_they_did() {
        // Written before names were quoted: a sequence name and a meta value are the rest
        // of their line, spaces inside kept; a quote inside a word is a character.
        let old = "troupe-trk 2\nsequence Ann  Lee # the actor\nmeta source troupe run\n\
                   meta map a\"b c\ntrack r_elbow_flexion\n0 0\nend\n";
        let set = parse_trk(old, "old.trk").unwrap();
        assert_eq!(set[0].name, "Ann  Lee");
        // An object's name too (older builds wrote it so, and could not read it back).
        let old_object = WITH_OBJECT.replace("object cup", "object cup é # the cup");
        let objects = parse_trk_file(&old_object, "old.trk").unwrap().objects;
        assert_eq!(objects[0].name, "cup é");
        assert_eq!(set[0].meta["source"], "troupe run");
        assert_eq!(set[0].meta["map"], "a\"b c");
        assert_eq!(parse_trk(&format_trk(&set), "again").unwrap(), set);
    }

    #[test]
    fn two_sequences_or_objects_of_one_name_are_not_written() {
        let dir = std::env::temp_dir().join(format!("troupe-trk-names-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("twice.trk");
        let mut file = odd_names();
        file.sequences[1].name = "Ann Lee".into();
        let err = write_trk(&path, &file.sequences).unwrap_err().to_string();
        assert!(err.contains("two sequences named `Ann Lee`"), "{err}");
        let err = write_trk_file(&path, &file).unwrap_err().to_string();
        assert!(err.contains("two sequences named `Ann Lee`"), "{err}");
        file = odd_names();
        file.objects[2].name = "my cup".into();
        let err = write_trk_file(&path, &file).unwrap_err().to_string();
        assert!(err.contains("two objects named `my cup`"), "{err}");
        assert!(!path.exists());
        // A sequence and an object may share a name.
        file.objects[2].name = "Ann Lee".into();
        file.objects[2].pose.name = "Ann Lee".into();
        write_trk_file(&path, &file).unwrap();
        assert_eq!(read_trk_file(&path).unwrap(), file);
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn a_byte_order_mark_is_no_part_of_the_header() {
        let set = parse_trk(&format!("\u{feff}{WAVE}"), "bom.trk").unwrap();
        assert_eq!(set, parse_trk(WAVE, "wave.trk").unwrap());
    }

    #[test]
    fn a_name_twice_or_a_bad_quote_is_an_error_naming_the_line() {
        let two = "troupe-trk 2\nsequence a\ntrack x\n0 0\nend\nsequence \"b\"\nsequence \"a\"\n";
        assert_parse_error(
            parse_trk(two, "f.trk"),
            two,
            "f.trk",
            7,
            "second sequence named `a` (the first: line 2)",
        );
        let unnamed = "troupe-trk 2\ntrack x\n0 0\nend\nsequence \"\"\n";
        assert_parse_error(
            parse_trk(unnamed, "f.trk"),
            unnamed,
            "f.trk",
            5,
            "the unnamed sequence before",
        );
        // An actor and an object may share a name; two objects may not.
        let text = format_trk_file(&odd_names());
        let objects = text.replace("object \"#\"", "object \"my cup\"");
        let line = objects
            .lines()
            .position(|l| l == "object \"my cup\"")
            .unwrap()
            + 1;
        let at = objects[..]
            .lines()
            .skip(line)
            .position(|l| l == "object \"my cup\"")
            .unwrap()
            + line
            + 1;
        assert_parse_error(
            parse_trk_file(&objects, "f.trk"),
            &objects,
            "f.trk",
            at,
            &format!("second object named `my cup` (the first: line {line})"),
        );
        let cases = [
            ("troupe-trk 2\nsequence \"Ann\n", 2, "not closed"),
            ("troupe-trk 2\nsequence \"Ann\" Lee\n", 2, "more follows"),
            ("troupe-trk 2\nsequence \"a\\qb\"\n", 2, "unknown escape"),
            (
                "troupe-trk 2\ntrack \"x\"y\n",
                2,
                "space after the closing quote",
            ),
            (
                &*WITH_OBJECT.replace("object cup", "object"),
                7,
                "expected `object NAME`",
            ),
        ];
        for (text, line, needle) in cases {
            assert_parse_error(parse_trk_file(text, "f.trk"), text, "f.trk", line, needle);
        }
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
