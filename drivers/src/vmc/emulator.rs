//! A VMC sender without a camera or a suit: a motion file (BVH or `.trk`) played on the
//! adult template and sent as a VMC stream in real time (`troupe emulate vmc`).

use crate::vmc::message::frame_bundle;
use crate::vmc::rig::VmcRig;
use std::net::UdpSocket;
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::skeleton::Skeleton;
use troupe_body::transform::Transform;
use troupe_motion::Sequence;

/// A motion that cannot be loaded or sent.
#[derive(Debug, thiserror::Error)]
pub enum VmcEmulatorError {
    /// The motion file cannot be read (the message names the file).
    #[error("{message}")]
    Motion {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
    /// The socket cannot be made or the target does not resolve.
    #[error("VMC emulator: {0}")]
    Socket(#[source] std::io::Error),
}

/// A motion played on a template, frame by frame, as VMC bundles.
pub struct VmcMotion {
    skeleton: Arc<Skeleton>,
    rig: VmcRig,
    sequence: Sequence,
    /// Per track: its DOF index.
    dofs: Vec<usize>,
}

impl VmcMotion {
    /// Loads `path` (a BVH, retargeted as `troupe seq` does, or a `.trk`) onto the
    /// adult template.
    pub fn load(path: &Path) -> Result<VmcMotion, VmcEmulatorError> {
        let err = |message: String| VmcEmulatorError::Motion {
            path: path.display().to_string(),
            message,
        };
        let skeleton = Arc::new(
            troupe_body::template::default_skeleton("adult")
                .map_err(|e| err(format!("{}: {e}", path.display())))?,
        );
        let is_bvh = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("bvh"));
        let sequence = if is_bvh {
            troupe_formats::retarget::load_sequence_for(&skeleton, path)
        } else {
            troupe_formats::load_sequence(path, Some(&skeleton))
        }
        .map_err(|e| err(e.to_string()))?;
        let dofs = sequence
            .tracks()
            .iter()
            .map(|t| {
                skeleton
                    .dof(t.dof())
                    .map_err(|e| err(format!("{}: {e}", path.display())))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let rig =
            VmcRig::new(skeleton.clone()).map_err(|e| err(format!("{}: {e}", path.display())))?;
        Ok(VmcMotion {
            skeleton,
            rig,
            sequence,
            dofs,
        })
    }

    /// The motion's length in seconds.
    pub fn duration(&self) -> f64 {
        self.sequence.duration()
    }

    /// The bundle bytes at time `t` into the motion (looped), stamped `/VMC/Ext/T` = `t`.
    pub fn frame(&self, t: f64) -> Vec<u8> {
        let d = self.duration();
        let at = self.sequence.start() + if d > 0.0 { t.rem_euclid(d) } else { 0.0 };
        let mut q = vec![0.0; self.skeleton.dof_count()];
        for (track, &dof) in self.sequence.tracks().iter().zip(&self.dofs) {
            q[dof] = track.value(at);
        }
        let mut g = vec![Transform::IDENTITY; self.skeleton.joints().len()];
        forward_kinematics(&self.skeleton, &q, &mut g);
        let pose = self.rig.pose(&g);
        rosc::encoder::encode(&frame_bundle(&pose, t)).unwrap_or_default()
    }
}

/// Sends `motion` to `to` at `rate` frames per second in real time, for `seconds` (or
/// until `stop`); returns the frames sent.
pub fn send_motion(
    motion: &VmcMotion,
    to: &str,
    rate: f64,
    seconds: Option<f64>,
    stop: &AtomicBool,
) -> Result<u64, VmcEmulatorError> {
    let socket = UdpSocket::bind("0.0.0.0:0").map_err(VmcEmulatorError::Socket)?;
    socket.connect(to).map_err(VmcEmulatorError::Socket)?;
    let period = Duration::from_secs_f64(1.0 / rate.max(1e-3));
    let start = Instant::now();
    let (mut sent, mut frames) = (0u64, 0u32);
    while !stop.load(Ordering::Relaxed) {
        let t = start.elapsed().as_secs_f64();
        if seconds.is_some_and(|s| t >= s) {
            break;
        }
        // A Marionette that is not up yet refuses datagrams: keep sending.
        if socket.send(&motion.frame(t)).is_ok() {
            sent += 1;
        }
        frames += 1;
        let next = start + period * frames;
        if let Some(wait) = next.checked_duration_since(Instant::now()) {
            std::thread::sleep(wait);
        }
    }
    Ok(sent)
}
