//! URDF export: a body as a robot description, for dynamics and robotics tools.
//!
//! Conventions (also in docs/formats.md, "URDF export"):
//! * one URDF joint per troupe DOF, named exactly as the DOF; the DOFs of one troupe joint
//!   are chained through massless links `<dof>_link`; the last one's child link carries
//!   the segment and is named as the troupe joint;
//! * Z up, X forward, Y left (REP 103): a troupe vector `(x, y, z)` is written
//!   `(z, x, y)`;
//! * limits in radians / metres; unlimited rotations are `continuous`; the root's
//!   translations are `prismatic` within ±1000 m;
//! * each segment link carries the mass, centre of mass and inertia of the solids attached
//!   to its joint; every other moving link carries troupe's nominal body (a 1 g bead, see
//!   [`troupe_body::dynamics::NOMINAL_LINK_MASS`]), as troupe's dynamics model does, so
//!   that forward-dynamics tools have an inertia on every joint and agree with troupe.
//! * troupe's armature (the rotor inertia its dynamics adds on each non-root DOF, which
//!   core URDF cannot express) is written as a `<transmission>` per DOF whose actuator
//!   carries Drake's `drake:rotor_inertia` with `drake:gear_ratio` 1 (reflected inertia
//!   = rotor inertia × ratio², Drake's convention); other URDF readers ignore it.

use glam::{DMat3, DVec3};
use std::fmt::Write as _;
use troupe_body::dynamics::{nominal_link_inertia, nominal_links, Model, NOMINAL_LINK_MASS};
use troupe_body::skeleton::{DofKind, Skeleton};

/// Troupe's Y-up frame to URDF's Z-up frame: `(x, y, z) ↦ (z, x, y)`.
fn z_up(v: DVec3) -> DVec3 {
    DVec3::new(v.z, v.x, v.y)
}

/// The rotation matrix of [`z_up`].
fn z_up_matrix() -> DMat3 {
    DMat3::from_cols(z_up(DVec3::X), z_up(DVec3::Y), z_up(DVec3::Z))
}

/// A vector as URDF writes it: three numbers separated by spaces.
fn xyz(v: DVec3) -> String {
    format!("{} {} {}", v.x, v.y, v.z)
}

/// Writes a link named `name` with an `<inertial>` of `mass` at `com` (URDF axes) with
/// `inertia` about the centre of mass (URDF axes), or without one when `mass` is zero.
fn link(s: &mut String, name: &str, mass: f64, com: DVec3, inertia: DMat3) {
    if mass <= 0.0 {
        let _ = writeln!(s, "  <link name=\"{name}\"/>");
        return;
    }
    let i = inertia;
    let _ = writeln!(s, "  <link name=\"{name}\">");
    let _ = writeln!(s, "    <inertial>");
    let _ = writeln!(s, "      <origin xyz=\"{}\" rpy=\"0 0 0\"/>", xyz(com));
    let _ = writeln!(s, "      <mass value=\"{mass}\"/>");
    let _ = writeln!(
        s,
        "      <inertia ixx=\"{}\" ixy=\"{}\" ixz=\"{}\" iyy=\"{}\" iyz=\"{}\" izz=\"{}\"/>",
        i.x_axis.x, i.y_axis.x, i.z_axis.x, i.y_axis.y, i.z_axis.y, i.z_axis.z
    );
    let _ = writeln!(s, "    </inertial>");
    let _ = writeln!(s, "  </link>");
}

/// Writes the link of DOF `dof` named `name`: with troupe's nominal body when `nominal`.
fn dof_link(s: &mut String, name: &str, nominal: bool) {
    if nominal {
        let inertia = DMat3::from_diagonal(DVec3::splat(nominal_link_inertia()));
        link(s, name, NOMINAL_LINK_MASS, DVec3::ZERO, inertia);
    } else {
        link(s, name, 0.0, DVec3::ZERO, DMat3::ZERO);
    }
}

/// Half-range of the root's prismatic joints in the file (URDF needs finite limits).
pub const PRISMATIC_RANGE: f64 = 1000.0;
/// Nominal effort limit written for every moving joint (troupe has no actuator model).
pub const NOMINAL_EFFORT: f64 = 1000.0;
/// Nominal velocity limit written for every moving joint.
pub const NOMINAL_VELOCITY: f64 = 100.0;

/// Drake's XML namespace, for the `drake:` elements that carry the armature.
pub const DRAKE_NAMESPACE: &str = "http://drake.mit.edu";

