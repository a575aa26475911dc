//! Skins shared between body sizes. Every length of a troupe template is a fraction of
//! the body's height, so a template's body at any height is its body at the default
//! height scaled, and so is its skin: the skin is made once per template, at the default
//! height, and each size uses it scaled. Building a skin takes seconds, so a scene of a
//! dozen people of different heights used to open a dozen seconds late (more for a
//! crowd), and kept a megabyte and a half per size on the GPU.
//!
//! A skeleton is taken for a template's only when it is one: the template of its name,
//! with every joint offset, end site and solid the default body's times one factor
//! ([`template_scale`]). Any other skeleton gets a skin of its own.

use super::Skin;
use crate::error::Result;
use crate::skeleton::{DofKind, Skeleton};
use crate::solid::Shape;
use crate::template::{templates, Template};
use crate::transform::Transform;
use glam::{DMat4, DVec3};
use std::sync::Arc;

/// How closely (m, times the scale when it is over 1) a skeleton's lengths must match
/// the template's scaled to be taken for it: rounding, not a different body.
const TOLERANCE: f64 = 1e-9;

/// A skin shared between sizes, and the factor that makes it the skin of one skeleton.
#[derive(Clone, Debug)]
pub struct SharedSkin {
    /// The skin as made (at the template's default height).
    pub skin: Arc<Skin>,
    /// The skeleton's lengths divided by those of the body the skin was made for.
    pub scale: f64,
}

impl SharedSkin {
    /// The skin at the skeleton's own size (what an exported file holds).
    pub fn to_skin(&self) -> Skin {
        if self.scale == 1.0 {
            (*self.skin).clone()
        } else {
            self.skin.scaled(self.scale)
        }
    }

    /// The skinning matrices of every slot for the skeleton's joint frames `globals`:
    /// they take the shared skin's bind-pose vertices to the posed skin of the skeleton's
    /// size (the rigid [`Skin::skinning_transforms`] with the scale between them).
    pub fn skinning_matrices(&self, globals: &[Transform]) -> Vec<DMat4> {
        let scale = DMat4::from_scale(DVec3::splat(self.scale));
        self.skin
            .scaled_frames(globals, self.scale)
            .iter()
            .zip(&self.skin.rest)
            .map(|(frame, rest)| matrix(frame) * scale * matrix(&rest.inverse()))
            .collect()
    }
}

/// `t` as a matrix.
fn matrix(t: &Transform) -> DMat4 {
    DMat4::from_rotation_translation(t.rotation, t.translation)
}

