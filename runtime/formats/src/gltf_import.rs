//! Reading motion back from glTF 2.0: the animation of a `.gltf` whose nodes carry troupe
//! joint names (as `--record OUT.gltf` and `troupe seq convert … OUT.gltf --template`
//! write them) becomes a troupe [`Sequence`] for a given skeleton.
//!
//! Each joint's animated local rotation is turned back into the angles of its DOFs by a
//! small least-squares solve (exact when the rotation is one the DOF axes can make); the
//! root's animated translation gives `root_x/y/z`. Only float accessors in an external
//! `.bin` buffer are read (what troupe writes); `.glb` and embedded data URIs are refused
//! with a message saying so.

use crate::error::{Error, Result};
use glam::{DQuat, DVec3};
use serde_json::Value;
use std::path::Path;
use troupe_body::kinematics::solve_joint_angles;
use troupe_body::skeleton::{DofKind, Skeleton};
use troupe_motion::sequence::{Key, Sequence, Track};

/// Reads the first animation of a glTF file as a sequence for `skeleton`.
pub fn read_gltf_motion(path: impl AsRef<Path>, skeleton: &Skeleton) -> Result<Sequence> {
    let path = path.as_ref();
    let file = path.display().to_string();
    let bad = |message: String| Error::Parse {
        file: file.clone(),
        line: 1,
        message,
    };
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("glb"))
    {
        return Err(bad(
            "binary .glb files are not supported; use .gltf with a .bin".into(),
        ));
    }
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let doc: Value = serde_json::from_str(&text).map_err(|e| Error::Parse {
        file: file.clone(),
        line: e.line(),
        message: format!("not glTF JSON: {e}"),
    })?;
    let uri = doc["buffers"][0]["uri"]
        .as_str()
        .ok_or_else(|| bad("no buffer with a `uri`".into()))?;
    if uri.starts_with("data:") {
        return Err(bad("embedded (data URI) buffers are not supported".into()));
    }
    let bin_path = path.parent().unwrap_or(Path::new(".")).join(uri);
    let bin = std::fs::read(&bin_path).map_err(|e| Error::io(&bin_path, e))?;
    let reader = Accessors {
        doc: &doc,
        bin: &bin,
        file: &file,
    };

    let animation = &doc["animations"][0];
    let channels = animation["channels"]
        .as_array()
        .ok_or_else(|| bad("the file has no animation".into()))?;
    let mut rotations: Vec<(usize, Vec<f32>, Vec<f32>)> = Vec::new();
    let mut translation: Option<(Vec<f32>, Vec<f32>)> = None;
    for (c, channel) in channels.iter().enumerate() {
        let sampler =
            &animation["samplers"][channel["sampler"].as_u64().unwrap_or(u64::MAX) as usize];
        let node = channel["target"]["node"].as_u64().unwrap_or(u64::MAX) as usize;
        let Some(name) = doc["nodes"][node]["name"].as_str() else {
            return Err(bad(format!(
                "animation channel {c}: target node {node} has no name"
            )));
        };
        let Ok(joint) = skeleton.joint(name) else {
            continue;
        };
        let input = reader.floats(sampler["input"].as_u64(), "SCALAR")?;
        match channel["target"]["path"].as_str() {
            Some("rotation") => rotations.push((
                joint,
                input,
                reader.floats(sampler["output"].as_u64(), "VEC4")?,
            )),
            Some("translation") if joint == 0 => {
                translation = Some((input, reader.floats(sampler["output"].as_u64(), "VEC3")?))
            }
            _ => {}
        }
    }
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
            let local = sample_vec3(input, output, t) - skeleton.joints()[0].offset;
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
    let mut seq = Sequence::new(
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
    );
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

/// Reads float accessors out of the binary buffer, checking every size against it.
struct Accessors<'a> {
    doc: &'a Value,
    bin: &'a [u8],
    file: &'a str,
}

