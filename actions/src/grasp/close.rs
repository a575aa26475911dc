//! Closing fingers against sensors (thesis 4.3.4): the finger DOFs move toward their
//! desired values in small sub-steps; when a sphere sensor would penetrate an obstacle,
//! the DOFs above it in the finger ([`HandSensor::stops`]) go back to their last
//! non-penetrating values and stop, while the other DOFs keep moving.
//!
//! [`HandSensor::stops`]: troupe_body::sensors::HandSensor::stops

use troupe_body::glam::DVec3;
use troupe_body::kinematics::local_transform;
use troupe_body::sensors::{HandSensors, Side};
use troupe_body::{Scope, Skeleton, Transform};

/// A sensor this close to an obstacle (metres) counts as touching it.
pub const CONTACT_DISTANCE: f64 = 0.002;
/// Largest change of one finger DOF per sub-step (radians, 0.4°): a fingertip 10 cm from
/// the joint moves at most 0.7 mm, which bounds how far a sensor can stop short of contact.
pub const MAX_SUBSTEP: f64 = 0.4 * std::f64::consts::PI / 180.0;

/// Signed distance from a world point to whatever the fingers must not penetrate.
pub type Field<'a> = &'a dyn Fn(DVec3) -> f64;

/// A hand's sensors plus what the finger kinematics needs.
#[derive(Clone, Debug)]
pub struct HandModel {
    /// The sensors.
    pub sensors: HandSensors,
    /// The wrist's descendants (finger joints) in topological order.
    pub joints: Vec<usize>,
    /// Wrist to middle fingertip at rest (metres), the size of 4.3.2's table.
    pub length: f64,
}

impl HandModel {
    /// The model of `side`'s hand.
    pub fn new(skeleton: &Skeleton, side: Side) -> crate::error::Result<HandModel> {
        let sensors = HandSensors::new(skeleton, side)?;
        let wrist = sensors.wrist;
        let all = skeleton.joints();
        let mut inside = vec![false; all.len()];
        let mut joints = Vec::new();
        for (j, joint) in all.iter().enumerate() {
            if joint.parent.is_some_and(|p| p == wrist || inside[p]) {
                inside[j] = true;
                joints.push(j);
            }
        }
        // Wrist to the middle fingertip: the chain's offsets plus its end site.
        let p = side.prefix();
        let mut length = DVec3::ZERO;
        for i in 0..=3 {
            let j = skeleton.joint(&format!("{p}middle{i}"))?;
            length += all[j].offset;
            if i == 3 {
                if let Some((_, o)) = skeleton.end_sites().iter().find(|(k, _)| *k == j) {
                    length += *o;
                }
            }
        }
        Ok(HandModel {
            sensors,
            joints,
            length: length.length(),
        })
    }

    /// Recomputes the finger joints' globals from the wrist's (already in `globals`).
    pub fn finger_kinematics(&self, skeleton: &Skeleton, q: &[f64], globals: &mut [Transform]) {
        let all = skeleton.joints();
        for &j in &self.joints {
            if let Some(p) = all[j].parent {
                globals[j] = globals[p].mul(&local_transform(skeleton, j, q));
            }
        }
    }

    /// Distance of every sensor's sphere to the field (negative: penetrating).
    pub fn distances(&self, globals: &[Transform], field: Field, out: &mut Vec<f64>) {
        out.clear();
        for (i, s) in self.sensors.sensors.iter().enumerate() {
            out.push(field(self.sensors.center(i, globals)) - s.radius);
        }
    }

    /// Moves the DOFs of `targets` toward their values, stopping (and adding to `blocked`)
    /// every DOF above a sensor that would penetrate the field. DOFs already in `blocked`
    /// do not move. `q` and `globals` are a full posture and its joint globals (the
    /// wrist's must be current); both are updated.
    pub fn advance(
        &self,
        skeleton: &Skeleton,
        q: &mut [f64],
        globals: &mut [Transform],
        targets: &[(usize, f64)],
        blocked: &mut Scope,
        field: Field,
    ) {
        let mut largest: f64 = 0.0;
        for &(d, v) in targets {
            if !blocked.contains(d) {
                largest = largest.max((v - q[d]).abs());
            }
        }
        if largest <= 0.0 {
            return;
        }
        let n = (largest / MAX_SUBSTEP).ceil().max(1.0) as usize;
        let mut previous: Vec<(usize, f64)> = Vec::with_capacity(targets.len());
        for k in 0..n {
            previous.clear();
            let remaining = (n - k) as f64;
            for &(d, v) in targets {
                if blocked.contains(d) {
                    continue;
                }
                previous.push((d, q[d]));
                q[d] += (v - q[d]) / remaining;
            }
            if previous.is_empty() {
                return;
            }
            // Revert the DOFs above every penetrating sensor; reverting only goes back
            // toward the last checked posture, so a few rounds settle it.
            for _ in 0..8 {
                self.finger_kinematics(skeleton, q, globals);
                let mut reverted = false;
                for (i, s) in self.sensors.sensors.iter().enumerate() {
                    if s.stops.is_empty() {
                        continue;
                    }
                    let c = self.sensors.center(i, globals);
                    if field(c) - s.radius >= 0.0 {
                        continue;
                    }
                    for &(d, old) in &previous {
                        if s.stops.contains(d) && !blocked.contains(d) {
                            q[d] = old;
                            blocked.insert(d);
                            reverted = true;
                        }
                    }
                }
                if !reverted {
                    break;
                }
            }
        }
        self.finger_kinematics(skeleton, q, globals);
    }

    /// For each finger (in [`troupe_body::sensors::FINGERS`] order): whether one of
    /// its sensors is within [`CONTACT_DISTANCE`] of the field.
    pub fn fingers_touching(&self, globals: &[Transform], field: Field) -> [bool; 5] {
        let mut touching = [false; 5];
        for (i, s) in self.sensors.sensors.iter().enumerate() {
            if let Some(f) = s.finger {
                let c = self.sensors.center(i, globals);
                if field(c) - s.radius <= CONTACT_DISTANCE {
                    touching[f] = true;
                }
            }
        }
        touching
    }

    /// For each finger: whether every one of its flexion DOFs is at a joint limit.
    pub fn fingers_at_limit(&self, skeleton: &Skeleton, q: &[f64]) -> [bool; 5] {
        let mut at = [true; 5];
        for (f, finger) in self.sensors.fingers.iter().enumerate() {
            for &d in &finger.dofs {
                let dof = &skeleton.dofs()[d];
                if !dof.name.ends_with("_flexion") {
                    continue;
                }
                if (q[d] - dof.max).abs() > 1e-9 && (q[d] - dof.min).abs() > 1e-9 {
                    at[f] = false;
                }
            }
        }
        at
    }
}