/// The URDF text of `skeleton`; with `fixed_root`, the root joint is attached to
/// `base_link` by a fixed joint instead of its DOFs. Fails when troupe's dynamics model
/// of the skeleton cannot be built (the armature comes from it).
pub fn urdf(skeleton: &Skeleton, fixed_root: bool) -> Result<String, crate::Error> {
    let armature = Model::new(skeleton)?.armature().to_vec();
    let c = z_up_matrix();
    let mut s = String::new();
    let _ = writeln!(s, "<?xml version=\"1.0\"?>");
    let nominal = nominal_links(skeleton);
    let _ = writeln!(
        s,
        "<!-- troupe body template `{}` ({:.3} kg of solids, {} nominal links of {} kg): Z up, one joint per DOF; see docs/formats.md -->",
        skeleton.name(),
        skeleton.total_mass(),
        nominal.iter().filter(|&&b| b).count(),
        NOMINAL_LINK_MASS
    );
    let _ = writeln!(
        s,
        "<robot name=\"{}\" xmlns:drake=\"{DRAKE_NAMESPACE}\">",
        skeleton.name()
    );
    let _ = writeln!(s, "  <link name=\"base_link\"/>");
    for (j, joint) in skeleton.joints().iter().enumerate() {
        // The segment link, with the solids attached to this joint.
        let solids: Vec<_> = skeleton
            .solids()
            .iter()
            .filter(|(k, _)| *k == j)
            .map(|(_, s)| s)
            .collect();
        let mass: f64 = solids.iter().map(|s| s.mass).sum();
        let mut com = DVec3::ZERO;
        let mut inertia = DMat3::ZERO;
        if mass > 0.0 {
            com = solids
                .iter()
                .map(|s| s.center_of_mass * s.mass)
                .sum::<DVec3>()
                / mass;
            for sol in &solids {
                let r = sol.center_of_mass - com;
                let shift = DMat3::from_diagonal(DVec3::splat(r.dot(r)))
                    - DMat3::from_cols(r * r.x, r * r.y, r * r.z);
                inertia += sol.inertia + shift * sol.mass;
            }
        }
        let last = (!joint.dofs.is_empty()).then(|| joint.dofs.end - 1);
        if mass > 0.0 {
            link(
                &mut s,
                &joint.name,
                mass,
                z_up(com),
                c * inertia * c.transpose(),
            );
        } else {
            // A joint's own link is its last DOF's link: it may carry the nominal body.
            dof_link(&mut s, &joint.name, last.is_some_and(|k| nominal[k]));
        }
        let parent = match joint.parent {
            Some(p) => skeleton.joints()[p].name.clone(),
            None => "base_link".to_string(),
        };
        let dofs = joint.dofs.clone();
        if dofs.is_empty() || (fixed_root && joint.parent.is_none()) {
            let _ = writeln!(s, "  <joint name=\"{}_fixed\" type=\"fixed\">", joint.name);
            let _ = writeln!(s, "    <parent link=\"{parent}\"/>");
            let _ = writeln!(s, "    <child link=\"{}\"/>", joint.name);
            let _ = writeln!(
                s,
                "    <origin xyz=\"{}\" rpy=\"0 0 0\"/>",
                xyz(z_up(joint.offset))
            );
            let _ = writeln!(s, "  </joint>");
            continue;
        }
        let mut from = parent;
        for d in dofs.clone() {
            let dof = &skeleton.dofs()[d];
            let last = d + 1 == dofs.end;
            let child = if last {
                joint.name.clone()
            } else {
                let name = format!("{}_link", dof.name);
                dof_link(&mut s, &name, nominal[d]);
                name
            };
            let (kind, limits) = match dof.kind {
                DofKind::Rotation if dof.min.is_finite() && dof.max.is_finite() => {
                    ("revolute", Some((dof.min, dof.max)))
                }
                DofKind::Rotation => ("continuous", None),
                DofKind::Translation => (
                    "prismatic",
                    Some((dof.min.max(-PRISMATIC_RANGE), dof.max.min(PRISMATIC_RANGE))),
                ),
            };
            let origin = if d == dofs.start {
                joint.offset
            } else {
                DVec3::ZERO
            };
            let _ = writeln!(s, "  <joint name=\"{}\" type=\"{kind}\">", dof.name);
            let _ = writeln!(s, "    <parent link=\"{from}\"/>");
            let _ = writeln!(s, "    <child link=\"{child}\"/>");
            let _ = writeln!(
                s,
                "    <origin xyz=\"{}\" rpy=\"0 0 0\"/>",
                xyz(z_up(origin))
            );
            let _ = writeln!(s, "    <axis xyz=\"{}\"/>", xyz(z_up(dof.axis)));
            match limits {
                Some((lo, hi)) => {
                    let _ = writeln!(
                        s,
                        "    <limit lower=\"{lo}\" upper=\"{hi}\" effort=\"{NOMINAL_EFFORT}\" velocity=\"{NOMINAL_VELOCITY}\"/>"
                    );
                }
                None => {
                    let _ = writeln!(
                        s,
                        "    <limit effort=\"{NOMINAL_EFFORT}\" velocity=\"{NOMINAL_VELOCITY}\"/>"
                    );
                }
            }
            let _ = writeln!(s, "  </joint>");
            if armature[d] > 0.0 {
                transmission(&mut s, &dof.name, armature[d]);
            }
            from = child;
        }
    }
    let _ = writeln!(s, "</robot>");
    Ok(s)
}

