//! Self-collision detection and response (thesis 4.6.2).
//!
//! **Detection**: sphere sensors at the elbows, hands, knees, ankles and feet (the ten of
//! figure 4-19) are tested against the body's solids, except those of their own limb.
//! For the special case of figure 4-20 — neither sensor touches, but the segment between
//! two related sensors crosses the body — the forearm (elbow–hand) and the shank
//! (knee–ankle) are also sampled at a quarter, half and three quarters of their length.
//!
//! **Response** (table 4-1): for every penetrating sensor on the chain being solved, a
//! response vector `v` along the solid's outward normal (depth + margin) is turned into a
//! joint-space step with the sub-chain's Jacobian, `Δz = J'⁺ Δz'` (eq. 4-2), and used as
//! the secondary task of IK, `Δq = J⁺Δx + (I − J⁺J)Δz`: the chain moves out of the body
//! while the end effector keeps to its goal. See [`CollisionAvoidance`].

pub use crate::collision::signed_distance;
use crate::collision::{outward, Volume, VolumesAround};
use crate::error::{Error, Result};
use crate::ik::{NullSpaceContext, NullSpaceTask};
use crate::jacobian::{fill_jacobian, Effector};
use crate::linalg::{Mat, Svd};
use crate::skeleton::Skeleton;
use crate::solid::Shape;
use crate::transform::Transform;
use glam::DVec3;

/// Sensors are this fraction of the limb's radius: just inside its surface, so that
/// limbs resting against each other (hands on the thighs) do not count as collisions.
pub const SENSOR_SCALE: f64 = 0.85;

/// A body sphere sensor.
#[derive(Clone, Debug, PartialEq)]
pub struct Sensor {
    /// `l_elbow`, `r_hand`, `l_knee`, `r_ankle`, `l_foot`, or for the sampled segments of
    /// figure 4-20 `l_forearm_50` (elbow–hand at 50 %) and `r_shank_25`; `l_upper_arm_50`
    /// (shoulder–elbow), which keeps out of other bodies only.
    pub name: String,
    /// The joint the sensor moves with.
    pub joint: usize,
    /// Centre in that joint's frame (for segment samples: at the rest posture).
    pub point: DVec3,
    /// Radius in metres.
    pub radius: f64,
    /// For each body solid (index into [`Skeleton::solids`]), whether the sensor ignores
    /// it (its own limb's solids).
    pub ignores: Vec<bool>,
}

/// A sensor penetrating (or, with a margin, approaching) a body solid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    /// Index of the sensor in [`BodySensors::sensors`].
    pub sensor: usize,
    /// Index of the solid in [`Skeleton::solids`].
    pub solid: usize,
    /// World centre of the sensor.
    pub center: DVec3,
    /// How deep the sphere is inside the solid (metres; negative: that far outside).
    pub depth: f64,
    /// Outward unit normal of the solid near the sensor, world frame.
    pub normal: DVec3,
}

/// The sensor set of a humanoid skeleton.
#[derive(Clone, Debug)]
pub struct BodySensors {
    sensors: Vec<Sensor>,
}

fn solid_by_name<'a>(skeleton: &'a Skeleton, name: &str) -> Result<(usize, &'a crate::Solid)> {
    skeleton
        .solids()
        .iter()
        .enumerate()
        .find(|(_, (_, s))| s.name == name)
        .map(|(i, (_, s))| (i, s))
        .ok_or_else(|| {
            Error::Invalid(format!(
                "self-collision: `{}` has no solid `{name}` (not a humanoid template)",
                skeleton.name()
            ))
        })
}

fn radii(shape: &Shape) -> (f64, f64) {
    match *shape {
        Shape::Sphere { radius } => (radius, radius),
        Shape::Cylinder { radius, .. } => (radius, radius),
        Shape::Frustum {
            bottom_radius,
            top_radius,
            ..
        } => (bottom_radius, top_radius),
        Shape::Box { half_extents } => (half_extents.x, half_extents.z),
        Shape::Ellipsoid { radii } => (radii.x, radii.z),
    }
}

