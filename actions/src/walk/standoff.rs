//! Stand-offs in corridors: walkers that stand face to face, each in the other's way,
//! where neither can step aside (two pairs abreast meeting in a 1.6 m corridor, two
//! groups tied into a knot in a 2.3 m one). Avoidance only slows a walk along its plan
//! and drifts it sideways, so both would wait for good; new routes round people
//! standing find none where the people fill the way. In a passage narrower than 2.6 m
//! (obstacle to obstacle), after [`BACK_OFF_AFTER`] of waiting with someone face to
//! face in its way, one of the two steps back, and to its right where there is room,
//! until nobody it backs off for is in its way: the one with the much shorter way back
//! out of the passage (or the only one that can step back at all), else the one that
//! comes later in the order of headings (`troupe_nav::way::backs_off_for`, the same for
//! a whole stream). One with something close behind but room to its right (out of an
//! aisle, by the stand beyond its end) steps aside only, until the other is well beside
//! its way. One of its own stream standing behind it steps back with it. See
//! `docs/navigation.md`, "Stand-offs".

use super::replan::{STANDING, WAITING_RATE};
use troupe_body::glam::DVec2;
use troupe_scene::space::{backs_off_for, Crowd, FootprintsAround, GAP};
use troupe_scene::GeneratorContext;

/// Seconds a walk waits with someone face to face in its way before it may step back.
pub const BACK_OFF_AFTER: f64 = 2.0;
/// How near (m) to where it began to wait a body that sways or steps in place still waits.
const IN_PLACE: f64 = 0.15;
/// Speed (m/s) at which a walker steps back.
pub const BACK_SPEED: f64 = 0.3;
/// Largest gap (m) between two discs for the other to count as in my way.
const IN_THE_WAY: f64 = 0.6;
/// The same while I step back: a little further, so that a step back is not undone by
/// the next tick's sway.
const STILL_IN_THE_WAY: f64 = 0.9;
/// Shortest step back (s): once begun, a step back goes on this long at least.
const SHORTEST_STEP_BACK: f64 = 0.6;
/// Largest cosine between my way and the way another faces for it to face me.
const FACE_TO_FACE: f64 = -0.7;
/// Smallest cosine between my way and the way another faces for it to go my way.
const SAME_WAY: f64 = 0.7;
/// Speed (m/s) backwards along my way of one of my own stream ahead that steps back
/// (half of [`BACK_SPEED`]: a walk's sway as it stands moves the body by less).
const STEPPING_BACK: f64 = 0.15;
/// Largest gap (m) between two discs for one of my own stream stepping back to step
/// back into me.
const BACKED_INTO: f64 = 0.3;
/// Widest passage (m, from obstacle to obstacle across the way) in which a walker steps
/// back: a corridor, where nobody can step aside far. In the open a stand-off clears as
/// the others sidestep; stepping back there as well (after 2, 4 or 6 s, beside the
/// furniture or anywhere) put more limbs into one another in the plaza
/// (docs/navigation.md, "Stand-offs").
const PASSAGE: f64 = 2.6;
/// Step (m) along the way at which the passage's width is measured.
const PASSAGE_STEP: f64 = 0.1;
/// How far (m) ahead of the body, along its way, the passage's width is measured besides
/// where it stands: as far as a walker stands from a doorway it waits to go through
/// (three walkers a side of a 1.6 m doorway in a thin wall stood for good before it).
const PASSAGE_AHEAD: f64 = 1.0;
/// Furthest (m) looked to the right for room to step aside into.
const ASIDE: f64 = 0.5;
/// Step (m) at which that room is measured, and the gap it keeps from an obstacle.
const ASIDE_STEP: f64 = 0.1;
/// Furthest (m) looked back along a walker's way for the end of the passage it stands
/// in (see [`way_out`]): beyond, two walkers deep in a long aisle are as far from its ends.
const WAY_OUT_FURTHEST: f64 = 3.0;
/// By how much (m) one walker's way out of a passage must be the shorter for it, rather
/// than the one later in the order of headings, to step back: a metre, so that where the
/// ways out differ less (two groups before a doorway, or in a corridor) the order of
/// headings decides, for a whole stream at once (with a quarter of a metre, walkers of
/// both sides of a doorway stepped back, each for another, and feet met its wall).
const NEARER_OUT: f64 = 1.0;
/// Room (m) behind a walker, along its way back, under which it cannot step back: the
/// other steps back for it.
const CORNERED: f64 = 0.3;

