//! The one place that chooses a reader or a writer by a file's extension.
//!
//! | extension | holds | loaded | saved |
//! |---|---|---|---|
//! | `.trk` | any number of sequences, tracks named by DOF | as written | every sequence in one file |
//! | `.bvh` | one actor's motion on a joint hierarchy | onto a body: exactly if the hierarchy is the body's own, else retargeted | one file per actor, on its body's hierarchy |
//! | `.gltf`, `.glb` | one actor's motion on a node hierarchy | onto a body whose joint names the nodes carry | one file per actor |
//!
//! A `.trk` names DOFs and plays on any body; the other formats carry a skeleton of their
//! own, so loading them needs the body to play on, and saving them needs each sequence's
//! body. Saving several actors to a one-actor format writes `NAME.ACTOR.EXT` for each.

use crate::bvh::{from_rig, write_bvh, Axis, RotationOrder};
use crate::error::{Error, Result};
use crate::gltf::{
    read_gltf_motion, write_character, write_glb, write_glb_with, write_gltf, write_gltf_with,
};
use crate::retarget::load_sequence_for;
use crate::rig::Rig;
use crate::trk::{read_trk, read_trk_set, write_trk_file, TrkFile};
use std::path::{Path, PathBuf};
use troupe_body::skeleton::Skeleton;
use troupe_body::skin::{SharedSkin, SkinLibrary};
use troupe_body::{Dressing, Skin};
use troupe_motion::object_motion::ObjectMotion;
use troupe_motion::sequence::Sequence;

/// The rotation order of the BVH files troupe writes from a body's motion.
pub const BVH_ROTATION_ORDER: RotationOrder = RotationOrder([Axis::Z, Axis::X, Axis::Y]);
/// BVH length units per metre of the files troupe writes from a body's motion
/// (centimetres).
pub const BVH_UNITS_PER_METRE: f64 = 100.0;

/// A motion file format, as its extension names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// troupe's own track file, `.trk`.
    Trk,
    /// Biovision Hierarchy, `.bvh`.
    Bvh,
    /// glTF 2.0 JSON with its buffers beside or embedded, `.gltf`.
    Gltf,
    /// Binary glTF 2.0, `.glb`.
    Glb,
}

impl Format {
    /// The format of `path` by its extension (case-insensitive).
    pub fn of(path: &Path) -> Result<Format> {
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "trk" => Ok(Format::Trk),
            "bvh" => Ok(Format::Bvh),
            "gltf" => Ok(Format::Gltf),
            "glb" => Ok(Format::Glb),
            // A name without an extension says so, rather than "`.` motion files".
            "" => Err(Error::UnknownFormat {
                path: path.display().to_string(),
                extension: "no extension".into(),
            }),
            _ => Err(Error::UnknownFormat {
                path: path.display().to_string(),
                extension: format!("`.{ext}`"),
            }),
        }
    }

    /// Whether the format carries a skeleton of its own, so that its motion is loaded
    /// onto a body (every format but `.trk`).
    pub fn binds_to_body(self) -> bool {
        self != Format::Trk
    }

    /// The format's name in messages.
    pub fn name(self) -> &'static str {
        match self {
            Format::Trk => ".trk",
            Format::Bvh => "BVH",
            Format::Gltf | Format::Glb => "glTF",
        }
    }
}

/// Every sequence of a motion file, to play on `body`: a `.trk` as written (`body` is not
/// needed); a `.bvh`, `.gltf` or `.glb` as one sequence onto `body` (see the module
/// table), which must then be given.
pub fn load_sequences(path: impl AsRef<Path>, body: Option<&Skeleton>) -> Result<Vec<Sequence>> {
    let path = path.as_ref();
    match Format::of(path)? {
        Format::Trk => read_trk_set(path),
        format => load_onto_body(path, format, body).map(|s| vec![s]),
    }
}

/// The one sequence of a motion file, to play on `body`, as [`load_sequences`] reads it;
/// a `.trk` that holds several sequences is an error.
pub fn load_sequence(path: impl AsRef<Path>, body: Option<&Skeleton>) -> Result<Sequence> {
    let path = path.as_ref();
    match Format::of(path)? {
        Format::Trk => read_trk(path),
        format => load_onto_body(path, format, body),
    }
}

