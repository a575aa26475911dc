//! Motion sequences (thesis 5.7 and 6.4.5): per-DOF tracks of Hermite keys on a common
//! time base.
//!
//! How a track fills the time between its keys is its [`Interpolation`]. The default,
//! `cubic`, is a monotone cubic (Fritsch–Carlson, with the Fritsch–Butland slopes that
//! SciPy's `PchipInterpolator` uses): where slopes are not given, the curve between two
//! keys never leaves the range of those two keys, so a hold stays a hold and a peak key is
//! the peak. A slope given on a key is used exactly (plain cubic Hermite), so a curve with
//! explicit slopes is the author's. `hermite` keeps the thesis's own default slopes (the
//! chord of the neighbouring keys, which overshoots next to a hold); `linear` and `step`
//! ignore slopes.

use crate::error::{Error, Result};
use std::collections::BTreeMap;

/// The longest sampling period (s) of a sequence that states no rate (see
/// [`Sequence::frame_time`]): troupe's tick at its default 100 Hz.
pub const FINEST_UNRATED_FRAME: f64 = 0.01;

/// One key of a track: a value at a time, with an optional slope (value per second).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// Time in seconds.
    pub time: f64,
    /// DOF value (radians or metres).
    pub value: f64,
    /// First derivative at the key; `None` takes the default of thesis 5.7.
    pub slope: Option<f64>,
}

impl Key {
    /// A key with the default slope.
    pub fn new(time: f64, value: f64) -> Self {
        Key {
            time,
            value,
            slope: None,
        }
    }

    /// A key with an explicit slope.
    pub fn with_slope(time: f64, value: f64, slope: f64) -> Self {
        Key {
            time,
            value,
            slope: Some(slope),
        }
    }
}

/// How a track fills the time between two keys.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Hash)]
pub enum Interpolation {
    /// Monotone cubic Hermite: default slopes never leave the two keys' range; given
    /// slopes are exact.
    #[default]
    Cubic,
    /// Cubic Hermite with the thesis's default slopes (5.7: zero at the ends, the chord of
    /// the neighbouring keys inside), which may overshoot; given slopes are exact.
    Hermite,
    /// A straight line between keys (slopes ignored).
    Linear,
    /// The earlier key's value holds until the next key (slopes ignored).
    Step,
}

impl Interpolation {
    /// Every interpolation, in the order of its names.
    pub const ALL: [Interpolation; 4] = [
        Interpolation::Cubic,
        Interpolation::Hermite,
        Interpolation::Linear,
        Interpolation::Step,
    ];

    /// The name used in `.trk` files and in Lua (`cubic`, `hermite`, `linear`, `step`).
    pub fn name(self) -> &'static str {
        match self {
            Interpolation::Cubic => "cubic",
            Interpolation::Hermite => "hermite",
            Interpolation::Linear => "linear",
            Interpolation::Step => "step",
        }
    }

    /// The interpolation called `name`, if there is one.
    pub fn from_name(name: &str) -> Option<Interpolation> {
        Interpolation::ALL.into_iter().find(|i| i.name() == name)
    }
}

/// The keys of one DOF and how to interpolate between them.
#[derive(Clone, Debug, PartialEq)]
pub struct Track {
    dof: String,
    keys: Vec<Key>,
    interpolation: Interpolation,
    slopes: Vec<f64>,
}

impl Track {
    /// Builds a track with the default (monotone cubic) interpolation; times must be
    /// finite and strictly increasing, values and slopes finite, and there must be at
    /// least one key.
    pub fn new(dof: impl Into<String>, keys: Vec<Key>) -> Result<Track> {
        let dof = dof.into();
        if keys.is_empty() {
            return Err(Error::Invalid(format!("track `{dof}` has no keys")));
        }
        for (i, k) in keys.iter().enumerate() {
            if !k.time.is_finite()
                || !k.value.is_finite()
                || k.slope.is_some_and(|s| !s.is_finite())
            {
                return Err(Error::Invalid(format!(
                    "track `{dof}` key {}: time, value and slope must be finite numbers",
                    i + 1
                )));
            }
            if i > 0 && k.time <= keys[i - 1].time {
                return Err(Error::Invalid(format!(
                    "track `{dof}` key {}: time {} does not follow {}",
                    i + 1,
                    k.time,
                    keys[i - 1].time
                )));
            }
        }
        let interpolation = Interpolation::default();
        let slopes = slopes_for(&keys, interpolation);
        Ok(Track {
            dof,
            keys,
            interpolation,
            slopes,
        })
    }

