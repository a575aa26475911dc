//! Collision between separate bodies, and between a body and the objects around it
//! (thesis 6.5.3, Collisionlib's role in Track: detection between actors, the response
//! vector that correction follows).
//!
//! **The volumes.** A body's solids are covered for collision by **tapered capsules**:
//! a segment whose radius changes linearly from one end to the other (the union of the
//! spheres centred on the segment). A limb's frustum or a trunk's cylinder becomes the
//! capsule along its axis with its end radii; a sphere (the hand) is itself; an
//! ellipsoid (the head) becomes the capsule along its longest axis with the largest other
//! radius. Every capsule *contains* its solid, so a depth measured between capsules is
//! never smaller than the solids' own: "at most 1 cm between capsules" holds for the
//! solids. Objects and walls keep their exact shape ([`Volume::Shape`]), measured by
//! their signed distance.
//!
//! **The depth.** Between two capsules, the deepest interpenetration is the largest
//! `r₁(s) + r₂(t) − |p₁(s) − p₂(t)|` over both segments: a concave function of (s, t),
//! whose inner maximum has a closed form and whose outer one a golden-section search
//! finds. Between a capsule and a shape, it is the largest `r(s) − d(p(s))`, `d` the
//! shape's signed distance (convex), again concave in `s`. Both are exact up to the
//! search's tolerance (a micrometre) and cost well under a microsecond.

use crate::skeleton::Skeleton;
use crate::solid::{Shape, Solid};
use crate::transform::Transform;
use glam::{DQuat, DVec3};

/// A tapered capsule: every point within `radius(t) = ra + (rb − ra)·t` of the point
/// `a + (b − a)·t` of its segment, for `t` in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// One end of the segment.
    pub a: DVec3,
    /// The other end.
    pub b: DVec3,
    /// The radius at `a` (m).
    pub ra: f64,
    /// The radius at `b` (m).
    pub rb: f64,
}

/// Something a body can run into: another body's capsule, or an object's exact shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Volume {
    /// A body part (see [`Capsule`]).
    Capsule(Capsule),
    /// An object or a wall: a shape placed in the world by `pose` (its canonical frame).
    Shape {
        /// The shape in its canonical frame.
        shape: Shape,
        /// Where the canonical frame is in the world.
        pose: Transform,
    },
}

/// How far a sphere enters a volume, and which way leads out.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Penetration {
    /// How deep (m; negative: that far apart).
    pub depth: f64,
    /// The volume's outward unit normal near the sphere (world): the response vector's
    /// direction.
    pub normal: DVec3,
}

/// Whether a sphere (centre `c`, `radius`) is more than `margin` away from everything
/// within `bound` of `centre` (a [`Capsule::bound`]), so more than `margin`
/// from what that sphere holds: a quick test before measuring it against a capsule (a
/// reach in a crowd has a few hundred round it, nearly all far). The nanometre keeps
/// rounding from deciding what the exact measure would not.
pub fn sphere_beyond(c: DVec3, radius: f64, margin: f64, (centre, bound): (DVec3, f64)) -> bool {
    let far = radius + bound + margin + 1e-9;
    (c - centre).length_squared() > far * far
}

/// Volumes a sphere is tested against many times, each capsule with the sphere that holds
/// it ([`Capsule::bound`]), found once: a reach in a crowd tests its arm's
/// sensors at every IK iteration, and plans its temporary goals over hundreds of
/// thousands of points, against a few hundred capsules, nearly all of them far (finding
/// each bound at each test was 105 M of the 145 M instructions a plan took in the crowd
/// benchmark).
#[derive(Clone, Debug, Default)]
pub struct VolumesAround<'a> {
    /// The volumes.
    pub volumes: &'a [Volume],
    /// Per volume, a capsule's bounding sphere (centre, radius); `None` for a shape.
    bounds: Vec<Option<(DVec3, f64)>>,
}