/// Whether a walk stands in a stand-off, and since when it has waited.
#[derive(Clone, Debug, Default)]
pub struct Standoff {
    /// Walk time since which the walk has waited, and where its body stood then.
    waiting: Option<(f64, DVec2)>,
    /// Walk time since which the walk has stepped back, while it does.
    backing_since: Option<f64>,
}

impl Standoff {
    /// Whether the walk steps back this tick (as the last [`Standoff::update`] decided).
    pub fn backing(&self) -> bool {
        self.backing_since.is_some()
    }

    /// Decides whether actor `ctx.actor` at `position`, going along the unit `along`,
    /// steps back this tick (then true), from the previous tick's crowd: those near it
    /// (`others`, but its `companions`), its plan clock's `rate` and whether its body
    /// stands; `now` is the walk's time.
    pub fn update(
        &mut self,
        ctx: &GeneratorContext,
        (position, along): (DVec2, DVec2),
        (others, companions, footprints): (&[usize], &[usize], &FootprintsAround),
        rate: f64,
        now: f64,
    ) -> bool {
        let crowd = ctx.world.crowd;
        let me = ctx.actor;
        // Held by the clearance, a body stands while its plan's clock runs on: it waits
        // as much as one whose clock stands, and as long as it steps in place where it
        // began to (carrying a cup into a doorway as someone came through it the other
        // way, both stood in it for good; a walker facing a waiter in an aisle swayed
        // faster than standing now and then, and never waited long enough to step back).
        let standing = crowd
            .velocities
            .get(me)
            .is_some_and(|v| v.length() < STANDING);
        let in_place = self
            .waiting
            .is_some_and(|(_, at)| at.distance(position) < IN_PLACE);
        if rate < WAITING_RATE || standing || in_place {
            self.waiting.get_or_insert((now, position));
        } else {
            self.waiting = None;
            if !self.backing() {
                // Neither waiting nor stepping back: nothing to look at (most ticks).
                return false;
            }
        }
        let waited = self
            .waiting
            .is_some_and(|(since, _)| now - since >= BACK_OFF_AFTER);
        // How far a body reaches across the way: its disc, or, carrying something, as far
        // as its hands and what they hold reach (two waiters carrying trays in an aisle).
        let carried = |i: usize| crowd.cores.get(i).filter(|core| core.carries());
        let across = |i: usize| {
            let disc = crowd.radii[i];
            carried(i).map_or(disc, |core| core.radius.max(disc))
        };
        let radius = across(me);
        // Who steps back of two face to face: the one with the shorter way back out of
        // the passage, when the other's is much longer or stopped (a walker at a niche's
        // mouth, for the one in it with a shelf behind), whoever the other faces; else the
        // one later in the order of headings. Each reads the same world, both bodies as
        // the crowd has them, so the two agree.
        let way_out_of = |i: usize| way_out(crowd, crowd.positions[i], crowd.facings[i], across(i));
        // Mine is found once, for the first neighbour that faces me.
        let my_way_out = std::cell::OnceCell::new();
        // Whether it stepped back on the last tick (`backing`, below, is this tick's).
        let was_backing = self.backing();
        let backs_off = |towards: f64, (j, facing): (usize, DVec2)| {
            // One stepping back goes on for whoever faces it: once it stood cornered at
            // the end of an aisle it had stepped back along, the other, now the one with
            // the way out, stood too, for good (two waiters with trays).
            if was_backing {
                return true;
            }
            match (*my_way_out.get_or_init(|| way_out_of(me)), way_out_of(j)) {
                (Some(_), None) => return true,
                (None, Some(_)) => return false,
                (Some(mine), Some(theirs)) if mine + NEARER_OUT < theirs => return true,
                (Some(mine), Some(theirs)) if theirs + NEARER_OUT < mine => return false,
                _ => {}
            }
            towards < FACE_TO_FACE && backs_off_for(along, facing)
        };
        let in_the_way = if was_backing {
            STILL_IN_THE_WAY
        } else {
            IN_THE_WAY
        };
        // Stepping back with no room behind goes aside only (see `Standoff::preferred`).
        let stepping_aside = was_backing
            && crowd
                .radii
                .get(me)
                .is_some_and(|&disc| blocked_behind(position, along, disc, footprints));
        let (mut face_to_face, mut backed_into) = (false, false);
        let mine = crowd.cores.get(me);
        let i_carry = mine.is_some_and(|core| core.carries());
        for &j in others {
            if j == me || companions.contains(&j) {
                continue;
            }
            // Ahead, on my way, and near: behind me first, which needs neither body's
            // reach (about half of those near, looked at for a tenth of the work).
            let offset = crowd.positions[j] - position;
            if offset.dot(along) <= 0.0 {
                continue;
            }
            let reach = radius + across(j) + GAP;
            // Stepping aside, it goes on until the other is well beside its way, as a
            // step back goes on until the other is well ahead (`STILL_IN_THE_WAY`): let
            // go as soon as they stood clear, a waiter stepped aside and back again by
            // the stand beyond an aisle's end, the other held by their trays.
            let beside = if stepping_aside {
                reach + (STILL_IN_THE_WAY - IN_THE_WAY)
            } else {
                reach
            };
            if along.perp_dot(offset).abs() >= beside {
                continue;
            }
            // The gap between the two: what the hands carry out in front counts.
            let gap = match (mine, crowd.cores.get(j)) {
                (Some(mine), Some(theirs)) if i_carry || theirs.carries() => mine.gap(theirs) - GAP,
                _ => offset.length() - reach,
            };
            if gap > in_the_way {
                continue;
            }
            let Some(&facing) = crowd.facings.get(j) else {
                continue;
            };
            let towards = facing.dot(along);
            if towards < 0.0 && backs_off(towards, (j, facing)) {
                face_to_face = true;
            } else if towards > SAME_WAY
                && crowd.velocities[j].dot(along) < -STEPPING_BACK
                && gap < BACKED_INTO
            {
                backed_into = true;
            }
        }
        let begun = self
            .backing_since
            .is_some_and(|since| now - since < SHORTEST_STEP_BACK);
        // In a passage or before one: a doorway in a wall is a passage a wall's thickness
        // long, and those who wait for it stand before it.
        let in_a_passage = || {
            (0..=(PASSAGE_AHEAD / PASSAGE_STEP).round() as usize).any(|i| {
                let ahead = along * (i as f64 * PASSAGE_STEP);
                passage_width(position + ahead, along, footprints).is_some_and(|w| w < PASSAGE)
            })
        };
        let stand_off = backed_into || (face_to_face && (was_backing || waited));
        let backing = begun || (stand_off && in_a_passage());
        self.backing_since = if backing {
            self.backing_since.or(Some(now))
        } else {
            None
        };
        backing
    }

