//! Thesis 6.4.1's anatomical converter: the orientations of sensors on a performer's body
//! (and the position of the root's sensor) become the joint rotations of the template,
//! after a calibration in a known pose; joints without a sensor follow by IK.

use glam::{DMat3, DQuat, DVec3};
use std::collections::BTreeMap;
use std::sync::Arc;
use troupe_body::ik::{IkOptions, IkSolver, IkTask};
use troupe_body::jacobian::Effector;
use troupe_body::kinematics::{forward_kinematics, solve_joint_angles};
use troupe_body::skeleton::{DofKind, Skeleton};
use troupe_body::transform::Transform;

/// A sensor map the template cannot take, or a calibration without every sensor.
#[derive(Debug, thiserror::Error)]
pub enum ConverterError {
    /// The map names a joint the template does not have.
    #[error("no joint '{0}' in the template (e.g. pelvis, sacroiliac, vl5, skullbase, r_shoulder, r_elbow, r_wrist)")]
    UnknownJoint(String),
    /// The map names a joint twice.
    #[error("joint '{0}' is mapped twice")]
    MappedTwice(String),
    /// The IK solver for the joints between sensors cannot be built.
    #[error(transparent)]
    Ik(#[from] troupe_body::Error),
    /// Calibration asked before a mapped bird sent a sample.
    #[error("calibration: no sample from bird {0} yet")]
    NoSample(u8),
}

/// The rotation from the Flock's transmitter frame (X forward, Y right, Z down) to the
/// scene's frame (Y up, an actor facing 0° looks along +Z, its right is −X).
pub fn transmitter_to_world() -> DQuat {
    DQuat::from_mat3(&DMat3::from_cols(DVec3::Z, -DVec3::X, -DVec3::Y))
}

/// Joint-name aliases accepted in a performer's bird map.
fn joint_alias(name: &str) -> &str {
    match name {
        "pelvis" | "root" => "HumanoidRoot",
        "head" => "skullbase",
        other => other,
    }
}

/// Thesis 6.4.1's anatomical converter: sensor orientations (and the root sensor's
/// position) to the joint rotations of the template, after a calibration in a known pose.
pub struct AnatomicalConverter {
    skeleton: Arc<Skeleton>,
    frame: DQuat,
    /// (joint, bird address), joints in increasing index order (parents first).
    map: Vec<(usize, u8)>,
    /// Per map entry: an IK solver over the rotation DOFs of the joints without a sensor
    /// between the entry's joint and its nearest mapped ancestor (e.g. shoulder and elbow
    /// for a wrist sensor under a chest sensor), or `None` when the parent is mapped.
    ik: Vec<Option<IkSolver>>,
    /// The previous conversion's IK DOF values: each solve starts from them (continuity,
    /// and a few iterations instead of a solve from rest).
    warm: Option<Vec<f64>>,
    calibration: Option<Calibration>,
}

#[derive(Clone, Debug)]
struct Calibration {
    /// Transmitter origin in the scene frame, estimated at calibration.
    origin: DVec3,
    /// Per map entry: the joint's origin relative to its sensor, in the sensor's frame.
    levers: Vec<DVec3>,
    base_q: Vec<f64>,
    /// Bird pose (world frame) at calibration, per map entry.
    sensor0: Vec<(DVec3, DQuat)>,
    /// Sensor-to-segment offset per map entry: segment = sensor × offset.
    offsets: Vec<DQuat>,
}

impl AnatomicalConverter {
    /// A converter for `map` (joint name → bird address); errors name unknown joints.
    pub fn new(
        skeleton: Arc<Skeleton>,
        map: &[(String, u8)],
        frame: DQuat,
    ) -> Result<AnatomicalConverter, ConverterError> {
        let mut m = Vec::new();
        for (name, addr) in map {
            let j = skeleton
                .joint(joint_alias(name))
                .map_err(|_| ConverterError::UnknownJoint(name.clone()))?;
            if m.iter().any(|&(jj, _)| jj == j) {
                return Err(ConverterError::MappedTwice(name.clone()));
            }
            m.push((j, *addr));
        }
        m.sort_by_key(|&(j, _)| j);
        let mapped: Vec<usize> = m.iter().map(|&(j, _)| j).collect();
        let mut ik = Vec::with_capacity(m.len());
        for &(j, _) in &m {
            let mut dofs = Vec::new();
            let mut a = skeleton.joints()[j].parent;
            while let Some(p) = a {
                if mapped.contains(&p) {
                    break;
                }
                let joint = &skeleton.joints()[p];
                if joint.parent.is_none() {
                    // The root's DOFs move the whole body: never solved for a limb.
                    break;
                }
                dofs.extend(
                    joint
                        .dofs
                        .clone()
                        .filter(|&d| skeleton.dofs()[d].kind == DofKind::Rotation),
                );
                a = joint.parent;
            }
            ik.push(if dofs.is_empty() {
                None
            } else {
                Some(IkSolver::new(
                    &skeleton,
                    dofs,
                    // Warm-started every frame: a few iterations follow the motion; the
                    // cap bounds a tick's cost when a sensor is out of reach.
                    IkOptions {
                        max_iterations: 30,
                        ..IkOptions::default()
                    },
                )?)
            });
        }
        Ok(AnatomicalConverter {
            skeleton,
            frame,
            map: m,
            ik,
            warm: None,
            calibration: None,
        })
    }

