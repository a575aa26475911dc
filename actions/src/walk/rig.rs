//! What the walking motor needs to know about a body, read once from its skeleton: DOF
//! indices and axis signs, segment lengths, the thigh height Ht (thesis 2.6) and the foot
//! geometry; and the analytic leg inverse kinematics that puts an ankle where the foot
//! placement wants it (the "foot placement correction with IK" of the walking issue).
//!
//! The leg IK is closed-form (law of cosines for the knee, then the hip's flexion and
//! abduction, then the ankle and subtalar from the wanted foot orientation): it is exact
//! whenever the target is within reach, costs a few dozen flops and never allocates, which
//! the crowd benchmark needs; the general Jacobian solver of `troupe_body::ik` would
//! iterate for the same answer.

use crate::error::{ActionError, Result};
use troupe_body::glam::{DQuat, DVec2, DVec3};
use troupe_body::kinematics::forward_kinematics;
use troupe_body::{Skeleton, Transform};

/// One leg's DOFs, axis signs and geometry.
#[derive(Clone, Debug)]
pub struct Leg {
    /// DOF indices: hip flexion, abduction, twist, knee, ankle, subtalar, metatarsal.
    pub dofs: [usize; 7],
    /// Sign of each DOF's axis along the axis the IK rotates about (+X, +Z, +Y, +X, +X,
    /// +Z, +X): a DOF value is the rotation about that axis times its sign.
    signs: [f64; 7],
    /// Hip joint offset in the pelvis (sacroiliac) frame.
    pub hip_offset: DVec3,
    /// Hip → knee length.
    pub thigh: f64,
    /// Knee → ankle length.
    pub shank: f64,
    /// The thigh solid's radius at the hip and at the knee.
    pub thigh_radii: [f64; 2],
    /// Floor-projected foot points relative to the point under the ankle, in the foot's
    /// frame (x left, z forward): the heel on the floor.
    pub heel: DVec3,
    /// The metatarsal (ball) joint relative to the point under the ankle.
    pub ball: DVec3,
    /// The toe tip on the sole, relative to the metatarsal joint (toes frame).
    pub toe_sole: DVec3,
    /// Joint indices: ankle, metatarsal (for measurements).
    pub joints: [usize; 2],
    /// Each DOF's limits (lower, upper), in [`Leg::dofs`] order.
    pub limits: [(f64, f64); 7],
    /// Where the foot's own joint (the subtalar, parent of the metatarsal) sits in the
    /// ankle joint's frame: below the ankle, so it swings sideways as the shank leans.
    pub subtalar: DVec3,
}

/// The body as the walking motor sees it.
#[derive(Clone, Debug)]
pub struct Rig {
    /// Root DOFs: x, y, z, yaw, pitch, roll.
    pub root: [usize; 6],
    /// Rest position of the root joint (its DOFs at zero).
    pub root_rest: DVec3,
    /// Pelvis DOFs: tilt, obliquity, rotation; and their axis signs (+X, +Z, +Y).
    pub pelvis: [usize; 3],
    pelvis_signs: [f64; 3],
    /// Sacroiliac offset from the root joint.
    sacro_offset: DVec3,
    /// Left leg, right leg.
    pub legs: [Leg; 2],
    /// Spine DOFs: vl5 flexion, vt12 torsion, vt6 torsion, vl5 lateral bend.
    pub spine: [usize; 4],
    /// Per arm (left, right): shoulder flexion, shoulder abduction, elbow flexion,
    /// shoulder twist.
    pub arms: [[usize; 4]; 2],
    /// Per arm (left, right), the DOFs that only a carrying arm moves (see [`super::carry`]):
    /// the clavicle's elevation and protraction, the forearm's pronation, the wrist's
    /// flexion and deviation.
    pub carrying_arms: [[usize; 5]; 2],
    /// Thigh height Ht: from the hip's flexion axis to the sole, standing (thesis 2.6).
    pub thigh_height: f64,
    /// Height of the ankle joint above the sole.
    pub ankle_height: f64,
    /// Half the distance between the hip joints.
    pub hip_half_width: f64,
}

