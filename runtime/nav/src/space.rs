//! The shared space: walls, the walkable floor, and navigation meshes of it (one per body
//! radius, obstacles inflated by it) that answer path queries.
//!
//! The mesh is a constrained Delaunay triangulation of the floor with the inflated
//! obstacles cut out, and the search is Polyanya (any-angle, optimal on the mesh), both
//! from the `polyanya` crate. A mesh is built when a query first needs it and kept while
//! its obstacles stay the same: adding, moving, putting down or removing an obstacle
//! makes the next query rebuild the meshes it asks for.

use crate::footprint::{segment_distance, Footprint};
use polyanya::{Mesh, Triangulation};
use std::sync::{Arc, Mutex};
use troupe_body::glam::DVec2;

/// Half the side of the square floor used when the scene gives no outline (m).
pub const OPEN_FLOOR_HALF_SIDE: f64 = 500.0;
/// Extra clearance (m) added to every body radius: the path keeps it between the body's
/// disc and the obstacles, for the corners the walk rounds and the pelvis' sway.
pub const CLEARANCE: f64 = 0.08;
/// Meshes kept at once (one per distinct radius asked for).
const CACHED_MESHES: usize = 8;

/// A straight wall standing on the floor.
#[derive(Clone, Debug, PartialEq)]
pub struct Wall {
    /// One end of its centre line (x, z).
    pub from: DVec2,
    /// The other end (x, z).
    pub to: DVec2,
    /// Its thickness (m).
    pub thickness: f64,
    /// Its height (m): for drawing, and what a carried hand passes over.
    pub height: f64,
}

impl Wall {
    /// The floor the wall covers, called `name`.
    pub fn footprint(&self, name: impl Into<String>) -> Footprint {
        let along = (self.to - self.from).normalize_or_zero();
        let side = along.perp() * (self.thickness / 2.0);
        Footprint::hull(
            name,
            &[
                self.from - side,
                self.to - side,
                self.to + side,
                self.from + side,
            ],
        )
        .with_top(self.height)
    }
}

/// The walkable floor: an outline (x, z) and holes in it.
#[derive(Clone, Debug, PartialEq)]
pub struct Floor {
    /// The outline's corners, in order.
    pub outline: Vec<DVec2>,
    /// Areas cut out of it, each a list of corners.
    pub holes: Vec<Vec<DVec2>>,
}

impl Floor {
    /// The open floor: a square of [`OPEN_FLOOR_HALF_SIDE`] about the origin.
    pub fn open() -> Floor {
        let h = OPEN_FLOOR_HALF_SIDE;
        Floor {
            outline: vec![
                DVec2::new(-h, -h),
                DVec2::new(h, -h),
                DVec2::new(h, h),
                DVec2::new(-h, h),
            ],
            holes: Vec::new(),
        }
    }

    /// Whether `p` is on the floor (inside the outline, outside every hole).
    pub fn contains(&self, p: DVec2) -> bool {
        inside(&self.outline, p) && !self.holes.iter().any(|h| inside(h, p))
    }
}

/// Even-odd test of `p` against the polygon `corners`.
fn inside(corners: &[DVec2], p: DVec2) -> bool {
    let n = corners.len();
    let mut odd = false;
    for i in 0..n {
        let (a, b) = (corners[i], corners[(i + 1) % n]);
        if (a.y > p.y) != (b.y > p.y) && p.x < a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x) {
            odd = !odd;
        }
    }
    odd
}

/// What a search round people standing ([`Space::path_around`]) does when the body
/// starts within an obstacle's inflation (closer to it than its radius and
/// [`CLEARANCE`]) but on the mesh.
///
/// The mesh's inflation ([`Footprint::inflated`]) holds the exact one, so such a start
/// is off the mesh and steps out to the nearest free point whatever this says; it counts
/// as on the mesh only within the search's 5 mm of the mesh's edge, where no path starts
/// either (the search cannot start outside its polygon). [`Space::path`], among the
/// furniture and walls alone, always steps out then. When the crate inflated the
/// obstacles, its arcs inside the circle left slivers of mesh cut off from the rest, and
/// a walker pressed 1 cm into a standing one's inflated disc found no way to a goal 2 m
/// off, the way round open, for 50 s of the plaza.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pressed {
    /// Search from where the body is, and fail if no path starts there.
    SearchFromHere,
    /// If no path starts where the body is, search again from the nearest point clear of
    /// every inflation, and step there first, as from a start off the mesh. A last
    /// resort: the step is towards whatever else is near by.
    StepOutIfStuck,
}

/// Why there is no path.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NoPath {
    /// The goal is off the walkable floor.
    #[error("no path: the goal ({:.2}, {:.2}) is off the walkable floor", .0.x, .0.y)]
    GoalOffFloor(DVec2),
    /// The start is off the walkable floor.
    #[error("no path: the start ({:.2}, {:.2}) is off the walkable floor", .0.x, .0.y)]
    StartOffFloor(DVec2),
    /// The goal is too close to an obstacle for the body.
    #[error("no path: the goal ({:.2}, {:.2}) is within {radius:.2} m of {obstacle}, closer than the body can stand", goal.x, goal.y)]
    GoalBlocked {
        /// The goal.
        goal: DVec2,
        /// The obstacle in the way.
        obstacle: String,
        /// The body radius (with its clearance).
        radius: f64,
    },
    /// The floor around the goal, or around the start, is cut off from the other's.
    #[error("no path: {}", enclosed_text(enclosing, *start, *goal))]
    Enclosed {
        /// The goal.
        goal: DVec2,
        /// The obstacles that close in the end cut off, nearest it first.
        enclosing: Vec<String>,
        /// The start, when it is the end cut off (the floor round it is the smaller, or no
        /// free point is near it); `None` when the goal is.
        start: Option<DVec2>,
    },
}

