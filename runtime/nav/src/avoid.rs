//! Local avoidance between walkers: reciprocal velocity obstacles by sampling (van den
//! Berg, Lin and Manocha 2008, the penalty form of their section 5). Each walker picks,
//! among a fixed list of candidate velocities around the one it would like, the one that
//! best trades deviation against time to collision, taking half the effort of avoiding
//! every neighbour (the "reciprocal" part) and all of it for obstacles. The candidates
//! are tried in a fixed order and the first best wins, so the choice is a pure function
//! of the previous tick's world: bit-identical with any thread count.

use crate::footprint::Footprint;
use smallvec::SmallVec;
use troupe_body::glam::DVec2;

/// Seconds ahead a collision matters.
pub const HORIZON: f64 = 3.0;
/// Gap (m) kept between two bodies' discs.
pub const GAP: f64 = 0.03;
/// Weight of 1 / (time to collision) against the deviation from the preferred velocity
/// (m, the penalty's units are m/s).
const URGENCY: f64 = 1.2;
/// Below this speed (m/s) a neighbour counts as standing: it will not take its half.
const STANDING: f64 = 0.1;
/// Speed factors of the candidates.
const SPEEDS: [f64; 5] = [1.0, 0.7, 0.4, 0.15, 0.06];
/// Turns (degrees) of the candidates from the preferred direction; negative turns to the
/// right and comes first, so two walkers head-on both keep right.
const TURNS: [f64; 13] = [
    0.0, -15.0, 15.0, -30.0, 30.0, -45.0, 45.0, -60.0, 60.0, -90.0, 90.0, -120.0, 120.0,
];

/// A body on the floor: where it is, how fast it goes, how wide it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Agent {
    /// Floor position (x, z).
    pub position: DVec2,
    /// Velocity (x, z) over the last tick.
    pub velocity: DVec2,
    /// Body radius (m).
    pub radius: f64,
    /// Floor points (x, z) under the body's ankles (its position for a body without
    /// feet). A walker's legs reach out to its feet: a foot planted a stride ahead
    /// reaches past the disc, and the walker cannot stop before it has come over it.
    pub feet: [DVec2; 2],
}

/// How far (m) a body reaches past the point under an ankle: the toes ahead of it, the
/// heel behind, and the leg leaning out above it.
pub const FOOT: f64 = 0.15;

impl Agent {
    /// A body of `radius` at `position` going at `velocity`, its feet under it.
    pub fn disc(position: DVec2, velocity: DVec2, radius: f64) -> Agent {
        Agent {
            position,
            velocity,
            radius,
            feet: [position; 2],
        }
    }

    /// How far (m) the body reaches from its position along the unit vector `towards`:
    /// its radius, or further where a foot reaches out that way (by [`FOOT`] past it).
    #[inline]
    pub fn reach(&self, towards: DVec2) -> f64 {
        self.feet
            .iter()
            .map(|f| (*f - self.position).dot(towards) + FOOT)
            .fold(self.radius, f64::max)
    }
}

/// The velocity `me` should take to go about `preferred` without running into `others`
/// or `obstacles`; `preferred` itself when nothing is in the way (then the second value is
/// true).
pub fn choose_velocity<'a>(
    me: &Agent,
    preferred: DVec2,
    others: &[Agent],
    obstacles: impl IntoIterator<Item = &'a Footprint>,
) -> (DVec2, bool) {
    let bounded = obstacles.into_iter().map(|f| (f, f.bounding_circle()));
    choose_velocity_bounded(me, preferred, others, bounded)
}

/// [`choose_velocity`], each obstacle given with the circle round it (centre, radius:
/// [`Footprint::bounding_circle`]), as the crowd keeps them: a decision among furniture
/// need not find them again.
pub fn choose_velocity_bounded<'a>(
    me: &Agent,
    preferred: DVec2,
    others: &[Agent],
    obstacles: impl IntoIterator<Item = (&'a Footprint, (DVec2, f64))>,
) -> (DVec2, bool) {
    let speed = preferred.length();
    let base = if speed > 1e-6 { speed } else { 0.5 };
    let forward = match preferred.try_normalize() {
        Some(forward) if speed > 1e-6 => forward,
        _ => DVec2::Y,
    };
    let spare = SPARE_NEIGHBOURS.take();
    let mut world = Surroundings::new(me, preferred, base, (others, spare), obstacles);
    let chosen = world.best(base, forward, speed > 1e-6);
    SPARE_NEIGHBOURS.set(std::mem::take(&mut world.neighbours));
    chosen
}

