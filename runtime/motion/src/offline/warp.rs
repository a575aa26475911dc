//! Time warping (thesis 5.6): constraints `(t, t′)` — the value the sequence had at time
//! `t` is displaced to `t′` — interpolated by a monotone cubic Hermite curve; and
//! "squeeze and stretch" of the key times around one key, keeping their ratios.

use crate::error::{Error, Result};
use crate::sequence::{Key, Sequence, Track};

/// A strictly increasing map from original time `t` to new time `t′`: the cubic Hermite
/// curve through the constraints with Fritsch–Carlson (harmonic-mean) slopes inside and the
/// end chords' slopes at the ends, so it never folds back; extended linearly outside.
#[derive(Clone, Debug, PartialEq)]
pub struct TimeWarp {
    from: Vec<f64>,
    to: Vec<f64>,
    slopes: Vec<f64>,
}

impl TimeWarp {
    /// A warp through `(t, t′)` pairs, both strictly increasing. One pair is a shift.
    pub fn new(pairs: &[(f64, f64)]) -> Result<TimeWarp> {
        if pairs.is_empty() {
            return Err(Error::Invalid(
                "a time warp needs at least one t:t' pair".into(),
            ));
        }
        for (i, &(t, u)) in pairs.iter().enumerate() {
            if !t.is_finite() || !u.is_finite() {
                return Err(Error::Invalid(format!(
                    "time warp pair {}: not finite",
                    i + 1
                )));
            }
            if i > 0 && (t <= pairs[i - 1].0 || u <= pairs[i - 1].1) {
                return Err(Error::Invalid(format!(
                    "time warp pair {} ({t}:{u}) must come after {}:{} in both times",
                    i + 1,
                    pairs[i - 1].0,
                    pairs[i - 1].1
                )));
            }
        }
        let from: Vec<f64> = pairs.iter().map(|p| p.0).collect();
        let to: Vec<f64> = pairs.iter().map(|p| p.1).collect();
        let n = pairs.len();
        let chord: Vec<f64> = (0..n.saturating_sub(1))
            .map(|i| (to[i + 1] - to[i]) / (from[i + 1] - from[i]))
            .collect();
        let slopes = (0..n)
            .map(
                |i| match (i.checked_sub(1).map(|j| chord[j]), chord.get(i)) {
                    (None, None) => 1.0,
                    (Some(d), None) | (None, Some(&d)) => d,
                    (Some(d0), Some(&d1)) => 2.0 / (1.0 / d0 + 1.0 / d1),
                },
            )
            .collect();
        Ok(TimeWarp { from, to, slopes })
    }

    /// The new time of original time `t`.
    pub fn map(&self, t: f64) -> f64 {
        let n = self.from.len();
        if t <= self.from[0] {
            return self.to[0] + (t - self.from[0]) * self.slopes[0];
        }
        if t >= self.from[n - 1] {
            return self.to[n - 1] + (t - self.from[n - 1]) * self.slopes[n - 1];
        }
        let i = self.from.partition_point(|&x| x <= t) - 1;
        let h = self.from[i + 1] - self.from[i];
        let s = (t - self.from[i]) / h;
        let (s2, s3) = (s * s, s * s * s);
        (2.0 * s3 - 3.0 * s2 + 1.0) * self.to[i]
            + (s3 - 2.0 * s2 + s) * h * self.slopes[i]
            + (-2.0 * s3 + 3.0 * s2) * self.to[i + 1]
            + (s3 - s2) * h * self.slopes[i + 1]
    }

    /// `dt′/dt` at original time `t`.
    pub fn derivative(&self, t: f64) -> f64 {
        let n = self.from.len();
        if t <= self.from[0] {
            return self.slopes[0];
        }
        if t >= self.from[n - 1] {
            return self.slopes[n - 1];
        }
        let i = self.from.partition_point(|&x| x <= t) - 1;
        let h = self.from[i + 1] - self.from[i];
        let s = (t - self.from[i]) / h;
        let s2 = s * s;
        ((6.0 * s2 - 6.0 * s) * self.to[i] + (-6.0 * s2 + 6.0 * s) * self.to[i + 1]) / h
            + (3.0 * s2 - 4.0 * s + 1.0) * self.slopes[i]
            + (3.0 * s2 - 2.0 * s) * self.slopes[i + 1]
    }
}