impl<'a> VolumesAround<'a> {
    /// `volumes` with their bounds.
    pub fn new(volumes: &'a [Volume]) -> VolumesAround<'a> {
        let bounds = volumes
            .iter()
            .map(|v| match v {
                Volume::Capsule(k) => Some(k.bound()),
                Volume::Shape { .. } => None,
            })
            .collect();
        VolumesAround { volumes, bounds }
    }

    /// Whether a sphere (centre `c`, `radius`) may come within `margin` of volume `k`:
    /// false only when it surely stays farther (see [`sphere_beyond`]).
    pub fn may_reach(&self, k: usize, c: DVec3, radius: f64, margin: f64) -> bool {
        self.bounds[k].is_none_or(|bounds| !sphere_beyond(c, radius, margin, bounds))
    }

    /// The volumes a sphere (centre `c`, `radius`) may come within `margin` of.
    pub fn near(
        &self,
        c: DVec3,
        radius: f64,
        margin: f64,
    ) -> impl Iterator<Item = &'a Volume> + '_ {
        (0..self.volumes.len())
            .filter(move |&k| self.may_reach(k, c, radius, margin))
            .map(|k| &self.volumes[k])
    }
}

impl Capsule {
    /// The point of the segment at `t`.
    #[inline]
    pub fn point(&self, t: f64) -> DVec3 {
        self.a + (self.b - self.a) * t
    }

    /// The radius at `t`.
    #[inline]
    pub fn radius(&self, t: f64) -> f64 {
        self.ra + (self.rb - self.ra) * t
    }

    /// The capsule moved by `frame`.
    pub fn placed(&self, frame: &Transform) -> Capsule {
        Capsule {
            a: frame.transform_point(self.a),
            b: frame.transform_point(self.b),
            ..*self
        }
    }

    /// The capsule that covers `shape` placed at `center` with `orientation` (in some
    /// frame; the capsule is in the same frame). See the module docs.
    pub fn covering(shape: &Shape, center: DVec3, orientation: DQuat) -> Capsule {
        let along = |axis: DVec3, half: f64, ra: f64, rb: f64| Capsule {
            a: center - orientation * (axis * half),
            b: center + orientation * (axis * half),
            ra,
            rb,
        };
        match *shape {
            Shape::Sphere { radius } => along(DVec3::Y, 0.0, radius, radius),
            Shape::Cylinder { radius, height } => along(DVec3::Y, height / 2.0, radius, radius),
            Shape::Frustum {
                bottom_radius,
                top_radius,
                height,
            } => along(DVec3::Y, height / 2.0, bottom_radius, top_radius),
            Shape::Ellipsoid { radii } => {
                // The longest axis carries the segment; the largest other radius is the
                // capsule's (which holds the ellipsoid: at a distance x past the
                // segment's end, the ellipsoid's section is never wider than the cap's).
                let (axis, long, other) = longest_axis(radii);
                along(axis, (long - other).max(0.0), other, other)
            }
            Shape::Box { half_extents } => {
                let (axis, long, _) = longest_axis(half_extents);
                let cross = (half_extents.length_squared() - long * long).sqrt();
                along(axis, long, cross, cross)
            }
        }
    }

