//! Dynamics (thesis chapter 3, appendices A and B): inverse dynamics by recursive
//! Newton–Euler, forward dynamics by the articulated-body algorithm, and a closed-loop
//! simulator with PD servos, joint limits and floor contact ([`sim`]).
//!
//! Conventions (see `docs/dynamics.md`): SI units, Y up, gravity `(0, −9.81, 0)` by
//! default. Every DOF is a link of its own (a joint with three DOFs is a chain of three
//! 1-DOF links). `tau[k]` is the generalized force of DOF `k`: a torque in N·m about its
//! axis for a rotation, a force in N along its axis for a translation; `qdd[k]` is the
//! second time derivative of the DOF's value. For the humanoid root, `root_x/y/z` are
//! world translations (their `tau` is the world force component along X, Y, Z on the
//! whole body), `root_yaw` rotates about world Y through the root, `root_pitch` about the
//! yawed X axis and `root_roll` about the yawed-and-pitched Z axis (their `tau` is the
//! torque about that axis through the root joint; `qdd` are Euler-angle accelerations,
//! singular at pitch = ±90°). Every non-root DOF has an armature (rotor inertia, kg·m²)
//! added to its diagonal of the mass matrix, in both directions, so that DOFs moving no
//! mass (fingers, toes, eyes) stay well-posed.

// The passes walk several per-DOF arrays in lockstep: index loops read best.
#![allow(clippy::needless_range_loop)]

pub mod aba;
mod anderson;
pub mod contact;
pub mod model;
pub mod rnea;
pub mod sim;
pub mod spatial;

use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use glam::DVec3;
pub use model::{
    nominal_link_inertia, nominal_links, Data, FloatingBase, Model, DEFAULT_ARMATURE,
    DEFAULT_ARMATURE_FRACTION, NOMINAL_LINK_MASS, NOMINAL_LINK_RADIUS,
};
pub use sim::{Control, Gains, SimParams, Simulation};
pub use spatial::{Force, Inertia, Motion};

/// Standard gravity (m/s²), pointing down (−Y).
pub const GRAVITY: DVec3 = DVec3::new(0.0, -9.81, 0.0);

/// External forces and torques on the segments, by joint (a joint's solids move with the
/// frame of its last DOF). Stored as world wrenches; reuse one value across calls.
#[derive(Clone, Debug)]
pub struct ExternalForces {
    per_joint: Vec<Force>,
    any: bool,
}

impl ExternalForces {
    /// No force on any of `skeleton`'s joints.
    pub fn new(skeleton: &Skeleton) -> ExternalForces {
        ExternalForces {
            per_joint: vec![Force::ZERO; skeleton.joints().len()],
            any: false,
        }
    }

    /// Adds the force `force` (N, world axes) applied at world point `point` on the
    /// segment of `joint`.
    pub fn add_force(&mut self, joint: usize, point: DVec3, force: DVec3) {
        self.per_joint[joint] += Force::at_point(point, force, DVec3::ZERO);
        self.any = true;
    }

    /// Adds a pure torque (N·m, world axes) on the segment of `joint`.
    pub fn add_torque(&mut self, joint: usize, torque: DVec3) {
        self.per_joint[joint] += Force::at_point(DVec3::ZERO, DVec3::ZERO, torque);
        self.any = true;
    }

    /// Removes every force.
    pub fn clear(&mut self) {
        if self.any {
            self.per_joint.iter_mut().for_each(|f| *f = Force::ZERO);
            self.any = false;
        }
    }

    /// The wrench on each joint's segment (about the world origin).
    pub fn wrenches(&self) -> &[Force] {
        &self.per_joint
    }

    /// Writes the wrenches into the per-link workspace.
    pub(crate) fn load(&self, model: &Model, data: &mut Data) {
        data.ext.iter_mut().for_each(|f| *f = Force::ZERO);
        if !self.any {
            return;
        }
        for (j, f) in self.per_joint.iter().enumerate() {
            if let Some((link, _)) = model.joint_link[j] {
                data.ext[link] += *f;
            }
        }
    }
}

