//! The closed-loop simulator (thesis 3.5, fig. 3-4): forward dynamics integrated with a
//! symplectic Störmer–Verlet step of `small_time_step` in momentum form (see `step` and
//! `docs/dynamics.md`), control torques refreshed every `time_step`, PD servos (eq. 4-1),
//! joint limits as stiff one-sided springs and floor contact.
//!
//! DOFs are either *dynamic* (integrated from forces) or *prescribed* (moved
//! kinematically: their value advances at their set velocity, zero acceleration, and the
//! dynamics reacts to that motion). When every root DOF of a humanoid root is dynamic the
//! root is integrated as a floating base (quaternion orientation, spatial velocity), so a
//! tumbling body never meets the Euler angles' singularity; its Euler DOFs are written
//! back for output. The base's row of the momentum equation is the whole body's spatial
//! momentum, which only gravity and external forces change: torque-free motion keeps
//! linear and angular momentum to round-off.

use super::anderson::{FixedPoint, Outcome};
use super::contact::{ContactParams, Floor};
use super::model::{self, Data, FloatingBase, Model};
use super::rnea::rnea;
use super::spatial::{Force, Motion};
use super::{aba, ExternalForces, GRAVITY};
use crate::error::{Error, Result};
use crate::skeleton::Skeleton;
use glam::{DMat3, DQuat, DVec3, EulerRot};

/// PD gains per unit of inertia: the torque on DOF `k` is
/// `M_kk · (kp · (q_d − q) + kd · (q̇_d − q̇))`, where `M_kk` (kg·m², or kg for a
/// translation) is the inertia the DOF moves (the diagonal of the mass matrix, armature
/// included): the gains scale with the segments' masses.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gains {
    /// Stiffness per unit inertia (1/s²): the square of the servo's natural frequency.
    pub kp: f64,
    /// Damping per unit inertia (1/s): `2·sqrt(kp)` is critical damping.
    pub kd: f64,
}

impl Default for Gains {
    fn default() -> Self {
        Gains {
            kp: 400.0,
            kd: 40.0,
        }
    }
}

impl Gains {
    /// Checks both gains are finite and ≥ 0.
    pub fn validate(&self) -> Result<()> {
        for (what, v) in [("kp", self.kp), ("kd", self.kd)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid_value(what, v, "a finite gain ≥ 0"));
            }
        }
        Ok(())
    }
}

/// What drives the dynamic DOFs during [`Simulation::advance`].
#[derive(Clone, Copy, Debug)]
pub enum Control<'a> {
    /// No actuation: the body moves under gravity, contact, limits and damping.
    Passive,
    /// PD servos toward `q` (moving at `qd`), eq. 4-1, refreshed every sub-step; with
    /// `gravity_compensation` the gravity and velocity torques predicted by inverse
    /// dynamics are added (refreshed every `time_step`).
    Servo {
        /// Desired values, one per DOF.
        q: &'a [f64],
        /// Desired velocities.
        qd: &'a [f64],
        /// Gains.
        gains: Gains,
        /// Add the inverse-dynamics gravity and velocity torques.
        gravity_compensation: bool,
    },
    /// Closed-loop tracking (fig. 3-4): every `time_step`, inverse dynamics of the desired
    /// acceleration corrected by the errors, `q̈_d + kp (q_d − q) + kd (q̇_d − q̇)`, gives
    /// the torques held until the next refresh.
    Track {
        /// Desired values.
        q: &'a [f64],
        /// Desired velocities.
        qd: &'a [f64],
        /// Desired accelerations.
        qdd: &'a [f64],
        /// Gains.
        gains: Gains,
    },
}

/// The shortest integration step (s) accepted: shorter ones make a tick take seconds
/// (1e-5 s already costs about 5 s of CPU per simulated second for one actor) and
/// `1e-9` would never end it.
pub const MIN_SMALL_TIME_STEP: f64 = 1e-5;

/// Simulation parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimParams {
    /// Integration step (s).
    pub small_time_step: f64,
    /// Control period (s): inverse dynamics is evaluated this often.
    pub time_step: f64,
    /// Gravity (m/s²).
    pub gravity: DVec3,
    /// The floor, if any.
    pub floor: Option<ContactParams>,
    /// Whether the joint limits push back.
    pub joint_limits: bool,
    /// Natural frequency (rad/s) of the limit springs, per unit inertia.
    pub limit_frequency: f64,
    /// Passive joint damping per unit inertia (1/s) on every dynamic non-root DOF.
    pub damping: f64,
    /// A DOF or base speed above this (rad/s or m/s) means the simulation diverged.
    pub max_speed: f64,
}

impl Default for SimParams {
    fn default() -> Self {
        SimParams {
            small_time_step: 1e-3,
            time_step: 1e-2,
            gravity: GRAVITY,
            floor: Some(ContactParams::default()),
            joint_limits: true,
            limit_frequency: 60.0,
            damping: 0.0,
            max_speed: 200.0,
        }
    }
}

