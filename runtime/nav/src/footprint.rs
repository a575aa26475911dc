//! Footprints: what an obstacle covers of the floor, as a convex polygon in (x, z).

use troupe_body::glam::{DQuat, DVec2, DVec3};
use troupe_body::object::Object;
use troupe_body::solid::Shape;

/// Points on a circle's polygon: enough that the polygon stays within 2 % of the circle.
const CIRCLE_SIDES: usize = 16;
/// An object whose lowest point is at most this high (m) stands on the floor.
pub const ON_FLOOR: f64 = 0.05;

/// The floor area an obstacle covers: a convex polygon in (x, z), counter-clockwise seen
/// from above, with the name people know the obstacle by.
#[derive(Clone, Debug, PartialEq)]
pub struct Footprint {
    /// The obstacle's name ("table", "wall 2", "actor bob").
    pub name: String,
    /// Corners in (x, z), counter-clockwise about +Y.
    pub outline: Vec<DVec2>,
}

impl Footprint {
    /// The footprint of the convex hull of `points` (x, z), called `name`.
    pub fn hull(name: impl Into<String>, points: &[DVec2]) -> Footprint {
        Footprint {
            name: name.into(),
            outline: convex_hull(points),
        }
    }

    /// A disc of `radius` around `centre`, as a polygon that contains the disc.
    pub fn disc(name: impl Into<String>, centre: DVec2, radius: f64) -> Footprint {
        let points: Vec<DVec2> = circle(radius).map(|p| centre + p).collect();
        Footprint::hull(name, &points)
    }

    /// The footprint of `object` seen from above, and the height of its lowest point.
    pub fn of_object(object: &Object) -> (Footprint, f64) {
        let points = surface_points(&object.shape, object.rotation, object.position);
        let lowest = points.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        let flat: Vec<DVec2> = points.iter().map(|p| DVec2::new(p.x, p.z)).collect();
        (Footprint::hull(object.name.clone(), &flat), lowest)
    }

    /// Whether `p` is inside the polygon (or on its border).
    pub fn contains(&self, p: DVec2) -> bool {
        let n = self.outline.len();
        n >= 3
            && (0..n).all(|i| {
                let (a, b) = (self.outline[i], self.outline[(i + 1) % n]);
                (b - a).perp_dot(p - a) >= 0.0
            })
    }

    /// Distance from `p` to the polygon: 0 inside.
    pub fn distance(&self, p: DVec2) -> f64 {
        if self.contains(p) {
            return 0.0;
        }
        let n = self.outline.len();
        (0..n)
            .map(|i| segment_distance(p, self.outline[i], self.outline[(i + 1) % n]))
            .fold(f64::INFINITY, f64::min)
    }

    /// The centre of the polygon's corners.
    pub fn centre(&self) -> DVec2 {
        self.outline.iter().copied().sum::<DVec2>() / self.outline.len().max(1) as f64
    }

    /// How far the polygon reaches from its centre in direction `dir` (a unit vector).
    pub fn reach(&self, dir: DVec2) -> f64 {
        let c = self.centre();
        self.outline
            .iter()
            .map(|p| (*p - c).dot(dir))
            .fold(0.0, f64::max)
    }
}

/// Distance from `p` to the segment `a`–`b`.
pub fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = if ab.length_squared() > 0.0 {
        ((p - a).dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).length()
}

/// Corners of a polygon that contains the circle of `radius` about the origin.
fn circle(radius: f64) -> impl Iterator<Item = DVec2> {
    let step = std::f64::consts::TAU / CIRCLE_SIDES as f64;
    // The polygon's edges touch the circle: its corners are 1/cos(step/2) further out.
    let r = radius / (step / 2.0).cos();
    (0..CIRCLE_SIDES).map(move |i| {
        let a = i as f64 * step;
        DVec2::new(r * a.cos(), r * a.sin())
    })
}

/// Points whose convex hull contains the shape, placed at `rotation`, `position`.
fn surface_points(shape: &Shape, rotation: DQuat, position: DVec3) -> Vec<DVec3> {
    let local: Vec<DVec3> = match *shape {
        Shape::Box { half_extents: h } => (0..8)
            .map(|i| {
                let s = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
                DVec3::new(s(1) * h.x, s(2) * h.y, s(4) * h.z)
            })
            .collect(),
        Shape::Sphere { radius } => caps(radius, radius, radius),
        Shape::Ellipsoid { radii } => caps(radii.x, radii.y, radii.z),
        Shape::Cylinder { radius, height } => rings(radius, radius, height),
        Shape::Frustum {
            bottom_radius,
            top_radius,
            height,
        } => rings(bottom_radius, top_radius, height),
    };
    local.into_iter().map(|p| position + rotation * p).collect()
}

/// Two circles of the given radii at y = ∓height/2.
fn rings(bottom: f64, top: f64, height: f64) -> Vec<DVec3> {
    let mut points: Vec<DVec3> = circle(bottom)
        .map(|p| DVec3::new(p.x, -height / 2.0, p.y))
        .collect();
    points.extend(circle(top).map(|p| DVec3::new(p.x, height / 2.0, p.y)));
    points
}

/// The corners of the box around an ellipsoid, rounded: its slices at y = 0 and ±ry.
fn caps(rx: f64, ry: f64, rz: f64) -> Vec<DVec3> {
    let mut points = Vec::new();
    // A polyhedron that contains the ellipsoid: three slices, the middle one widened so
    // that the hull of the slices covers the bulge between them.
    for (y, k) in [(-ry, 0.0), (0.0, std::f64::consts::SQRT_2), (ry, 0.0)] {
        let k = if k == 0.0 { 1e-6 } else { k };
        points.extend(circle(1.0).map(|p| DVec3::new(p.x * rx * k, y, p.y * rz * k)));
    }
    points
}

/// The convex hull of `points`, counter-clockwise about +Y seen from above (Andrew's
/// monotone chain).
fn convex_hull(points: &[DVec2]) -> Vec<DVec2> {
    let mut p: Vec<DVec2> = points.to_vec();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<DVec2> = Vec::with_capacity(p.len() * 2);
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &DVec2>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for &q in iter {
            while hull.len() >= start + 2
                && cross(hull[hull.len() - 2], hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop();
    }
    hull
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_turned_box_covers_its_turned_rectangle() {
        let object = Object {
            name: "table".into(),
            shape: Shape::Box {
                half_extents: DVec3::new(1.0, 0.4, 0.5),
            },
            position: DVec3::new(2.0, 0.4, 0.0),
            rotation: DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2),
            mass: 20.0,
        };
        let (f, lowest) = Footprint::of_object(&object);
        assert!(lowest.abs() < 1e-12);
        assert_eq!(f.outline.len(), 4);
        // Turned a quarter: long along z now.
        assert!(f.contains(DVec2::new(2.0, 0.9)));
        assert!(!f.contains(DVec2::new(2.9, 0.0)));
        assert!((f.distance(DVec2::new(2.0, 2.0)) - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_disc_contains_its_circle() {
        let f = Footprint::disc("stool", DVec2::new(1.0, 1.0), 0.3);
        for i in 0..100 {
            let a = i as f64 * 0.0628;
            assert!(f.contains(DVec2::new(1.0 + 0.3 * a.cos(), 1.0 + 0.3 * a.sin())));
        }
        assert!(f.distance(DVec2::new(1.0, 1.4)) < 0.1);
    }
}