thread_local! {
    /// A list of neighbours kept on each thread from one decision to the next, so that a
    /// decision does not allocate one (see `docs/PERFORMANCE.md`, "One look beyond").
    static SPARE_NEIGHBOURS: std::cell::Cell<Vec<Neighbour>> =
        const { std::cell::Cell::new(Vec::new()) };
}

/// The candidate velocity turned from the unit `forward` by the turn of sine and cosine
/// `(s, c)`, at `k` times `base`.
fn candidate(forward: DVec2, (s, c): (f64, f64), base: f64, k: f64) -> DVec2 {
    // A positive turn is counter-clockwise seen from above (x, z): to the left of a
    // walker facing +z is +x.
    let dir = DVec2::new(
        forward.x * c + forward.y * s,
        -forward.x * s + forward.y * c,
    );
    dir * base * k
}

/// The sines and cosines of [`TURNS`].
static FAN: std::sync::LazyLock<[(f64, f64); TURNS.len()]> =
    std::sync::LazyLock::new(|| TURNS.map(|turn| turn.to_radians().sin_cos()));

/// For each of [`SPEEDS`] and [`TURNS`], the candidate's distance from the preferred
/// velocity, the preferred speed being 1: |k·(sin t, cos t) − (0, 1)|.
static DEVIATIONS: std::sync::LazyLock<[[f64; TURNS.len()]; SPEEDS.len()]> =
    std::sync::LazyLock::new(|| {
        SPEEDS.map(|k| {
            TURNS.map(|turn| {
                let (s, c) = turn.to_radians().sin_cos();
                DVec2::new(k * s, k * c - 1.0).length()
            })
        })
    });

/// The least of each row of [`DEVIATIONS`]: the candidate going straight on, and no row's
/// less than the row's before (the rows go slower).
static LEAST: std::sync::LazyLock<[f64; SPEEDS.len()]> = std::sync::LazyLock::new(|| {
    DEVIATIONS.map(|row| row.iter().copied().fold(f64::INFINITY, f64::min))
});

/// A neighbour as one decision sees it: what every candidate velocity shares, found once.
struct Neighbour {
    /// From me to them.
    offset: DVec2,
    /// Its length.
    distance: f64,
    /// Their velocity.
    velocity: DVec2,
    /// Whether our discs (with the gap) already touch.
    touching: bool,
    /// The candidate's share of the relative velocity: 2 when they take half the
    /// avoiding, 1 when they stand.
    share: f64,
    /// What the relative velocity loses to their motion (and mine, when reciprocal).
    shift: DVec2,
    /// `|offset|² − reach²` of the ray–disc test.
    clearance: f64,
}

/// An obstacle near enough to matter to some candidate within [`OBSTACLE_LOOKAHEAD`].
struct Near<'a> {
    /// Its footprint.
    footprint: &'a Footprint,
    /// The centre and radius of a circle around it, for a quick "too far to touch".
    centre: DVec2,
    /// That circle's radius.
    bound: f64,
    /// How far it is now.
    now: f64,
}

/// Seconds ahead an obstacle matters, in steps of a quarter second.
const OBSTACLE_LOOKAHEAD: f64 = 0.75;

/// Everything one decision reads, prepared once for all its candidates.
struct Surroundings<'a> {
    /// Where I stand.
    position: DVec2,
    /// My radius.
    radius: f64,
    /// The velocity I would like.
    preferred: DVec2,
    /// The walkers and standers near me.
    neighbours: Vec<Neighbour>,
    /// The obstacles some candidate could reach (the usual few on the stack).
    obstacles: SmallVec<[Near<'a>; 8]>,
}