impl SimParams {
    /// Checks every field.
    pub fn validate(&self) -> Result<()> {
        let positive = |what: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::invalid_value(what, v, "a finite number > 0"))
            }
        };
        positive("small_time_step", self.small_time_step)?;
        if self.small_time_step < MIN_SMALL_TIME_STEP {
            return Err(Error::invalid_value(
                "small_time_step",
                self.small_time_step,
                "at least 1e-5 s (10 µs: a tick of 10 ms then takes 1,000 sub-steps)",
            ));
        }
        positive("time_step", self.time_step)?;
        if self.small_time_step > self.time_step {
            return Err(Error::invalid_value(
                "small_time_step",
                self.small_time_step,
                format!(
                    "at most time_step ({} s): the integration steps divide each control period",
                    self.time_step
                ),
            ));
        }
        positive("limit_frequency", self.limit_frequency)?;
        positive("max_speed", self.max_speed)?;
        if !(self.damping.is_finite() && self.damping >= 0.0) {
            return Err(Error::invalid_value("damping", self.damping, "≥ 0"));
        }
        if !self.gravity.is_finite() {
            return Err(Error::Invalid("gravity must be finite".into()));
        }
        if let Some(f) = &self.floor {
            f.validate()?;
        }
        Ok(())
    }
}

/// A push: a force at the whole body's centre of mass and a torque, for a while (the
/// thesis's supporting force, fig. 3-5).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Push {
    force: DVec3,
    torque: DVec3,
    until: f64,
}

/// One actor's body simulated by forward dynamics (see the module docs).
#[derive(Clone, Debug)]
pub struct Simulation {
    model: Model,
    data: Data,
    params: SimParams,
    floor: Option<Floor>,
    names: Vec<String>,
    limits: Vec<(f64, f64)>,
    q: Vec<f64>,
    qd: Vec<f64>,
    qdd: Vec<f64>,
    tau: Vec<f64>,
    implicit: Vec<f64>,
    /// The joint forces averaged over the last `advance`.
    tau_mean: Vec<f64>,
    /// Fixed-point passes of each implicit stage since the start.
    passes: [u64; 2],
    /// Steps whose fixed point of each implicit stage ran out of passes.
    unconverged: [u64; 2],
    /// Generalized momenta of the dynamic DOFs (workspace of the step).
    momenta: Vec<f64>,
    /// Right-hand side and solution of the step's velocity solve.
    rhs: Vec<f64>,
    x: Vec<f64>,
    /// The state at the step's start, restored when the step fails.
    q_prev: Vec<f64>,
    qd_prev: Vec<f64>,
    /// The implicit stages' solver; its iterate is the base velocity (ω, v), then the
    /// joint velocities.
    fixed_point: FixedPoint,
    /// The half-step velocities at the step's start posture (same layout as the iterate).
    xa: Vec<f64>,
    held: Vec<f64>,
    prescribed: Vec<bool>,
    base: Option<FloatingBase>,
    ext: ExternalForces,
    push: Option<Push>,
    push_link: usize,
    time: f64,
    since_control: f64,
    control_due: bool,
    deepest: f64,
}

impl Simulation {
    /// A simulation of `skeleton` from state (`q`, `qd`) in which the DOFs with
    /// `dynamic[k]` are integrated and the others prescribed. The root is a floating base
    /// when all its DOFs are dynamic and it is the humanoid root; a root that is only
    /// partly dynamic is prescribed whole.
    pub fn new(
        skeleton: &Skeleton,
        q: &[f64],
        qd: &[f64],
        dynamic: &[bool],
        params: SimParams,
    ) -> Result<Simulation> {
        params.validate()?;
        super::check_state(skeleton, "q", q)?;
        super::check_state(skeleton, "qd", qd)?;
        let model = Model::new(skeleton)?;
        if dynamic.len() != model.n {
            return Err(Error::Invalid(
                "dynamics: dynamic mask has the wrong size".into(),
            ));
        }
        let floor = match params.floor {
            Some(p) => Some(Floor::new(&model, skeleton, p)?),
            None => None,
        };
        let mut prescribed: Vec<bool> = dynamic.iter().map(|d| !d).collect();
        let root = model.root.clone();
        let root_dynamic = root.clone().all(|k| dynamic[k]);
        if !root_dynamic {
            prescribed[root.clone()].iter_mut().for_each(|p| *p = true);
        }
        let floating = root_dynamic && model.floating;
        let push_link = model
            .bodies
            .iter()
            .max_by(|a, b| a.mass.total_cmp(&b.mass))
            .map_or(0, |b| b.link);
        let mut sim = Simulation {
            data: Data::new(&model),
            params,
            floor,
            names: skeleton.dofs().iter().map(|d| d.name.clone()).collect(),
            limits: skeleton.limits().to_vec(),
            q: q.to_vec(),
            qd: qd.to_vec(),
            qdd: vec![0.0; model.n],
            tau: vec![0.0; model.n],
            implicit: vec![0.0; model.n],
            tau_mean: vec![0.0; model.n],
            passes: [0; 2],
            unconverged: [0; 2],
            momenta: vec![0.0; model.n],
            rhs: vec![0.0; model.n],
            x: vec![0.0; model.n],
            q_prev: vec![0.0; model.n],
            qd_prev: vec![0.0; model.n],
            fixed_point: FixedPoint::new(model.n + 6),
            xa: vec![0.0; model.n + 6],
            held: vec![0.0; model.n],
            prescribed,
            base: None,
            ext: ExternalForces::new(skeleton),
            push: None,
            push_link,
            time: 0.0,
            since_control: 0.0,
            control_due: true,
            deepest: 0.0,
            model,
        };
        if floating {
            model::kinematics(&sim.model, &mut sim.data, &sim.q, None);
            let b = root.end - 1;
            let mut velocity = Motion::ZERO;
            for k in root {
                velocity += sim.data.s[k] * sim.qd[k];
            }
            sim.base = Some(FloatingBase {
                position: sim.data.pos[b],
                rotation: sim.data.rot[b],
                velocity,
            });
        }
        Ok(sim)
    }