    /// The same keys interpolated by `interpolation`.
    pub fn with_interpolation(mut self, interpolation: Interpolation) -> Track {
        self.set_interpolation(interpolation);
        self
    }

    /// Interpolates the keys by `interpolation` from now on.
    pub fn set_interpolation(&mut self, interpolation: Interpolation) {
        self.slopes = slopes_for(&self.keys, interpolation);
        self.interpolation = interpolation;
    }

    /// How the track interpolates between its keys.
    pub fn interpolation(&self) -> Interpolation {
        self.interpolation
    }

    /// The DOF name the track drives.
    pub fn dof(&self) -> &str {
        &self.dof
    }
    /// The keys as given.
    pub fn keys(&self) -> &[Key] {
        &self.keys
    }
    /// The slope used at each key by the cubic interpolations (given, or the default).
    pub fn slopes(&self) -> &[f64] {
        &self.slopes
    }
    /// Time of the first key.
    pub fn start(&self) -> f64 {
        self.keys[0].time
    }
    /// Time of the last key.
    pub fn end(&self) -> f64 {
        self.keys[self.keys.len() - 1].time
    }

    /// The value at `t`; before the first key and after the last the end values hold.
    pub fn value(&self, t: f64) -> f64 {
        let mut cursor = 0;
        self.value_at(t, &mut cursor)
    }

    /// The value at `t`, using and updating `cursor` (a key index) so that evaluating at
    /// increasing times costs O(1) per call.
    #[inline]
    pub fn value_at(&self, t: f64, cursor: &mut usize) -> f64 {
        let segment = self.segment(t, cursor);
        self.value_in(segment)
    }

    /// Where `t` falls among the keys (updating `cursor` as [`Track::value_at`] does).
    /// Tracks with the same key times share it: see [`Track::same_times`].
    #[inline]
    pub fn locate(&self, t: f64, cursor: &mut usize) -> Segment {
        self.segment(t, cursor)
    }

    /// Whether both tracks have keys at exactly the same times.
    pub fn same_times(&self, other: &Track) -> bool {
        self.keys.len() == other.keys.len()
            && self
                .keys
                .iter()
                .zip(&other.keys)
                .all(|(a, b)| a.time == b.time)
    }

    /// The value in a segment found by [`Track::locate`] on a track with the same key times.
    #[inline]
    pub fn value_in(&self, segment: Segment) -> f64 {
        match segment {
            Segment::Before => self.keys[0].value,
            Segment::After => self.keys[self.keys.len() - 1].value,
            Segment::Inside(i, s, h) => {
                let (k0, k1) = (&self.keys[i], &self.keys[i + 1]);
                match self.interpolation {
                    Interpolation::Step => return k0.value,
                    Interpolation::Linear => return k0.value + s * (k1.value - k0.value),
                    Interpolation::Cubic | Interpolation::Hermite => {}
                }
                let (s2, s3) = (s * s, s * s * s);
                // The Hermite basis with h00 = 1 − h01 folded in, so that a hold (equal
                // values, zero slopes) returns its value exactly.
                let h10 = s3 - 2.0 * s2 + s;
                let h01 = -2.0 * s3 + 3.0 * s2;
                let h11 = s3 - s2;
                k0.value
                    + h01 * (k1.value - k0.value)
                    + h * (h10 * self.slopes[i] + h11 * self.slopes[i + 1])
            }
        }
    }

