//! Reading motion back from glTF 2.0 with the `gltf` crate: the first animation of a
//! `.gltf` or `.glb` whose nodes carry troupe joint names (as `--record OUT.gltf` and
//! `troupe seq convert … OUT.gltf --template` write them) becomes a troupe [`Sequence`]
//! for a given skeleton.
//!
//! Each joint's animated local rotation is turned back into the angles of its DOFs by a
//! small least-squares solve (exact when the rotation is one the DOF axes can make); the
//! root's animated translation gives `root_x/y/z`, scaled by the ratio of the skeleton's
//! root height to the file's (its root node's rest translation), as a troupe BVH's is: a
//! recording of a child played on an adult keeps its feet on the floor, and on the body it
//! was recorded from it replays exactly. [`recorded_body`] finds that body from the
//! nodes' rest translations. Buffers may be external files, base64
//! `data:` URIs or the binary chunk of a `.glb`; channels are read from tightly packed
//! 32-bit float accessors (what troupe writes), and everything else is refused with a
//! message naming the file and what was wrong. A file of a user's character (what
//! `--record` writes for an actor dressed in one) is refused too: its bones are the
//! character's, not troupe's joints.

use super::uri;
use crate::error::{Error, Result};
use ::gltf::accessor::{DataType, Dimensions};
use ::gltf::animation::{Interpolation, Property};
use ::gltf::buffer::Source;
use ::gltf::{Accessor, Gltf};
use base64::Engine as _;
use glam::{DQuat, DVec3};
use std::path::{Path, PathBuf};
use troupe_body::kinematics::solve_joint_angles;
use troupe_body::skeleton::{DofKind, Skeleton};
use troupe_motion::sequence::{Key, Sequence, Track};

/// Bytes of a binary glTF header: magic, version and total length.
const GLB_HEADER: usize = 12;

/// The file a user's character came from, when the document is one troupe wrote of an
/// actor dressed in it (a node's `extras` mark it, see [`super::character`]).
fn character_source(gltf: &Gltf) -> Option<String> {
    gltf.document.as_json().nodes.iter().find_map(|node| {
        let extras: serde_json::Value = serde_json::from_str(node.extras.as_ref()?.get()).ok()?;
        let character = extras.get(super::character::CHARACTER_EXTRAS)?;
        Some(character["source"].as_str().unwrap_or("?").to_string())
    })
}

/// A glTF file (`.gltf` or `.glb`) read and parsed once, to ask both the body it was
/// recorded from and its motion (buffer files beside it are read by
/// [`GltfFile::motion`]).
pub struct GltfFile {
    path: PathBuf,
    gltf: Gltf,
}

impl GltfFile {
    /// Reads and parses `path`; errors name the file and what was wrong.
    pub fn read(path: impl AsRef<Path>) -> Result<GltfFile> {
        let path = path.as_ref();
        let file = path.display().to_string();
        let bad = |line: usize, message: String| Error::Parse {
            file: file.clone(),
            line,
            message,
        };
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        check_glb_header(&bytes).map_err(|m| bad(1, m))?;
        let gltf = Gltf::from_slice(&bytes).map_err(|e| match e {
            ::gltf::Error::Deserialize(e) => bad(e.line().max(1), format!("not glTF JSON: {e}")),
            other => bad(1, format!("not valid glTF: {other}")),
        })?;
        Ok(GltfFile {
            path: path.to_path_buf(),
            gltf,
        })
    }

