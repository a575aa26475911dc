//! Whole-body reach: the posture that brings one or two wrists to their goals, as a
//! person does — the arm first; then the spine, leaning and twisting; then, for a low
//! target, the legs, lowering the pelvis straight down with the knees bent and the feet
//! where they stand (flat, then the heels rising once the ankles bend no further) —
//! keeping the centre of mass over the feet.
//!
//! Each [`Stage`] widens the DOFs the inverse kinematics may move (within the action's
//! scope); a posture counts only if the wrists reach their goals and the centre of mass,
//! projected on the floor, stays within the feet's support rectangle.

use crate::walk::Rig;
use troupe_body::glam::{DQuat, DVec2, DVec3};
use troupe_body::ik::{Goal, IkOptions, IkSolver, IkTask};
use troupe_body::jacobian::{rotation_error, scope_dofs_moving, Effector};
use troupe_body::kinematics::{center_of_mass, forward_kinematics};
use troupe_body::sensors::Side;
use troupe_body::{Scope, Skeleton, Transform};
use troupe_scene::space::Footprint;
use troupe_scene::World;

/// A planned hand pose must be reachable within this distance (metres)…
pub const REACH_TOLERANCE: f64 = 0.005;
/// … and this angle (radians, 3°).
pub const REACH_ANGLE: f64 = 3.0 * std::f64::consts::PI / 180.0;
/// Depths (metres) the pelvis is lowered to, in turn, for a target the standing body
/// cannot reach.
pub const CROUCH_DEPTHS: [f64; 6] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6];
/// The most the trunk leans (radians, 40°): a target further down is reached by bending
/// the knees rather than by folding over straight legs.
pub const MAX_LEAN: f64 = 0.7;
/// How far (metres) the centre of mass may go beyond the ankles and the balls of the feet:
/// the heel behind the ankle and the toes ahead of the balls still carry weight.
pub const SUPPORT_MARGIN: (f64, f64) = (0.05, 0.06);

/// The least gap (m) a crouch leaves between a thigh and the furniture (see
/// [`BodyReach::keeping_knees_off`]).
pub const KNEE_CLEARANCE: f64 = 0.01;

/// What the reach may move besides the arms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Stage {
    /// The arms only.
    Arms,
    /// The arms and the spine (lean and twist).
    Spine,
    /// The arms and the spine, with the pelvis lowered by the given step of
    /// [`CROUCH_DEPTHS`] (knees bent, the feet on the floor), or as deep as the legs go
    /// when that is less.
    Crouch(usize),
}

/// A posture that reaches, with how the body got there.
#[derive(Clone, Debug, PartialEq)]
pub struct Reached {
    /// The whole posture.
    pub q: Vec<f64>,
    /// The DOFs it changed, with their values.
    pub changed: Vec<(usize, f64)>,
    /// How far (radians) the trunk leans from where it was (the vl5 → vt1 axis).
    pub lean: f64,
    /// How far (metres) the pelvis was lowered.
    pub crouch: f64,
}

/// Why a stage did not reach: the wrists' remaining distance and angle, or a balance
/// failure.
#[derive(Clone, Debug, PartialEq)]
pub enum Missed {
    /// The best remaining distance (m) and angle (rad) over the goals.
    By(f64, f64),
    /// The wrists reached, but the centre of mass left the feet (by metres).
    Balance(f64),
    /// The wrists reached, but only by leaning more than [`MAX_LEAN`] (radians).
    Lean(f64),
    /// The crouch step was deeper than the legs go with the feet on the floor (they go
    /// `deepest` metres): tried that deep instead, it missed as `then` says (`None`: a
    /// shallower step already had tried it).
    Legs {
        /// How deep (metres) the legs go at most.
        deepest: f64,
        /// How the crouch as deep as the legs go missed.
        then: Option<Box<Missed>>,
    },
}