/// The sign of `axis` along `unit`, or an error when it is not (anti)parallel to it.
fn sign_along(skeleton: &Skeleton, dof: usize, unit: DVec3) -> Result<f64> {
    let d = &skeleton.dofs()[dof];
    let c = d.axis.dot(unit);
    if (c.abs() - 1.0).abs() > 1e-9 {
        return Err(ActionError::Unfit(format!(
            "DOF `{}` turns about {} where the walking motor expects ±{unit}: not a humanoid template leg",
            d.name, d.axis
        )));
    }
    Ok(c.signum())
}

impl Rig {
    /// Reads a humanoid template skeleton (the `adult` or `child` of
    /// `troupe_body::template`, any size).
    pub fn new(skeleton: &Skeleton) -> Result<Rig> {
        let d = |n: &str| skeleton.dof(n);
        let j = |n: &str| skeleton.joint(n);
        let mut rest = vec![Transform::IDENTITY; skeleton.joints().len()];
        forward_kinematics(skeleton, &vec![0.0; skeleton.dof_count()], &mut rest);
        let root_joint = j("HumanoidRoot")?;
        let sacro = j("sacroiliac")?;
        let joints = skeleton.joints();
        let mut legs = Vec::with_capacity(2);
        for s in ["l_", "r_"] {
            let n = |x: &str| format!("{s}{x}");
            let dofs = [
                d(&n("hip_flexion"))?,
                d(&n("hip_abduction"))?,
                d(&n("hip_twist"))?,
                d(&n("knee_flexion"))?,
                d(&n("ankle_flexion"))?,
                d(&n("subtalar_inversion"))?,
                d(&n("metatarsal_flexion"))?,
            ];
            let units = [
                DVec3::X,
                DVec3::Z,
                DVec3::Y,
                DVec3::X,
                DVec3::X,
                DVec3::Z,
                DVec3::X,
            ];
            let mut signs = [0.0; 7];
            for i in 0..7 {
                signs[i] = sign_along(skeleton, dofs[i], units[i])?;
            }
            let (hip, knee, ankle, mt) = (
                j(&n("hip"))?,
                j(&n("knee"))?,
                j(&n("ankle"))?,
                j(&n("metatarsal"))?,
            );
            let thigh_v = joints[knee].offset;
            let shank_v = joints[ankle].offset;
            for (what, v) in [("thigh", thigh_v), ("shank", shank_v)] {
                if v.x.abs() > 1e-9 || v.z.abs() > 1e-9 || v.y >= 0.0 {
                    return Err(ActionError::Unfit(format!(
                        "the {s}{what} does not hang straight down at rest: not a humanoid template leg"
                    )));
                }
            }
            let ankle_rest = rest[ankle].translation;
            let mt_rest = rest[mt].translation;
            let under_ankle = DVec3::new(ankle_rest.x, 0.0, ankle_rest.z);
            let ball = mt_rest - under_ankle;
            // The heel: the back end of the foot solid on the floor (the template's foot
            // frustum runs from the heel to the toes along +Z).
            let heel_z = skeleton
                .solids()
                .iter()
                .find(|(_, solid)| solid.name == n("foot"))
                .and_then(|(jj, solid)| match solid.shape {
                    troupe_body::Shape::Frustum { height, .. } => {
                        Some(rest[*jj].transform_point(solid.center).z - height / 2.0)
                    }
                    _ => None,
                })
                .unwrap_or(-0.3 * ball.z);
            let thigh_radii = skeleton
                .solids()
                .iter()
                .find(|(_, solid)| solid.name == n("thigh"))
                .and_then(|(_, solid)| match solid.shape {
                    // The frustum stands along the thigh: its top at the hip.
                    troupe_body::Shape::Frustum {
                        bottom_radius,
                        top_radius,
                        ..
                    } => Some([top_radius, bottom_radius]),
                    _ => None,
                })
                // A template whose thigh is not a frustum: a 1.75 m adult's.
                .unwrap_or([0.08, 0.053]);
            let tip = skeleton
                .end_sites()
                .iter()
                .find(|(jj, _)| *jj == mt)
                .map(|(_, o)| *o)
                .unwrap_or(DVec3::new(0.0, 0.0, 0.03));
            legs.push(Leg {
                dofs,
                signs,
                hip_offset: joints[hip].offset,
                thigh: thigh_v.length(),
                shank: shank_v.length(),
                thigh_radii,
                heel: DVec3::new(0.0, 0.0, heel_z - ankle_rest.z),
                ball,
                toe_sole: DVec3::new(tip.x, -mt_rest.y, tip.z),
                joints: [ankle, mt],
                limits: dofs.map(|dof| skeleton.limits()[dof]),
                subtalar: match joints[mt].parent {
                    Some(p) if p != ankle => joints[p].offset,
                    _ => DVec3::ZERO,
                },
            });
        }
        let pelvis = [
            d("sacroiliac_tilt")?,
            d("sacroiliac_obliquity")?,
            d("sacroiliac_rotation")?,
        ];
        let pelvis_signs = [
            sign_along(skeleton, pelvis[0], DVec3::X)?,
            sign_along(skeleton, pelvis[1], DVec3::Z)?,
            sign_along(skeleton, pelvis[2], DVec3::Y)?,
        ];
        let l_hip = rest[j("l_hip")?].translation;
        let r_hip = rest[j("r_hip")?].translation;
        let l_ankle = rest[j("l_ankle")?].translation;
        let right = legs.pop().expect("two legs");
        let left = legs.pop().expect("two legs");
        Ok(Rig {
            root: [
                d("root_x")?,
                d("root_y")?,
                d("root_z")?,
                d("root_yaw")?,
                d("root_pitch")?,
                d("root_roll")?,
            ],
            root_rest: joints[root_joint].offset,
            pelvis,
            pelvis_signs,
            sacro_offset: joints[sacro].offset,
            legs: [left, right],
            spine: [
                d("vl5_flexion")?,
                d("vt12_torsion")?,
                d("vt6_torsion")?,
                d("vl5_lateral_bend")?,
            ],
            arms: [
                [
                    d("l_shoulder_flexion")?,
                    d("l_shoulder_abduction")?,
                    d("l_elbow_flexion")?,
                    d("l_shoulder_twist")?,
                ],
                [
                    d("r_shoulder_flexion")?,
                    d("r_shoulder_abduction")?,
                    d("r_elbow_flexion")?,
                    d("r_shoulder_twist")?,
                ],
            ],
            carrying_arms: [
                [
                    d("l_sternoclavicular_elevation")?,
                    d("l_sternoclavicular_protraction")?,
                    d("l_elbow_pronation")?,
                    d("l_wrist_flexion")?,
                    d("l_wrist_deviation")?,
                ],
                [
                    d("r_sternoclavicular_elevation")?,
                    d("r_sternoclavicular_protraction")?,
                    d("r_elbow_pronation")?,
                    d("r_wrist_flexion")?,
                    d("r_wrist_deviation")?,
                ],
            ],
            thigh_height: 0.5 * (l_hip.y + r_hip.y),
            ankle_height: l_ankle.y,
            hip_half_width: 0.5 * (l_hip.x - r_hip.x).abs(),
        })
    }