    /// The template and standing height of the troupe body the file was written from, as
    /// [`recorded_body`] finds them.
    pub fn recorded_body(&self) -> Option<(String, f64)> {
        if character_source(&self.gltf).is_some() {
            return None;
        }
        let rest: std::collections::HashMap<&str, DVec3> = self
            .gltf
            .nodes()
            .filter_map(|n| {
                let [x, y, z] = n.transform().decomposed().0;
                Some((n.name()?, DVec3::new(x as f64, y as f64, z as f64)))
            })
            .collect();
        troupe_body::template::templates()
            .into_iter()
            .find_map(|t| {
                let at_default = t.instantiate(t.default_params()).ok()?;
                let root = rest.get(at_default.joints().first()?.name.as_str())?;
                let height = t.default_height * root.y / at_default.joints()[0].offset.y;
                let mut params = t.default_params();
                params.height = height;
                let body = t.instantiate(params).ok()?;
                let same = body.joints().iter().all(|j| {
                    rest.get(j.name.as_str()).is_some_and(|r| {
                        (*r - j.offset).length() < 1e-5 * (1.0 + j.offset.length())
                    })
                });
                same.then(|| (t.name.to_string(), height))
            })
    }

    /// The first animation as a sequence for `skeleton`, as [`read_gltf_motion`] reads it.
    pub fn motion(&self, skeleton: &Skeleton) -> Result<Sequence> {
        let (path, gltf) = (self.path.as_path(), &self.gltf);
        let file = path.display().to_string();
        let bad = |message: String| Error::Parse {
            file: file.clone(),
            line: 1,
            message,
        };
        if let Some(source) = character_source(gltf) {
            return Err(bad(format!(
                "it holds a user's character ({source}) moved by its own bones, not troupe's \
                 joints: play the run's .trk recording instead"
            )));
        }
        let buffers = load_buffers(gltf, path, &bad)?;

        let animation = gltf
            .animations()
            .next()
            .ok_or_else(|| bad("the file has no animation".into()))?;
        let mut rotations: Vec<(usize, Vec<f32>, Vec<f32>)> = Vec::new();
        let mut translation: Option<(Vec<f32>, Vec<f32>)> = None;
        for (c, channel) in animation.channels().enumerate() {
            let node = channel.target().node();
            let Some(name) = node.name() else {
                return Err(bad(format!(
                    "animation channel {c}: target node {} has no name",
                    node.index()
                )));
            };
            let Ok(joint) = skeleton.joint(name) else {
                continue;
            };
            let sampler = channel.sampler();
            if sampler.interpolation() == Interpolation::CubicSpline {
                return Err(bad(format!(
                "animation channel {c}: CUBICSPLINE samplers are not supported (LINEAR or STEP)"
            )));
            }
            let input = floats(sampler.input(), Dimensions::Scalar, &buffers, &bad)?;
            match channel.target().property() {
                Property::Rotation => {
                    let output = floats(sampler.output(), Dimensions::Vec4, &buffers, &bad)?;
                    // glTF asks for unit quaternions; one that is not finite, or nearly zero,
                    // has no rotation to read (it was patched over silently).
                    if let Some(k) = output.chunks(4).position(|q| {
                        let n = q.iter().map(|&x| (x as f64) * (x as f64)).sum::<f64>();
                        !(n.is_finite() && n > 1e-6)
                    }) {
                        let q = &output[4 * k..4 * k + 4];
                        return Err(bad(format!(
                        "animation channel {c} (`{name}` rotation), key {k}: {q:?} is not a rotation \
                         (glTF asks for unit quaternions)"
                    )));
                    }
                    rotations.push((joint, input, output))
                }
                Property::Translation if joint == 0 => {
                    translation = Some((
                        input,
                        floats(sampler.output(), Dimensions::Vec3, &buffers, &bad)?,
                    ))
                }
                _ => {}
            }
        }
        // The root's translation is the recorded body's: scaled to this one's (see the module
        // documentation).
        let playing_root = skeleton.joints()[0].offset;
        let recorded_root = gltf
            .nodes()
            .find(|n| n.name() == Some(skeleton.joints()[0].name.as_str()))
            .map(|n| n.transform().decomposed().0[1] as f64)
            .unwrap_or(playing_root.y);
        let scale = if recorded_root > 1e-9 && playing_root.y > 1e-9 {
            playing_root.y / recorded_root
        } else {
            1.0
        };
        if rotations.is_empty() && translation.is_none() {
            return Err(bad(format!(
            "no animation channel targets a joint of the `{}` skeleton (node names must be troupe joint names)",
            skeleton.name()
        )));
        }
        // Sample every channel at the times of the longest input.
        let times: Vec<f64> = rotations
            .iter()
            .map(|(_, t, _)| t)
            .chain(translation.as_ref().map(|(t, _)| t))
            .max_by_key(|t| t.len())
            .map(|t| t.iter().map(|&x| x as f64).collect())
            .unwrap_or_default();
        if times.windows(2).any(|w| w[1] <= w[0]) || times.iter().any(|t| !t.is_finite()) {
            return Err(bad("animation times must be finite and increasing".into()));
        }

        let n = skeleton.dof_count();
        let mut q = vec![0.0; n];
        let mut values: Vec<Vec<f64>> = vec![Vec::with_capacity(times.len()); n];
        let mut driven = vec![false; n];
        for &t in &times {
            for (joint, input, output) in &rotations {
                let r = sample_quat(input, output, t);
                solve_joint_angles(skeleton, *joint, r, &mut q);
                for d in skeleton.joints()[*joint].dofs.clone() {
                    driven[d] |= skeleton.dofs()[d].kind == DofKind::Rotation;
                }
            }
            if let Some((input, output)) = &translation {
                let local = sample_vec3(input, output, t) * scale - playing_root;
                for d in skeleton.joints()[0].dofs.clone() {
                    let dof = &skeleton.dofs()[d];
                    if dof.kind == DofKind::Translation {
                        q[d] = local.dot(dof.axis);
                        driven[d] = true;
                    }
                }
            }
            for (d, v) in q.iter().enumerate() {
                values[d].push(*v);
            }
        }
        // Named as troupe names its animation: after the actor recorded (`run --record`),
        // else the file.
        let name = match animation.name().filter(|n| !n.is_empty()) {
            Some(name) => name.to_string(),
            None => path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
        };
        let mut seq = Sequence::new(name);
        seq.meta.insert("source".into(), file.clone());
        if times.len() > 1 {
            let rate = (times.len() - 1) as f64 / (times[times.len() - 1] - times[0]);
            seq.meta.insert("rate".into(), format!("{}", rate.round()));
        }
        for d in (0..n).filter(|&d| driven[d]) {
            let keys = times
                .iter()
                .zip(&values[d])
                .map(|(&t, &v)| Key::new(t, v))
                .collect();
            seq.add_track(Track::new(skeleton.dofs()[d].name.clone(), keys)?)?;
        }
        Ok(seq)
    }
}