/// Lowers the pelvis of `q` by `depth` (raises it for a negative one) with each foot
/// where it stands: flat while its ankle bends far enough, else on the ball of the foot
/// ([`stand_leg`]); false, `q` partly changed, if a leg cannot reach its foot.
fn lower_pelvis(sk: &Skeleton, rig: &Rig, root_y: usize, q: &mut [f64], depth: f64) -> bool {
    let mut g = vec![Transform::IDENTITY; sk.joints().len()];
    forward_kinematics(sk, q, &mut g);
    let heading = q[rig.root[3]];
    let pelvis = [q[rig.pelvis[0]], q[rig.pelvis[1]], q[rig.pelvis[2]]];
    let pelvis_rot = rig.pelvis_rotation(heading, pelvis);
    let root = g[0].translation - DVec3::Y * depth;
    q[root_y] -= depth;
    for (leg, l) in rig.legs.iter().enumerate() {
        let ankle_joint = l.joints[0];
        let (yaw, pitch) = Rig::foot_heading_pitch(&g[ankle_joint]);
        // Where the ankle of the foot put flat would be: a crouch that starts with the
        // heels raised (one already crouched) raises them from there, not again.
        let ankle = rig.plant_under(leg, g[ankle_joint].translation, yaw, pitch)
            + rig.ankle_from_plant(leg, DVec2::ZERO, yaw, 0.0);
        let hip = rig.hip_position(leg, root, heading, pelvis_rot);
        let Some(vals) = stand_leg(rig, leg, pelvis_rot, heading + pelvis[2], hip, ankle, yaw)
        else {
            return false;
        };
        for (i, &d) in l.dofs.iter().enumerate() {
            q[d] = vals[i];
        }
    }
    true
}