    /// The centre and radius of a sphere that holds the capsule: every point of it lies
    /// within the radius of the centre.
    pub fn bound(&self) -> (DVec3, f64) {
        let c = (self.a + self.b) / 2.0;
        (c, (self.b - self.a).length() / 2.0 + self.ra.max(self.rb))
    }
}

/// The longest of three semi-axes: its unit axis, its length and the largest other.
fn longest_axis(v: DVec3) -> (DVec3, f64, f64) {
    if v.x >= v.y && v.x >= v.z {
        (DVec3::X, v.x, v.y.max(v.z))
    } else if v.y >= v.z {
        (DVec3::Y, v.y, v.x.max(v.z))
    } else {
        (DVec3::Z, v.z, v.x.max(v.y))
    }
}

/// The parameter `t` in [0, 1] of `capsule` that maximizes `radius(t) − |p − point(t)|`
/// (closed form: the function is concave in `t`).
fn nearest_on(capsule: &Capsule, p: DVec3) -> f64 {
    let d = capsule.b - capsule.a;
    let len2 = d.length_squared();
    if len2 < 1e-18 {
        return 0.0;
    }
    let len = len2.sqrt();
    let t0 = d.dot(p - capsule.a) / len2;
    let h = (p - capsule.point(t0)).length();
    // With slope c = dr/ds, the optimum lies c·h/√(1 − c²) along the axis past the
    // projection (towards the wider end).
    let c = ((capsule.rb - capsule.ra) / len).clamp(-0.999, 0.999);
    (t0 + c * h / (1.0 - c * c).sqrt() / len).clamp(0.0, 1.0)
}

/// The golden-section maximum over [0, 1] of a concave `f`: the argument and the value.
fn maximize(f: impl Fn(f64) -> f64) -> (f64, f64) {
    const INV_PHI: f64 = 0.618_033_988_749_894_9;
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    let mut x1 = hi - INV_PHI * (hi - lo);
    let mut x2 = lo + INV_PHI * (hi - lo);
    let (mut f1, mut f2) = (f(x1), f(x2));
    // 30 steps shrink the bracket to 0.618³⁰ ≈ 5e-7 of the segment.
    for _ in 0..30 {
        if f1 < f2 {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + INV_PHI * (hi - lo);
            f2 = f(x2);
        } else {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - INV_PHI * (hi - lo);
            f1 = f(x1);
        }
    }
    // The ends too: a concave function on a segment may peak at either.
    [(x1, f1), (0.0, f(0.0)), (1.0, f(1.0))]
        .into_iter()
        .fold(
            (x1, f64::NEG_INFINITY),
            |best, c| if c.1 > best.1 { c } else { best },
        )
}

impl Volume {
    /// A sphere around the volume: centre and radius (for a quick rejection).
    pub fn bound(&self) -> (DVec3, f64) {
        match self {
            Volume::Capsule(c) => c.bound(),
            Volume::Shape { shape, pose } => {
                let r = match *shape {
                    Shape::Box { half_extents } => half_extents.length(),
                    Shape::Sphere { radius } => radius,
                    Shape::Cylinder { radius, height } => radius.hypot(height / 2.0),
                    Shape::Frustum {
                        bottom_radius,
                        top_radius,
                        height,
                    } => bottom_radius.max(top_radius).hypot(height / 2.0),
                    Shape::Ellipsoid { radii } => radii.max_element(),
                };
                (pose.translation, r)
            }
        }
    }

    /// How far a sphere (centre `c`, `radius`) enters the volume, and the way out.
    pub fn sphere(&self, c: DVec3, radius: f64) -> Penetration {
        match self {
            Volume::Capsule(k) => {
                let t = nearest_on(k, c);
                let off = c - k.point(t);
                let dist = off.length();
                let normal = if dist > 1e-12 {
                    off / dist
                } else {
                    // On the axis: out sideways, the same way every time.
                    (k.b - k.a).any_orthonormal_vector()
                };
                Penetration {
                    depth: radius + k.radius(t) - dist,
                    normal,
                }
            }
            Volume::Shape { shape, pose } => shape_sphere(shape, pose, c, radius),
        }
    }

    /// How far a sphere (centre `c`, `radius`) enters the volume: [`Volume::sphere`]'s
    /// depth without the normal (a shape's gradient costs six more distances).
    pub fn sphere_depth(&self, c: DVec3, radius: f64) -> f64 {
        match self {
            Volume::Capsule(_) => self.sphere(c, radius).depth,
            Volume::Shape { shape, pose } => {
                radius - signed_distance(shape, pose.inverse().transform_point(c))
            }
        }
    }

    /// Whether `capsule` may touch the volume: false only when it surely does not (a
    /// quick test before [`Volume::capsule_depth`]'s search). Against a capsule, the axes'
    /// distance; against a shape, its signed distance at the axis' middle, which no point
    /// of the axis undercuts by more than half its length (a distance changes no faster
    /// than the point moves).
    pub fn may_touch(&self, capsule: &Capsule) -> bool {
        let widest = capsule.ra.max(capsule.rb);
        match self {
            Volume::Capsule(k) => {
                segment_distance(capsule.a, capsule.b, k.a, k.b) < widest + k.ra.max(k.rb)
            }
            Volume::Shape { shape, pose } => {
                let mid = pose.inverse().transform_point(capsule.point(0.5));
                signed_distance(shape, mid) - (capsule.b - capsule.a).length() / 2.0 < widest
            }
        }
    }