/// Reads the first animation of a glTF file (`.gltf` or `.glb`) as a sequence for
/// `skeleton`.
pub fn read_gltf_motion(path: impl AsRef<Path>, skeleton: &Skeleton) -> Result<Sequence> {
    GltfFile::read(path)?.motion(skeleton)
}

/// The template and standing height of the troupe body a glTF file was written from: the
/// template (at the height its root node's rest translation gives) whose joints' offsets
/// all match the nodes' rest translations of the same names (within glTF's f32 precision).
/// `None` for a file of any other skeleton, or of a user's character.
pub fn recorded_body(path: impl AsRef<Path>) -> Result<Option<(String, f64)>> {
    Ok(GltfFile::read(path)?.recorded_body())
}

/// Refuses a binary glTF whose header is cut short or declares a total length shorter
/// than itself, which `gltf` would otherwise subtract past zero.
pub(crate) fn check_glb_header(bytes: &[u8]) -> std::result::Result<(), String> {
    if !bytes.starts_with(b"glTF") {
        return Ok(());
    }
    let Some(length) = bytes.get(8..GLB_HEADER) else {
        return Err(format!(
            "truncated binary glTF: {} bytes, shorter than its {GLB_HEADER}-byte header",
            bytes.len()
        ));
    };
    let declared = u32::from_le_bytes([length[0], length[1], length[2], length[3]]) as usize;
    if declared < GLB_HEADER {
        return Err(format!(
            "binary glTF header declares {declared} bytes, shorter than the header itself"
        ));
    }
    Ok(())
}

