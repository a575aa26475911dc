//! Gaussian and Laplacian pyramids of sampled tracks (thesis 5.2–5.4, after Burt and
//! Adelson): REDUCE with the 5-tap generating kernel, EXPAND by cubic Hermite
//! interpolation, reconstruction (table 5-4), band editing (eq. 5-9) and the
//! multiresolution blend of two sequences (table 5-5).
//!
//! A pyramid of `N` levels needs `k·2^N + 1` evenly spaced samples; sequences are resampled
//! onto such a [`Grid`] (`2^K + 1` samples no further apart than the sequence's frame time).

use crate::error::{Error, Result};
use crate::offline::blend::BlendPair;
use crate::sequence::{Key, Sequence, Track};

/// The kernel parameter `a` the thesis uses (Gaussian-like weighting).
pub const DEFAULT_A: f64 = 0.4;

/// Largest grid exponent `K` (2^K + 1 samples) a sequence is resampled to.
pub const MAX_GRID_EXPONENT: u32 = 22;

/// The generating kernel `w(−2..=2) = (c, b, a, b, c)` with `b = 1/4`, `c = 1/4 − a/2`
/// (symmetric, normalized, equal contribution).
pub fn kernel(a: f64) -> [f64; 5] {
    let c = 0.25 - a / 2.0;
    [c, 0.25, a, 0.25, c]
}

/// REDUCE (eq. 5-3): `G_l[i] = Σ_m w(m)·G_{l−1}[2i + m]` for the inner samples; the first
/// and last samples are copied. `g.len()` must be odd (2m + 1 samples give m + 1).
pub fn reduce(g: &[f64], a: f64) -> Vec<f64> {
    let w = kernel(a);
    let m = g.len() / 2;
    (0..=m)
        .map(|i| {
            if i == 0 || i == m {
                g[2 * i]
            } else {
                (0..5).map(|k| w[k] * g[2 * i + k - 2]).sum()
            }
        })
        .collect()
}

/// EXPAND (eq. 5-4 with Hermite interpolation as in 5.2): `n` samples become `2n − 1`;
/// the even ones are the given samples, the odd ones the cubic Hermite spline through them
/// (central-difference slopes inside, one-sided at the ends) at the midpoints.
pub fn expand(g: &[f64]) -> Vec<f64> {
    let n = g.len();
    if n < 2 {
        return g.to_vec();
    }
    // h·slope at each sample (the spacing cancels).
    let hm = |i: usize| -> f64 {
        if i == 0 {
            g[1] - g[0]
        } else if i == n - 1 {
            g[n - 1] - g[n - 2]
        } else {
            (g[i + 1] - g[i - 1]) / 2.0
        }
    };
    let mut out = Vec::with_capacity(2 * n - 1);
    for i in 0..n - 1 {
        out.push(g[i]);
        out.push((g[i] + g[i + 1]) / 2.0 + (hm(i) - hm(i + 1)) / 8.0);
    }
    out.push(g[n - 1]);
    out
}

/// The Gaussian pyramid `G_0 … G_levels` of `samples`.
pub fn gaussian(samples: &[f64], levels: usize, a: f64) -> Result<Vec<Vec<f64>>> {
    check_levels(samples.len(), levels)?;
    let mut g = vec![samples.to_vec()];
    for l in 0..levels {
        let next = reduce(&g[l], a);
        g.push(next);
    }
    Ok(g)
}

fn check_levels(n: usize, levels: usize) -> Result<()> {
    let step = 1usize.checked_shl(levels as u32).unwrap_or(0);
    if levels > 30 || step == 0 || n < step + 1 || !(n - 1).is_multiple_of(step) {
        return Err(Error::Invalid(format!(
            "a pyramid of {levels} levels needs k·2^{levels} + 1 samples, not {n}"
        )));
    }
    Ok(())
}

/// A Laplacian pyramid: the band-pass levels `L_0 … L_{N−1}` and the top low-pass `G_N`,
/// over evenly spaced samples starting at `start`, `dt` apart at level 0.
#[derive(Clone, Debug, PartialEq)]
pub struct Pyramid {
    /// Time of the first sample.
    pub start: f64,
    /// Sample spacing of level 0 (level `l` has `2^l · dt`, eq. 5-7).
    pub dt: f64,
    /// `L_l = G_l − EXPAND(G_{l+1})` (eq. 5-5), finest first.
    pub bands: Vec<Vec<f64>>,
    /// `G_N`, the coarsest low-pass level.
    pub top: Vec<f64>,
}