/// Moves every key of `seq` by `map` (explicit slopes are divided by `dt′/dt` so the
/// motion keeps its shape in the new time). A `rate` in the metadata stays true: keys
/// moved by one factor (a uniform stretch or squeeze, a shift) are `factor / rate`
/// apart; keys moved unevenly have no rate, and it is dropped (the frame time then
/// follows the keys, see [`Sequence::frame_time`]).
pub fn remap_times(
    seq: &Sequence,
    map: impl Fn(f64) -> f64,
    derivative: impl Fn(f64) -> f64,
) -> Result<Sequence> {
    let mut out = seq.empty_like();
    if let Some(rate) = out.meta.get("rate").and_then(|r| r.parse::<f64>().ok()) {
        match uniform_factor(seq, &map) {
            Some(factor) => {
                let rate = format!("{}", rate / factor);
                out.meta.insert("rate".into(), rate);
            }
            None => {
                out.meta.remove("rate");
            }
        }
    }
    for track in seq.tracks() {
        let keys = track
            .keys()
            .iter()
            .map(|k| Key {
                time: map(k.time),
                value: k.value,
                slope: k.slope.map(|s| {
                    let d = derivative(k.time);
                    if d > 0.0 {
                        s / d
                    } else {
                        s
                    }
                }),
            })
            .collect();
        out.add_track(Track::new(track.dof(), keys)?.with_interpolation(track.interpolation()))?;
    }
    Ok(out)
}

/// The one factor by which `map` scales the time between every two keys of `seq`, if
/// it scales them all alike (within 1e-9 s); `None` when the keys move unevenly.
fn uniform_factor(seq: &Sequence, map: &impl Fn(f64) -> f64) -> Option<f64> {
    let times = || {
        seq.tracks()
            .iter()
            .flat_map(|t| t.keys().iter().map(|k| k.time))
    };
    let first = times().fold(f64::INFINITY, f64::min);
    let last = times().fold(f64::NEG_INFINITY, f64::max);
    if last <= first {
        // One key time (or none): nothing is spaced, so any factor keeps the rate.
        return Some(1.0);
    }
    let (from, to) = (map(first), map(last));
    let factor = (to - from) / (last - first);
    let even = times().all(|t| (map(t) - (from + (t - first) * factor)).abs() <= 1e-9);
    (factor > 0.0 && even).then_some(factor)
}

/// Warps a sequence's time by `warp` (the keys move, their values stay).
pub fn warp_sequence(seq: &Sequence, warp: &TimeWarp) -> Result<Sequence> {
    remap_times(seq, |t| warp.map(t), |t| warp.derivative(t))
}

