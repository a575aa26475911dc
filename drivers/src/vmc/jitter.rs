//! The jitter buffer between a VMC sender and the ticks: frames wait `latency` seconds,
//! then play out interpolated, so a 30 or 60 Hz sender moves smoothly at 100 Hz ticks and
//! uneven arrival does not show.
//!
//! Each frame is placed on the receiver's clock by the sender's `/VMC/Ext/T` when it has
//! one: its due time is `T + offset`, with `offset` the smallest `arrival − T` seen (the
//! least-delayed packet), so network jitter does not move frames around. A frame without
//! `T` is due when it arrived.
//!
//! A sender whose clock goes back has restarted, unless the frame is an old one arriving
//! out of order. The two are told apart by lateness: on the sender's old clock a frame
//! is due at `T + offset`, and a datagram overtaken on the network arrives a few
//! milliseconds after that, while a restarted clock's frames arrive as late as the time
//! the old clock had run when the new one started. A frame whose `T` goes back and that
//! arrives more than [`RESTART_LATENESS`] after its due time starts the clock afresh.

use crate::vmc::rig::VmcPose;
use std::collections::VecDeque;
use std::time::Instant;

/// How late (s) a frame whose clock went back may arrive and still be taken as an old
/// frame reordered by the network rather than a restarted sender. Networks reorder by
/// milliseconds, far below this; a sender restarted sooner than this after it started
/// is not recognised, and holds its last pose at most this long.
pub const RESTART_LATENESS: f64 = 0.25;

/// One buffered frame.
#[derive(Clone, Debug)]
struct Frame {
    /// When it plays, receiver clock (s).
    due: f64,
    /// The sender's `T`, if any.
    source_time: Option<f64>,
    /// The whole pose so far (every bone's latest value).
    pose: VmcPose,
    /// When it arrived (live only): for the latency measurement.
    arrived: Option<Instant>,
    /// Whether it has been played at full weight.
    shown: bool,
}

/// Frames in due order, played `latency` seconds late and interpolated.
#[derive(Debug)]
pub struct JitterBuffer {
    latency: f64,
    frames: VecDeque<Frame>,
    offset: Option<f64>,
    last_source: Option<f64>,
    /// Every bone's latest value, what each new frame builds on.
    merged: VmcPose,
}

/// What the buffer plays at one moment.
#[derive(Clone, Debug, PartialEq)]
pub struct Playout {
    /// The interpolated pose.
    pub pose: VmcPose,
    /// The sender's time of the newer frame used.
    pub source_time: Option<f64>,
    /// When the frame this playout reaches for the first time (at full weight) arrived
    /// (live only): its sample-to-posture latency ends with this tick.
    pub arrived: Option<Instant>,
}

impl JitterBuffer {
    /// A buffer delaying frames by `latency` seconds (≥ 0).
    pub fn new(latency: f64) -> JitterBuffer {
        JitterBuffer {
            latency: latency.max(0.0),
            frames: VecDeque::new(),
            offset: None,
            last_source: None,
            merged: VmcPose::default(),
        }
    }

    /// Adds a frame that arrived at `arrival` (receiver clock, s) carrying `pose` (the
    /// bones it set) and the sender's time.
    pub fn push(
        &mut self,
        arrival: f64,
        source_time: Option<f64>,
        pose: &VmcPose,
        arrived: Option<Instant>,
    ) {
        if pose.is_empty() {
            return;
        }
        let due = match source_time {
            Some(t) => {
                let went_back = self.last_source.is_some_and(|l| t < l);
                let late = self
                    .offset
                    .is_some_and(|o| arrival - (t + o) > RESTART_LATENESS);
                if went_back && late {
                    // The sender restarted: its clock starts again.
                    self.offset = None;
                }
                self.last_source = Some(t);
                let o = self.offset.map_or(arrival - t, |o| o.min(arrival - t));
                self.offset = Some(o);
                t + o
            }
            None => arrival,
        };
        self.merged.update(pose);
        let frame = Frame {
            due,
            source_time,
            pose: self.merged.clone(),
            arrived,
            shown: false,
        };
        // Keep due order (a late datagram of an older frame slots in).
        let at = self.frames.partition_point(|f| f.due <= due);
        self.frames.insert(at, frame);
    }

