//! Who is where: every actor's floor position, velocity and radius at the end of the
//! previous tick, a grid to find the ones near a point, and the obstacles' footprints.
//! The scene rebuilds it once a tick, before the actors step, so every walker decides
//! from the same world whatever the thread count.

use crate::clearance::{Body, Capsule, FootSpan};
use crate::footprint::Footprint;
use crate::space::Wall;
use troupe_body::glam::{DQuat, DVec2, DVec3};
use troupe_body::solid::Shape;

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
    /// The rank of each actor's line of walking, for the give-way rule
    /// ([`crate::way::line_rank`] of its facing), found by [`Crowd::index`].
    pub ranks: Vec<Option<f64>>,
    /// Each actor's body on the floor, its disc stretched to hold its feet (see
    /// [`crate::clearance::Capsule`]).
    pub bodies: Vec<Capsule>,
    /// The part of each actor's body its root's step carries: its disc stretched by its
    /// stride and widened by its wrists, without the feet planted on the floor, which
    /// stay where they are as the body moves (see [`crate::clearance::limit_step`]),
    /// with what it is made of (see [`crate::clearance::Body`]).
    pub cores: Vec<Body>,
    /// The floor points (x, z) under each actor's ankles (left, right); its root's for
    /// a body without them. Gathered once a tick for every walker's avoidance, which
    /// looked them up in the neighbours' postures (a twentieth of the crowd
    /// benchmark's tick, in cache misses).
    pub feet: Vec<[DVec2; 2]>,
    /// Each actor's feet (left, right) seen from above, heel to toe tip, if it has them:
    /// its capsule holds them only roughly (a foot planted wide widens the whole capsule,
    /// which is then mostly floor), so a foot in the air keeps from them as well (see
    /// [`crate::clearance::foot_may_move`]).
    pub soles: Vec<Option<[FootSpan; 2]>>,
    /// Every obstacle's footprint, as `World::obstacles` lists them (walls, then objects).
    pub footprints: Vec<Footprint>,
    /// The centre and radius of a circle round each footprint.
    bounds: Vec<(DVec2, f64)>,
    /// (cell, actor) sorted: the actors of a cell are a contiguous run.
    cells: Cells,
    /// (cell, footprint) sorted, for every cell a footprint's bounding box overlaps.
    footprint_cells: Cells,
    /// The walls and objects the footprints were made from (see
    /// [`Crowd::footprints_current`]).
    made_from: (Vec<Wall>, Vec<ObjectStamp>),
}

/// What an object's obstacle footprint is made from: while it stays the same, so does
/// the footprint (see [`Crowd::footprints_current`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ObjectStamp {
    /// Someone holds it: not an obstacle, wherever the hand takes it.
    Held,
    /// Nobody holds it: its shape, its pose and what the script said (`obstacle = …`).
    Free {
        /// Its shape.
        shape: Shape,
        /// Where its centre is.
        position: DVec3,
        /// How it is turned.
        rotation: DQuat,
        /// `obstacle = true | false`, or `None` for "when it stands on the floor".
        forced: Option<bool>,
    },
}

/// The grid cell of `p`.
fn cell_of(p: DVec2) -> (i64, i64) {
    (floor_to_int(p.x / CELL), floor_to_int(p.y / CELL))
}

/// `x.floor() as i64`, without the call to `floor` that a build for the common x86-64
/// target makes (it has no rounding instruction): some ten a walker's tick, about 1 % of
/// the crowd benchmark's navigation. Exact for every `x`: a float's truncation is exact
/// below 2⁵³, and beyond it every float is whole; NaN and the infinities saturate as
/// `as` does.
fn floor_to_int(x: f64) -> i64 {
    let whole = x as i64;
    if (whole as f64) > x {
        whole.saturating_sub(1)
    } else {
        whole
    }
}