impl BodySensors {
    /// The sensors of a humanoid template (the joint and solid names of `adult`/`child`).
    pub fn new(skeleton: &Skeleton) -> Result<BodySensors> {
        let mut sensors = Vec::new();
        let solids = skeleton.solids();
        let own = |root: &str| -> Result<Vec<bool>> {
            let scope_root = skeleton.joint(root)?;
            let mut inside = vec![false; skeleton.joints().len()];
            for (j, jt) in skeleton.joints().iter().enumerate() {
                inside[j] = j == scope_root || jt.parent.is_some_and(|p| inside[p]);
            }
            Ok(solids.iter().map(|(j, _)| inside[*j]).collect())
        };
        for side in ["l_", "r_"] {
            let arm = own(&format!("{side}sternoclavicular"))?;
            let leg = own(&format!("{side}hip"))?;
            let (_, forearm) = solid_by_name(skeleton, &format!("{side}forearm"))?;
            let (_, hand) = solid_by_name(skeleton, &format!("{side}hand"))?;
            let (_, upper_arm) = solid_by_name(skeleton, &format!("{side}upper_arm"))?;
            let (_, shank) = solid_by_name(skeleton, &format!("{side}leg"))?;
            let (_, foot) = solid_by_name(skeleton, &format!("{side}foot"))?;
            let (fore_bottom, fore_top) = radii(&forearm.shape);
            let (shank_bottom, shank_top) = radii(&shank.shape);
            let (foot_bottom, _) = radii(&foot.shape);
            let shoulder = skeleton.joint(&format!("{side}shoulder"))?;
            let elbow = skeleton.joint(&format!("{side}elbow"))?;
            let wrist = skeleton.joint(&format!("{side}wrist"))?;
            let knee = skeleton.joint(&format!("{side}knee"))?;
            let ankle = skeleton.joint(&format!("{side}ankle"))?;
            let subtalar = skeleton.joint(&format!("{side}subtalar"))?;
            let mut add =
                |name: String, joint: usize, point: DVec3, radius: f64, ignores: &Vec<bool>| {
                    sensors.push(Sensor {
                        name,
                        joint,
                        point,
                        radius: radius * SENSOR_SCALE,
                        ignores: ignores.clone(),
                    })
                };
            add(format!("{side}elbow"), elbow, DVec3::ZERO, fore_top, &arm);
            add(
                format!("{side}hand"),
                wrist,
                hand.center,
                radii(&hand.shape).0,
                &arm,
            );
            add(format!("{side}knee"), knee, DVec3::ZERO, shank_top, &leg);
            add(
                format!("{side}ankle"),
                ankle,
                DVec3::ZERO,
                shank_bottom,
                &leg,
            );
            add(
                format!("{side}foot"),
                subtalar,
                foot.center,
                foot_bottom,
                &leg,
            );
            // Figure 4-20: samples of the segments between related sensors.
            let wrist_in_elbow = skeleton.joints()[wrist].offset + hand.center;
            let elbow_in_shoulder = skeleton.joints()[elbow].offset;
            // The upper arm is not one of figure 4-19's sensors: hanging, it rests
            // against the chest, so it ignores every solid of its own body and keeps out
            // of other bodies and obstacles only (a reach's external volumes).
            let (upper_bottom, upper_top) = radii(&upper_arm.shape);
            let whole_body = vec![true; solids.len()];
            let ankle_in_knee = skeleton.joints()[ankle].offset;
            for pct in [25, 50, 75] {
                let t = pct as f64 / 100.0;
                add(
                    format!("{side}forearm_{pct}"),
                    elbow,
                    wrist_in_elbow * t,
                    fore_bottom,
                    &arm,
                );
                add(
                    format!("{side}upper_arm_{pct}"),
                    shoulder,
                    elbow_in_shoulder * t,
                    upper_top + (upper_bottom - upper_top) * t,
                    &whole_body,
                );
                add(
                    format!("{side}shank_{pct}"),
                    knee,
                    ankle_in_knee * t,
                    shank_bottom,
                    &leg,
                );
            }
        }
        Ok(BodySensors { sensors })
    }

    /// Every sensor.
    pub fn sensors(&self) -> &[Sensor] {
        &self.sensors
    }

    /// The index of the sensor called `name`.
    pub fn index_of(&self, name: &str) -> Option<usize> {
        self.sensors.iter().position(|s| s.name == name)
    }

    /// The world centre of sensor `i` for joint globals `globals`.
    pub fn center(&self, i: usize, globals: &[Transform]) -> DVec3 {
        let s = &self.sensors[i];
        globals[s.joint].transform_point(s.point)
    }

