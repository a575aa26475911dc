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
//! | `SecureGrasp(o)` | the thumb or every other finger is more than [`RELEASE_DISTANCE`] from `o` (the hand opens) | `GraspingInProgress` or `FreeHand` | release `o` |
//!
//! The caller applies the decisions (for a scene: [`troupe_scene::holding::HoldRequest`]
//! `Attach`/`Release` through its generator's writer, or [`troupe_scene::Scene::request_hold`]).

use super::close::{HandModel, CONTACT_DISTANCE};

/// A secure grasp is released only when the thumb, or every other finger, has moved this
/// far from the object (metres): hysteresis, so fingers sliding on the surface while the
/// glove keeps closing do not release and re-attach the object.
pub const RELEASE_DISTANCE: f64 = 0.006;
use troupe_body::glam::DVec3;
use troupe_body::sensors::{object_distance, Side};
use troupe_body::{Scope, Skeleton, Transform};
use troupe_scene::Object;

/// The automaton's states: the scene's blackboard carries them for scripts and observers.
pub use troupe_scene::HandState;

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
    pub fn new(skeleton: &Skeleton, side: Side, q: &[f64]) -> crate::error::Result<GraspAutomaton> {
        if q.len() != skeleton.dof_count() {
            return Err(crate::error::ActionError::Unfit(format!(
                "grasp automaton: posture has {} values, the skeleton {} DOFs",
                q.len(),
                skeleton.dof_count()
            )));
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
    ) -> crate::error::Result<AutomatonOutput> {
        if posture.len() != self.q.len() || globals.len() != skeleton.joints().len() {
            return Err(crate::error::ActionError::Unfit(
                "grasp automaton: posture or globals do not match the skeleton".into(),
            ));
        }
        self.targets.clear();
        for &(d, v) in desired {
            if !self.model.sensors.scope.contains(d) {
                return Err(crate::error::ActionError::Unfit(format!(
                    "grasp automaton: DOF #{d} is not a finger DOF of the {} hand",
                    self.model.sensors.side.name()
                )));
            }
            if !v.is_finite() {
                return Err(crate::error::ActionError::Unfit(format!(
                    "grasp automaton: desired value of `{}` is not finite",
                    skeleton.dofs()[d].name
                )));
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
                let o = if touched.contains(&Some(o)) {
                    Some(o)
                } else {
                    any
                };
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
                // Per finger: within the release distance of the held object.
                let mut near = [false; 5];
                if let Some(obj) = objects.get(o) {
                    for (i, s) in hs.sensors.iter().enumerate() {
                        if let Some(f) = s.finger {
                            let c = hs.center(i, &self.globals);
                            if object_distance(obj, c) - s.radius <= RELEASE_DISTANCE {
                                near[f] = true;
                            }
                        }
                    }
                }
                if near[0] && near[1..].contains(&true) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::template::default_skeleton;
    use troupe_body::{ActorState, Shape};

    /// A ball in front of the right palm, and the hand's posture.
    fn setup(radius: f64) -> (Skeleton, ActorState, Object, GraspAutomaton) {
        let skel = default_skeleton("adult").unwrap();
        let state = ActorState::new(&skel, vec![0.0; skel.dof_count()]);
        let a = GraspAutomaton::new(&skel, Side::Right, &state.q).unwrap();
        let hs = &a.model().sensors;
        let w = state.globals[hs.wrist];
        let palm = w.transform_point(hs.palm);
        let n = w.rotation * hs.palm_normal;
        let palm_r = hs.sensors.last().unwrap().radius;
        let ball = troupe_scene::Scene::object(
            "ball",
            Shape::Sphere { radius },
            // Toward the wrist and the thumb side, where the thumb can oppose the fingers.
            palm + n * (palm_r + radius + 0.004) - w.rotation * hs.finger_direction * 0.035
                + w.rotation * DVec3::Z * 0.03,
            0.2,
        );
        (skel, state, ball, a)
    }

    /// Synthetic glove: every finger DOF of the hand at fraction `k` of its upper limit.
    fn glove(skel: &Skeleton, a: &GraspAutomaton, k: f64) -> Vec<(usize, f64)> {
        a.model()
            .sensors
            .scope
            .iter()
            .map(|d| (d, k * skel.dofs()[d].max))
            .collect()
    }

    #[test]
    fn closing_glove_grasps_securely_without_penetration_and_opening_releases() {
        let (skel, state, ball, mut a) = setup(0.03);
        let objects = [ball];
        let mut seen = vec![a.state()];
        let mut decisions = Vec::new();
        for tick in 0..=100 {
            let k = tick as f64 / 100.0;
            let out = a
                .update(
                    &skel,
                    &state.q,
                    &state.globals,
                    &glove(&skel, &a, k),
                    &objects,
                )
                .unwrap();
            if *seen.last().unwrap() != out.state {
                seen.push(out.state);
            }
            decisions.extend(out.decision);
            // No sensor inside the ball by more than 2 mm.
            let mut q = state.q.clone();
            for &(d, v) in &out.values {
                q[d] = v;
            }
            let mut g = state.globals.clone();
            a.model().finger_kinematics(&skel, &q, &mut g);
            for i in 0..a.model().sensors.sensors.len() {
                let d = a.model().sensors.distance_to_object(i, &g, &objects[0]);
                assert!(d >= -0.002, "tick {tick}: sensor {i} penetrates {d}");
            }
        }
        assert_eq!(
            seen,
            vec![
                HandState::FreeHand,
                HandState::GraspingInProgress(0),
                HandState::SecureGrasp(0)
            ]
        );
        assert_eq!(decisions, vec![HandDecision::Attach(0)]);
        // The glove closes to a full fist, but the fingers stopped on the ball.
        let closed = a
            .update(
                &skel,
                &state.q,
                &state.globals,
                &glove(&skel, &a, 1.0),
                &objects,
            )
            .unwrap();
        assert!(closed.touching[0] && closed.touching[1..].iter().any(|t| *t));
        // Opening the glove releases the ball and frees the hand.
        let mut last = None;
        for tick in 0..=50 {
            let k = 1.0 - tick as f64 / 50.0;
            let out = a
                .update(
                    &skel,
                    &state.q,
                    &state.globals,
                    &glove(&skel, &a, k),
                    &objects,
                )
                .unwrap();
            if let Some(d) = out.decision {
                assert_eq!(d, HandDecision::Release(0));
                last = Some(d);
            }
        }
        assert_eq!(last, Some(HandDecision::Release(0)));
        assert_eq!(a.state(), HandState::FreeHand);
    }

    #[test]
    fn glove_far_from_objects_follows_exactly() {
        let (skel, state, mut ball, mut a) = setup(0.035);
        ball.position += DVec3::new(0.0, 0.0, 2.0);
        let want = glove(&skel, &a, 0.7);
        let out = a
            .update(&skel, &state.q, &state.globals, &want, &[ball])
            .unwrap();
        assert_eq!(out.state, HandState::FreeHand);
        for (d, v) in want {
            let got = out.values.iter().find(|x| x.0 == d).unwrap().1;
            assert!((got - v).abs() < 1e-12);
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let (skel, state, ball, mut a) = setup(0.035);
        let elbow = skel.dof("r_elbow_flexion").unwrap();
        let e = a
            .update(
                &skel,
                &state.q,
                &state.globals,
                &[(elbow, 0.1)],
                std::slice::from_ref(&ball),
            )
            .unwrap_err();
        assert!(
            e.to_string().contains("not a finger DOF of the right hand"),
            "{e}"
        );
        let d = a.model().sensors.scope.iter().next().unwrap();
        let e = a
            .update(&skel, &state.q, &state.globals, &[(d, f64::NAN)], &[ball])
            .unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
    }
}