impl<'a> Surroundings<'a> {
    /// What `me` sees, for candidates no faster than `fastest`, of the `others` (listed
    /// in `list`, its contents dropped) and the `obstacles`.
    fn new(
        me: &Agent,
        preferred: DVec2,
        fastest: f64,
        (others, mut list): (&[Agent], Vec<Neighbour>),
        obstacles: impl IntoIterator<Item = (&'a Footprint, (DVec2, f64))>,
    ) -> Surroundings<'a> {
        list.clear();
        list.extend(others.iter().map(|o| {
            let offset = o.position - me.position;
            // Each body reaches towards the other as far as its disc or its feet.
            let towards = offset.normalize_or_zero();
            let reach = me.reach(towards) + o.reach(-towards) + GAP;
            // Reciprocal: I take half the change and they are assumed to take the
            // other half, unless they stand still: then I go round them alone.
            let (share, shift) = if o.velocity.length() > STANDING {
                (2.0, me.velocity + o.velocity)
            } else {
                (1.0, o.velocity)
            };
            Neighbour {
                offset,
                distance: offset.length(),
                velocity: o.velocity,
                touching: offset.length() < reach,
                share,
                shift,
                clearance: offset.length_squared() - reach * reach,
            }
        }));
        let reach = me.radius + fastest * OBSTACLE_LOOKAHEAD;
        let obstacles = obstacles
            .into_iter()
            .filter_map(|(footprint, (centre, bound))| {
                // No candidate comes within my radius of it in time: leave it out.
                if (centre - me.position).length() - bound >= reach {
                    return None;
                }
                Some(Near {
                    footprint,
                    centre,
                    bound,
                    now: footprint.distance(me.position),
                })
            })
            .collect();
        Surroundings {
            position: me.position,
            radius: me.radius,
            preferred,
            neighbours: list,
            obstacles,
        }
    }

    /// The velocity to go at among these surroundings, `base` being the preferred speed
    /// (or a stand-in when it is zero, then not `known`) and `forward` its direction:
    /// the preferred velocity itself when nothing is in the way (then true), else the
    /// first best of standing still and the fan of candidates.
    fn best(&self, base: f64, forward: DVec2, known: bool) -> (DVec2, bool) {
        let preferred = self.preferred;
        let mut best = (preferred, self.penalty(preferred, f64::INFINITY));
        if best.1 <= 0.0 {
            return (preferred, true);
        }
        let still = self.penalty(DVec2::ZERO, best.1);
        if still < best.1 {
            best = (DVec2::ZERO, still);
        }
        // How far a candidate is from the preferred velocity depends only on its speed
        // factor and turn (`DEVIATIONS`, in units of the preferred speed). A candidate
        // that deviates more than the best penalty so far has lost before any neighbour
        // is weighed (its penalty starts at its deviation), and most of the fan has: they
        // are passed over on the table's figure, with a margin far above the rounding of
        // the deviation that `Surroundings::penalty` computes, so the same ones lose.
        for ((k, deviations), &least) in SPEEDS.iter().zip(DEVIATIONS.iter()).zip(LEAST.iter()) {
            // Slower rows deviate more (`LEAST` only grows): once a row's least deviation
            // has lost, so has every candidate left.
            if known && least * base > best.1 + 1e-9 * base {
                break;
            }
            for (&(s, c), &deviation) in FAN.iter().zip(deviations) {
                if known && deviation * base > best.1 + 1e-9 * base {
                    continue;
                }
                let v = candidate(forward, (s, c), base, *k);
                let p = self.penalty(v, best.1);
                if p < best.1 {
                    best = (v, p);
                }
            }
        }
        (best.0, false)
    }

    /// Deviation from the preferred velocity plus urgency over the time to the first
    /// collision of candidate `v`; 0 when `v` is the preferred velocity and nothing is hit
    /// within [`HORIZON`]. The search stops as soon as the penalty reaches `bound` (the
    /// best so far): it only grows, so the candidate has lost, and the value returned is
    /// then some number at least `bound`.
    fn penalty(&self, v: DVec2, bound: f64) -> f64 {
        let deviation = (v - self.preferred).length();
        if deviation >= bound {
            return deviation;
        }
        let with = |ttc: f64| {
            if ttc > HORIZON {
                deviation
            } else {
                deviation + URGENCY / ttc.max(1e-3)
            }
        };
        let mut ttc = f64::INFINITY;
        for n in &self.neighbours {
            if n.touching {
                // Already too close: only moving apart (or not closer) is acceptable,
                // whatever the other does.
                let closing = (v - n.velocity).dot(n.offset) / n.distance.max(1e-9);
                if closing > 0.0 {
                    return 1e9 + closing;
                }
                continue;
            }
            let t = ray_disc(n.offset, n.share * v - n.shift, n.clearance);
            if t < ttc {
                ttc = t;
                if with(ttc) >= bound {
                    return with(ttc);
                }
            }
        }
        for o in &self.obstacles {
            // Obstacles stand still: only the next moments matter, or a slow sidestep
            // towards a wall would count as a collision long before it could be one.
            for step in 1..=3 {
                let t = step as f64 * 0.25;
                let at = self.position + v * t;
                // Outside the circle round it by my radius: no need to measure closer.
                if (at - o.centre).length() - o.bound >= self.radius {
                    continue;
                }
                let gap = o.footprint.distance(at);
                if gap < self.radius && gap < o.now {
                    ttc = ttc.min(t);
                    break;
                }
            }
        }
        with(ttc)
    }
}