/// The DOF values of leg `leg` (in the rig's order) with its hip at `hip` (the pelvis at
/// world rotation `pelvis`, yaw `pelvis_yaw`) and its foot, heading `yaw`, standing where
/// a flat foot has its ankle at `ankle`: flat while the ankle's dorsiflexion stays within
/// its limit, else with the heel raised just enough, the foot rolling on the ball joint
/// and the toes flat on the floor, as a person squats. `None` when the leg cannot reach,
/// or only past a joint's limit (the knee folded past 150°, the heel raised past what the
/// toes bend): the pelvis is lower than the legs go with the feet on the floor.
fn stand_leg(
    rig: &Rig,
    leg: usize,
    pelvis: DQuat,
    pelvis_yaw: f64,
    hip: DVec3,
    ankle: DVec3,
    yaw: f64,
) -> Option<[f64; 7]> {
    let l = &rig.legs[leg];
    let flat = rig.ankle_from_plant(leg, DVec2::ZERO, yaw, 0.0);
    // The heel up by `rise` (radians): the ankle turns up about the ball joint, and the
    // toes bend back by as much to stay on the floor.
    let solve = |rise: f64| {
        let at = ankle + rig.ankle_from_plant(leg, DVec2::ZERO, yaw, -rise) - flat;
        rig.solve_leg(leg, pelvis, pelvis_yaw, None, hip, at, (yaw, -rise, -rise))
    };
    // Every DOF within its limits (a hair over: the limits are where the posture clamps),
    // and the ankle reached.
    let fits = |(vals, miss): ([f64; 7], f64)| {
        let within =
            (vals.iter().zip(&l.limits)).all(|(v, (lo, hi))| *v > lo - 1e-6 && *v < hi + 1e-6);
        (within && miss <= 1e-3).then_some(vals)
    };
    // The templates' ankle flexion is positive toward dorsiflexion (its 30° bound).
    let dorsiflexion = l.limits[4].1;
    let (vals, miss) = solve(0.0);
    if vals[4] <= dorsiflexion {
        return fits((vals, miss));
    }
    // As far as the toes bend back (their DOF's sign read off a solve).
    let toes = l.limits[6];
    let most = if solve(1.0).0[6] < 0.0 {
        -toes.0
    } else {
        toes.1
    };
    if solve(most).0[4] > dorsiflexion {
        return None;
    }
    // Raising the heel takes the shank's lean off the ankle: bisect for the least rise
    // that keeps the ankle within its limit.
    let (mut lo, mut hi) = (0.0, most);
    while hi - lo > 1e-7 {
        let mid = 0.5 * (lo + hi);
        if solve(mid).0[4] > dorsiflexion {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let (vals, miss) = solve(hi);
    // A leg folded so far that the ankle's angle jumps (the knee near straight back)
    // brackets a jump, not the limit.
    if (vals[4] - dorsiflexion).abs() > 1e-3 {
        return None;
    }
    fits((vals, miss))
}

/// The legs of a crouch on its way down (or back up): an action that moves `root_y`
/// between two heights by interpolation solves the legs again for each height, the feet
/// where they stood at its start (see `stand_leg`). Interpolated too, the knees
/// straighten faster than the pelvis rises (the leg's length is not linear in the knee's
/// angle) and the soles went up to 10 cm into the floor halfway, and stayed there if the
/// action stopped then.
pub struct CrouchLegs {
    rig: Rig,
    root_y: usize,
    /// The posture the crouch starts from: its feet stay where they are.
    start: Vec<f64>,
    /// How far (m) the pelvis goes down in all.
    depth: f64,
    /// Per leg DOF, the start's value less the legs solved at the start's height (feet
    /// not quite flat, another hip twist): faded out on the way down, so the legs neither
    /// jump at the start nor miss the planned crouch at its end.
    offset: Vec<(usize, f64)>,
    scratch: Vec<f64>,
}

impl CrouchLegs {
    /// For a crouch `depth` metres down from posture `start` of `skeleton`; `None` when
    /// the skeleton has no legs the walk's rig knows or they cannot stand where they are.
    pub fn new(skeleton: &Skeleton, start: &[f64], depth: f64) -> Option<CrouchLegs> {
        let rig = Rig::new(skeleton).ok()?;
        let root_y = skeleton.dof("root_y").ok()?;
        let mut solved = start.to_vec();
        if !lower_pelvis(skeleton, &rig, root_y, &mut solved, 0.0) {
            return None;
        }
        let offset = (rig.legs.iter().flat_map(|l| l.dofs))
            .map(|d| (d, start[d] - solved[d]))
            .collect();
        Some(CrouchLegs {
            rig,
            root_y,
            start: start.to_vec(),
            depth,
            offset,
            scratch: Vec::new(),
        })
    }

    /// The leg DOFs it sets.
    pub fn dofs(&self) -> impl Iterator<Item = usize> + '_ {
        self.offset.iter().map(|&(d, _)| d)
    }

    /// Sets the legs of `q` for its `root_y`: the feet where they stood at the start.
    /// A height the legs cannot reach leaves them as they are.
    pub fn apply(&mut self, skeleton: &Skeleton, q: &mut [f64]) {
        let depth = self.start[self.root_y] - q[self.root_y];
        self.scratch.clear();
        self.scratch.extend_from_slice(&self.start);
        if lower_pelvis(skeleton, &self.rig, self.root_y, &mut self.scratch, depth) {
            // Down or up (a crouched body standing): the offset fades either way.
            let rest = if self.depth != 0.0 {
                (1.0 - depth / self.depth).clamp(0.0, 1.0)
            } else {
                1.0
            };
            for &(d, off) in &self.offset {
                q[d] = self.scratch[d] + off * rest;
            }
        }
    }
}

/// What kept every posture tried from counting, gathered over a search: an error then
/// names what limited the reach, not only how far the wrists stayed from their goals.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Shortfall {
    /// The least the wrists missed by (metres, plus 0.1 m per radian), over the postures
    /// that did not reach.
    pub miss: Option<f64>,
    /// The least lean (radians) of a posture that reached only by leaning past
    /// [`MAX_LEAN`].
    pub lean: Option<f64>,
    /// The least distance (metres) the centre of mass went beyond the feet, over the
    /// postures that reached but would fall.
    pub balance: Option<f64>,
    /// How deep (metres) the legs crouch at most with the feet on the floor, when a
    /// deeper crouch was wanted; with the least miss, lean and centre-of-mass distance
    /// (as above) of the postures crouched that deep, for the error to name the legs when
    /// it gives one of those.
    pub legs: Option<(f64, [Option<f64>; 3])>,
    /// What the knees would have gone into, crouched deeper (see
    /// [`BodyReach::keeping_knees_off`]).
    pub knees_by: Option<String>,
}