    /// Every DOF the motor writes.
    pub fn dofs(&self, arms: bool) -> Vec<usize> {
        let mut v: Vec<usize> = self.root.to_vec();
        v.extend(self.pelvis);
        for leg in &self.legs {
            v.extend(leg.dofs);
        }
        v.extend(self.spine);
        if arms {
            for a in &self.arms {
                v.extend(a);
            }
            for a in &self.carrying_arms {
                v.extend(a);
            }
        }
        v
    }

    /// The world rotation of the pelvis (sacroiliac frame) for a root heading and the
    /// pelvis angles (tilt, obliquity, rotation as DOF values).
    pub fn pelvis_rotation(&self, heading: f64, pelvis: [f64; 3]) -> DQuat {
        let s = self.pelvis_signs;
        DQuat::from_rotation_y(heading)
            * DQuat::from_rotation_x(pelvis[0] * s[0])
            * DQuat::from_rotation_z(pelvis[1] * s[1])
            * DQuat::from_rotation_y(pelvis[2] * s[2])
    }

    /// World position of a hip joint for the root at `root` (world position of the root
    /// joint) with the pelvis at world rotation `pelvis` (heading included).
    pub fn hip_position(&self, leg: usize, root: DVec3, heading: f64, pelvis: DQuat) -> DVec3 {
        root + DQuat::from_rotation_y(heading) * self.sacro_offset
            + pelvis * self.legs[leg].hip_offset
    }