    /// The deepest interpenetration of `capsule` with this volume (m; negative: the
    /// distance between them), and the point of the capsule's axis where it is.
    pub fn capsule_depth(&self, capsule: &Capsule) -> (f64, DVec3) {
        let (t, depth) = maximize(|t| self.sphere_depth(capsule.point(t), capsule.radius(t)));
        (depth, capsule.point(t))
    }
}

/// How far a sphere (centre `c`, `radius`, world) enters `shape` placed by `pose`; the
/// normal is the signed distance's gradient, turned into the world.
pub fn shape_sphere(shape: &Shape, pose: &Transform, c: DVec3, radius: f64) -> Penetration {
    let p = pose.inverse().transform_point(c);
    let d = signed_distance(shape, p);
    let g = outward(shape, p);
    Penetration {
        depth: radius - d,
        normal: pose.rotation * g,
    }
}

/// The unit gradient of `shape`'s signed distance at `p` (canonical frame): the way out
/// of the solid there (central differences; straight up where it vanishes).
pub fn outward(shape: &Shape, p: DVec3) -> DVec3 {
    let h = 1e-5;
    let g = DVec3::new(
        signed_distance(shape, p + DVec3::X * h) - signed_distance(shape, p - DVec3::X * h),
        signed_distance(shape, p + DVec3::Y * h) - signed_distance(shape, p - DVec3::Y * h),
        signed_distance(shape, p + DVec3::Z * h) - signed_distance(shape, p - DVec3::Z * h),
    );
    if g.length_squared() > 1e-30 {
        g.normalize()
    } else {
        DVec3::Y
    }
}

/// Signed distance from `p` (in the shape's canonical frame) to the surface of `shape`:
/// negative inside. Exact for spheres, boxes and cylinders; for frusta and ellipsoids a
/// first-order estimate with the exact sign.
pub fn signed_distance(shape: &Shape, p: DVec3) -> f64 {
    fn capped(dr: f64, dy: f64) -> f64 {
        dr.max(dy).min(0.0) + DVec3::new(dr.max(0.0), dy.max(0.0), 0.0).length()
    }
    match *shape {
        Shape::Sphere { radius } => p.length() - radius,
        Shape::Box { half_extents } => {
            let q = p.abs() - half_extents;
            q.max(DVec3::ZERO).length() + q.max_element().min(0.0)
        }
        Shape::Cylinder { radius, height } => {
            capped(p.x.hypot(p.z) - radius, p.y.abs() - height / 2.0)
        }
        Shape::Frustum {
            bottom_radius,
            top_radius,
            height,
        } => {
            let hh = height / 2.0;
            let s = (p.y.clamp(-hh, hh) / height) + 0.5;
            let r = bottom_radius + (top_radius - bottom_radius) * s;
            let slope = (top_radius - bottom_radius) / height;
            let dr = (p.x.hypot(p.z) - r) / (1.0 + slope * slope).sqrt();
            capped(dr, p.y.abs() - hh)
        }
        Shape::Ellipsoid { radii } => {
            let k0 = (p / radii).length();
            let k1 = (p / (radii * radii)).length();
            if k1 < 1e-12 {
                -radii.min_element()
            } else {
                k0 * (k0 - 1.0) / k1
            }
        }
    }
}

/// A body's collision volumes: one capsule per solid, in its joint's frame. Built once
/// per skeleton; [`BodyVolumes::place`] puts them in the world for a posture.
#[derive(Clone, Debug, PartialEq)]
pub struct BodyVolumes {
    /// (joint, capsule in the joint's frame), in the skeleton's solid order.
    capsules: Vec<(usize, Capsule)>,
}

impl BodyVolumes {
    /// The capsules covering every solid of `skeleton`.
    pub fn new(skeleton: &Skeleton) -> BodyVolumes {
        let capsules = skeleton
            .solids()
            .iter()
            .map(|(joint, s): &(usize, Solid)| {
                (*joint, Capsule::covering(&s.shape, s.center, s.orientation))
            })
            .collect();
        BodyVolumes { capsules }
    }

    /// How many capsules (one per solid).
    pub fn len(&self) -> usize {
        self.capsules.len()
    }

    /// Whether the body has no solids.
    pub fn is_empty(&self) -> bool {
        self.capsules.is_empty()
    }

    /// The joint that carries capsule `i`.
    pub fn joint(&self, i: usize) -> usize {
        self.capsules[i].0
    }