/// A BVH or glTF motion onto `body`.
fn load_onto_body(path: &Path, format: Format, body: Option<&Skeleton>) -> Result<Sequence> {
    let body = body.ok_or_else(|| Error::NeedsBody {
        path: path.display().to_string(),
        format: format.name().into(),
    })?;
    match format {
        Format::Bvh => load_sequence_for(body, path),
        _ => read_gltf_motion(path, body),
    }
}

/// Saves `sequences` to `path` and returns the files written: a `.trk` holds them all;
/// to a one-actor format each sequence is written on its actor's body — `actors` gives
/// `(name, skeleton)` in the sequences' order — as `path` itself when there is one
/// sequence, else `NAME.ACTOR.EXT` beside it.
pub fn save_sequences<'a>(
    path: impl AsRef<Path>,
    sequences: &[Sequence],
    actors: impl IntoIterator<Item = (&'a str, &'a Skeleton)>,
) -> Result<Vec<PathBuf>> {
    save_recording(path, sequences, &[], actors)
}

/// Saves a recording — the actors' `sequences` (as [`save_sequences`]) and the scene's
/// `objects` — and returns the files written: a `.trk` holds everything; each glTF file
/// holds its actor and every object, as animated nodes; BVH, one hierarchy per file,
/// writes each object as `STEM.OBJECT.bvh`, a one-joint hierarchy whose six channels are
/// the object's pose (who held it is in `.trk` and glTF only).
pub fn save_recording<'a>(
    path: impl AsRef<Path>,
    sequences: &[Sequence],
    objects: &[ObjectMotion],
    actors: impl IntoIterator<Item = (&'a str, &'a Skeleton)>,
) -> Result<Vec<PathBuf>> {
    let actors = actors
        .into_iter()
        .map(|(name, skeleton)| (name, skeleton, None));
    save_dressed_recording(path, sequences, objects, actors)
}

/// [`save_recording`] of actors that may be dressed in a user's character: `actors` gives
/// `(name, skeleton, look)`; a glTF file of an actor with a look holds that character
/// (its bones, mesh and their animation, [`crate::gltf::character`]) in place of
/// troupe's skeleton and generated skin. Other formats are written as by
/// [`save_recording`].
pub fn save_dressed_recording<'a>(
    path: impl AsRef<Path>,
    sequences: &[Sequence],
    objects: &[ObjectMotion],
    actors: impl IntoIterator<Item = (&'a str, &'a Skeleton, Option<&'a Dressing>)>,
) -> Result<Vec<PathBuf>> {
    let path = path.as_ref();
    let format = Format::of(path)?;
    if format == Format::Trk {
        let file = TrkFile {
            sequences: sequences.to_vec(),
            objects: objects.to_vec(),
        };
        write_trk_file(path, &file)?;
        return Ok(vec![path.to_path_buf()]);
    }
    let beside = |name: &str| {
        let stem = path.file_stem().unwrap_or_default().to_string_lossy();
        let ext = path.extension().unwrap_or_default().to_string_lossy();
        path.with_file_name(format!("{stem}.{name}.{ext}"))
    };
    let mut written = Vec::new();
    let mut skins = Skins::default();
    for (seq, (actor, skeleton, look)) in sequences.iter().zip(actors) {
        let out = if sequences.len() == 1 {
            path.to_path_buf()
        } else {
            beside(actor)
        };
        let rig = Rig::from_sequence(skeleton, seq)?;
        match format {
            // A glTF file of a troupe body carries its skin (a skeleton that is not a
            // troupe template's is written with bones only), or the user's character the
            // actor is dressed in, and every object.
            Format::Gltf | Format::Glb => {
                let with: Vec<(&ObjectMotion, Rig)> = objects
                    .iter()
                    .map(|o| (o, Rig::from_object(o, seq.start(), &rig.times)))
                    .collect();
                match look {
                    Some(look) => write_character(&out, look, &rig, &with, actor)?,
                    None => {
                        // Scaled to the actor's size for this file only.
                        let skin = skins.of(skeleton, &out).map(|s| s.to_skin());
                        if format == Format::Gltf {
                            write_gltf_with(&out, &rig, skin.as_ref(), &with, actor)?;
                        } else {
                            write_glb_with(&out, &rig, skin.as_ref(), &with, actor)?;
                        }
                    }
                }
            }
            _ => save_rig(&out, &rig, actor, seq.frame_time())?,
        }
        written.push(out);
    }
    if format == Format::Bvh {
        let (start, frame_time, end) = match sequences.first() {
            Some(seq) => (seq.start(), seq.frame_time(), seq.end()),
            None => (
                0.0,
                0.01,
                objects.iter().map(|o| o.pose.end()).fold(0.0, f64::max),
            ),
        };
        let frames = ((end - start) / frame_time - 1e-9).ceil().max(0.0) as usize + 1;
        let times: Vec<f64> = (0..frames).map(|k| k as f64 * frame_time).collect();
        for object in objects {
            let out = beside(&object.name);
            if written.contains(&out) {
                return Err(Error::Invalid(format!(
                    "{}: object `{}` has an actor's name, so its BVH file would replace the actor's",
                    out.display(),
                    object.name
                )));
            }
            let rig = Rig::from_object(object, start, &times);
            save_rig(&out, &rig, &object.name, frame_time)?;
            written.push(out);
        }
    }
    Ok(written)
}

