//! A BVH's own channels as a troupe sequence and back: one track per channel, in troupe's
//! units (radians, metres).

use super::channel::Channel;
use super::motion::Bvh;
use crate::error::Result;
use crate::rig::sampled_frames;
use troupe_motion::sequence::{Key, Sequence, Track};

impl Bvh {
    /// The BVH's own channels as a troupe sequence: one track per channel, named
    /// `JOINT.Xrotation` etc., with rotations in radians and positions multiplied by
    /// `scale` (file units to metres). Metadata records `rate`, `source` and `bvh_scale`.
    pub fn to_channel_sequence(&self, name: &str, scale: f64) -> Result<Sequence> {
        let mut seq = Sequence::new(name);
        seq.meta
            .insert("rate".into(), format!("{}", 1.0 / self.frame_time()));
        seq.meta.insert("source".into(), "bvh".into());
        seq.meta.insert("bvh_scale".into(), format!("{scale}"));
        for j in self.joints() {
            for (i, c) in j.channels.iter().enumerate() {
                // Rotations are unwrapped (±360° jumps removed) so that tools that filter
                // or blend see a continuous curve; the rotations are the same.
                let mut last: Option<f64> = None;
                let keys = (0..self.frame_count())
                    .map(|k| {
                        let v = self.frame(k)[j.first_channel + i];
                        let v = match c {
                            Channel::Position(_) => v * scale,
                            Channel::Rotation(_) => {
                                let mut r = v.to_radians();
                                if let Some(p) = last {
                                    r -= std::f64::consts::TAU
                                        * ((r - p) / std::f64::consts::TAU).round();
                                }
                                last = Some(r);
                                r
                            }
                        };
                        Key::new(k as f64 * self.frame_time(), v)
                    })
                    .collect();
                seq.add_track(Track::new(format!("{}.{c}", j.name), keys)?)?;
            }
        }
        Ok(seq)
    }

    /// The BVH motion of a channel sequence made by [`Bvh::to_channel_sequence`] (perhaps
    /// edited since) on this hierarchy: frames every `seq.frame_time()` from the
    /// sequence's start to its end; positions are divided by `scale`. A channel without a
    /// track keeps this motion's value at the same frame (its last frame past the end).
    pub fn with_channel_sequence(&self, seq: &Sequence, scale: f64) -> Result<Bvh> {
        let ft = seq.frame_time();
        let n = sampled_frames(seq)?;
        let mut data = Vec::with_capacity(n * self.channel_count());
        let tracks: Vec<Option<&Track>> = self
            .joints()
            .iter()
            .flat_map(|j| {
                j.channels
                    .iter()
                    .map(move |c| seq.track(&format!("{}.{c}", j.name)))
            })
            .collect();
        let kinds: Vec<Channel> = self
            .joints()
            .iter()
            .flat_map(|j| j.channels.clone())
            .collect();
        let mut cursors = vec![0usize; tracks.len()];
        for k in 0..n {
            let t = seq.start() + k as f64 * ft;
            for (c, track) in tracks.iter().enumerate() {
                let v = match track {
                    Some(tr) => match kinds[c] {
                        Channel::Position(_) => tr.value_at(t, &mut cursors[c]) / scale,
                        Channel::Rotation(_) => tr.value_at(t, &mut cursors[c]).to_degrees(),
                    },
                    None if self.frame_count() > 0 => self.frame(k.min(self.frame_count() - 1))[c],
                    None => 0.0,
                };
                data.push(v);
            }
        }
        Bvh::new(self.joints().to_vec(), ft, data)
    }
}

#[cfg(test)]
mod tests {
    use crate::bvh::fixtures::{data, max_position_difference};
    use crate::bvh::read_bvh;

    #[test]
    fn channel_sequences_round_trip_through_troupe_units() {
        let b = read_bvh(data("pybvhrepo_cmu_12_01_walk.bvh")).unwrap();
        let seq = b.to_channel_sequence("walk", 0.01).unwrap();
        assert_eq!(seq.tracks().len(), b.channel_count());
        assert!((seq.frame_time() - b.frame_time()).abs() < 1e-12);
        let back = b.with_channel_sequence(&seq, 0.01).unwrap();
        assert_eq!(back.frame_count(), b.frame_count());
        assert!(max_position_difference(&b, &back) < 1e-6);
    }
}