    /// Replaces `out` with the world capsules for joint transforms `globals`.
    pub fn place(&self, globals: &[Transform], out: &mut Vec<Capsule>) {
        out.clear();
        out.extend(self.capsules.iter().map(|(j, c)| c.placed(&globals[*j])));
    }
}

/// The distance between the segments `p0–p1` and `q0–q1` (closest points in closed
/// form, after Ericson, *Real-Time Collision Detection*, 5.1.9).
pub fn segment_distance(p0: DVec3, p1: DVec3, q0: DVec3, q1: DVec3) -> f64 {
    let (d1, d2, r) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, e, f) = (d1.length_squared(), d2.length_squared(), d2.dot(r));
    let eps = 1e-18;
    let (s, t) = if a <= eps && e <= eps {
        (0.0, 0.0)
    } else if a <= eps {
        (0.0, (f / e).clamp(0.0, 1.0))
    } else {
        let c = d1.dot(r);
        if e <= eps {
            ((-c / a).clamp(0.0, 1.0), 0.0)
        } else {
            let b = d1.dot(d2);
            let denom = a * e - b * b;
            let mut s = if denom > eps {
                ((b * f - c * e) / denom).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut t = (b * s + f) / e;
            if t < 0.0 {
                t = 0.0;
                s = (-c / a).clamp(0.0, 1.0);
            } else if t > 1.0 {
                t = 1.0;
                s = ((b - c) / a).clamp(0.0, 1.0);
            }
            (s, t)
        }
    };
    ((p0 + d1 * s) - (q0 + d2 * t)).length()
}

/// The deepest interpenetration between two sets of capsules (two bodies): the depth
/// and the indices of the two capsules; `None` when no two touch. Pairs that surely do
/// not touch ([`Volume::may_touch`]) are skipped before the exact (search) depth.
pub fn deepest_between(a: &[Capsule], b: &[Capsule]) -> Option<(f64, usize, usize)> {
    let mut best: Option<(f64, usize, usize)> = None;
    for (i, ca) in a.iter().enumerate() {
        for (j, cb) in b.iter().enumerate() {
            let other = Volume::Capsule(*cb);
            if !other.may_touch(ca) {
                continue;
            }
            let (depth, _) = other.capsule_depth(ca);
            if depth <= 0.0 {
                continue;
            }
            if best.is_none_or(|(d, _, _)| depth > d) {
                best = Some((depth, i, j));
            }
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cap(a: [f64; 3], b: [f64; 3], ra: f64, rb: f64) -> Capsule {
        Capsule {
            a: DVec3::from(a),
            b: DVec3::from(b),
            ra,
            rb,
        }
    }

    #[test]
    fn crossing_capsules_interpenetrate_by_their_radii_less_the_axes_distance() {
        let x = cap([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.1, 0.1);
        let z = cap([0.0, 0.15, -1.0], [0.0, 0.15, 1.0], 0.1, 0.1);
        let (d, at) = Volume::Capsule(z).capsule_depth(&x);
        assert!((d - 0.05).abs() < 1e-6, "{d}");
        assert!(at.length() < 1e-3, "{at}");
        // Apart: the negative depth is the gap.
        let far = cap([0.0, 0.5, -1.0], [0.0, 0.5, 1.0], 0.1, 0.1);
        let (d, _) = Volume::Capsule(far).capsule_depth(&x);
        assert!((d + 0.3).abs() < 1e-6, "{d}");
    }

    #[test]
    fn segment_distances_match_a_brute_force_search() {
        let cases = [
            (
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.5, 1.0, -1.0],
                [0.5, 1.0, 1.0],
            ),
            (
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [2.0, 0.5, 0.0],
                [3.0, 0.5, 0.0],
            ),
            (
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.2, 0.3, 0.0],
                [0.8, 0.3, 0.0],
            ),
            (
                [0.0, 0.0, 0.0],
                [0.0, 0.0, 0.0],
                [0.2, 0.3, 0.0],
                [0.8, 0.3, 0.4],
            ),
        ];
        for (p0, p1, q0, q1) in cases {
            let (p0, p1, q0, q1) = (
                DVec3::from(p0),
                DVec3::from(p1),
                DVec3::from(q0),
                DVec3::from(q1),
            );
            let mut brute = f64::INFINITY;
            for i in 0..=200 {
                for j in 0..=200 {
                    let (s, t) = (i as f64 / 200.0, j as f64 / 200.0);
                    brute = brute.min((p0.lerp(p1, s) - q0.lerp(q1, t)).length());
                }
            }
            let d = segment_distance(p0, p1, q0, q1);
            assert!(
                (d - brute).abs() < 1e-3 && d <= brute + 1e-12,
                "{d} vs {brute}"
            );
        }
    }

    #[test]
    fn a_sphere_a_capsule_passes_over_is_beyond_its_margin() {
        // Spheres round tapered capsules at every distance: whenever the quick test
        // says a sphere cannot come within the margin, the measured depth agrees.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut passed_over, mut measured) = (0, 0);
        for _ in 0..20_000 {
            let mut point = || DVec3::new(next() - 0.5, next() - 0.5, next() - 0.5);
            let (a, b, c) = (point(), point(), point() * 1.5);
            let k = cap(a.into(), b.into(), next() * 0.2, next() * 0.2);
            let (radius, margin) = (next() * 0.1, next() * 0.05);
            if sphere_beyond(c, radius, margin, k.bound()) {
                passed_over += 1;
                let depth = Volume::Capsule(k).sphere(c, radius).depth;
                assert!(depth <= -margin, "{k:?} {c}");
            } else {
                measured += 1;
            }
        }
        assert!(
            passed_over > 1_000 && measured > 1_000,
            "{passed_over} {measured}"
        );
    }

    #[test]
    fn a_tapered_capsule_is_deepest_where_it_is_wide() {
        // A cone-like capsule along x, wide at +x; a sphere above it.
        let k = cap([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.0, 0.2);
        let p = Volume::Capsule(k).sphere(DVec3::new(0.5, 0.15, 0.0), 0.0);
        // Brute force over the axis.
        let brute = (0..=10000)
            .map(|i| {
                let t = i as f64 / 10000.0;
                k.radius(t) - (DVec3::new(0.5, 0.15, 0.0) - k.point(t)).length()
            })
            .fold(f64::NEG_INFINITY, f64::max);
        assert!((p.depth - brute).abs() < 1e-6, "{} vs {brute}", p.depth);
    }

    #[test]
    fn a_capsule_against_a_box_finds_the_deepest_point() {
        let table = Volume::Shape {
            shape: Shape::Box {
                half_extents: DVec3::new(1.0, 0.375, 0.5),
            },
            pose: Transform::from_translation(DVec3::new(0.0, 0.375, 0.0)),
        };
        // A forearm sloping down into the table top: its low end 2 cm below the top.
        let arm = cap([0.0, 1.0, 0.0], [0.3, 0.73 + 0.02, 0.0], 0.02, 0.02);
        let (d, at) = table.capsule_depth(&arm);
        assert!((d - 0.02).abs() < 1e-5, "{d}");
        assert!((at.x - 0.3).abs() < 1e-3, "{at}");
    }

    #[test]
    fn covering_capsules_hold_their_solids() {
        let shapes = [
            Shape::Ellipsoid {
                radii: DVec3::new(0.08, 0.12, 0.1),
            },
            Shape::Frustum {
                bottom_radius: 0.03,
                top_radius: 0.05,
                height: 0.4,
            },
            Shape::Box {
                half_extents: DVec3::new(0.1, 0.3, 0.2),
            },
        ];
        for shape in shapes {
            let k = Capsule::covering(&shape, DVec3::ZERO, DQuat::IDENTITY);
            // Points sampled on a grid: inside the solid ⇒ inside the capsule.
            for i in -10..=10 {
                for j in -10..=10 {
                    for l in -10..=10 {
                        let p = DVec3::new(i as f64, j as f64, l as f64) * 0.031;
                        if shape.contains(p) {
                            let s = Volume::Capsule(k).sphere(p, 0.0);
                            assert!(s.depth >= -1e-9, "{shape:?} {p}: {}", s.depth);
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_body_at_rest_has_a_capsule_per_solid_around_its_joints() {
        use crate::kinematics::forward_kinematics;
        use crate::template::template;
        let t = template("adult").unwrap();
        let s = t.instantiate(t.default_params()).unwrap();
        let v = BodyVolumes::new(&s);
        assert_eq!(v.len(), s.solids().len());
        let mut g = vec![Transform::IDENTITY; s.joints().len()];
        forward_kinematics(&s, &vec![0.0; s.dof_count()], &mut g);
        let mut placed = Vec::new();
        v.place(&g, &mut placed);
        // Two bodies side by side 1 m apart do not touch; 0.3 m apart they do.
        let shifted = |dx: f64| -> Vec<Capsule> {
            let f = Transform::from_translation(DVec3::new(dx, 0.0, 0.0));
            placed.iter().map(|c| c.placed(&f)).collect()
        };
        assert_eq!(deepest_between(&placed, &shifted(1.0)), None);
        let (d, _, _) = deepest_between(&placed, &shifted(0.3)).unwrap();
        assert!(d > 0.05, "{d}");
    }
}