    /// The DOFs the converter writes: each mapped joint's rotations (and the root's
    /// translations), and the DOFs its IK solves for the joints without a sensor.
    pub fn driven_dofs(&self) -> Vec<usize> {
        let sk = &self.skeleton;
        let mut dofs = Vec::new();
        for &(j, _) in &self.map {
            let joint = &sk.joints()[j];
            for d in joint.dofs.clone() {
                if joint.parent.is_some() && sk.dofs()[d].kind == DofKind::Translation {
                    continue;
                }
                dofs.push(d);
            }
        }
        dofs.extend(
            self.ik
                .iter()
                .flatten()
                .flat_map(|s| s.dofs().iter().copied()),
        );
        dofs
    }

    /// Bird addresses the converter needs.
    pub fn birds(&self) -> Vec<u8> {
        self.map.iter().map(|&(_, a)| a).collect()
    }

    /// Whether a calibration has been taken.
    pub fn is_calibrated(&self) -> bool {
        self.calibration.is_some()
    }

    fn world(&self, pose: (DVec3, DQuat)) -> (DVec3, DQuat) {
        (
            self.frame * pose.0,
            (self.frame * pose.1 * self.frame.inverse()).normalize(),
        )
    }

    /// Calibrates: the performer stands in the posture `base_q` (the template's reference
    /// pose at the actor's place) while the birds read `poses`. The sensor-to-segment offset
    /// of each mapped segment is the rotation that takes the sensor's orientation to the
    /// segment's (thesis 6.4.1: "a simple calibration").
    pub fn calibrate(
        &mut self,
        base_q: &[f64],
        poses: &BTreeMap<u8, (DVec3, DQuat)>,
    ) -> Result<(), ConverterError> {
        let mut globals = vec![Transform::IDENTITY; self.skeleton.joints().len()];
        forward_kinematics(&self.skeleton, base_q, &mut globals);
        let mut sensor0 = Vec::new();
        let mut offsets = Vec::new();
        for &(j, addr) in &self.map {
            let pose = poses.get(&addr).ok_or(ConverterError::NoSample(addr))?;
            let (p, q) = self.world(*pose);
            offsets.push(q.inverse() * globals[j].rotation);
            sensor0.push((p, q));
        }
        // Sensors sit close to their joints, so the mean of (joint − sensor) estimates where
        // the transmitter is in the scene; what remains per sensor is its small lever.
        let n = self.map.len().max(1) as f64;
        let origin = self
            .map
            .iter()
            .zip(&sensor0)
            .map(|(&(j, _), s)| globals[j].translation - s.0)
            .sum::<DVec3>()
            / n;
        let levers = self
            .map
            .iter()
            .zip(&sensor0)
            .map(|(&(j, _), s)| s.1.inverse() * (globals[j].translation - (s.0 + origin)))
            .collect();
        self.warm = None;
        self.calibration = Some(Calibration {
            origin,
            levers,
            base_q: base_q.to_vec(),
            sensor0,
            offsets,
        });
        Ok(())
    }

    /// Calibrates for sources that already give segment poses in the scene frame (OSC):
    /// no offset, no lever; the root goes where its pose says.
    pub fn calibrate_direct(&mut self, base_q: &[f64]) {
        let mut globals = vec![Transform::IDENTITY; self.skeleton.joints().len()];
        forward_kinematics(&self.skeleton, base_q, &mut globals);
        let k = self.map.len();
        self.warm = None;
        self.calibration = Some(Calibration {
            origin: DVec3::ZERO,
            levers: vec![DVec3::ZERO; k],
            base_q: base_q.to_vec(),
            sensor0: self
                .map
                .iter()
                .map(|&(j, _)| (globals[j].translation, DQuat::IDENTITY))
                .collect(),
            offsets: vec![DQuat::IDENTITY; k],
        });
    }

