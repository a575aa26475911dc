//! Right of way between crossing walkers: a stable give-way order, so that two streams
//! crossing each other's way do not both wait for a gap the other waits for too.
//!
//! Reciprocal avoidance alone lets the front rows of two crossing streams enter the
//! crossing together, each taking half the avoiding, until both stand in each other's way
//! (the plaza's gridlock, `docs/navigation.md`). Here one of the two has the way: the
//! walker whose line of walking comes first (by its angle, mod 180°, from 22.5°) keeps
//! going, the other stops at a line before the crossing ([`wait_line`]) until the first
//! has passed. The order is total over lines (no cycle of walkers each waiting for the
//! next, as "the one from the right goes first" makes at a four-way crossing), it depends
//! only on the two directions, and it reads nothing but the previous tick's world.

use crate::avoid::Agent;
use std::f64::consts::PI;
use troupe_body::glam::DVec2;

/// Smallest angle (radians) between two walkers' lines for their ways to cross: flows
/// that meet at a sharper angle merge, or pass head-on, by plain reciprocal avoidance.
pub const CROSSING: f64 = 60.0 * PI / 180.0;
/// Slowest speed (m/s) of a neighbour that makes others wait for it: one slower stands.
pub const MOVING: f64 = 0.1;
/// Speed (m/s) at which a slower neighbour with the way is expected to cross.
const ASSUMED_SPEED: f64 = 1.0;

/// Who gives way when my way meets a neighbour's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Precedence {
    /// Our ways do not cross (or one of us stands): we share the avoiding.
    Shared,
    /// I have the way: the neighbour waits for me.
    Mine,
    /// The neighbour has the way: I wait for it.
    Theirs,
}

/// Who gives way between a walker heading along `mine` and a neighbour heading along
/// `theirs` (directions; either may be unnormalised, a zero one crosses nobody).
pub fn precedence(mine: DVec2, theirs: DVec2) -> Precedence {
    match (line_rank(mine), line_rank(theirs)) {
        (Some(a), Some(b)) => precedence_of_ranks(a, b),
        _ => Precedence::Shared,
    }
}

/// [`precedence`] between the lines of ranks `a` (mine) and `b` (the neighbour's), each
/// found once (see [`line_rank`]).
fn precedence_of_ranks(a: f64, b: f64) -> Precedence {
    let apart = (a - b).abs();
    if apart.min(PI - apart) < CROSSING {
        Precedence::Shared
    } else if a < b {
        Precedence::Mine
    } else {
        Precedence::Theirs
    }
}

/// Where the ranking of lines starts over (radians from +x). Every ranking of lines has
/// such a cut, where a line a hair one way of it comes first and a hair the other way
/// comes last; it is put between the axes and their diagonals, where scenes' walkers
/// seldom go, so that the sway of a walk along an axis does not flip who has the way.
const CUT: f64 = PI / 8.0;

/// The rank of the line along `d`: its angle from [`CUT`], in [0, π). Both directions of
/// a line share it, so two counter-flows have the same rank.
fn line_angle(d: DVec2) -> f64 {
    (d.y.atan2(d.x) - CUT).rem_euclid(PI)
}

/// The rank of the line along `d` (see `line_angle`), or `None` for a zero direction,
/// which crosses nobody's way.
pub fn line_rank(d: DVec2) -> Option<f64> {
    (d.length() >= 1e-9).then(|| line_angle(d))
}

/// Whether a walker heading along `mine` steps back for one heading along `theirs` when
/// the two stand face to face, each in the other's way (a stand-off in a corridor or a
/// knot of walkers, `docs/navigation.md`, "Stand-offs"): the one whose heading comes
/// later round the whole turn from 22.5° (the cut of the lines' ranks) does. The order
/// is total over headings, so in any knot one walker at least keeps its place, and it
/// reads only the two headings: a stream meeting another head-on steps back as one.
pub fn backs_off_for(mine: DVec2, theirs: DVec2) -> bool {
    heading_key(mine) > heading_key(theirs)
}

/// The place of the heading along `d` in the order of [`backs_off_for`]: its angle from
/// [`CUT`], in [0, 2π).
fn heading_key(d: DVec2) -> f64 {
    (d.y.atan2(d.x) - CUT).rem_euclid(2.0 * PI)
}

/// Gap (m) a waiting walker keeps from the discs of those that have the way as they pass.
pub const WAIT_GAP: f64 = 1.5;
/// How far (m) a walker may have come onto the way of one that has it and still stop
/// there rather than go on across.
const OVERSHOOT: f64 = 0.3;
/// Seconds ahead a walker that has the way makes another wait: one further off leaves
/// time to cross.
pub const WAIT_HORIZON: f64 = 3.0;