/// The generated skins of a recording's actors: made once per template
/// ([`SkinLibrary`]: every height shares it) and found once per skeleton (actors of one
/// body share theirs).
#[derive(Default)]
struct Skins {
    library: SkinLibrary,
    found: Vec<(*const Skeleton, Option<SharedSkin>)>,
}

impl Skins {
    /// The skin of `skeleton`; `None`, with a warning naming `out`, for a skeleton that is
    /// not a troupe template's.
    fn of(&mut self, skeleton: &Skeleton, out: &Path) -> Option<&SharedSkin> {
        let key: *const Skeleton = skeleton;
        let at = match self.found.iter().position(|(k, _)| *k == key) {
            Some(at) => at,
            None => {
                let skin = match self.library.get(skeleton) {
                    Ok(shared) => Some(shared),
                    Err(e) => {
                        tracing::warn!("{}: written without a skin: {e}", out.display());
                        None
                    }
                };
                self.found.push((key, skin));
                self.found.len() - 1
            }
        };
        self.found[at].1.as_ref()
    }
}

/// Saves a rig and the skin of its skeleton as glTF (`.gltf` or `.glb` by `path`'s
/// extension), the scene named `name`.
pub fn save_skinned(path: &Path, rig: &Rig, skin: Option<&Skin>, name: &str) -> Result<()> {
    match Format::of(path)? {
        Format::Gltf => write_gltf_with(path, rig, skin, &[], name),
        Format::Glb => write_glb_with(path, rig, skin, &[], name),
        _ => Err(Error::Invalid(format!(
            "{}: a skinned character is written as .gltf or .glb",
            path.display()
        ))),
    }
}

/// Saves a user's character fitted to a skeleton (`dressing`), following `rig` (that
/// skeleton's), as glTF (`.gltf` or `.glb` by `path`'s extension), the scene named `name`.
pub fn save_character(path: &Path, dressing: &Dressing, rig: &Rig, name: &str) -> Result<()> {
    match Format::of(path)? {
        Format::Gltf | Format::Glb => write_character(path, dressing, rig, &[], name),
        _ => Err(Error::Invalid(format!(
            "{}: a character is written as .gltf or .glb",
            path.display()
        ))),
    }
}

