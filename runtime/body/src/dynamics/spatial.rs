//! Minimal 6-D spatial algebra (Featherstone, *Rigid Body Dynamics Algorithms*, ch. 2) in
//! world coordinates, Plücker vectors taken at the world origin.
//!
//! * a motion vector `(w, v)`: angular velocity `w` and the velocity `v` of the body point
//!   that coincides with the world origin;
//! * a force vector `(n, f)`: the moment `n` about the world origin and the force `f`;
//! * an inertia `[A B; Bᵀ C]` maps a motion to a force: `n = A w + B v`, `f = Bᵀ w + C v`.

use glam::{DMat3, DVec3};
use std::ops::{Add, AddAssign, Mul, Sub};

/// A spatial motion vector (velocity, acceleration, joint axis).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Motion {
    /// Angular part (rad/s).
    pub w: DVec3,
    /// Linear part: velocity of the point at the world origin (m/s).
    pub v: DVec3,
}

/// A spatial force vector (wrench about the world origin).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Force {
    /// Moment about the world origin (N·m).
    pub n: DVec3,
    /// Force (N).
    pub f: DVec3,
}

impl Motion {
    /// The zero motion.
    pub const ZERO: Motion = Motion {
        w: DVec3::ZERO,
        v: DVec3::ZERO,
    };

    /// A motion from its angular and linear parts.
    #[inline]
    pub fn new(w: DVec3, v: DVec3) -> Motion {
        Motion { w, v }
    }

    /// The spatial cross product `self ×ₘ m` (derivative of `m` moving with velocity `self`).
    #[inline]
    pub fn cross_motion(&self, m: &Motion) -> Motion {
        Motion {
            w: self.w.cross(m.w),
            v: self.w.cross(m.v) + self.v.cross(m.w),
        }
    }

    /// The spatial cross product `self ×* f` (derivative of `f` moving with velocity `self`).
    #[inline]
    pub fn cross_force(&self, f: &Force) -> Force {
        Force {
            n: self.w.cross(f.n) + self.v.cross(f.f),
            f: self.w.cross(f.f),
        }
    }

    /// The scalar product with a force (power).
    #[inline]
    pub fn dot(&self, f: &Force) -> f64 {
        self.w.dot(f.n) + self.v.dot(f.f)
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.w.is_finite() && self.v.is_finite()
    }
}

impl Add for Motion {
    type Output = Motion;
    #[inline]
    fn add(self, o: Motion) -> Motion {
        Motion::new(self.w + o.w, self.v + o.v)
    }
}

impl Sub for Motion {
    type Output = Motion;
    #[inline]
    fn sub(self, o: Motion) -> Motion {
        Motion::new(self.w - o.w, self.v - o.v)
    }
}

impl AddAssign for Motion {
    #[inline]
    fn add_assign(&mut self, o: Motion) {
        self.w += o.w;
        self.v += o.v;
    }
}

impl Mul<f64> for Motion {
    type Output = Motion;
    #[inline]
    fn mul(self, s: f64) -> Motion {
        Motion::new(self.w * s, self.v * s)
    }
}

impl Force {
    /// The zero force.
    pub const ZERO: Force = Force {
        n: DVec3::ZERO,
        f: DVec3::ZERO,
    };

    /// A force `f` applied at world point `p`, plus a free torque `torque`.
    #[inline]
    pub fn at_point(p: DVec3, f: DVec3, torque: DVec3) -> Force {
        Force {
            n: p.cross(f) + torque,
            f,
        }
    }

    /// Whether every component is finite.
    pub fn is_finite(&self) -> bool {
        self.n.is_finite() && self.f.is_finite()
    }
}

impl Add for Force {
    type Output = Force;
    #[inline]
    fn add(self, o: Force) -> Force {
        Force {
            n: self.n + o.n,
            f: self.f + o.f,
        }
    }
}

impl Sub for Force {
    type Output = Force;
    #[inline]
    fn sub(self, o: Force) -> Force {
        Force {
            n: self.n - o.n,
            f: self.f - o.f,
        }
    }
}

impl AddAssign for Force {
    #[inline]
    fn add_assign(&mut self, o: Force) {
        self.n += o.n;
        self.f += o.f;
    }
}

impl Mul<f64> for Force {
    type Output = Force;
    #[inline]
    fn mul(self, s: f64) -> Force {
        Force {
            n: self.n * s,
            f: self.f * s,
        }
    }
}