impl Accessors<'_> {
    fn floats(&self, index: Option<u64>, kind: &str) -> Result<Vec<f32>> {
        let bad = |message: String| Error::Parse {
            file: self.file.to_string(),
            line: 1,
            message,
        };
        let i = index.ok_or_else(|| bad("a sampler without an accessor".into()))? as usize;
        let acc = &self.doc["accessors"][i];
        let comps = match kind {
            "SCALAR" => 1,
            "VEC3" => 3,
            _ => 4,
        };
        if acc["type"].as_str() != Some(kind) || acc["componentType"].as_u64() != Some(5126) {
            return Err(bad(format!(
                "accessor {i}: expected {kind} of 32-bit floats"
            )));
        }
        let count = acc["count"].as_u64().unwrap_or(0) as usize;
        let view =
            &self.doc["bufferViews"][acc["bufferView"].as_u64().unwrap_or(u64::MAX) as usize];
        let stride = view["byteStride"].as_u64().unwrap_or(4 * comps as u64) as usize;
        if stride != 4 * comps {
            return Err(bad(format!(
                "accessor {i}: interleaved buffer views are not supported"
            )));
        }
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
            + acc["byteOffset"].as_u64().unwrap_or(0) as usize;
        let len = count
            .checked_mul(4 * comps)
            .filter(|l| start.checked_add(*l).is_some_and(|e| e <= self.bin.len()));
        let len = len.ok_or_else(|| {
            bad(format!(
                "accessor {i}: {count} × {kind} does not fit in the buffer"
            ))
        })?;
        Ok(self.bin[start..start + len]
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect())
    }
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
    use crate::gltf::{write_gltf, Rig};
    use crate::rig::tests::fk_positions;
    use troupe_body::template::template;

    #[test]
    fn a_troupe_gltf_reads_back_to_the_same_positions() {
        let t = template("adult").unwrap();
        let skel = t.instantiate(t.default_params()).unwrap();
        let mut seq = Sequence::new("motion");
        seq.meta.insert("rate".into(), "30".into());
        for (d, dof) in skel.dofs().iter().enumerate() {
            let keys = (0..4)
                .map(|k| {
                    Key::new(
                        k as f64 * 0.5,
                        (((d * 5 + k * 3) as f64).sin() * 0.4).clamp(dof.min, dof.max),
                    )
                })
                .collect();
            seq.add_track(Track::new(dof.name.clone(), keys).unwrap())
                .unwrap();
        }
        let dir = std::env::temp_dir().join(format!("troupe-gltf-import-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("motion.gltf");
        write_gltf(&path, &Rig::from_sequence(&skel, &seq).unwrap(), "motion").unwrap();
        let back = read_gltf_motion(&path, &skel).unwrap();
        for time in [0.0, 0.5, 1.2] {
            let q: Vec<f64> = skel
                .dofs()
                .iter()
                .map(|d| seq.track(&d.name).unwrap().value(time))
                .collect();
            let q2: Vec<f64> = skel
                .dofs()
                .iter()
                .map(|d| back.track(&d.name).map(|t| t.value(time)).unwrap_or(0.0))
                .collect();
            let (a, b) = (fk_positions(&skel, &q), fk_positions(&skel, &q2));
            for (j, (x, y)) in a.iter().zip(&b).enumerate() {
                // f32 storage in glTF and linear resampling bound the error.
                assert!(
                    (*x - *y).length() < 2e-3,
                    "t={time} {}: {x} vs {y}",
                    skel.joints()[j].name
                );
            }
        }
        // Garbage is an error, not a panic.
        std::fs::write(dir.join("bad.gltf"), "{ not json").unwrap();
        assert!(matches!(
            read_gltf_motion(dir.join("bad.gltf"), &skel),
            Err(Error::Parse { .. })
        ));
        std::fs::write(dir.join("short.bin"), [0u8; 3]).unwrap();
        let mut doc: Value =
            serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        doc["buffers"][0]["uri"] = "short.bin".into();
        std::fs::write(dir.join("short.gltf"), doc.to_string()).unwrap();
        let err = read_gltf_motion(dir.join("short.gltf"), &skel)
            .unwrap_err()
            .to_string();
        assert!(err.contains("does not fit"), "{err}");
    }
}