    /// Appends to `out` every (sensor, solid) pair whose depth exceeds `-margin` (with
    /// `margin = 0`: the penetrations). Only sensors for which `filter` is true are tested.
    pub fn contacts(
        &self,
        skeleton: &Skeleton,
        globals: &[Transform],
        margin: f64,
        filter: impl Fn(usize) -> bool,
        out: &mut Vec<Contact>,
    ) {
        for (i, sensor) in self.sensors.iter().enumerate() {
            if !filter(i) {
                continue;
            }
            let c = globals[sensor.joint].transform_point(sensor.point);
            for (k, (j, solid)) in skeleton.solids().iter().enumerate() {
                if sensor.ignores[k] {
                    continue;
                }
                if let Some((depth, normal)) =
                    sphere_depth(&globals[*j], solid, c, sensor.radius, margin)
                {
                    out.push(Contact {
                        sensor: i,
                        solid: k,
                        center: c,
                        depth,
                        normal,
                    });
                }
            }
        }
    }

    /// The deepest penetration of any sensor at the posture `globals` (0 when none).
    pub fn deepest(&self, skeleton: &Skeleton, globals: &[Transform]) -> (f64, Option<Contact>) {
        let mut found = Vec::new();
        self.contacts(skeleton, globals, 0.0, |_| true, &mut found);
        found
            .into_iter()
            .filter(|c| c.depth > 0.0)
            .fold((0.0, None), |(d, best), c| {
                if c.depth > d {
                    (c.depth, Some(c))
                } else {
                    (d, best)
                }
            })
    }

    /// Moves `point` (a sphere of `radius` with the exclusions of sensor `sensor`) out of
    /// every body solid it penetrates, plus `margin`: the temporary goal of 4.6.3 for an
    /// end effector whose path crosses the body.
    pub fn push_out(
        &self,
        skeleton: &Skeleton,
        globals: &[Transform],
        sensor: usize,
        point: DVec3,
        margin: f64,
    ) -> DVec3 {
        let s = &self.sensors[sensor];
        let mut p = point;
        for _ in 0..8 {
            let mut moved = false;
            for (k, (j, solid)) in skeleton.solids().iter().enumerate() {
                if s.ignores[k] {
                    continue;
                }
                if let Some((depth, normal)) =
                    sphere_depth(&globals[*j], solid, p, s.radius, margin)
                {
                    p += normal * (depth + margin);
                    moved = true;
                }
            }
            if !moved {
                break;
            }
        }
        p
    }
}

/// Depth of a sphere (centre `c`, `radius`, world) inside `solid` placed by `frame`, and
/// the solid's outward normal there; `None` when farther than `margin` from it.
fn sphere_depth(
    frame: &Transform,
    solid: &crate::Solid,
    c: DVec3,
    radius: f64,
    margin: f64,
) -> Option<(f64, DVec3)> {
    let local = frame.inverse().transform_point(c);
    let p = solid.orientation.inverse() * (local - solid.center);
    let d = signed_distance(&solid.shape, p);
    let depth = radius - d;
    if depth <= -margin {
        return None;
    }
    let g = outward(&solid.shape, p);
    Some((depth, frame.rotation * (solid.orientation * g)))
}

/// The self-collision response of table 4-1 as an IK secondary task: each sensor on the
/// solved chain that penetrates (or comes within `margin` of) a body solid is pushed out
/// along the solid's normal through its sub-chain's pseudo-inverse (eq. 4-2).
pub struct CollisionAvoidance<'a> {
    sensors: &'a BodySensors,
    /// Other bodies' and objects' volumes the sensors also keep out of (see
    /// [`CollisionAvoidance::with_external`]).
    external: VolumesAround<'a>,
    /// How far outside the external volumes the sensors start to be pushed (m).
    external_margin: f64,
    /// Whether the body's own solids count (off: only the external volumes do).
    own_body: bool,
    margin: f64,
    skip: Vec<usize>,
    /// Per sensor, whether the solved DOFs move it; found on the first step, since the
    /// DOFs do not change during a solve.
    movable: Vec<bool>,
    contacts: Vec<Contact>,
    j: Mat,
    svd: Svd,
}