    /// The first derivative at `t` (zero outside the keyed range; for `linear`, the
    /// chord of the segment `t` starts; for `step`, zero).
    pub fn velocity(&self, t: f64) -> f64 {
        let n = self.keys.len();
        let cubic = matches!(
            self.interpolation,
            Interpolation::Cubic | Interpolation::Hermite
        );
        if n > 1 && cubic && t == self.keys[0].time {
            return self.slopes[0];
        }
        if n > 1 && cubic && t == self.keys[n - 1].time {
            return self.slopes[n - 1];
        }
        let mut cursor = 0;
        match self.segment(t, &mut cursor) {
            Segment::Before | Segment::After => 0.0,
            Segment::Inside(i, s, h) => {
                let (k0, k1) = (&self.keys[i], &self.keys[i + 1]);
                match self.interpolation {
                    Interpolation::Step => return 0.0,
                    Interpolation::Linear => return (k1.value - k0.value) / h,
                    Interpolation::Cubic | Interpolation::Hermite => {}
                }
                let s2 = s * s;
                let d00 = 6.0 * s2 - 6.0 * s;
                let d10 = 3.0 * s2 - 4.0 * s + 1.0;
                let d01 = -6.0 * s2 + 6.0 * s;
                let d11 = 3.0 * s2 - 2.0 * s;
                (d00 * k0.value + d01 * k1.value) / h
                    + d10 * self.slopes[i]
                    + d11 * self.slopes[i + 1]
            }
        }
    }

    /// The values at `n` evenly spaced times `t0, t0 + dt, …`.
    pub fn sample(&self, t0: f64, dt: f64, n: usize) -> Vec<f64> {
        let mut cursor = 0;
        (0..n)
            .map(|i| self.value_at(t0 + i as f64 * dt, &mut cursor))
            .collect()
    }

    /// A track of keys at `t0, t0 + dt, …` through `values`, with explicit slopes: central
    /// differences inside, one-sided differences at the ends (so a sampled straight line
    /// stays straight).
    pub fn from_samples(dof: impl Into<String>, t0: f64, dt: f64, values: &[f64]) -> Result<Track> {
        let slopes = sample_slopes(values, dt);
        let keys = values
            .iter()
            .zip(slopes)
            .enumerate()
            .map(|(i, (&v, s))| Key::with_slope(t0 + i as f64 * dt, v, s))
            .collect();
        Track::new(dof, keys)
    }

    /// The same keys (and interpolation) under another DOF name.
    pub fn renamed(&self, dof: impl Into<String>) -> Track {
        Track {
            dof: dof.into(),
            ..self.clone()
        }
    }

    #[inline]
    fn segment(&self, t: f64, cursor: &mut usize) -> Segment {
        let keys = &self.keys;
        let n = keys.len();
        if n == 1 || t <= keys[0].time {
            return Segment::Before;
        }
        if t >= keys[n - 1].time {
            return Segment::After;
        }
        let mut i = (*cursor).min(n - 2);
        if keys[i].time > t || keys[i + 1].time <= t {
            // Not in the cached segment: look at the next one, else search.
            if i + 2 < n && keys[i + 1].time <= t && keys[i + 2].time > t {
                i += 1;
            } else {
                i = keys.partition_point(|k| k.time <= t) - 1;
            }
        }
        *cursor = i;
        let h = keys[i + 1].time - keys[i].time;
        Segment::Inside(i, (t - keys[i].time) / h, h)
    }
}

/// Where a time falls among a track's keys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    /// Before (or at) the first key.
    Before,
    /// At or after the last key.
    After,
    /// Between key `i` and `i + 1`: (i, fraction in [0, 1), segment length in seconds).
    Inside(usize, f64, f64),
}

