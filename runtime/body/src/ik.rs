//! Inverse kinematics (thesis 2.3, eq. 2-1): `Δq = J⁺Δx + (I − J⁺J)Δz`, iterated under the
//! small-movement hypothesis until the end effectors reach their goals.
//!
//! * **Main tasks**: end effectors with a position goal, or a position and orientation
//!   goal. Tasks of equal priority are stacked into one Jacobian; a lower priority level
//!   works in the null space of the higher ones (`Δq_k = Δq_{k−1} + (J_k P_{k−1})⁺(Δx_k −
//!   J_k Δq_{k−1})`, `P_k = P_{k−1} − (J_k P_{k−1})⁺(J_k P_{k−1})`).
//! * **Pseudo-inverse**: SVD ([`crate::linalg::Svd`]); damped least squares near
//!   singularities (`σ/(σ² + λ²)`, with `λ² = λ_max²(1 − (σ_min/ε)²)` when the smallest
//!   singular value falls below `ε`).
//! * **Secondary task** `Δz` (projected on the null space of every main task): joint-limit
//!   avoidance (the gradient of `Σ ((q − mid)/range)²`), an optional reference posture,
//!   and any [`NullSpaceTask`] (self-collision correction, 4.6.2).
//! * **Joint limits**: a step that would cross a limit locks that DOF at the limit and the
//!   step is solved again without it (the clamping loop).
//! * **Small movements**: each iteration moves an effector by at most
//!   [`IkOptions::max_position_step`] / [`IkOptions::max_orientation_step`].
//!
//! Every buffer lives in the [`IkSolver`]; solving allocates nothing once warmed up.

use crate::error::{Error, Result};
use crate::jacobian::{dof_axes, fill_jacobian, rotation_error, DofAxis, Effector};
use crate::kinematics::forward_kinematics;
use crate::linalg::{Mat, Svd};
use crate::skeleton::Skeleton;
use crate::transform::Transform;
use glam::{DQuat, DVec3};

/// The `index`-th element of the van der Corput sequence in base `base` (in [0, 1)).
fn halton(mut index: u64, base: u64) -> f64 {
    let (mut f, mut r) = (1.0, 0.0);
    while index > 0 {
        f /= base as f64;
        r += f * (index % base) as f64;
        index /= base;
    }
    r
}

/// Tuning of the solver.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkOptions {
    /// Most iterations per [`IkSolver::solve`] call.
    pub max_iterations: usize,
    /// A position goal is met within this distance (metres).
    pub position_tolerance: f64,
    /// An orientation goal is met within this angle (radians).
    pub orientation_tolerance: f64,
    /// Largest effector displacement asked of one iteration (metres).
    pub max_position_step: f64,
    /// Largest effector rotation asked of one iteration (radians).
    pub max_orientation_step: f64,
    /// Largest joint motion one priority level may ask of one iteration (radians or
    /// metres); a larger step is scaled down whole.
    pub max_joint_step: f64,
    /// Largest damping factor `λ_max` (damped least squares).
    pub damping: f64,
    /// Constant damping of the priority levels below the first.
    pub lower_level_damping: f64,
    /// Damping starts when the smallest singular value falls below this `ε`.
    pub singular_threshold: f64,
    /// Gain of the joint-limit avoidance secondary task (0 disables it).
    pub limit_avoidance: f64,
    /// Gain pulling toward the reference posture, when one is given (0 disables it).
    pub posture_gain: f64,
    /// Most iterations spent on a still-active null-space task (self-collision) once the
    /// goals are met; `usize::MAX` runs it until it is inactive or `max_iterations`. A
    /// tracking caller that solves again next tick needs only a few.
    pub settle_iterations: usize,
}

impl Default for IkOptions {
    fn default() -> Self {
        IkOptions {
            max_iterations: 200,
            position_tolerance: 1e-5,
            orientation_tolerance: 1e-4,
            max_position_step: 0.08,
            max_orientation_step: 0.3,
            max_joint_step: 0.3,
            damping: 0.02,
            lower_level_damping: 0.3,
            singular_threshold: 0.03,
            limit_avoidance: 0.02,
            posture_gain: 0.0,
            settle_iterations: usize::MAX,
        }
    }
}

