//! The scene's shared space: which objects are obstacles, the walls and the walkable
//! floor (`troupe_nav::Space`), and path queries on the world as it stands.
//!
//! An object is an obstacle when it stands on the floor (its lowest point within
//! [`ON_FLOOR`] of it) and nobody holds it, unless the script said otherwise with
//! `obstacle = true | false`. Walls always are.

use crate::world::World;
use crate::{Error, Result, Scene};
use troupe_body::glam::DVec2;
pub use troupe_nav::avoid::{choose_velocity, choose_velocity_bounded, Agent, GAP};
pub use troupe_nav::clearance::{
    clear_foot, foot_may_move, gap_bound, limit_step, nearest_gap, nearest_gaps, Body, Capsule,
    FootSpan, Surroundings, OBSTACLE_MARGIN,
};
pub use troupe_nav::crowd::ObjectStamp;
pub use troupe_nav::crowd::CELL as NEIGHBOUR_RANGE;
pub use troupe_nav::footprint::{segment_distance, surface_points, ON_FLOOR};
pub use troupe_nav::way::{backs_off_for, wait_line, Walker};
pub use troupe_nav::{
    body_radius, path_length, Crowd, Floor, Footprint, FootprintsAround, NoPath, Pressed, Space,
    Walking, Wall, CLEARANCE,
};

/// A walker's plan and its last avoidance decision, as a walking generator reports it
/// ([`crate::Generator::navigation`]) for the debug view.
#[derive(Clone, Debug, PartialEq)]
pub struct Navigation {
    /// The planned path ahead (x, z): from where the plan is now to its end, with its
    /// rounded corners, without the sidestep avoidance adds.
    pub path: Vec<DVec2>,
    /// Where the walk ends (x, z).
    pub goal: DVec2,
    /// The velocities (x, z, m/s) of the last avoidance decision: the one the walker
    /// preferred (along its plan) and the one it chose. `None` once the plan has ended.
    pub velocities: Option<(DVec2, DVec2)>,
}

impl World<'_> {
    /// Whether object `index` is an obstacle now (see the module docs).
    pub fn is_obstacle(&self, index: usize) -> bool {
        self.obstacle_footprint(index).is_some()
    }

    /// What object `index`'s obstacle footprint is made from (see [`ObjectStamp`]).
    pub fn obstacle_stamp(&self, index: usize) -> ObjectStamp {
        if self.holder(index).is_some() {
            return ObjectStamp::Held;
        }
        let o = &self.objects[index];
        ObjectStamp::Free {
            shape: o.shape,
            position: o.position,
            rotation: o.rotation,
            forced: self.obstacle_flags.get(index).copied().flatten(),
        }
    }

    /// Object `index`'s footprint if it is an obstacle now.
    fn obstacle_footprint(&self, index: usize) -> Option<Footprint> {
        if self.holder(index).is_some() {
            return None;
        }
        let (footprint, lowest) = Footprint::of_object(&self.objects[index]);
        let forced = self.obstacle_flags.get(index).copied().flatten();
        forced.unwrap_or(lowest <= ON_FLOOR).then_some(footprint)
    }

    /// Every obstacle's footprint now: walls first (in the order added), then objects (in
    /// the order added).
    pub fn obstacles(&self) -> Vec<Footprint> {
        let mut all: Vec<Footprint> = self.space.wall_footprints().collect();
        all.extend((0..self.objects.len()).filter_map(|i| self.obstacle_footprint(i)));
        all
    }

    /// The shortest path for a body of `radius` from `from` to `to` (x, z) around the
    /// obstacles: the points after `from`, or why there is none.
    pub fn path(
        &self,
        from: DVec2,
        to: DVec2,
        radius: f64,
    ) -> std::result::Result<Vec<DVec2>, NoPath> {
        self.space.path(&self.obstacles(), from, to, radius)
    }
}

/// Farthest (m) a floor's outline or holes may reach from the origin along x or z: the
/// navigation mesh's triangulation loses its precision far beyond (a floor 10,000 km
/// wide failed inside it); the open floor is 1 km wide.
pub const FLOOR_REACH: f64 = 100_000.0;