    /// The velocity a body of `radius` at `position`, going along the unit `along`,
    /// would like as it steps back: back along its way at [`BACK_SPEED`], and as much to
    /// its right as the `footprints` round it leave room (up to 0.5 m, keeping 0.1 m);
    /// with something close behind it (`blocked_behind`), aside only. Avoidance then
    /// keeps it off those behind and beside it.
    pub fn preferred(
        position: DVec2,
        along: DVec2,
        radius: f64,
        footprints: &FootprintsAround,
    ) -> DVec2 {
        let room = room_towards(position, along.perp(), radius, footprints, ASIDE);
        let aside = (room / (2.0 * ASIDE_STEP)).min(1.0);
        let back = if blocked_behind(position, along, radius, footprints) {
            0.0
        } else {
            1.0
        };
        (-along * back + along.perp() * aside)
            .try_normalize()
            .unwrap_or(-along)
            * BACK_SPEED
    }
}

/// Whether a body of `radius` at `position`, going along the unit `along`, has less than
/// [`CORNERED`] of room straight behind it among the `footprints` round it: a step back
/// then goes aside only (the stand beyond an aisle's end, with the open floor beside it).
fn blocked_behind(
    position: DVec2,
    along: DVec2,
    radius: f64,
    footprints: &FootprintsAround,
) -> bool {
    room_towards(position, -along, radius, footprints, CORNERED) < CORNERED
}

/// How far (m, at most `furthest`) a body of `radius` at `position` may move along the
/// unit `direction` before its disc comes within [`ASIDE_STEP`] of one of the
/// `footprints` round it, measured every [`ASIDE_STEP`]: in a corridor, nothing to the
/// right for the walker by the wall on its right.
fn room_towards(
    position: DVec2,
    direction: DVec2,
    radius: f64,
    footprints: &FootprintsAround,
    furthest: f64,
) -> f64 {
    let keep = radius + ASIDE_STEP;
    let mut room = furthest;
    for f in footprints.within(keep + furthest) {
        let mut d = 0.0;
        while d < room {
            let next = (d + ASIDE_STEP).min(room);
            if f.distance(position + direction * next) < keep {
                room = d;
                break;
            }
            d = next;
        }
    }
    room
}