impl IkOptions {
    /// Checks that every value is finite and in range.
    pub fn validate(&self) -> Result<()> {
        for (what, v) in [
            ("position_tolerance", self.position_tolerance),
            ("orientation_tolerance", self.orientation_tolerance),
            ("max_position_step", self.max_position_step),
            ("max_orientation_step", self.max_orientation_step),
            ("max_joint_step", self.max_joint_step),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid_value(what, v, "a finite number > 0"));
            }
        }
        for (what, v) in [
            ("damping", self.damping),
            ("lower_level_damping", self.lower_level_damping),
            ("singular_threshold", self.singular_threshold),
            ("limit_avoidance", self.limit_avoidance),
            ("posture_gain", self.posture_gain),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid_value(what, v, "a finite number ≥ 0"));
            }
        }
        Ok(())
    }
}

/// What an end effector should reach.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Goal {
    /// World position of the effector point.
    pub position: DVec3,
    /// World orientation of the effector's joint frame, if asked.
    pub orientation: Option<DQuat>,
}

/// One main task: an effector, its goal and its priority (0 is the highest).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkTask {
    /// The point that moves.
    pub effector: Effector,
    /// Where it should go.
    pub goal: Goal,
    /// Priority level: smaller numbers win; equal numbers are solved together.
    pub priority: u32,
}

impl IkTask {
    /// A position-only task of the highest priority.
    pub fn position(effector: Effector, position: DVec3) -> IkTask {
        IkTask {
            effector,
            goal: Goal {
                position,
                orientation: None,
            },
            priority: 0,
        }
    }

    fn rows(&self) -> usize {
        if self.goal.orientation.is_some() {
            6
        } else {
            3
        }
    }
}

/// How a solve ended.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IkReport {
    /// Iterations done.
    pub iterations: usize,
    /// Whether every task met its tolerances (and no null-space task was still active).
    pub converged: bool,
    /// The largest remaining position error over the tasks (metres).
    pub position_error: f64,
    /// The largest remaining orientation error over the tasks (radians).
    pub orientation_error: f64,
}

/// What a secondary task sees: the posture being solved.
pub struct NullSpaceContext<'a> {
    /// The skeleton.
    pub skeleton: &'a Skeleton,
    /// The current posture (every DOF).
    pub q: &'a [f64],
    /// Its joint globals.
    pub globals: &'a [Transform],
    /// The DOFs the solver moves (the columns).
    pub dofs: &'a [usize],
    /// Their world axes.
    pub axes: &'a [DofAxis],
}

/// A secondary task: a joint-space step `Δz` that the solver projects on the null space of
/// the main tasks (eq. 2-1).
pub trait NullSpaceTask {
    /// Adds this task's step to `dz` (indexed like `ctx.dofs`); returns whether the task
    /// still has work to do (the solve does not count as converged while it has).
    fn add_step(&mut self, ctx: &NullSpaceContext, dz: &mut [f64]) -> bool;
}

/// An IK solver over a fixed set of DOFs, with its workspaces.
#[derive(Clone, Debug)]
pub struct IkSolver {
    dofs: Vec<usize>,
    options: IkOptions,
    globals: Vec<Transform>,
    axes: Vec<DofAxis>,
    j: Mat,
    jp: Mat,
    p: Mat,
    svd: Svd,
    dx: Vec<f64>,
    dq: Vec<f64>,
    dz: Vec<f64>,
    jdq: Vec<f64>,
    zproj: Vec<f64>,
    step_buf: Vec<f64>,
    locked: Vec<bool>,
    lock_step: Vec<f64>,
    levels: Vec<u32>,
    best: Vec<f64>,
}

impl IkSolver {
    /// A solver moving `dofs` (DOF indices of `skeleton`; duplicates are dropped).
    pub fn new(skeleton: &Skeleton, mut dofs: Vec<usize>, options: IkOptions) -> Result<Self> {
        options.validate()?;
        dofs.sort_unstable();
        dofs.dedup();
        if let Some(&d) = dofs.iter().find(|&&d| d >= skeleton.dof_count()) {
            return Err(Error::Invalid(format!(
                "ik: no DOF {d} in `{}`",
                skeleton.name()
            )));
        }
        if dofs.is_empty() {
            return Err(Error::Invalid("ik: no DOF to move".into()));
        }
        let n = dofs.len();
        Ok(IkSolver {
            options,
            globals: vec![Transform::IDENTITY; skeleton.joints().len()],
            axes: Vec::with_capacity(n),
            j: Mat::zeros(6, n),
            jp: Mat::zeros(6, n),
            p: Mat::zeros(n, n),
            svd: Svd::default(),
            dx: Vec::with_capacity(12),
            dq: vec![0.0; n],
            dz: vec![0.0; n],
            jdq: Vec::with_capacity(12),
            zproj: Vec::with_capacity(n),
            step_buf: Vec::with_capacity(n),
            locked: vec![false; n],
            lock_step: vec![0.0; n],
            levels: Vec::new(),
            best: Vec::new(),
            dofs,
        })
    }

