//! The interactive grasping automaton of thesis 4.7 (figure 4-26): a hand driven from any
//! source of finger values (a data glove, a network stream, a test) that never
//! penetrates objects, and that decides when an object is grasped and released.
//!
//! Each [`GraspAutomaton::update`] takes the desired finger DOF values and the objects
//! near the hand. The fingers move from their last corrected values toward the desired
//! ones; a DOF above a touching sensor stops at the contact (the same sub-stepped rule as
//! automatic grasping, [`super::close`]). Then:
//!
//! | state | condition | next state | decision |
//! |---|---|---|---|
//! | `FreeHand` | a finger touches object `o` | `GraspingInProgress(o)` | — |
//! | `GraspingInProgress(o)` | the thumb and another finger touch `o` | `SecureGrasp(o)` | attach `o` |
//! | `GraspingInProgress(o)` | nothing touches | `FreeHand` | — |
//! | `SecureGrasp(o)` | the thumb or every other finger lets go of `o` (the hand opens) | `GraspingInProgress` or `FreeHand` | release `o` |
//!
//! The caller applies the decisions (for a scene: [`troupe_runtime::holding::HoldRequest`]
//! `Attach`/`Release` through its generator's writer, or [`troupe_runtime::Scene::request_hold`]).

use super::close::{HandModel, CONTACT_DISTANCE};
use troupe_runtime::glam::DVec3;
use troupe_runtime::sensors::{object_distance, Side};
use troupe_runtime::{Object, Scope, Skeleton, Transform};

/// The automaton's states (4.7: pale skin, blue, green in the thesis' display).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandState {
    /// Nothing touched.
    FreeHand,
    /// Some finger touches object `.0`, not yet a secure grasp.
    GraspingInProgress(usize),
    /// Thumb and another finger hold object `.0`: it is attached to the hand.
    SecureGrasp(usize),
}

impl HandState {
    /// `FREE_HAND`, `GRASPING_IN_PROGRESS` or `SECURE_GRASP`.
    pub fn name(self) -> &'static str {
        match self {
            HandState::FreeHand => "FREE_HAND",
            HandState::GraspingInProgress(_) => "GRASPING_IN_PROGRESS",
            HandState::SecureGrasp(_) => "SECURE_GRASP",
        }
    }
}

/// What the caller should do with an object after an update.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandDecision {
    /// Attach object `.0` to the hand (it follows the wrist).
    Attach(usize),
    /// Release object `.0`.
    Release(usize),
}

/// The result of one update.
#[derive(Clone, Debug, PartialEq)]
pub struct AutomatonOutput {
    /// Corrected finger values (DOF, value), every finger DOF of the hand.
    pub values: Vec<(usize, f64)>,
    /// The state after the update.
    pub state: HandState,
    /// Attach or release, when the state changed so.
    pub decision: Option<HandDecision>,
    /// Per finger (thumb, index, middle, ring, pinky): touching an object.
    pub touching: [bool; 5],
}

/// The grasping automaton of one hand.
pub struct GraspAutomaton {
    model: HandModel,
    state: HandState,
    values: Vec<(usize, f64)>,
    q: Vec<f64>,
    globals: Vec<Transform>,
    targets: Vec<(usize, f64)>,
}

impl GraspAutomaton {
    /// An automaton for `side`'s hand of `skeleton`, fingers starting at `q`'s values.
    pub fn new(skeleton: &Skeleton, side: Side, q: &[f64]) -> Result<GraspAutomaton, String> {
        if q.len() != skeleton.dof_count() {
            return Err(format!(
                "grasp automaton: posture has {} values, the skeleton {} DOFs",
                q.len(),
                skeleton.dof_count()
            ));
        }
        let model = HandModel::new(skeleton, side)?;
        let values = model.sensors.scope.iter().map(|d| (d, q[d])).collect();
        Ok(GraspAutomaton {
            model,
            state: HandState::FreeHand,
            values,
            q: q.to_vec(),
            globals: Vec::new(),
            targets: Vec::new(),
        })
    }

    /// The current state.
    pub fn state(&self) -> HandState {
        self.state
    }