impl Shortfall {
    /// Counts one posture that did not count.
    pub fn note(&mut self, missed: Missed) {
        let least = |old: Option<f64>, v: f64| Some(old.map_or(v, |o| o.min(v)));
        match missed {
            Missed::By(miss, angle) if (miss + angle * 0.1).is_finite() => {
                self.miss = least(self.miss, miss + angle * 0.1);
            }
            Missed::By(..) => {}
            Missed::Lean(lean) => self.lean = least(self.lean, lean),
            Missed::Balance(by) => self.balance = least(self.balance, by),
            Missed::Legs { deepest, then } => {
                let legs = self.legs.get_or_insert((deepest, [None; 3]));
                legs.0 = legs.0.min(deepest);
                if let Some(missed) = then {
                    let figures = &mut legs.1;
                    match *missed {
                        Missed::By(miss, angle) if (miss + angle * 0.1).is_finite() => {
                            figures[0] = least(figures[0], miss + angle * 0.1);
                        }
                        Missed::Lean(lean) => figures[1] = least(figures[1], lean),
                        Missed::Balance(by) => figures[2] = least(figures[2], by),
                        _ => {}
                    }
                    self.note(*missed);
                }
            }
        }
    }

    /// What limited the reach, for an error: the postures that reached but leaned too
    /// far or would fall, then how near the others came (`best`: "the best grasp"), and
    /// the legs' deepest crouch when it limited that.
    pub fn describe(&self, best: &str) -> String {
        let mut parts = Vec::new();
        if let Some(lean) = self.lean {
            parts.push(format!(
                "the wrist gets there only by leaning the trunk {:.0}° (at most {:.0}°)",
                lean.to_degrees(),
                MAX_LEAN.to_degrees()
            ));
        }
        if let Some(by) = self.balance {
            parts.push(format!(
                "reaching it would put the centre of mass {by:.3} m beyond the feet"
            ));
        }
        match (self.miss, parts.is_empty()) {
            (Some(miss), true) => parts.push(format!("{best} misses by {miss:.3} m")),
            (Some(miss), false) => parts.push(format!("otherwise it misses by {miss:.3} m")),
            (None, true) => parts.push("no posture reaches it".into()),
            (None, false) => {}
        }
        // The legs limited it when the figure given came from as deep as they go (or no
        // posture was tried that deep: they crouch no deeper than a shallower step).
        let shown = [self.miss, self.lean, self.balance];
        if let Some((depth, _)) = self.legs.filter(|(_, figures)| {
            figures.iter().all(Option::is_none)
                || (figures.iter().zip(shown)).any(|(f, s)| f.is_some() && *f == s)
        }) {
            let knees = match &self.knees_by {
                Some(by) => format!(" and the knees clear of `{by}`"),
                None => String::new(),
            };
            parts.push(format!(
                "the legs crouch {depth:.2} m at most with the feet on the floor{knees}"
            ));
        }
        parts.join("; ")
    }
}

/// The obstacles within 1.5 m of actor `actor`'s root in `world` but the one called
/// `except` (the object the hands go to), for [`BodyReach::keeping_knees_off`].
pub fn furniture_round(world: &World, actor: usize, except: &str) -> Vec<Footprint> {
    let Some(&at) = world.crowd.positions.get(actor) else {
        return Vec::new();
    };
    world
        .crowd
        .footprints_around(at, Vec::new())
        .within(1.5)
        .filter(|f| f.name != except)
        .cloned()
        .collect()
}

/// Whole-body reaching for one actor's skeleton, limited to `allowed` DOFs besides the
/// arms of the hands that reach.
pub struct BodyReach<'a> {
    skeleton: &'a Skeleton,
    allowed: Scope,
    spine: Scope,
    legs: Scope,
    root_y: usize,
    rig: Option<Rig>,
    /// The furniture round the body, which a crouch keeps the thighs off (see
    /// [`BodyReach::keeping_knees_off`]).
    obstacles: Vec<Footprint>,
    /// The knee joints (left, right), if the skeleton has them.
    knees: Option<[usize; 2]>,
    /// What last held a crouch back by the knees.
    knees_by: std::cell::RefCell<Option<String>>,
}

impl<'a> BodyReach<'a> {
    /// Reaching on `skeleton`, moving the spine and legs only where `allowed` says.
    pub fn new(skeleton: &'a Skeleton, allowed: Scope) -> crate::error::Result<BodyReach<'a>> {
        Ok(BodyReach {
            skeleton,
            allowed,
            spine: skeleton.scope("spine")?,
            legs: skeleton.scope("legs")?,
            root_y: skeleton.dof("root_y")?,
            rig: Rig::new(skeleton).ok(),
            obstacles: Vec::new(),
            knees: skeleton
                .joint("l_knee")
                .ok()
                .zip(skeleton.joint("r_knee").ok())
                .map(|(l, r)| [l, r]),
            knees_by: Default::default(),
        })
    }

    /// Crouches no deeper than keeps each thigh [`KNEE_CLEARANCE`] off `obstacles` (or,
    /// already nearer, no nearer): the knees come forwards as the pelvis goes down, and a
    /// ball picked up from the floor by a café table put a thigh 48 mm into it.
    pub fn keeping_knees_off(mut self, obstacles: Vec<Footprint>) -> BodyReach<'a> {
        self.obstacles = obstacles;
        self
    }

