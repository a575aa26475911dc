//! Forward dynamics: the articulated-body algorithm (Featherstone table 7.1), the O(n)
//! equivalent of the Armstrong-Green formulation of thesis appendix A, in world
//! coordinates, with prescribed-acceleration DOFs (hybrid dynamics, Featherstone 9.2) and
//! an optional floating base.

use super::model::{first_link, Data, FloatingBase, Model};
use super::spatial::{Force, Motion};
use glam::DVec3;

/// Accelerations for the state prepared by [`super::model::kinematics`] and
/// [`super::model::velocities`], generalized forces `tau`, gravity and the external
/// wrenches in `data.ext`. DOFs with `prescribed[k]` keep the acceleration found in
/// `qdd[k]`; every other entry of `qdd` is written. With a floating base, returns the
/// base's spatial acceleration (the root entries of `qdd` are left untouched).
/// `implicit[k]` (when given) is added to DOF `k`'s diagonal of the mass matrix, like the
/// armature: `h·c + h²·k` turns a damper `c` and spring `k` on the DOF, evaluated at the
/// step's start, into their implicit (backward Euler) form. Returns
/// `None` when a DOF has no inertia left to accelerate (a singular configuration).
#[allow(clippy::too_many_arguments)]
pub(crate) fn aba(
    model: &Model,
    data: &mut Data,
    tau: &[f64],
    gravity: DVec3,
    prescribed: Option<&[bool]>,
    implicit: Option<&[f64]>,
    base: Option<&FloatingBase>,
    qdd: &mut [f64],
) -> Option<Motion> {
    let start = first_link(model, base);
    let fixed = |k: usize| prescribed.is_some_and(|p| p[k]);
    for k in 0..model.n {
        let i = data.inertia[k];
        data.ia[k] = i;
        data.pa[k] = if model.massive[k] {
            let v = data.v[k];
            v.cross_force(&i.apply(&v)) - data.ext[k]
        } else {
            Force::ZERO - data.ext[k]
        };
    }
    for k in (start..model.n).rev() {
        let s = data.s[k];
        let parent = model.parent[k];
        if fixed(k) {
            if let Some(p) = parent {
                let ia = data.ia[k];
                let pa = data.pa[k] + ia.apply(&(data.c[k] + s * qdd[k]));
                data.ia[p] += ia;
                data.pa[p] += pa;
            }
            continue;
        }
        let u_vec = data.ia[k].apply(&s);
        let d = s.dot(&u_vec) + model.armature[k] + implicit.map_or(0.0, |x| x[k]);
        if d.is_nan() || d <= 1e-14 {
            return None;
        }
        let u = tau[k] - s.dot(&data.pa[k]);
        data.uu[k] = u_vec;
        data.d[k] = d;
        data.u[k] = u;
        if let Some(p) = parent {
            let mut ia = data.ia[k];
            ia.sub_outer(&u_vec, 1.0 / d);
            let pa = data.pa[k] + ia.apply(&data.c[k]) + u_vec * (u / d);
            data.ia[p] += ia;
            data.pa[p] += pa;
        }
    }
    let a_world = Motion::new(DVec3::ZERO, -gravity);
    let mut base_accel = None;
    if base.is_some() {
        let b = model.root.end - 1;
        let a = data.ia[b].solve(&(data.pa[b] * -1.0));
        if !a.is_finite() {
            return None;
        }
        data.a[b] = a;
        base_accel = Some(a - a_world);
    }
    for k in start..model.n {
        let ap = model.parent[k].map_or(a_world, |p| data.a[p]);
        let a0 = ap + data.c[k];
        if !fixed(k) {
            qdd[k] = (data.u[k] - a0.dot(&data.uu[k])) / data.d[k];
        }
        data.a[k] = a0 + data.s[k] * qdd[k];
    }
    match base {
        Some(_) => base_accel,
        None => Some(Motion::ZERO),
    }
}

/// Factors the joint-space mass matrix at the posture prepared by
/// [`super::model::kinematics`] for [`solve`]: the articulated inertias (`data.ia`,
/// unreduced), `U = IA·S` (`data.uu`) and `D = Sᵀ·IA·S + armature + implicit`
/// (`data.d`) of the articulated-body algorithm (Featherstone table 7.1), which depend
/// on the posture only. `None` when a DOF has no inertia left (singular configuration).
pub(crate) fn factor(
    model: &Model,
    data: &mut Data,
    prescribed: Option<&[bool]>,
    implicit: Option<&[f64]>,
    base: Option<&FloatingBase>,
) -> Option<()> {
    let start = first_link(model, base);
    let fixed = |k: usize| prescribed.is_some_and(|p| p[k]);
    for k in 0..model.n {
        data.ia[k] = data.inertia[k];
    }
    for k in (start..model.n).rev() {
        let parent = model.parent[k];
        if fixed(k) {
            if let Some(p) = parent {
                let ia = data.ia[k];
                data.ia[p] += ia;
            }
            continue;
        }
        let s = data.s[k];
        let u_vec = data.ia[k].apply(&s);
        let d = s.dot(&u_vec) + model.armature[k] + implicit.map_or(0.0, |x| x[k]);
        if d.is_nan() || d <= 1e-14 {
            return None;
        }
        data.uu[k] = u_vec;
        data.d[k] = d;
        if let Some(p) = parent {
            let mut ia = data.ia[k];
            ia.sub_outer(&u_vec, 1.0 / d);
            data.ia[p] += ia;
        }
    }
    Some(())
}

/// Solves `(M + implicit) x = rhs` after [`factor`] (the articulated-body algorithm with
/// no velocity and no gravity): with `rhs` the generalized momenta this gives the joint
/// velocities. DOFs with `prescribed[k]` keep the value found in `x[k]`. With a floating
/// base, `base_rhs` is the base's row (the whole body's spatial momentum about the world
/// origin) and the base's spatial velocity is returned.
pub(crate) fn solve(
    model: &Model,
    data: &mut Data,
    rhs: &[f64],
    prescribed: Option<&[bool]>,
    base: Option<(&FloatingBase, Force)>,
    x: &mut [f64],
) -> Option<Motion> {
    let start = first_link(model, base.map(|b| b.0));
    let fixed = |k: usize| prescribed.is_some_and(|p| p[k]);
    for k in 0..model.n {
        data.pa[k] = Force::ZERO;
    }
    let b = model.root.end.max(1) - 1;
    if let Some((_, h)) = base {
        data.pa[b] = h * -1.0;
    }
    for k in (start..model.n).rev() {
        let parent = model.parent[k];
        if fixed(k) {
            if let Some(p) = parent {
                let pa = data.pa[k] + data.ia[k].apply(&(data.s[k] * x[k]));
                data.pa[p] += pa;
            }
            continue;
        }
        let u = rhs[k] - data.s[k].dot(&data.pa[k]);
        data.u[k] = u;
        if let Some(p) = parent {
            let pa = data.pa[k] + data.uu[k] * (u / data.d[k]);
            data.pa[p] += pa;
        }
    }
    let mut base_velocity = Motion::ZERO;
    if base.is_some() {
        base_velocity = data.ia[b].solve(&(data.pa[b] * -1.0));
        if !base_velocity.is_finite() {
            return None;
        }
        data.a[b] = base_velocity;
    }
    for k in start..model.n {
        let a0 = model.parent[k].map_or(Motion::ZERO, |p| data.a[p]);
        if !fixed(k) {
            x[k] = (data.u[k] - a0.dot(&data.uu[k])) / data.d[k];
        }
        data.a[k] = a0 + data.s[k] * x[k];
    }
    Some(base_velocity)
}