    /// The model simulated.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// DOF values (root Euler DOFs included).
    pub fn q(&self) -> &[f64] {
        &self.q
    }

    /// DOF velocities (root Euler rates included; zero at the Euler singularity).
    pub fn qd(&self) -> &[f64] {
        &self.qd
    }

    /// Simulated time (s).
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Whether the root is integrated as a floating base.
    pub fn floating(&self) -> bool {
        self.base.is_some()
    }

    /// Whether DOF `k` is prescribed (moved kinematically).
    pub fn is_prescribed(&self, k: usize) -> bool {
        self.prescribed[k]
    }

    /// Sets a prescribed DOF's value and velocity (ignored for dynamic DOFs).
    pub fn set_prescribed(&mut self, k: usize, q: f64, qd: f64) {
        if self.prescribed[k] && q.is_finite() && qd.is_finite() {
            self.q[k] = q;
            self.qd[k] = qd;
        }
    }

    /// Persistent external forces (cleared only by the caller).
    pub fn external_forces_mut(&mut self) -> &mut ExternalForces {
        &mut self.ext
    }

    /// Applies `force` at the whole body's centre of mass and `torque` to it for
    /// `duration` seconds from now.
    pub fn push(&mut self, force: DVec3, torque: DVec3, duration: f64) {
        self.push = Some(Push {
            force,
            torque,
            until: self.time + duration,
        });
    }

    /// The deepest floor penetration seen at the last step (m).
    pub fn penetration(&self) -> f64 {
        self.deepest
    }

    /// The joint forces applied at the last sub-step (N·m or N per DOF): control (servo,
    /// track) plus passive joint damping and limit springs; 0 for prescribed DOFs and a
    /// floating root.
    pub fn torques(&self) -> &[f64] {
        &self.tau
    }

    /// Fixed-point passes taken so far by the velocity stage and by the posture stage of
    /// the steps (each pass costs about one articulated-body solve; the posture stage's
    /// also a kinematics pass and a factorization): a measure of the integrator's cost.
    pub fn passes(&self) -> [u64; 2] {
        self.passes
    }

    /// Steps so far whose velocity stage and whose posture stage stopped at the most
    /// passes (60) without converging. Such a step is not refused: it goes on from the
    /// last pass, with an error larger than the integrator's, which a count that grows
    /// with time makes visible (a `small_time_step` too long for a fast spin or a stiff
    /// servo).
    pub fn unconverged_steps(&self) -> [u64; 2] {
        self.unconverged
    }

    /// The same joint forces averaged over the last [`Simulation::advance`] (their
    /// impulse divided by its duration): what a tick applied, for recording (fig. 3-9).
    pub fn mean_torques(&self) -> &[f64] {
        &self.tau_mean
    }

    fn prepare(&mut self) {
        let base = self.base;
        model::kinematics(&self.model, &mut self.data, &self.q, base.as_ref());
        model::velocities(&self.model, &mut self.data, &self.qd, base.as_ref());
    }

    /// Kinetic and potential energy (J) of the current state.
    pub fn energy(&mut self) -> (f64, f64) {
        self.prepare();
        (
            model::kinetic_energy(&self.model, &self.data, &self.qd_for_energy()),
            model::potential_energy(&self.model, &self.data, self.params.gravity),
        )
    }

    fn qd_for_energy(&self) -> Vec<f64> {
        let mut qd = self.qd.clone();
        if self.base.is_some() {
            for k in self.model.root.clone() {
                qd[k] = 0.0; // the root's armature is zero anyway
            }
        }
        qd
    }

    /// Linear momentum and angular momentum about the world origin of the current state.
    pub fn momentum(&mut self) -> (DVec3, DVec3) {
        self.prepare();
        let h = model::momentum(&self.model, &self.data);
        (h.f, h.n)
    }

    /// The whole body's centre of mass.
    pub fn center_of_mass(&mut self) -> DVec3 {
        self.prepare();
        model::center_of_mass(&self.model, &self.data)
    }