/// "a closes the way to (x, z)", "a and b close the way from (x, z) to (x, z)".
fn enclosed_text(names: &[String], start: Option<DVec2>, goal: DVec2) -> String {
    let verb = if names.len() == 1 { "closes" } else { "close" };
    let from = start.map_or(String::new(), |s| format!(" from ({:.2}, {:.2})", s.x, s.y));
    format!(
        "{} {verb} the way{from} to ({:.2}, {:.2})",
        list(names),
        goal.x,
        goal.y
    )
}

/// "a", "a and b", "a, b and c".
fn list(names: &[String]) -> String {
    match names {
        [] => "the obstacles".into(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

/// A mesh for one radius and the obstacles it was built from.
struct CachedMesh {
    radius_mm: i64,
    obstacles: Vec<Footprint>,
    floor: Floor,
    mesh: Arc<Mesh>,
}

/// How walks get to their goals: navigated (the default) or straight, for measuring what
/// navigation costs (`troupe bench --navigation on,off`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Walking {
    /// Walks plan round the obstacles, avoid one another, give way, keep lanes, take new
    /// routes and turn their shoulders to pass (`docs/navigation.md`).
    #[default]
    Navigated,
    /// Walks go in a straight line to their goals (near an object or actor, to the same
    /// free standing point as when navigating) and through whatever is in the way: no
    /// path search, avoidance, give-way, lanes, new routes nor shoulder turn (the crowd
    /// keeps the obstacles' footprints all the same, for the standing points, as when
    /// navigating). Hands do not go round other bodies and
    /// obstacles either (no temporary goals of `reach`, `grasp`, `give`): with bodies
    /// standing in one another, that work would grow with the overlaps and no longer be
    /// the crowd's without navigation. The rest of the tick's work is the same.
    Straight,
}

/// Walls, the walkable floor and the navigation meshes built from them.
#[derive(Default)]
pub struct Space {
    /// Walls, in the order added.
    pub walls: Vec<Wall>,
    /// The walkable floor; `None` is the open floor ([`Floor::open`]).
    pub floor: Option<Floor>,
    /// Whether walks navigate or go straight (see [`Walking`]).
    pub walking: Walking,
    cache: Mutex<Vec<CachedMesh>>,
    builds: std::sync::atomic::AtomicU64,
}

impl Clone for Space {
    fn clone(&self) -> Space {
        Space {
            walls: self.walls.clone(),
            floor: self.floor.clone(),
            walking: self.walking,
            ..Space::default()
        }
    }
}

impl std::fmt::Debug for Space {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Space")
            .field("walls", &self.walls)
            .field("floor", &self.floor)
            .field("walking", &self.walking)
            .finish_non_exhaustive()
    }
}

impl Space {
    /// The walls' footprints, named "wall 1", "wall 2", … in the order added.
    pub fn wall_footprints(&self) -> impl Iterator<Item = Footprint> + '_ {
        self.walls
            .iter()
            .enumerate()
            .map(|(i, w)| w.footprint(format!("wall {}", i + 1)))
    }

    /// The walkable floor.
    pub fn floor(&self) -> Floor {
        self.floor.clone().unwrap_or_else(Floor::open)
    }

    /// How many meshes have been built so far (a query that reuses one builds none).
    pub fn meshes_built(&self) -> u64 {
        self.builds.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// The mesh of the floor with `obstacles` inflated by `radius` (and [`CLEARANCE`]),
    /// built now or reused.
    pub fn mesh(&self, obstacles: &[Footprint], radius: f64) -> Arc<Mesh> {
        let radius_mm = inflation_mm(radius);
        let floor = self.floor();
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(c) = cache
            .iter()
            .find(|c| c.radius_mm == radius_mm && c.obstacles == obstacles && c.floor == floor)
        {
            return c.mesh.clone();
        }
        let mesh = Arc::new(build_mesh(&floor, obstacles, radius_mm as f64 / 1000.0));
        self.builds
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        cache.retain(|c| c.radius_mm != radius_mm);
        if cache.len() >= CACHED_MESHES {
            cache.remove(0);
        }
        cache.push(CachedMesh {
            radius_mm,
            obstacles: obstacles.to_vec(),
            floor,
            mesh: mesh.clone(),
        });
        mesh
    }

    /// The edges of the navigation mesh for a body of `radius` among `obstacles` (the
    /// mesh [`Space::path`] searches, built now or reused), each once, as pairs of floor
    /// points (x, z): what `--debug nav` draws.
    pub fn mesh_edges(&self, obstacles: &[Footprint], radius: f64) -> Vec<[DVec2; 2]> {
        let mesh = self.mesh(obstacles, radius);
        let mut edges: Vec<(u32, u32)> = Vec::new();
        let mut corners: Vec<DVec2> = Vec::new();
        for layer in &mesh.layers {
            let base = corners.len() as u32;
            corners.extend(
                layer
                    .vertices
                    .iter()
                    .map(|v| DVec2::new(v.coords.x as f64, v.coords.y as f64)),
            );
            for polygon in &layer.polygons {
                let n = polygon.vertices.len();
                for i in 0..n {
                    let (a, b) = (polygon.vertices[i], polygon.vertices[(i + 1) % n]);
                    edges.push((base + a.min(b), base + a.max(b)));
                }
            }
        }
        // An edge between two polygons is listed by both.
        edges.sort_unstable();
        edges.dedup();
        edges
            .into_iter()
            .filter_map(|(a, b)| Some([*corners.get(a as usize)?, *corners.get(b as usize)?]))
            .collect()
    }

    /// The shortest path from `from` to `to` (x, z) for a body of `radius` among
    /// `obstacles`: the points after `from`, ending at `to`; or why there is none. A start
    /// too close to an obstacle first steps out to the nearest free point.
    pub fn path(
        &self,
        obstacles: &[Footprint],
        from: DVec2,
        to: DVec2,
        radius: f64,
    ) -> Result<Vec<DVec2>, NoPath> {
        self.search(
            obstacles,
            from,
            to,
            radius,
            Pressed::SearchFromHere,
            true,
            || self.mesh(obstacles, radius),
        )
    }

    /// The shortest path as [`Space::path`] finds it, round `temporary` obstacles too
    /// (people standing in the way), on a mesh built for this query alone: the cached
    /// meshes of the lasting obstacles stay as they are.
    pub fn path_around(
        &self,
        obstacles: &[Footprint],
        temporary: &[Footprint],
        from: DVec2,
        to: DVec2,
        radius: f64,
        pressed: Pressed,
    ) -> Result<Vec<DVec2>, NoPath> {
        let all: Vec<Footprint> = obstacles.iter().chain(temporary).cloned().collect();
        self.search(&all, from, to, radius, pressed, false, || {
            let inflated = inflation_mm(radius) as f64 / 1000.0;
            Arc::new(build_mesh(&self.floor(), &all, inflated))
        })
    }

    /// The shortest path from `from` to `to` among `obstacles` on the mesh `mesh` gives.
    ///
    /// `lasting`: the obstacles are furniture and walls only ([`Space::path`]), so a start
    /// pressed into what the mesh cuts out, from which no path starts, steps out whatever
    /// `pressed` says: a walk that ended beside an obstacle must be able to leave it.
    #[allow(clippy::too_many_arguments)]
    fn search(
        &self,
        obstacles: &[Footprint],
        from: DVec2,
        to: DVec2,
        radius: f64,
        pressed: Pressed,
        lasting: bool,
        mesh: impl FnOnce() -> Arc<Mesh>,
    ) -> Result<Vec<DVec2>, NoPath> {
        let floor = self.floor();
        if !floor.contains(to) {
            return Err(NoPath::GoalOffFloor(to));
        }
        if !floor.contains(from) {
            return Err(NoPath::StartOffFloor(from));
        }
        let inflated = radius + CLEARANCE;
        if let Some(o) = obstacles.iter().find(|o| o.distance(to) < inflated) {
            return Err(NoPath::GoalBlocked {
                goal: to,
                obstacle: o.name.clone(),
                radius: inflated,
            });
        }
        let mesh = mesh();
        let cut = Cut::new(&floor, obstacles, from, radius);
        let on_mesh = mesh.point_in_mesh(v2(from));
        let mut found = if on_mesh {
            mesh.path(v2(from), v2(to))
        } else {
            None
        };
        let mut points = Vec::new();
        let mut start = from;
        // A start within the mesh's 5 mm search tolerance of a cut-out outline counts as
        // on the mesh, but the search cannot start outside its polygon and finds nothing
        // (a visitor that `walk{ to = OBJECT }` left 3 mm inside a pedestal's inflation
        // could not plan again: every walk it started failed). Among furniture and walls
        // such a start steps out; round people standing, as `pressed` says, as before.
        let pressed_in = if lasting {
            !cut.clear(from)
        } else {
            pressed == Pressed::StepOutIfStuck
                && obstacles.iter().any(|o| o.distance(from) < inflated)
        };
        if found.is_none() && (!on_mesh || pressed_in) {
            if let Some(free) = nearest_free(&mesh, obstacles, from, inflated) {
                start = free;
                found = mesh.path(v2(free), v2(to));
            }
            // No path from there either: it can lie within the search's tolerance of the
            // mesh too, at an outline's corner, so the step goes to the nearest point of
            // the mesh itself. Not round people: the plaza's walkers found 7 routes more
            // (of 53 steps out that found none), but over its twelve layouts walked into
            // one another more (docs/navigation.md, "Planning").
            if found.is_none() && lasting {
                if let Some(free) = nearest_on_mesh(&mesh, &cut, from) {
                    start = free;
                    found = mesh.path(v2(free), v2(to));
                }
            }
            if found.is_some() {
                points.push(start);
            }
        }
        let found = found.ok_or_else(|| enclosed(&mesh, &cut, obstacles, (from, start), to))?;
        points.extend(
            found
                .path
                .iter()
                .map(|p| DVec2::new(p.x as f64, p.y as f64)),
        );
        // The search works in f32: end exactly at the goal.
        if let Some(last) = points.last_mut() {
            *last = to;
        }
        Ok(points)
    }
}

/// The length of the path from `from` through `points` (m).
pub fn path_length(from: DVec2, points: &[DVec2]) -> f64 {
    let mut at = from;
    points
        .iter()
        .map(|&p| {
            let leg = (p - at).length();
            at = p;
            leg
        })
        .sum()
}

/// The radius plus [`CLEARANCE`] in whole millimetres: what a mesh is inflated by.
fn inflation_mm(radius: f64) -> i64 {
    ((radius + CLEARANCE) * 1000.0).round() as i64
}

/// How far (m) [`nearest_free`] looks.
const FREE_SEARCH: f64 = 1.5;

/// Farther (m) than the mesh's inflation that a point must lie outside the outlines the
/// mesh cuts out to count as clear of them: the mesh is built in f32.
const CUT_MARGIN: f64 = 0.001;

/// What the mesh of a body leaves out near a point: the obstacles' outlines as the mesh
/// cuts them out ([`Footprint::inflated`] by the mesh's inflation, a whole number of
/// millimetres) and the floor's edge, so that a point clear of them lies on the mesh
/// itself, not merely within the search's tolerance of it.
struct Cut<'a> {
    floor: &'a Floor,
    obstacles: &'a [Footprint],
    around: DVec2,
    /// What the mesh inflated the obstacles by (m).
    inflation: f64,
    /// The outlines of the obstacles near `around`, made when first asked for.
    grown: std::cell::OnceCell<Vec<Footprint>>,
}