    /// What held a crouch back by the knees, the last time one was (see
    /// [`BodyReach::keeping_knees_off`]).
    pub fn knees_by(&self) -> Option<String> {
        self.knees_by.borrow().clone()
    }

    /// The least gap (m) between a thigh of the body posed at `q` and the obstacles whose
    /// top is above it, and which obstacle; `None` with none round.
    fn thighs_gap(&self, q: &[f64]) -> Option<(f64, usize)> {
        let (rig, knees) = (self.rig.as_ref()?, self.knees?);
        if self.obstacles.is_empty() {
            return None;
        }
        let mut g = vec![Transform::IDENTITY; self.skeleton.joints().len()];
        forward_kinematics(self.skeleton, q, &mut g);
        let heading = q[rig.root[3]];
        let pelvis = [q[rig.pelvis[0]], q[rig.pelvis[1]], q[rig.pelvis[2]]];
        let pelvis_rot = rig.pelvis_rotation(heading, pelvis);
        let mut least: Option<(f64, usize)> = None;
        for (leg, &knee) in knees.iter().enumerate() {
            let hip = rig.hip_position(leg, g[0].translation, heading, pelvis_rot);
            let knee = g[knee].translation;
            let [r_hip, r_knee] = rig.legs[leg].thigh_radii;
            for k in [0.5, 0.75, 1.0] {
                let (p, r) = (hip.lerp(knee, k), r_hip + (r_knee - r_hip) * k);
                for (i, f) in self.obstacles.iter().enumerate() {
                    if p.y - r < f.top {
                        let gap = f.distance(DVec2::new(p.x, p.z)) - r;
                        if least.is_none_or(|(g, _)| gap < g) {
                            least = Some((gap, i));
                        }
                    }
                }
            }
        }
        least
    }

    /// The stages `allowed` permits, cheapest first.
    pub fn stages(&self) -> Vec<Stage> {
        let mut stages = vec![Stage::Arms];
        if self.allowed.overlaps(&self.spine) {
            stages.push(Stage::Spine);
        }
        let legs = self.allowed.contains_all(&self.legs) && self.allowed.contains(self.root_y);
        if legs && self.rig.is_some() {
            stages.extend((0..CROUCH_DEPTHS.len()).map(Stage::Crouch));
        }
        stages
    }

    /// The DOFs a reach with the hands `sides` may move at all (for the action's scope).
    pub fn body_scope(skeleton: &Skeleton) -> crate::error::Result<Scope> {
        let mut s = skeleton.scope("spine+legs")?;
        s.insert(skeleton.dof("root_y")?);
        Ok(s)
    }

    /// The first stage past the arms alone (lean, then crouch, as `allowed` permits) that
    /// brings the wrists of `goals` from posture `q0` to their poses, if any: for an
    /// action whose arm alone has missed.
    pub fn beyond_the_arm(
        &self,
        q0: &[f64],
        goals: &[(Side, Transform)],
    ) -> crate::error::Result<Option<Reached>> {
        Ok(self.search_beyond_the_arm(q0, goals)?.ok())
    }

    /// As [`BodyReach::beyond_the_arm`], with what limited every stage when none reaches.
    pub fn search_beyond_the_arm(
        &self,
        q0: &[f64],
        goals: &[(Side, Transform)],
    ) -> crate::error::Result<Result<Reached, Shortfall>> {
        let mut shortfall = Shortfall::default();
        for stage in self.stages().into_iter().skip(1) {
            match self.reach(q0, goals, stage)? {
                Ok(reached) => return Ok(Ok(reached)),
                Err(missed) => shortfall.note(missed),
            }
        }
        shortfall.knees_by = self.knees_by();
        Ok(Err(shortfall))
    }