    /// The DOFs the solver moves, in index order.
    pub fn dofs(&self) -> &[usize] {
        &self.dofs
    }

    /// The options.
    pub fn options(&self) -> &IkOptions {
        &self.options
    }

    /// Changes the options.
    pub fn set_options(&mut self, options: IkOptions) -> Result<()> {
        options.validate()?;
        self.options = options;
        Ok(())
    }

    /// The joint globals of the last posture the solver evaluated.
    pub fn globals(&self) -> &[Transform] {
        &self.globals
    }

    /// Checks a task list against the skeleton: known joints, finite goals.
    pub fn check_tasks(skeleton: &Skeleton, tasks: &[IkTask]) -> Result<()> {
        for t in tasks {
            if t.effector.joint >= skeleton.joints().len() {
                return Err(Error::Invalid(format!(
                    "ik: no joint {} in `{}`",
                    t.effector.joint,
                    skeleton.name()
                )));
            }
            if !t.effector.point.is_finite() || !t.goal.position.is_finite() {
                return Err(Error::Invalid(format!(
                    "ik: the goal of `{}` is not a finite position",
                    skeleton.joints()[t.effector.joint].name
                )));
            }
            if let Some(r) = t.goal.orientation {
                if !r.is_finite() || (r.length() - 1.0).abs() > 1e-6 {
                    return Err(Error::Invalid(format!(
                        "ik: the orientation goal of `{}` is not a unit quaternion",
                        skeleton.joints()[t.effector.joint].name
                    )));
                }
            }
        }
        Ok(())
    }

    /// Moves the solver's DOFs of `q` (a full posture, modified in place) until every
    /// task meets its tolerances, progress stalls, or `max_iterations` is reached.
    /// `reference` (a full posture) is pulled toward with `posture_gain`; `extra` adds
    /// its own secondary task.
    pub fn solve(
        &mut self,
        skeleton: &Skeleton,
        q: &mut [f64],
        tasks: &[IkTask],
        reference: Option<&[f64]>,
        mut extra: Option<&mut dyn NullSpaceTask>,
    ) -> Result<IkReport> {
        if q.len() != skeleton.dof_count() || self.globals.len() != skeleton.joints().len() {
            return Err(Error::Invalid(format!(
                "ik: posture has {} values, `{}` has {} DOFs",
                q.len(),
                skeleton.name(),
                skeleton.dof_count()
            )));
        }
        if reference.is_some_and(|r| r.len() != q.len()) {
            return Err(Error::Invalid(
                "ik: the reference posture has the wrong size".into(),
            ));
        }
        if q.iter().any(|v| !v.is_finite()) {
            return Err(Error::Invalid("ik: the posture is not finite".into()));
        }
        Self::check_tasks(skeleton, tasks)?;
        let mut report = IkReport::default();
        self.best.clear();
        self.best.resize(tasks.len(), f64::INFINITY);
        let mut stalled = 0;
        let mut settling = 0;
        loop {
            forward_kinematics(skeleton, q, &mut self.globals);
            let (pe, oe) = self.errors(tasks);
            report.position_error = pe;
            report.orientation_error = oe;
            let met =
                pe <= self.options.position_tolerance && oe <= self.options.orientation_tolerance;
            if report.iterations >= self.options.max_iterations {
                report.converged = met;
                break;
            }
            dof_axes(skeleton, q, &self.globals, &self.dofs, &mut self.axes);
            let active = match extra.as_mut() {
                Some(e) => self.secondary(skeleton, q, reference, Some(&mut **e)),
                None => self.secondary(skeleton, q, reference, None),
            };
            if met && !active {
                report.converged = true;
                break;
            }
            if met {
                if settling >= self.options.settle_iterations {
                    report.converged = true;
                    break;
                }
                settling += 1;
            }
            // Progress check: some task's error (1 rad counted as 0.1 m) still shrinks.
            let mut progress = false;
            for (t, best) in tasks.iter().zip(self.best.iter_mut()) {
                let mut e = (t.goal.position - t.effector.position(&self.globals)).length();
                if let Some(r) = t.goal.orientation {
                    e += 0.1 * rotation_error(t.effector.rotation(&self.globals), r).length();
                }
                if e < *best * (1.0 - 1e-3) {
                    *best = e;
                    progress = true;
                }
            }
            if progress {
                stalled = 0;
            } else {
                stalled += 1;
                if stalled > 30 && !active {
                    break;
                }
            }
            self.step(skeleton, q, tasks);
            report.iterations += 1;
        }
        Ok(report)
    }

