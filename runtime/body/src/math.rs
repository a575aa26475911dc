//! Scalar and small-vector math shared by the body model and the crates above it: the
//! smoothstep ease, the mass-weighted centre of a set of parts, a dense solve of a few
//! unknowns, and reproducible draws for tests and benchmarks.
//!
//! Each formula lives here once so that every caller rounds the same way: recordings are
//! compared bit for bit, so two copies that drift apart in operation order would make
//! two actions disagree in the last bit.

use glam::DVec3;

/// The smoothstep ease `3u² − 2u³` of `u` clamped to [0, 1]: rises from 0 to 1 with zero
/// slope at both ends.
#[inline]
pub fn smoothstep(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * (3.0 - 2.0 * u)
}

/// Reproducible draws in [0, 1) for tests and benchmarks: a 64-bit linear congruential
/// generator seeded with `seed` (Knuth's MMIX constants), its top 53 bits. The same seed
/// gives the same numbers on every machine.
pub fn draws(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (seed >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The mass-weighted mean of `parts` (each a position and its mass), summed in the order
/// given; the origin when the total mass is not positive.
#[inline]
pub fn center_of_mass(parts: impl IntoIterator<Item = (DVec3, f64)>) -> DVec3 {
    let mut weighted = DVec3::ZERO;
    let mut mass = 0.0;
    for (position, m) in parts {
        weighted += position * m;
        mass += m;
    }
    if mass > 0.0 {
        weighted / mass
    } else {
        DVec3::ZERO
    }
}

/// Solves the leading `m × m` block of `a x = b` (`m ≤ N`) by Gaussian elimination with
/// partial pivoting and back substitution; `a` and `b` are overwritten. `None` when a
/// pivot is zero or not a number, or the solution is not finite.
// Two rows of one matrix are walked in lockstep: index loops read best.
#[allow(clippy::needless_range_loop)]
pub fn solve_small<const N: usize>(
    a: &mut [[f64; N]; N],
    b: &mut [f64; N],
    m: usize,
) -> Option<[f64; N]> {
    for c in 0..m {
        let p = (c..m).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[p][c] == 0.0 || a[p][c].is_nan() {
            return None;
        }
        a.swap(c, p);
        b.swap(c, p);
        for r in c + 1..m {
            let f = a[r][c] / a[c][c];
            for k in c..m {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; N];
    for r in (0..m).rev() {
        let mut s = b[r];
        for k in r + 1..m {
            s -= a[r][k] * x[k];
        }
        x[r] = s / a[r][r];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smoothstep_eases_from_zero_to_one_and_clamps() {
        assert_eq!(smoothstep(-1.0), 0.0);
        assert_eq!(smoothstep(0.0), 0.0);
        assert_eq!(smoothstep(0.5), 0.5);
        assert_eq!(smoothstep(1.0), 1.0);
        assert_eq!(smoothstep(2.0), 1.0);
        assert!((smoothstep(0.25) - 0.15625).abs() < 1e-15);
    }

    #[test]
    fn the_center_of_mass_weighs_each_part_by_its_mass() {
        let c = center_of_mass([(DVec3::X, 3.0), (DVec3::Y * 2.0, 1.0)]);
        assert!((c - DVec3::new(0.75, 0.5, 0.0)).length() < 1e-15);
        assert_eq!(center_of_mass([]), DVec3::ZERO);
    }

    #[test]
    fn small_systems_are_solved_and_singular_ones_refused() {
        // Needs a row swap: the first pivot is zero.
        let mut a = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [2.0, 0.0, 3.0]];
        let mut b = [7.0, 3.0, 11.0];
        let x = solve_small(&mut a, &mut b, 3).unwrap();
        for (got, want) in x.iter().zip([1.0, 2.0, 3.0]) {
            assert!((got - want).abs() < 1e-12, "{x:?}");
        }
        // Only the leading block counts.
        let mut a = [[2.0, 9.0], [9.0, 9.0]];
        let mut b = [4.0, 9.0];
        assert_eq!(solve_small(&mut a, &mut b, 1), Some([2.0, 0.0]));
        let mut a = [[1.0, 2.0], [2.0, 4.0]];
        let mut b = [1.0, 2.0];
        assert_eq!(solve_small(&mut a, &mut b, 2), None);
    }
}