impl Pyramid {
    /// Builds the pyramid of `levels` levels from `samples` (`k·2^levels + 1` of them).
    pub fn new(samples: &[f64], start: f64, dt: f64, levels: usize, a: f64) -> Result<Pyramid> {
        let mut g = gaussian(samples, levels, a)?;
        let top = g.pop().unwrap_or_default();
        let mut bands = Vec::with_capacity(levels);
        for l in 0..levels {
            let up = expand(if l + 1 < levels { &g[l + 1] } else { &top });
            bands.push(g[l].iter().zip(up).map(|(x, e)| x - e).collect());
        }
        Ok(Pyramid {
            start,
            dt,
            bands,
            top,
        })
    }

    /// Number of band-pass levels `N`.
    pub fn depth(&self) -> usize {
        self.bands.len()
    }

    /// Sample spacing of level `l`.
    pub fn level_dt(&self, l: usize) -> f64 {
        self.dt * (1u64 << l) as f64
    }

    /// Reconstruction (table 5-4, eq. 5-6): the original samples, up to rounding.
    pub fn reconstruct(&self) -> Vec<f64> {
        let ones = vec![1.0; self.depth() + 1];
        self.reconstruct_weighted(&ones)
    }

    /// Band editing (eq. 5-9): `w_N·G_N + Σ w_l·L_l`, expanding from the top; `weights`
    /// holds `w_0 … w_{N−1}` for the bands then `w_N` for the top (missing weights are 1).
    pub fn reconstruct_weighted(&self, weights: &[f64]) -> Vec<f64> {
        let w = |l: usize| weights.get(l).copied().unwrap_or(1.0);
        let n = self.depth();
        let mut g: Vec<f64> = self.top.iter().map(|x| x * w(n)).collect();
        for l in (0..n).rev() {
            g = expand(&g)
                .into_iter()
                .zip(&self.bands[l])
                .map(|(e, b)| e + w(l) * b)
                .collect();
        }
        g
    }
}

/// Evenly spaced sample times `start + i·dt`, `i < n`, with `n = 2^K + 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// First sample time.
    pub start: f64,
    /// Spacing.
    pub dt: f64,
    /// Number of samples.
    pub n: usize,
}

impl Grid {
    /// The smallest `2^K + 1` grid over `[start, end]` with `K ≥ levels` and spacing at
    /// most `frame_time` (`K` capped at [`MAX_GRID_EXPONENT`]).
    pub fn covering(start: f64, end: f64, frame_time: f64, levels: usize) -> Result<Grid> {
        let d = end - start;
        if !(d.is_finite() && d > 0.0) {
            return Err(Error::Invalid(
                "a pyramid needs a sequence longer than zero seconds".into(),
            ));
        }
        if levels as u32 > MAX_GRID_EXPONENT {
            return Err(Error::invalid_value(
                "pyramid levels",
                levels as f64,
                format!("at most {MAX_GRID_EXPONENT}"),
            ));
        }
        let need = (d / frame_time.max(1e-9)).log2().ceil().max(0.0) as u32;
        let k = need.clamp(levels as u32, MAX_GRID_EXPONENT);
        let n = (1usize << k) + 1;
        Ok(Grid {
            start,
            dt: d / (1usize << k) as f64,
            n,
        })
    }

    /// The time of sample `i`.
    pub fn time(&self, i: usize) -> f64 {
        self.start + i as f64 * self.dt
    }
}

/// Keys at `times` on the Hermite curve through `values` sampled on `grid` (value and
/// slope of that curve).
fn resample_at(dof: &str, grid: &Grid, values: &[f64], times: &[f64]) -> Result<Track> {
    let fine = Track::from_samples(dof, grid.start, grid.dt, values)?;
    let keys = times
        .iter()
        .map(|&t| Key::with_slope(t, fine.value(t), fine.velocity(t)))
        .collect();
    Track::new(dof, keys)
}