/// The largest magnitude a state or input value may have (rad, m, their rates, N·m, N):
/// far beyond any body's, and far below where the solve's products overflow (a torque of
/// 1e308 came back as "singular configuration").
pub const STATE_BOUND: f64 = 1e9;

/// Checks that `values` has one finite entry within ±[`STATE_BOUND`] per DOF; the error
/// names the first bad one.
pub fn check_state(skeleton: &Skeleton, what: &str, values: &[f64]) -> Result<()> {
    if values.len() != skeleton.dof_count() {
        return Err(Error::Invalid(format!(
            "dynamics: `{what}` has {} values, skeleton `{}` has {} DOFs",
            values.len(),
            skeleton.name(),
            skeleton.dof_count()
        )));
    }
    if let Some(k) = values
        .iter()
        .position(|v| !v.is_finite() || v.abs() > STATE_BOUND)
    {
        return Err(Error::invalid_value(
            format!("dynamics: {what}[{}]", skeleton.dofs()[k].name),
            values[k],
            format!("a finite number within ±{STATE_BOUND:e}"),
        ));
    }
    Ok(())
}

/// A model with its workspace and gravity: the object to keep for repeated calls (no
/// call allocates).
#[derive(Clone, Debug)]
pub struct Dynamics {
    model: Model,
    data: Data,
    gravity: DVec3,
}

impl Dynamics {
    /// Builds the model of `skeleton` (see [`Model::new`]) with standard gravity.
    pub fn new(skeleton: &Skeleton) -> Result<Dynamics> {
        Ok(Dynamics::from_model(Model::new(skeleton)?))
    }