    /// World position of the knee of `leg` at DOF `values` (in [`Leg::dofs`] order), its
    /// hip at `hip` under the pelvis' world rotation `pelvis`: the thigh hangs straight
    /// down at rest (checked by [`Rig::new`]).
    pub fn knee_position(&self, leg: usize, pelvis: DQuat, hip: DVec3, values: &[f64; 7]) -> DVec3 {
        hip + self.thigh_rotation(leg, pelvis, values) * DVec3::new(0.0, -self.legs[leg].thigh, 0.0)
    }

    /// The thigh's world rotation for `leg` at DOF `values` (in [`Leg::dofs`] order) under
    /// the pelvis' world rotation `pelvis`: the hip's flexion, abduction and twist.
    fn thigh_rotation(&self, leg: usize, pelvis: DQuat, values: &[f64; 7]) -> DQuat {
        let l = &self.legs[leg];
        let a = |i: usize| values[i] * l.signs[i];
        pelvis
            * DQuat::from_rotation_x(a(0))
            * DQuat::from_rotation_z(a(1))
            * DQuat::from_rotation_y(a(2))
    }

    /// The heading and pitch (toes up positive, as [`Rig::ankle_from_plant`] takes them)
    /// of a foot whose ankle joint has the world frame `ankle`.
    pub fn foot_heading_pitch(ankle: &Transform) -> (f64, f64) {
        let fwd = ankle.rotation * DVec3::Z;
        (fwd.x.atan2(fwd.z), fwd.y.atan2(fwd.x.hypot(fwd.z)))
    }

    /// The floor point (x, z, and the floor's height) a foot of `leg` with its ankle
    /// joint at `ankle`, heading `yaw` and pitch `pitch`, is planted at: under the ankle
    /// of the foot put flat, its heel or ball where it is (see [`Rig::ankle_from_plant`]).
    pub fn plant_under(&self, leg: usize, ankle: DVec3, yaw: f64, pitch: f64) -> DVec3 {
        ankle - self.ankle_from_plant(leg, DVec2::ZERO, yaw, pitch)
    }

    /// World position of the ankle joint of a foot planted at floor point `plant` (under
    /// the ankle when flat) with heading `yaw` and pitch `pitch` (toes up positive): a
    /// positive pitch rolls about the heel (heel strike), a negative one about the ball
    /// joint (heel off), so the contact point stays where it is.
    pub fn ankle_from_plant(&self, leg: usize, plant: DVec2, yaw: f64, pitch: f64) -> DVec3 {
        let l = &self.legs[leg];
        let ankle = DVec3::new(0.0, self.ankle_height, 0.0);
        let pivot = if pitch >= 0.0 { l.heel } else { l.ball };
        let r = DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(-pitch);
        DVec3::new(plant.x, 0.0, plant.y)
            + DQuat::from_rotation_y(yaw) * pivot
            + r * (ankle - pivot)
    }