impl Crowd {
    /// Rebuilds the grid after `positions` changed, and the lines' ranks after `facings`
    /// did.
    pub fn index(&mut self) {
        self.ranks.clear();
        self.ranks
            .extend(self.facings.iter().map(|&f| crate::way::line_rank(f)));
        self.cells.entries.clear();
        self.cells.entries.extend(
            self.positions
                .iter()
                .enumerate()
                .map(|(i, p)| (cell_of(*p), i)),
        );
        self.cells.sort();
        self.cells.gather_blocks();
    }

    /// Sets the obstacles' footprints.
    pub fn set_footprints(&mut self, footprints: Vec<Footprint>) {
        self.bounds = footprints.iter().map(Footprint::bounding_circle).collect();
        self.footprints = footprints;
        self.footprint_cells.entries.clear();
        for (i, f) in self.footprints.iter().enumerate() {
            let lowest = f.outline.iter().copied().reduce(DVec2::min);
            let highest = f.outline.iter().copied().reduce(DVec2::max);
            let (Some(lowest), Some(highest)) = (lowest, highest) else {
                continue;
            };
            let (x0, z0) = cell_of(lowest);
            let (x1, z1) = cell_of(highest);
            for x in x0..=x1 {
                for z in z0..=z1 {
                    self.footprint_cells.entries.push(((x, z), i));
                }
            }
        }
        self.footprint_cells.sort();
        self.footprint_cells.gather_unions();
    }

    /// Whether the footprints were made from these `walls` and objects (`stamps`, in
    /// object order), and notes them as the ones the next footprints are made from.
    /// Building every object's footprint and the grid of them each tick cost the crowd
    /// benchmark 3 % of its tick; the scene rebuilds them only when this says no.
    pub fn footprints_current(
        &mut self,
        walls: &[Wall],
        stamps: impl Iterator<Item = ObjectStamp>,
    ) -> bool {
        let (made_walls, made_objects) = &mut self.made_from;
        let mut same = made_walls.as_slice() == walls;
        if !same {
            *made_walls = walls.to_vec();
        }
        let mut count = 0;
        for (i, stamp) in stamps.enumerate() {
            count = i + 1;
            match made_objects.get_mut(i) {
                Some(made) if *made == stamp => {}
                Some(made) => {
                    *made = stamp;
                    same = false;
                }
                None => {
                    made_objects.push(stamp);
                    same = false;
                }
            }
        }
        if made_objects.len() != count {
            made_objects.truncate(count);
            same = false;
        }
        same
    }

    /// Pushes onto `out` every actor within [`CELL`] of `p` (and possibly a little
    /// further), in actor order.
    pub fn near(&self, p: DVec2, out: &mut Vec<usize>) {
        if let Some(block) = self.cells.block(p) {
            out.extend_from_slice(block);
            return;
        }
        let start = out.len();
        self.cells.around(p, out);
        out[start..].sort_unstable();
    }

    /// Pushes onto `out` the actors [`Crowd::near`] finds round `p` but not round
    /// `seen` (those of the grid cells round `p` that are not round `seen`), in no set
    /// order: a look further ahead, without listing again the ones a look round `seen`
    /// found (merging the two lists, and the longer list the walk's clearance and
    /// shoulders then read, cost a walker about 1,000 instructions a tick).
    pub fn near_beyond(&self, p: DVec2, seen: DVec2, out: &mut Vec<usize>) {
        self.cells.around_except(p, seen, out);
    }

    /// Every footprint within `range` (at most [`CELL`]) of `p`, and maybe a few a little
    /// further, in the order they were set.
    pub fn footprints_near(&self, p: DVec2, range: f64) -> impl Iterator<Item = &Footprint> {
        self.footprints_around(p, Vec::new()).into_within(range)
    }

