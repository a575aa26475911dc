//! Observers that write a run's outputs to files: what `--record`, `--record-torques` and
//! `--trace` attach to a session. The gathering lives in the runtime (the posture
//! recorder, the torque log, the timeline); writing files by format is the command line's.

use anyhow::bail;
use std::path::{Path, PathBuf};
use troupe_actions::dynamics::TorqueLog;
use troupe_scene::record::PostureRecorder;
use troupe_scene::timeline::TimelineRecorder;
use troupe_scene::{Event, Observer, Result, Scene};

/// `--record FILE`: every actor's postures, written at the end as `.trk`, `.bvh` or
/// `.gltf` (one file per actor for the last two).
pub struct RecordFile {
    recorder: PostureRecorder,
    path: PathBuf,
}

impl RecordFile {
    /// Records to `path`.
    pub fn new(path: &Path) -> Self {
        RecordFile {
            recorder: PostureRecorder::new(),
            path: path.to_path_buf(),
        }
    }
}

impl Observer for RecordFile {
    fn name(&self) -> String {
        format!("--record {}", self.path.display())
    }

    fn start(&mut self, scene: &Scene) -> Result<()> {
        self.recorder.start(scene)
    }

    fn publish(&mut self, scene: &Scene, events: &[Event]) -> Result<()> {
        self.recorder.publish(scene, events)
    }

    fn finish(&mut self, scene: &Scene) -> Result<Option<String>> {
        let written = write_recording(&self.path, &self.recorder.sequences(scene), scene)
            .map_err(|e| troupe_scene::Error::Invalid(format!("{e:#}")))?;
        let list: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
        Ok(Some(format!(
            "recorded {} ticks of postures to {}",
            self.recorder.len(),
            list.join(", ")
        )))
    }
}

/// `--record-torques FILE.trk`: the joint torques of the dynamics actions, written at the
/// end.
pub struct TorqueFile {
    log: TorqueLog,
    path: PathBuf,
}

impl TorqueFile {
    /// Writes what `log` gathers to `path`.
    pub fn new(log: TorqueLog, path: &Path) -> Self {
        TorqueFile {
            log,
            path: path.to_path_buf(),
        }
    }
}

impl Observer for TorqueFile {
    fn name(&self) -> String {
        format!("--record-torques {}", self.path.display())
    }

    fn publish(&mut self, _scene: &Scene, _events: &[Event]) -> Result<()> {
        Ok(())
    }

    fn finish(&mut self, scene: &Scene) -> Result<Option<String>> {
        let set = self.log.sequences(scene);
        if set.is_empty() {
            return Ok(Some(format!(
                "no dynamics action ran: no torques to record to {}",
                self.path.display()
            )));
        }
        troupe_formats::trk::write_trk(&self.path, &set)
            .map_err(|e| troupe_scene::Error::Invalid(e.to_string()))?;
        Ok(Some(format!(
            "recorded {} joint torques ({} actor(s)) to {}",
            self.log.len(),
            set.len(),
            self.path.display()
        )))
    }
}

/// `--trace FILE.json`: the action timeline as Chrome trace-event JSON.
pub struct TraceFile {
    timeline: TimelineRecorder,
    path: PathBuf,
}

impl TraceFile {
    /// Writes the timeline to `path`.
    pub fn new(path: &Path) -> Self {
        TraceFile {
            timeline: TimelineRecorder::new(),
            path: path.to_path_buf(),
        }
    }
}

impl Observer for TraceFile {
    fn name(&self) -> String {
        format!("--trace {}", self.path.display())
    }

    fn publish(&mut self, scene: &Scene, events: &[Event]) -> Result<()> {
        self.timeline.publish(scene, events)
    }

    fn finish(&mut self, scene: &Scene) -> Result<Option<String>> {
        let json = self.timeline.to_json(scene).to_string();
        std::fs::write(&self.path, json)
            .map_err(|e| troupe_scene::Error::Invalid(e.to_string()))?;
        Ok(Some(format!(
            "wrote the action timeline to {} (open in Perfetto or chrome://tracing)",
            self.path.display()
        )))
    }
}

/// Writes a recording by the file's extension: `.trk` holds every actor; `.bvh` and
/// `.gltf` hold one actor each, so a scene of several actors writes `NAME.ACTOR.EXT`.
fn write_recording(
    path: &std::path::Path,
    sequences: &[troupe_motion::Sequence],
    scene: &troupe_scene::Scene,
) -> anyhow::Result<Vec<PathBuf>> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext == "trk" {
        troupe_formats::trk::write_trk(path, sequences)?;
        return Ok(vec![path.to_path_buf()]);
    }
    if ext != "bvh" && ext != "gltf" {
        bail!(
            "--record {}: use a .trk, .bvh or .gltf file",
            path.display()
        );
    }
    let mut written = Vec::new();
    for (seq, actor) in sequences.iter().zip(scene.actors()) {
        let out = if sequences.len() == 1 {
            path.to_path_buf()
        } else {
            let stem = path.file_stem().unwrap_or_default().to_string_lossy();
            path.with_file_name(format!("{stem}.{}.{ext}", actor.name))
        };
        let rig = troupe_formats::gltf::Rig::from_sequence(&actor.skeleton, seq)?;
        if ext == "bvh" {
            let order = "ZXY".parse()?;
            let bvh = troupe_formats::bvh::from_rig(&rig, seq.frame_time(), order, 100.0)?;
            troupe_formats::bvh::write_bvh(&out, &bvh)?;
        } else {
            troupe_formats::gltf::write_gltf(&out, &rig, &actor.name)?;
        }
        written.push(out);
    }
    Ok(written)
}