/// When a point leaving the origin at velocity `v` first comes within reach of `d`
/// (`clearance`: `|d|² − reach²`).
fn ray_disc(d: DVec2, v: DVec2, clearance: f64) -> f64 {
    let b = v.dot(d);
    if b <= 0.0 {
        return f64::INFINITY;
    }
    let a = v.length_squared();
    let disc = b * b - a * clearance;
    if a < 1e-12 || disc < 0.0 {
        return f64::INFINITY;
    }
    (b - disc.sqrt()) / a
}

#[cfg(test)]
mod tests {
    use super::*;

    fn agent(x: f64, z: f64, vx: f64, vz: f64) -> Agent {
        Agent::disc(DVec2::new(x, z), DVec2::new(vx, vz), 0.28)
    }

    #[test]
    fn a_slower_row_of_candidates_never_deviates_less() {
        // What lets `Surroundings::best` stop at the first row that has lost.
        for pair in LEAST.windows(2) {
            assert!(pair[0] <= pair[1], "{LEAST:?}");
        }
        for (row, least) in DEVIATIONS.iter().zip(LEAST.iter()) {
            assert!(row.iter().all(|d| d >= least));
        }
    }

    #[test]
    fn nothing_in_the_way_keeps_the_preferred_velocity() {
        let me = agent(0.0, 0.0, 0.0, 1.2);
        let aside = agent(3.0, 0.0, 0.0, 1.2);
        let (v, free) = choose_velocity(&me, DVec2::new(0.0, 1.2), &[aside], []);
        assert!(free);
        assert_eq!(v, DVec2::new(0.0, 1.2));
    }

    #[test]
    fn head_on_walkers_both_keep_right() {
        let a = agent(0.0, 0.0, 0.0, 1.2);
        let b = agent(0.0, 3.0, 0.0, -1.2);
        let (va, _) = choose_velocity(&a, DVec2::new(0.0, 1.2), &[b], []);
        let (vb, _) = choose_velocity(&b, DVec2::new(0.0, -1.2), &[a], []);
        // a faces +z: its right is −x; b faces −z: its right is +x.
        assert!(va.x < 0.0 && vb.x > 0.0, "{va} {vb}");
        // Mirror images: the choice depends only on the geometry.
        assert!((va.x + vb.x).abs() < 1e-12 && (va.y + vb.y).abs() < 1e-12);
    }

    #[test]
    fn a_foot_planted_ahead_widens_the_reach_towards_it_only() {
        let mut a = agent(0.0, 0.0, 0.0, 1.2);
        assert_eq!(a.reach(DVec2::Y), 0.28);
        a.feet = [DVec2::new(0.09, 0.6), DVec2::new(-0.09, -0.2)];
        assert!((a.reach(DVec2::Y) - (0.6 + FOOT)).abs() < 1e-12);
        assert!((a.reach(DVec2::X) - 0.28).abs() < 1e-12);
        // Bob stands 0.8 m ahead: the discs are 0.21 m apart, so Ann may still go on
        // at a slant; with her foot planted 0.4 m ahead her leg already reaches him, and
        // she may only keep her distance.
        let bob = agent(0.0, 0.8, 0.0, 0.0);
        let ann = agent(0.0, 0.0, 0.0, 1.2);
        let (v, _) = choose_velocity(&ann, DVec2::new(0.0, 1.2), &[bob], []);
        assert!(v.y > 0.0, "{v}");
        let ann = Agent {
            feet: [DVec2::new(0.09, 0.4), DVec2::new(-0.09, -0.1)],
            ..ann
        };
        let (v, _) = choose_velocity(&ann, DVec2::new(0.0, 1.2), &[bob], []);
        assert!(v.y <= 0.0, "{v}");
    }