    /// Height of the foot's lowest sole point (heel, ball or toe tip) below the ankle
    /// joint, for a foot at pitch `pitch` with the toes at `toes` (negative: below).
    pub fn lowest_offset(&self, leg: usize, pitch: f64, toes: f64) -> f64 {
        let l = &self.legs[leg];
        let ya = self.ankle_height;
        let (sp, cp) = pitch.sin_cos();
        // y of Rx(−pitch)·v.
        let y = |v: DVec3| v.y * cp + v.z * sp;
        let heel = DVec3::new(0.0, -ya, l.heel.z);
        let ball = DVec3::new(l.ball.x, -ya, l.ball.z);
        let toe = l.ball - DVec3::new(0.0, ya, 0.0) + DQuat::from_rotation_x(toes) * l.toe_sole;
        y(heel).min(y(ball)).min(y(toe))
    }

    /// How far (world) to move the ankle target of `leg` so that its foot stays where
    /// [`Rig::ankle_from_plant`] puts it, for the leg at DOF `values` (in [`Leg::dofs`]
    /// order) under the pelvis' world rotation `pelvis`: the foot hangs from its subtalar
    /// joint, which sits below the ankle in the shank's frame, whereas the plant is
    /// measured as if it turned with the foot. As the shank leans sideways over a planted
    /// foot (a sidestep), the difference creeps by millimetres.
    pub fn subtalar_shift(&self, leg: usize, pelvis: DQuat, values: &[f64; 7]) -> DVec3 {
        let l = &self.legs[leg];
        let a = |i: usize| values[i] * l.signs[i];
        let ankle = self.thigh_rotation(leg, pelvis, values)
            * DQuat::from_rotation_x(a(3))
            * DQuat::from_rotation_x(a(4));
        let foot = ankle * DQuat::from_rotation_z(a(5));
        foot * l.subtalar - ankle * l.subtalar
    }