/// The bytes of every buffer of `gltf`: the `.glb` binary chunk, a base64 `data:` URI,
/// or a file beside `path` (its URI percent-decoded).
pub(crate) fn load_buffers(
    gltf: &Gltf,
    path: &Path,
    bad: &dyn Fn(String) -> Error,
) -> Result<Vec<Vec<u8>>> {
    let dir = path.parent().unwrap_or(Path::new("."));
    gltf.buffers()
        .map(|buffer| match buffer.source() {
            Source::Bin => gltf.blob.clone().ok_or_else(|| {
                bad(format!(
                    "buffer {} is the binary chunk, but the file has none",
                    buffer.index()
                ))
            }),
            Source::Uri(uri) if uri.starts_with("data:") => {
                decode_data_uri(uri).map_err(|why| bad(format!("buffer {}: {why}", buffer.index())))
            }
            Source::Uri(written) => {
                // Percent-decoded, as RFC 3986 asks; as written when that names no file
                // and the URI as written does (a file troupe wrote before it encoded
                // names, or a loose writer's `50%.bin`).
                let verbatim = dir.join(written);
                let file = match uri::decode(written) {
                    Ok(name) if dir.join(&name).exists() || !verbatim.exists() => dir.join(name),
                    _ => verbatim,
                };
                std::fs::read(&file).map_err(|e| Error::io(&file, e))
            }
        })
        .collect()
}

/// The bytes of a `data:[MEDIA-TYPE];base64,PAYLOAD` URI.
fn decode_data_uri(uri: &str) -> std::result::Result<Vec<u8>, String> {
    let (header, payload) = uri
        .split_once(',')
        .ok_or("a data URI without a `,` before its data")?;
    if !header.ends_with(";base64") {
        return Err("a data URI that is not base64 (`data:…;base64,…`)".into());
    }
    base64::engine::general_purpose::STANDARD
        .decode(payload)
        .map_err(|e| format!("a data URI that is not valid base64: {e}"))
}

/// The values of a tightly packed accessor of 32-bit floats with `dims` components,
/// checking every size against the buffer (a bad file is an error, never a panic).
fn floats(
    accessor: Accessor<'_>,
    dims: Dimensions,
    buffers: &[Vec<u8>],
    bad: &dyn Fn(String) -> Error,
) -> Result<Vec<f32>> {
    let i = accessor.index();
    let kind = match dims {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec3 => "VEC3",
        _ => "VEC4",
    };
    if accessor.data_type() != DataType::F32 || accessor.dimensions() != dims {
        return Err(bad(format!(
            "accessor {i}: expected {kind} of 32-bit floats"
        )));
    }
    if accessor.sparse().is_some() {
        return Err(bad(format!(
            "accessor {i}: sparse accessors are not supported"
        )));
    }
    let view = accessor
        .view()
        .ok_or_else(|| bad(format!("accessor {i}: no buffer view")))?;
    let size = 4 * dims.multiplicity();
    if view.stride().unwrap_or(size) != size {
        return Err(bad(format!(
            "accessor {i}: interleaved buffer views are not supported"
        )));
    }
    let data = &buffers[view.buffer().index()];
    let count = accessor.count();
    let start = view.offset().checked_add(accessor.offset());
    let range = start
        .zip(count.checked_mul(size))
        .and_then(|(s, len)| Some(s..s.checked_add(len)?))
        .filter(|r| r.end <= data.len());
    let range = range.ok_or_else(|| {
        bad(format!(
            "accessor {i}: {count} × {kind} does not fit in the buffer"
        ))
    })?;
    Ok(data[range]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect())
}