    /// Tries `stage` from posture `q0`: the wrists of `goals` to their poses.
    pub fn reach(
        &self,
        q0: &[f64],
        goals: &[(Side, Transform)],
        stage: Stage,
    ) -> crate::error::Result<Result<Reached, Missed>> {
        let sk = self.skeleton;
        let mut tasks = Vec::new();
        for (side, goal) in goals {
            let task = IkTask {
                effector: Effector::at_joint(sk.joint(&format!("{}wrist", side.prefix()))?),
                goal: Goal {
                    position: goal.translation,
                    orientation: Some(goal.rotation),
                },
                priority: 0,
            };
            tasks.push((task, sk.scope(&format!("{}_arm", side.name()))?));
        }
        self.reach_tasks(q0, &tasks, stage, (REACH_TOLERANCE, REACH_ANGLE))
    }

    /// Tries `stage` from posture `q0`: each task's effector to its goal, moving its
    /// `arm` scope (and at later stages the spine, after crouching), within `tolerance`
    /// (metres, radians).
    pub fn reach_tasks(
        &self,
        q0: &[f64],
        tasks: &[(IkTask, Scope)],
        stage: Stage,
        tolerance: (f64, f64),
    ) -> crate::error::Result<Result<Reached, Missed>> {
        let mut q = q0.to_vec();
        let mut crouch = 0.0;
        let mut deepest = None;
        if let Stage::Crouch(i) = stage {
            crouch = CROUCH_DEPTHS[i];
            if !self.crouch(&mut q, crouch) {
                // Deeper than the legs go with the feet on the floor: the first such step
                // crouches as deep as they go instead, the later ones not at all.
                let most = self.deepest_crouch(q0, crouch);
                let above = if i == 0 { 0.0 } else { CROUCH_DEPTHS[i - 1] };
                q.copy_from_slice(q0);
                if most <= above + 1e-3 || !self.crouch(&mut q, most) {
                    return Ok(Err(Missed::Legs {
                        deepest: most,
                        then: None,
                    }));
                }
                crouch = most;
                deepest = Some(most);
            }
        }
        let result = self.solve_stage(q0, q, tasks, stage, tolerance, crouch)?;
        Ok(match (result, deepest) {
            (Err(missed), Some(deepest)) => Err(Missed::Legs {
                deepest,
                then: Some(Box::new(missed)),
            }),
            (result, _) => result,
        })
    }

    /// The rest of [`BodyReach::reach_tasks`], from posture `q` crouched by `crouch`.
    fn solve_stage(
        &self,
        q0: &[f64],
        mut q: Vec<f64>,
        tasks: &[(IkTask, Scope)],
        stage: Stage,
        tolerance: (f64, f64),
        crouch: f64,
    ) -> crate::error::Result<Result<Reached, Missed>> {
        let sk = self.skeleton;
        let mut moving = Scope::EMPTY;
        for (task, arm) in tasks {
            let mut scope = *arm;
            if stage != Stage::Arms {
                scope = scope.union(&self.spine.intersection(&self.allowed));
            }
            let dofs = scope_dofs_moving(sk, &scope, task.effector.joint);
            moving = moving.union(&dofs.into_iter().collect());
        }
        let options = IkOptions {
            max_iterations: 200,
            ..IkOptions::default()
        };
        let tasks: Vec<IkTask> = tasks.iter().map(|(t, _)| *t).collect();
        let mut solver = IkSolver::new(sk, moving.iter().collect(), options)?;
        solver.solve(sk, &mut q, &tasks, Some(q0), None)?;
        let g = solver.globals();
        let (mut miss, mut angle) = (0.0f64, 0.0f64);
        for task in &tasks {
            miss = miss.max((task.effector.position(g) - task.goal.position).length());
            if let Some(r) = task.goal.orientation {
                angle = angle.max(rotation_error(task.effector.rotation(g), r).length());
            }
        }
        if miss > tolerance.0 || angle > tolerance.1 {
            return Ok(Err(Missed::By(miss, angle)));
        }
        let mut globals = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(sk, &q, &mut globals);
        let outside = self.outside_support(&globals);
        if outside > 0.0 {
            return Ok(Err(Missed::Balance(outside)));
        }
        let mut before = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(sk, q0, &mut before);
        let lean = self
            .trunk_axis(&globals)?
            .angle_between(self.trunk_axis(&before)?);
        if lean > MAX_LEAN {
            return Ok(Err(Missed::Lean(lean)));
        }
        let changed = (0..q.len())
            .filter(|&d| q[d] != q0[d])
            .map(|d| (d, q[d]))
            .collect();
        Ok(Ok(Reached {
            q,
            changed,
            lean,
            crouch,
        }))
    }