    /// Advances by `duration` seconds in sub-steps of at most `small_time_step` under
    /// `control`. Fails (leaving the state as it was at the failing step's start) when the
    /// simulation diverges or the control's vectors are malformed.
    pub fn advance(&mut self, duration: f64, control: &Control) -> Result<()> {
        if !(duration.is_finite() && duration >= 0.0) {
            return Err(Error::invalid_value("duration", duration, "≥ 0"));
        }
        self.check_control(control)?;
        let steps = (duration / self.params.small_time_step).ceil().max(1.0) as usize;
        let h = duration / steps as f64;
        if h == 0.0 {
            return Ok(());
        }
        let start_time = self.time;
        self.tau_mean.iter_mut().for_each(|t| *t = 0.0);
        for i in 0..steps {
            let elapsed = i as f64 * h;
            self.step(h, control, elapsed)?;
            for (m, t) in self.tau_mean.iter_mut().zip(&self.tau) {
                *m += t / steps as f64;
            }
        }
        self.time = start_time + duration;
        Ok(())
    }

    fn check_control(&self, control: &Control) -> Result<()> {
        let (vectors, gains): (Vec<(&str, &[f64])>, Option<Gains>) = match control {
            Control::Passive => (vec![], None),
            Control::Servo { q, qd, gains, .. } => (vec![("q", q), ("qd", qd)], Some(*gains)),
            Control::Track { q, qd, qdd, gains } => {
                (vec![("q", q), ("qd", qd), ("qdd", qdd)], Some(*gains))
            }
        };
        for (what, v) in vectors {
            if v.len() != self.model.n {
                return Err(Error::Invalid(format!(
                    "dynamics: desired {what} has the wrong size"
                )));
            }
            if let Some(k) = v.iter().position(|x| !x.is_finite()) {
                return Err(Error::invalid_value(
                    format!("desired {what}[{}]", self.names[k]),
                    v[k],
                    "a finite number",
                ));
            }
        }
        if let Some(g) = gains {
            g.validate()?;
        }
        Ok(())
    }

    /// One Störmer–Verlet step of `h` seconds; `elapsed` is the time since the desired
    /// values were sampled (desired values advance at the desired velocities). A step
    /// that fails leaves the state as it was at its start.
    ///
    /// The scheme, in momentum form (generalized leapfrog, Hairer, Lubich & Wanner,
    /// "Geometric Numerical Integration", VI.3; see the module docs). With p = ∂T/∂q̇ the
    /// generalized momenta (the whole body's spatial momentum for a floating base) and
    /// F(q, q̇) = ∂L/∂q + Q_ext their rate without the joint forces:
    ///   p½ = p + h/2 (τ + F(q, q̇½)),            q̇½ = M(q)⁻¹ p½      (implicit in q̇½)
    ///   q⁺ = q + h/2 (q̇½ + M(q⁺)⁻¹ p½)                              (implicit in q⁺)
    ///   p⁺ = p½ + h/2 (τ + F(q⁺, M(q⁺)⁻¹ p½)),   q̇⁺ = M(q⁺)⁻¹ p⁺.
    /// Symplectic and second order: energy oscillates instead of drifting. Both implicit
    /// equations are fixed points solved with Anderson acceleration, each pass an O(n)
    /// momentum sweep and an articulated-body solve. The per-DOF springs and dampers
    /// (servo, limits, damping) keep their linearly implicit first-order treatment (`D`,
    /// added to the mass matrix in the first half).
    fn step(&mut self, h: f64, control: &Control, elapsed: f64) -> Result<()> {
        self.q_prev.copy_from_slice(&self.q);
        self.qd_prev.copy_from_slice(&self.qd);
        let base_at_start = self.base;
        let outcome = self.integrate(h, control, elapsed);
        if outcome.is_err() {
            self.q.copy_from_slice(&self.q_prev);
            self.qd.copy_from_slice(&self.qd_prev);
            self.base = base_at_start;
        }
        outcome
    }

    /// The stages of [`Simulation::step`], in order.
    fn integrate(&mut self, h: f64, control: &Control, elapsed: f64) -> Result<()> {
        self.prepare();
        self.refresh_control(control, h);
        self.load_external(false);
        self.joint_forces(control, h, elapsed);
        let frame = self.enter_moving_frame();
        let start = self.start_momenta(frame, h);
        let half_velocity = self.first_kick(&start)?;
        let (drift_velocity, candidate) = self
            .drift(&start, half_velocity)
            .ok_or_else(|| self.singular())?;
        let (velocity, end_momentum) = self
            .second_kick(&start, drift_velocity, candidate)
            .ok_or_else(|| self.singular())?;
        self.finish_step(&start, velocity, candidate, end_momentum)
    }