impl<'a> Cut<'a> {
    /// What the mesh for a body of `radius` among `obstacles` on `floor` cuts out within
    /// [`FREE_SEARCH`] of `around`.
    fn new(floor: &'a Floor, obstacles: &'a [Footprint], around: DVec2, radius: f64) -> Cut<'a> {
        Cut {
            floor,
            obstacles,
            around,
            inflation: inflation_mm(radius) as f64 / 1000.0,
            grown: std::cell::OnceCell::new(),
        }
    }

    /// The grown outlines near `around`, named as their obstacles.
    fn grown(&self) -> &[Footprint] {
        self.grown.get_or_init(|| {
            // An outline reaches at most 2 % further than the inflation.
            let reach = 2.0 * self.inflation + FREE_SEARCH + CUT_MARGIN;
            self.obstacles
                .iter()
                .filter(|o| o.outline.len() >= 3 && o.distance(self.around) < reach)
                .map(|o| Footprint {
                    name: o.name.clone(),
                    outline: o.inflated(self.inflation + CUT_MARGIN),
                    top: o.top,
                })
                .collect()
        })
    }

    /// The obstacles whose cut-out outline holds `p` (within [`FREE_SEARCH`] of `around`).
    fn holding(&self, p: DVec2) -> impl Iterator<Item = &str> + '_ {
        self.grown()
            .iter()
            .filter(move |o| o.contains(p))
            .map(|o| o.name.as_str())
    }

    /// Whether `p` is within the inflation of the floor's edge or of a hole's.
    fn at_floor_edge(&self, p: DVec2) -> bool {
        let near = |ring: &[DVec2]| {
            (0..ring.len()).any(|i| {
                let (a, b) = (ring[i], ring[(i + 1) % ring.len()]);
                segment_distance(p, a, b) < self.inflation + CUT_MARGIN
            })
        };
        !self.floor.contains(p)
            || near(&self.floor.outline)
            || self.floor.holes.iter().any(|h| near(h))
    }

    /// Whether a body centred at `p` (within [`FREE_SEARCH`] of `around`) stands clear of
    /// everything the mesh cuts out, so on the mesh itself.
    fn clear(&self, p: DVec2) -> bool {
        self.holding(p).next().is_none() && !self.at_floor_edge(p)
    }
}

