//! The posture the skin is bound in, which is not quite the one it is made in.
//!
//! Linear blend skinning folds the inside of a bend by how far the joint has turned from
//! the posture the skin is bound in: a band of weights of length L turning the skin at
//! distance r from the joint by θ folds it when L < 2·r·tan(θ/2) (docs/viewer.md). The
//! skin is made with the legs straight and the clavicles level
//! ([`super::bind_posture`]), where the volumes lie apart and the surface and the
//! weights come out clean; but a hip's range is −30…120°, so bound there, a hip flexed
//! to its limit has turned 120°.
//!
//! So the skin made in the bind posture is carried by its own weights to the
//! [`bound_posture`], the hips a little flexed and the clavicles a little raised, and
//! bound there: its positions and normals are those, its rest frames the slots' frames
//! there ([`super::Skin::rest`]); its surface, weights and helpers are the ones it was
//! made with. Every other posture is skinned from there.
//!
//! What it costs is the body standing as it was made. Carried to the bound posture and
//! back, a vertex that blends two joints turned apart comes back nearer to them (a blend
//! of rotations is shorter than each), and further the more they turned: the skin back
//! in the bind posture is within 2.6 mm of the surface it was made as with the hips bound
//! at 15°, 4.6 mm at 20°, 1.0 cm at 30° and 2.3 cm at 45°, where the folds are fewest
//! (1,032 over `examples/skin_folds.rs`' 3,000 full-range postures bound where the skin
//! is made; 717 at 20°, 665 at 30°, 630 at 45°). The hips are bound at 20°, which keeps
//! the body within the surface grid's cell (4.4 mm on a 1.75 m adult): with the clavicles
//! at 7.5°, 649 folds, the hips and the pelvis 544 → 229, vt1 185 → 131 (the test below
//! holds the standing body to 5 mm; docs/skin-notes.md, "Bound a little bent").
//!
//! Making the skin in a flexed posture instead (tried with the hips at 15-45°) folded
//! more, not less: the thighs' volumes then lie against the lower belly, whose weights
//! and surface changed with them (docs/skin-notes.md, "The hips made flexed"). Carrying
//! the mesh to the bound posture so that it comes back to the surface exactly (each
//! vertex moved by the inverse of its blend) folded three times as many: the body
//! standing is exact only with the folds of the skin bound where it is made.

use crate::kinematics::forward_kinematics;
use crate::skeleton::Skeleton;
use crate::transform::Transform;

/// How far the hips are flexed (degrees) in the posture the skin is bound in: as far as
/// keeps the standing body within the surface grid's cell of the surface it is made as
/// (see [the module](self)).
pub const BOUND_HIP_FLEXION: f64 = 20.0;

/// How far the clavicles are raised (degrees) in the posture the skin is bound in, of their
/// −10…40° range: a shrug folds the crease between the neck and the trapezius (vt1's
/// folds; 0.7 mm off the standing body). With the hips bound at 45° and the knees at
/// 75°: 594 level, 534 at 5°, 526 at 7.5°, 534 at 10°; at 15° vt1's folds fell but the
/// shoulders' doubled.
pub const BOUND_CLAVICLE_ELEVATION: f64 = 7.5;

/// The posture the skin is bound in: [`super::bind_posture`], where it is made, with the
/// hips flexed by [`BOUND_HIP_FLEXION`] and the clavicles raised by
/// [`BOUND_CLAVICLE_ELEVATION`] (each DOF the skeleton has).
pub fn bound_posture(skeleton: &Skeleton) -> Vec<f64> {
    let mut q = super::bind_posture(skeleton);
    for side in ["l_", "r_"] {
        for (dof, degrees) in [
            ("hip_flexion", BOUND_HIP_FLEXION),
            ("sternoclavicular_elevation", BOUND_CLAVICLE_ELEVATION),
        ] {
            if let Ok(d) = skeleton.dof(&format!("{side}{dof}")) {
                q[d] += degrees.to_radians();
            }
        }
    }
    q
}

/// The joint frames of `skeleton` in its [`bound_posture`].
pub fn bound_globals(skeleton: &Skeleton) -> Vec<Transform> {
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &bound_posture(skeleton), &mut globals);
    globals
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skin::{bind_globals, Skin};
    use crate::template::default_skeleton;
    use glam::DVec3;

    /// The skin bound a little bent, posed back in the posture it is made in, is the
    /// surface it was made as within 5 mm (the surface grid's cell is 4.4 mm on this
    /// adult): 4.6 mm at the worst, at the crease under the buttocks. Bound at 30° it was
    /// 1.0 cm, at 45° 2.3 cm.
    #[test]
    fn the_skin_bound_a_little_bent_stands_as_it_was_made() {
        let skeleton = default_skeleton("adult").unwrap();
        let (made, mirror) = Skin::made(&skeleton).unwrap();
        let bound = made.clone().bound_at(&bound_globals(&skeleton), &mirror);
        let standing = bound.deform(&bind_globals(&skeleton));
        let worst = standing
            .iter()
            .zip(&made.positions)
            .map(|(p, m)| (*p - DVec3::from(m.map(f64::from))).length())
            .fold(0.0, f64::max);
        assert!(worst < 0.005, "a vertex {worst:.4} m off the surface");
        // And it is bound elsewhere: the hips' rest frames are turned.
        let hip = skeleton.joint("l_hip").unwrap();
        assert!(
            bound.rest[hip]
                .rotation
                .angle_between(made.rest[hip].rotation)
                > 0.3
        );
    }
}