    /// The inverse-dynamics box of the control loop (thesis 3.5, fig. 3-4): every
    /// `time_step`, the mass diagonal that scales the servo gains and the torques held
    /// until the next refresh (gravity compensation for the servos, inverse dynamics of
    /// the corrected desired acceleration for tracking).
    fn refresh_control(&mut self, control: &Control, h: f64) {
        let n = self.model.n;
        let base = self.base;
        if self.control_due {
            model::mass_diagonal(&self.model, &mut self.data, base.as_ref());
            match control {
                Control::Passive => self.held.iter_mut().for_each(|t| *t = 0.0),
                Control::Servo {
                    gravity_compensation,
                    ..
                } => {
                    if *gravity_compensation {
                        self.data.ext.iter_mut().for_each(|f| *f = Force::ZERO);
                        // Inverse dynamics at zero acceleration, in the accelerations'
                        // buffer borrowed for the call.
                        let mut zero = std::mem::take(&mut self.qdd);
                        zero.iter_mut().for_each(|a| *a = 0.0);
                        rnea(
                            &self.model,
                            &mut self.data,
                            &zero,
                            self.params.gravity,
                            base.as_ref().map(|b| (b, Motion::ZERO)),
                            &mut self.held,
                        );
                        self.qdd = zero;
                    } else {
                        self.held.iter_mut().for_each(|t| *t = 0.0);
                    }
                }
                Control::Track { q, qd, qdd, gains } => {
                    self.load_external(true);
                    let mut reference = std::mem::take(&mut self.qdd);
                    for k in 0..n {
                        reference[k] = if self.prescribed[k] {
                            0.0
                        } else {
                            qdd[k] + gains.kp * (q[k] - self.q[k]) + gains.kd * (qd[k] - self.qd[k])
                        };
                    }
                    rnea(
                        &self.model,
                        &mut self.data,
                        &reference,
                        self.params.gravity,
                        base.as_ref().map(|b| (b, Motion::ZERO)),
                        &mut self.held,
                    );
                    self.qdd = reference;
                }
            }
            // rnea overwrote the accelerations' workspace only; velocities are intact.
            self.control_due = false;
        }
        self.since_control += h;
        if self.since_control >= self.params.time_step - 1e-12 {
            self.since_control = 0.0;
            self.control_due = true;
        }
    }

    /// The joint forces τ that enter the forward dynamics (thesis 3.4's input torques):
    /// the held control torques, the PD servos (eq. 4-1), passive damping and the
    /// joint-limit springs. Their stiffness k and
    /// damping c are integrated implicitly (h·c + h²·k is added to the DOF's inertia in
    /// the forward dynamics), so stiff gains stay stable.
    fn joint_forces(&mut self, control: &Control, h: f64, elapsed: f64) {
        let n = self.model.n;
        let root = self.model.root.clone();
        let floating = self.base.is_some();
        let diag = &self.data.diag;
        for k in 0..n {
            self.implicit[k] = 0.0;
            if self.prescribed[k] || (floating && root.contains(&k)) {
                self.tau[k] = 0.0;
                continue;
            }
            let (mut t, mut stiff, mut damp) = (self.held[k], 0.0, 0.0);
            if let Control::Servo { q, qd, gains, .. } = control {
                let target = q[k] + qd[k] * elapsed;
                t += diag[k] * (gains.kp * (target - self.q[k]) + gains.kd * (qd[k] - self.qd[k]));
                stiff += diag[k] * gains.kp;
                damp += diag[k] * gains.kd;
            }
            if !root.contains(&k) {
                t -= self.params.damping * diag[k] * self.qd[k];
                damp += self.params.damping * diag[k];
                if self.params.joint_limits {
                    let (lt, ls, ld) = self.limit_torque(k, diag[k]);
                    t += lt;
                    stiff += ls;
                    damp += ld;
                }
            }
            self.tau[k] = t;
            self.implicit[k] = h * damp + h * h * stiff;
        }
    }

    /// Not in the thesis (its root is not a floating base): the inertial frame a floating
    /// base is stepped in. At the step's start it has its
    /// origin at the base and moves with the centre of mass. World Plücker coordinates
    /// far from the origin or at a high falling speed would otherwise make the
    /// discretisation error grow with them (it is not Galilean invariant), and in it the
    /// body's linear momentum is nil at the step's start (see [`Simulation::finish_step`]).
    /// Moves the external wrenches and the link frames into it.
    fn enter_moving_frame(&mut self) -> MovingFrame {
        let Some(b) = self.base else {
            return MovingFrame {
                base: None,
                shift: DVec3::ZERO,
                carry: DVec3::ZERO,
            };
        };
        let shift = b.position;
        let carry = model::momentum(&self.model, &self.data).f / self.model.total_mass;
        let base = Some(FloatingBase {
            position: DVec3::ZERO,
            rotation: b.rotation,
            velocity: Motion::new(
                b.velocity.w,
                b.velocity.v + b.velocity.w.cross(b.position) - carry,
            ),
        });
        for f in &mut self.data.ext {
            f.n -= shift.cross(f.f);
        }
        model::kinematics(&self.model, &mut self.data, &self.q, base.as_ref());
        model::velocities(&self.model, &mut self.data, &self.qd, base.as_ref());
        MovingFrame { base, shift, carry }
    }