/// How far (m) a body reaching `radius` across its way, at `position` and facing the
/// unit `way`, would step straight back before it stood out of every passage narrower
/// than [`PASSAGE`], measured every [`PASSAGE_STEP`] among the crowd's footprints round
/// each point: `None` if an obstacle stops it within [`CORNERED`] and it has no room to
/// step aside to its right either (it is cornered), the distance it went back if it has
/// (it makes way aside: see [`Standoff::preferred`]), [`WAY_OUT_FURTHEST`] if the passage
/// goes on further back or an obstacle stops it further on (one straight back, which a
/// step back turns round: the stand at an aisle's end). Only what it would come nearer
/// to stops it: a wall beside, however near, does not (a walker at a niche's mouth, a
/// hand's breadth from one of its walls, counted as cornered as the one with the shelf
/// behind it).
fn way_out(crowd: &Crowd, position: DVec2, way: DVec2, radius: f64) -> Option<f64> {
    let keep = radius + ASIDE_STEP;
    let steps = |m: f64| (m / PASSAGE_STEP).round() as usize;
    let mut found = Vec::new();
    for step in 1..=steps(WAY_OUT_FURTHEST) {
        let back = |step: usize| position - way * (step as f64 * PASSAGE_STEP);
        let (from, to) = (back(step - 1), back(step));
        let around = crowd.footprints_around(to, found);
        let stopped = around.within(keep).any(|f| {
            let near = f.distance(to);
            near < keep && near < f.distance(from)
        });
        if stopped && step > steps(CORNERED) {
            return Some(WAY_OUT_FURTHEST);
        }
        if stopped {
            // Something close behind: cornered, unless there is room to step aside to
            // the right, as a step back goes (see `Standoff::preferred`).
            let here = crowd.footprints_around(position, Vec::new());
            let aside = room_towards(position, way.perp(), radius, &here, ASIDE);
            return (aside >= ASIDE).then_some(step as f64 * PASSAGE_STEP);
        }
        if passage_width(to, way, &around).is_some_and(|w| w >= PASSAGE) {
            return Some(step as f64 * PASSAGE_STEP);
        }
        found = around.into_found();
    }
    Some(WAY_OUT_FURTHEST)
}

/// Whether a body at `position`, facing the unit `along`, stands in the open: in no
/// passage narrower than [`PASSAGE`] across `along` (see [`passage_width`]) among the
/// `footprints` round it.
pub(super) fn in_the_open(position: DVec2, along: DVec2, footprints: &FootprintsAround) -> bool {
    passage_width(position, along, footprints).is_some_and(|w| w >= PASSAGE)
}