    #[test]
    fn overlapping_bodies_never_close_in() {
        let me = agent(0.0, 0.0, 0.0, 1.0);
        let other = agent(0.0, 0.5, 0.0, 0.0);
        let (v, _) = choose_velocity(&me, DVec2::new(0.0, 1.0), &[other], []);
        assert!(v.y <= 0.0, "{v}");
    }

    #[test]
    fn a_wall_ahead_is_not_walked_into() {
        let wall = Footprint::hull(
            "wall",
            &[
                DVec2::new(-2.0, 0.5),
                DVec2::new(2.0, 0.5),
                DVec2::new(2.0, 0.6),
                DVec2::new(-2.0, 0.6),
            ],
        );
        let me = agent(0.0, 0.0, 0.0, 1.0);
        let (v, _) = choose_velocity(&me, DVec2::new(0.0, 1.0), &[], [&wall]);
        assert!(v.y < 0.5, "{v}");
    }

    /// What [`choose_velocity`] picks when every candidate of the fan is weighed.
    fn weighing_every_candidate(
        me: &Agent,
        preferred: DVec2,
        others: &[Agent],
        obstacles: &[&Footprint],
    ) -> DVec2 {
        let speed = preferred.length();
        let base = if speed > 1e-6 { speed } else { 0.5 };
        let forward = preferred.try_normalize().filter(|_| speed > 1e-6);
        let forward = forward.unwrap_or(DVec2::Y);
        let world = Surroundings::new(
            me,
            preferred,
            base,
            (others, Vec::new()),
            obstacles.iter().map(|&f| (f, f.bounding_circle())),
        );
        let mut best = (preferred, world.penalty(preferred, f64::INFINITY));
        if best.1 <= 0.0 {
            return preferred;
        }
        let still = world.penalty(DVec2::ZERO, best.1);
        if still < best.1 {
            best = (DVec2::ZERO, still);
        }
        for k in SPEEDS {
            for &turn in FAN.iter() {
                let v = candidate(forward, turn, base, k);
                let p = world.penalty(v, best.1);
                if p < best.1 {
                    best = (v, p);
                }
            }
        }
        best.0
    }

    #[test]
    fn candidates_passed_over_by_their_deviation_change_no_choice() {
        // Crowds of 1 to 12 walkers and standers round a walker, some touching it, a
        // pillar now and then; the preferred velocity of any speed (none too) and way.
        let pillar = Footprint::disc("pillar", DVec2::new(0.4, 1.1), 0.2);
        let mut random = troupe_body::math::draws(12345);
        let mut chose_a_turn = 0;
        for case in 0..2000 {
            let me = agent(0.0, 0.0, random() - 0.5, random() * 1.5);
            let others: Vec<Agent> = (0..1 + case % 12)
                .map(|_| {
                    let (a, d) = (random() * std::f64::consts::TAU, 0.4 + random() * 3.0);
                    let moving = random() < 0.7;
                    let (vx, vz) = if moving {
                        (random() * 2.6 - 1.3, random() * 2.6 - 1.3)
                    } else {
                        (0.0, 0.0)
                    };
                    agent(d * a.sin(), d * a.cos(), vx, vz)
                })
                .collect();
            let obstacles: Vec<&Footprint> = if case % 3 == 0 { vec![&pillar] } else { vec![] };
            let speed = if case % 50 == 0 { 0.0 } else { random() * 1.6 };
            let way = random() * std::f64::consts::TAU;
            let preferred = DVec2::new(way.sin(), way.cos()) * speed;
            let (v, _) = choose_velocity(&me, preferred, &others, obstacles.iter().copied());
            let every = weighing_every_candidate(&me, preferred, &others, &obstacles);
            assert_eq!(v, every, "case {case}");
            if v != preferred && v != DVec2::ZERO {
                chose_a_turn += 1;
            }
        }
        // The crowds are thick enough that the fan decides often.
        assert!(chose_a_turn > 500, "{chose_a_turn}");
    }
}
