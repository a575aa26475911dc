//! The navigation debug view (`--debug nav`): the navigation mesh the walkers plan on,
//! the obstacles' footprints and how far the mesh keeps bodies from them, each walker's
//! planned path to its goal, and the velocities of its last avoidance decision.
//!
//! [`NavOverlay::from_scene`] gathers all of it from the scene as it stands (the space's
//! mesh, the walks' plans, the crowd); [`NavOverlay::segments`] turns it into coloured
//! lines on the floor, drawn by the line pipeline (`lines.rs`).

use crate::lines::Segment;
use glam::{Vec2, Vec3};
use troupe_scene::space::{body_radius, CLEARANCE};
use troupe_scene::Scene;

/// Colour (sRGB) of the navigation mesh's polygon edges.
pub const NAV_MESH: [f32; 3] = [0.30, 0.50, 0.90];
/// Colour (sRGB) of an obstacle's footprint.
pub const NAV_FOOTPRINT: [f32; 3] = [0.12, 0.12, 0.14];
/// Colour (sRGB) of an obstacle's footprint inflated by the body radius and clearance:
/// where the mesh stops.
pub const NAV_INFLATED: [f32; 3] = [0.88, 0.16, 0.14];
/// Colour (sRGB) of a walker's planned path and its goal.
pub const NAV_PATH: [f32; 3] = [0.62, 0.12, 0.86];
/// Colour (sRGB) of the velocity a walker preferred (along its plan).
pub const NAV_PREFERRED: [f32; 3] = [0.05, 0.55, 0.25];
/// Colour (sRGB) of the velocity avoidance chose.
pub const NAV_CHOSEN: [f32; 3] = [1.0, 0.52, 0.0];

/// Metres around everything shown within which mesh edges are drawn: the open floor is a
/// square kilometre, whose long edges would streak to the horizon.
const MARGIN: f32 = 4.0;
/// Heights (m) above the floor of each layer, so that they do not fight the floor or
/// one another for depth.
const MESH_HEIGHT: f32 = 0.012;
const OUTLINE_HEIGHT: f32 = 0.02;
const PATH_HEIGHT: f32 = 0.03;
const ARROW_HEIGHT: f32 = 0.04;
/// Line widths in pixels of a 720-pixel-high picture (they scale with its height).
const THIN: f32 = 1.5;
const MEDIUM: f32 = 2.5;
const THICK: f32 = 3.5;

/// One walker's plan and avoidance, in floor coordinates (x, z).
#[derive(Clone, Debug, PartialEq)]
pub struct NavWalker {
    /// The actor's index.
    pub actor: usize,
    /// Where its root stands now.
    pub position: Vec2,
    /// The planned path ahead, ending at the goal.
    pub path: Vec<Vec2>,
    /// Where the walk ends.
    pub goal: Vec2,
    /// The preferred and the chosen velocity (m/s) of its last avoidance decision.
    pub velocities: Option<(Vec2, Vec2)>,
}

/// What `--debug nav` draws, gathered from a scene (see the module docs).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NavOverlay {
    /// The body radius (m) the mesh is built for, without the clearance.
    pub radius: f32,
    /// The navigation mesh's polygon edges (each once).
    pub mesh: Vec<[Vec2; 2]>,
    /// Every obstacle's footprint (walls, then objects), counter-clockwise.
    pub footprints: Vec<Vec<Vec2>>,
    /// The same footprints inflated by the radius and the clearance.
    pub inflated: Vec<Vec<Vec2>>,
    /// The walkers, in actor order.
    pub walkers: Vec<NavWalker>,
}

impl NavOverlay {
    /// Gathers the overlay from `scene`: the mesh and inflated footprints for the body
    /// radius most of its actors have (the larger on a tie; an adult's in a scene
    /// without actors), every walk's plan ahead and last avoidance decision. It reads the
    /// scene and changes nothing it simulates (a mesh it asks for is cached as a path
    /// query's would be).
    pub fn from_scene(scene: &Scene) -> NavOverlay {
        let radius = shown_radius(&scene.crowd().radii).unwrap_or_else(adult_radius);
        let obstacles = scene.world().obstacles();
        let flat = |p: troupe_body::glam::DVec2| Vec2::new(p.x as f32, p.y as f32);
        let walkers = scene
            .navigation()
            .into_iter()
            .map(|(actor, nav)| {
                let root = scene.states()[actor].globals[0].translation;
                NavWalker {
                    actor,
                    position: Vec2::new(root.x as f32, root.z as f32),
                    path: nav.path.iter().map(|p| flat(*p)).collect(),
                    goal: flat(nav.goal),
                    velocities: nav.velocities.map(|(p, c)| (flat(p), flat(c))),
                }
            })
            .collect();
        NavOverlay {
            radius: radius as f32,
            mesh: scene
                .space()
                .mesh_edges(&obstacles, radius)
                .iter()
                .map(|[a, b]| [flat(*a), flat(*b)])
                .collect(),
            footprints: obstacles
                .iter()
                .map(|o| o.outline.iter().map(|p| flat(*p)).collect())
                .collect(),
            inflated: obstacles
                .iter()
                .map(|o| {
                    o.inflated(radius + CLEARANCE)
                        .into_iter()
                        .map(flat)
                        .collect()
                })
                .collect(),
            walkers,
        }
    }