/// Writes the transmission of DOF `name` whose actuator carries troupe's armature as
/// Drake's rotor inertia (gear ratio 1, so the reflected inertia is the armature).
fn transmission(s: &mut String, name: &str, armature: f64) {
    let _ = writeln!(s, "  <transmission name=\"{name}_transmission\">");
    let _ = writeln!(
        s,
        "    <type>transmission_interface/SimpleTransmission</type>"
    );
    let _ = writeln!(s, "    <joint name=\"{name}\">");
    let _ = writeln!(
        s,
        "      <hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface>"
    );
    let _ = writeln!(s, "    </joint>");
    let _ = writeln!(s, "    <actuator name=\"{name}_armature\">");
    let _ = writeln!(s, "      <mechanicalReduction>1</mechanicalReduction>");
    let _ = writeln!(s, "      <drake:rotor_inertia value=\"{armature}\"/>");
    let _ = writeln!(s, "      <drake:gear_ratio value=\"1\"/>");
    let _ = writeln!(s, "    </actuator>");
    let _ = writeln!(s, "  </transmission>");
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;
    use std::collections::HashMap;
    use troupe_body::kinematics::forward_kinematics;
    use troupe_body::template::template;
    use troupe_body::transform::Transform;

    /// One parsed URDF joint.
    struct UJoint {
        kind: String,
        parent: String,
        child: String,
        xyz: DVec3,
        rpy: DVec3,
        axis: DVec3,
        limits: Option<(f64, f64)>,
    }

    fn vec(s: Option<&str>) -> DVec3 {
        let v: Vec<f64> = s
            .unwrap_or("0 0 0")
            .split_whitespace()
            .map(|x| x.parse().unwrap())
            .collect();
        DVec3::new(v[0], v[1], v[2])
    }

    fn parse(text: &str) -> (HashMap<String, UJoint>, HashMap<String, f64>) {
        let doc = roxmltree::Document::parse(text).unwrap();
        let robot = doc.root_element();
        assert_eq!(robot.tag_name().name(), "robot");
        let mut joints = HashMap::new();
        let mut masses = HashMap::new();
        for n in robot.children().filter(|n| n.is_element()) {
            let child = |tag: &str| n.children().find(|c| c.has_tag_name(tag));
            match n.tag_name().name() {
                "link" => {
                    if let Some(m) = n
                        .descendants()
                        .find(|c| c.has_tag_name("mass"))
                        .and_then(|m| m.attribute("value"))
                    {
                        masses.insert(n.attribute("name").unwrap().to_string(), m.parse().unwrap());
                    }
                }
                "joint" => {
                    let origin = child("origin");
                    let limit = child("limit");
                    joints.insert(
                        n.attribute("name").unwrap().to_string(),
                        UJoint {
                            kind: n.attribute("type").unwrap().to_string(),
                            parent: child("parent").unwrap().attribute("link").unwrap().into(),
                            child: child("child").unwrap().attribute("link").unwrap().into(),
                            xyz: vec(origin.and_then(|o| o.attribute("xyz"))),
                            rpy: vec(origin.and_then(|o| o.attribute("rpy"))),
                            axis: vec(child("axis").and_then(|a| a.attribute("xyz"))),
                            limits: limit.and_then(|l| {
                                Some((
                                    l.attribute("lower")?.parse().ok()?,
                                    l.attribute("upper")?.parse().ok()?,
                                ))
                            }),
                        },
                    );
                }
                _ => {}
            }
        }
        (joints, masses)
    }

    /// World frames of every link for joint values `values` (by URDF joint name).
    fn urdf_fk(
        joints: &HashMap<String, UJoint>,
        values: &HashMap<String, f64>,
    ) -> HashMap<String, Transform> {
        let mut frames = HashMap::new();
        frames.insert("base_link".to_string(), Transform::IDENTITY);
        let mut changed = true;
        while changed {
            changed = false;
            for (name, j) in joints {
                if frames.contains_key(&j.child) {
                    continue;
                }
                let Some(parent) = frames.get(&j.parent).copied() else {
                    continue;
                };
                let rot = DQuat::from_rotation_z(j.rpy.z)
                    * DQuat::from_rotation_y(j.rpy.y)
                    * DQuat::from_rotation_x(j.rpy.x);
                let origin = Transform::new(rot, j.xyz);
                let v = values.get(name).copied().unwrap_or(0.0);
                let motion = match j.kind.as_str() {
                    "revolute" | "continuous" => {
                        Transform::new(DQuat::from_axis_angle(j.axis.normalize(), v), DVec3::ZERO)
                    }
                    "prismatic" => Transform::from_translation(j.axis * v),
                    _ => Transform::IDENTITY,
                };
                frames.insert(j.child.clone(), parent.mul(&origin).mul(&motion));
                changed = true;
            }
        }
        frames
    }

    fn from_z_up(v: DVec3) -> DVec3 {
        DVec3::new(v.y, v.z, v.x)
    }

    #[test]
    fn exported_urdf_matches_troupe_kinematics_and_masses() {
        for (name, fixed) in [("adult", false), ("child", false), ("adult", true)] {
            let t = template(name).unwrap();
            let s = t.instantiate(t.default_params()).unwrap();
            let text = urdf(&s, fixed).unwrap();
            let (joints, masses) = parse(&text);
            // Every DOF is a joint named as the DOF, with its limits.
            for (i, d) in s.dofs().iter().enumerate() {
                if fixed && i < 6 {
                    assert!(!joints.contains_key(&d.name));
                    continue;
                }
                let j = &joints[&d.name];
                if d.min.is_finite() && d.kind == DofKind::Rotation {
                    assert_eq!(j.limits, Some((d.min, d.max)), "{}", d.name);
                }
            }
            // The solids' masses, plus troupe's nominal body on every other moving link.
            let total: f64 = masses.values().sum();
            let beads = nominal_links(&s).iter().filter(|&&b| b).count();
            assert!(beads > 0);
            let expected = s.total_mass() + beads as f64 * NOMINAL_LINK_MASS;
            assert!((total - expected).abs() < 1e-9, "{total} vs {expected}");
            // Random postures: every troupe joint's link lands where troupe's FK puts it.
            let mut draw = troupe_body::math::draws(99);
            for _ in 0..50 {
                let mut q = vec![0.0; s.dof_count()];
                let mut values = HashMap::new();
                for (i, d) in s.dofs().iter().enumerate() {
                    let u = draw();
                    if fixed && i < 6 {
                        continue;
                    }
                    let (lo, hi) = if d.min.is_finite() {
                        (d.min, d.max)
                    } else {
                        (-2.0, 2.0)
                    };
                    q[i] = lo + (hi - lo) * u;
                    values.insert(d.name.clone(), q[i]);
                }
                let mut g = vec![Transform::IDENTITY; s.joints().len()];
                forward_kinematics(&s, &q, &mut g);
                let frames = urdf_fk(&joints, &values);
                for (j, joint) in s.joints().iter().enumerate() {
                    let p = from_z_up(frames[&joint.name].translation);
                    assert!(
                        (p - g[j].translation).length() < 1e-9,
                        "{name}: {} at {p}, troupe {}",
                        joint.name,
                        g[j].translation
                    );
                }
            }
        }
    }

    #[test]
    fn every_moving_dof_carries_troupe_armature_as_drake_rotor_inertia() {
        for name in ["adult", "child"] {
            let t = template(name).unwrap();
            let s = t.instantiate(t.default_params()).unwrap();
            let model = Model::new(&s).unwrap();
            for fixed in [true, false] {
                let text = urdf(&s, fixed).unwrap();
                let doc = roxmltree::Document::parse(&text).unwrap();
                let mut written = HashMap::new();
                for t in doc.descendants().filter(|n| n.has_tag_name("transmission")) {
                    let joint = t.children().find(|c| c.has_tag_name("joint")).unwrap();
                    let value = |tag: &str| -> f64 {
                        t.descendants()
                            .find(|c| c.has_tag_name((DRAKE_NAMESPACE, tag)))
                            .and_then(|c| c.attribute("value"))
                            .unwrap()
                            .parse()
                            .unwrap()
                    };
                    assert_eq!(value("gear_ratio"), 1.0);
                    written.insert(joint.attribute("name").unwrap(), value("rotor_inertia"));
                }
                let root = model.root_dofs();
                for (k, d) in s.dofs().iter().enumerate() {
                    if root.contains(&k) {
                        assert!(
                            !written.contains_key(d.name.as_str()),
                            "{name}: root {}",
                            d.name
                        );
                    } else {
                        assert_eq!(
                            written.get(d.name.as_str()),
                            Some(&model.armature()[k]),
                            "{name}: {}",
                            d.name
                        );
                    }
                }
            }
        }
    }
}