/// The first two edges of `polygon` (edge i from point i to the next) that cross or
/// touch, not counting neighbours meeting at their shared corner; a last point that
/// repeats the first closes the polygon and is not an edge of its own.
fn crossing_edges(polygon: &[DVec2]) -> Option<(usize, usize)> {
    let polygon = match polygon {
        [first, .., last] if first == last => &polygon[..polygon.len() - 1],
        _ => polygon,
    };
    let n = polygon.len();
    let edge = |i: usize| (polygon[i], polygon[(i + 1) % n]);
    let side = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
    let meet = |(a, b): (DVec2, DVec2), (c, d): (DVec2, DVec2)| {
        let (abc, abd, cda, cdb) = (side(a, b, c), side(a, b, d), side(c, d, a), side(c, d, b));
        if abc == 0.0 && abd == 0.0 {
            // On one line: they meet only if their spans along it overlap.
            let along = |p: DVec2| (p - a).dot(b - a);
            let (lo, hi) = (along(c).min(along(d)), along(c).max(along(d)));
            return hi >= 0.0 && lo <= (b - a).length_squared();
        }
        abc * abd <= 0.0 && cda * cdb <= 0.0
    };
    (0..n).find_map(|i| {
        ((i + 2)..n)
            .filter(|&j| !(i == 0 && j == n - 1))
            .find(|&j| meet(edge(i), edge(j)))
            .map(|j| (i, j))
    })
}

impl Scene {
    /// Makes walks navigate (the default) or go straight to their goals (see
    /// [`Walking`]): `troupe bench --navigation off` measures the crowd without
    /// navigation this way.
    pub fn set_walking(&mut self, walking: Walking) {
        self.space_mut().walking = walking;
    }

    /// Adds a wall; the next path query plans around it.
    pub fn add_wall(&mut self, wall: Wall) -> Result<usize> {
        let finite = wall.from.is_finite() && wall.to.is_finite();
        if !finite || (wall.to - wall.from).length() < 1e-6 {
            return Err(Error::Invalid(format!(
                "wall: `from` {} and `to` {} must be two distinct finite points",
                wall.from, wall.to
            )));
        }
        for (name, v) in [("thickness", wall.thickness), ("height", wall.height)] {
            if !(v.is_finite() && v > 0.0 && v <= 100.0) {
                return Err(Error::invalid_value(name, v, "a length in (0, 100] m"));
            }
        }
        self.space_mut().walls.push(wall);
        Ok(self.space().walls.len())
    }

    /// Sets the walkable floor (an outline and holes), replacing the open floor.
    pub fn set_floor(&mut self, floor: Floor) -> Result<()> {
        let polygons = std::iter::once(&floor.outline).chain(&floor.holes);
        for (k, polygon) in polygons.enumerate() {
            let what = if k == 0 {
                "the outline".to_string()
            } else {
                format!("hole {k}")
            };
            if polygon.len() < 3 || polygon.iter().any(|p| !p.is_finite()) {
                return Err(Error::Invalid(format!(
                    "floor: {what} needs at least 3 finite points (got {})",
                    polygon.len()
                )));
            }
            if let Some(p) = polygon.iter().find(|p| p.abs().max_element() > FLOOR_REACH) {
                return Err(Error::Invalid(format!(
                    "floor: {what} reaches {p}, beyond {} km of the origin",
                    FLOOR_REACH / 1000.0
                )));
            }
            if let Some((a, b)) = crossing_edges(polygon) {
                return Err(Error::Invalid(format!(
                    "floor: {what} crosses itself (its edges {} and {})",
                    a + 1,
                    b + 1
                )));
            }
            // The shoelace formula.
            let n = polygon.len();
            let area = (0..n)
                .map(|i| polygon[i].perp_dot(polygon[(i + 1) % n]))
                .sum::<f64>()
                .abs()
                / 2.0;
            if area < 1e-6 {
                return Err(Error::Invalid(format!("floor: {what} encloses no area")));
            }
        }
        self.space_mut().floor = Some(floor);
        Ok(())
    }

    /// The two actors whose body discs (radius [`body_radius`] about the root) overlap
    /// most now, and by how much (m); `None` when no two overlap. A measure for tests
    /// and reports: the discs hold the bodies standing, so no overlap means no solids
    /// meet (an arm swung out may reach past its disc).
    pub fn deepest_overlap(&self) -> Option<(f64, usize, usize)> {
        let radii = &self.crowd().radii;
        let at: Vec<DVec2> = self
            .states()
            .iter()
            .map(|s| DVec2::new(s.globals[0].translation.x, s.globals[0].translation.z))
            .collect();
        let mut deepest = None;
        for i in 0..at.len() {
            for j in i + 1..at.len() {
                let depth = radii[i] + radii[j] - (at[i] - at[j]).length();
                if depth > 0.0 && deepest.is_none_or(|(d, _, _)| depth > d) {
                    deepest = Some((depth, i, j));
                }
            }
        }
        deepest
    }

    /// Makes object `index` an obstacle (`Some(true)`), never one (`Some(false)`), or one
    /// when it stands on the floor (`None`, the default).
    pub fn set_obstacle(&mut self, index: usize, obstacle: Option<bool>) -> Result<()> {
        let slot = self
            .obstacle_flags_mut()
            .get_mut(index)
            .ok_or_else(|| Error::Invalid(format!("no object {index}")))?;
        *slot = obstacle;
        Ok(())
    }
}
