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
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.split('#').next().unwrap_or("").trim()))
        .filter(|(_, l)| !l.is_empty());

    let (n, header) = lines.next().ok_or_else(|| {
        err(
            1,
            format!("empty file: expected `troupe-trk {TRK_VERSION}`"),
        )
    })?;
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
            "sequence" => {
                close(current.take(), &mut out)?;
                current = Some(Block::Sequence(Sequence::new(rest)));
            }
            "object" if version >= 2 => {
                if rest.is_empty() || rest.contains(char::is_whitespace) {
                    return Err(err(n, format!("expected `object NAME`, found `{line}`")));
                }
                close(current.take(), &mut out)?;
                current = Some(Block::Object(ObjectDraft {
                    line: n,
                    shape: None,
                    mass: None,
                    pose: Sequence::new(rest),
                    holds: Vec::new(),
                }));
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
                let (key, value) = rest
                    .split_once(char::is_whitespace)
                    .ok_or_else(|| err(n, "expected `meta KEY VALUE`".into()))?;
                sequence_of(&mut current)
                    .meta
                    .insert(key.to_string(), value.trim().to_string());
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
    let words: Vec<&str> = rest.split_whitespace().collect();
    let [from, to, actor, joint] = words[..] else {
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
        actor: actor.into(),
        joint: joint.into(),
    })
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
        format_tracks(&mut out, seq);
    }
    out
}

/// Writes sequences and objects as `.trk` text.
pub fn format_trk_file(file: &TrkFile) -> String {
    let mut out = format_trk(&file.sequences);
    for object in &file.objects {
        let _ = writeln!(out, "object {}", object.name);
        let _ = writeln!(out, "shape {}", format_shape(&object.shape));
        let _ = writeln!(out, "mass {}", object.mass);
        format_tracks(&mut out, &object.pose);
        for h in &object.holds {
            let _ = writeln!(out, "held {} {} {} {}", h.from, h.to, h.actor, h.joint);
        }
    }
    out
}

/// The `track … end` blocks of `seq`.
fn format_tracks(out: &mut String, seq: &Sequence) {
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

/// Writes a whole file (sequences and objects) to `path`.
pub fn write_trk_file(path: impl AsRef<Path>, file: &TrkFile) -> Result<()> {
    let path = path.as_ref();
    std::fs::write(path, format_trk_file(file)).map_err(|e| Error::io(path, e))
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
