//! Who is where: every actor's floor position, velocity and radius at the end of the
//! previous tick, a grid to find the ones near a point, and the obstacles' footprints.
//! The scene rebuilds it once a tick, before the actors step, so every walker decides
//! from the same world whatever the thread count.

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
    /// Every obstacle's footprint, with the centre and radius of a circle around it.
    pub footprints: Vec<(Footprint, DVec2, f64)>,
    /// (cell, actor) sorted: the actors of a cell are a contiguous run.
    cells: Vec<((i64, i64), usize)>,
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
                let c = f.centre();
                let r = f
                    .outline
                    .iter()
                    .map(|p| (*p - c).length())
                    .fold(0.0, f64::max);
                (f, c, r)
            })
            .collect();
    }

    /// Pushes onto `out` every actor within [`CELL`] of `p` (and possibly a little
    /// further), in actor order.
    pub fn near(&self, p: DVec2, out: &mut Vec<usize>) {
        let (cx, cz) = cell_of(p);
        let start = out.len();
        for x in cx - 1..=cx + 1 {
            for z in cz - 1..=cz + 1 {
                let from = self.cells.partition_point(|e| e.0 < (x, z));
                out.extend(
                    self.cells[from..]
                        .iter()
                        .take_while(|e| e.0 == (x, z))
                        .map(|e| e.1),
                );
            }
        }
        out[start..].sort_unstable();
    }

    /// The footprints whose bounding circle comes within `range` of `p`.
    pub fn footprints_near(&self, p: DVec2, range: f64) -> impl Iterator<Item = &Footprint> {
        self.footprints
            .iter()
            .filter(move |(_, c, r)| (*c - p).length() <= r + range)
            .map(|(f, _, _)| f)
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
}