/// The nearest point of the mesh to `p` (a body inflated by `inflated` among
/// `obstacles`), searched on rings 2 cm apart up to [`FREE_SEARCH`].
fn nearest_free(mesh: &Mesh, obstacles: &[Footprint], p: DVec2, inflated: f64) -> Option<DVec2> {
    // Asking the mesh about a point off it is slow (it searches round the point), so the
    // points within the inflated footprints near by are passed over first; the mesh's
    // inflation is polygonal, not exactly ours, hence the plain search if that finds none.
    let near: Vec<&Footprint> = obstacles
        .iter()
        .filter(|o| o.distance(p) < inflated + FREE_SEARCH)
        .collect();
    let clear = |q: DVec2| near.iter().all(|o| o.distance(q) >= inflated);
    on_rings(p, |q| clear(q) && mesh.point_in_mesh(v2(q)))
        .or_else(|| on_rings(p, |q| mesh.point_in_mesh(v2(q))))
}

/// The nearest point to the point `cut` is about that lies on the mesh itself, clear of
/// what the mesh cuts out, not merely within the search's tolerance (5 mm) of it, as a
/// search's start must: on rings 2 cm apart up to [`FREE_SEARCH`].
fn nearest_on_mesh(mesh: &Mesh, cut: &Cut, p: DVec2) -> Option<DVec2> {
    on_rings(p, |q| cut.clear(q) && mesh.point_in_mesh(v2(q)))
}

