//! BVH (Biovision Hierarchy) motion files: import, forward kinematics and export.
//!
//! The reader accepts what real files contain: any of the six rotation orders per joint,
//! rotation channels listed before or after position channels, CRLF or LF line ends (mixed
//! too), tabs or spaces, `End Site` blocks, several roots, and a root with a non-zero
//! `OFFSET` together with absolute position channels. A `Frames:` count that disagrees
//! with the data rows is reported with a `tracing` warning and the rows are used.
//!
//! Conventions (those of pybvh, bvhio and bvhtoolbox): rotation channels compose in the
//! order listed, intrinsically (`Zrotation Xrotation Yrotation` means `R = Rz·Rx·Ry`);
//! a joint's local transform is `translate(t) · R`, where `t` is the joint's `OFFSET` with
//! every component that has a position channel replaced by that channel's value.
//!
//! A [`Bvh`] keeps the file's own units (degrees, and whatever length unit the file uses);
//! conversion to troupe's metres and radians happens where a BVH becomes a troupe
//! [`Sequence`](troupe_motion::Sequence) (see [`Bvh::to_channel_sequence`] and
//! [`crate::retarget`]).
//!
//! One concept per file: [`channel`] (axes, channels, rotation orders), [`motion`] (the
//! hierarchy and its frames), [`kinematics`], [`read`], [`write`](mod@write),
//! [`channels`] (a BVH's channels as a troupe sequence) and [`rig`] (to and from the
//! one [`Rig`](crate::Rig)).

pub mod channel;
pub mod channels;
pub mod kinematics;
pub mod motion;
pub mod read;
pub mod rig;
pub mod write;

pub use channel::{Axis, Channel, RotationOrder, MAX_JOINT_CHANNELS};
pub use motion::{Bvh, BvhJoint};
pub use read::{parse_bvh, read_bvh};
pub use rig::from_rig;
pub use write::write_bvh;

/// Shared data of the BVH tests: the files in `../shared/data/bvh` and a pose comparison.
#[cfg(test)]
pub(crate) mod fixtures {
    use super::Bvh;

    /// Two hierarchies in one file: `A` with an end site, and `B` with a child `C`, ten
    /// units to A's right; two frames.
    pub(crate) const TWO_ROOTS: &str = "HIERARCHY\nROOT A\n{\nOFFSET 0 0 0\n\
        CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n\
        End Site\n{\nOFFSET 0 5 0\n}\n}\n\
        ROOT B\n{\nOFFSET 10 0 0\n\
        CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n\
        JOINT C\n{\nOFFSET 0 5 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n\
        End Site\n{\nOFFSET 0 5 0\n}\n}\n}\n\
        MOTION\nFrames: 2\nFrame Time: 0.1\n\
        0 0 0 0 0 0 10 0 0 0 0 0 0 0 0\n\
        1 0 0 0 0 90 10 0 0 90 0 0 45 0 0\n";

    /// The path of a file in `../shared/data/bvh`.
    pub(crate) fn data(name: &str) -> String {
        format!(
            "{}/../../../shared/data/bvh/{name}",
            env!("CARGO_MANIFEST_DIR")
        )
    }

    /// Every BVH file shipped in `../shared/data/bvh`.
    pub(crate) fn shared_files() -> Vec<std::path::PathBuf> {
        let dir = data("");
        let mut files: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{dir}: {e}"))
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "bvh"))
            .collect();
        files.sort();
        files
    }

    /// Maximum distance between the global joint positions of two motions of one skeleton.
    pub(crate) fn max_position_difference(a: &Bvh, b: &Bvh) -> f64 {
        assert_eq!(a.frame_count(), b.frame_count());
        let mut worst: f64 = 0.0;
        for k in 0..a.frame_count() {
            for (p, q) in a.joint_positions(k).iter().zip(b.joint_positions(k)) {
                worst = worst.max((*p - q).length());
            }
        }
        worst
    }
}