    /// The leg's DOF values that put its ankle at `ankle` with the foot at heading `yaw`
    /// and pitch `pitch` and the toes at `toes` (rotation about the foot's +X, as the
    /// pitch), given the pelvis world rotation and the hip's world position. Returns the
    /// values (in [`Leg::dofs`] order) and how far the ankle stays from its target (zero
    /// when it is within reach). `twist_guess`, the hip twist DOF value of the previous
    /// tick, makes the twist iteration converge in one or two passes.
    #[allow(clippy::too_many_arguments)]
    pub fn solve_leg(
        &self,
        leg: usize,
        pelvis: DQuat,
        pelvis_yaw: f64,
        twist_guess: Option<f64>,
        hip: DVec3,
        ankle: DVec3,
        (yaw, pitch, toes): (f64, f64, f64),
    ) -> ([f64; 7], f64) {
        let l = &self.legs[leg];
        let (l1, l2) = (l.thigh, l.shank);
        let inv = pelvis.inverse();
        let mut d = inv * (ankle - hip);
        let reach = l1 + l2;
        let dist = d.length();
        let mut miss = 0.0;
        if dist > reach {
            miss = dist - reach;
            d *= reach / dist;
        }
        let dist = d.length().max(1e-9);
        // Knee: law of cosines (0 = straight).
        let c = ((dist * dist - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)).clamp(-1.0, 1.0);
        let kappa = c.acos();
        // Hip twist turns the foot toward its heading (the ankle has no yaw): start from
        // the heading difference, then correct by the yaw the foot still misses (the hip's
        // flexion and abduction couple into yaw), a few Newton-like passes.
        let mut gamma = match twist_guess {
            Some(g) => g * l.signs[2],
            None => super::route::wrap(yaw - pelvis_yaw),
        }
        .clamp(-0.75, 0.75);
        let foot = DQuat::from_rotation_y(yaw) * DQuat::from_rotation_x(-pitch);
        let want = foot * DVec3::Z;
        // What the passes share: the ankle in the thigh's frame with the knee bent, the
        // way to the ankle and the foot's wanted heading. The compiler takes the knee's
        // sine and cosine out of the loop itself, but not an `atan2`: found here, the
        // crowd benchmark makes a fifth fewer of them.
        let v = DVec3::new(0.0, -l1 - l2 * kappa.cos(), -l2 * kappa.sin());
        let towards_ankle = d.z.atan2(d.y);
        let want_heading = want.x.atan2(want.z);
        let (mut alpha, mut beta, mut delta, mut eps) = (0.0, 0.0, 0.0, 0.0);
        let mut prev: Option<(f64, f64)> = None;
        for pass in 0..6 {
            let w = DQuat::from_rotation_y(gamma) * v;
            // Abduction about +Z: bring w's x onto d's x.
            let r = w.x.hypot(w.y);
            let phi = w.y.atan2(w.x);
            beta = super::route::wrap(-(d.x / r).clamp(-1.0, 1.0).acos() - phi);
            let (sb, cb) = beta.sin_cos();
            let y1 = w.x * sb + w.y * cb;
            let z1 = w.z;
            // Flexion about +X: turn (y1, z1) onto (d.y, d.z).
            alpha = super::route::wrap(towards_ankle - z1.atan2(y1));
            let shank = pelvis
                * DQuat::from_rotation_x(alpha)
                * DQuat::from_rotation_z(beta)
                * DQuat::from_rotation_y(gamma)
                * DQuat::from_rotation_x(kappa);
            let rel = shank.inverse() * foot;
            let f = rel * DVec3::Z;
            delta = (-f.y).atan2(f.z);
            let u = DQuat::from_rotation_x(-delta) * (rel * DVec3::Y);
            eps = (-u.x).atan2(u.y);
            // Where the foot really points with these angles, against where it should.
            let got =
                shank * DQuat::from_rotation_x(delta) * DQuat::from_rotation_z(eps) * DVec3::Z;
            let err = super::route::wrap(want_heading - got.x.atan2(got.z));
            // The last pass keeps the twist its angles were solved with.
            if err.abs() < 1e-6 || pass == 5 {
                break;
            }
            // Secant step on err(γ) (its slope is near 1: the twist turns the foot),
            // so a warm start converges in two or three passes.
            let slope = match prev {
                Some((g0, e0)) if (gamma - g0).abs() > 1e-12 => {
                    let m: f64 = (e0 - err) / (gamma - g0);
                    if m.abs() > 0.2 {
                        m
                    } else {
                        1.0
                    }
                }
                _ => 1.0,
            };
            prev = Some((gamma, err));
            let next = (gamma + err / slope).clamp(-0.75, 0.75);
            // A twist held at its bound (the foot turned further than the hip twists)
            // stays there: the passes left would solve the same angles again.
            if next == gamma {
                break;
            }
            gamma = next;
        }
        let s = l.signs;
        (
            [
                alpha * s[0],
                beta * s[1],
                gamma * s[2],
                kappa * s[3],
                delta * s[4],
                eps * s[5],
                toes * s[6],
            ],
            miss,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::template::default_skeleton;

    #[test]
    fn leg_ik_puts_the_ankle_and_the_foot_where_asked() {
        let skeleton = default_skeleton("adult").unwrap();
        let rig = Rig::new(&skeleton).unwrap();
        let mut q = vec![0.0; skeleton.dof_count()];
        let mut g = vec![Transform::IDENTITY; skeleton.joints().len()];
        let heading = 0.4;
        let pelvis_angles = [0.05, -0.04, 0.08];
        q[rig.root[1]] = -0.08;
        q[rig.root[3]] = heading;
        for i in 0..3 {
            q[rig.pelvis[i]] = pelvis_angles[i];
        }
        let pelvis = rig.pelvis_rotation(heading, pelvis_angles);
        let root = rig.root_rest + DVec3::new(0.0, -0.08, 0.0);
        for (leg, side) in [(0usize, 1.0), (1, -1.0)] {
            let hip = rig.hip_position(leg, root, heading, pelvis);
            let plant = DVec2::new(0.1 * side + 0.05, 0.15);
            for pitch in [0.2, 0.0, -0.4] {
                let yaw = heading + 0.1;
                let target = rig.ankle_from_plant(leg, plant, yaw, pitch);
                let (vals, miss) = rig.solve_leg(
                    leg,
                    pelvis,
                    heading + 0.08,
                    None,
                    hip,
                    target,
                    (yaw, pitch, 0.0),
                );
                assert_eq!(miss, 0.0);
                for (i, &dof) in rig.legs[leg].dofs.iter().enumerate() {
                    q[dof] = vals[i];
                }
                forward_kinematics(&skeleton, &q, &mut g);
                let got = g[rig.legs[leg].joints[0]].translation;
                assert!(
                    (got - target).length() < 1e-9,
                    "leg {leg} pitch {pitch}: {got} vs {target}"
                );
                let knee = g[skeleton.joint(["l_knee", "r_knee"][leg]).unwrap()].translation;
                let said = rig.knee_position(leg, pelvis, hip, &vals);
                assert!((said - knee).length() < 1e-9, "knee {said} vs {knee}");
                // The foot's forward direction has the wanted pitch.
                let fwd = g[rig.legs[leg].joints[0]].rotation * DVec3::Z;
                let got_pitch = fwd.y.atan2(fwd.x.hypot(fwd.z));
                assert!(
                    (got_pitch - pitch).abs() < 0.02,
                    "pitch {got_pitch} vs {pitch}"
                );
            }
        }
    }

    #[test]
    fn the_subtalar_shift_keeps_a_planted_foot_put_as_the_shank_leans() {
        let skeleton = default_skeleton("adult").unwrap();
        let rig = Rig::new(&skeleton).unwrap();
        let mut q = vec![0.0; skeleton.dof_count()];
        let mut g = vec![Transform::IDENTITY; skeleton.joints().len()];
        let leg = 0;
        let subtalar = skeleton.joints()[rig.legs[leg].joints[1]].parent.unwrap();
        let plant = DVec2::new(0.09, 0.1);
        let ankle = rig.ankle_from_plant(leg, plant, 0.0, 0.0);
        // Where the foot's joint is when the foot stands at `plant`, the leg upright.
        let wanted = ankle + rig.legs[leg].subtalar;
        // The body sidestepped 0.15 m: the shank leans over the planted foot.
        let pelvis = rig.pelvis_rotation(0.0, [0.0; 3]);
        let root = rig.root_rest + DVec3::new(-0.15, -0.03, 0.0);
        q[rig.root[0]] = -0.15;
        q[rig.root[1]] = -0.03;
        let hip = rig.hip_position(leg, root, 0.0, pelvis);
        let solve = |target: DVec3| {
            rig.solve_leg(leg, pelvis, 0.0, None, hip, target, (0.0, 0.0, 0.0))
                .0
        };
        let foot_at = |values: [f64; 7], q: &mut Vec<f64>, g: &mut Vec<Transform>| {
            for (i, &dof) in rig.legs[leg].dofs.iter().enumerate() {
                q[dof] = values[i];
            }
            forward_kinematics(&skeleton, q, g);
            g[subtalar].translation
        };
        let plain = solve(ankle);
        let drift = (foot_at(plain, &mut q, &mut g) - wanted).length();
        let shifted = solve(ankle + rig.subtalar_shift(leg, pelvis, &plain));
        let kept = (foot_at(shifted, &mut q, &mut g) - wanted).length();
        assert!(drift > 5e-4, "the lean moves the foot: {drift}");
        assert!(
            kept < 0.2 * drift,
            "the shift keeps it: {kept} (without: {drift})"
        );
    }

    #[test]
    fn thigh_height_is_53_percent_of_the_body() {
        let skeleton = default_skeleton("adult").unwrap();
        let rig = Rig::new(&skeleton).unwrap();
        assert!(
            (rig.thigh_height / 1.75 - 0.53).abs() < 0.005,
            "{}",
            rig.thigh_height
        );
    }
}