/// Band editing of every track (eq. 5-9): `weights` = `w_0 … w_{N−1}, w_N` (so
/// `weights.len() − 1` levels). Each track is sampled on a `2^K + 1` grid and rebuilt
/// with the weights; what the weights changed, read back at the track's own key times
/// (value and slope), is added to its keys. So unit weights give the track back (to
/// rounding): the grid need not line up with the keys, which resampling the rebuilt
/// curve itself there would move (8° at a key of a hand-keyed wave).
pub fn band_edit(seq: &Sequence, weights: &[f64], a: f64) -> Result<Sequence> {
    if weights.len() < 2 {
        return Err(Error::Invalid(
            "band editing needs at least two weights (w0 and the top)".into(),
        ));
    }
    let levels = weights.len() - 1;
    let grid = Grid::covering(seq.start(), seq.end(), seq.frame_time(), levels)?;
    let mut out = seq.empty_like();
    for track in seq.tracks() {
        let samples = track.sample(grid.start, grid.dt, grid.n);
        let p = Pyramid::new(&samples, grid.start, grid.dt, levels, a)?;
        let change: Vec<f64> = p
            .reconstruct_weighted(weights)
            .iter()
            .zip(&samples)
            .map(|(edited, was)| edited - was)
            .collect();
        let change = Track::from_samples(track.dof(), grid.start, grid.dt, &change)?;
        let keys = track
            .keys()
            .iter()
            .map(|k| {
                let (dv, ds) = (change.value(k.time), change.velocity(k.time));
                if dv == 0.0 && ds == 0.0 {
                    *k
                } else {
                    Key::with_slope(k.time, k.value + dv, track.velocity(k.time) + ds)
                }
            })
            .collect();
        let mut edited = Track::new(track.dof(), keys)?;
        edited.set_interpolation(track.interpolation());
        out.add_track(edited)?;
    }
    Ok(out)
}