    /// The state thesis 3.4's integration starts from, in momentum form: the generalized
    /// momenta p = ∂T/∂q̇ of the dynamic DOFs at the step's start, and the
    /// base's row (the whole body's spatial momentum) after its first half kick, which
    /// only the impulse of gravity and external forces changes (world axes, about the
    /// origin: no velocity-product term).
    fn start_momenta(&mut self, frame: MovingFrame, h: f64) -> StepStart {
        let n = self.model.n;
        let root = self.model.root.clone();
        let start_com = model::center_of_mass(&self.model, &self.data);
        model::subtree_wrenches(&self.model, &mut self.data, self.params.gravity);
        model::subtree_momenta(&self.model, &mut self.data);
        let first = if frame.base.is_some() { root.end } else { 0 };
        for k in first..n {
            if !self.prescribed[k] {
                self.momenta[k] =
                    model::generalized_momentum(&self.model, &self.data, k, self.qd[k]);
            }
        }
        let base_link = root.end.max(1) - 1;
        StepStart {
            h,
            frame,
            first,
            base_link,
            start_com,
            start_momentum_linear: self.data.f[base_link].f,
            base_half: self.data.f[base_link] + self.data.w[base_link] * (0.5 * h),
        }
    }

    /// The first half of thesis 3.4's time integration, a kick implicit in the half-step
    /// velocities (each pass a forward-dynamics solve, Appendix A):
    /// p½ = p + h/2 (τ + F(q, q̇½)), q̇½ = M(q)⁻¹ p½. The unknowns (base velocity ω, v;
    /// joint velocities) are iterated with Anderson acceleration (see `anderson`): the
    /// plain iteration diverges on the near-null modes of massless links. Leaves p½ in
    /// `momenta` and q̇½ in `x`, and returns the base's half-step velocity.
    fn first_kick(&mut self, s: &StepStart) -> Result<Motion> {
        let n = self.model.n;
        let h = s.h;
        let base = s.frame.base;
        if aba::factor(
            &self.model,
            &mut self.data,
            Some(&self.prescribed),
            Some(&self.implicit),
            base.as_ref(),
        )
        .is_none()
        {
            return Err(self.singular());
        }
        let mut base_velocity = base.map_or(Motion::ZERO, |b| b.velocity);
        put_motion(&mut self.fixed_point.z, base_velocity);
        self.fixed_point.z[6..].copy_from_slice(&self.qd);
        let outcome = self.fixed_point.solve(&mut self.passes[0], |z, image| {
            self.x.copy_from_slice(&z[6..]);
            let iterate = base.map(|mut b| {
                b.velocity = get_motion(z);
                b
            });
            model::velocities(&self.model, &mut self.data, &self.x, iterate.as_ref());
            model::subtree_momenta(&self.model, &mut self.data);
            for k in s.first..n {
                if !self.prescribed[k] {
                    self.rhs[k] = self.momenta[k]
                        + 0.5 * h * (self.held[k] + model::momentum_rate(&self.data, k))
                        + h * (self.tau[k] - self.held[k])
                        + self.implicit[k] * self.qd[k];
                }
            }
            let Some(v) = aba::solve(
                &self.model,
                &mut self.data,
                &self.rhs,
                Some(&self.prescribed),
                base.as_ref().map(|b| (b, s.base_half)),
                &mut self.x,
            ) else {
                return false;
            };
            base_velocity = v;
            put_motion(image, v);
            image[6..].copy_from_slice(&self.x);
            true
        });
        if !self.settled(0, outcome) {
            return Err(self.singular());
        }
        for k in s.first..n {
            if !self.prescribed[k] {
                self.momenta[k] = self.rhs[k] - self.implicit[k] * self.x[k];
            }
        }
        Ok(base_velocity)
    }

    /// The posture update of thesis 3.4's time integration, a drift implicit in the
    /// posture: q⁺ = q + h/2 (q̇½(q) + q̇½(q⁺)) with
    /// q̇½(q) = M(q)⁻¹ p½; the unknown is q̇½(q⁺) (base velocity, joint velocities),
    /// iterated with Anderson acceleration. Leaves q⁺ in `q`, the mass matrix factored
    /// at q⁺ in `data` and q̇½(q⁺) in `x`; returns the base's velocity and pose at q⁺,
    /// or `None` when a DOF lost all its inertia.
    fn drift(
        &mut self,
        s: &StepStart,
        half_velocity: Motion,
    ) -> Option<(Motion, Option<FloatingBase>)> {
        let n = self.model.n;
        let h = s.h;
        let base = s.frame.base;
        put_motion(&mut self.xa, half_velocity);
        self.xa[6..].copy_from_slice(&self.x);
        self.fixed_point.z.copy_from_slice(&self.xa);
        let mut candidate = base;
        let mut solved = None;
        let outcome = self.fixed_point.solve(&mut self.passes[1], |z, image| {
            for k in s.first..n {
                self.q[k] = self.q_prev[k] + 0.5 * h * (self.xa[6 + k] + z[6 + k]);
            }
            if let (Some(b0), Some(c)) = (&base, &mut candidate) {
                let (va, vb) = (get_motion(&self.xa), get_motion(z));
                let w = (va.w + vb.w) * 0.5;
                let vp = (va.v + va.w.cross(b0.position) + vb.v + vb.w.cross(c.position)) * 0.5;
                c.position = b0.position + vp * h;
                let angle = w.length() * h;
                c.rotation = if angle > 0.0 {
                    (DQuat::from_axis_angle(w.normalize(), angle) * b0.rotation).normalize()
                } else {
                    b0.rotation
                };
            }
            model::kinematics(&self.model, &mut self.data, &self.q, candidate.as_ref());
            self.x.copy_from_slice(&z[6..]);
            solved = aba::factor(
                &self.model,
                &mut self.data,
                Some(&self.prescribed),
                None,
                candidate.as_ref(),
            )
            .and_then(|_| {
                aba::solve(
                    &self.model,
                    &mut self.data,
                    &self.momenta,
                    Some(&self.prescribed),
                    candidate.as_ref().map(|b| (b, s.base_half)),
                    &mut self.x,
                )
            });
            let Some(v) = solved else { return false };
            put_motion(image, v);
            image[6..].copy_from_slice(&self.x);
            true
        });
        if !self.settled(1, outcome) {
            return None;
        }
        solved.map(|v| (v, candidate))
    }