/// Squeeze and stretch (5.6): key time `t` moves to `new_t` inside `[tl, tr]`; keys in
/// `[tl, t]` keep their ratio `(t − ti)/(t − tl)`, keys in `[t, tr]` keep
/// `(ti − t)/(tr − t)`; keys outside `[tl, tr]` do not move.
pub fn squeeze_stretch(seq: &Sequence, tl: f64, t: f64, tr: f64, new_t: f64) -> Result<Sequence> {
    if !(tl <= t && t <= tr && tl < tr) || !(tl < new_t && new_t < tr || new_t == t) {
        return Err(Error::Invalid(format!(
            "squeeze/stretch needs tl ≤ t ≤ tr and tl < new time < tr (got {tl}, {t}, {tr}, {new_t})"
        )));
    }
    if (t == tl || t == tr) && new_t != t {
        // A limit key itself moves: one side keeps its ratio, the other is empty.
        if t == tr {
            let f = (new_t - tl) / (t - tl);
            return remap_times(
                seq,
                |x| {
                    if (tl..=t).contains(&x) {
                        tl + (x - tl) * f
                    } else {
                        x
                    }
                },
                |x| if (tl..=t).contains(&x) { f } else { 1.0 },
            );
        }
        let f = (tr - new_t) / (tr - t);
        return remap_times(
            seq,
            |x| {
                if (t..=tr).contains(&x) {
                    tr - (tr - x) * f
                } else {
                    x
                }
            },
            |x| if (t..=tr).contains(&x) { f } else { 1.0 },
        );
    }
    let left = (new_t - tl) / (t - tl);
    let right = (tr - new_t) / (tr - t);
    remap_times(
        seq,
        |x| {
            if x < tl || x > tr {
                x
            } else if x <= t {
                new_t - (t - x) / (t - tl) * (new_t - tl)
            } else {
                new_t + (x - t) / (tr - t) * (tr - new_t)
            }
        },
        |x| {
            if x < tl || x > tr {
                1.0
            } else if x <= t {
                left
            } else {
                right
            }
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn seq() -> Sequence {
        let mut s = Sequence::new("s");
        let keys = (0..=10)
            .map(|i| Key::new(i as f64 * 0.1, (i * i) as f64))
            .collect();
        s.add_track(Track::new("x", keys).unwrap()).unwrap();
        s
    }

    #[test]
    fn warp_passes_through_constraints_and_is_monotone() {
        let w = TimeWarp::new(&[(0.0, 0.0), (0.5, 0.2), (0.6, 0.9), (1.0, 1.0)]).unwrap();
        for (t, u) in [(0.0, 0.0), (0.5, 0.2), (0.6, 0.9), (1.0, 1.0)] {
            assert!((w.map(t) - u).abs() < 1e-12);
        }
        let mut last = f64::NEG_INFINITY;
        for i in 0..=1000 {
            let x = w.map(i as f64 * 0.0012 - 0.1);
            assert!(x > last);
            last = x;
        }
        let s = warp_sequence(&seq(), &w).unwrap();
        let x = s.track("x").unwrap();
        // The value at original 0.5 is now at 0.2.
        assert!((x.value(0.2) - 25.0).abs() < 1e-9);
        assert!(TimeWarp::new(&[(0.0, 1.0), (1.0, 0.5)]).is_err());
        // One pair shifts.
        let shift = TimeWarp::new(&[(0.0, 2.0)]).unwrap();
        assert_eq!(shift.map(0.5), 2.5);
    }

    #[test]
    fn squeeze_keeps_ratios() {
        // Move the key at 0.5 to 0.3 within [0.2, 0.9].
        let s = squeeze_stretch(&seq(), 0.2, 0.5, 0.9, 0.3).unwrap();
        let times: Vec<f64> = s
            .track("x")
            .unwrap()
            .keys()
            .iter()
            .map(|k| k.time)
            .collect();
        assert!((times[5] - 0.3).abs() < 1e-12);
        assert!((times[3] - (0.3 - (0.2 / 0.3) * 0.1)).abs() < 1e-12);
        assert!((times[7] - (0.3 + (0.2 / 0.4) * 0.6)).abs() < 1e-12);
        assert_eq!(times[1], 0.1);
        assert_eq!(times[10], 1.0);
        assert!(squeeze_stretch(&seq(), 0.2, 0.5, 0.9, 0.95).is_err());
    }

    #[test]
    fn the_rate_follows_an_even_warp_and_is_dropped_by_an_uneven_one() {
        let mut rated = seq();
        rated.meta.insert("rate".into(), "10".into());
        let rate = |s: &Sequence| s.meta.get("rate").cloned();
        // Twice as slow: keys 0.2 s apart, 5 Hz; a shift keeps the rate.
        let slow = TimeWarp::new(&[(0.0, 0.0), (1.0, 2.0)]).unwrap();
        let slower = warp_sequence(&rated, &slow).unwrap();
        assert_eq!(rate(&slower).as_deref(), Some("5"));
        assert!((slower.frame_time() - 0.2).abs() < 1e-12);
        let shift = TimeWarp::new(&[(0.0, 3.0)]).unwrap();
        assert_eq!(
            rate(&warp_sequence(&rated, &shift).unwrap()).as_deref(),
            Some("10")
        );
        // Uneven warps leave no rate that holds.
        let uneven = TimeWarp::new(&[(0.0, 0.0), (0.5, 0.2), (1.0, 1.0)]).unwrap();
        assert_eq!(rate(&warp_sequence(&rated, &uneven).unwrap()), None);
        assert_eq!(
            rate(&squeeze_stretch(&rated, 0.2, 0.5, 0.9, 0.3).unwrap()),
            None
        );
        // Without a rate, none is made up.
        assert_eq!(rate(&warp_sequence(&seq(), &slow).unwrap()), None);
    }
}
