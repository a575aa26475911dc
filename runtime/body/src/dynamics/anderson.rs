//! Anderson acceleration (Walker & Ni, "Anderson acceleration for fixed-point
//! iterations", SIAM J. Numer. Anal. 49, 2011) of a fixed-point iteration `z = G(z)`.
//!
//! The simulator's implicit velocity equation is a fixed point whose plain iteration
//! contracts only while `h·|q̇|` times the conditioning of the mass matrix stays below
//! one; the massless links between two DOF groups (vc4 and skullbase torsions, vt12 and
//! vt6, …) leave near-null modes with only the armature's inertia, whose gyroscopic
//! coupling to a spinning segment makes the plain iteration diverge at a few rad/s.
//! Mixing the last few iterates by least squares (a nonlinear GMRES) converges there.

use crate::linalg::dot;
use crate::math::solve_small;

/// Depth of the history: how many previous iterates are mixed.
const DEPTH: usize = 6;
/// Most passes of one solve.
pub(crate) const MAX_ITERATIONS: usize = 60;
/// Relative change of the iterate at which the fixed point is reached (far below the
/// simulator step's O(h²) error; tighter only costs passes).
const CONVERGED: f64 = 1e-8;

/// How a fixed-point solve ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Outcome {
    /// The last pass moved the iterate by at most `CONVERGED` relative to its size.
    Converged,
    /// The change was not a finite number: the caller's checks of the state report it.
    NotFinite,
    /// [`MAX_ITERATIONS`] passes without converging: the last image stands as the answer.
    Unconverged,
    /// The map could not be evaluated at the current iterate.
    Failed,
}

/// An Anderson-accelerated solve of `z = G(z)` on vectors of a fixed length, with its
/// buffers kept between solves.
#[derive(Clone, Debug)]
pub(crate) struct FixedPoint {
    /// The iterate: the caller writes the initial guess here before [`FixedPoint::solve`].
    pub(crate) z: Vec<f64>,
    /// `G(z)` of the last pass.
    image: Vec<f64>,
    anderson: Anderson,
}

impl FixedPoint {
    /// A solver for vectors of `n` entries.
    pub(crate) fn new(n: usize) -> FixedPoint {
        FixedPoint {
            z: vec![0.0; n],
            image: vec![0.0; n],
            anderson: Anderson::new(n),
        }
    }

    /// Iterates from the guess in `z`: each pass counts in `passes` and has `map(z, g)`
    /// write `G(z)` into `g`, or return `false` when `G` cannot be evaluated there. The
    /// side effects of the last call of `map` are the caller's answer: after a
    /// convergence, an exhausted budget or a non-finite change, that call's image is the
    /// solution.
    pub(crate) fn solve(
        &mut self,
        passes: &mut u64,
        mut map: impl FnMut(&[f64], &mut [f64]) -> bool,
    ) -> Outcome {
        self.anderson.reset();
        for _ in 0..MAX_ITERATIONS {
            *passes += 1;
            if !map(&self.z, &mut self.image) {
                return Outcome::Failed;
            }
            let (mut change, mut scale): (f64, f64) = (0.0, 0.0);
            for (g, z) in self.image.iter().zip(&self.z) {
                change = change.max((g - z).abs());
                scale = scale.max(g.abs());
            }
            if !change.is_finite() {
                return Outcome::NotFinite;
            }
            if change <= CONVERGED * (1.0 + scale) {
                return Outcome::Converged;
            }
            self.anderson.next(&mut self.z, &self.image);
        }
        Outcome::Unconverged
    }
}

/// The history of an Anderson-accelerated iteration on vectors of a fixed length.
#[derive(Clone, Debug)]
struct Anderson {
    /// Differences of successive residuals `f = G(z) − z`, newest at `(head + len − 1) % DEPTH`.
    df: Vec<Vec<f64>>,
    /// Differences of successive images `G(z)`.
    dg: Vec<Vec<f64>>,
    f_prev: Vec<f64>,
    g_prev: Vec<f64>,
    len: usize,
    head: usize,
    started: bool,
}

impl Anderson {
    /// An empty history for vectors of `n` entries.
    fn new(n: usize) -> Anderson {
        Anderson {
            df: vec![vec![0.0; n]; DEPTH],
            dg: vec![vec![0.0; n]; DEPTH],
            f_prev: vec![0.0; n],
            g_prev: vec![0.0; n],
            len: 0,
            head: 0,
            started: false,
        }
    }