    /// Like [`IkSolver::solve`] (without a reference posture or extra task), but when the
    /// local solve from `q` does not converge it starts again from up to `restarts`
    /// deterministic postures (quasi-random within the limits, Halton sequence) and keeps
    /// the best result: the local method's escape from joint-limit local minima.
    pub fn solve_with_restarts(
        &mut self,
        skeleton: &Skeleton,
        q: &mut [f64],
        tasks: &[IkTask],
        restarts: usize,
    ) -> Result<IkReport> {
        let mut best_q = q.to_vec();
        let mut best = self.solve(skeleton, &mut best_q, tasks, None, None)?;
        let mut total = best.iterations;
        let mut trial = q.to_vec();
        const PRIMES: [u64; 12] = [2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37];
        for k in 1..=restarts {
            if best.converged {
                break;
            }
            trial.copy_from_slice(q);
            for (c, &d) in self.dofs.iter().enumerate() {
                let dof = &skeleton.dofs()[d];
                let (lo, hi) = if dof.min.is_finite() && dof.max.is_finite() {
                    (dof.min, dof.max)
                } else {
                    continue;
                };
                let u = halton(k as u64, PRIMES[c % PRIMES.len()]);
                // Stay clear of the limits: sample the middle 80 % of the range.
                trial[d] = lo + (hi - lo) * (0.1 + 0.8 * u);
            }
            let r = self.solve(skeleton, &mut trial, tasks, None, None)?;
            total += r.iterations;
            let score = |r: &IkReport| r.position_error + 0.1 * r.orientation_error;
            if r.converged || score(&r) < score(&best) {
                best = r;
                best_q.copy_from_slice(&trial);
            }
        }
        q.copy_from_slice(&best_q);
        best.iterations = total;
        Ok(best)
    }

    /// The largest position and orientation errors of `tasks` at the current globals.
    fn errors(&self, tasks: &[IkTask]) -> (f64, f64) {
        let mut pe: f64 = 0.0;
        let mut oe: f64 = 0.0;
        for t in tasks {
            pe = pe.max((t.goal.position - t.effector.position(&self.globals)).length());
            if let Some(r) = t.goal.orientation {
                oe = oe.max(rotation_error(t.effector.rotation(&self.globals), r).length());
            }
        }
        (pe, oe)
    }

    /// Computes the secondary task `dz` at the current globals and axes. Returns whether
    /// the extra null-space task is still active.
    fn secondary(
        &mut self,
        skeleton: &Skeleton,
        q: &[f64],
        reference: Option<&[f64]>,
        extra: Option<&mut dyn NullSpaceTask>,
    ) -> bool {
        self.dz.iter_mut().for_each(|z| *z = 0.0);
        let o = self.options;
        let all = skeleton.dofs();
        for (c, &d) in self.dofs.iter().enumerate() {
            let dof = &all[d];
            if o.limit_avoidance > 0.0 && dof.min.is_finite() && dof.max.is_finite() {
                let range = dof.max - dof.min;
                if range > 1e-9 {
                    let mid = 0.5 * (dof.max + dof.min);
                    // The gradient of Σ((q − mid)/range)² scaled by the gain, but never
                    // past the middle in one step: on a narrow range (a spine joint's 8°)
                    // the plain gradient overshot it (by 2.05 × at the default gain), and
                    // the oscillation kept the main task from converging.
                    let pull = (o.limit_avoidance * 2.0 / (range * range)).min(1.0);
                    self.dz[c] -= pull * (q[d] - mid);
                }
            }
            if let Some(r) = reference {
                self.dz[c] += o.posture_gain * (r[d] - q[d]);
            }
        }
        match extra {
            Some(task) => {
                let ctx = NullSpaceContext {
                    skeleton,
                    q,
                    globals: &self.globals,
                    dofs: &self.dofs,
                    axes: &self.axes,
                };
                task.add_step(&ctx, &mut self.dz)
            }
            None => false,
        }
    }

