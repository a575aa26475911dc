//! Key reduction: the spline compression of thesis 5.8 and the pyramid compression of 5.5.
//!
//! Both keep the result within a tolerance of the original **at every original key**
//! (the thesis's spline method bounds a Simpson integral of the error normalized by the
//! subset's duration; that criterion alone would allow one sample to stray, so the spline
//! method here checks both: the normalized integral against `integral_tolerance` and the
//! largest deviation against `tolerance`).

use crate::error::{Error, Result};
use crate::offline::pyramid::{gaussian, Grid};
use crate::sequence::{Interpolation, Key, Sequence, Track};

/// Fewest segments a linear subset spans; shorter straight stretches stay in the curve.
pub const MIN_LINEAR: usize = 3;

/// Settings of the spline compression.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplineOptions {
    /// Largest allowed deviation at any original key (DOF units: radians or metres).
    pub tolerance: f64,
    /// Largest allowed Simpson integral of |error| divided by the subset's duration (the
    /// thesis's criterion); `None` takes `tolerance / 4`.
    pub integral_tolerance: Option<f64>,
    /// Linear criterion: a key is in a linear subset when its slope, its predecessor's and
    /// the chord between them differ by at most this fraction of the track's largest
    /// |slope| (the "normalized neighbourhood" of 5.8).
    pub linear_tolerance: f64,
}

impl SplineOptions {
    /// Options with tolerance `tolerance` and the defaults for the rest.
    pub fn new(tolerance: f64) -> SplineOptions {
        SplineOptions {
            tolerance,
            integral_tolerance: None,
            linear_tolerance: 0.001,
        }
    }
}

/// What a compression did to a sequence.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompressReport {
    /// Keys in the input, all tracks together.
    pub keys_before: usize,
    /// Keys in the output.
    pub keys_after: usize,
    /// Largest |output − input| at the input's keys, over all tracks.
    pub max_error: f64,
}

/// Largest |approx − original| at the original's key times.
pub fn max_error(original: &Track, approx: &Track) -> f64 {
    let mut cursor = 0;
    original
        .keys()
        .iter()
        .map(|k| (approx.value_at(k.time, &mut cursor) - k.value).abs())
        .fold(0.0, f64::max)
}

/// Simpson integral of `f` at the (possibly uneven) abscissae `t`; a last odd interval is
/// integrated by the trapezoid rule.
pub fn simpson(t: &[f64], f: &[f64]) -> f64 {
    let n = t.len();
    let mut sum = 0.0;
    let mut i = 0;
    while i + 2 < n {
        let (h0, h1) = (t[i + 1] - t[i], t[i + 2] - t[i + 1]);
        sum += (h0 + h1) / 6.0
            * ((2.0 - h1 / h0) * f[i]
                + (h0 + h1).powi(2) / (h0 * h1) * f[i + 1]
                + (2.0 - h0 / h1) * f[i + 2]);
        i += 2;
    }
    if i + 1 < n {
        sum += (t[i + 1] - t[i]) * (f[i] + f[i + 1]) / 2.0;
    }
    sum
}