    /// The footprints near `p`, found once for several ranges round it (see
    /// [`FootprintsAround::within`]): a walk looks for obstacles round its body five
    /// times a tick, at five ranges. They are listed in `found` (its contents dropped),
    /// which [`FootprintsAround::into_found`] gives back for the next time.
    pub fn footprints_around(&self, p: DVec2, mut found: Vec<usize>) -> FootprintsAround<'_> {
        found.clear();
        match self.footprint_cells.block(p) {
            Some(block) => found.extend_from_slice(block),
            None => {
                self.footprint_cells.around(p, &mut found);
                found.sort_unstable();
                found.dedup();
            }
        }
        FootprintsAround {
            crowd: self,
            at: p,
            found,
        }
    }

    /// Whether footprint `i`'s bounding circle comes within `range` of `p`.
    fn footprint_reaches(&self, i: usize, p: DVec2, range: f64) -> bool {
        let (c, r) = self.bounds[i];
        (c - p).length() <= r + range
    }
}

/// The footprints of the grid cells round a point (see [`Crowd::footprints_around`]).
#[derive(Clone, Debug)]
pub struct FootprintsAround<'a> {
    /// The crowd they are of.
    crowd: &'a Crowd,
    /// The point.
    at: DVec2,
    /// Their indices, in the order they were set.
    found: Vec<usize>,
}

impl<'a> FootprintsAround<'a> {
    /// Every footprint within `range` (at most [`CELL`]) of the point, and maybe a few a
    /// little further, in the order they were set: what [`Crowd::footprints_near`] gives.
    pub fn within(&self, range: f64) -> impl Iterator<Item = &'a Footprint> + '_ {
        self.within_bounded(range).map(|(footprint, _)| footprint)
    }

    /// [`FootprintsAround::within`], each with the circle round it (centre, radius: see
    /// [`Footprint::bounding_circle`]), which the crowd keeps.
    pub fn within_bounded(
        &self,
        range: f64,
    ) -> impl Iterator<Item = (&'a Footprint, (DVec2, f64))> + '_ {
        let (crowd, at) = (self.crowd, self.at);
        self.found
            .iter()
            .filter(move |&&i| crowd.footprint_reaches(i, at, range))
            .map(move |&i| (&crowd.footprints[i], crowd.bounds[i]))
    }

    /// The list the footprints were found in, to find them in again.
    pub fn into_found(self) -> Vec<usize> {
        self.found
    }

    /// [`FootprintsAround::within`], taking them.
    fn into_within(self, range: f64) -> impl Iterator<Item = &'a Footprint> {
        let (crowd, at) = (self.crowd, self.at);
        self.found
            .into_iter()
            .filter(move |&i| crowd.footprint_reaches(i, at, range))
            .map(move |i| &crowd.footprints[i])
    }
}

/// Items on a grid of [`CELL`]-wide cells: (cell, item) pairs sorted, so that the items
/// of a cell, and of a column's consecutive cells, are one run of the list; and where
/// each cell's run starts, for a rectangle of cells round them all.
#[derive(Clone, Debug, Default)]
struct Cells {
    /// (cell, item), sorted.
    entries: Vec<((i64, i64), usize)>,
    /// The entries' items alone, in the same order: runs of them are copied out whole.
    items: Vec<usize>,
    /// The rectangle's lowest cell and its size in cells (x, z).
    origin: (i64, i64),
    size: (i64, i64),
    /// Where the run of each cell of the rectangle starts (x major), and the end; empty
    /// when the items are too spread out for such a table to pay (then the runs are
    /// found by binary search).
    starts: Vec<u32>,
    /// For each cell of the rectangle (x major), the items of the 3 × 3 cells round it,
    /// in order, one list after another (see [`Cells::gather_blocks`]); empty when not
    /// gathered.
    blocks: Vec<usize>,
    /// Where each cell's list in `blocks` starts, and the end.
    block_starts: Vec<u32>,
}