/// A neighbour as the give-way rule sees it: its body, and which way it faces (a walker
/// faces its way, also while it waits or steps aside).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Walker {
    /// Where it is, how fast it goes, how wide it is.
    pub body: Agent,
    /// The unit floor direction it faces.
    pub facing: DVec2,
    /// The rank of that line ([`line_rank`] of `facing`): the crowd finds every actor's
    /// once a tick (`Crowd::ranks`), rather than each decision for each neighbour (an
    /// `atan2` per neighbour per decision, 2 % of the crowd benchmark's instructions).
    pub rank: Option<f64>,
}

impl Walker {
    /// A neighbour with `body`, facing `facing`, its line's rank found here.
    pub fn new(body: Agent, facing: DVec2) -> Walker {
        Walker {
            body,
            facing,
            rank: line_rank(facing),
        }
    }
}

/// How far (m) a walker may go along its way before it must wait for the neighbours that
/// have the way over it (see [`precedence`]); `None` when none makes it wait.
///
/// The walker is at `me` (its `velocity` is unused), heading along the unit `along` at
/// its planned `speed`. A neighbour `j` that moves (faster than [`MOVING`]) and faces a
/// line with the way makes the walker wait when `j`, going on the way it faces at its
/// speed or at least `ASSUMED_SPEED` (a walker slowed in a crowd will speed up again),
/// comes within [`WAIT_HORIZON`] of crossing the walker's way ahead, too soon for the
/// walker to cross first: the walker then stops where its disc stays [`WAIT_GAP`] clear
/// of `j`'s as `j` passes. A walker already well onto `j`'s way goes on across (stopping
/// there would block it).
pub fn wait_line(
    me: &Agent,
    along: DVec2,
    speed: f64,
    others: impl IntoIterator<Item = Walker>,
) -> Option<f64> {
    let mut line: Option<f64> = None;
    if along.length() < 1e-9 {
        return line;
    }
    let mine = line_angle(along);
    for j in others {
        // One facing nowhere crosses nobody's way. (Asked before the speed, which takes a
        // square root: most of those near do not have the way.)
        if j.rank.map(|b| precedence_of_ranks(mine, b)) != Some(Precedence::Theirs) {
            continue;
        }
        let moving = j.body.velocity.length();
        if moving < MOVING {
            continue;
        }
        let velocity = j.facing * moving.max(ASSUMED_SPEED);
        let half = me.radius + j.body.radius + WAIT_GAP;
        let offset = j.body.position - me.position;
        // j's distance from my line (signed) and its speed across it.
        let off_line = along.perp_dot(offset);
        let across = along.perp_dot(velocity);
        if across.abs() < 1e-6 {
            continue;
        }
        // When j's centre crosses my line, and how long it is within `half` of it.
        let t_centre = -off_line / across;
        let t_out = t_centre + half / across.abs();
        if t_out <= 0.0 || t_centre - half / across.abs() > WAIT_HORIZON {
            continue;
        }
        // Where along my way j crosses it, and the stretch of my way its disc sweeps.
        let s_cross = along.dot(offset) + along.dot(velocity) * t_centre;
        let sweep = half * velocity.length() / across.abs();
        let (s_in, s_out) = (s_cross - sweep, s_cross + sweep);
        if s_out <= 0.0 || s_in <= -OVERSHOOT {
            // Behind me, or I am well on its way already: go on across.
            continue;
        }
        // Time enough to cross before j comes (from standing, a second to get going).
        let t_in = t_centre - half / across.abs();
        if speed > 0.05 && s_out / speed + 1.0 < t_in {
            continue;
        }
        let s_in = s_in.max(0.0);
        line = Some(line.map_or(s_in, |l: f64| l.min(s_in)));
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_ways_have_one_and_only_one_precedence() {
        let dirs = [0.0f64, 30.0, 60.0, 90.0, 135.0, 180.0, 250.0, 300.0];
        for &a in &dirs {
            for &b in &dirs {
                let (u, v) = (
                    DVec2::from_angle(a.to_radians()),
                    DVec2::from_angle(b.to_radians()),
                );
                let (p, q) = (precedence(u, v * 1.3), precedence(v, u * 1.3));
                match p {
                    Precedence::Shared => assert_eq!(q, Precedence::Shared, "{a} {b}"),
                    Precedence::Mine => assert_eq!(q, Precedence::Theirs, "{a} {b}"),
                    Precedence::Theirs => assert_eq!(q, Precedence::Mine, "{a} {b}"),
                }
            }
        }
    }

    #[test]
    fn of_two_walkers_face_to_face_exactly_one_steps_back() {
        for a in (0..72).map(|k| k as f64 * 5.0 + 0.3) {
            let mine = DVec2::from_angle(a.to_radians());
            for off in [180.0f64, 150.0, 210.0, 135.0] {
                let theirs = DVec2::from_angle((a + off).to_radians()) * 1.7;
                assert_ne!(
                    backs_off_for(mine, theirs),
                    backs_off_for(theirs, mine),
                    "{a} {off}"
                );
            }
        }
        // A total order: of three walkers, one steps back for none of the others.
        let dirs = [0.2f64, 2.3, 4.4].map(DVec2::from_angle);
        let keeps = dirs
            .iter()
            .filter(|&&d| dirs.iter().all(|&e| !backs_off_for(d, e)))
            .count();
        assert_eq!(keeps, 1);
    }

    #[test]
    fn counter_flows_share_and_perpendicular_ones_do_not() {
        let east = DVec2::new(1.3, 0.0);
        let north = DVec2::new(0.0, 1.3);
        assert_eq!(precedence(east, -east), Precedence::Shared);
        assert_eq!(precedence(east, east * 0.5), Precedence::Shared);
        // The line along z comes first, whichever way along it each walks, and a walk's
        // sway does not change that.
        assert_eq!(precedence(north, east), Precedence::Mine);
        assert_eq!(precedence(-north, -east), Precedence::Mine);
        assert_eq!(precedence(east, -north), Precedence::Theirs);
        for sway in [-0.06, 0.0, 0.06] {
            assert_eq!(
                precedence(east, north + DVec2::X * sway),
                Precedence::Theirs
            );
            assert_eq!(
                precedence(east + DVec2::Y * sway, north),
                Precedence::Theirs
            );
        }
        // Nobody crosses a walker without a direction.
        assert_eq!(precedence(north, DVec2::ZERO), Precedence::Shared);
    }

    #[test]
    fn there_is_no_cycle_of_waiting() {
        // Whoever has the way over whom, among walkers in 24 directions: never a chain
        // a over b over c with c over a.
        let dirs: Vec<DVec2> = (0..24)
            .map(|k| DVec2::from_angle(k as f64 * PI / 12.0 + 0.1))
            .collect();
        let over = |a: DVec2, b: DVec2| precedence(a, b) == Precedence::Mine;
        for &a in &dirs {
            for &b in dirs.iter().filter(|&&b| over(a, b)) {
                for &c in dirs.iter().filter(|&&c| over(b, c)) {
                    assert!(!over(c, a), "{a} {b} {c}");
                }
            }
        }
    }

    fn walker(x: f64, z: f64, facing: DVec2, speed: f64) -> Walker {
        Walker::new(Agent::disc(DVec2::new(x, z), facing * speed, 0.28), facing)
    }

    #[test]
    fn a_walker_waits_before_the_way_of_one_that_has_it() {
        // I walk along +x from (−3, 0); a walker along +z (its line comes first) will
        // cross my way at (0, 0) in 2 s.
        let me = walker(-3.0, 0.0, DVec2::X, 1.3).body;
        let north = walker(0.0, -2.6, DVec2::Y, 1.3);
        let line = wait_line(&me, DVec2::X, 1.3, [north]).unwrap();
        // Stopped there, my disc stays WAIT_GAP clear of its disc.
        assert!((line - (3.0 - (0.56 + WAIT_GAP))).abs() < 1e-9, "{line}");
        // It does not wait for me: my line comes after its.
        let it = north.body;
        let me_walking = walker(-3.0, 0.0, DVec2::X, 1.3);
        assert_eq!(wait_line(&it, DVec2::Y, 1.3, [me_walking]), None);
        // Far off (crossing in more than WAIT_HORIZON), past me, or standing: no wait.
        let far = walker(0.0, -6.0, DVec2::Y, 1.3);
        let past = walker(0.0, 2.5, DVec2::Y, 1.3);
        let standing = walker(0.0, -1.0, DVec2::Y, 0.0);
        assert_eq!(wait_line(&me, DVec2::X, 1.3, [far, past, standing]), None);
        // Already well onto its way: go on across.
        let on_way = walker(-0.3, 0.0, DVec2::X, 1.3).body;
        assert_eq!(wait_line(&on_way, DVec2::X, 1.3, [north]), None);
        // Slowed down in a crowd, it still has the way, expected at ASSUMED_SPEED.
        let slow = walker(0.0, -2.6, DVec2::Y, 0.2);
        assert!(wait_line(&me, DVec2::X, 1.3, [slow]).is_some());
    }
}