/// Compresses one track (5.8, table "data compression flow chart"): linear subsets become
/// one straight Hermite segment, the non-linear subsets are approximated by recursive
/// Hermite subdivision. The output keys are a subset of the input's, with explicit slopes;
/// a key without a slope takes the chord of its neighbours (thesis 5.8), the better
/// estimate of a sampled curve's derivative. A `linear` or `step` track is returned as it
/// is: its keys are not Hermite samples.
pub fn compress_track(track: &Track, opts: &SplineOptions) -> Result<Track> {
    if !(opts.tolerance.is_finite() && opts.tolerance >= 0.0) {
        return Err(Error::invalid_value(
            "compression tolerance",
            opts.tolerance,
            "a number ≥ 0",
        ));
    }
    let keys = track.keys();
    let n = keys.len();
    let hermite = matches!(
        track.interpolation(),
        Interpolation::Cubic | Interpolation::Hermite
    );
    if n <= 2 || !hermite {
        return Ok(track.clone());
    }
    let t: Vec<f64> = keys.iter().map(|k| k.time).collect();
    let v: Vec<f64> = keys.iter().map(|k| k.value).collect();
    let chords = track.clone().with_interpolation(Interpolation::Hermite);
    let s = chords.slopes();
    let tol = opts.tolerance;
    let itol = opts.integral_tolerance.unwrap_or(tol / 4.0);
    let smax = s.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let eps = opts.linear_tolerance * smax.max(1e-12);
    let chord = |i: usize, j: usize| (v[j] - v[i]) / (t[j] - t[i]);
    // Key k is linear with its predecessor: both slopes near the chord between them.
    let linear = |k: usize| {
        let c = chord(k - 1, k);
        (s[k] - c).abs() <= eps && (s[k - 1] - c).abs() <= eps
    };
    // Every key strictly between i and j lies within the tolerance of the chord i–j.
    let on_line = |i: usize, j: usize| {
        let c = chord(i, j);
        (i + 1..j).all(|m| (v[i] + c * (t[m] - t[i]) - v[m]).abs() <= tol)
    };

    // The end of the linear subset from `i` (at most `limit` keys further).
    let run_end = |i: usize, limit: usize| {
        let mut j = i;
        while j + 1 < n && j - i < limit && linear(j + 1) && on_line(i, j + 1) {
            j += 1;
        }
        j
    };

    // Pass 1: split into linear subsets (at least MIN_LINEAR segments; shorter ones are
    // just part of the curve) and non-linear subsets; fix the slopes at the linear ends.
    let mut slope: Vec<Option<f64>> = vec![None; n];
    let mut nonlinear = Vec::new();
    let mut i = 0;
    while i < n - 1 {
        let j = run_end(i, usize::MAX);
        if j - i >= MIN_LINEAR {
            let c = chord(i, j);
            slope[i] = Some(c);
            slope[j] = Some(c);
            i = j;
            if i == n - 1 {
                break;
            }
        }
        let mut k = i + 1;
        while k + 1 < n && run_end(k, MIN_LINEAR) - k < MIN_LINEAR {
            k += 1;
        }
        nonlinear.push((i, k));
        i = k;
    }
    let mut keep = vec![false; n];
    keep[0] = true;
    keep[n - 1] = true;
    for (a, b) in &nonlinear {
        keep[*a] = true;
        keep[*b] = true;
    }
    for (k, sl) in slope.iter().enumerate() {
        if sl.is_some() {
            keep[k] = true;
        }
    }
    let mut slope: Vec<f64> = slope
        .iter()
        .enumerate()
        .map(|(k, x)| x.unwrap_or(s[k]))
        .collect();

    // Pass 2: recursive Hermite approximation of each non-linear subset.
    let mut stack: Vec<(usize, usize)> = nonlinear.into_iter().filter(|(a, b)| b - a > 1).collect();
    let mut err = Vec::new();
    while let Some((a, b)) = stack.pop() {
        let h = t[b] - t[a];
        err.clear();
        err.extend((a..=b).map(|m| {
            let u = (t[m] - t[a]) / h;
            let (u2, u3) = (u * u, u * u * u);
            let y = (2.0 * u3 - 3.0 * u2 + 1.0) * v[a]
                + (u3 - 2.0 * u2 + u) * h * slope[a]
                + (-2.0 * u3 + 3.0 * u2) * v[b]
                + (u3 - u2) * h * slope[b];
            (y - v[m]).abs()
        }));
        let (worst, at) =
            err[1..err.len() - 1]
                .iter()
                .enumerate()
                .fold(
                    (0.0f64, 0),
                    |(w, at), (i, &e)| if e > w { (e, i) } else { (w, at) },
                );
        let integral = simpson(&t[a..=b], &err) / h;
        if worst <= tol && integral <= itol {
            continue;
        }
        let m = a + 1 + at;
        keep[m] = true;
        slope[m] = s[m];
        stack.push((a, m));
        stack.push((m, b));
    }
    let out = (0..n)
        .filter(|&k| keep[k])
        .map(|k| Key::with_slope(t[k], v[k], slope[k]))
        .collect();
    Ok(Track::new(track.dof(), out)?.with_interpolation(track.interpolation()))
}

/// Spline compression of every track of `seq` (5.8).
pub fn compress_spline(seq: &Sequence, opts: &SplineOptions) -> Result<(Sequence, CompressReport)> {
    let mut out = seq.empty_like();
    let mut report = CompressReport::default();
    for track in seq.tracks() {
        let c = compress_track(track, opts)?;
        report.keys_before += track.keys().len();
        report.keys_after += c.keys().len();
        report.max_error = report.max_error.max(max_error(track, &c));
        out.add_track(c)?;
    }
    Ok((out, report))
}