    /// The overlay as coloured lines on the floor: mesh edges near what is shown (thin,
    /// blue), footprints (black) and their inflated outlines (red), each walker's path
    /// with a cross at its goal (violet), and its preferred (green) and chosen (orange)
    /// velocities as arrows from its root, one second long.
    pub fn segments(&self, out: &mut Vec<Segment>) {
        let on = |p: Vec2, height: f32| Vec3::new(p.x, height, p.y);
        let mut line = |a: Vec2, b: Vec2, height: f32, width: f32, color: [f32; 3]| {
            out.push(Segment::new(on(a, height), on(b, height), width, color));
        };
        if let Some((lo, hi)) = self.bounds() {
            let (lo, hi) = (lo - Vec2::splat(MARGIN), hi + Vec2::splat(MARGIN));
            for &[a, b] in &self.mesh {
                if let Some((a, b)) = clip(a, b, lo, hi) {
                    line(a, b, MESH_HEIGHT, THIN, NAV_MESH);
                }
            }
        }
        for (outlines, height, color) in [
            (&self.footprints, OUTLINE_HEIGHT, NAV_FOOTPRINT),
            (&self.inflated, OUTLINE_HEIGHT, NAV_INFLATED),
        ] {
            for outline in outlines {
                for (i, &a) in outline.iter().enumerate() {
                    line(a, outline[(i + 1) % outline.len()], height, MEDIUM, color);
                }
            }
        }
        for w in &self.walkers {
            for pair in w.path.windows(2) {
                line(pair[0], pair[1], PATH_HEIGHT, THICK, NAV_PATH);
            }
            let arm = 0.15;
            for d in [Vec2::new(arm, arm), Vec2::new(arm, -arm)] {
                line(w.goal - d, w.goal + d, PATH_HEIGHT, THICK, NAV_PATH);
            }
            if let Some((preferred, chosen)) = w.velocities {
                for (v, width, color) in [
                    (preferred, MEDIUM, NAV_PREFERRED),
                    (chosen, THICK, NAV_CHOSEN),
                ] {
                    arrow(&mut line, w.position, v, width, color);
                }
            }
        }
    }

    /// Bounds (x, z) of everything but the mesh: footprints, walkers and their paths.
    fn bounds(&self) -> Option<(Vec2, Vec2)> {
        let mut points = self
            .footprints
            .iter()
            .flatten()
            .chain(
                self.walkers
                    .iter()
                    .flat_map(|w| w.path.iter().chain([&w.position])),
            )
            .copied()
            .peekable();
        let first = *points.peek()?;
        Some(points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }
}

/// An arrow from `from` along velocity `v` (one second of it), with a head.
fn arrow(
    line: &mut impl FnMut(Vec2, Vec2, f32, f32, [f32; 3]),
    from: Vec2,
    v: Vec2,
    width: f32,
    color: [f32; 3],
) {
    let tip = from + v;
    let Some(dir) = v.try_normalize() else {
        return;
    };
    line(from, tip, ARROW_HEIGHT, width, color);
    let head = 0.18f32.min(v.length() * 0.5);
    for side in [-1.0, 1.0] {
        let back = Vec2::from_angle(side * 0.45).rotate(-dir) * head;
        line(tip, tip + back, ARROW_HEIGHT, width, color);
    }
}

/// The radius most of `radii` share, to the millimetre (the larger on a tie).
fn shown_radius(radii: &[f64]) -> Option<f64> {
    let mut mm: Vec<i64> = radii.iter().map(|r| (r * 1000.0).round() as i64).collect();
    mm.sort_unstable();
    let mut best: Option<(usize, i64)> = None;
    for run in mm.chunk_by(|a, b| a == b) {
        if best.is_none_or(|(n, _)| run.len() >= n) {
            best = Some((run.len(), run[0]));
        }
    }
    best.map(|(_, r)| r as f64 / 1000.0)
}

/// The default adult's body radius.
fn adult_radius() -> f64 {
    troupe_body::template("adult")
        .and_then(|t| t.instantiate(t.default_params()))
        .map(|s| body_radius(&s))
        .unwrap_or(0.28)
}

/// The part of segment `a`–`b` inside the rectangle `lo`–`hi` (Liang–Barsky), if any.
fn clip(a: Vec2, b: Vec2, lo: Vec2, hi: Vec2) -> Option<(Vec2, Vec2)> {
    let d = b - a;
    let (mut t0, mut t1) = (0.0f32, 1.0f32);
    for (p, q) in [
        (-d.x, a.x - lo.x),
        (d.x, hi.x - a.x),
        (-d.y, a.y - lo.y),
        (d.y, hi.y - a.y),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return None;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then(|| (a + d * t0, a + d * t1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_radius_shown_is_the_most_common_one() {
        assert_eq!(shown_radius(&[]), None);
        assert_eq!(shown_radius(&[0.19, 0.28, 0.28]), Some(0.28));
        assert_eq!(shown_radius(&[0.19, 0.19, 0.28]), Some(0.19));
        assert_eq!(shown_radius(&[0.28, 0.19]), Some(0.28));
        assert!((adult_radius() - 0.28).abs() < 0.01, "{}", adult_radius());
    }

    #[test]
    fn clipping_keeps_the_part_inside() {
        let (lo, hi) = (Vec2::splat(-1.0), Vec2::splat(1.0));
        let (a, b) = clip(Vec2::new(-3.0, 0.0), Vec2::new(0.5, 0.0), lo, hi).unwrap();
        assert_eq!((a, b), (Vec2::new(-1.0, 0.0), Vec2::new(0.5, 0.0)));
        assert!(clip(Vec2::new(-3.0, 2.0), Vec2::new(3.0, 2.0), lo, hi).is_none());
    }
}