    /// The hand's sensors and kinematics.
    pub fn model(&self) -> &HandModel {
        &self.model
    }

    /// One update. `posture` is the actor's full posture and `globals` its joint globals
    /// (the wrist's must be current; finger values in `posture` are ignored: the
    /// automaton keeps its own corrected ones). `desired` are the source's finger values
    /// (DOF, radians; any subset of the hand's DOFs). `objects` are what the hand may
    /// touch (object indices in decisions are positions in this slice).
    pub fn update(
        &mut self,
        skeleton: &Skeleton,
        posture: &[f64],
        globals: &[Transform],
        desired: &[(usize, f64)],
        objects: &[Object],
    ) -> Result<AutomatonOutput, String> {
        if posture.len() != self.q.len() || globals.len() != skeleton.joints().len() {
            return Err("grasp automaton: posture or globals do not match the skeleton".into());
        }
        self.targets.clear();
        for &(d, v) in desired {
            if !self.model.sensors.scope.contains(d) {
                return Err(format!(
                    "grasp automaton: DOF #{d} is not a finger DOF of the {} hand",
                    self.model.sensors.side.name()
                ));
            }
            if !v.is_finite() {
                return Err(format!(
                    "grasp automaton: desired value of `{}` is not finite",
                    skeleton.dofs()[d].name
                ));
            }
            self.targets.push((d, skeleton.dofs()[d].clamp(v)));
        }
        self.q.copy_from_slice(posture);
        for &(d, v) in &self.values {
            self.q[d] = v;
        }
        self.globals.clear();
        self.globals.extend_from_slice(globals);
        self.model
            .finger_kinematics(skeleton, &self.q, &mut self.globals);
        let field = |p: DVec3| {
            objects
                .iter()
                .map(|o| object_distance(o, p))
                .fold(f64::INFINITY, f64::min)
        };
        let mut blocked = Scope::EMPTY;
        self.model.advance(
            skeleton,
            &mut self.q,
            &mut self.globals,
            &self.targets,
            &mut blocked,
            &field,
        );
        for v in &mut self.values {
            v.1 = self.q[v.0];
        }
        // Which object each finger touches (the nearest one).
        let hs = &self.model.sensors;
        let mut touching = [false; 5];
        let mut touched: [Option<usize>; 5] = [None; 5];
        for (i, s) in hs.sensors.iter().enumerate() {
            let Some(f) = s.finger else { continue };
            let c = hs.center(i, &self.globals);
            let near = objects
                .iter()
                .enumerate()
                .map(|(k, o)| (k, object_distance(o, c) - s.radius))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((k, d)) = near {
                if d <= CONTACT_DISTANCE {
                    touching[f] = true;
                    touched[f] = Some(k);
                }
            }
        }
        let holds = |o: usize| touched[0] == Some(o) && touched[1..].contains(&Some(o));
        let any = touched.iter().find_map(|t| *t);
        let mut decision = None;
        self.state = match self.state {
            HandState::FreeHand => match any {
                Some(o) if holds(o) => {
                    decision = Some(HandDecision::Attach(o));
                    HandState::SecureGrasp(o)
                }
                Some(o) => HandState::GraspingInProgress(o),
                None => HandState::FreeHand,
            },
            HandState::GraspingInProgress(o) => {
                let o = if touched.contains(&Some(o)) { Some(o) } else { any };
                match o {
                    Some(o) if holds(o) => {
                        decision = Some(HandDecision::Attach(o));
                        HandState::SecureGrasp(o)
                    }
                    Some(o) => HandState::GraspingInProgress(o),
                    None => HandState::FreeHand,
                }
            }
            HandState::SecureGrasp(o) => {
                if holds(o) {
                    HandState::SecureGrasp(o)
                } else {
                    decision = Some(HandDecision::Release(o));
                    match any {
                        Some(k) => HandState::GraspingInProgress(k),
                        None => HandState::FreeHand,
                    }
                }
            }
        };
        Ok(AutomatonOutput {
            values: self.values.clone(),
            state: self.state,
            decision,
            touching,
        })
    }
}
