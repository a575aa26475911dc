//! Who is where: every actor's floor position, velocity and radius at the end of the
//! previous tick, a grid to find the ones near a point, and the obstacles' footprints.
//! The scene rebuilds it once a tick, before the actors step, so every walker decides
//! from the same world whatever the thread count.

use crate::clearance::Capsule;
use crate::footprint::Footprint;
use troupe_body::glam::DVec2;

/// Side of a grid cell (m): at least the distance a walker looks around.
pub const CELL: f64 = 3.0;

/// Every actor's place on the floor at the end of the previous tick.
#[derive(Clone, Debug, Default)]
pub struct Crowd {
    /// Root position (x, z) per actor.
    pub positions: Vec<DVec2>,
    /// Root velocity (x, z) over the previous tick, per actor.
    pub velocities: Vec<DVec2>,
    /// Body radius per actor (see [`crate::body_radius`]).
    pub radii: Vec<f64>,
    /// Which way each actor faces: the unit floor direction (x, z) of its root's +z.
    pub facings: Vec<DVec2>,
    /// Each actor's body on the floor, its disc stretched to hold its feet (see
    /// [`crate::clearance::Capsule`]).
    pub bodies: Vec<Capsule>,
    /// Every obstacle's footprint, with the centre and radius of a circle around it.
    pub footprints: Vec<(Footprint, DVec2, f64)>,
    /// (cell, actor) sorted: the actors of a cell are a contiguous run.
    cells: Vec<((i64, i64), usize)>,
    /// (cell, footprint) sorted, for every cell a footprint's bounding box overlaps.
    footprint_cells: Vec<((i64, i64), usize)>,
}

/// The grid cell of `p`.
fn cell_of(p: DVec2) -> (i64, i64) {
    ((p.x / CELL).floor() as i64, (p.y / CELL).floor() as i64)
}

impl Crowd {
    /// Rebuilds the grid after `positions` changed.
    pub fn index(&mut self) {
        self.cells.clear();
        self.cells.extend(
            self.positions
                .iter()
                .enumerate()
                .map(|(i, p)| (cell_of(*p), i)),
        );
        self.cells.sort_unstable();
    }

    /// Sets the obstacles' footprints.
    pub fn set_footprints(&mut self, footprints: Vec<Footprint>) {
        self.footprints = footprints
            .into_iter()
            .map(|f| {
                let (c, r) = f.bounding_circle();
                (f, c, r)
            })
            .collect();
        self.footprint_cells.clear();
        for (i, (f, _, _)) in self.footprints.iter().enumerate() {
            let lowest = f.outline.iter().copied().reduce(DVec2::min);
            let highest = f.outline.iter().copied().reduce(DVec2::max);
            let (Some(lowest), Some(highest)) = (lowest, highest) else {
                continue;
            };
            let (x0, z0) = cell_of(lowest);
            let (x1, z1) = cell_of(highest);
            for x in x0..=x1 {
                for z in z0..=z1 {
                    self.footprint_cells.push(((x, z), i));
                }
            }
        }
        self.footprint_cells.sort_unstable();
    }

    /// Pushes onto `out` every actor within [`CELL`] of `p` (and possibly a little
    /// further), in actor order.
    pub fn near(&self, p: DVec2, out: &mut Vec<usize>) {
        let start = out.len();
        around(&self.cells, p, out);
        out[start..].sort_unstable();
    }

    /// Every footprint within `range` (at most [`CELL`]) of `p`, and maybe a few a little
    /// further, in the order they were set.
    pub fn footprints_near(&self, p: DVec2, range: f64) -> impl Iterator<Item = &Footprint> {
        let mut found = Vec::new();
        around(&self.footprint_cells, p, &mut found);
        found.sort_unstable();
        found.dedup();
        found
            .into_iter()
            .map(|i| &self.footprints[i])
            .filter(move |(_, c, r)| (*c - p).length() <= r + range)
            .map(|(f, _, _)| f)
    }
}

/// Pushes onto `out` the items of `cells` ((cell, item) sorted) in the 3 × 3 cells around
/// `p`'s: for each of the three columns the three cells are one run of the sorted list.
fn around(cells: &[((i64, i64), usize)], p: DVec2, out: &mut Vec<usize>) {
    let (cx, cz) = cell_of(p);
    for x in cx - 1..=cx + 1 {
        let from = cells.partition_point(|e| e.0 < (x, cz - 1));
        let to = from + cells[from..].partition_point(|e| e.0 <= (x, cz + 1));
        out.extend(cells[from..to].iter().map(|e| e.1));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_finds_the_neighbours_in_actor_order() {
        let mut crowd = Crowd {
            positions: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(10.0, 0.0),
                DVec2::new(-2.5, 1.0),
                DVec2::new(2.0, -2.9),
            ],
            ..Crowd::default()
        };
        crowd.index();
        let mut out = Vec::new();
        crowd.near(DVec2::new(0.1, 0.1), &mut out);
        assert_eq!(out, vec![0, 2, 3]);
    }

    #[test]
    fn footprints_near_finds_the_ones_within_range_once() {
        let mut crowd = Crowd::default();
        let square = |name: &str, x: f64, z: f64, h: f64| {
            let c = DVec2::new(x, z);
            Footprint::hull(
                name,
                &[
                    c + DVec2::new(-h, -h),
                    c + DVec2::new(h, -h),
                    c + DVec2::new(h, h),
                    c + DVec2::new(-h, h),
                ],
            )
        };
        crowd.set_footprints(vec![
            square("big", 0.0, 0.0, 4.0),
            square("far", 20.0, 0.0, 0.5),
            square("near", 2.0, 2.5, 0.2),
        ]);
        let names: Vec<&str> = crowd
            .footprints_near(DVec2::new(1.0, 1.0), 2.0)
            .map(|f| f.name.as_str())
            .collect();
        assert_eq!(names, vec!["big", "near"]);
        assert_eq!(crowd.footprints_near(DVec2::new(10.0, 0.0), 2.0).count(), 0);
    }
}