    /// The trunk's axis, from the lowest to the highest spine joint.
    fn trunk_axis(&self, g: &[Transform]) -> crate::error::Result<DVec3> {
        let sk = self.skeleton;
        Ok(g[sk.joint("vt1")?].translation - g[sk.joint("vl5")?].translation)
    }

    /// Lowers the pelvis of `q` by `depth` with the feet where they are (see
    /// [`stand_leg`]); false if the legs cannot with the feet on the floor.
    /// Also false where the thighs would come nearer the furniture than
    /// [`KNEE_CLEARANCE`] (see [`BodyReach::keeping_knees_off`]).
    fn crouch(&self, q: &mut [f64], depth: f64) -> bool {
        let Some(rig) = &self.rig else { return false };
        let before = self.thighs_gap(q);
        if !lower_pelvis(self.skeleton, rig, self.root_y, q, depth) {
            return false;
        }
        match (self.thighs_gap(q), before) {
            (Some((gap, i)), before)
                if gap < KNEE_CLEARANCE && before.is_none_or(|(was, _)| gap < was) =>
            {
                *self.knees_by.borrow_mut() = Some(self.obstacles[i].name.clone());
                false
            }
            _ => true,
        }
    }

    /// The deepest (metres, to a millimetre) the pelvis of `q0` goes down, at most
    /// `below`, with the feet on the floor.
    fn deepest_crouch(&self, q0: &[f64], below: f64) -> f64 {
        let mut q = q0.to_vec();
        let (mut lo, mut hi) = (0.0, below);
        while hi - lo > 1e-3 {
            let mid = 0.5 * (lo + hi);
            q.copy_from_slice(q0);
            if self.crouch(&mut q, mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo
    }

    /// How far (metres) the centre of mass lies outside the feet's support rectangle, in
    /// the body's frame (0 inside).
    fn outside_support(&self, g: &[Transform]) -> f64 {
        let sk = self.skeleton;
        let com = center_of_mass(sk, g);
        let heading = g[0].rotation * DVec3::Z;
        let fwd = DVec3::new(heading.x, 0.0, heading.z).normalize_or(DVec3::Z);
        let left = DVec3::Y.cross(fwd);
        let names = ["l_ankle", "r_ankle", "l_metatarsal", "r_metatarsal"];
        let (mut f0, mut f1, mut s0, mut s1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for n in names {
            let Ok(j) = sk.joint(n) else { return 0.0 };
            let p = g[j].translation;
            f0 = f0.min(p.dot(fwd));
            f1 = f1.max(p.dot(fwd));
            s0 = s0.min(p.dot(left));
            s1 = s1.max(p.dot(left));
        }
        let (back, front) = SUPPORT_MARGIN;
        let (f, s) = (com.dot(fwd), com.dot(left));
        let beyond = |v: f64, lo: f64, hi: f64| (lo - v).max(v - hi).max(0.0);
        beyond(f, f0 - back, f1 + front).max(beyond(s, s0 - 0.04, s1 + 0.04))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::template::default_skeleton;

    /// Each foot's heel, sole under the ball joint and sole under the tip of the toes
    /// (the rig's points) in posture `g`: their heights.
    fn soles(rig: &Rig, g: &[Transform]) -> Vec<[f64; 3]> {
        (rig.legs.iter())
            .map(|l| {
                let [ankle, ball] = l.joints;
                let heel = DVec3::new(0.0, -rig.ankle_height, l.heel.z);
                [
                    g[ankle].transform_point(heel).y,
                    g[ball].transform_point(DVec3::new(0.0, -l.ball.y, 0.0)).y,
                    g[ball].transform_point(l.toe_sole).y,
                ]
            })
            .collect()
    }

    #[test]
    fn past_the_ankles_limit_a_crouch_raises_the_heels_with_the_toes_on_the_floor() {
        for (template, depths) in [
            ("adult", [0.05, 0.2, 0.4, 0.5]),
            ("child", [0.05, 0.1, 0.2, 0.3]),
        ] {
            let sk = default_skeleton(template).unwrap();
            let rig = Rig::new(&sk).unwrap();
            let root_y = sk.dof("root_y").unwrap();
            let q0 = vec![0.0; sk.dof_count()];
            let mut g0 = vec![Transform::IDENTITY; sk.joints().len()];
            forward_kinematics(&sk, &q0, &mut g0);
            let standing = soles(&rig, &g0);
            for depth in depths {
                let mut q = q0.clone();
                assert!(
                    lower_pelvis(&sk, &rig, root_y, &mut q, depth),
                    "{template} {depth}"
                );
                let mut g = g0.clone();
                forward_kinematics(&sk, &q, &mut g);
                for (leg, l) in rig.legs.iter().enumerate() {
                    for (i, &d) in l.dofs.iter().enumerate() {
                        let (lo, hi) = l.limits[i];
                        assert!(
                            q[d] > lo - 1e-6 && q[d] < hi + 1e-6,
                            "{template} {depth}: DOF {i} at {}",
                            q[d]
                        );
                    }
                    let ball = g[l.joints[1]].translation;
                    assert!(
                        (ball - g0[l.joints[1]].translation).length() < 1e-6,
                        "{template} {depth}: the ball moved to {ball}"
                    );
                    let [heel, under_ball, tip] = soles(&rig, &g)[leg];
                    // The foot rolls on the ball joint: the sole under it tilts up behind.
                    assert!(
                        under_ball > -1e-9 && tip.abs() < 1e-3,
                        "{template} {depth}: ball {under_ball}, toes {tip}"
                    );
                    assert!(heel > -1e-9, "{template} {depth}: heel {heel}");
                    let ankle = q[l.dofs[4]];
                    if depth == 0.05 {
                        // Shallow, the ankle bends: the foot flat as it stood.
                        assert!(
                            (heel - standing[leg][0]).abs() < 1e-6 && ankle < l.limits[4].1 - 0.01,
                            "{template}: heel {heel}"
                        );
                    } else {
                        // Deeper, the ankle at its limit and the heel off the floor.
                        assert!(
                            (ankle - l.limits[4].1).abs() < 1e-3 && heel > 0.02,
                            "{template} {depth}: ankle {ankle}, heel {heel}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_crouch_deeper_than_the_knees_fold_is_refused_and_the_reach_goes_as_deep_as_they_do() {
        for (template, too_deep, most) in [("adult", 0.6, (0.5, 0.6)), ("child", 0.4, (0.3, 0.4))] {
            let sk = default_skeleton(template).unwrap();
            let rig = Rig::new(&sk).unwrap();
            let root_y = sk.dof("root_y").unwrap();
            let q0 = vec![0.0; sk.dof_count()];
            let mut q = q0.clone();
            assert!(
                !lower_pelvis(&sk, &rig, root_y, &mut q, too_deep),
                "{template}"
            );
            let body = BodyReach::new(&sk, BodyReach::body_scope(&sk).unwrap()).unwrap();
            let deepest = body.deepest_crouch(&q0, too_deep);
            assert!(
                deepest > most.0 && deepest < most.1,
                "{template}: {deepest}"
            );
            let mut q = q0.clone();
            assert!(body.crouch(&mut q, deepest));
            // The knees then fold nearly as far as they go.
            let l = &rig.legs[0];
            assert!(
                q[l.dofs[3]] > l.limits[3].1 - 0.05,
                "{template}: knee {}",
                q[l.dofs[3]]
            );
        }
    }

    #[test]
    fn the_error_names_the_legs_when_the_deepest_crouch_gave_its_figure() {
        let legs = |miss: f64| Missed::Legs {
            deepest: 0.55,
            then: Some(Box::new(Missed::By(miss, 0.0))),
        };
        let mut limited = Shortfall::default();
        limited.note(Missed::By(0.08, 0.0));
        limited.note(legs(0.04));
        let said = limited.describe("the best grasp");
        assert_eq!(said, "the best grasp misses by 0.040 m; the legs crouch 0.55 m at most with the feet on the floor");
        // Crouching nearer did not help: the legs are not what limited it.
        let mut not = Shortfall::default();
        not.note(Missed::By(0.01, 0.0));
        not.note(legs(0.04));
        assert_eq!(
            not.describe("the best grasp"),
            "the best grasp misses by 0.010 m"
        );
    }
}