impl<'a> CollisionAvoidance<'a> {
    /// A response over `sensors`, keeping them `margin` metres clear of the body;
    /// sensors in `skip` (e.g. the end effector's own, which the main task drives) are
    /// left out.
    pub fn new(sensors: &'a BodySensors, margin: f64, skip: Vec<usize>) -> Self {
        CollisionAvoidance {
            sensors,
            external: VolumesAround::default(),
            external_margin: margin,
            own_body: true,
            margin,
            skip,
            movable: Vec::new(),
            contacts: Vec::new(),
            j: Mat::zeros(3, 1),
            svd: Svd::default(),
        }
    }

    /// Also keeps the sensors out of `external` volumes (other actors' bodies, obstacles:
    /// thesis 6.5.3, figure 6-22's correction with IK), each sensor at its limb's full
    /// radius, the same response vector and sub-chain pseudo-inverse as for the body;
    /// each is pushed once it comes within `margin` of one. Other bodies and objects
    /// want a wider margin than the body's own: the sensors sample the limbs sparsely,
    /// and an elbow swinging round another's arm meets it between two samples of a tick.
    pub fn with_external(mut self, external: &'a [Volume], margin: f64) -> Self {
        self.external = VolumesAround::new(external);
        self.external_margin = margin;
        self
    }

    /// Leaves the body's own solids out: only the external volumes count.
    pub fn without_own_body(mut self) -> Self {
        self.own_body = false;
        self
    }

    /// Adds the response to sensor `sensor` moving by `v` (world) to `dz`.
    fn respond(&mut self, ctx: &NullSpaceContext, sensor: usize, v: DVec3, dz: &mut [f64]) {
        let s = &self.sensors.sensors()[sensor];
        self.j.reset(3, ctx.dofs.len());
        let e = Effector {
            joint: s.joint,
            point: s.point,
        };
        fill_jacobian(
            ctx.skeleton,
            ctx.globals,
            ctx.dofs,
            ctx.axes,
            &e,
            false,
            &mut self.j,
            0,
        );
        self.svd.compute(&self.j);
        self.svd
            .add_pseudo_inverse_times(&[v.x, v.y, v.z], 1e-4, dz);
    }
}