    /// Converts the latest bird poses into DOF values: `q` starts from the calibration
    /// posture; the root joint's translation follows its bird's displacement; each mapped
    /// joint's rotation DOFs are solved (parents first) so that its segment has the sensor's
    /// orientation times the offset. Joints without a sensor between a mapped joint and its
    /// nearest mapped ancestor are solved by IK so that the mapped joint reaches its sensor's
    /// position (sensor + lever); other joints keep their calibration values.
    /// Marks the DOFs it set in `mask`. Does nothing before calibration.
    pub fn convert(
        &mut self,
        poses: &BTreeMap<u8, (DVec3, DQuat)>,
        q: &mut [f64],
        mask: &mut [bool],
    ) {
        let Some(cal) = &self.calibration else { return };
        q.copy_from_slice(&cal.base_q);
        let sk = &self.skeleton;
        let mut globals = vec![Transform::IDENTITY; sk.joints().len()];
        for (k, &(j, addr)) in self.map.iter().enumerate() {
            let Some(pose) = poses.get(&addr) else {
                continue;
            };
            let (p, rot) = self.world(*pose);
            let joint = &sk.joints()[j];
            if joint.parent.is_none() {
                // The root follows the bird's displacement since calibration.
                let delta = p - cal.sensor0[k].0;
                for d in joint.dofs.clone() {
                    let dof = &sk.dofs()[d];
                    if dof.kind == DofKind::Translation {
                        q[d] = cal.base_q[d] + dof.axis.dot(delta);
                        mask[d] = true;
                    }
                }
            }
            if let Some(solver) = self.ik[k].as_mut() {
                if let Some(w) = &self.warm {
                    for &d in solver.dofs() {
                        q[d] = w[d];
                    }
                }
                let goal = p + cal.origin + rot * cal.levers[k];
                let task = IkTask::position(
                    Effector {
                        joint: j,
                        point: DVec3::ZERO,
                    },
                    goal,
                );
                if let Err(e) = solver.solve(sk, q, &[task], None, None) {
                    tracing::debug!("performer IK for {}: {e}", joint.name);
                }
                for &d in solver.dofs() {
                    mask[d] = true;
                }
            }
            forward_kinematics(sk, q, &mut globals);
            let target = rot * cal.offsets[k];
            // Rotation DOFs of the joint now, and what they must become:
            // G = X · R(q) and G' = X · R' give R' = R(q) · G⁻¹ · G'.
            let mut r = DQuat::IDENTITY;
            for d in joint.dofs.clone() {
                let dof = &sk.dofs()[d];
                if dof.kind == DofKind::Rotation {
                    r *= DQuat::from_axis_angle(dof.axis, q[d]);
                }
            }
            let wanted = (r * globals[j].rotation.inverse() * target).normalize();
            solve_joint_angles(sk, j, wanted, q);
            for d in joint.dofs.clone() {
                if sk.dofs()[d].kind == DofKind::Rotation {
                    mask[d] = true;
                }
            }
        }
        self.warm = Some(q.to_vec());
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use troupe_body::TemplateParams;

    /// The adult template at its default size.
    pub(crate) fn adult() -> Arc<Skeleton> {
        let t = troupe_body::template("adult").unwrap();
        Arc::new(
            t.instantiate(TemplateParams {
                height: t.default_height,
                mass: t.default_mass,
            })
            .unwrap(),
        )
    }

    #[test]
    fn converter_turns_and_moves_segments_with_their_sensors() {
        let sk = adult();
        let n = sk.dof_count();
        let frame = transmitter_to_world();
        // Transmitter X forward maps to the scene's +Z, Z down to −Y.
        assert!((frame * DVec3::X - DVec3::Z).length() < 1e-12);
        assert!((frame * DVec3::Z + DVec3::Y).length() < 1e-12);
        let map = [("pelvis".to_string(), 1u8), ("skullbase".to_string(), 2u8)];
        let mut c = AnatomicalConverter::new(sk.clone(), &map, frame).unwrap();
        let (p1, q1) = (DVec3::new(0.5, 0.1, 0.2), DQuat::from_rotation_z(0.3));
        let (p2, q2) = (DVec3::new(0.5, 0.1, -0.5), DQuat::from_rotation_x(-0.2));
        let mut poses = BTreeMap::from([(1, (p1, q1)), (2, (p2, q2))]);
        let base = vec![0.0; n];
        c.calibrate(&base, &poses).unwrap();
        let mut g0 = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &base, &mut g0);

        // Unmoved sensors give the calibration posture.
        let (mut q, mut mask) = (vec![1.0; n], vec![false; n]);
        c.convert(&poses, &mut q, &mut mask);
        assert!(
            q.iter().all(|v| v.abs() < 1e-9),
            "calibration pose reproduced"
        );

        // The pelvis bird turns 20° about the transmitter's Z (down) and moves 10 cm
        // forward; the head bird nods 0.15 rad about the transmitter's Y.
        let turn = DQuat::from_rotation_z(0.35);
        let nod = DQuat::from_rotation_y(0.15);
        poses.insert(1, (p1 + DVec3::new(0.1, 0.0, 0.0), turn * q1));
        poses.insert(2, (p2, nod * q2));
        c.convert(&poses, &mut q, &mut mask);
        assert!((q[sk.dof("root_z").unwrap()] - 0.1).abs() < 1e-12);
        assert!(q[sk.dof("root_x").unwrap()].abs() < 1e-12);
        let mut g = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &q, &mut g);
        let w = |r: DQuat| frame * r * frame.inverse();
        let root = sk.joint("HumanoidRoot").unwrap();
        assert!(g[root].rotation.angle_between(w(turn) * g0[root].rotation) < 1e-6);
        // A yaw about the transmitter's down axis is a turn about the scene's −Y.
        assert!((q[sk.dof("root_yaw").unwrap()] + 0.35).abs() < 1e-6);
        let head = sk.joint("skullbase").unwrap();
        assert!(g[head].rotation.angle_between(w(nod) * g0[head].rotation) < 1e-4);
        assert!(mask[sk.dof("root_yaw").unwrap()] && !mask[sk.dof("r_elbow_flexion").unwrap()]);
    }