/// The multiresolution blend of table 5-5: B starts at `at` on A's time base; both are
/// resampled on one grid, decomposed into Laplacian pyramids of `levels` levels, each level
/// is blended with the ease weight of [`BlendPair`] at that level's sample times (A alone
/// before the window, B alone after it; B inside A returns to A), and the result is
/// reconstructed and sampled every frame time.
pub fn pyramid_blend(
    a_seq: &Sequence,
    b_seq: &Sequence,
    at: f64,
    over: f64,
    levels: usize,
    a: f64,
) -> Result<Sequence> {
    let pair = BlendPair::new(a_seq, b_seq, at, over)?;
    let (t0, t1) = pair.span();
    let ft = a_seq.frame_time().min(b_seq.frame_time());
    let grid = Grid::covering(t0, t1, ft, levels)?;
    // Up to the end: a span that is not a whole number of frames ends on a shorter one.
    let n_out = ((t1 - t0) / ft - 1e-9).ceil().max(0.0) as usize + 1;
    let times: Vec<f64> = (0..n_out).map(|i| (t0 + i as f64 * ft).min(t1)).collect();
    let mut out = a_seq.empty_like();
    out.name = format!("{}+{}", a_seq.name, b_seq.name);
    out.meta.insert("rate".into(), format!("{}", 1.0 / ft));
    for dof in pair.dofs() {
        // A track only one sequence has is that sequence's on its own clock on both
        // sides, so the blend keeps it as it is (as `blend` does): taken for the other's
        // too, it was blended with a copy of itself shifted by B's start.
        let (ta, tb) = pair.tracks(&dof);
        let of_a = |t: f64| ta.map(|a| a.value(t));
        let of_b = |t: f64| tb.map(|b| b.value(t + pair.b_shift));
        if ta.is_none() && tb.is_none() {
            continue;
        }
        // One side's samples: its own track, else the other's.
        let side = |own: &dyn Fn(f64) -> Option<f64>, other: &dyn Fn(f64) -> Option<f64>| {
            (0..grid.n)
                .map(|i| {
                    own(grid.time(i))
                        .or_else(|| other(grid.time(i)))
                        .unwrap_or(0.0)
                })
                .collect::<Vec<f64>>()
        };
        let (sa, sb) = (side(&of_a, &of_b), side(&of_b, &of_a));
        let pa = Pyramid::new(&sa, grid.start, grid.dt, levels, a)?;
        let pb = Pyramid::new(&sb, grid.start, grid.dt, levels, a)?;
        let mix = |l: usize, x: &[f64], y: &[f64]| -> Vec<f64> {
            let step = grid.dt * (1u64 << l) as f64;
            x.iter()
                .zip(y)
                .enumerate()
                .map(|(i, (x, y))| {
                    let w = pair.transition.weight(grid.start + i as f64 * step);
                    w * x + (1.0 - w) * y
                })
                .collect()
        };
        let ps = Pyramid {
            start: grid.start,
            dt: grid.dt,
            bands: (0..levels)
                .map(|l| mix(l, &pa.bands[l], &pb.bands[l]))
                .collect(),
            top: mix(levels, &pa.top, &pb.top),
        };
        out.add_track(resample_at(&dof, &grid, &ps.reconstruct(), &times)?)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signal(n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let t = i as f64 * 0.01;
                (2.0 * t).sin() + 0.3 * (17.0 * t).cos() + 0.05 * ((i * 7919) % 13) as f64
            })
            .collect()
    }

    #[test]
    fn kernel_is_normalized_and_reduce_halves() {
        for a in [0.3, 0.4, 0.5, 0.6] {
            let w = kernel(a);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            assert!((w[2] + 2.0 * w[0] - 2.0 * w[1]).abs() < 1e-15);
        }
        assert_eq!(reduce(&[1.0; 9], 0.4), vec![1.0; 5]);
        assert_eq!(expand(&[0.0, 1.0, 2.0]), vec![0.0, 0.5, 1.0, 1.5, 2.0]);
        assert!(gaussian(&[0.0; 10], 2, 0.4).is_err());
    }

    /// Unit weights reproduce the input: the bound is rounding only, a few ulps of the
    /// signal's magnitude per level (asserted: 1e-13 for values of order 1, 10 levels).
    #[test]
    fn unit_weight_reconstruction_reproduces_the_input() {
        for (n, levels) in [(9, 3), (17, 4), (1025, 10), (3 * 64 + 1, 6)] {
            let s = signal(n);
            let p = Pyramid::new(&s, 0.0, 0.01, levels, DEFAULT_A).unwrap();
            let r = p.reconstruct();
            let err = s
                .iter()
                .zip(&r)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-13, "{n}/{levels}: {err}");
            assert_eq!(p.top.len(), (n - 1) / (1 << levels) + 1);
        }
    }

    #[test]
    fn band_weights_scale_the_bands() {
        let s = signal(65);
        let p = Pyramid::new(&s, 0.0, 0.01, 3, DEFAULT_A).unwrap();
        // Only the top: a smooth low-pass version.
        let low = p.reconstruct_weighted(&[0.0, 0.0, 0.0, 1.0]);
        let rough = |v: &[f64]| {
            v.windows(3)
                .map(|w| (w[0] - 2.0 * w[1] + w[2]).abs())
                .sum::<f64>()
        };
        assert!(rough(&low) < rough(&s) / 3.0);
        // Doubling the finest band doubles its contribution.
        let d = p.reconstruct_weighted(&[2.0, 1.0, 1.0, 1.0]);
        for i in 0..65 {
            assert!((d[i] - s[i] - p.bands[0][i]).abs() < 1e-12);
        }
        // Through sequences: unit weights keep the values at the keys (resampling only).
        let mut seq = Sequence::new("s");
        seq.add_track(Track::from_samples("x", 0.0, 0.01, &s).unwrap())
            .unwrap();
        let same = band_edit(&seq, &[1.0, 1.0, 1.0, 1.0], DEFAULT_A).unwrap();
        for (k, v) in same.track("x").unwrap().keys().iter().zip(&s) {
            assert!((k.value - v).abs() < 1e-12);
        }
    }

    /// A hand-keyed wave (keys half a second apart and irregular, no rate): its keys are
    /// not on any 2^K + 1 grid over its span.
    fn hand_keyed() -> Sequence {
        let mut seq = Sequence::new("wave");
        let keys = [
            (0.0, 0.0),
            (0.5, 1.2),
            (1.0, 0.6),
            (1.3, 1.9),
            (2.2, 1.9),
            (2.9, 0.0),
        ];
        seq.add_track(
            Track::new("x", keys.iter().map(|&(t, v)| Key::new(t, v)).collect()).unwrap(),
        )
        .unwrap();
        seq
    }

    #[test]
    fn unit_band_weights_give_a_hand_keyed_sequence_back_and_others_change_it_smoothly() {
        let seq = hand_keyed();
        let x = seq.track("x").unwrap();
        let same = band_edit(&seq, &[1.0, 1.0, 1.0, 1.0], DEFAULT_A).unwrap();
        let back = same.track("x").unwrap();
        // Keys and the curve between them (a key moved 0.139 rad when the rebuilt curve
        // was resampled at the keys).
        for i in 0..=290 {
            let t = i as f64 * 0.01;
            assert!((back.value(t) - x.value(t)).abs() < 1e-12, "{t}");
        }
        // The finest band left out smooths the curve a little, no more than it is rough.
        let smooth = band_edit(&seq, &[0.0, 1.0, 1.0, 1.0], DEFAULT_A).unwrap();
        let smooth = smooth.track("x").unwrap();
        let moved = (0..=290)
            .map(|i| (smooth.value(i as f64 * 0.01) - x.value(i as f64 * 0.01)).abs())
            .fold(0.0, f64::max);
        assert!(moved > 1e-4 && moved < 0.3, "{moved}");
    }

    #[test]
    fn a_blend_of_hand_keyed_sequences_is_a_before_its_window_and_b_after() {
        let a = hand_keyed();
        let mut b = Sequence::new("b");
        let keys = vec![Key::new(0.0, 1.0), Key::new(0.7, 0.2), Key::new(1.6, 1.5)];
        b.add_track(Track::new("x", keys).unwrap()).unwrap();
        let s = pyramid_blend(&a, &b, 1.0, 0.5, 3, DEFAULT_A).unwrap();
        let (x, ta, tb) = (
            s.track("x").unwrap(),
            a.track("x").unwrap(),
            b.track("x").unwrap(),
        );
        // It ends where A ends (2.9 s, after B's 1.0 + 1.6 s), not a frame short.
        assert!((x.end() - 2.9).abs() < 1e-9, "{}", x.end());
        // A alone before the window, B alone from its end (1.5 s) until B, inside A, eases
        // back to A over its last 0.5 s, then A alone again.
        let off = |range: std::ops::RangeInclusive<i32>, want: &dyn Fn(f64) -> f64| {
            range
                .map(|i| (x.value(i as f64 * 0.01) - want(i as f64 * 0.01)).abs())
                .fold(0.0, f64::max)
        };
        let (before, during, after) = (
            off(0..=100, &|t| ta.value(t)),
            off(150..=210, &|t| tb.value(t - 1.0)),
            off(260..=290, &|t| ta.value(t)),
        );
        assert!(
            before < 5e-3 && during < 5e-3 && after < 5e-3,
            "{before} {during} {after}"
        );
    }

    #[test]
    fn pyramid_blend_goes_from_a_to_b_continuously() {
        let mk = |f: fn(f64) -> f64| {
            let v: Vec<f64> = (0..301).map(|i| f(i as f64 * 0.01)).collect();
            let mut s = Sequence::new("s");
            s.meta.insert("rate".into(), "100".into());
            s.add_track(Track::from_samples("x", 0.0, 0.01, &v).unwrap())
                .unwrap();
            s
        };
        let a = mk(|t| t.sin());
        let b = mk(|t| 2.0 + (3.0 * t).cos());
        let s = pyramid_blend(&a, &b, 1.0, 0.5, 4, DEFAULT_A).unwrap();
        let x = s.track("x").unwrap();
        assert!((x.end() - 4.0).abs() < 1e-9);
        assert!((x.value(0.2) - 0.2f64.sin()).abs() < 0.05);
        assert!((x.value(3.5) - (2.0 + (3.0 * 2.5f64).cos())).abs() < 0.05);
        // No jumps: neighbouring keys differ by no more than the steepest input allows.
        let k = x.keys();
        let worst = k
            .windows(2)
            .map(|w| (w[1].value - w[0].value).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.1, "{worst}");
        // B inside A.
        let short = mk(|_| 5.0);
        let short = crate::offline::warp::squeeze_stretch(&short, 0.0, 3.0, 3.0, 0.5).unwrap();
        let inside = pyramid_blend(&a, &short, 1.0, 1.0, 3, DEFAULT_A).unwrap();
        let x = inside.track("x").unwrap();
        assert!(x.value(1.25) > 3.0, "{}", x.value(1.25));
        assert!((x.value(2.8) - 2.8f64.sin()).abs() < 0.05);
    }

    #[test]
    fn a_track_only_one_sequence_has_is_kept_as_it_is() {
        // A's own ramp, 1 per second, which B lacks: it was blended with a copy of itself
        // shifted by B's start (0.9375 at 1.5 s).
        let ramp = |name: &str, track: &str, f: fn(f64) -> f64| {
            let v: Vec<f64> = (0..301).map(|i| f(i as f64 * 0.01)).collect();
            let mut s = Sequence::new(name);
            s.meta.insert("rate".into(), "100".into());
            s.add_track(Track::from_samples(track, 0.0, 0.01, &v).unwrap())
                .unwrap();
            s.add_track(Track::from_samples("x", 0.0, 0.01, &v).unwrap())
                .unwrap();
            s
        };
        let a = ramp("a", "only_a", |t| t);
        let b = ramp("b", "only_b", |t| 10.0 + t);
        let s = pyramid_blend(&a, &b, 1.0, 0.5, 4, DEFAULT_A).unwrap();
        let only_a = s.track("only_a").unwrap();
        for t in [0.5, 1.5, 2.0] {
            assert!(
                (only_a.value(t) - t).abs() < 1e-6,
                "{t}: {}",
                only_a.value(t)
            );
        }
        // B's, on B's clock: B starts at 1 s.
        let only_b = s.track("only_b").unwrap();
        for t in [1.5, 2.5, 3.5] {
            let want = 10.0 + (t - 1.0);
            assert!(
                (only_b.value(t) - want).abs() < 1e-6,
                "{t}: {}",
                only_b.value(t)
            );
        }
    }
}