/// The segment of `input` holding `t` and the fraction along it (clamped at the ends).
fn locate(input: &[f32], t: f64) -> (usize, usize, f64) {
    let n = input.len();
    if n < 2 || t <= input[0] as f64 {
        return (0, 0, 0.0);
    }
    if t >= input[n - 1] as f64 {
        return (n - 1, n - 1, 0.0);
    }
    let i = input.partition_point(|&x| (x as f64) <= t) - 1;
    let span = (input[i + 1] - input[i]) as f64;
    (
        i,
        i + 1,
        if span > 0.0 {
            (t - input[i] as f64) / span
        } else {
            0.0
        },
    )
}

fn sample_quat(input: &[f32], output: &[f32], t: f64) -> DQuat {
    let get = |k: usize| {
        let o = &output[(4 * k).min(output.len().saturating_sub(4))..];
        DQuat::from_xyzw(o[0] as f64, o[1] as f64, o[2] as f64, o[3] as f64).normalize()
    };
    let (a, b, f) = locate(input, t);
    get(a).slerp(get(b), f)
}

fn sample_vec3(input: &[f32], output: &[f32], t: f64) -> DVec3 {
    let get = |k: usize| {
        let o = &output[(3 * k).min(output.len().saturating_sub(3))..];
        DVec3::new(o[0] as f64, o[1] as f64, o[2] as f64)
    };
    let (a, b, f) = locate(input, t);
    get(a).lerp(get(b), f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gltf::{write_glb, write_gltf};
    use crate::rig::tests::{adult, every_dof_moving, fk_positions, posture};
    use crate::rig::Rig;
    use serde_json::Value;
    use std::path::PathBuf;

    /// A fresh scratch directory for one test.
    fn scratch(name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("troupe-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Checks that `back` replays `seq` on `skel` within glTF's precision.
    fn same_postures(skel: &Skeleton, seq: &Sequence, back: &Sequence) {
        for time in [0.0, 0.5, 1.2] {
            let a = fk_positions(skel, &posture(skel, seq, time));
            let b = fk_positions(skel, &posture(skel, back, time));
            for (j, (x, y)) in a.iter().zip(&b).enumerate() {
                // f32 storage in glTF and linear resampling bound the error.
                assert!(
                    (*x - *y).length() < 2e-3,
                    "t={time} {}: {x} vs {y}",
                    skel.joints()[j].name
                );
            }
        }
    }

    #[test]
    fn gltf_glb_and_data_uri_files_read_back_to_the_same_positions() {
        let skel = adult();
        let seq = every_dof_moving(&skel, 4, 0.5, "30");
        let rig = Rig::from_sequence(&skel, &seq).unwrap();
        let dir = scratch("gltf-read");
        let gltf = dir.join("motion.gltf");
        write_gltf(&gltf, &rig, "motion").unwrap();
        same_postures(&skel, &seq, &read_gltf_motion(&gltf, &skel).unwrap());

        let glb = dir.join("motion.glb");
        write_glb(&glb, &rig, "motion").unwrap();
        let back = read_gltf_motion(&glb, &skel).unwrap();
        same_postures(&skel, &seq, &back);
        // The same document and buffer, so the same keys, whichever container held them.
        assert!(back.tracks() == read_gltf_motion(&gltf, &skel).unwrap().tracks());

        // The same document with its buffer embedded as a data URI.
        let bin = std::fs::read(dir.join("motion.bin")).unwrap();
        let mut doc: Value = serde_json::from_slice(&std::fs::read(&gltf).unwrap()).unwrap();
        doc["buffers"][0]["uri"] = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&bin)
        )
        .into();
        let embedded = dir.join("embedded.gltf");
        std::fs::write(&embedded, doc.to_string()).unwrap();
        same_postures(&skel, &seq, &read_gltf_motion(&embedded, &skel).unwrap());
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn a_recording_read_onto_another_body_keeps_its_feet_on_the_floor_and_tells_its_body() {
        let child = {
            let t = troupe_body::template::template("child").unwrap();
            let mut params = t.default_params();
            params.height = 1.4;
            t.instantiate(params).unwrap()
        };
        let mut seq = Sequence::new("kid");
        seq.meta.insert("rate".into(), "10".into());
        for (dof, a, b) in [
            ("root_x", 0.0, 1.0),
            ("root_y", 0.0, -0.05),
            ("root_z", 0.0, 0.4),
        ] {
            seq.add_track(Track::new(dof, vec![Key::new(0.0, a), Key::new(1.0, b)]).unwrap())
                .unwrap();
        }
        let dir = scratch("gltf-body");
        let glb = dir.join("kid.glb");
        write_glb(&glb, &Rig::from_sequence(&child, &seq).unwrap(), "kid").unwrap();
        let (template, height) = recorded_body(&glb).unwrap().unwrap();
        assert_eq!(template, "child");
        assert!((height - 1.4).abs() < 1e-4, "{height}");
        assert_eq!(recorded_body(dir.join("missing.glb")).ok(), None);
        // On the body it was recorded from, the root's DOFs come back as they were.
        let same = read_gltf_motion(&glb, &child).unwrap();
        for (dof, want) in [("root_x", 1.0), ("root_y", -0.05), ("root_z", 0.4)] {
            let got = same.track(dof).unwrap().value(1.0);
            assert!((got - want).abs() < 1e-5, "{dof}: {got} against {want}");
        }
        // On the default adult, scaled by the two roots' heights: the root stands as high
        // over the floor, in proportion, and travels as far in strides (it once sank 25 cm).
        let grown = read_gltf_motion(&glb, &adult()).unwrap();
        let ratio = adult().joints()[0].offset.y / child.joints()[0].offset.y;
        for (dof, want) in [
            ("root_x", ratio),
            ("root_y", -0.05 * ratio),
            ("root_z", 0.4 * ratio),
        ] {
            let got = grown.track(dof).unwrap().value(1.0);
            assert!((got - want).abs() < 1e-5, "{dof}: {got} against {want}");
        }
        assert!(grown.track("root_y").unwrap().value(0.0).abs() < 1e-5);
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn buffer_file_names_are_percent_encoded_and_read_back() {
        let skel = adult();
        let seq = every_dof_moving(&skel, 3, 0.5, "10");
        let rig = Rig::from_sequence(&skel, &seq).unwrap();
        let dir = scratch("gltf-uri");
        for (stem, uri) in [
            ("G%20v1", "G%2520v1.bin"),
            ("G.take#2", "G.take%232.bin"),
            ("cup é", "cup%20%C3%A9.bin"),
        ] {
            let gltf = dir.join(format!("{stem}.gltf"));
            write_gltf(&gltf, &rig, stem).unwrap();
            assert!(dir.join(format!("{stem}.bin")).is_file());
            let doc: Value = serde_json::from_slice(&std::fs::read(&gltf).unwrap()).unwrap();
            assert_eq!(doc["buffers"][0]["uri"], uri);
            same_postures(&skel, &seq, &read_gltf_motion(&gltf, &skel).unwrap());
        }
        // Written before names were encoded, a URI names its file as written.
        let mut doc: Value =
            serde_json::from_slice(&std::fs::read(dir.join("G%20v1.gltf")).unwrap()).unwrap();
        doc["buffers"][0]["uri"] = "G%20v1.bin".into();
        let old = dir.join("old.gltf");
        std::fs::write(&old, doc.to_string()).unwrap();
        same_postures(&skel, &seq, &read_gltf_motion(&old, &skel).unwrap());
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn bad_files_are_errors_that_name_the_file_never_panics() {
        let skel = adult();
        let rig = Rig::from_sequence(&skel, &every_dof_moving(&skel, 3, 0.5, "10")).unwrap();
        let dir = scratch("gltf-bad");
        let glb = dir.join("motion.glb");
        write_glb(&glb, &rig, "motion").unwrap();
        let bytes = std::fs::read(&glb).unwrap();
        let gltf = dir.join("motion.gltf");
        write_gltf(&gltf, &rig, "motion").unwrap();
        let mut doc: Value = serde_json::from_slice(&std::fs::read(&gltf).unwrap()).unwrap();
        let with_uri = |uri: &str| {
            let mut d = doc.clone();
            d["buffers"][0]["uri"] = uri.into();
            d.to_string().into_bytes()
        };
        std::fs::write(dir.join("short.bin"), [0u8; 3]).unwrap();
        let mut tiny_header = bytes[..20].to_vec();
        tiny_header[8..12].copy_from_slice(&4u32.to_le_bytes());
        let cases: Vec<(&str, Vec<u8>, &str)> = vec![
            ("garbage.gltf", b"{ not json".to_vec(), "not glTF JSON"),
            ("garbage.glb", vec![0xff; 64], "not glTF JSON"),
            (
                "cut.glb",
                bytes[..bytes.len() / 2].to_vec(),
                "not valid glTF",
            ),
            ("header.glb", bytes[..7].to_vec(), "truncated binary glTF"),
            ("tiny.glb", tiny_header, "shorter than the header"),
            ("short.gltf", with_uri("short.bin"), "does not fit"),
            ("text.gltf", with_uri("data:text/plain,hello"), "not base64"),
            ("b64.gltf", with_uri("data:;base64,@@@"), "not valid base64"),
            ("empty.gltf", Vec::new(), "not glTF JSON"),
        ];
        for (name, content, needle) in cases {
            let file = dir.join(name);
            std::fs::write(&file, content).unwrap();
            match read_gltf_motion(&file, &skel) {
                Err(Error::Parse {
                    file: f, message, ..
                }) => {
                    assert_eq!(f, file.display().to_string());
                    assert!(message.contains(needle), "{name}: {message}");
                }
                other => panic!("{name}: {other:?}"),
            }
        }
        // A buffer file that is missing names that file.
        std::fs::write(dir.join("lost.gltf"), with_uri("lost.bin")).unwrap();
        let err = read_gltf_motion(dir.join("lost.gltf"), &skel).unwrap_err();
        assert!(err.to_string().contains("lost.bin"), "{err}");
        // A rotation key that is not a rotation (NaN, zero) is refused, naming where.
        let channel = doc["animations"][0]["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["target"]["path"] == "rotation")
            .unwrap()
            .clone();
        let sampler =
            &doc["animations"][0]["samplers"][channel["sampler"].as_u64().unwrap() as usize];
        let accessor = &doc["accessors"][sampler["output"].as_u64().unwrap() as usize];
        let view = &doc["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
        let at = (view["byteOffset"].as_u64().unwrap_or(0)
            + accessor["byteOffset"].as_u64().unwrap_or(0)) as usize
            + 16; // the second key
        let bin = std::fs::read(dir.join("motion.bin")).unwrap();
        for (name, key) in [("nan", [f32::NAN, 0.0, 0.0, 1.0]), ("zero", [0.0f32; 4])] {
            let mut patched = bin.clone();
            for (i, x) in key.iter().enumerate() {
                patched[at + 4 * i..at + 4 * i + 4].copy_from_slice(&x.to_le_bytes());
            }
            std::fs::write(dir.join(format!("{name}.bin")), patched).unwrap();
            let file = dir.join(format!("{name}.gltf"));
            std::fs::write(&file, with_uri(&format!("{name}.bin"))).unwrap();
            let err = read_gltf_motion(&file, &skel).unwrap_err().to_string();
            assert!(
                err.contains("rotation), key 1:") && err.contains("is not a rotation"),
                "{name}: {err}"
            );
        }
        // Nodes that are not troupe joints.
        for node in doc["nodes"].as_array_mut().unwrap() {
            node["name"] = "elsewhere".into();
        }
        std::fs::write(dir.join("other.gltf"), doc.to_string()).unwrap();
        let err = read_gltf_motion(dir.join("other.gltf"), &skel).unwrap_err();
        assert!(err.to_string().contains("troupe joint names"), "{err}");
        std::fs::remove_dir_all(dir).ok();
    }
}
