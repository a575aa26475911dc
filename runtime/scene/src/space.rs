//! The scene's shared space: which objects are obstacles, the walls and the walkable
//! floor (`troupe_nav::Space`), and path queries on the world as it stands.
//!
//! An object is an obstacle when it stands on the floor (its lowest point within
//! [`ON_FLOOR`] of it) and nobody holds it, unless the script said otherwise with
//! `obstacle = true | false`. Walls always are.

use crate::world::World;
use crate::{Error, Result, Scene};
use troupe_body::glam::DVec2;
pub use troupe_nav::avoid::{choose_velocity, Agent, GAP};
pub use troupe_nav::clearance::{
    clear_foot, foot_may_move, limit_step, nearest_gap, Capsule, FootSpan, Surroundings,
};
pub use troupe_nav::crowd::ObjectStamp;
pub use troupe_nav::crowd::CELL as NEIGHBOUR_RANGE;
pub use troupe_nav::footprint::ON_FLOOR;
pub use troupe_nav::way::{wait_line, Walker};
pub use troupe_nav::{
    body_radius, path_length, Crowd, Floor, Footprint, NoPath, Space, Walking, Wall, CLEARANCE,
};

/// How far (m) a foot's solid reaches round the segment under it from its heel to its toe
/// tip: the template's foot frustum (0.024 h at the ball) for bodies up to 2.08 m.
pub const FOOT_RADIUS: f64 = 0.05;
/// How far (m) a thigh's solid reaches round the point over its knee: the template's
/// thigh frustum (0.030 h at the knee) for bodies up to 2.0 m.
const KNEE_RADIUS: f64 = 0.06;
/// The template foot's heel and toe tip, as fractions of the ankle-to-ball length from
/// the point under the ankle (`troupe_body`'s template: heel at -0.2, ball at 0.69 and
/// toe tip at 0.85 of the foot's length).
const HEEL: f64 = 0.2 / 0.69;
const TOE: f64 = 0.85 / 0.69;

/// How far a walking body reaches forwards and backwards past its disc at
/// [`STRIDE_SPEED`] or faster, as a fraction of its radius, besides where its feet stand:
/// the swinging leg's knee and foot on their way to a landing the feet do not show yet
/// (the template adult, radius 0.28 m: its front toe tip at heel strike and back heel at
/// toe-off are about 0.5 m from its root, its hands swing about 0.37 m from it). Slower,
/// the strides are shorter.
const STRIDE: f64 = 0.9;
/// The speed (m/s, along the way the body faces) from which the stride is full.
const STRIDE_SPEED: f64 = 1.2;

/// The joints that shape an actor's body on the floor beyond its disc
/// ([`troupe_nav::Capsule`]): the feet, which stretch it along the way it faces, and the
/// wrists, which widen it as the arms swing out.
#[derive(Clone, Debug, Default)]
pub struct BodyJoints {
    /// The ankle and ball joints of each foot (left, right), if it has them.
    feet: Option<[[usize; 2]; 2]>,
    /// The knee joints: a leg lifted to step (even in place) brings its knee forwards.
    knees: Vec<usize>,
    /// Each wrist joint and its horizontal distance from the root at rest, where the
    /// body's radius holds the hand hanging from it.
    wrists: Vec<(usize, f64)>,
}

impl BodyJoints {
    /// The joints of `skeleton`, posed at rest at `globals`.
    pub fn new(skeleton: &troupe_body::Skeleton, globals: &[troupe_body::Transform]) -> Self {
        let j = |name: &str| skeleton.joint(name).ok();
        let feet = (|| {
            Some([
                [j("l_ankle")?, j("l_metatarsal")?],
                [j("r_ankle")?, j("r_metatarsal")?],
            ])
        })();
        let knees = ["l_knee", "r_knee"].into_iter().filter_map(j).collect();
        let root = floor_point(&globals[0]);
        let wrists = ["l_wrist", "r_wrist"]
            .into_iter()
            .filter_map(j)
            .filter_map(|w| Some((w, (floor_point(globals.get(w)?) - root).length())))
            .collect();
        BodyJoints {
            feet,
            knees,
            wrists,
        }
    }

    /// The body posed at `globals`, facing `facing` and going at `velocity` (x, z), of
    /// disc `radius`: the disc stretched by the stride at that speed (see [`STRIDE`]) and
    /// to hold its feet, widened by as far as a wrist is further out from it than at rest.
    pub fn body(
        &self,
        globals: &[troupe_body::Transform],
        facing: DVec2,
        velocity: DVec2,
        radius: f64,
    ) -> Capsule {
        let root = floor_point(&globals[0]);
        let stride = STRIDE * radius * (velocity.dot(facing).abs() / STRIDE_SPEED).min(1.0);
        let feet = self.foot_spans(globals);
        let mut body = Capsule::around(root, facing, radius, stride, &feet);
        for &(wrist, at_rest) in &self.wrists {
            if let Some(w) = globals.get(wrist) {
                let out = body.distance(floor_point(w)) - at_rest;
                body.radius = body.radius.max(radius + out);
            }
        }
        body
    }

    /// The legs on the floor of the body posed at `globals`: each foot's span and each
    /// knee's point (none for a body without them).
    pub fn foot_spans(&self, globals: &[troupe_body::Transform]) -> Vec<FootSpan> {
        let feet = self.feet.into_iter().flatten().filter_map(|[ankle, ball]| {
            let (a, b) = (
                floor_point(globals.get(ankle)?),
                floor_point(globals.get(ball)?),
            );
            Some(FootSpan {
                heel: a - (b - a) * HEEL,
                toe: a + (b - a) * TOE,
                radius: FOOT_RADIUS,
            })
        });
        let knees = self.knees.iter().filter_map(|&k| {
            let at = floor_point(globals.get(k)?);
            Some(FootSpan {
                heel: at,
                toe: at,
                radius: KNEE_RADIUS,
            })
        });
        feet.chain(knees).collect()
    }
}

/// The floor point (x, z) under a joint.
fn floor_point(g: &troupe_body::Transform) -> DVec2 {
    DVec2::new(g.translation.x, g.translation.z)
}

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
