//! The blend rule: how the contributions of an actor's running actions become one posture.
//!
//! For each DOF `d`, every running action `i` whose generator wrote `d` this tick
//! contributes its desired value `v_i` with the effective weight `w_i = b_i · e_i`, where
//! `b_i` is the action's weight for `weighted` actions and 1 for every other mode, and
//! `e_i` is its ease factor ([`ease_factor`]). With `W = Σ w_i`:
//!
//! * `W = 0` (no action drives `d`): the DOF keeps its held value, `q = h`.
//! * `0 < W < 1`: the contributions pull the held value part of the way,
//!   `q = h + Σ w_i (v_i − h)`.
//! * `W ≥ 1`: the contributions are normalised, `q = Σ w_i v_i / W`, and the held value
//!   becomes `q`, so a DOF holds its last fully driven value once its actions stop.
//!
//! The result is clamped to the DOF's limits. `h` is also set directly by
//! `Scene::set_dofs` (Lua `actor:pose{}`).

use troupe_body::math::smoothstep;

/// The ease curve: smoothstep `3x² − 2x³` on [0, 1], with zero slope at both ends.
#[inline]
pub fn ease(x: f64) -> f64 {
    smoothstep(x)
}

/// The ease factor of an action at `time`: rises from 0 to 1 over `ease_in` seconds after
/// `start`; once terminating (from `terminate`), falls from the level it had then to 0
/// over `ease_out` seconds.
pub fn ease_factor(
    time: f64,
    start: f64,
    ease_in: f64,
    terminate: Option<f64>,
    ease_out: f64,
) -> f64 {
    let rising = |t: f64| {
        if ease_in > 0.0 {
            ease((t - start) / ease_in)
        } else {
            1.0
        }
    };
    match terminate {
        None => rising(time),
        Some(_) if ease_out <= 0.0 => 0.0,
        Some(t0) => rising(t0) * (1.0 - ease((time - t0) / ease_out)),
    }
}

/// Per-DOF accumulators for one actor's tick.
#[derive(Clone, Debug, Default)]
pub struct Accumulator {
    weighted_sum: Vec<f64>,
    weight: Vec<f64>,
}

impl Accumulator {
    /// Clears the accumulators for `n` DOFs.
    pub fn reset(&mut self, n: usize) {
        self.weighted_sum.clear();
        self.weighted_sum.resize(n, 0.0);
        self.weight.clear();
        self.weight.resize(n, 0.0);
    }

    /// Adds a contribution of `value` with effective weight `w` to DOF `d`.
    #[inline]
    pub fn add(&mut self, d: usize, value: f64, w: f64) {
        self.weighted_sum[d] += w * value;
        self.weight[d] += w;
    }

    /// Applies the blend rule: writes `q` and updates `held`; `clamp(d, v)` applies limits.
    #[inline]
    pub fn resolve(&self, held: &mut [f64], q: &mut [f64], clamp: impl Fn(usize, f64) -> f64) {
        for d in 0..q.len() {
            let w = self.weight[d];
            let h = held[d];
            let value = if w <= 0.0 {
                h
            } else if w < 1.0 {
                // Σ w_i (v_i − h) = Σ w_i v_i − W h
                h + self.weighted_sum[d] - w * h
            } else {
                let v = clamp(d, self.weighted_sum[d] / w);
                held[d] = v;
                v
            };
            q[d] = clamp(d, value);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ease_curve() {
        assert_eq!(ease(0.0), 0.0);
        assert_eq!(ease(1.0), 1.0);
        assert_eq!(ease(0.5), 0.5);
        assert!((ease(0.25) - 0.15625).abs() < 1e-15);
        assert_eq!(ease(-1.0), 0.0);
        assert_eq!(ease(2.0), 1.0);
    }

    #[test]
    fn ease_factor_in_and_out() {
        assert_eq!(ease_factor(1.0, 1.0, 0.5, None, 0.0), 0.0);
        assert_eq!(ease_factor(1.25, 1.0, 0.5, None, 0.0), 0.5);
        assert_eq!(ease_factor(2.0, 1.0, 0.5, None, 0.0), 1.0);
        assert_eq!(ease_factor(2.0, 1.0, 0.5, Some(2.0), 1.0), 1.0);
        assert_eq!(ease_factor(2.5, 1.0, 0.5, Some(2.0), 1.0), 0.5);
        // Cancelled during ease-in: falls from the level it had reached.
        let level = ease_factor(1.2, 1.0, 1.0, None, 1.0);
        assert_eq!(ease_factor(1.2, 1.0, 1.0, Some(1.2), 1.0), level);
        assert!(ease_factor(1.3, 1.0, 1.0, Some(1.2), 1.0) < level);
        assert_eq!(ease_factor(2.2, 1.0, 1.0, Some(1.2), 1.0), 0.0);
    }

    #[test]
    fn blend_rule_cases() {
        let mut acc = Accumulator::default();
        acc.reset(3);
        acc.add(1, 2.0, 0.5); // half way from held 0 to 2
        acc.add(2, 1.0, 1.0);
        acc.add(2, 3.0, 1.0); // normalised average
        let mut held = vec![5.0, 0.0, 0.0];
        let mut q = vec![0.0; 3];
        acc.resolve(&mut held, &mut q, |_, v| v);
        assert_eq!(q, vec![5.0, 1.0, 2.0]);
        assert_eq!(held, vec![5.0, 0.0, 2.0]);
        // Limits apply.
        acc.resolve(&mut held, &mut q, |_, v| v.min(1.5));
        assert_eq!(q[2], 1.5);
    }
}