    /// The pose to show at `now` (receiver clock): the frames due `latency` ago,
    /// interpolated; `None` before the first is due. Frames no longer needed are dropped.
    pub fn play(&mut self, now: f64) -> Option<Playout> {
        let t = now - self.latency;
        // Keep one frame at or before t: the start of the interpolation.
        while self.frames.len() >= 2 && self.frames[1].due <= t {
            self.frames.pop_front();
        }
        let a = self.frames.front_mut()?;
        if a.due > t {
            return None;
        }
        let arrived = if a.shown { None } else { a.arrived };
        a.shown = true;
        let a = &self.frames[0];
        match self.frames.get(1) {
            Some(b) if b.due > a.due => {
                let u = ((t - a.due) / (b.due - a.due)).clamp(0.0, 1.0);
                Some(Playout {
                    pose: a.pose.lerp(&b.pose, u),
                    source_time: a.source_time,
                    arrived,
                })
            }
            _ => Some(Playout {
                pose: a.pose.clone(),
                source_time: a.source_time,
                arrived,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DQuat, DVec3};
    use troupe_body::transform::Transform;

    fn pose(angle: f64) -> VmcPose {
        let mut p = VmcPose::default();
        p.bones[1] = Some(Transform::new(DQuat::from_rotation_x(angle), DVec3::ZERO));
        p
    }

    fn angle(p: &Playout) -> f64 {
        p.pose.bones[1].unwrap().rotation.to_axis_angle().1
    }

    #[test]
    fn a_30_hz_sender_plays_smoothly_despite_jitter() {
        let mut j = JitterBuffer::new(0.02);
        // Frames every 1/30 s carrying angle = T; arrival delayed 0…8 ms unevenly.
        let jitter = [0.0, 0.008, 0.002, 0.006, 0.001, 0.007];
        for (k, d) in jitter.iter().enumerate() {
            let t = k as f64 / 30.0;
            j.push(t + 0.005 + d, Some(t), &pose(t), None);
        }
        assert!(j.play(0.0).is_none(), "nothing is due before the latency");
        // At 100 Hz ticks the played angle follows T linearly, jitter gone: the offset is
        // the smallest delay (5 ms) and frames play 20 ms after that.
        for tick in 3..15 {
            let now = tick as f64 / 100.0;
            let got = angle(&j.play(now).unwrap());
            let want = (now - 0.025).clamp(0.0, 5.0 / 30.0);
            assert!((got - want).abs() < 1e-6, "tick {tick}: {got} vs {want}");
        }
    }

    #[test]
    fn without_sender_time_frames_play_by_arrival_and_hold_the_last() {
        let mut j = JitterBuffer::new(0.0);
        j.push(0.0, None, &pose(0.0), None);
        j.push(0.1, None, &pose(0.2), None);
        assert!((angle(&j.play(0.05).unwrap()) - 0.1).abs() < 1e-9);
        assert!((angle(&j.play(1.0).unwrap()) - 0.2).abs() < 1e-9);
        // A restarted sender (T jumps back) is placed afresh.
        let mut j = JitterBuffer::new(0.0);
        j.push(10.0, Some(100.0), &pose(0.1), None);
        j.push(10.1, Some(0.0), &pose(0.3), None);
        assert!((angle(&j.play(10.1).unwrap()) - 0.3).abs() < 1e-9);
    }

    #[test]
    fn a_sender_restarted_less_than_a_second_into_its_clock_plays_at_once() {
        // The tester's case: a sender runs 1 s (T 0…1), is silent 0.3 s, and starts
        // again from T = 0 with another pose: its clock went back by only 1 s.
        let mut j = JitterBuffer::new(0.02);
        for k in 0..=60 {
            let t = k as f64 / 60.0;
            j.push(10.0 + t, Some(t), &pose(0.1), None);
        }
        for k in 0..=30 {
            let t = k as f64 / 60.0;
            j.push(11.3 + t, Some(t), &pose(0.5), None);
        }
        let got = angle(&j.play(11.3 + 0.25).unwrap());
        assert!(
            (got - 0.5).abs() < 1e-9,
            "{got}: still the first sender's pose"
        );
    }

    #[test]
    fn a_datagram_overtaken_on_the_network_is_not_a_restart() {
        let mut j = JitterBuffer::new(0.02);
        j.push(10.000, Some(0.0), &pose(0.0), None);
        j.push(10.035, Some(2.0 / 60.0), &pose(0.2), None);
        // The frame between them arrives last, 29 ms late: it slots in by its T.
        j.push(10.045, Some(1.0 / 60.0), &pose(0.1), None);
        let mid = 10.0 + 1.0 / 60.0 + 0.02;
        assert!((angle(&j.play(mid).unwrap()) - 0.1).abs() < 1e-9);
        let end = 10.0 + 2.0 / 60.0 + 0.02;
        assert!((angle(&j.play(end).unwrap()) - 0.2).abs() < 1e-9);
    }
}
