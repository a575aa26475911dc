//! How much floor a body needs: the radius of the vertical cylinder about its root that
//! holds it standing at rest, from its template and size.

use troupe_body::glam::DVec2;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::skeleton::Skeleton;
use troupe_body::solid::Shape;
use troupe_body::transform::Transform;

/// The body's radius seen from above: the farthest any segment solid reaches
/// horizontally from the root's vertical axis in the rest posture (arms hanging).
pub fn body_radius(skeleton: &Skeleton) -> f64 {
    let q = vec![0.0; skeleton.dof_count()];
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &q, &mut globals);
    let root = globals[0].translation;
    let axis = DVec2::new(root.x, root.z);
    skeleton
        .solids()
        .iter()
        .map(|(joint, solid)| {
            let c = globals[*joint].transform_point(solid.center);
            (DVec2::new(c.x, c.z) - axis).length() + horizontal_reach(&solid.shape)
        })
        .fold(0.0, f64::max)
}

/// How far a solid reaches sideways from its centre, whatever its orientation about Y;
/// a limb's length along its own axis hangs vertically at rest and does not count.
fn horizontal_reach(shape: &Shape) -> f64 {
    match *shape {
        Shape::Box { half_extents: h } => h.x.hypot(h.z),
        Shape::Sphere { radius } => radius,
        Shape::Cylinder { radius, .. } => radius,
        Shape::Frustum {
            bottom_radius,
            top_radius,
            ..
        } => bottom_radius.max(top_radius),
        Shape::Ellipsoid { radii } => radii.x.max(radii.z),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::template::template;

    #[test]
    fn an_adult_needs_about_a_quarter_metre_and_a_child_less() {
        let adult = template("adult").unwrap();
        let a = body_radius(&adult.instantiate(adult.default_params()).unwrap());
        let child = template("child").unwrap();
        let c = body_radius(&child.instantiate(child.default_params()).unwrap());
        println!("adult {a:.3} child {c:.3}");
        assert!((0.2..0.4).contains(&a), "{a}");
        assert!(c < a, "{c} vs {a}");
    }
}