/// Why no path joins `start` (the search's start; `from` before stepping out) to `goal`
/// on `mesh`: the obstacles round the end whose floor is cut off from the other's.
///
/// Each end's floor is the part of the mesh its polygon is joined to across shared edges;
/// the end cut off is the one on the smaller part, and what closes it in are the
/// obstacles whose outlines make that part's outer boundary (not those standing inside
/// it, nor those near the other end). An end off the mesh is closed in by the outlines
/// that hold it.
fn enclosed(
    mesh: &Mesh,
    cut: &Cut,
    obstacles: &[Footprint],
    (from, start): (DVec2, DVec2),
    goal: DVec2,
) -> NoPath {
    let nearest_first = |mut names: Vec<(f64, String)>| -> Vec<String> {
        // By the millimetre, so that obstacles as far, but for a rounding, go by name.
        let mm = |d: f64| (d * 1000.0).round();
        names.sort_by(|a, b| mm(a.0).total_cmp(&mm(b.0)).then(a.1.cmp(&b.1)));
        names.dedup_by(|a, b| a.1 == b.1);
        names.into_iter().map(|(_, n)| n).collect()
    };
    // The obstacles (or the floor's edge) whose cut-out outline holds `p`.
    let holding = |p: DVec2| {
        let mut names: Vec<(f64, String)> = obstacles
            .iter()
            .filter(|o| o.distance(p) < cut.inflation * 1.03 + CUT_MARGIN)
            .map(|o| (o.distance(p), o.name.clone()))
            .collect();
        if names.is_empty() {
            names.push((0.0, FLOOR_EDGE.into()));
        }
        nearest_first(names)
    };
    let enclosing = |names: Vec<String>, cut_off_start: bool| NoPath::Enclosed {
        goal,
        enclosing: names,
        start: cut_off_start.then_some(from),
    };
    let (Some(s), Some(g)) = (locate(mesh, start), locate(mesh, goal)) else {
        return if locate(mesh, start).is_none() {
            enclosing(holding(start), true)
        } else {
            enclosing(holding(goal), false)
        };
    };
    let layer = &mesh.layers[0];
    let (from_start, from_goal) = (Island::of(layer, s), Island::of(layer, g));
    if from_start.polygons.contains(&g) {
        // Joined, yet the search found nothing: name what is near the goal.
        let inflated = cut.inflation;
        let mut near: Vec<(f64, String)> = obstacles
            .iter()
            .map(|o| (o.distance(goal), o.name.clone()))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let closest = near.first().map_or(0.0, |n| n.0);
        near.retain(|(d, _)| *d <= closest + 2.0 * inflated + 1.0);
        return enclosing(nearest_first(near), false);
    }
    let (end, island, cut_off_start) = if from_start.area <= from_goal.area {
        (start, from_start, true)
    } else {
        (goal, from_goal, false)
    };
    let mut names = Vec::new();
    for v in island.outer_boundary(layer) {
        let before = names.len();
        names.extend(
            obstacles
                .iter()
                .filter(|o| o.distance(v) < cut.inflation * 1.03 + 2.0 * CUT_MARGIN)
                .map(|o| (o.distance(end), o.name.clone())),
        );
        if names.len() == before {
            names.push((f64::INFINITY, FLOOR_EDGE.into()));
        }
    }
    enclosing(nearest_first(names), cut_off_start)
}

/// What [`NoPath::Enclosed`] calls the floor's edge (or a hole's) when it closes the way.
const FLOOR_EDGE: &str = "the floor's edge";

/// The polygon of the mesh's (single) layer that holds `p`, within the search's tolerance.
fn locate(mesh: &Mesh, p: DVec2) -> Option<usize> {
    let at = mesh.get_point_layer(v2(p)).into_iter().next()?;
    // The crate packs the layer into the index's top 8 bits.
    Some((at.polygon() & 0x00ff_ffff) as usize)
}

/// A part of a mesh's layer whose polygons are joined across shared edges.
struct Island {
    /// Its polygons, by index.
    polygons: Vec<usize>,
    /// Its area (m²).
    area: f64,
}

impl Island {
    /// The part of `layer` joined to polygon `first`.
    fn of(layer: &polyanya::Layer, first: usize) -> Island {
        let mut seen = vec![false; layer.polygons.len()];
        let mut polygons = Vec::new();
        let mut todo = vec![first];
        seen[first] = true;
        while let Some(p) = todo.pop() {
            polygons.push(p);
            for (a, b) in edges(layer, p) {
                if let Some(q) = across(layer, p, a, b) {
                    if !std::mem::replace(&mut seen[q], true) {
                        todo.push(q);
                    }
                }
            }
        }
        polygons.sort_unstable();
        let area = polygons
            .iter()
            .map(|&p| signed_area(layer, &layer.polygons[p].vertices).abs())
            .sum();
        Island { polygons, area }
    }

    /// The corners (x, z) of the island's outer boundary: of the loops its unshared edges
    /// make, the one turning the way its polygons do that holds the most floor (the
    /// others go round what stands inside it).
    fn outer_boundary(&self, layer: &polyanya::Layer) -> Vec<DVec2> {
        let mut next: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
        let mut turn = 0.0;
        for &p in &self.polygons {
            turn += signed_area(layer, &layer.polygons[p].vertices);
            for (a, b) in edges(layer, p) {
                if across(layer, p, a, b).is_none() {
                    next.entry(a).or_default().push(b);
                }
            }
        }
        let mut best: (f64, Vec<u32>) = (0.0, Vec::new());
        while let Some((&first, _)) = next.iter().find(|(_, to)| !to.is_empty()) {
            let mut ring = vec![first];
            let mut at = first;
            while let Some(b) = next.get_mut(&at).and_then(|to| to.pop()) {
                if b == first {
                    break;
                }
                ring.push(b);
                at = b;
            }
            let area = signed_area(layer, &ring) * turn.signum();
            if area > best.0 {
                best = (area, ring);
            }
        }
        best.1.iter().map(|&v| corner(layer, v)).collect()
    }
}

/// The edges (corner indices) of polygon `p` of `layer`, in its order.
fn edges(layer: &polyanya::Layer, p: usize) -> impl Iterator<Item = (u32, u32)> + '_ {
    let v = &layer.polygons[p].vertices;
    (0..v.len()).map(move |i| (v[i], v[(i + 1) % v.len()]))
}

/// The polygon of `layer` other than `p` that shares its edge `a`–`b`, if any.
fn across(layer: &polyanya::Layer, p: usize, a: u32, b: u32) -> Option<usize> {
    let at_b = &layer.vertices.get(b as usize)?.polygons;
    layer
        .vertices
        .get(a as usize)?
        .polygons
        .iter()
        .find(|&&q| q != u32::MAX && q as usize != p && at_b.contains(&q))
        .map(|&q| q as usize)
}

/// Corner `v` of `layer` as a floor point (x, z).
fn corner(layer: &polyanya::Layer, v: u32) -> DVec2 {
    let c = layer.vertices[v as usize].coords + layer.offset;
    DVec2::new(c.x as f64, c.y as f64)
}

/// The signed area (m²) of the polygon through `layer`'s corners `ring`.
fn signed_area(layer: &polyanya::Layer, ring: &[u32]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| corner(layer, ring[i]).perp_dot(corner(layer, ring[(i + 1) % n])))
        .sum::<f64>()
        / 2.0
}

