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
    /// How high (m) the obstacle reaches above the floor: a hand carried higher passes
    /// over it (see [`crate::clearance::Body::against`]); infinite when not
    /// known.
    pub top: f64,
}

impl Footprint {
    /// The footprint of the convex hull of `points` (x, z), called `name`, of unknown
    /// height.
    pub fn hull(name: impl Into<String>, points: &[DVec2]) -> Footprint {
        Footprint {
            name: name.into(),
            outline: convex_hull(points),
            top: f64::INFINITY,
        }
    }

    /// The same footprint, `top` metres high.
    pub fn with_top(self, top: f64) -> Footprint {
        Footprint { top, ..self }
    }

    /// A disc of `radius` around `centre`, as a polygon that contains the disc.
    pub fn disc(name: impl Into<String>, centre: DVec2, radius: f64) -> Footprint {
        let points: Vec<DVec2> = circle(radius).map(|p| centre + p).collect();
        Footprint::hull(name, &points)
    }

    /// The footprint of `object` seen from above, as high as its highest point, and the
    /// height of its lowest point.
    pub fn of_object(object: &Object) -> (Footprint, f64) {
        let points = surface_points(&object.shape, object.rotation, object.position);
        let lowest = points.iter().map(|p| p.y).fold(f64::INFINITY, f64::min);
        let top = points.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max);
        let flat: Vec<DVec2> = points.iter().map(|p| DVec2::new(p.x, p.z)).collect();
        (
            Footprint::hull(object.name.clone(), &flat).with_top(top),
            lowest,
        )
    }

    /// The polygon's edges, each from a corner to the next, the last back to the first.
    fn edges(&self) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        // Pairs read round the outline rather than indexed `(i + 1) % n`, a division per
        // edge: every walker among furniture measures footprints many times a tick.
        let closing = self
            .outline
            .last()
            .copied()
            .zip(self.outline.first().copied());
        self.outline.windows(2).map(|w| (w[0], w[1])).chain(closing)
    }

    /// Whether `p` is inside the polygon (or on its border).
    pub fn contains(&self, p: DVec2) -> bool {
        self.outline.len() >= 3 && self.edges().all(|(a, b)| (b - a).perp_dot(p - a) >= 0.0)
    }

    /// Distance from `p` to the polygon: 0 inside.
    pub fn distance(&self, p: DVec2) -> f64 {
        // One pass: inside while left of every edge; the square root once, of the least
        // squared distance to an edge (the same number as the least distance).
        let mut inside = self.outline.len() >= 3;
        let mut nearest = f64::INFINITY;
        // Read by `for_each`, which runs through the chained closing edge without asking
        // at each edge which part it is in.
        self.edges().for_each(|(a, b)| {
            let (ab, ap) = (b - a, p - a);
            inside &= ab.perp_dot(ap) >= 0.0;
            nearest = nearest.min(segment_distance_squared(ap, ab));
        });
        if inside {
            0.0
        } else {
            nearest.sqrt()
        }
    }

    /// The point of the polygon's outline nearest `p` (`p` itself is not on it unless it
    /// lies on an edge); `None` for a footprint without an outline.
    pub fn nearest_point(&self, p: DVec2) -> Option<DVec2> {
        self.edges()
            .map(|(a, b)| nearest_on_segment(p, a, b))
            .min_by(|x, y| {
                (*x - p)
                    .length_squared()
                    .total_cmp(&(*y - p).length_squared())
            })
    }

    /// The point of the polygon nearest `p`: `p` itself inside.
    pub fn nearest(&self, p: DVec2) -> DVec2 {
        if self.contains(p) {
            return p;
        }
        self.nearest_point(p).unwrap_or(p)
    }

    /// The part of the segment `a`–`b` inside the polygon, as the fractions of the way from
    /// `a` to `b` where it goes in and comes out; `None` if it stays outside (Cyrus–Beck
    /// clipping against each edge's line).
    pub fn span(&self, a: DVec2, b: DVec2) -> Option<(f64, f64)> {
        let n = self.outline.len();
        if n < 3 {
            return None;
        }
        let (mut enter, mut leave) = (0.0f64, 1.0f64);
        let d = b - a;
        for (i, &p) in self.outline.iter().enumerate() {
            let edge = self.outline[(i + 1) % n] - p;
            // Inside is left of every edge (counter-clockwise): edge × (x − p) ≥ 0.
            let at_a = edge.perp_dot(a - p);
            let along = edge.perp_dot(d);
            if along == 0.0 {
                if at_a < 0.0 {
                    return None;
                }
            } else {
                let t = -at_a / along;
                if along > 0.0 {
                    enter = enter.max(t);
                } else {
                    leave = leave.min(t);
                }
            }
            if enter > leave {
                return None;
            }
        }
        Some((enter, leave))
    }

    /// A circle that holds the polygon: the centre of its corners and the farthest
    /// corner's distance from it.
    pub fn bounding_circle(&self) -> (DVec2, f64) {
        let c = self.centre();
        let r = self
            .outline
            .iter()
            .map(|p| (*p - c).length_squared())
            .fold(0.0, f64::max)
            .sqrt();
        (c, r)
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

impl Footprint {
    /// The outline of the floor kept clear of this footprint by a body of `radius`: the
    /// polygon grown by `radius`, its corners rounded by polygonal arcs whose sides touch
    /// the circle and turn by at most 22.5° each. It holds every point within
    /// `radius` of the footprint and reaches at most 2 % of `radius` further (at the
    /// arcs' corners). The navigation mesh cuts these out, and `--debug nav` draws them.
    pub fn inflated(&self, radius: f64) -> Vec<DVec2> {
        let n = self.outline.len();
        if n < 3 {
            // A point or a segment grows into a disc or a stadium: its hull's circle.
            let c = self.centre();
            let reach = self
                .outline
                .iter()
                .map(|p| (*p - c).length())
                .fold(0.0, f64::max);
            return circle(reach + radius).map(|p| c + p).collect();
        }
        let normal = |i: usize| -> DVec2 {
            let (a, b) = (self.outline[i], self.outline[(i + 1) % n]);
            // Counter-clockwise about +Y: the outward normal is to the right of a → b.
            -(b - a).perp().normalize_or_zero()
        };
        let mut out = Vec::new();
        for i in 0..n {
            let (from, to) = (normal((i + n - 1) % n), normal(i));
            // The normals turn counter-clockwise round a convex, counter-clockwise outline.
            // The arc's sides are tangent to the circle at `from`, at each step, and at
            // `to`; its corners lie between, 1/cos(step/2) times the radius out. The first
            // and last sides lie on the grown edges, which are exact.
            let turn = from.perp_dot(to).atan2(from.dot(to)).max(0.0);
            let steps = (turn / CORNER_STEP).ceil().max(1.0);
            let step = turn / steps;
            let reach = radius / (step / 2.0).cos();
            let start = from.y.atan2(from.x);
            for k in 0..steps as usize {
                let a = start + step * (k as f64 + 0.5);
                out.push(self.outline[i] + DVec2::new(a.cos(), a.sin()) * reach);
            }
        }
        out
    }
}

/// Largest turn (radians) between two sides of an [`Footprint::inflated`] outline's
/// rounded corner: 22.5°, so that its corners lie within 2 % of the radius of the circle.
const CORNER_STEP: f64 = std::f64::consts::PI / 8.0;

/// Distance from `p` to the segment `a`–`b`.
pub fn segment_distance(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    segment_distance_squared(p - a, b - a).sqrt()
}

/// Squared distance from a point to a segment, both relative to the segment's start:
/// `ap` to the point, `ab` to the segment's end.
fn segment_distance_squared(ap: DVec2, ab: DVec2) -> f64 {
    (ab * segment_fraction(ap, ab) - ap).length_squared()
}

/// The point of the segment `a`–`b` nearest `p`.
#[inline]
pub fn nearest_on_segment(p: DVec2, a: DVec2, b: DVec2) -> DVec2 {
    a + (b - a) * segment_fraction(p - a, b - a)
}

/// How far along the segment `ab` (0 at its start, 1 at its end) is the point of it
/// nearest the point `ap` from its start.
fn segment_fraction(ap: DVec2, ab: DVec2) -> f64 {
    if ab.length_squared() > 0.0 {
        (ap.dot(ab) / ab.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    }
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
pub fn surface_points(shape: &Shape, rotation: DQuat, position: DVec3) -> Vec<DVec3> {
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
    fn a_segment_through_a_box_is_clipped_to_it_and_one_beside_it_is_not() {
        let wall = Footprint::hull(
            "wall",
            &[
                DVec2::new(-1.0, 1.95),
                DVec2::new(1.0, 1.95),
                DVec2::new(1.0, 2.05),
                DVec2::new(-1.0, 2.05),
            ],
        );
        let (a, b) = (DVec2::new(0.0, 1.0), DVec2::new(0.0, 3.0));
        let (enter, leave) = wall.span(a, b).unwrap();
        assert!((enter - 0.475).abs() < 1e-12 && (leave - 0.525).abs() < 1e-12);
        // Ending on the face: only touching it.
        let (enter, leave) = wall.span(a, DVec2::new(0.0, 1.95)).unwrap();
        assert!(leave - enter < 1e-12, "{enter} {leave}");
        // Beside the wall, and short of it.
        assert!(wall
            .span(DVec2::new(1.5, 1.0), DVec2::new(1.5, 3.0))
            .is_none());
        assert!(wall.span(a, DVec2::new(0.0, 1.9)).is_none());
        // Wholly inside.
        assert_eq!(
            wall.span(DVec2::new(0.0, 2.0), DVec2::new(0.5, 2.0)),
            Some((0.0, 1.0))
        );
        let near = |p: DVec2, q: DVec2| (wall.nearest(p) - q).length() < 1e-12;
        assert!(near(DVec2::new(0.3, 1.0), DVec2::new(0.3, 1.95)));
        assert!(near(DVec2::new(2.0, 3.05), DVec2::new(1.0, 2.05)));
        assert!(near(DVec2::new(0.2, 2.0), DVec2::new(0.2, 2.0)));
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

    #[test]
    fn an_inflated_outline_holds_the_radius_all_round_and_little_more() {
        let table = Footprint::hull(
            "table",
            &[
                DVec2::new(-1.0, -0.5),
                DVec2::new(1.0, -0.5),
                DVec2::new(1.0, 0.5),
                DVec2::new(-1.0, 0.5),
            ],
        );
        let pillar = Footprint::disc("pillar", DVec2::new(3.0, 1.0), 0.2);
        let post = Footprint::hull("post", &[DVec2::new(-2.0, 2.0)]);
        let wedge = Footprint::hull(
            "wedge",
            &[
                DVec2::new(0.0, 0.0),
                DVec2::new(2.0, 0.0),
                DVec2::new(0.0, 0.3),
            ],
        );
        // Four corners of 90°, each in four steps of 22.5°.
        assert_eq!(table.inflated(0.3).len(), 16);
        for f in [&table, &pillar, &post, &wedge] {
            for radius in [0.05, 0.3, 1.2] {
                let grown = Footprint {
                    name: "grown".into(),
                    outline: f.inflated(radius),
                    top: f64::INFINITY,
                };
                let n = grown.outline.len();
                // Convex and counter-clockwise, as a footprint.
                for i in 0..n {
                    let (a, b, c) = (
                        grown.outline[i],
                        grown.outline[(i + 1) % n],
                        grown.outline[(i + 2) % n],
                    );
                    assert!((b - a).perp_dot(c - b) > 0.0, "{}: turns at {b}", f.name);
                }
                // Every corner within 2 % past the radius, and every side's nearest
                // point to the footprint at the radius or further: the grown outline
                // holds the footprint grown exactly.
                for i in 0..n {
                    let (a, b) = (grown.outline[i], grown.outline[(i + 1) % n]);
                    let d = f.distance(a);
                    assert!(d >= radius - 1e-9 && d <= radius * 1.02, "{}: {d}", f.name);
                    for k in 0..=50 {
                        let q = a.lerp(b, k as f64 / 50.0);
                        assert!(f.distance(q) >= radius - 1e-9, "{}: {q}", f.name);
                    }
                }
                // And nothing within the radius lies outside it.
                for k in 0..360 {
                    let dir = DVec2::from_angle((k as f64).to_radians());
                    let c = f.centre();
                    let mut t = 0.0;
                    while f.distance(c + dir * t) < radius * 0.999 {
                        t += 0.001;
                    }
                    assert!(grown.contains(c + dir * (t - 0.001)), "{}", f.name);
                }
            }
        }
    }
}
