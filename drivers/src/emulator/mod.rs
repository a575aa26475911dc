//! Emulators that speak the Flock of Birds and CyberGlove protocols on a pseudo-terminal,
//! so drivers, probes and performer actors run without hardware.
//!
//! The emulators answer the same commands the drivers send (see `shared/reference/
//! devices.md`) and encode records exactly as the documented formats say, from a motion
//! source: a built-in synthetic motion, a BVH file, or a `.rec` recording. Each device's
//! emulator lives with its protocol (`fob::emulator`, `cyberglove::emulator`); this module
//! runs one on a new pty.

pub(crate) mod error;
pub(crate) mod motion;
pub(crate) mod options;
pub(crate) mod pty;

pub use error::{EmulatorError, MotionError};
pub use motion::Motion;
pub use options::EmulatorOptions;
pub use pty::Pty;

use crate::cyberglove::emulator::GloveEmulator;
use crate::fob::emulator::FobEmulator;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;

/// A running emulator: its pty path; stops (closing the pty) when dropped.
pub struct Emulator {
    path: String,
    link: Option<PathBuf>,
    stop: Arc<AtomicBool>,
    thread: Option<JoinHandle<()>>,
}

impl Emulator {
    /// The path a driver opens (the link when one was asked for, else the pty).
    pub fn path(&self) -> String {
        self.link
            .as_ref()
            .map(|l| l.display().to_string())
            .unwrap_or_else(|| self.path.clone())
    }

    /// The pty's own path.
    pub fn pty_path(&self) -> &str {
        &self.path
    }

    /// Stops the emulator and closes the pty (a connected driver sees the port vanish).
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::Release);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
        if let Some(l) = &self.link {
            remove_symlink(l);
        }
    }

    /// Waits until the emulator thread ends (it runs until stopped).
    pub fn join(mut self) {
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

impl Drop for Emulator {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Which device to emulate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeviceKind {
    /// Flock of Birds.
    Fob,
    /// CyberGlove.
    CyberGlove,
}

/// Starts an emulator on a new pty; with `link`, a symbolic link at that path points to the
/// pty (replaced if it exists), so a driver can reopen the same path after a restart.
pub fn start(
    kind: DeviceKind,
    options: EmulatorOptions,
    link: Option<&Path>,
) -> Result<Emulator, EmulatorError> {
    let pty = Pty::open()?;
    let path = pty.path().to_string();
    if let Some(l) = link {
        if std::fs::symlink_metadata(l).is_ok_and(|m| !m.file_type().is_symlink()) {
            return Err(EmulatorError::LinkOccupied(l.to_path_buf()));
        }
        remove_symlink(l);
        std::os::unix::fs::symlink(&path, l).map_err(|source| EmulatorError::Link {
            link: l.to_path_buf(),
            pty: path.clone(),
            source,
        })?;
    }
    let stop = Arc::new(AtomicBool::new(false));
    let s = stop.clone();
    let thread = std::thread::Builder::new()
        .name(format!("emulator {path}"))
        .spawn(move || match kind {
            DeviceKind::Fob => FobEmulator::new(options).run(&pty, &s),
            DeviceKind::CyberGlove => GloveEmulator::new(options).run(&pty, &s),
        })
        .map_err(EmulatorError::Thread)?;
    Ok(Emulator {
        path,
        link: link.map(Path::to_path_buf),
        stop,
        thread: Some(thread),
    })
}

/// Removes `path` if it is a symbolic link (the emulator's `--link`), and nothing else.
fn remove_symlink(path: &std::path::Path) {
    if std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink()) {
        let _ = std::fs::remove_file(path);
    }
}