    /// The second half of thesis 3.4's time integration, a kick at q⁺ (on the mass
    /// matrix the drift factored there):
    /// p⁺ = p½ + h/2 (τ_held + ∂L/∂q(q⁺, q̇½) + Q_ext), then q̇⁺ = M(q⁺)⁻¹ p⁺ into `x`.
    /// Returns the base's velocity and its row of p⁺, or `None` when a DOF lost all its
    /// inertia.
    fn second_kick(
        &mut self,
        s: &StepStart,
        drift_velocity: Motion,
        candidate: Option<FloatingBase>,
    ) -> Option<(Motion, Force)> {
        let n = self.model.n;
        let h = s.h;
        let at = candidate.map(|mut c| {
            c.velocity = drift_velocity;
            c
        });
        model::velocities(&self.model, &mut self.data, &self.x, at.as_ref());
        model::subtree_wrenches(&self.model, &mut self.data, self.params.gravity);
        model::subtree_momenta(&self.model, &mut self.data);
        for k in s.first..n {
            if !self.prescribed[k] {
                self.momenta[k] += 0.5 * h * (self.held[k] + model::momentum_rate(&self.data, k));
            }
        }
        let base_end = s.base_half + self.data.w[s.base_link] * (0.5 * h);
        aba::solve(
            &self.model,
            &mut self.data,
            &self.momenta,
            Some(&self.prescribed),
            at.as_ref().map(|b| (b, base_end)),
            &mut self.x,
        )
        .map(|v| (v, base_end))
    }

    /// The end of thesis 3.4's outbound process, "updating the whole structure": writes
    /// the new velocities and accelerations, takes the floating base back from the moving
    /// frame to the world, updates the root's Euler DOFs and checks the state.
    fn finish_step(
        &mut self,
        s: &StepStart,
        velocity: Motion,
        candidate: Option<FloatingBase>,
        end_momentum: Force,
    ) -> Result<()> {
        let h = s.h;
        for k in s.first..self.model.n {
            if !self.prescribed[k] {
                self.qdd[k] = (self.x[k] - self.qd_prev[k]) / h;
                self.qd[k] = self.x[k];
            } else {
                self.qdd[k] = 0.0;
            }
        }
        if let Some(c) = candidate {
            // The centre of mass moves by exactly the mean momentum over the step
            // (linear in time under constant forces): translating the body by the
            // drift's O(h³) discrepancy keeps the world angular momentum exact when
            // taken back from the moving frame, whose contribution
            // M (c₁ − c₀ − h P̄/M) × u would otherwise accumulate.
            let m = self.model.total_mass;
            let com = model::center_of_mass(&self.model, &self.data);
            let mean = (s.start_momentum_linear + end_momentum.f) * (0.5 * h / m);
            let correction = s.start_com + mean - com;
            // Back to the world frame.
            let MovingFrame { shift, carry, .. } = s.frame;
            let v = velocity;
            let point = v.v + v.w.cross(c.position) + carry;
            let position = c.position + correction + shift + carry * h;
            self.base = Some(FloatingBase {
                position,
                rotation: c.rotation,
                velocity: Motion::new(v.w, point - v.w.cross(position)),
            });
        }
        self.sync_root();
        self.check()
    }

    /// Counts a fixed-point solve of stage `stage` (0 velocity, 1 posture) that ran out of
    /// passes; `false` when it could not be evaluated.
    fn settled(&mut self, stage: usize, outcome: Outcome) -> bool {
        if outcome == Outcome::Unconverged {
            self.unconverged[stage] += 1;
        }
        outcome != Outcome::Failed
    }

    /// Loads the persistent forces, the push and (unless `without_contact`) the floor's
    /// forces into the workspace (after `prepare`).
    fn load_external(&mut self, without_contact: bool) {
        self.ext.load(&self.model, &mut self.data);
        if let Some(p) = self.push {
            if self.time < p.until {
                let com = model::center_of_mass(&self.model, &self.data);
                self.data.ext[self.push_link] += Force::at_point(com, p.force, p.torque);
            } else {
                self.push = None;
            }
        }
        if without_contact {
            return;
        }
        self.deepest = match &self.floor {
            Some(f) => f.apply(&mut self.data),
            None => 0.0,
        };
    }