impl Cells {
    /// Sorts the entries and finds where each cell's run starts. A lookup by binary
    /// search over a thousand actors' cells took a tenth of the crowd benchmark's tick
    /// (several look-ups per walker and tick).
    fn sort(&mut self) {
        self.entries.sort_unstable();
        self.items.clear();
        self.items.extend(self.entries.iter().map(|e| e.1));
        self.starts.clear();
        let (Some(first), Some(last)) = (self.entries.first(), self.entries.last()) else {
            return;
        };
        let (x0, x1) = (first.0 .0, last.0 .0);
        let z0 = self.entries.iter().map(|e| e.0 .1).min().unwrap_or(0);
        let z1 = self.entries.iter().map(|e| e.0 .1).max().unwrap_or(0);
        let (nx, nz) = (x1.saturating_sub(x0) + 1, z1.saturating_sub(z0) + 1);
        let fits = u32::try_from(self.entries.len()).is_ok()
            && nx
                .checked_mul(nz)
                .is_some_and(|n| n <= 4 * self.entries.len() as i64 + 4096);
        if !fits {
            return;
        }
        self.origin = (x0, z0);
        self.size = (nx, nz);
        let cells = (nx * nz) as usize;
        self.starts.resize(cells + 1, 0);
        let mut at = 0;
        for k in 0..cells {
            self.starts[k] = at as u32;
            let cell = (x0 + k as i64 / nz, z0 + k as i64 % nz);
            while at < self.entries.len() && self.entries[at].0 <= cell {
                at += 1;
            }
        }
        self.starts[cells] = self.entries.len() as u32;
    }

    /// Makes the lists of [`Cells::block`] anew with `fill`, given the cleared lists and
    /// the rectangle's lowest cell and size (x, z), when the rectangle has a table of runs.
    fn make_blocks(
        &mut self,
        fill: impl FnOnce(&Cells, (i64, i64), (i64, i64), &mut Vec<usize>, &mut Vec<u32>),
    ) {
        let mut blocks = std::mem::take(&mut self.blocks);
        let mut ends = std::mem::take(&mut self.block_starts);
        blocks.clear();
        ends.clear();
        if !self.starts.is_empty() {
            fill(self, self.origin, self.size, &mut blocks, &mut ends);
        }
        self.blocks = blocks;
        self.block_starts = ends;
    }

    /// Gathers, for every cell of the rectangle, the items of the 3 × 3 cells round it
    /// in order (see [`Cells::block`]): once a tick for all, where every walker looked
    /// them up twice a tick and sorted them, and walkers in one cell share the list. Each
    /// item, in order, joins the lists of the nine cells round its own, so every list
    /// comes out in order without a sort. The items are `0..n`, each once (an actor).
    fn gather_blocks(&mut self) {
        self.make_blocks(|cells, (x0, z0), (nx, nz), blocks, ends| {
            let (nx, nz) = (nx as usize, nz as usize);
            // The rectangle's cells round each item's cell: columns `xs`, rows `zs`.
            let mut round = vec![(0..0, 0..0); cells.entries.len()];
            let count = nx * nz;
            ends.resize(count + 1, 0);
            for &((x, z), item) in &cells.entries {
                let (x, z) = ((x - x0) as usize, (z - z0) as usize);
                let xs = x.saturating_sub(1)..(x + 2).min(nx);
                let zs = z.saturating_sub(1)..(z + 2).min(nz);
                // Each list's length first (shifted by one: then where it starts).
                for x in xs.clone() {
                    for z in zs.clone() {
                        ends[x * nz + z + 1] += 1;
                    }
                }
                round[item] = (xs, zs);
            }
            for k in 0..count {
                ends[k + 1] += ends[k];
            }
            blocks.resize(ends[count] as usize, 0);
            let mut next = ends.clone();
            for (item, (xs, zs)) in round.into_iter().enumerate() {
                for x in xs {
                    for z in zs.clone() {
                        let k = x * nz + z;
                        blocks[next[k] as usize] = item;
                        next[k] += 1;
                    }
                }
            }
        });
    }

    /// Gathers, for every cell of the rectangle, the items of the 3 × 3 cells round it,
    /// sorted and each once (see [`Cells::block`]): an obstacle covers several cells, and
    /// every walker sorted the nine cells' items and dropped the repeats each tick (4 %
    /// of the crowd benchmark's navigation), where the obstacles seldom change.
    fn gather_unions(&mut self) {
        self.make_blocks(|cells, (x0, z0), (nx, nz), blocks, ends| {
            ends.push(0);
            let mut union = Vec::new();
            for x in x0..x0 + nx {
                for z in z0..z0 + nz {
                    union.clear();
                    cells.around_cell((x, z), &mut union);
                    union.sort_unstable();
                    union.dedup();
                    blocks.extend_from_slice(&union);
                    ends.push(blocks.len() as u32);
                }
            }
        });
    }

