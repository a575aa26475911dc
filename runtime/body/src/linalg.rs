//! Small dense linear algebra for inverse kinematics: a row-major matrix and a singular
//! value decomposition by one-sided Jacobi rotations, with the damped pseudo-inverse and
//! the null-space projector of eq. 2-1 built on it.
//!
//! Matrices here are a few rows (3 to 12 task dimensions) by a few tens of columns (the
//! DOFs of a chain), so a plain Jacobi SVD is both exact to rounding and fast; every
//! buffer is kept between calls so that solving allocates nothing once warmed up.

/// A dense `rows × cols` matrix stored row by row.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mat {
    rows: usize,
    cols: usize,
    data: Vec<f64>,
}

impl Mat {
    /// A zero matrix.
    pub fn zeros(rows: usize, cols: usize) -> Mat {
        Mat {
            rows,
            cols,
            data: vec![0.0; rows * cols],
        }
    }

    /// Resizes to `rows × cols` and sets every entry to zero (keeps the allocation).
    pub fn reset(&mut self, rows: usize, cols: usize) {
        self.rows = rows;
        self.cols = cols;
        self.data.clear();
        self.data.resize(rows * cols, 0.0);
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// Number of columns.
    pub fn cols(&self) -> usize {
        self.cols
    }

    /// Entry `(r, c)`.
    #[inline]
    pub fn get(&self, r: usize, c: usize) -> f64 {
        self.data[r * self.cols + c]
    }

    /// Sets entry `(r, c)`.
    #[inline]
    pub fn set(&mut self, r: usize, c: usize, v: f64) {
        self.data[r * self.cols + c] = v;
    }

    /// Row `r` as a slice.
    #[inline]
    pub fn row(&self, r: usize) -> &[f64] {
        &self.data[r * self.cols..(r + 1) * self.cols]
    }

    /// Row `r` as a mutable slice.
    #[inline]
    pub fn row_mut(&mut self, r: usize) -> &mut [f64] {
        &mut self.data[r * self.cols..(r + 1) * self.cols]
    }

    /// `out = self · x` (`x.len() == cols`, `out.len() == rows`).
    pub fn mul_vec(&self, x: &[f64], out: &mut [f64]) {
        for (r, o) in out.iter_mut().enumerate().take(self.rows) {
            *o = dot(self.row(r), x);
        }
    }

    /// `out = self · p` where `p` is a symmetric `cols × cols` matrix.
    pub fn mul_symmetric(&self, p: &Mat, out: &mut Mat) {
        out.reset(self.rows, p.cols);
        for r in 0..self.rows {
            for c in 0..p.cols {
                // p is symmetric: column c equals row c.
                let v = dot(self.row(r), p.row(c));
                out.set(r, c, v);
            }
        }
    }
}

/// The dot product of two equal-length slices.
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The singular value decomposition `J = V Σ Uᵀ` of a wide matrix `J` (`m × n`, `m ≤ n`
/// in IK): `U` holds `m` orthonormal `n`-vectors (the row space of `J`), `V` is an
/// orthogonal `m × m` matrix, `Σ` the singular values.
///
/// Computed by one-sided Jacobi rotations on the rows of `J` (the columns of `Jᵀ`).
#[derive(Clone, Debug, Default)]
pub struct Svd {
    m: usize,
    n: usize,
    /// Row k: the k-th right singular vector of J (an n-vector), unit length or zero.
    u: Vec<f64>,
    /// Column k: the k-th left singular vector of J (an m-vector), stored row-major m × m.
    v: Vec<f64>,
    sigma: Vec<f64>,
    scratch: Vec<f64>,
}

/// Singular values below this are treated as zero (rank deficiency).
pub const RANK_EPSILON: f64 = 1e-9;

impl Svd {
    /// Decomposes `j`; replaces any previous decomposition.
    pub fn compute(&mut self, j: &Mat) {
        let (m, n) = (j.rows, j.cols);
        self.m = m;
        self.n = n;
        self.u.clear();
        self.u.extend_from_slice(&j.data);
        self.v.clear();
        self.v.resize(m * m, 0.0);
        for k in 0..m {
            self.v[k * m + k] = 1.0;
        }
        let scale: f64 = j.data.iter().map(|x| x * x).sum::<f64>().max(1e-300);
        for _sweep in 0..60 {
            let mut rotated = false;
            for p in 0..m {
                for q in p + 1..m {
                    let (a, b) = self.u.split_at_mut(q * n);
                    let up = &mut a[p * n..p * n + n];
                    let uq = &mut b[..n];
                    let alpha = dot(up, up);
                    let beta = dot(uq, uq);
                    let gamma = dot(up, uq);
                    if gamma.abs() <= 1e-13 * (alpha * beta).sqrt()
                        || alpha.min(beta) < 1e-26 * scale
                    {
                        continue;
                    }
                    rotated = true;
                    let zeta = (beta - alpha) / (2.0 * gamma);
                    let t = zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt());
                    let c = 1.0 / (1.0 + t * t).sqrt();
                    let s = c * t;
                    for (x, y) in up.iter_mut().zip(uq.iter_mut()) {
                        let (xp, xq) = (*x, *y);
                        *x = c * xp - s * xq;
                        *y = s * xp + c * xq;
                    }
                    for r in 0..m {
                        let (vp, vq) = (self.v[r * m + p], self.v[r * m + q]);
                        self.v[r * m + p] = c * vp - s * vq;
                        self.v[r * m + q] = s * vp + c * vq;
                    }
                }
            }
            if !rotated {
                break;
            }
        }
        self.sigma.clear();
        for k in 0..m {
            let row = &mut self.u[k * n..k * n + n];
            let s = dot(row, row).sqrt();
            self.sigma.push(s);
            if s > RANK_EPSILON {
                row.iter_mut().for_each(|x| *x /= s);
            } else {
                row.iter_mut().for_each(|x| *x = 0.0);
            }
        }
    }

    /// The singular values (unsorted).
    pub fn singular_values(&self) -> &[f64] {
        &self.sigma
    }

    /// The smallest singular value (0 for an empty matrix).
    pub fn min_singular_value(&self) -> f64 {
        if self.sigma.is_empty() {
            0.0
        } else {
            self.sigma.iter().copied().fold(f64::INFINITY, f64::min)
        }
    }

    /// The rank: singular values above [`RANK_EPSILON`].
    pub fn rank(&self) -> usize {
        self.sigma.iter().filter(|s| **s > RANK_EPSILON).count()
    }

    /// `out += J⁺_λ · dx`, the damped least-squares pseudo-inverse `U Σ(Σ² + λ²)⁻¹ Vᵀ`
    /// (`lambda2 = λ²`; 0 gives the Moore–Penrose pseudo-inverse).
    pub fn add_pseudo_inverse_times(&mut self, dx: &[f64], lambda2: f64, out: &mut [f64]) {
        let (m, n) = (self.m, self.n);
        self.scratch.clear();
        for k in 0..m {
            let s = self.sigma[k];
            if s <= RANK_EPSILON {
                self.scratch.push(0.0);
                continue;
            }
            let vk: f64 = (0..m).map(|r| self.v[r * m + k] * dx[r]).sum();
            self.scratch.push(vk * s / (s * s + lambda2));
        }
        for k in 0..m {
            let w = self.scratch[k];
            if w != 0.0 {
                let row = &self.u[k * n..k * n + n];
                for (o, u) in out.iter_mut().zip(row) {
                    *o += w * u;
                }
            }
        }
    }

    /// Removes from the projector `p` (an `n × n` symmetric matrix) the row space of the
    /// decomposed matrix: `p ← p − U_r U_rᵀ` (the `(I − J⁺J)` of eq. 2-1, applied to
    /// a projector whose range contains that row space).
    pub fn remove_row_space(&self, p: &mut Mat) {
        let n = self.n;
        for k in 0..self.m {
            if self.sigma[k] <= RANK_EPSILON {
                continue;
            }
            let u = &self.u[k * n..k * n + n];
            for r in 0..n {
                let ur = u[r];
                if ur == 0.0 {
                    continue;
                }
                let row = p.row_mut(r);
                for (x, uc) in row.iter_mut().zip(u) {
                    *x -= ur * uc;
                }
            }
        }
    }

    /// Projects `x` onto the null space of the decomposed matrix: `x ← x − U_r U_rᵀ x`.
    pub fn project_out_row_space(&self, x: &mut [f64]) {
        let n = self.n;
        for k in 0..self.m {
            if self.sigma[k] <= RANK_EPSILON {
                continue;
            }
            let u = &self.u[k * n..k * n + n];
            let c = dot(u, x);
            for (xi, ui) in x.iter_mut().zip(u) {
                *xi -= c * ui;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Draws in [-1, 1).
    fn pseudo_random(draw: &mut impl FnMut() -> f64) -> f64 {
        draw() * 2.0 - 1.0
    }

    #[test]
    fn pseudo_inverse_solves_full_rank_systems_and_projects_out() {
        let mut draw = crate::math::draws(7);
        for (m, n) in [(3, 7), (6, 9), (6, 21), (3, 3)] {
            let mut j = Mat::zeros(m, n);
            for r in 0..m {
                for c in 0..n {
                    j.set(r, c, pseudo_random(&mut draw));
                }
            }
            let mut svd = Svd::default();
            svd.compute(&j);
            assert_eq!(svd.rank(), m);
            let dx: Vec<f64> = (0..m).map(|_| pseudo_random(&mut draw)).collect();
            let mut dq = vec![0.0; n];
            svd.add_pseudo_inverse_times(&dx, 0.0, &mut dq);
            let mut back = vec![0.0; m];
            j.mul_vec(&dq, &mut back);
            for (a, b) in back.iter().zip(&dx) {
                assert!((a - b).abs() < 1e-10, "{a} vs {b}");
            }
            // A projected vector is invisible to J.
            let mut z: Vec<f64> = (0..n).map(|_| pseudo_random(&mut draw)).collect();
            svd.project_out_row_space(&mut z);
            j.mul_vec(&z, &mut back);
            assert!(back.iter().all(|x| x.abs() < 1e-10), "{back:?}");
        }
    }

    #[test]
    fn rank_deficient_matrices_are_detected() {
        let mut j = Mat::zeros(3, 4);
        for c in 0..4 {
            j.set(0, c, c as f64 + 1.0);
            j.set(1, c, 2.0 * (c as f64 + 1.0));
            j.set(2, c, if c == 0 { 1.0 } else { 0.0 });
        }
        let mut svd = Svd::default();
        svd.compute(&j);
        assert_eq!(svd.rank(), 2);
        assert!(svd.min_singular_value() < 1e-9);
    }
}