    /// One step of eq. 2-1 at the current globals, axes and secondary task: updates `q`.
    fn step(&mut self, skeleton: &Skeleton, q: &mut [f64], tasks: &[IkTask]) {
        let n = self.dofs.len();
        let all = skeleton.dofs();
        // Priority levels, highest first.
        self.levels.clear();
        self.levels.extend(tasks.iter().map(|t| t.priority));
        self.levels.sort_unstable();
        self.levels.dedup();

        self.locked.iter_mut().for_each(|l| *l = false);
        for _pass in 0..=n {
            self.solve_step(skeleton, tasks);
            // Clamping loop: lock the DOFs this step would push past a limit.
            let mut newly_locked = false;
            for (c, &d) in self.dofs.iter().enumerate() {
                if self.locked[c] {
                    continue;
                }
                let v = q[d] + self.dq[c];
                let dof = &all[d];
                if v < dof.min - 1e-12 || v > dof.max + 1e-12 {
                    // Locked at the limit it was heading for; the others make up for it.
                    self.locked[c] = true;
                    self.lock_step[c] = dof.clamp(v) - q[d];
                    newly_locked = true;
                }
            }
            if !newly_locked {
                break;
            }
        }
        for c in 0..n {
            let d = self.dofs[c];
            q[d] = all[d].clamp(q[d] + self.dq[c]);
        }
    }