    /// Forgets the history (a new fixed-point problem).
    fn reset(&mut self) {
        self.len = 0;
        self.head = 0;
        self.started = false;
    }

    /// Given the current iterate `z` and its image `g = G(z)`, writes the next iterate
    /// into `z`.
    fn next(&mut self, z: &mut [f64], g: &[f64]) {
        let n = z.len();
        if self.started {
            let slot = (self.head + self.len) % DEPTH;
            if self.len == DEPTH {
                self.head = (self.head + 1) % DEPTH;
            } else {
                self.len += 1;
            }
            for i in 0..n {
                let f = g[i] - z[i];
                self.df[slot][i] = f - self.f_prev[i];
                self.dg[slot][i] = g[i] - self.g_prev[i];
            }
        }
        for i in 0..n {
            self.f_prev[i] = g[i] - z[i];
            self.g_prev[i] = g[i];
        }
        self.started = true;
        let m = self.len;
        if m == 0 {
            z.copy_from_slice(g);
            return;
        }
        // Least squares min |f − ΔF γ| by the normal equations, lightly regularized.
        let mut a = [[0.0f64; DEPTH]; DEPTH];
        let mut b = [0.0f64; DEPTH];
        let col = |j: usize| (self.head + j) % DEPTH;
        for r in 0..m {
            let dr = &self.df[col(r)];
            b[r] = dot(dr, &self.f_prev);
            for c in 0..=r {
                let v = dot(dr, &self.df[col(c)]);
                a[r][c] = v;
                a[c][r] = v;
            }
        }
        let trace: f64 = (0..m).map(|i| a[i][i]).sum();
        for i in 0..m {
            a[i][i] += 1e-10 * trace + f64::MIN_POSITIVE;
        }
        let Some(gamma) = solve_small(&mut a, &mut b, m) else {
            z.copy_from_slice(g);
            return;
        };
        z.copy_from_slice(g);
        for j in 0..m {
            let dg = &self.dg[col(j)];
            for i in 0..n {
                z[i] -= gamma[j] * dg[i];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn it_converges_where_the_plain_iteration_diverges() {
        // z = G(z) = R z + c with R a rotation scaled by 1.5: the plain iteration
        // diverges, Anderson converges to the fixed point (I − R)⁻¹ c.
        let (s, co) = (0.7f64.sin() * 1.5, 0.7f64.cos() * 1.5);
        let g = |z: &[f64]| vec![co * z[0] - s * z[1] + 1.0, s * z[0] + co * z[1] - 2.0];
        let mut acc = Anderson::new(2);
        let mut z = vec![0.0, 0.0];
        for _ in 0..20 {
            let gz = g(&z);
            acc.next(&mut z, &gz);
        }
        let gz = g(&z);
        assert!(
            (gz[0] - z[0]).abs() < 1e-9 && (gz[1] - z[1]).abs() < 1e-9,
            "{z:?}"
        );
        let mut plain = vec![0.0, 0.0];
        for _ in 0..20 {
            plain = g(&plain);
        }
        assert!((g(&plain)[0] - plain[0]).abs() > 1.0);
    }

    #[test]
    fn a_solve_says_how_it_ended() {
        let mut passes = 0;
        let mut solver = FixedPoint::new(1);
        // z = cos z converges in a few passes.
        let outcome = solver.solve(&mut passes, |z, g| {
            g[0] = z[0].cos();
            true
        });
        assert_eq!(outcome, Outcome::Converged);
        assert!(
            (solver.z[0] - solver.z[0].cos()).abs() < 1e-6,
            "{}",
            solver.z[0]
        );
        assert!(passes < MAX_ITERATIONS as u64);
        // z = z + 1 has no fixed point: the budget runs out and says so. (From 0 every
        // iterate is a whole number, so no rounding hands Anderson a spurious secant.)
        passes = 0;
        solver.z[0] = 0.0;
        let outcome = solver.solve(&mut passes, |z, g| {
            g[0] = z[0] + 1.0;
            true
        });
        assert_eq!(outcome, Outcome::Unconverged);
        assert_eq!(passes, MAX_ITERATIONS as u64);
        let outcome = solver.solve(&mut passes, |_, g| {
            g[0] = f64::INFINITY;
            true
        });
        assert_eq!(outcome, Outcome::NotFinite);
        let outcome = solver.solve(&mut passes, |_, _| false);
        assert_eq!(outcome, Outcome::Failed);
    }
}