    /// The items in the 3 × 3 cells around `p`'s, in order, when `p`'s cell is one of
    /// the rectangle's and they were gathered.
    fn block(&self, p: DVec2) -> Option<&[usize]> {
        if self.block_starts.is_empty() {
            return None;
        }
        let ((x0, z0), (nx, nz)) = (self.origin, self.size);
        let (cx, cz) = cell_of(p);
        if cx < x0 || cx >= x0 + nx || cz < z0 || cz >= z0 + nz {
            return None;
        }
        let k = ((cx - x0) * nz + (cz - z0)) as usize;
        let (from, to) = (self.block_starts[k], self.block_starts[k + 1]);
        Some(&self.blocks[from as usize..to as usize])
    }

    /// Pushes onto `out` the items in the 3 × 3 cells around `p`'s, column by column,
    /// each column in the list's order.
    fn around(&self, p: DVec2, out: &mut Vec<usize>) {
        self.around_cell(cell_of(p), out);
    }

    /// [`Cells::around`] the cell `(cx, cz)`.
    fn around_cell(&self, (cx, cz): (i64, i64), out: &mut Vec<usize>) {
        let mut runs = [(0, 0); 3];
        for (x, run) in (cx - 1..=cx + 1).zip(&mut runs) {
            *run = self.column_run(x, cz - 1, cz + 1);
        }
        self.extend_with_runs(&runs, out);
    }

    /// Pushes onto `out` the items in the 3 × 3 cells around `p`'s that are not among
    /// the 3 × 3 cells around `seen`'s, column by column.
    fn around_except(&self, p: DVec2, seen: DVec2, out: &mut Vec<usize>) {
        let (cx, cz) = cell_of(p);
        let (sx, sz) = cell_of(seen);
        // Each column whole where it is not beside `seen`'s, else the rows below and
        // above those beside `seen`'s.
        let mut runs = [(0, 0); 6];
        for (x, pair) in (cx - 1..=cx + 1).zip(runs.chunks_exact_mut(2)) {
            if (x - sx).abs() > 1 {
                pair[0] = self.column_run(x, cz - 1, cz + 1);
            } else {
                pair[0] = self.column_run(x, cz - 1, (cz + 1).min(sz - 2));
                pair[1] = self.column_run(x, (cz - 1).max(sz + 2), cz + 1);
            }
        }
        self.extend_with_runs(&runs, out);
    }

    /// Where the items of column `x`'s cells from row `lo` to row `hi` lie in the
    /// entries: one run, since the entries are sorted by cell (empty when there are none).
    fn column_run(&self, x: i64, lo: i64, hi: i64) -> (usize, usize) {
        let entries = &self.entries;
        if lo > hi {
            return (0, 0);
        }
        if self.starts.is_empty() {
            let from = entries.partition_point(|e| e.0 < (x, lo));
            return (
                from,
                from + entries[from..].partition_point(|e| e.0 <= (x, hi)),
            );
        }
        let ((x0, z0), (nx, nz)) = (self.origin, self.size);
        let (lo, hi) = (lo.max(z0), hi.min(z0 + nz - 1));
        if x < x0 || x >= x0 + nx || lo > hi {
            return (0, 0);
        }
        let k = ((x - x0) * nz) as usize;
        let from = self.starts[k + (lo - z0) as usize] as usize;
        (from, self.starts[k + (hi - z0) as usize + 1] as usize)
    }