    /// The limit spring's torque on DOF `k`, with the stiffness and damping in effect.
    fn limit_torque(&self, k: usize, inertia: f64) -> (f64, f64, f64) {
        let (lo, hi) = self.limits[k];
        let w = self.params.limit_frequency;
        let (stiff, damp) = (w * w * inertia, 2.0 * w * inertia);
        let (q, qd) = (self.q[k], self.qd[k]);
        if q < lo && stiff * (lo - q) - damp * qd > 0.0 {
            (stiff * (lo - q) - damp * qd, stiff, damp)
        } else if q > hi && -stiff * (q - hi) - damp * qd < 0.0 {
            (-stiff * (q - hi) - damp * qd, stiff, damp)
        } else {
            (0.0, 0.0, 0.0)
        }
    }

    /// Writes the floating base's pose and velocity back into the root's Euler DOFs.
    fn sync_root(&mut self) {
        let Some(b) = self.base else { return };
        let root = self.model.root.clone();
        let offset = self.model.pre[root.start].map_or(DVec3::ZERO, |t| t.translation);
        let t = b.position - offset;
        let (mut yaw, pitch, roll) = b.rotation.to_euler(EulerRot::YXZ);
        let prev = self.q[root.start + 3];
        yaw += (2.0 * std::f64::consts::PI) * ((prev - yaw) / (2.0 * std::f64::consts::PI)).round();
        let r = root.start;
        self.q[r..r + 6].copy_from_slice(&[t.x, t.y, t.z, yaw, pitch, roll]);
        // Euler rates: ω = a_yaw ẏ + a_pitch ṗ + a_roll ṙ.
        let w = b.velocity.w;
        let vp = b.velocity.v + w.cross(b.position);
        let a_yaw = DVec3::Y;
        let a_pitch = DQuat::from_rotation_y(yaw) * DVec3::X;
        let a_roll = b.rotation * DVec3::Z;
        let m = DMat3::from_cols(a_yaw, a_pitch, a_roll);
        let rates = if m.determinant().abs() > 1e-9 {
            m.inverse() * w
        } else {
            DVec3::ZERO
        };
        self.qd[r..r + 6].copy_from_slice(&[vp.x, vp.y, vp.z, rates.x, rates.y, rates.z]);
    }

    fn check(&self) -> Result<()> {
        let limit = self.params.max_speed;
        for k in 0..self.model.n {
            // A floating root's Euler rates may be large near pitch ±90° while its
            // angular velocity is modest: the base is checked below instead.
            let euler = self.base.is_some() && self.model.root.contains(&k);
            if !self.q[k].is_finite()
                || !self.qd[k].is_finite()
                || (!euler && self.qd[k].abs() > limit)
            {
                return Err(self.diverged(&format!(
                    "DOF `{}` reached q = {}, q̇ = {} (limit {limit})",
                    self.names[k], self.q[k], self.qd[k]
                )));
            }
        }
        if let Some(b) = &self.base {
            let v = b.velocity.v + b.velocity.w.cross(b.position);
            if !b.position.is_finite()
                || !b.rotation.is_finite()
                || v.length() > limit
                || b.velocity.w.length() > limit
            {
                return Err(self.diverged("the root's speed exploded"));
            }
        }
        Ok(())
    }

    fn singular(&self) -> Error {
        self.diverged("a DOF lost all its inertia (singular configuration)")
    }

    fn diverged(&self, what: &str) -> Error {
        Error::Diverged {
            time: self.time,
            what: what.to_string(),
        }
    }
}

/// The inertial frame a floating base's step is taken in (see
/// [`Simulation::enter_moving_frame`]).
#[derive(Clone, Copy, Debug)]
struct MovingFrame {
    /// The floating base seen from the frame, if the root floats.
    base: Option<FloatingBase>,
    /// The frame's origin in the world: the base's position at the step's start.
    shift: DVec3,
    /// The frame's velocity in the world: the centre of mass's at the step's start.
    carry: DVec3,
}

/// What the stages of one step share once its momenta are known.
#[derive(Clone, Copy, Debug)]
struct StepStart {
    /// The step's length (s).
    h: f64,
    frame: MovingFrame,
    /// The first DOF with a row of its own: past the root's when the base floats.
    first: usize,
    /// The link whose subtree momentum is the base's row (the root's last link).
    base_link: usize,
    /// The centre of mass at the step's start, in the moving frame.
    start_com: DVec3,
    /// The whole body's linear momentum at the step's start, in the moving frame.
    start_momentum_linear: DVec3,
    /// The base's row of the momenta after the first half kick.
    base_half: Force,
}

/// Writes a spatial velocity into the first six entries of `z`.
fn put_motion(z: &mut [f64], m: Motion) {
    z[..3].copy_from_slice(&m.w.to_array());
    z[3..6].copy_from_slice(&m.v.to_array());
}

/// Reads a spatial velocity from the first six entries of `z`.
fn get_motion(z: &[f64]) -> Motion {
    Motion::new(DVec3::from_slice(&z[..3]), DVec3::from_slice(&z[3..6]))
}