/// The slope at each key for `interpolation`: a given slope is kept; otherwise zero at
/// the ends ("start slowly / end slowly", thesis 5.7) and inside the default of the
/// interpolation (unused by `linear` and `step`, which ignore slopes).
fn slopes_for(keys: &[Key], interpolation: Interpolation) -> Vec<f64> {
    let n = keys.len();
    let secant = |i: usize| (keys[i + 1].value - keys[i].value) / (keys[i + 1].time - keys[i].time);
    (0..n)
        .map(|i| {
            keys[i].slope.unwrap_or_else(|| {
                if i == 0 || i == n - 1 {
                    return 0.0;
                }
                match interpolation {
                    Interpolation::Hermite => {
                        (keys[i + 1].value - keys[i - 1].value)
                            / (keys[i + 1].time - keys[i - 1].time)
                    }
                    Interpolation::Cubic => monotone_slope(
                        secant(i - 1),
                        secant(i),
                        keys[i].time - keys[i - 1].time,
                        keys[i + 1].time - keys[i].time,
                    ),
                    Interpolation::Linear | Interpolation::Step => 0.0,
                }
            })
        })
        .collect()
}

/// The Fritsch–Butland slope at a key between secants `d0` (over `h0` seconds) and `d1`
/// (over `h1`): zero where the keys turn or hold, else a weighted harmonic mean of the
/// secants. It is at most three times the smaller secant, inside the Fritsch–Carlson
/// region where a cubic Hermite segment is monotone, so with zero end slopes a segment
/// stays between its two keys.
fn monotone_slope(d0: f64, d1: f64, h0: f64, h1: f64) -> f64 {
    if d0 * d1 <= 0.0 {
        return 0.0;
    }
    let (w0, w1) = (2.0 * h1 + h0, h1 + 2.0 * h0);
    (w0 + w1) / (w0 / d0 + w1 / d1)
}

/// Slopes of evenly spaced samples: central differences inside, one-sided at the ends.
pub fn sample_slopes(values: &[f64], dt: f64) -> Vec<f64> {
    let n = values.len();
    (0..n)
        .map(|i| {
            if n < 2 {
                0.0
            } else if i == 0 {
                (values[1] - values[0]) / dt
            } else if i == n - 1 {
                (values[n - 1] - values[n - 2]) / dt
            } else {
                (values[i + 1] - values[i - 1]) / (2.0 * dt)
            }
        })
        .collect()
}

/// A multiple-track sequence: tracks for several DOFs on one time base, with metadata.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct Sequence {
    /// A name for listings (often the file stem).
    pub name: String,
    /// Whether players loop it by default.
    pub looping: bool,
    /// Free-form metadata (`rate`, `source`, …), kept through read and write.
    pub meta: BTreeMap<String, String>,
    tracks: Vec<Track>,
}

impl Sequence {
    /// An empty sequence.
    pub fn new(name: impl Into<String>) -> Self {
        Sequence {
            name: name.into(),
            ..Default::default()
        }
    }

    /// Adds a track; a DOF may have only one track.
    pub fn add_track(&mut self, track: Track) -> Result<()> {
        if self.tracks.iter().any(|t| t.dof == track.dof) {
            return Err(Error::Duplicate {
                what: "track for DOF",
                name: track.dof,
            });
        }
        self.tracks.push(track);
        Ok(())
    }

    /// The tracks in insertion order.
    pub fn tracks(&self) -> &[Track] {
        &self.tracks
    }

    /// The track of DOF `dof`.
    pub fn track(&self, dof: &str) -> Option<&Track> {
        self.tracks.iter().find(|t| t.dof == dof)
    }

    /// The earliest key time (0 for an empty sequence).
    pub fn start(&self) -> f64 {
        finite_or_zero(
            self.tracks
                .iter()
                .map(Track::start)
                .fold(f64::INFINITY, f64::min),
        )
    }

    /// The latest key time (0 for an empty sequence).
    pub fn end(&self) -> f64 {
        finite_or_zero(
            self.tracks
                .iter()
                .map(Track::end)
                .fold(f64::NEG_INFINITY, f64::max),
        )
    }

    /// `end − start`.
    pub fn duration(&self) -> f64 {
        self.end() - self.start()
    }