/// The width (m, up to twice [`PASSAGE`]) of the passage across `along` at `position`:
/// how far the nearest of the `footprints` is on its left and on its right (at most
/// [`PASSAGE`] each), whatever their direction but behind it (a doorway in a thin wall, which a way
/// crosses at a slant, is as narrow as the door); `None` inside a footprint.
fn passage_width(position: DVec2, along: DVec2, footprints: &FootprintsAround) -> Option<f64> {
    let (mut left, mut right) = (PASSAGE, PASSAGE);
    // Within the footprints found round the body (a cell of the crowd's grid): one
    // missed further off only makes the passage measure wider.
    for f in footprints.within(PASSAGE) {
        if f.contains(position) {
            return None;
        }
        let Some(nearest) = f.nearest_point(position) else {
            continue;
        };
        let (offset, d) = (nearest - position, nearest.distance(position));
        // Wholly behind: a doorway just come through is not one to step back into. A
        // wall beside that goes on ahead counts, wherever its nearest point is: one
        // walking out of a niche at a slant, its nearest point on one side behind it,
        // counted as in the open and never stepped back for the one at its mouth.
        let ahead = |p: &DVec2| (*p - position).dot(along) >= -PASSAGE_STEP;
        if offset.dot(along) < -PASSAGE_STEP && !f.outline.iter().any(ahead) {
            continue;
        }
        if along.perp_dot(offset) > 0.0 {
            left = left.min(d);
        } else {
            right = right.min(d);
        }
    }
    Some(left + right)
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_scene::space::Footprint;

    /// A box's footprint from its corners (x0, z0) and (x1, z1).
    fn block(name: &str, (x0, z0): (f64, f64), (x1, z1): (f64, f64)) -> Footprint {
        let corners = [(x0, z0), (x1, z0), (x1, z1), (x0, z1)].map(|(x, z)| DVec2::new(x, z));
        Footprint::hull(name, &corners)
    }

    fn crowd_among(footprints: Vec<Footprint>) -> Crowd {
        let mut crowd = Crowd::default();
        crowd.set_footprints(footprints);
        crowd
    }

    /// The niche of `scripts/tests/navigation.lua`: 1 m wide, 2 m deep, open to -z, a
    /// shelf at its back.
    fn niche() -> Crowd {
        crowd_among(vec![
            block("west wall", (9.45, 0.0), (9.55, 2.0)),
            block("east wall", (10.45, 0.0), (10.55, 2.0)),
            block("back wall", (9.45, 1.95), (10.55, 2.05)),
            block("shelf", (9.55, 1.65), (10.45, 1.95)),
        ])
    }

    #[test]
    fn a_wall_beside_leaves_the_way_out_of_a_niche_open() {
        // A hand's breadth (0.07 m) from the west wall, at the niche's mouth: the room
        // measured round the disc (`room_towards`) is none, though stepping back never
        // comes nearer the wall.
        let (at, facing, radius) = (DVec2::new(9.83, 0.3), DVec2::Y, 0.28);
        let crowd = niche();
        let around = crowd.footprints_around(at, Vec::new());
        assert!(room_towards(at, -facing, radius, &around, CORNERED) < CORNERED);
        let out = way_out(&crowd, at, facing, radius).expect("a way out");
        assert!(out > 0.3 && out < 2.0, "{out} m out");
    }

    #[test]
    fn a_shelf_close_behind_leaves_no_way_out() {
        // In the niche facing out of it, the shelf 0.55 m behind.
        let crowd = niche();
        assert_eq!(
            way_out(&crowd, DVec2::new(10.0, 1.1), DVec2::NEG_Y, 0.28),
            None
        );
        // Facing the shelf at the niche's mouth, its back to the open.
        assert!(way_out(&crowd, DVec2::new(10.0, 0.3), DVec2::Y, 0.28).is_some());
    }

    #[test]
    fn the_way_out_of_an_aisle_is_the_shorter_nearer_its_end() {
        // An aisle 1.6 m wide from z = -4 to 4.
        let walls = vec![
            block("west wall", (-0.85, -4.0), (-0.75, 4.0)),
            block("east wall", (0.75, -4.0), (0.85, 4.0)),
        ];
        let crowd = crowd_among(walls.clone());
        let out = |z: f64| way_out(&crowd, DVec2::new(0.3, z), DVec2::Y, 0.28);
        // Facing north half a metre inside, stepping back south: out past the walls' ends.
        let near = out(-3.5).expect("a way out");
        assert!(near > 0.5 && near < 2.0, "{near} m out");
        // In the middle: further than is looked.
        assert_eq!(out(0.0), Some(WAY_OUT_FURTHEST));
        assert!(near + NEARER_OUT < WAY_OUT_FURTHEST);
        // With a stand on the aisle's line beyond its south end, it would come to the
        // stand further back than a step: it steps back round it, as far out as it can be.
        let stand = block("stand", (-0.25, -5.6), (0.25, -5.2));
        let crowd = crowd_among([walls, vec![stand]].concat());
        let on_line = way_out(&crowd, DVec2::new(0.3, -3.0), DVec2::Y, 0.28);
        assert_eq!(on_line, Some(WAY_OUT_FURTHEST));
    }

    #[test]
    fn a_stand_close_behind_with_the_open_floor_aside_is_no_corner() {
        // A waiter reaching 0.41 m with its tray, stepped back out of the aisle above to
        // beside the stand beyond its north end, facing back into it: the stand is close
        // behind, the open floor to its right (east, facing south).
        let walls = vec![
            block("west wall", (-0.85, -4.0), (-0.75, 4.0)),
            block("east wall", (0.75, -4.0), (0.85, 4.0)),
            block("stand", (-0.25, 5.2), (0.25, 5.6)),
        ];
        let crowd = crowd_among(walls);
        let (at, facing, radius) = (DVec2::new(0.45, 4.65), DVec2::NEG_Y, 0.41);
        let around = crowd.footprints_around(at, Vec::new());
        assert!(blocked_behind(at, facing, radius, &around));
        // Its way out is a step: it is the one to make way, not the one in the aisle.
        let out = way_out(&crowd, at, facing, radius).expect("room aside");
        assert!(out <= 0.3, "{out} m out");
        assert!(out + NEARER_OUT < WAY_OUT_FURTHEST);
        // And it makes way aside only, to its right.
        let v = Standoff::preferred(at, facing, radius, &around);
        assert!(v.dot(facing).abs() < 1e-12, "{v}");
        assert!((v - DVec2::X * BACK_SPEED).length() < 1e-12, "{v}");
    }
}