    /// Wraps an existing model.
    pub fn from_model(model: Model) -> Dynamics {
        let data = Data::new(&model);
        Dynamics {
            model,
            data,
            gravity: GRAVITY,
        }
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// Sets gravity (m/s², world axes).
    pub fn set_gravity(&mut self, gravity: DVec3) {
        self.gravity = gravity;
    }

    /// Gravity in m/s².
    pub fn gravity(&self) -> DVec3 {
        self.gravity
    }

    /// Inverse dynamics: the generalized forces `tau` (one per DOF) that give the
    /// accelerations `qdd` at state (`q`, `qd`) under gravity and `ext`. With
    /// `fixed_root`, the root is held still (its `qd` and `qdd` are taken as 0) and its
    /// `tau` entries are the force and torques the support must supply. The caller checks
    /// inputs (see [`check_state`]); slices must have one entry per DOF.
    pub fn inverse_dynamics(
        &mut self,
        q: &[f64],
        qd: &[f64],
        qdd: &[f64],
        ext: &ExternalForces,
        fixed_root: bool,
        tau: &mut [f64],
    ) {
        model::kinematics(&self.model, &mut self.data, q, None);
        let mut qd_w = std::mem::take(&mut self.data.qd);
        qd_w.copy_from_slice(qd);
        let mut qdd_w = std::mem::take(&mut self.data.qdd);
        qdd_w.copy_from_slice(qdd);
        if fixed_root {
            for k in self.model.root.clone() {
                qd_w[k] = 0.0;
                qdd_w[k] = 0.0;
            }
        }
        model::velocities(&self.model, &mut self.data, &qd_w, None);
        ext.load(&self.model, &mut self.data);
        rnea::rnea(&self.model, &mut self.data, &qdd_w, self.gravity, None, tau);
        self.data.qd = qd_w;
        self.data.qdd = qdd_w;
    }

    /// Forward dynamics: the accelerations `qdd` that the generalized forces `tau` give
    /// at state (`q`, `qd`) under gravity and `ext`. With `fixed_root`, the root is held
    /// still (its `qd` is taken as 0, its `tau` ignored, its `qdd` set to 0). Fails at a
    /// singular configuration (a free root at pitch = ±90°).
    pub fn forward_dynamics(
        &mut self,
        q: &[f64],
        qd: &[f64],
        tau: &[f64],
        ext: &ExternalForces,
        fixed_root: bool,
        qdd: &mut [f64],
    ) -> Result<()> {
        model::kinematics(&self.model, &mut self.data, q, None);
        let root = self.model.root.clone();
        let mut qd_w = std::mem::take(&mut self.data.qd);
        qd_w.copy_from_slice(qd);
        if fixed_root {
            for k in root.clone() {
                qd_w[k] = 0.0;
                qdd[k] = 0.0;
            }
        }
        model::velocities(&self.model, &mut self.data, &qd_w, None);
        self.data.qd = qd_w;
        ext.load(&self.model, &mut self.data);
        let mask = if fixed_root {
            Some(&self.model.root_mask[..])
        } else {
            None
        };
        let ok = aba::aba(
            &self.model,
            &mut self.data,
            tau,
            self.gravity,
            mask,
            None,
            None,
            qdd,
        );
        if ok.is_none() || qdd.iter().any(|a| !a.is_finite()) {
            return Err(Error::SingularConfiguration);
        }
        Ok(())
    }

    /// Kinetic and potential energy (J) at (`q`, `qd`); potential energy is zero at y = 0.
    pub fn energy(&mut self, q: &[f64], qd: &[f64]) -> (f64, f64) {
        model::kinematics(&self.model, &mut self.data, q, None);
        model::velocities(&self.model, &mut self.data, qd, None);
        (
            model::kinetic_energy(&self.model, &self.data, qd),
            model::potential_energy(&self.model, &self.data, self.gravity),
        )
    }

    /// Linear momentum (kg·m/s) and angular momentum about the world origin (kg·m²/s)
    /// of the bodies at (`q`, `qd`).
    pub fn momentum(&mut self, q: &[f64], qd: &[f64]) -> (DVec3, DVec3) {
        model::kinematics(&self.model, &mut self.data, q, None);
        model::velocities(&self.model, &mut self.data, qd, None);
        let h = model::momentum(&self.model, &self.data);
        (h.f, h.n)
    }
}

/// One-off inverse dynamics on `skeleton` under standard gravity (allocates; keep a
/// [`Dynamics`] for repeated calls). Inputs are checked.
pub fn inverse_dynamics(
    skeleton: &Skeleton,
    q: &[f64],
    qd: &[f64],
    qdd: &[f64],
    ext: &ExternalForces,
    fixed_root: bool,
) -> Result<Vec<f64>> {
    check_state(skeleton, "q", q)?;
    check_state(skeleton, "qd", qd)?;
    check_state(skeleton, "qdd", qdd)?;
    let mut d = Dynamics::new(skeleton)?;
    let mut tau = vec![0.0; q.len()];
    d.inverse_dynamics(q, qd, qdd, ext, fixed_root, &mut tau);
    Ok(tau)
}

/// One-off forward dynamics on `skeleton` under standard gravity (allocates; keep a
/// [`Dynamics`] for repeated calls). Inputs are checked.
pub fn forward_dynamics(
    skeleton: &Skeleton,
    q: &[f64],
    qd: &[f64],
    tau: &[f64],
    ext: &ExternalForces,
    fixed_root: bool,
) -> Result<Vec<f64>> {
    check_state(skeleton, "q", q)?;
    check_state(skeleton, "qd", qd)?;
    check_state(skeleton, "tau", tau)?;
    let mut d = Dynamics::new(skeleton)?;
    let mut qdd = vec![0.0; q.len()];
    d.forward_dynamics(q, qd, tau, ext, fixed_root, &mut qdd)?;
    Ok(qdd)
}

#[cfg(test)]
mod tests;
