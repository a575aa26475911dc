//! Forward dynamics: the articulated-body algorithm (Featherstone table 7.1), the O(n)
//! equivalent of the Armstrong-Green formulation of thesis appendix A, in world
//! coordinates, with prescribed-acceleration DOFs (hybrid dynamics, Featherstone 9.2) and
//! an optional floating base.

use super::model::{first_link, Data, FloatingBase, Model};
use super::spatial::Motion;
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
        let v = data.v[k];
        data.ia[k] = i;
        data.pa[k] = v.cross_force(&i.apply(&v)) - data.ext[k];
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