    #[test]
    fn joints_without_a_sensor_follow_by_ik() {
        let sk = adult();
        let n = sk.dof_count();
        let frame = transmitter_to_world();
        let map = [
            ("pelvis".to_string(), 1u8),
            ("vl5".to_string(), 2u8),
            ("r_wrist".to_string(), 3u8),
        ];
        let mut c = AnatomicalConverter::new(sk.clone(), &map, frame).unwrap();
        let base = vec![0.0; n];
        let mut g0 = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &base, &mut g0);
        // Birds placed at their joints (transmitter 1 m behind the scene origin).
        let to_tx = |p: DVec3| frame.inverse() * (p + DVec3::new(0.0, 0.0, 1.0));
        let mut poses: BTreeMap<u8, (DVec3, DQuat)> = map
            .iter()
            .map(|(name, a)| {
                let j = sk.joint(joint_alias(name)).unwrap();
                (*a, (to_tx(g0[j].translation), DQuat::IDENTITY))
            })
            .collect();
        c.calibrate(&base, &poses).unwrap();
        // The wrist bird rises 15 cm and comes 10 cm forward; nothing else moves.
        let wrist = sk.joint("r_wrist").unwrap();
        let goal = g0[wrist].translation + DVec3::new(0.0, 0.15, 0.10);
        poses.insert(3, (to_tx(goal), DQuat::IDENTITY));
        let (mut q, mut mask) = (vec![0.0; n], vec![false; n]);
        c.convert(&poses, &mut q, &mut mask);
        let mut g = vec![Transform::IDENTITY; sk.joints().len()];
        forward_kinematics(&sk, &q, &mut g);
        assert!(
            (g[wrist].translation - goal).length() < 1e-3,
            "wrist at {} not {}",
            g[wrist].translation,
            goal
        );
        let elbow = sk.dof("r_elbow_flexion").unwrap();
        assert!(mask[elbow] && q[elbow].abs() > 0.05, "the elbow bends (IK)");
        assert!(q[sk.dof("root_x").unwrap()].abs() < 1e-12, "the root stays");
    }

    #[test]
    fn calibration_needs_every_mapped_bird() {
        let sk = adult();
        let mut c = AnatomicalConverter::new(
            sk.clone(),
            &[("pelvis".into(), 1), ("r_wrist".into(), 2)],
            DQuat::IDENTITY,
        )
        .unwrap();
        let poses = BTreeMap::from([(1, (DVec3::ZERO, DQuat::IDENTITY))]);
        let e = c.calibrate(&vec![0.0; sk.dof_count()], &poses).unwrap_err();
        assert!(e.to_string().contains("bird 2"), "{e}");
        assert!(
            AnatomicalConverter::new(sk, &[("tail".into(), 1)], DQuat::IDENTITY)
                .map(|_| ())
                .unwrap_err()
                .to_string()
                .contains("'tail'")
        );
    }
}