    /// The sequence's sampling period: `1 / meta rate` when that is a positive number
    /// (a recording, a motion file), else the smallest key spacing of any track, at most
    /// [`FINEST_UNRATED_FRAME`]: hand-set keys half a second apart are curves, which a
    /// frame at every key would turn into straight lines.
    pub fn frame_time(&self) -> f64 {
        if let Some(rate) = self.meta.get("rate").and_then(|r| r.parse::<f64>().ok()) {
            if rate.is_finite() && rate > 0.0 {
                return 1.0 / rate;
            }
        }
        let min = self
            .tracks
            .iter()
            .flat_map(|t| t.keys.windows(2).map(|w| w[1].time - w[0].time))
            .fold(f64::INFINITY, f64::min);
        if min.is_finite() && min > 0.0 {
            min.min(FINEST_UNRATED_FRAME)
        } else {
            FINEST_UNRATED_FRAME
        }
    }

    /// Interpolates every track by `interpolation`.
    pub fn set_interpolation(&mut self, interpolation: Interpolation) {
        for track in &mut self.tracks {
            track.set_interpolation(interpolation);
        }
    }

    /// A sequence with the same name, looping flag and metadata, and no tracks.
    pub fn empty_like(&self) -> Sequence {
        Sequence {
            name: self.name.clone(),
            looping: self.looping,
            meta: self.meta.clone(),
            tracks: Vec::new(),
        }
    }
}