/// `a bᵀ` as a 3×3 matrix.
#[inline]
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// `Mᵀ x` without forming the transpose.
#[inline]
fn transpose_mul(m: &DMat3, x: DVec3) -> DVec3 {
    DVec3::new(m.x_axis.dot(x), m.y_axis.dot(x), m.z_axis.dot(x))
}

/// The skew matrix `[c]×` with `[c]× x = c × x`.
#[inline]
fn skew(c: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, c.z, -c.y),
        DVec3::new(-c.z, 0.0, c.x),
        DVec3::new(c.y, -c.x, 0.0),
    )
}

/// A symmetric spatial inertia `[A B; Bᵀ C]` (rigid or articulated).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertia {
    /// Rotational block (about the world origin).
    pub a: DMat3,
    /// Coupling block.
    pub b: DMat3,
    /// Translational block.
    pub c: DMat3,
}

impl Default for Inertia {
    fn default() -> Self {
        Inertia::ZERO
    }
}

impl Inertia {
    /// The zero inertia (a massless body).
    pub const ZERO: Inertia = Inertia {
        a: DMat3::ZERO,
        b: DMat3::ZERO,
        c: DMat3::ZERO,
    };

    /// The inertia of a rigid body of `mass` with its centre of mass at world point `com`
    /// and rotational inertia `inertia_com` about the COM (world axes).
    pub fn rigid(mass: f64, com: DVec3, inertia_com: DMat3) -> Inertia {
        let cx = skew(com);
        Inertia {
            a: inertia_com - cx * cx * mass,
            b: cx * mass,
            c: DMat3::from_diagonal(DVec3::splat(mass)),
        }
    }

    /// `I m`: the momentum (or force) of motion `m`.
    #[inline]
    pub fn apply(&self, m: &Motion) -> Force {
        Force {
            n: self.a * m.w + self.b * m.v,
            f: transpose_mul(&self.b, m.w) + self.c * m.v,
        }
    }

    /// `I − u uᵀ / d` for a force-type vector `u` (the articulated-body update).
    #[inline]
    pub fn sub_outer(&mut self, u: &Force, inv_d: f64) {
        let (n, f) = (u.n * inv_d, u.f * inv_d);
        self.a -= outer(n, u.n);
        self.b -= outer(n, u.f);
        self.c -= outer(f, u.f);
    }

    /// Solves `I x = r` for a motion `x` (the inertia must be positive definite).
    pub fn solve(&self, r: &Force) -> Motion {
        // Schur complement of C: (A − B C⁻¹ Bᵀ) w = n − B C⁻¹ f, then v = C⁻¹ (f − Bᵀ w).
        let c_inv = self.c.inverse();
        let bc = self.b * c_inv;
        let schur = self.a - bc * self.b.transpose();
        let w = schur.inverse() * (r.n - bc * r.f);
        let v = c_inv * (r.f - transpose_mul(&self.b, w));
        Motion { w, v }
    }
}

impl Add for Inertia {
    type Output = Inertia;
    #[inline]
    fn add(self, o: Inertia) -> Inertia {
        Inertia {
            a: self.a + o.a,
            b: self.b + o.b,
            c: self.c + o.c,
        }
    }
}

impl AddAssign for Inertia {
    #[inline]
    fn add_assign(&mut self, o: Inertia) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rigid_inertia_gives_the_momentum_of_a_point_mass() {
        // A point mass at c moving with the body: p = m (v + w × c), L = c × p.
        let (m, c) = (2.0, DVec3::new(0.3, -0.1, 0.5));
        let i = Inertia::rigid(m, c, DMat3::ZERO);
        let mo = Motion::new(DVec3::new(0.2, 1.0, -0.4), DVec3::new(1.0, 0.5, 0.1));
        let h = i.apply(&mo);
        let p = (mo.v + mo.w.cross(c)) * m;
        assert!((h.f - p).length() < 1e-12);
        assert!((h.n - c.cross(p)).length() < 1e-12);
        let back = (i + Inertia::rigid(1.0, DVec3::X, DMat3::IDENTITY))
            .solve(&(h + Inertia::rigid(1.0, DVec3::X, DMat3::IDENTITY).apply(&mo)));
        assert!((back.w - mo.w).length() < 1e-10 && (back.v - mo.v).length() < 1e-10);
    }
}
