//! Inverse dynamics: the recursive Newton–Euler algorithm (thesis appendix B; Featherstone
//! table 5.1) in world coordinates, O(n).

use super::model::{first_link, FloatingBase, Model};
use super::spatial::{Force, Motion};
use glam::DVec3;

/// Generalized forces `tau` that produce `qdd` at the state prepared by
/// [`super::model::kinematics`] and [`super::model::velocities`], with gravity and the
/// external wrenches in `data.ext`. With a floating base, `base_accel` is the base's
/// spatial acceleration, the root entries of `tau` are left at 0 and the wrench the base
/// needs is returned; otherwise the returned wrench is the one the world exerts on the
/// root link's parent (zero when nothing is fixed).
pub(crate) fn rnea(
    model: &Model,
    data: &mut super::model::Data,
    qdd: &[f64],
    gravity: DVec3,
    base: Option<(&FloatingBase, Motion)>,
    tau: &mut [f64],
) -> Force {
    let start = first_link(model, base.map(|b| b.0));
    // Gravity as a fictitious upward acceleration of the world (Featherstone 5.3).
    let a_world = Motion::new(DVec3::ZERO, -gravity);
    let mut base_link = None;
    if let Some((_, a_base)) = base {
        let b = model.root.end - 1;
        base_link = Some(b);
        let a = a_base + a_world;
        data.a[b] = a;
        let i = &data.inertia[b];
        let v = data.v[b];
        data.f[b] = i.apply(&a) + v.cross_force(&i.apply(&v)) - data.ext[b];
        for k in model.root.clone() {
            tau[k] = 0.0;
        }
    }
    for k in start..model.n {
        let ap = model.parent[k].map_or(a_world, |p| data.a[p]);
        let a = ap + data.s[k] * qdd[k] + data.c[k];
        data.a[k] = a;
        if model.massive[k] {
            let i = &data.inertia[k];
            let v = data.v[k];
            data.f[k] = i.apply(&a) + v.cross_force(&i.apply(&v)) - data.ext[k];
        } else {
            // No body on this link: only the external wrench (usually none).
            data.f[k] = Force::ZERO - data.ext[k];
        }
    }
    for k in (start..model.n).rev() {
        let f = data.f[k];
        tau[k] = data.s[k].dot(&f) + model.armature[k] * qdd[k];
        if let Some(p) = model.parent[k] {
            data.f[p] += f;
        }
    }
    match base_link {
        Some(b) => data.f[b],
        None => Force::ZERO,
    }
}