/// The fold of an empty track list is infinite; such a sequence spans [0, 0].
fn finite_or_zero(x: f64) -> f64 {
    if x.is_finite() {
        x
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolates_keys_and_default_slopes() {
        let t = Track::new(
            "x",
            vec![Key::new(0.0, 0.0), Key::new(1.0, 2.0), Key::new(2.0, 0.0)],
        )
        .unwrap();
        assert_eq!(t.slopes(), &[0.0, 0.0, 0.0]);
        assert_eq!(t.value(1.0), 2.0);
        assert_eq!(t.value(0.5), 1.0);
        assert_eq!(t.value(-1.0), 0.0);
        assert_eq!(t.value(3.0), 0.0);
        let ramp = Track::new(
            "y",
            vec![Key::new(0.0, 0.0), Key::new(1.0, 1.0), Key::new(2.0, 2.0)],
        )
        .unwrap();
        assert_eq!(ramp.slopes()[1], 1.0);
        // Zero end slopes: starts slowly.
        assert!(ramp.value(0.1) < 0.1);
    }

    /// The value range of keys `i` and `i + 1`, widened by a rounding margin.
    fn key_range(t: &Track, i: usize) -> (f64, f64) {
        let (a, b) = (t.keys()[i].value, t.keys()[i + 1].value);
        let eps = 1e-12 * (1.0 + a.abs().max(b.abs()));
        (a.min(b) - eps, a.max(b) + eps)
    }

    #[test]
    fn a_hold_between_two_keys_stays_a_hold() {
        // The case: with the thesis's chord slopes the hold peaks at 1.2.
        let keys = vec![
            Key::new(0.0, 0.0),
            Key::new(1.0, 1.0),
            Key::new(2.0, 1.0),
            Key::new(3.0, 0.0),
        ];
        let cubic = Track::new("x", keys.clone()).unwrap();
        assert_eq!(cubic.interpolation(), Interpolation::Cubic);
        let hermite = cubic.clone().with_interpolation(Interpolation::Hermite);
        let peak = |t: &Track| {
            (0..=300)
                .map(|i| t.value(i as f64 / 100.0))
                .fold(f64::MIN, f64::max)
        };
        assert_eq!(peak(&cubic), 1.0);
        assert!(
            peak(&hermite) > 1.1,
            "the thesis default overshoots: {}",
            peak(&hermite)
        );
        for i in 0..=100 {
            assert_eq!(cubic.value(1.0 + i as f64 / 100.0), 1.0);
        }
    }

    #[test]
    fn linear_and_step_ignore_slopes() {
        let keys = vec![
            Key::with_slope(0.0, 0.0, 5.0),
            Key::new(2.0, 1.0),
            Key::new(3.0, -1.0),
        ];
        let linear = Track::new("x", keys.clone())
            .unwrap()
            .with_interpolation(Interpolation::Linear);
        assert_eq!(linear.value(0.5), 0.25);
        assert_eq!(linear.value(2.5), 0.0);
        assert_eq!(linear.velocity(1.0), 0.5);
        let step = linear.clone().with_interpolation(Interpolation::Step);
        assert_eq!(step.value(1.999), 0.0);
        assert_eq!(step.value(2.0), 1.0);
        assert_eq!(step.value(2.9), 1.0);
        assert_eq!(step.velocity(2.5), 0.0);
        for i in Interpolation::ALL {
            assert_eq!(Interpolation::from_name(i.name()), Some(i));
        }
        assert_eq!(Interpolation::from_name("spline"), None);
    }

    proptest::proptest! {
        #[test]
        fn the_default_never_leaves_the_range_of_its_two_keys(
            keys in proptest::collection::vec((0.01f64..3.0, -10.0f64..10.0), 2..12),
            steps in 1usize..40,
        ) {
            let mut time = 0.0;
            let keys: Vec<Key> = keys.iter().map(|&(dt, v)| { time += dt; Key::new(time, v) }).collect();
            let track = Track::new("x", keys).unwrap();
            for i in 0..track.keys().len() - 1 {
                let (lo, hi) = key_range(&track, i);
                let (t0, t1) = (track.keys()[i].time, track.keys()[i + 1].time);
                for j in 0..=steps {
                    let v = track.value(t0 + (t1 - t0) * j as f64 / steps as f64);
                    proptest::prop_assert!(lo <= v && v <= hi, "segment {i}: {v} outside [{lo}, {hi}]");
                }
            }
        }

        #[test]
        fn given_slopes_are_exact_hermite(
            v0 in -5.0f64..5.0, v1 in -5.0f64..5.0, m0 in -20.0f64..20.0, m1 in -20.0f64..20.0,
            h in 0.1f64..3.0, s in 0.0f64..1.0,
        ) {
            let track = Track::new("x", vec![Key::with_slope(0.0, v0, m0), Key::with_slope(h, v1, m1)]).unwrap();
            let hermite = track.clone().with_interpolation(Interpolation::Hermite);
            // The cubic Hermite basis written out (thesis 5.7).
            let want = (2.0 * s.powi(3) - 3.0 * s * s + 1.0) * v0
                + (s.powi(3) - 2.0 * s * s + s) * h * m0
                + (-2.0 * s.powi(3) + 3.0 * s * s) * v1
                + (s.powi(3) - s * s) * h * m1;
            let got = track.value(s * h);
            proptest::prop_assert!((got - want).abs() <= 1e-9 * (1.0 + want.abs()), "{got} vs {want}");
            proptest::prop_assert_eq!(got, hermite.value(s * h));
        }
    }

    #[test]
    fn explicit_slopes_make_a_straight_line_exact() {
        let t = Track::new(
            "x",
            vec![
                Key::with_slope(0.0, 1.0, 2.0),
                Key::with_slope(3.0, 7.0, 2.0),
            ],
        )
        .unwrap();
        for i in 0..=30 {
            let x = i as f64 / 10.0;
            assert!((t.value(x) - (1.0 + 2.0 * x)).abs() < 1e-12);
            assert!((t.velocity(x) - 2.0).abs() < 1e-12);
        }
    }

    #[test]
    fn cursor_evaluation_matches_search() {
        let keys: Vec<Key> = (0..50)
            .map(|i| Key::new(i as f64 * 0.1, (i as f64).sin()))
            .collect();
        let t = Track::new("x", keys).unwrap();
        let mut cursor = 0;
        for i in 0..600 {
            let x = i as f64 * 0.009 - 0.2;
            assert_eq!(t.value_at(x, &mut cursor), t.value(x));
        }
        // Going backwards also works.
        assert_eq!(t.value_at(0.05, &mut cursor), t.value(0.05));
    }

    #[test]
    fn bad_keys_are_errors() {
        assert!(Track::new("x", vec![]).is_err());
        assert!(Track::new("x", vec![Key::new(1.0, 0.0), Key::new(1.0, 1.0)]).is_err());
        assert!(Track::new("x", vec![Key::new(f64::NAN, 0.0)]).is_err());
    }
}
