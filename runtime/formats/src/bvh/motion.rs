//! The BVH motion: a hierarchy of joints and the channel values of every frame.

use super::channel::{Channel, RotationOrder};
use crate::error::{Error, Result};
use glam::DVec3;

/// One joint of a BVH hierarchy.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhJoint {
    /// The joint's name as written in the file.
    pub name: String,
    /// Parent joint index (smaller than this joint's), `None` for a root.
    pub parent: Option<usize>,
    /// The `OFFSET` from the parent, in file units.
    pub offset: DVec3,
    /// The joint's channels in file order.
    pub channels: Vec<Channel>,
    /// Index of the joint's first channel in a frame row.
    pub first_channel: usize,
    /// Offsets of the joint's `End Site` blocks (usually zero or one).
    pub end_sites: Vec<DVec3>,
}

/// A BVH motion: its own hierarchy and the channel values of every frame (file units).
#[derive(Clone, Debug, PartialEq)]
pub struct Bvh {
    joints: Vec<BvhJoint>,
    frame_time: f64,
    channel_count: usize,
    data: Vec<f64>,
}

impl Bvh {
    /// Builds a motion from a hierarchy and frame-major channel data; checks sizes and
    /// recomputes every joint's `first_channel`.
    pub fn new(mut joints: Vec<BvhJoint>, frame_time: f64, data: Vec<f64>) -> Result<Bvh> {
        if !(frame_time.is_finite() && frame_time > 0.0) {
            return Err(Error::invalid_value(
                "BVH frame time",
                frame_time,
                "a positive number of seconds",
            ));
        }
        let mut count = 0;
        for (i, j) in joints.iter_mut().enumerate() {
            if j.parent.is_some_and(|p| p >= i) {
                return Err(Error::Invalid(format!(
                    "BVH joint `{}`: parent must come first",
                    j.name
                )));
            }
            j.first_channel = count;
            count += j.channels.len();
        }
        if joints.is_empty() {
            return Err(Error::Invalid("BVH without joints".into()));
        }
        if count == 0 && !data.is_empty() || count > 0 && !data.len().is_multiple_of(count) {
            return Err(Error::Invalid(format!(
                "BVH data of {} values is not a whole number of {count}-channel frames",
                data.len()
            )));
        }
        Ok(Bvh {
            joints,
            frame_time,
            channel_count: count,
            data,
        })
    }

    /// The joints in file order (parents first).
    pub fn joints(&self) -> &[BvhJoint] {
        &self.joints
    }
    /// The index of the joint called `name`.
    pub fn joint(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }
    /// Seconds per frame.
    pub fn frame_time(&self) -> f64 {
        self.frame_time
    }
    /// Total channels per frame.
    pub fn channel_count(&self) -> usize {
        self.channel_count
    }
    /// Number of frames.
    pub fn frame_count(&self) -> usize {
        self.data.len().checked_div(self.channel_count).unwrap_or(0)
    }
    /// Duration from the first to the last frame, in seconds.
    pub fn duration(&self) -> f64 {
        self.frame_count().saturating_sub(1) as f64 * self.frame_time
    }
    /// The channel values of frame `k` (file units, degrees).
    pub fn frame(&self, k: usize) -> &[f64] {
        &self.data[k * self.channel_count..(k + 1) * self.channel_count]
    }
    /// Mutable channel values of frame `k`.
    pub fn frame_mut(&mut self, k: usize) -> &mut [f64] {
        &mut self.data[k * self.channel_count..(k + 1) * self.channel_count]
    }

    /// The same motion with every joint's rotation channels rewritten as three channels in
    /// `order` (after the joint's position channels); global poses are unchanged.
    pub fn with_rotation_order(&self, order: RotationOrder) -> Bvh {
        let mut joints = self.joints.clone();
        for j in &mut joints {
            let has_rot = j.channels.iter().any(|c| matches!(c, Channel::Rotation(_)));
            j.channels.retain(|c| matches!(c, Channel::Position(_)));
            if has_rot {
                j.channels
                    .extend(order.0.iter().map(|&a| Channel::Rotation(a)));
            }
        }
        let count: usize = joints.iter().map(|j| j.channels.len()).sum();
        let mut data = Vec::with_capacity(self.frame_count() * count);
        for k in 0..self.frame_count() {
            let frame = self.frame(k);
            for (j, (old, new)) in self.joints.iter().zip(&joints).enumerate() {
                let values = &frame[old.first_channel..old.first_channel + old.channels.len()];
                for (c, &v) in old.channels.iter().zip(values) {
                    if let Channel::Position(_) = c {
                        data.push(v);
                    }
                }
                if new
                    .channels
                    .iter()
                    .any(|c| matches!(c, Channel::Rotation(_)))
                {
                    data.extend(
                        order
                            .decompose(self.local_transform(j, frame).rotation)
                            .map(f64::to_degrees),
                    );
                }
            }
        }
        // The joints and data were built consistently, so this cannot fail.
        Bvh::new(joints, self.frame_time, data).unwrap_or_else(|_| self.clone())
    }
}
