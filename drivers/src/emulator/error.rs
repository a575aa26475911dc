//! What can go wrong starting an emulator or loading its motion.

use crate::record::error::RecordError;
use std::path::PathBuf;

/// An emulator that cannot start.
#[derive(Debug, thiserror::Error)]
pub enum EmulatorError {
    /// No pseudo-terminal could be opened.
    #[error("openpty: {0}")]
    Pty(#[source] std::io::Error),
    /// The `--link` path holds something other than a symbolic link.
    #[error("--link {}: a file that is not a symbolic link is there; not replacing it", .0.display())]
    LinkOccupied(PathBuf),
    /// The `--link` symbolic link could not be made.
    #[error("linking {} to {pty}: {source}", link.display())]
    Link {
        /// The link's path.
        link: PathBuf,
        /// The pty it should point to.
        pty: String,
        /// What the file system said.
        #[source]
        source: std::io::Error,
    },
    /// The emulator thread could not be started.
    #[error("starting the emulator thread: {0}")]
    Thread(#[source] std::io::Error),
}

/// A motion file that cannot drive an emulator; every error names the file.
#[derive(Debug, thiserror::Error)]
pub enum MotionError {
    /// The BVH file cannot be read.
    #[error(transparent)]
    Bvh(#[from] troupe_formats::Error),
    /// A bird is mapped to a joint the BVH does not have.
    #[error("{}: no joint '{joint}'", path.display())]
    NoJoint {
        /// The BVH file.
        path: PathBuf,
        /// The joint asked for.
        joint: String,
    },
    /// Fewer joints than birds.
    #[error("{}: {joints} joints for {birds} birds", path.display())]
    TooFewJoints {
        /// The BVH file.
        path: PathBuf,
        /// Joints available.
        joints: usize,
        /// Birds to drive.
        birds: usize,
    },
    /// The recording cannot be read or decoded.
    #[error(transparent)]
    Recording(#[from] RecordError),
    /// The recording has no single stream of the device's kind.
    #[error("{}: no single '{kind}' stream in the recording", path.display())]
    NoStream {
        /// The recording.
        path: PathBuf,
        /// The device kind.
        kind: String,
    },
    /// The stream has no complete record.
    #[error("{}: the '{kind}' stream has no complete record", path.display())]
    EmptyStream {
        /// The recording.
        path: PathBuf,
        /// The device kind.
        kind: String,
    },
    /// Neither `.bvh` nor `.rec`.
    #[error("{}: expected a .bvh or .rec file", .0.display())]
    Extension(PathBuf),
}