    /// Computes `dq` for the current axes, locks and secondary task.
    fn solve_step(&mut self, skeleton: &Skeleton, tasks: &[IkTask]) {
        let n = self.dofs.len();
        let o = self.options;
        // Locked DOFs move to their limits; the tasks account for that motion.
        for c in 0..n {
            self.dq[c] = if self.locked[c] {
                self.lock_step[c]
            } else {
                0.0
            };
        }
        let any_locked = self.locked.iter().any(|l| *l);
        let single = self.levels.len() <= 1;
        if !single {
            self.p.reset(n, n);
            for c in 0..n {
                if !self.locked[c] {
                    self.p.set(c, c, 1.0);
                }
            }
        }
        for li in 0..self.levels.len() {
            let level = self.levels[li];
            let rows: usize = tasks
                .iter()
                .filter(|t| t.priority == level)
                .map(|t| t.rows())
                .sum();
            self.j.reset(rows, n);
            self.dx.clear();
            let mut r = 0;
            for t in tasks.iter().filter(|t| t.priority == level) {
                let orient = t.goal.orientation.is_some();
                fill_jacobian(
                    skeleton,
                    &self.globals,
                    &self.dofs,
                    &self.axes,
                    &t.effector,
                    orient,
                    &mut self.j,
                    r,
                );
                let mut e = t.goal.position - t.effector.position(&self.globals);
                let len = e.length();
                if len > o.max_position_step {
                    e *= o.max_position_step / len;
                }
                self.dx.extend_from_slice(&[e.x, e.y, e.z]);
                if let Some(goal) = t.goal.orientation {
                    let mut w = rotation_error(t.effector.rotation(&self.globals), goal);
                    let a = w.length();
                    if a > o.max_orientation_step {
                        w *= o.max_orientation_step / a;
                    }
                    self.dx.extend_from_slice(&[w.x, w.y, w.z]);
                }
                r += t.rows();
            }
            // Subtract what higher levels and locked DOFs already do: Δx_k − J_k Δq.
            if li > 0 || any_locked {
                self.jdq.clear();
                self.jdq.resize(rows, 0.0);
                self.j.mul_vec(&self.dq, &mut self.jdq);
                for (x, y) in self.dx.iter_mut().zip(&self.jdq) {
                    *x -= y;
                }
            }
            if single {
                for c in 0..n {
                    if self.locked[c] {
                        for r in 0..rows {
                            self.j.set(r, c, 0.0);
                        }
                    }
                }
                self.svd.compute(&self.j);
            } else {
                self.j.mul_symmetric(&self.p, &mut self.jp);
                self.svd.compute(&self.jp);
            }
            let smin = self.svd.min_singular_value();
            let eps = o.singular_threshold;
            let mut lambda2 = if smin < eps && eps > 0.0 {
                o.damping * o.damping * (1.0 - (smin / eps) * (smin / eps))
            } else {
                0.0
            };
            if li > 0 {
                // Lower levels lose rank exactly where they conflict with higher ones
                // (algorithmic singularities): always damp them.
                lambda2 = lambda2.max(o.lower_level_damping * o.lower_level_damping);
            }
            // Each level's joint step is bounded (small movements): scale it down whole.
            self.step_buf.clear();
            self.step_buf.resize(n, 0.0);
            self.svd
                .add_pseudo_inverse_times(&self.dx, lambda2, &mut self.step_buf);
            let largest = self.step_buf.iter().fold(0.0f64, |m, x| m.max(x.abs()));
            let scale = if largest > o.max_joint_step {
                o.max_joint_step / largest
            } else {
                1.0
            };
            for (q, s) in self.dq.iter_mut().zip(&self.step_buf) {
                *q += scale * s;
            }
            if !single {
                self.svd.remove_row_space(&mut self.p);
            }
        }
        // Secondary task, projected on the null space of every level.
        if single {
            self.zproj.clear();
            self.zproj.extend_from_slice(&self.dz);
            for (c, z) in self.zproj.iter_mut().enumerate() {
                if self.locked[c] {
                    *z = 0.0;
                }
            }
            if !self.levels.is_empty() {
                self.svd.project_out_row_space(&mut self.zproj);
            }
            for (q, z) in self.dq.iter_mut().zip(&self.zproj) {
                *q += z;
            }
        } else {
            for c in 0..n {
                let v = crate::linalg::dot(self.p.row(c), &self.dz);
                self.dq[c] += v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Instant;

    fn adult() -> Skeleton {
        crate::template::default_skeleton("adult").unwrap()
    }

    fn hand(s: &Skeleton) -> Effector {
        Effector {
            joint: s.joint("r_wrist").unwrap(),
            point: DVec3::new(0.0, -0.0735, 0.005),
        }
    }

    fn fk(s: &Skeleton, q: &[f64]) -> Vec<Transform> {
        let mut g = vec![Transform::IDENTITY; s.joints().len()];
        forward_kinematics(s, q, &mut g);
        g
    }

    /// Random reachable goals: the hand's pose at random postures within the limits.
    fn reach_many(orientation: bool) -> (Vec<f64>, Vec<usize>, usize) {
        let s = adult();
        let dofs: Vec<usize> = s.scope("right_arm").unwrap().iter().collect();
        let mut solver = IkSolver::new(&s, dofs.clone(), IkOptions::default()).unwrap();
        let e = hand(&s);
        let mut draw = crate::math::draws(42);
        let (mut times, mut iterations, mut failures) = (Vec::new(), Vec::new(), 0);
        for _ in 0..1000 {
            let mut target_q = vec![0.0; s.dof_count()];
            for &d in &dofs {
                let dof = &s.dofs()[d];
                target_q[d] = dof.min + (dof.max - dof.min) * draw();
            }
            let g = fk(&s, &target_q);
            let task = IkTask {
                effector: e,
                goal: Goal {
                    position: e.position(&g),
                    orientation: orientation.then(|| e.rotation(&g)),
                },
                priority: 0,
            };
            let mut q = vec![0.0; s.dof_count()];
            let t0 = Instant::now();
            let report = solver.solve_with_restarts(&s, &mut q, &[task], 16).unwrap();
            times.push(t0.elapsed().as_secs_f64() * 1e6);
            iterations.push(report.iterations);
            let g = fk(&s, &q);
            let err = (e.position(&g) - task.goal.position).length();
            let ang = task
                .goal
                .orientation
                .map_or(0.0, |r| rotation_error(e.rotation(&g), r).length());
            if err > 1e-3 || ang > 1f64.to_radians() {
                eprintln!(
                    "missed: {err:.4} m, {ang:.4} rad after {} iterations",
                    report.iterations
                );
                failures += 1;
            }
            for &d in &dofs {
                let dof = &s.dofs()[d];
                assert!(q[d] >= dof.min - 1e-12 && q[d] <= dof.max + 1e-12);
            }
        }
        (times, iterations, failures)
    }

    fn summary(what: &str, mut times: Vec<f64>, mut its: Vec<usize>) {
        times.sort_by(f64::total_cmp);
        its.sort_unstable();
        eprintln!(
            "{what}: solve time median {:.1} µs, worst {:.1} µs; iterations median {}, worst {}",
            times[times.len() / 2],
            times[times.len() - 1],
            its[its.len() / 2],
            its[its.len() - 1]
        );
    }

    #[test]
    fn a_thousand_random_reachable_positions_within_a_millimetre() {
        let (times, its, failures) = reach_many(false);
        summary("position", times, its);
        assert_eq!(failures, 0);
    }

    #[test]
    fn a_thousand_random_reachable_poses_within_a_millimetre_and_a_degree() {
        let (times, its, failures) = reach_many(true);
        summary("position+orientation", times, its);
        assert_eq!(failures, 0);
    }

    /// A null-space task that never finishes, counting its calls.
    struct Restless(usize);

    impl NullSpaceTask for Restless {
        fn add_step(&mut self, _ctx: &NullSpaceContext, dz: &mut [f64]) -> bool {
            self.0 += 1;
            dz.iter_mut().for_each(|z| *z += 0.01);
            true
        }
    }

    #[test]
    fn settle_iterations_bound_the_work_on_an_active_null_space_task() {
        let s = adult();
        let dofs: Vec<usize> = s.scope("right_arm").unwrap().iter().collect();
        let e = hand(&s);
        let goal = DVec3::new(-0.25, 1.2, 0.35);
        let task = IkTask::position(e, goal);
        let run = |settle: usize| {
            let options = IkOptions {
                settle_iterations: settle,
                ..IkOptions::default()
            };
            let mut solver = IkSolver::new(&s, dofs.clone(), options).unwrap();
            let mut q = vec![0.0; s.dof_count()];
            let mut task_calls = Restless(0);
            let r = solver
                .solve(&s, &mut q, &[task], None, Some(&mut task_calls))
                .unwrap();
            (r, task_calls.0)
        };
        let (unbounded, _) = run(usize::MAX);
        assert_eq!(unbounded.iterations, IkOptions::default().max_iterations);
        assert!(!unbounded.converged || unbounded.position_error <= 1e-5);
        let (bounded, calls) = run(2);
        assert!(bounded.converged, "{bounded:?}");
        assert!(bounded.position_error <= 1e-5);
        assert!(bounded.iterations < unbounded.iterations, "{bounded:?}");
        // The goal was met at some iteration k; two more steps followed, then the check.
        let met_at = bounded.iterations - 2;
        assert_eq!(calls, met_at + 3, "{bounded:?}");
    }

    #[test]
    fn a_null_space_goal_leaves_the_main_task_unchanged() {
        let s = adult();
        let dofs: Vec<usize> = s.scope("right_arm+spine").unwrap().iter().collect();
        let e = hand(&s);
        let mut solver = IkSolver::new(&s, dofs.clone(), IkOptions::default()).unwrap();
        let mut q = vec![0.0; s.dof_count()];
        let goal = DVec3::new(-0.25, 1.2, 0.35);
        let task = IkTask::position(e, goal);
        let r = solver.solve(&s, &mut q, &[task], None, None).unwrap();
        assert!(r.converged, "{r:?}");

        // First order: J · (I − J⁺J) Δz = 0 for an arbitrary Δz.
        let j = crate::jacobian::jacobian(&s, &q, &dofs, &e, false).unwrap();
        let mut svd = Svd::default();
        svd.compute(&j);
        let mut z: Vec<f64> = (0..dofs.len())
            .map(|i| ((i * 7 % 5) as f64 - 2.0) * 0.3)
            .collect();
        svd.project_out_row_space(&mut z);
        let mut jz = vec![0.0; 3];
        j.mul_vec(&z, &mut jz);
        assert!(jz.iter().all(|v| v.abs() < 1e-12), "{jz:?}");

        // Iterated: a reference posture far away pulls the body through the null space;
        // the posture changes a lot, the hand stays on its goal.
        let mut reference = q.clone();
        // Within vt12's 10° of torsion (template.rs, TRUNK).
        reference[s.dof("vt12_torsion").unwrap()] = 0.15;
        reference[s.dof("vl5_flexion").unwrap()] = 0.3;
        reference[s.dof("r_shoulder_twist").unwrap()] = 0.8;
        let before = q.clone();
        // Without the limit avoidance, which pulls the trunk's narrow ranges to their middle
        // as hard as the reference pulls them away.
        let mut o = IkOptions {
            posture_gain: 0.2,
            limit_avoidance: 0.0,
            ..IkOptions::default()
        };
        o.max_iterations = 60;
        solver.set_options(o).unwrap();
        struct Always;
        impl NullSpaceTask for Always {
            fn add_step(&mut self, _: &NullSpaceContext, _: &mut [f64]) -> bool {
                true
            }
        }
        solver
            .solve(&s, &mut q, &[task], Some(&reference), Some(&mut Always))
            .unwrap();
        let moved: f64 = dofs.iter().map(|&d| (q[d] - before[d]).abs()).sum();
        let g = fk(&s, &q);
        let err = (e.position(&g) - goal).length();
        assert!(moved > 0.5, "the posture moved by {moved} rad in all");
        assert!(err < 1e-5, "the main task error stays at {err} m");
        assert!(
            (q[s.dof("vt12_torsion").unwrap()] - 0.15).abs() < 0.1,
            "{}",
            q[s.dof("vt12_torsion").unwrap()]
        );
    }

    #[test]
    fn higher_priorities_win_and_lower_ones_do_what_they_can() {
        let s = adult();
        let dofs: Vec<usize> = s.scope("arms+spine").unwrap().iter().collect();
        let mut solver = IkSolver::new(&s, dofs, IkOptions::default()).unwrap();
        let right = hand(&s);
        let left = Effector {
            joint: s.joint("l_wrist").unwrap(),
            point: DVec3::new(0.0, -0.0735, 0.005),
        };
        // Both hands at one point far in front: impossible together.
        let far = DVec3::new(-0.1, 1.2, 0.55);
        let mut q = vec![0.0; s.dof_count()];
        let tasks = [
            IkTask::position(right, far),
            IkTask {
                priority: 1,
                ..IkTask::position(left, DVec3::new(0.6, 2.6, 0.0))
            },
        ];
        let start = (left.position(&fk(&s, &q)) - tasks[1].goal.position).length();
        let r = solver.solve(&s, &mut q, &tasks, None, None).unwrap();
        let g = fk(&s, &q);
        assert!((right.position(&g) - far).length() < 1e-4, "{r:?}");
        let end = (left.position(&g) - tasks[1].goal.position).length();
        assert!(end > 0.05 && end < start - 0.3, "{start} → {end}");
        // Reachable together at equal priority.
        let tasks = [
            IkTask::position(right, DVec3::new(-0.1, 1.1, 0.35)),
            IkTask::position(left, DVec3::new(0.1, 1.1, 0.35)),
        ];
        let mut q = vec![0.0; s.dof_count()];
        let r = solver.solve(&s, &mut q, &tasks, None, None).unwrap();
        assert!(r.converged && r.position_error < 1e-5, "{r:?}");
    }

    #[test]
    fn limits_hold_and_unreachable_goals_end_at_the_closest_point() {
        let s = adult();
        let dofs: Vec<usize> = s.scope("right_arm").unwrap().iter().collect();
        let mut solver = IkSolver::new(&s, dofs.clone(), IkOptions::default()).unwrap();
        let mut q = vec![0.0; s.dof_count()];
        let e = hand(&s);
        let r = solver
            .solve(
                &s,
                &mut q,
                &[IkTask::position(e, DVec3::new(-0.2, 1.4, 3.0))],
                None,
                None,
            )
            .unwrap();
        assert!(!r.converged);
        assert!(r.position_error > 2.0 && r.position_error < 2.8, "{r:?}");
        for &d in &dofs {
            let dof = &s.dofs()[d];
            assert!(q[d] >= dof.min && q[d] <= dof.max, "{}", dof.name);
        }
    }

    #[test]
    fn bad_goals_are_errors_not_panics() {
        let s = adult();
        let mut solver = IkSolver::new(&s, vec![50, 51, 52], IkOptions::default()).unwrap();
        let mut q = vec![0.0; s.dof_count()];
        let e = hand(&s);
        let nan = IkTask::position(e, DVec3::new(f64::NAN, 1.0, 0.0));
        assert!(solver.solve(&s, &mut q, &[nan], None, None).is_err());
        let unknown = IkTask::position(Effector::at_joint(999), DVec3::ONE);
        assert!(solver.solve(&s, &mut q, &[unknown], None, None).is_err());
        let mut bad = IkTask::position(e, DVec3::ONE);
        bad.goal.orientation = Some(DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0));
        assert!(solver.solve(&s, &mut q, &[bad], None, None).is_err());
        assert!(solver.solve(&s, &mut q[..10], &[], None, None).is_err());
        assert!(IkSolver::new(&s, vec![10_000], IkOptions::default()).is_err());
        assert!(IkSolver::new(&s, vec![], IkOptions::default()).is_err());
        let o = IkOptions {
            damping: f64::NAN,
            ..IkOptions::default()
        };
        assert!(IkSolver::new(&s, vec![1], o).is_err());
    }
}