/// The first point around `p` that is `free`, on rings 2 cm apart up to [`FREE_SEARCH`],
/// 32 points a ring.
fn on_rings(p: DVec2, free: impl Fn(DVec2) -> bool) -> Option<DVec2> {
    let rings = (FREE_SEARCH / 0.02).round() as usize;
    for ring in 1..=rings {
        let r = ring as f64 * 0.02;
        for k in 0..32 {
            let a = k as f64 * std::f64::consts::TAU / 32.0;
            let q = p + DVec2::new(a.cos(), a.sin()) * r;
            if free(q) {
                return Some(q);
            }
        }
    }
    None
}

/// A floor point in the mesh's f32 coordinates.
fn v2(p: DVec2) -> polyanya_glam::Vec2 {
    polyanya_glam::Vec2::new(p.x as f32, p.y as f32)
}

/// The mesh of `floor` with `obstacles` inflated by `inflated` metres.
///
/// The floor's edge and its holes, which may be any polygon, are inflated by the crate
/// and built first (`Triangulation::prebuild`, the crate's way of building a lasting part
/// once). The obstacles, convex footprints, are inflated here ([`Footprint::inflated`]):
/// the crate inflates a polygon as the union of a rounded rectangle round each of its
/// edges, a boolean operation that was three quarters of a new route's mesh
/// (docs/PERFORMANCE.md, "Obstacles inflated by troupe"), and its arcs lie inside the
/// circle, so a body a centimetre inside its clearance could stand on a sliver of mesh
/// cut off from the rest; grown here, the outline holds the clearance all round.
fn build_mesh(floor: &Floor, obstacles: &[Footprint], inflated: f64) -> Mesh {
    let ring = |points: &[DVec2]| points.iter().map(|p| v2(*p)).collect::<Vec<_>>();
    let mut triangulation = Triangulation::from_outer_edges(&ring(&floor.outline));
    triangulation.add_obstacles(floor.holes.iter().map(|h| ring(h)));
    triangulation.set_agent_radius(inflated as f32);
    triangulation.agent_radius_on_outer_edge(true);
    triangulation.prebuild();
    // What is added after the prebuilt part is inflated already.
    triangulation.set_agent_radius(0.0);
    triangulation.add_obstacles(
        obstacles
            .iter()
            .filter(|o| o.outline.len() >= 3)
            .map(|o| ring(&o.inflated(inflated))),
    );
    let mut mesh = triangulation.as_navmesh();
    mesh.merge_polygons();
    mesh.bake();
    // Points are found within a centimetre of the mesh, not the crate's default 10 cm:
    // "on the mesh" must mean clear of the inflated obstacles.
    mesh.set_search_delta(0.005).set_search_steps(2);
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Walls 0.1 m thick and 2 m high round the four `corners` (x, z), in turn.
    fn walls_round(space: &mut Space, corners: [(f64, f64); 4]) {
        for i in 0..4 {
            let (a, b) = (corners[i], corners[(i + 1) % 4]);
            space.walls.push(Wall {
                from: DVec2::new(a.0, a.1),
                to: DVec2::new(b.0, b.1),
                thickness: 0.1,
                height: 2.0,
            });
        }
    }

    /// A 2 m × 1 m table centred at (0, 2).
    fn table() -> Footprint {
        Footprint::hull(
            "table",
            &[
                DVec2::new(-1.0, 1.5),
                DVec2::new(1.0, 1.5),
                DVec2::new(1.0, 2.5),
                DVec2::new(-1.0, 2.5),
            ],
        )
    }

    /// The smallest distance from the polyline `from`, `points` to `obstacle`.
    fn closest(obstacle: &Footprint, from: DVec2, points: &[DVec2]) -> f64 {
        let mut prev = from;
        let mut best = f64::INFINITY;
        for &p in points {
            for k in 0..=100 {
                best = best.min(obstacle.distance(prev.lerp(p, k as f64 / 100.0)));
            }
            prev = p;
        }
        best
    }

    #[test]
    fn a_start_within_a_clearance_steps_out_to_find_its_way() {
        // Walkers standing on a 1.5 m grid east, north and south of a goal; a walker
        // pressed against the one south of it, 1 cm inside its inflated disc (the plaza,
        // `plaza_layouts.lua`, layout 11.2/1.5: it stood there for the last 50 s). When
        // the crate inflated the discs, its arcs inside the circle left a pocket of mesh
        // there, cut off from the rest, and the search from it failed; the outlines grown
        // by `Footprint::inflated` hold the clearance, so the start is off the mesh and
        // steps out however the walk is pressed.
        let standing: Vec<Footprint> = [
            (-1.2050, 14.6999),
            (-2.7003, 14.6950),
            (-1.2004, 13.2000),
            (-1.2000, 11.7000),
            (-2.70036907988682, 11.703751558483862),
            (-1.2030, 10.1961),
            (-2.7014, 10.1984),
        ]
        .iter()
        .enumerate()
        .map(|(i, &(x, z))| Footprint::disc(format!("walker {i}"), DVec2::new(x, z), 0.28))
        .collect();
        let from = DVec2::new(-3.158332168407947, 11.27543325172803);
        let goal = DVec2::new(-2.7, 13.2);
        let inflated = 0.28 + CLEARANCE;
        assert!(
            standing[4].distance(from) < inflated,
            "the start is within an inflation"
        );
        let space = Space::default();
        for pressed in [Pressed::SearchFromHere, Pressed::StepOutIfStuck] {
            let path = space
                .path_around(&[], &standing, from, goal, 0.28, pressed)
                .expect("the way round the west side is open");
            assert_eq!(*path.last().unwrap(), goal);
            // It steps out first, to a point clear of every inflation.
            assert!(
                standing.iter().all(|o| o.distance(path[0]) >= inflated),
                "{path:?}"
            );
            assert!((path[0] - from).length() < 0.1, "{path:?}");
        }
    }

    /// A 0.5 m square pedestal centred at (`x`, `z`).
    fn pedestal(name: &str, x: f64, z: f64) -> Footprint {
        Footprint::hull(
            name,
            &[
                DVec2::new(x - 0.25, z - 0.25),
                DVec2::new(x + 0.25, z - 0.25),
                DVec2::new(x + 0.25, z + 0.25),
                DVec2::new(x - 0.25, z + 0.25),
            ],
        )
    }

    #[test]
    fn a_start_a_few_millimetres_into_an_inflation_steps_out() {
        // Where `walk{ to = mask }` left a visitor of 1.76 m in the museum
        // (explore7/museum_wide.lua): 0.3617 m from the pedestal, within the search's
        // 5 mm of the mesh for these radii, so on the mesh for the crate, but outside
        // every polygon: the search found nothing, and every walk the visitor started
        // failed ("amphora_ped close the way to (0.00, 5.00)").
        let obstacles = [
            pedestal("mask", 3.5, 4.5),
            Footprint::disc("amphora_ped", DVec2::new(0.0, 6.0), 0.25),
        ];
        let (from, goal) = (DVec2::new(2.8883, 4.4689), DVec2::new(0.0, 5.0));
        let space = Space::default();
        for radius in [0.280, 0.282, 0.284, 0.286, 0.288, 0.3] {
            let inflated = radius + CLEARANCE;
            let path = space
                .path(&obstacles, from, goal, radius)
                .unwrap_or_else(|e| panic!("radius {radius}: {e}"));
            assert_eq!(*path.last().unwrap(), goal);
            // Pressed into the inflation, it steps out first, a few centimetres.
            if obstacles[0].distance(from) < inflated {
                assert!(obstacles[0].distance(path[0]) >= inflated, "{path:?}");
                assert!((path[0] - from).length() < 0.1, "{path:?}");
            }
        }
    }

    #[test]
    fn a_start_closed_in_names_what_closes_it_not_what_is_near_the_goal() {
        let mut space = Space::default();
        walls_round(&mut space, [(4.0, 4.0), (8.0, 4.0), (8.0, 8.0), (4.0, 8.0)]);
        let mut obstacles: Vec<Footprint> = space.wall_footprints().collect();
        // A stool inside the room, clear of the walls, and the table near the goal.
        obstacles.push(Footprint::disc("stool", DVec2::new(6.5, 6.5), 0.2));
        obstacles.push(table());
        let e = space
            .path(&obstacles, DVec2::new(5.0, 4.7), DVec2::new(0.0, 1.0), 0.3)
            .unwrap_err();
        // Nearest the start first: wall 1 (0.65 m), 4 (0.95 m), 2 (2.95 m), 3 (3.25 m).
        assert_eq!(
            e.to_string(),
            "no path: wall 1, wall 4, wall 2 and wall 3 close the way from (5.00, 4.70) to (0.00, 1.00)"
        );
        // The other way round, the goal is closed in.
        let e = space
            .path(&obstacles, DVec2::new(0.0, 1.0), DVec2::new(5.0, 4.7), 0.3)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "no path: wall 1, wall 4, wall 2 and wall 3 close the way to (5.00, 4.70)"
        );
        // A start deep inside one obstacle, with no free point within reach: it alone
        // closes the way.
        let stage = Footprint::hull(
            "stage",
            &[
                DVec2::new(-12.0, -2.0),
                DVec2::new(-8.0, -2.0),
                DVec2::new(-8.0, 2.0),
                DVec2::new(-12.0, 2.0),
            ],
        );
        let e = space
            .path(&[stage], DVec2::new(-10.0, 0.0), DVec2::new(0.0, -3.0), 0.3)
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "no path: stage closes the way from (-10.00, 0.00) to (0.00, -3.00)"
        );
    }

    #[test]
    fn a_path_goes_around_a_table_keeping_the_radius() {
        let space = Space::default();
        let obstacles = [table()];
        let (from, to) = (DVec2::ZERO, DVec2::new(0.0, 4.0));
        let path = space.path(&obstacles, from, to, 0.3).unwrap();
        assert!(path.len() >= 3, "{path:?}");
        assert_eq!(*path.last().unwrap(), to);
        let d = closest(&obstacles[0], from, &path);
        // The grown outline holds the clearance (less the mesh's f32 rounding).
        assert!(d >= 0.3 + CLEARANCE - 1e-4, "{d}");
        // Shortest: around the short side of the table, not much longer than the radius.
        let length = path_length(from, &path);
        assert!(length < 5.4, "{length}");
    }

    #[test]
    fn the_mesh_edges_surround_the_inflated_table_once_each() {
        let space = Space::default();
        let edges = space.mesh_edges(&[table()], 0.3);
        assert!(edges.len() >= 8, "{}", edges.len());
        let inflated = 0.3 + CLEARANCE;
        for [a, b] in &edges {
            assert!(a != b);
            // No edge runs through the table's inflated footprint (but for the chords of
            // the crate's polygonal corners, a centimetre or two inside the arc).
            for k in 0..=20 {
                let p = a.lerp(*b, k as f64 / 20.0);
                assert!(table().distance(p) >= inflated - 0.025, "{a} {b}");
            }
        }
        let mut sorted = edges.clone();
        sorted.sort_by(|x, y| {
            (x[0].x, x[0].y, x[1].x, x[1].y)
                .partial_cmp(&(y[0].x, y[0].y, y[1].x, y[1].y))
                .unwrap()
        });
        sorted.dedup();
        assert_eq!(sorted.len(), edges.len());
        // Some edge ends on the inflated table's outline: the mesh is cut round it.
        assert!(edges
            .iter()
            .flatten()
            .any(|p| (table().distance(*p) - inflated).abs() < 0.02));
    }

    #[test]
    fn an_open_floor_gives_the_straight_line() {
        let space = Space::default();
        let path = space
            .path(&[], DVec2::new(1.0, 1.0), DVec2::new(-3.0, 7.0), 0.3)
            .unwrap();
        assert_eq!(path, vec![DVec2::new(-3.0, 7.0)]);
    }

    #[test]
    fn a_goal_closed_in_by_walls_names_them() {
        let mut space = Space::default();
        walls_round(&mut space, [(4.0, 4.0), (6.0, 4.0), (6.0, 6.0), (4.0, 6.0)]);
        let mut obstacles: Vec<Footprint> = space.wall_footprints().collect();
        obstacles.push(table());
        let e = space
            .path(&obstacles, DVec2::ZERO, DVec2::new(5.0, 5.0), 0.3)
            .unwrap_err();
        let text = e.to_string();
        assert!(
            text.starts_with("no path: wall 1, wall 2, wall 3 and wall 4 close the way"),
            "{text}"
        );
        // A goal inside an obstacle's inflated footprint says which.
        let e = space
            .path(&obstacles, DVec2::ZERO, DVec2::new(0.0, 1.3), 0.3)
            .unwrap_err();
        assert!(e.to_string().contains("of table"), "{e}");
        // Off the floor.
        let e = space
            .path(&obstacles, DVec2::ZERO, DVec2::new(900.0, 0.0), 0.3)
            .unwrap_err();
        assert!(matches!(e, NoPath::GoalOffFloor(_)), "{e}");
    }

    #[test]
    fn meshes_are_reused_until_the_obstacles_change() {
        let space = Space::default();
        let mut obstacles = vec![table()];
        for _ in 0..3 {
            space
                .path(&obstacles, DVec2::ZERO, DVec2::new(0.0, 4.0), 0.3)
                .unwrap();
        }
        assert_eq!(space.meshes_built(), 1);
        // A second radius has its own mesh; the first stays.
        space
            .path(&obstacles, DVec2::ZERO, DVec2::new(0.0, 4.0), 0.2)
            .unwrap();
        space
            .path(&obstacles, DVec2::ZERO, DVec2::new(0.0, 4.0), 0.3)
            .unwrap();
        assert_eq!(space.meshes_built(), 2);
        // Moving the table rebuilds: the path now goes straight.
        for p in &mut obstacles[0].outline {
            p.x += 5.0;
        }
        let path = space
            .path(&obstacles, DVec2::ZERO, DVec2::new(0.0, 4.0), 0.3)
            .unwrap();
        assert_eq!(path.len(), 1);
        assert_eq!(space.meshes_built(), 3);
    }

    #[test]
    fn a_path_around_temporary_obstacles_leaves_the_cached_mesh_alone() {
        let space = Space::default();
        let obstacles = [table()];
        space
            .path(&obstacles, DVec2::ZERO, DVec2::new(0.0, 4.0), 0.3)
            .unwrap();
        // Someone stands on the straight way from (3, 0) to (3, 4).
        let someone = Footprint::disc("someone", DVec2::new(3.0, 2.0), 0.28);
        let (from, to) = (DVec2::new(3.0, 0.0), DVec2::new(3.0, 4.0));
        let path = space
            .path_around(
                &obstacles,
                std::slice::from_ref(&someone),
                from,
                to,
                0.3,
                Pressed::SearchFromHere,
            )
            .unwrap();
        assert!(path.len() >= 2, "{path:?}");
        assert!(closest(&someone, from, &path) >= 0.3 + CLEARANCE - 0.01);
        // The cached mesh is still the table's: no rebuild for the plain query.
        space
            .path(&obstacles, DVec2::ZERO, DVec2::new(0.0, 4.0), 0.3)
            .unwrap();
        assert_eq!(space.meshes_built(), 1);
        assert_eq!(space.path(&obstacles, from, to, 0.3).unwrap(), vec![to]);
    }

    #[test]
    fn a_start_too_close_steps_out_first() {
        let space = Space::default();
        let path = space
            .path(&[table()], DVec2::new(0.0, 1.3), DVec2::new(0.0, -2.0), 0.3)
            .unwrap();
        assert!(
            table().distance(path[0]) >= 0.3 + CLEARANCE - 0.03,
            "{path:?}"
        );
    }

    #[test]
    fn a_floor_outline_bounds_the_walk() {
        let space = Space {
            floor: Some(Floor {
                outline: vec![
                    DVec2::new(-2.0, -2.0),
                    DVec2::new(2.0, -2.0),
                    DVec2::new(2.0, 2.0),
                    DVec2::new(-2.0, 2.0),
                ],
                holes: vec![vec![
                    DVec2::new(-0.5, 0.5),
                    DVec2::new(0.5, 0.5),
                    DVec2::new(0.5, 1.0),
                    DVec2::new(-0.5, 1.0),
                ]],
            }),
            ..Space::default()
        };
        let e = space
            .path(&[], DVec2::ZERO, DVec2::new(3.0, 0.0), 0.3)
            .unwrap_err();
        assert!(matches!(e, NoPath::GoalOffFloor(_)), "{e}");
        // The hole is walked around.
        let path = space
            .path(&[], DVec2::ZERO, DVec2::new(0.0, 1.6), 0.2)
            .unwrap();
        assert!(path.len() >= 2, "{path:?}");
    }
}