impl NullSpaceTask for CollisionAvoidance<'_> {
    fn add_step(&mut self, ctx: &NullSpaceContext, dz: &mut [f64]) -> bool {
        self.contacts.clear();
        let sensors = self.sensors;
        if self.movable.is_empty() {
            // Only sensors the solved DOFs can move take part.
            let moved: crate::Scope = ctx.dofs.iter().copied().collect();
            self.movable = (0..sensors.sensors().len())
                .map(|i| {
                    !self.skip.contains(&i)
                        && !crate::jacobian::ancestor_dofs(ctx.skeleton, sensors.sensors()[i].joint)
                            .intersection(&moved)
                            .is_empty()
                })
                .collect();
        }
        let movable = &self.movable;
        let own_body = self.own_body;
        sensors.contacts(
            ctx.skeleton,
            ctx.globals,
            self.margin,
            |i| own_body && movable[i],
            &mut self.contacts,
        );
        let mut penetrating = false;
        let contacts = std::mem::take(&mut self.contacts);
        for c in &contacts {
            penetrating |= c.depth > 0.0;
            // Step 3–4 of table 4-1: the guidance frame g2 is the sensor moved by v.
            self.respond(ctx, c.sensor, c.normal * (c.depth + self.margin), dz);
        }
        self.contacts = contacts;
        for i in 0..sensors.sensors().len() {
            if self.external.volumes.is_empty() || !self.movable[i] {
                continue;
            }
            let c = sensors.center(i, ctx.globals);
            let radius = sensors.sensors()[i].radius / SENSOR_SCALE;
            for k in 0..self.external.volumes.len() {
                // A sensor farther than the margin from a capsule's bounding sphere is
                // farther from the capsule: no push (a reach's tick in a crowd took 5 M
                // instructions measuring them all).
                if !self.external.may_reach(k, c, radius, self.external_margin) {
                    continue;
                }
                let p = self.external.volumes[k].sphere(c, radius);
                if p.depth > -self.external_margin {
                    penetrating |= p.depth > 0.0;
                    self.respond(ctx, i, p.normal * (p.depth + self.external_margin), dz);
                }
            }
        }
        penetrating
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::forward_kinematics;
    use crate::template::{template, TemplateParams};

    #[test]
    fn signed_distances_have_the_right_sign_and_size() {
        let cyl = Shape::Cylinder {
            radius: 0.1,
            height: 0.4,
        };
        assert!((signed_distance(&cyl, DVec3::new(0.3, 0.0, 0.0)) - 0.2).abs() < 1e-12);
        assert!((signed_distance(&cyl, DVec3::new(0.0, 0.1, 0.05)) + 0.05).abs() < 1e-12);
        let sphere = Shape::Sphere { radius: 0.2 };
        assert!((signed_distance(&sphere, DVec3::new(0.0, 0.5, 0.0)) - 0.3).abs() < 1e-12);
        let ell = Shape::Ellipsoid {
            radii: DVec3::new(0.1, 0.2, 0.3),
        };
        assert!(signed_distance(&ell, DVec3::new(0.0, 0.19, 0.0)) < 0.0);
        assert!(signed_distance(&ell, DVec3::new(0.0, 0.21, 0.0)) > 0.0);
        let f = Shape::Frustum {
            bottom_radius: 0.2,
            top_radius: 0.1,
            height: 1.0,
        };
        assert!(signed_distance(&f, DVec3::new(0.19, -0.5 + 1e-3, 0.0)) < 0.0);
        assert!(signed_distance(&f, DVec3::new(0.16, 0.5 - 1e-3, 0.0)) > 0.0);
        let b = Shape::Box {
            half_extents: DVec3::new(0.1, 0.2, 0.3),
        };
        assert!((signed_distance(&b, DVec3::new(0.0, 0.0, 0.5)) - 0.2).abs() < 1e-12);
    }

    #[test]
    fn the_rest_pose_is_collision_free_and_an_elbow_in_the_chest_is_not() {
        for t in ["adult", "child"] {
            let tpl = template(t).unwrap();
            let s = tpl.instantiate(tpl.default_params()).unwrap();
            let sensors = BodySensors::new(&s).unwrap();
            // Figure 4-19's ten, the forearms' and shanks' samples, the upper arms'.
            assert_eq!(sensors.sensors().len(), 10 + 12 + 6);
            let mut g = vec![Transform::IDENTITY; s.joints().len()];
            let mut q = vec![0.0; s.dof_count()];
            forward_kinematics(&s, &q, &mut g);
            let (depth, contact) = sensors.deepest(&s, &g);
            assert_eq!(depth, 0.0, "{t}: {contact:?}");
            // The arm adducted into the side of the trunk.
            q[s.dof("r_shoulder_abduction").unwrap()] = -0.5;
            forward_kinematics(&s, &q, &mut g);
            let (depth, contact) = sensors.deepest(&s, &g);
            assert!(depth > 0.0, "{t}: {contact:?}");
            // The upper arm lies in the trunk too, but its samples keep out of other
            // bodies only.
            let mut contacts = Vec::new();
            sensors.contacts(&s, &g, 0.0, |_| true, &mut contacts);
            let names = |c: &Contact| sensors.sensors()[c.sensor].name.clone();
            assert!(contacts.iter().any(|c| names(c).starts_with("r_elbow")));
            assert!(!contacts.iter().any(|c| names(c).contains("upper_arm")));
        }
        let s = template("adult")
            .unwrap()
            .instantiate(TemplateParams {
                height: 1.75,
                mass: 70.0,
            })
            .unwrap();
        let sensors = BodySensors::new(&s).unwrap();
        let mut g = vec![Transform::IDENTITY; s.joints().len()];
        forward_kinematics(&s, &vec![0.0; s.dof_count()], &mut g);
        // A point inside the chest is pushed out in front of it.
        let hand = sensors.index_of("r_hand").unwrap();
        let chest = g[s.joint("vt6").unwrap()].translation + DVec3::new(0.0, 0.0, 0.05);
        let out = sensors.push_out(&s, &g, hand, chest, 0.01);
        let mut probe = sensors.clone();
        probe.sensors[hand].point = DVec3::ZERO;
        let mut moved = g.clone();
        moved[probe.sensors[hand].joint] = Transform::from_translation(out);
        assert_eq!(probe.deepest(&s, &moved).0, 0.0);
        assert!(out.z > 0.1, "{out}");
    }
}