/// The skins made so far: one per template, and none for other skeletons (their
/// owners keep those).
#[derive(Debug, Default)]
pub struct SkinLibrary {
    made: Vec<(&'static str, Arc<Skin>)>,
}

impl SkinLibrary {
    /// The skin of `skeleton`: a template's at any height shares the template's skin,
    /// made on first use; any other skeleton's is made now (an error for a skeleton
    /// lacking a template's joints or solids, as [`Skin::build`]).
    pub fn get(&mut self, skeleton: &Skeleton) -> Result<SharedSkin> {
        let Some((template, scale)) = template_scale(skeleton) else {
            return Ok(SharedSkin {
                skin: Arc::new(Skin::build(skeleton)?),
                scale: 1.0,
            });
        };
        if let Some((_, skin)) = self.made.iter().find(|(name, _)| *name == template.name) {
            return Ok(SharedSkin {
                skin: skin.clone(),
                scale,
            });
        }
        let skin = Arc::new(Skin::build(
            &template.instantiate(template.default_params())?,
        )?);
        self.made.push((template.name, skin.clone()));
        Ok(SharedSkin { skin, scale })
    }
}

/// The template `skeleton` was made from and how many times the template's default body
/// it is; `None` unless it is exactly that body scaled (same joints, degrees of freedom
/// and solids, every length the default's times one factor).
pub fn template_scale(skeleton: &Skeleton) -> Option<(Template, f64)> {
    let template = templates()
        .into_iter()
        .find(|t| t.name == skeleton.name())?;
    let default = template.instantiate(template.default_params()).ok()?;
    let size = |s: &Skeleton| -> f64 { s.joints().iter().map(|j| j.offset.length()).sum() };
    let scale = size(skeleton) / size(&default);
    (scale.is_finite() && scale > 0.0 && is_scaled(&default, skeleton, scale))
        .then_some((template, scale))
}

/// Whether `other` is `base` with every length times `scale`.
fn is_scaled(base: &Skeleton, other: &Skeleton, scale: f64) -> bool {
    let tolerance = TOLERANCE * scale.max(1.0);
    let near = |a: DVec3, b: DVec3| (a * scale - b).length() <= tolerance;
    let joints = base.joints().len() == other.joints().len()
        && base.joints().iter().zip(other.joints()).all(|(a, b)| {
            a.name == b.name && a.parent == b.parent && a.dofs == b.dofs && near(a.offset, b.offset)
        });
    // A rotation's limits are angles; a translation's are lengths, which scale.
    let limit = |a: f64, b: f64, kind: DofKind| match kind {
        DofKind::Rotation => a == b,
        DofKind::Translation if a.is_finite() => (a * scale - b).abs() <= tolerance,
        DofKind::Translation => a == b,
    };
    let dofs = base.dofs().len() == other.dofs().len()
        && base.dofs().iter().zip(other.dofs()).all(|(a, b)| {
            a.name == b.name
                && a.joint == b.joint
                && a.kind == b.kind
                && a.axis == b.axis
                && limit(a.min, b.min, a.kind)
                && limit(a.max, b.max, a.kind)
        });
    let end_sites = base.end_sites().len() == other.end_sites().len()
        && base
            .end_sites()
            .iter()
            .zip(other.end_sites())
            .all(|(a, b)| a.0 == b.0 && near(a.1, b.1));
    let solids = base.solids().len() == other.solids().len()
        && base
            .solids()
            .iter()
            .zip(other.solids())
            .all(|((ja, a), (jb, b))| {
                ja == jb
                    && a.name == b.name
                    && near(a.center, b.center)
                    && a.orientation.angle_between(b.orientation) <= TOLERANCE
                    && shape_scaled(&a.shape, &b.shape, scale, tolerance)
            });
    joints && dofs && end_sites && solids
}

/// Whether shape `b` is shape `a` with every length times `scale` (within `tolerance`).
fn shape_scaled(a: &Shape, b: &Shape, scale: f64, tolerance: f64) -> bool {
    let same = |x: f64, y: f64| (x * scale - y).abs() <= tolerance;
    let same3 = |x: DVec3, y: DVec3| (x * scale - y).abs().max_element() <= tolerance;
    match (a, b) {
        (Shape::Box { half_extents: x }, Shape::Box { half_extents: y }) => same3(*x, *y),
        (Shape::Sphere { radius: x }, Shape::Sphere { radius: y }) => same(*x, *y),
        (
            Shape::Cylinder {
                radius: r1,
                height: h1,
            },
            Shape::Cylinder {
                radius: r2,
                height: h2,
            },
        ) => same(*r1, *r2) && same(*h1, *h2),
        (
            Shape::Frustum {
                bottom_radius: b1,
                top_radius: t1,
                height: h1,
            },
            Shape::Frustum {
                bottom_radius: b2,
                top_radius: t2,
                height: h2,
            },
        ) => same(*b1, *b2) && same(*t1, *t2) && same(*h1, *h2),
        (Shape::Ellipsoid { radii: x }, Shape::Ellipsoid { radii: y }) => same3(*x, *y),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::forward_kinematics;
    use crate::template::{template, TemplateParams};

    fn adult(height: f64) -> Skeleton {
        template("adult")
            .unwrap()
            .instantiate(TemplateParams { height, mass: 60.0 })
            .unwrap()
    }

    #[test]
    fn a_template_at_any_height_is_its_default_body_scaled() {
        for (height, name) in [(1.2, "adult"), (1.75, "adult"), (2.3, "adult")] {
            let (t, scale) = template_scale(&adult(height)).unwrap();
            assert_eq!(t.name, name);
            assert!((scale - height / 1.75).abs() < 1e-12, "{height}: {scale}");
        }
        let child = template("child").unwrap();
        let (t, scale) = template_scale(
            &child
                .instantiate(TemplateParams {
                    height: 1.0,
                    mass: 20.0,
                })
                .unwrap(),
        )
        .unwrap();
        assert_eq!(t.name, "child");
        assert!((scale - 1.0 / child.default_height).abs() < 1e-12);
    }

    #[test]
    fn a_body_of_other_proportions_is_not_a_templates() {
        // A child's body is not the adult's scaled, even at the adult's name.
        let adult_default = adult(1.75);
        let child = template("child")
            .unwrap()
            .instantiate(TemplateParams {
                height: 1.75,
                mass: 60.0,
            })
            .unwrap();
        let size = |s: &Skeleton| -> f64 { s.joints().iter().map(|j| j.offset.length()).sum() };
        let scale = size(&child) / size(&adult_default);
        assert!(!is_scaled(&adult_default, &child, scale));
        // And a factor off by a millionth is not the body's.
        let tall = adult(1.9);
        assert!(is_scaled(&adult_default, &tall, 1.9 / 1.75));
        assert!(!is_scaled(&adult_default, &tall, 1.9 / 1.75 * (1.0 + 1e-6)));
    }

    #[test]
    fn the_shared_skin_scaled_is_the_skin_of_the_scaled_body() {
        let mut library = SkinLibrary::default();
        let (short, tall) = (adult(1.5), adult(1.95));
        let a = library.get(&short).unwrap();
        let b = library.get(&tall).unwrap();
        assert!(Arc::ptr_eq(&a.skin, &b.skin), "one skin for both sizes");
        // Its bind frames are the scaled body's own: the skin a build of that body makes
        // has the same (they depend only on the skeleton).
        let own = Skin::build(&short).unwrap();
        let scaled = a.to_skin();
        for (s, o) in scaled.rest.iter().zip(&own.rest) {
            assert!((s.translation - o.translation).length() < 1e-9);
            // Compared by components: `angle_between` of two equal rotations turned
            // about x by 30° (the hips' and knees' in the bound posture) is 3·10⁻⁸, the
            // arccosine's rounding.
            assert!(
                s.rotation.abs_diff_eq(o.rotation, 1e-12),
                "{s:?} against {o:?}"
            );
        }
        // And its surface is where that build puts the body's: the same bounds, within the
        // surface grid's cell (height/400, 3.75 mm), and the same area within 1 %.
        let bounds = |p: &[[f32; 3]]| {
            p.iter()
                .map(|v| DVec3::from(v.map(f64::from)))
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(v), hi.max(v))
                })
        };
        let area = |skin: &Skin| -> f64 {
            let p = |i: u32| DVec3::from(skin.positions[i as usize].map(f64::from));
            skin.indices
                .chunks_exact(3)
                .map(|t| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).length() / 2.0)
                .sum()
        };
        let ((lo, hi), (own_lo, own_hi)) = (bounds(&scaled.positions), bounds(&own.positions));
        let worst = (lo - own_lo).abs().max((hi - own_hi).abs()).max_element();
        let (area_scaled, area_own) = (area(&scaled), area(&own));
        eprintln!(
            "bounds within {worst:.4} m of the own build's; area {area_scaled:.4} against {area_own:.4} m²"
        );
        assert!(
            worst < 1.5 / 400.0,
            "bounds {lo}..{hi} against {own_lo}..{own_hi}"
        );
        assert!(
            (area_scaled / area_own - 1.0).abs() < 0.01,
            "area {area_scaled} against {area_own}"
        );
        // Posed, the scaled skin is the shared skin's pose scaled, and the matrices the
        // viewer uploads take the shared vertices there.
        let q: Vec<f64> = short
            .dofs()
            .iter()
            .enumerate()
            .map(|(i, d)| {
                if d.min.is_finite() && d.max.is_finite() {
                    d.min + (d.max - d.min) * ((i * 37 % 101) as f64 / 100.0)
                } else {
                    0.0
                }
            })
            .collect();
        let mut at_short = vec![Transform::IDENTITY; short.joints().len()];
        forward_kinematics(&short, &q, &mut at_short);
        let mut at_default = at_short.clone();
        forward_kinematics(&adult(1.75), &q, &mut at_default);
        let posed = scaled.deform(&at_short);
        let reference = a.skin.deform(&at_default);
        let matrices = a.skinning_matrices(&at_short);
        for (v, ((p, r), rest)) in posed
            .iter()
            .zip(&reference)
            .zip(&a.skin.positions)
            .enumerate()
        {
            assert!((*p - *r * a.scale).length() < 1e-5, "vertex {v}");
            let rest = DVec3::from(rest.map(f64::from));
            let by_matrices: DVec3 = a.skin.joints[v]
                .iter()
                .zip(&a.skin.weights[v])
                .map(|(&j, &w)| matrices[j as usize].transform_point3(rest) * w as f64)
                .sum();
            assert!((by_matrices - *p).length() < 1e-5, "vertex {v}");
        }
    }
}