    /// Pushes onto `out` the items of the entries' `runs`, in turn. Room for all of them
    /// is made at once: growing the list run by run reallocated it (2 % of the crowd
    /// benchmark's instructions).
    fn extend_with_runs(&self, runs: &[(usize, usize)], out: &mut Vec<usize>) {
        out.reserve(runs.iter().map(|(from, to)| to - from).sum());
        for &(from, to) in runs {
            out.extend_from_slice(&self.items[from..to]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `count` actors spread over a field `half` metres either way of the origin, and
    /// when `spread` one more far out (then the table of runs would be too large), indexed.
    fn field(count: usize, half: f64, spread: bool) -> Crowd {
        let mut positions: Vec<DVec2> = (0..count)
            .map(|i| {
                let f = i as f64;
                DVec2::new((f * 7.31).sin() * half, (f * 3.17).cos() * half)
            })
            .collect();
        if spread {
            positions.push(DVec2::new(5.0e5, -5.0e5));
        }
        let mut crowd = Crowd {
            positions,
            ..Crowd::default()
        };
        crowd.index();
        assert_eq!(crowd.cells.starts.is_empty(), spread);
        crowd
    }

    #[test]
    fn the_table_of_runs_finds_what_the_binary_search_finds() {
        for spread in [false, true] {
            let crowd = field(200, 20.0, spread);
            let searched = Cells {
                starts: Vec::new(),
                ..crowd.cells.clone()
            };
            for k in 0..400 {
                let p = DVec2::new(k as f64 * 0.13 - 26.0, (k as f64 * 0.71).sin() * 26.0);
                let (mut a, mut b) = (Vec::new(), Vec::new());
                crowd.cells.around(p, &mut a);
                searched.around(p, &mut b);
                assert_eq!(a, b, "{p}");
            }
        }
    }

    #[test]
    fn the_gathered_blocks_give_what_looking_up_and_sorting_gives() {
        // Clusters and gaps on a field; points on it, at its edges and off it.
        let positions: Vec<DVec2> = (0..300)
            .map(|i| {
                let f = i as f64;
                let cluster = DVec2::new(
                    (f * 0.37).floor().sin() * 12.0,
                    (f * 0.37).floor().cos() * 9.0,
                );
                cluster + DVec2::new((f * 7.31).sin(), (f * 3.17).cos()) * 2.5
            })
            .collect();
        let mut crowd = Crowd {
            positions,
            ..Crowd::default()
        };
        crowd.index();
        assert!(!crowd.cells.block_starts.is_empty());
        let mut blocked = 0;
        for k in 0..2000 {
            let p = DVec2::new(
                (k as f64 * 0.113).sin() * 17.0,
                (k as f64 * 0.071).cos() * 14.0,
            );
            let mut near = Vec::new();
            crowd.near(p, &mut near);
            let mut looked_up = Vec::new();
            crowd.cells.around(p, &mut looked_up);
            looked_up.sort_unstable();
            assert_eq!(near, looked_up, "{p}");
            blocked += usize::from(crowd.cells.block(p).is_some());
        }
        // Most of the points are on the field, some off it.
        assert!((500..2000).contains(&blocked), "{blocked}");
    }

    #[test]
    fn floor_to_int_is_floor_then_as() {
        let mut random = troupe_body::math::draws(3);
        let special = [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.999999999,
            -3.0000001,
            1e300,
            -1e300,
        ]
        .into_iter()
        .chain([
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MIN_POSITIVE,
        ])
        .chain([-f64::MIN_POSITIVE, 9.3e18, -9.3e18, 4503599627370495.5]);
        let drawn = (0..100_000).map(|k| (random() - 0.5) * 10f64.powi(k % 20 - 4));
        for x in special.chain(drawn) {
            assert_eq!(floor_to_int(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn the_footprints_gathered_round_each_cell_are_what_looking_up_gives() {
        // Boxes of 0.3–7 m across (one covering many cells, most covering one to four) on
        // a field; points on it, at its edges and off it.
        let footprints: Vec<Footprint> = (0..120)
            .map(|i| {
                let f = i as f64;
                let at = DVec2::new((f * 1.37).sin() * 20.0, (f * 0.91).cos() * 15.0);
                let size = if i % 17 == 0 {
                    7.0
                } else {
                    0.3 + (f * 0.53).sin().abs() * 2.0
                };
                let corners = [(0.0, 0.0), (size, 0.0), (size, size), (0.0, size)];
                Footprint::hull("box", &corners.map(|(x, z)| at + DVec2::new(x, z)))
            })
            .collect();
        let mut crowd = Crowd::default();
        crowd.set_footprints(footprints);
        assert!(!crowd.footprint_cells.block_starts.is_empty());
        let mut gathered = 0;
        for k in 0..2000 {
            let p = DVec2::new(
                (k as f64 * 0.113).sin() * 26.0,
                (k as f64 * 0.071).cos() * 20.0,
            );
            let found = crowd.footprints_around(p, Vec::new()).into_found();
            let mut looked_up = Vec::new();
            crowd.footprint_cells.around(p, &mut looked_up);
            looked_up.sort_unstable();
            looked_up.dedup();
            assert_eq!(found, looked_up, "{p}");
            gathered += usize::from(crowd.footprint_cells.block(p).is_some());
        }
        assert!((500..2000).contains(&gathered), "{gathered}");
    }

    #[test]
    fn a_look_beyond_finds_what_one_look_adds_to_another() {
        for spread in [false, true] {
            let crowd = field(300, 15.0, spread);
            let mut added = 0;
            for k in 0..500 {
                let k = k as f64;
                let seen = DVec2::new((k * 0.113).sin() * 16.0, (k * 0.071).cos() * 16.0);
                // 3 m ahead, as a walker looks, or nearer and further.
                let ahead = seen + DVec2::new((k * 0.9).cos(), (k * 0.9).sin()) * (k % 7.0);
                let (mut here, mut there, mut beyond) = (Vec::new(), Vec::new(), Vec::new());
                crowd.near(seen, &mut here);
                crowd.near(ahead, &mut there);
                crowd.near_beyond(ahead, seen, &mut beyond);
                beyond.sort_unstable();
                let only_there: Vec<usize> =
                    there.into_iter().filter(|j| !here.contains(j)).collect();
                assert_eq!(beyond, only_there, "{seen} {ahead}");
                added += beyond.len();
            }
            assert!(added > 1000, "{added}");
        }
    }

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

    #[test]
    fn footprints_stay_current_until_a_wall_or_an_object_changes() {
        let mut crowd = Crowd::default();
        let table = ObjectStamp::Free {
            shape: Shape::Box {
                half_extents: DVec3::new(1.0, 0.4, 0.5),
            },
            position: DVec3::new(0.0, 0.4, 2.0),
            rotation: DQuat::IDENTITY,
            forced: None,
        };
        let wall = Wall {
            from: DVec2::ZERO,
            to: DVec2::X,
            thickness: 0.1,
            height: 2.0,
        };
        // Nothing yet: the empty set of footprints is current.
        assert!(crowd.footprints_current(&[], std::iter::empty()));
        assert!(!crowd.footprints_current(&[], [table].into_iter()));
        assert!(crowd.footprints_current(&[], [table].into_iter()));
        // A wall added, an object moved, picked up, added or removed: not current.
        let walls = std::slice::from_ref(&wall);
        assert!(!crowd.footprints_current(walls, [table].into_iter()));
        assert!(crowd.footprints_current(walls, [table].into_iter()));
        let moved = match table {
            ObjectStamp::Free {
                shape,
                rotation,
                forced,
                ..
            } => ObjectStamp::Free {
                shape,
                position: DVec3::new(0.0, 0.4, 2.001),
                rotation,
                forced,
            },
            held => held,
        };
        assert!(!crowd.footprints_current(walls, [moved].into_iter()));
        assert!(!crowd.footprints_current(walls, [ObjectStamp::Held].into_iter()));
        assert!(crowd.footprints_current(walls, [ObjectStamp::Held].into_iter()));
        let two = [ObjectStamp::Held, table];
        assert!(!crowd.footprints_current(walls, two.into_iter()));
        assert!(!crowd.footprints_current(walls, [ObjectStamp::Held].into_iter()));
    }
}