/// Saves a rig's motion to a one-actor format by `path`'s extension: glTF names its scene
/// `name`; BVH is written in [`BVH_ROTATION_ORDER`] and [`BVH_UNITS_PER_METRE`], a frame
/// every `frame_time` seconds. A `.trk` cannot hold a rig (it names DOFs, not joints).
pub fn save_rig(path: impl AsRef<Path>, rig: &Rig, name: &str, frame_time: f64) -> Result<()> {
    let path = path.as_ref();
    match Format::of(path)? {
        Format::Bvh => write_bvh(
            path,
            &from_rig(rig, frame_time, BVH_ROTATION_ORDER, BVH_UNITS_PER_METRE)?,
        ),
        Format::Gltf => write_gltf(path, rig, name),
        Format::Glb => write_glb(path, rig, name),
        Format::Trk => Err(Error::Invalid(format!(
            "{}: a .trk holds DOF tracks, not a joint hierarchy; save the sequence instead",
            path.display()
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::tests::{adult, every_dof_moving, fk_positions, posture};

    #[test]
    fn formats_by_extension() {
        for (file, format) in [
            ("a.trk", Format::Trk),
            ("a.BVH", Format::Bvh),
            ("dir.v2/a.gltf", Format::Gltf),
            ("a.Glb", Format::Glb),
        ] {
            assert_eq!(Format::of(Path::new(file)).unwrap(), format, "{file}");
        }
        for file in ["a.txt", "a", "a.trk.bak"] {
            assert!(matches!(
                Format::of(Path::new(file)),
                Err(Error::UnknownFormat { .. })
            ));
        }
        // A name without an extension is told so (it read "`.` motion files").
        assert_eq!(
            Format::of(Path::new("out")).unwrap_err().to_string(),
            "out: cannot read or write motion files with no extension (use .trk, .bvh, .gltf or .glb)"
        );
    }

    #[test]
    fn every_format_saves_and_loads_two_actors() {
        let skel = adult();
        let mut both = [
            every_dof_moving(&skel, 4, 0.25, "20"),
            every_dof_moving(&skel, 3, 0.5, "20"),
        ];
        // Named after their actors, as a recording names them (a .trk needs each name
        // once).
        both[0].name = "ann".into();
        both[1].name = "bob".into();
        let dir = std::env::temp_dir().join(format!("troupe-dispatch-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let actors = [("ann", &skel), ("bob", &skel)];
        for ext in ["trk", "bvh", "gltf", "glb"] {
            let path = dir.join(format!("rec.{ext}"));
            let written = save_sequences(&path, &both, actors).unwrap();
            let loaded: Vec<Sequence> = written
                .iter()
                .flat_map(|f| load_sequences(f, Some(&skel)).unwrap())
                .collect();
            if ext == "trk" {
                assert_eq!(written, std::slice::from_ref(&path));
                assert_eq!(loaded, both);
                continue;
            }
            assert_eq!(
                written,
                [
                    dir.join(format!("rec.ann.{ext}")),
                    dir.join(format!("rec.bob.{ext}"))
                ]
            );
            if ext == "gltf" {
                // A troupe body's glTF carries its skin: one mesh on a root node.
                let text = std::fs::read_to_string(&written[0]).unwrap();
                let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
                assert_eq!(doc["meshes"].as_array().map(Vec::len), Some(1));
                let skinned = doc["nodes"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .position(|n| n.get("skin").is_some() && n.get("mesh").is_some())
                    .unwrap();
                assert!(doc["scenes"][0]["nodes"]
                    .as_array()
                    .unwrap()
                    .contains(&serde_json::Value::from(skinned)));
            }
            for (want, got) in both.iter().zip(&loaded) {
                let time = 0.25;
                let p = fk_positions(&skel, &posture(&skel, want, time));
                let q = fk_positions(&skel, &posture(&skel, got, time));
                for (x, y) in p.iter().zip(&q) {
                    // glTF stores f32; BVH round-trips exactly up to the decomposition.
                    assert!((*x - *y).length() < 2e-3, "{ext}: {x} vs {y}");
                }
            }
        }
        // One sequence is written to the path itself.
        let one = dir.join("one.bvh");
        assert_eq!(
            save_sequences(&one, &both[..1], [("ann", &skel)]).unwrap(),
            std::slice::from_ref(&one)
        );
        // Motion bound to a body needs one; a .trk does not.
        assert!(matches!(
            load_sequences(&one, None),
            Err(Error::NeedsBody { .. })
        ));
        assert_eq!(load_sequence(dir.join("rec.trk"), None).ok(), None);
        assert!(save_rig(
            dir.join("x.trk"),
            &Rig::from_sequence(&skel, &both[0]).unwrap(),
            "x",
            0.05
        )
        .is_err());
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn recordings_keep_their_objects_in_every_format() {
        use glam::{DQuat, DVec3};
        use troupe_body::solid::Shape;
        use troupe_motion::object_motion::Hold;
        let skel = adult();
        let actor = every_dof_moving(&skel, 4, 0.25, "20");
        let times: Vec<f64> = (0..=20).map(|i| i as f64 * 0.05).collect();
        let poses: Vec<(DVec3, DQuat)> = times
            .iter()
            .map(|&t| (DVec3::new(t, 1.0, 0.5), DQuat::from_rotation_y(t)))
            .collect();
        let shape = Shape::Cylinder {
            radius: 0.04,
            height: 0.1,
        };
        let mut cup = ObjectMotion::from_samples("cup", shape, 0.3, &times, &poses).unwrap();
        cup.holds.push(Hold {
            from: 0.25,
            to: 0.75,
            actor: "ann".into(),
            joint: "r_wrist".into(),
        });
        let objects = [cup];
        let dir = std::env::temp_dir().join(format!("troupe-objects-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let actors = [("ann", &skel)];
        // .trk: everything, exactly.
        let trk = dir.join("rec.trk");
        save_recording(&trk, std::slice::from_ref(&actor), &objects, actors).unwrap();
        let back = crate::trk::read_trk_file(&trk).unwrap();
        assert_eq!(back.objects, objects);
        assert_eq!(back.sequences, std::slice::from_ref(&actor));
        // glTF: an animated node with the holders in its extras; the actor still reads back.
        for ext in ["gltf", "glb"] {
            let path = dir.join(format!("rec.{ext}"));
            save_recording(&path, std::slice::from_ref(&actor), &objects, actors).unwrap();
            let doc = ::gltf::Gltf::open(&path).unwrap();
            let node = doc
                .nodes()
                .find(|n| n.name() == Some("cup"))
                .expect("a cup node");
            let extras: serde_json::Value =
                serde_json::from_str(node.extras().as_ref().unwrap().get()).unwrap();
            assert_eq!(extras["troupe_object"]["held"][0]["actor"], "ann");
            assert_eq!(extras["troupe_object"]["shape"], "cylinder 0.04 0.1");
            let animated: Vec<_> = doc
                .animations()
                .next()
                .unwrap()
                .channels()
                .filter(|c| c.target().node().index() == node.index())
                .map(|c| c.target().property())
                .collect();
            assert_eq!(animated.len(), 2, "translation and rotation");
            assert!(doc
                .scenes()
                .next()
                .unwrap()
                .nodes()
                .any(|n| n.index() == node.index()));
            assert!(load_sequence(&path, Some(&skel)).is_ok());
        }
        // BVH: the object's own one-joint file, whose root follows the pose.
        let bvh = dir.join("rec.bvh");
        let written = save_recording(&bvh, std::slice::from_ref(&actor), &objects, actors).unwrap();
        assert_eq!(written, [bvh.clone(), dir.join("rec.cup.bvh")]);
        let b = crate::bvh::read_bvh(dir.join("rec.cup.bvh")).unwrap();
        assert_eq!(b.joints().len(), 1);
        let k = 10; // 0.5 s at 20 frames per second
        let p = b.joint_positions(k)[0] / BVH_UNITS_PER_METRE;
        assert!((p - DVec3::new(0.5, 1.0, 0.5)).length() < 1e-9, "{p}");
        // An object named like one of several actors would overwrite its file: refused.
        let mut ann = objects[0].clone();
        ann.name = "bob".into();
        let two = [actor.clone(), actor.clone()];
        let err = save_recording(&bvh, &two, &[ann], [("ann", &skel), ("bob", &skel)]);
        assert!(err.unwrap_err().to_string().contains("has an actor's name"));
        std::fs::remove_dir_all(dir).ok();
    }
}