/// Pyramid compression (5.5): each track is resampled on a `2^K + 1` grid and replaced by
/// the coarsest Gaussian level `G_l` (`2^(K−l) + 1` keys, high frequencies filtered out)
/// whose error at every original key stays within `tolerance`; a track that no level fits
/// is kept as it is.
pub fn compress_pyramid(
    seq: &Sequence,
    tolerance: f64,
    a: f64,
) -> Result<(Sequence, CompressReport)> {
    let mut out = seq.empty_like();
    let mut report = CompressReport::default();
    for track in seq.tracks() {
        report.keys_before += track.keys().len();
        let best = if track.keys().len() > 2 && track.end() > track.start() {
            let grid = Grid::covering(track.start(), track.end(), seq.frame_time(), 0)?;
            let k = (grid.n - 1).trailing_zeros() as usize;
            let levels = gaussian(&track.sample(grid.start, grid.dt, grid.n), k, a)?;
            let mut best = None;
            for (l, g) in levels.iter().enumerate().rev() {
                let dt = grid.dt * (1u64 << l) as f64;
                let cand = Track::from_samples(track.dof(), grid.start, dt, g)?;
                if cand.keys().len() < track.keys().len() && max_error(track, &cand) <= tolerance {
                    best = Some(cand);
                    break;
                }
            }
            best
        } else {
            None
        };
        let c = best.unwrap_or_else(|| track.clone());
        report.keys_after += c.keys().len();
        report.max_error = report.max_error.max(max_error(track, &c));
        out.add_track(c)?;
    }
    Ok((out, report))
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn sampled(f: impl Fn(f64) -> f64, n: usize, dt: f64) -> Track {
        let v: Vec<f64> = (0..n).map(|i| f(i as f64 * dt)).collect();
        Track::new(
            "x",
            v.iter()
                .enumerate()
                .map(|(i, &x)| Key::new(i as f64 * dt, x))
                .collect(),
        )
        .unwrap()
    }

    #[test]
    fn simpson_is_exact_for_cubics_on_even_grids() {
        let t: Vec<f64> = (0..=10).map(|i| i as f64 * 0.1).collect();
        let f: Vec<f64> = t.iter().map(|x| x * x * x).collect();
        assert!((simpson(&t, &f) - 0.25).abs() < 1e-12);
    }

    #[test]
    fn linear_runs_collapse_to_their_ends() {
        // Ramp up, hold, ramp down: piecewise linear.
        let f = |t: f64| {
            if t < 1.0 {
                t
            } else if t < 2.0 {
                1.0
            } else {
                3.0 - t
            }
        };
        let tr = sampled(f, 301, 0.01);
        let c = compress_track(&tr, &SplineOptions::new(1e-6)).unwrap();
        assert!(c.keys().len() <= 12, "{}", c.keys().len());
        assert!(max_error(&tr, &c) <= 1e-6);
    }

    #[test]
    fn smooth_curves_compress_within_tolerance() {
        let tr = sampled(|t| (2.0 * t).sin() + 0.2 * (9.0 * t).cos(), 500, 0.01);
        for tol in [1e-2, 1e-3, 1e-4] {
            let c = compress_track(&tr, &SplineOptions::new(tol)).unwrap();
            let e = max_error(&tr, &c);
            assert!(e <= tol, "{tol}: {e}");
            assert!(c.keys().len() < 150, "{tol}: {}", c.keys().len());
        }
        let mut seq = Sequence::new("s");
        seq.add_track(tr.clone()).unwrap();
        let (p, r) = compress_pyramid(&seq, 1e-3, 0.4).unwrap();
        assert!(r.max_error <= 1e-3 && r.keys_after < r.keys_before, "{r:?}");
        assert!(max_error(&tr, p.track("x").unwrap()) <= 1e-3);
    }

    proptest! {
        #[test]
        fn error_within_tolerance_at_every_original_key(
            values in proptest::collection::vec(-3.0f64..3.0, 3..200),
            smooth in 0usize..4,
            tol in 1e-4f64..0.5,
        ) {
            // Random walks, optionally smoothed, sampled at 100 Hz.
            let mut v = values.clone();
            for _ in 0..smooth {
                v = (0..v.len()).map(|i| {
                    let a = v[i.saturating_sub(1)];
                    let c = v[(i + 1).min(v.len() - 1)];
                    (a + 2.0 * v[i] + c) / 4.0
                }).collect();
            }
            let tr = sampled(|t| v[(t * 100.0).round() as usize], v.len(), 0.01);
            let c = compress_track(&tr, &SplineOptions::new(tol)).unwrap();
            prop_assert!(max_error(&tr, &c) <= tol * (1.0 + 1e-9) + 1e-12);
            prop_assert!(c.keys().len() <= tr.keys().len());
        }
    }
}
