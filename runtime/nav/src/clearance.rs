//! The backstop behind avoidance: each tick, a walker's body moves towards no other body or
//! obstacle further than keeps them apart, and its feet land and swing clear of them,
//! whatever avoidance chose.
//!
//! Avoidance ([`crate::avoid`]) weighs velocities; in a dense crowd the best of them may
//! still close on a neighbour, and a walker held by its planted feet or stopped by the
//! give-way rule may not go where it chose. Three rules, all from the previous tick's
//! world:
//!
//! - **The body's step** ([`limit_step`]; conservative advancement, as in continuous
//!   collision detection). A body on the floor is a [`Capsule`] along the way it faces:
//!   its disc (the body's radius) stretched forwards and backwards by its stride and as
//!   far as its feet and knees stand, widened by a foot planted wide
//!   ([`Body::around`]). Against each neighbour's capsule, the step from where the body
//!   stood may close at most **half** the gap between the two (less [`BODY_MARGIN`]),
//!   measured between their nearest points; the neighbour, deciding from the same
//!   previous tick, closes at most the other half, so together they never close more than
//!   the gap. Against an obstacle, which stands still, the whole gap (less
//!   [`OBSTACLE_MARGIN`]), for the capsule and for the disc round its middle (the
//!   capsule stretches and turns from tick to tick, so one touching a corner could slide
//!   its end along it while its middle closed in). A gap already closed may not close
//!   further. The walker's own capsule is the part its step carries (the crowd's core,
//!   without its planted feet); its neighbours' are whole. Sliding along a
//!   neighbour or a wall stays free: only the part of the step towards it is limited.
//!   Each limit is a half-plane of steps holding the zero step, so standing still always
//!   satisfies them all; the step kept is the wanted one projected onto the half-planes
//!   it leaves, in a fixed order, and shortened if some limit is still broken after a few
//!   rounds.
//! - **A foot's landing** ([`clear_foot`]): the foot's span on the floor (heel to toe tip,
//!   with its solid's radius round it) is moved out of the other bodies and the
//!   obstacles before it lands, by at most [`LANDING_SHIFT`]. The capsule holds the feet
//!   where they stand, but a swinging foot goes where its landing was planned, ahead of
//!   the body, under where the body was headed before its step was limited.
//! - **A foot in the air** ([`foot_may_move`]) closes on a body by at most half the gap
//!   and on an obstacle by the gap, like the body's step.
//!
//! Pure functions of the previous tick's crowd: bit-identical with any thread count. What
//! the capsule does not hold and moves within a tick (a hand hanging past an obstacle at a
//! corner, an arm reaching out, a body turning on the spot) is left to the margins, the
//! reach's detours and avoidance; a knee bending forwards towards an obstacle, to the
//! walk (`actions/src/walk/knees.rs`).

use crate::footprint::{nearest_on_segment, Footprint};
use smallvec::SmallVec;
use troupe_body::glam::DVec2;

/// Gap (m) the step keeps between two bodies' capsules, and between a capsule and an
/// obstacle: what a body's limbs move within a tick beyond the capsule the previous tick
/// left (a foot swinging out to land, a knee coming forwards as the leg swings, a foot
/// cutting the corner it walks round), and the capsule does not hold.
pub const BODY_MARGIN: f64 = 0.02;
/// See [`BODY_MARGIN`].
pub const OBSTACLE_MARGIN: f64 = 0.02;

/// How much further (m) a foot keeps from an obstacle, landing or in the air, than its
/// own solid needs: the leg above it leans out towards the landing, and the knee of a
/// foot lifted high comes out over it.
pub const LEG_CLEARANCE: f64 = 0.08;

/// Farthest (m) a landing is moved to clear what is round it: further, the foot would land
/// out of the legs' reach, and the walker steps in place instead.
pub const LANDING_SHIFT: f64 = 0.15;

/// Rounds of projection (of a step onto its limits, of a foot out of what it touches)
/// before giving up on the nearest answer.
const ROUNDS: usize = 4;

/// A foot on the floor as the clearance sees it: the segment under it from the heel to the
/// toe tip (x, z) and how far its solid reaches round that segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootSpan {
    /// The point under the heel.
    pub heel: DVec2,
    /// The point under the toe tip.
    pub toe: DVec2,
    /// How far (m) the foot's solid reaches from the segment.
    pub radius: f64,
}

impl FootSpan {
    /// A circle (centre, radius) that holds the span's solid.
    fn bound(&self) -> (DVec2, f64) {
        let mid = (self.heel + self.toe) / 2.0;
        (mid, (self.toe - self.heel).length() / 2.0 + self.radius)
    }

    /// Points along the span's segment, heel to toe, at most 5 cm apart: a convex
    /// footprint's corner cannot reach further between two of them than a foot's radius
    /// covers.
    fn samples(&self) -> impl Iterator<Item = DVec2> {
        let (heel, along) = (self.heel, self.toe - self.heel);
        let n = (along.length() / 0.05).ceil().max(1.0) as usize;
        (0..=n).map(move |k| heel + along * (k as f64 / n as f64))
    }

    /// The same span moved by `by`.
    pub fn moved(&self, by: DVec2) -> FootSpan {
        FootSpan {
            heel: self.heel + by,
            toe: self.toe + by,
            ..*self
        }
    }
}

/// How far (m) above an obstacle a hand passes over it: lower, the hand counts against it.
pub const HAND_OVER: f64 = 0.05;

/// How far a part of a body on the floor reaches along the line its capsule lies on: from
/// `back` to `front` (m along the capsule's axis from its [`Body::origin`]) with
/// `radius` round that.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// Where the part's segment starts (m along the axis from the origin).
    pub back: f64,
    /// Where it ends.
    pub front: f64,
    /// How far (m) the part reaches round its segment.
    pub radius: f64,
}

impl Reach {
    /// The reach that holds both this one and `other`.
    fn with(self, other: Reach) -> Reach {
        Reach {
            back: self.back.min(other.back),
            front: self.front.max(other.front),
            radius: self.radius.max(other.radius),
        }
    }
}

/// A hand that makes a body on the floor reach further than its [`Body::bare`] part:
/// out to the side it widens the capsule, out in front (or behind) it lengthens it, as a
/// foot does (a tray carried in front widened the whole capsule by how far it was held
/// out, and two waiters who met in a 1.4 m aisle filled it from wall to wall).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HandReach {
    /// The capsule that holds the bare body and the hand, with what it holds.
    pub reach: Reach,
    /// How low (m above the floor) the hand, and what it holds, reach.
    pub lowest: f64,
    /// Whether the hand holds something.
    pub holds: bool,
    /// How far (m) ahead of the capsule's [`Body::origin`] the body reaches with this
    /// hand, whatever its stride: as far as what the hand holds lengthens it, and its
    /// radius round that (what a walk to someone keeps between them: `walk{ to = ACTOR }`).
    pub ahead: f64,
}

/// A body on the floor as its neighbours' clearance sees it: the segment `centre ±
/// axis·half_length` with `radius` round it (see [`Body`] for what it is made of).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// The middle of the segment (x, z), on the line through the body's root along `axis`.
    pub centre: DVec2,
    /// The unit direction the body faces (x, z).
    pub axis: DVec2,
    /// Half the segment's length (m).
    pub half_length: f64,
    /// How far (m) the body reaches round the segment, its hands included.
    pub radius: f64,
}

impl Capsule {
    /// The segment `centre ± axis·half_length` with `radius` round it.
    pub fn new(centre: DVec2, axis: DVec2, half_length: f64, radius: f64) -> Capsule {
        Capsule {
            centre,
            axis,
            half_length,
            radius,
        }
    }

    /// The same capsule moved by `by` (x, z).
    pub fn moved(&self, by: DVec2) -> Capsule {
        Capsule {
            centre: self.centre + by,
            ..*self
        }
    }

    /// A circle (centre, radius) that holds the capsule.
    fn bound(&self) -> (DVec2, f64) {
        (self.centre, self.half_length + self.radius)
    }

    /// Distance (m) from `p` to the segment (not to the surface round it).
    pub fn distance(&self, p: DVec2) -> f64 {
        let (a, b) = self.ends();
        (p - nearest_on_segment(p, a, b)).length()
    }

    /// The segment's two ends.
    fn ends(&self) -> (DVec2, DVec2) {
        let half = self.axis * self.half_length;
        (self.centre - half, self.centre + half)
    }

    /// The gap (m) between this body and `other` (negative where they overlap).
    pub fn gap(&self, other: &Capsule) -> f64 {
        let (mine, theirs) = self.nearest_to(other);
        (mine - theirs).length() - self.radius - other.radius
    }

    /// The nearest points of this capsule's segment and `other`'s (on this, on `other`).
    fn nearest_to(&self, other: &Capsule) -> (DVec2, DVec2) {
        nearest_between(self.ends(), other.ends())
    }
}

/// A body on the floor as its own step sees it: its [`Capsule`], and what the capsule is
/// made of, the bare body and each hand's reach along its line, which the step measures
/// against obstacles of each height. Its neighbours copy only the capsule, every tick:
/// this whole, copied, cost the crowd of `troupe bench` about 9 % of its speed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Body {
    /// The capsule that holds it all.
    pub shape: Capsule,
    /// The point on the segment's line from which [`Body::bare`] and the hands' reaches
    /// are measured: the middle of the bare body's segment.
    pub origin: DVec2,
    /// How far it reaches without its hands: the disc and the feet.
    pub bare: Reach,
    /// The hands that make it reach further (see [`Body::against`]).
    pub hands: [Option<HandReach>; 2],
}

impl std::ops::Deref for Body {
    type Target = Capsule;

    fn deref(&self) -> &Capsule {
        &self.shape
    }
}

impl Body {
    /// The segment `centre ± axis·half_length` with `radius` round it, and no hands.
    pub fn new(centre: DVec2, axis: DVec2, half_length: f64, radius: f64) -> Body {
        Body {
            shape: Capsule::new(centre, axis, half_length, radius),
            origin: centre,
            bare: Reach {
                back: -half_length,
                front: half_length,
                radius,
            },
            hands: [None; 2],
        }
    }

    /// The body of `radius` whose root stands at `root` facing `axis` (a unit vector; zero
    /// for no facing) with its `feet` on the floor: its disc, stretched along `axis` by
    /// `stride` either way (where a walker's legs swing) and further as far as it takes to
    /// hold each foot (with the foot's radius) that lies within the disc's width. A foot
    /// planted wider than that (a sidestep's wide stance) widens the capsule instead.
    pub fn around(root: DVec2, axis: DVec2, radius: f64, stride: f64, feet: &[FootSpan]) -> Body {
        let (mut back, mut front) = if axis == DVec2::ZERO {
            (0.0, 0.0)
        } else {
            (-stride, stride)
        };
        // A foot wider than the disc widens it.
        let mut wide = radius;
        if axis != DVec2::ZERO {
            let side = axis.perp();
            for foot in feet {
                for p in [foot.heel, foot.toe] {
                    let along = (p - root).dot(axis);
                    let across = (p - root).dot(side).abs();
                    let inner = radius - foot.radius;
                    let room = (inner * inner - across * across).max(0.0).sqrt();
                    front = front.max(along - room);
                    back = back.min(along + room);
                    wide = wide.max(across + foot.radius);
                }
            }
        }
        Body::new(
            root + axis * (front + back) / 2.0,
            axis,
            (front - back) / 2.0,
            wide,
        )
    }

    /// What it takes this body to reach what a hand `held` and its arm's `joints` as
    /// well, the hand reaching as low as `lowest`: each held point `(point, radius)` with
    /// its radius round it (negative: a point that may lie that far outside), each joint
    /// `(point, disc, at_rest)` allowed as far out from the segment as it stands at rest
    /// within a disc of radius `disc`. The held points first: the bare body's capsule
    /// widened by as far as one lies out to the side past it, then lengthened to hold
    /// those in front of it or behind (a tray carried in front lengthens the body, and no
    /// more widens it by how far it is held out). Then the joints widen it by as far as
    /// each lies out from that segment, as an arm swinging out does.
    pub fn reaching(
        &self,
        held: impl Iterator<Item = (DVec2, f64)> + Clone,
        joints: impl Iterator<Item = (DVec2, f64, f64)>,
        lowest: f64,
    ) -> HandReach {
        let place = |p: DVec2| {
            let from = p - self.origin;
            if self.axis == DVec2::ZERO {
                (0.0, from.length())
            } else {
                (from.dot(self.axis), from.dot(self.axis.perp()).abs())
            }
        };
        let wide = held
            .clone()
            .map(|(p, radius)| place(p).1 + radius)
            .fold(self.bare.radius, f64::max);
        // The front as what is held takes it, from the origin: the stride left out.
        let mut ahead = 0.0_f64;
        let holds = held.clone().next().is_some();
        let held = held.fold(
            Reach {
                radius: wide,
                ..self.bare
            },
            |reach, (p, radius)| {
                let (along, across) = place(p);
                let inner = wide - radius;
                let room = (inner * inner - across * across).max(0.0).sqrt();
                ahead = ahead.max(along - room);
                Reach {
                    back: reach.back.min(along + room),
                    front: reach.front.max(along - room),
                    ..reach
                }
            },
        );
        let (a, b) = (
            self.origin + self.axis * held.back,
            self.origin + self.axis * held.front,
        );
        let reach = joints.fold(held, |reach, (p, disc, at_rest)| {
            let out = disc + (p - nearest_on_segment(p, a, b)).length() - at_rest;
            Reach {
                radius: reach.radius.max(out),
                ..reach
            }
        });
        HandReach {
            reach,
            lowest,
            holds,
            ahead: ahead + reach.radius,
        }
    }

    /// Its hand `i` (0 or 1) reaches as `hand` says: a hand further out than the body
    /// reaches widens or lengthens it.
    pub fn add_hand(&mut self, i: usize, hand: HandReach) {
        self.hands[i] = Some(hand);
        let whole = self
            .hands
            .iter()
            .flatten()
            .fold(self.bare, |r, h| r.with(h.reach));
        let (centre, half_length, radius) = self.placed(whole);
        self.shape = Capsule {
            centre,
            half_length,
            radius,
            ..self.shape
        };
    }

    /// Where reach `r` lies: its segment's middle, half its length and its radius.
    fn placed(&self, r: Reach) -> (DVec2, f64, f64) {
        let middle = self.origin + self.axis * (r.back + r.front) / 2.0;
        (middle, (r.front - r.back) / 2.0, r.radius)
    }

    /// The body as it reaches towards an obstacle `top` metres high (its segment's ends
    /// and its radius): all of it, but a hand carried [`HAND_OVER`] or more above the
    /// obstacle passes over it (a cup carried to a table).
    pub fn against(&self, top: f64) -> ((DVec2, DVec2), f64) {
        let reach = self
            .hands
            .iter()
            .flatten()
            .filter(|h| h.lowest < top + HAND_OVER)
            .fold(self.bare, |r, h| r.with(h.reach));
        let (a, b) = (reach.back, reach.front);
        (
            (self.origin + self.axis * a, self.origin + self.axis * b),
            reach.radius,
        )
    }

    /// Whether a hand of the body holds something.
    #[inline]
    pub fn carries(&self) -> bool {
        self.hands.iter().flatten().any(|h| h.holds)
    }

    /// How far (m) ahead of its middle ([`Body::origin`]) the body reaches with its
    /// hands, whatever its stride (see [`HandReach::ahead`]); zero without hands.
    pub fn hands_ahead(&self) -> f64 {
        self.hands
            .iter()
            .flatten()
            .fold(0.0, |far, h| far.max(h.ahead))
    }

    /// The same body moved by `by` (x, z).
    pub fn moved(&self, by: DVec2) -> Body {
        Body {
            shape: self.shape.moved(by),
            origin: self.origin + by,
            ..*self
        }
    }

    /// The disc round the middle of the bare body's segment, as wide as the body reaches
    /// round its segment: what a step must not close on an obstacle whatever the
    /// segment's length (see [`limit_step`]).
    fn middle_disc(&self) -> Body {
        let disc = |r: Reach| Reach {
            back: 0.0,
            front: 0.0,
            ..r
        };
        Body {
            shape: Capsule {
                centre: self.origin,
                half_length: 0.0,
                ..self.shape
            },
            bare: disc(self.bare),
            hands: self.hands.map(|h| {
                h.map(|h| HandReach {
                    reach: disc(h.reach),
                    ..h
                })
            }),
            ..*self
        }
    }
}

/// A foot's span as it keeps from obstacles (see [`LEG_CLEARANCE`]).
fn with_leg(span: &FootSpan) -> FootSpan {
    FootSpan {
        radius: span.radius + LEG_CLEARANCE,
        ..*span
    }
}

/// A lower bound (m) on the gap between two solids held by circles `a` and `b` (centre,
/// radius): cheap, to leave out what is far before the exact distance.
#[inline]
pub fn gap_bound(a: (DVec2, f64), b: (DVec2, f64)) -> f64 {
    (a.0 - b.0).length() - a.1 - b.1
}

/// A lower bound (m) on the gap between a solid held by circle `a` and footprint `f`.
fn footprint_gap_bound(a: (DVec2, f64), f: &Footprint) -> f64 {
    f.distance(a.0) - a.1
}

/// What is round a walker this tick, as the previous tick left it: the other bodies and
/// the obstacles near.
#[derive(Clone, Debug, Default)]
pub struct Surroundings<'a> {
    /// Other walkers' and standing actors' bodies.
    pub bodies: Vec<Capsule>,
    /// Each body's velocity (x, z) over the previous tick, as `bodies` lists them (none
    /// listed: all standing).
    pub velocities: Vec<DVec2>,
    /// Their feet (see `Crowd::soles`), which a foot in the air keeps from as from a
    /// body.
    pub feet: Vec<FootSpan>,
    /// The obstacles near (the usual few on the stack, as each tick gathers them).
    pub obstacles: SmallVec<[&'a Footprint; 8]>,
    /// The circle round each of `obstacles` (centre, radius: `Footprint::bounding_circle`),
    /// in their order, or none: with them, obstacles too far to matter are passed over
    /// without measuring their footprints (see [`Surroundings::circle_gap`]).
    pub bounds: Vec<(DVec2, f64)>,
}

impl<'a> Surroundings<'a> {
    /// Where the bodies walking away from `from` will be `seconds` from now: each moved on
    /// by half of what its velocity covers in that time, which it covers even if it stops
    /// meanwhile, evenly over 0.8 s or more (a walk's stop), as long as `seconds` is at
    /// most that; the others where they stand. `None` when no body walks away. A foot
    /// landing behind someone walking ahead lands where that one has gone from (see
    /// [`clear_foot`]), not where it stands now. (Not capped at 0.8 s, which the strikes
    /// of slow walks pass: capped, the plaza's test layout put feet 4.4 cm into one
    /// another, against none; docs/navigation.md, "Limits".)
    pub fn ahead(&self, from: DVec2, seconds: f64) -> Option<Surroundings<'a>> {
        let velocity = |i: usize| self.velocities.get(i).copied().unwrap_or_default();
        let leaving = |i: usize, body: &Capsule| velocity(i).dot(body.centre - from) > 0.0;
        if seconds <= 0.0 || !self.bodies.iter().enumerate().any(|(i, b)| leaving(i, b)) {
            return None;
        }
        let bodies = self.bodies.iter().enumerate().map(|(i, body)| {
            if leaving(i, body) {
                body.moved(velocity(i) * (0.5 * seconds))
            } else {
                *body
            }
        });
        Some(Surroundings {
            bodies: bodies.collect(),
            velocities: self.velocities.clone(),
            feet: self.feet.clone(),
            obstacles: self.obstacles.clone(),
            bounds: self.bounds.clone(),
        })
    }

    /// A lower bound (m) on the gap between the circle `a` (centre, radius) and obstacle
    /// `k`, from the circle round the obstacle (`bounds`), or −∞ without one. It costs a
    /// square root, a fraction of the footprint's own distance, and is never above that
    /// distance, so a test that it passes (`> x`, `>= x`) needs no measuring: in a crowd
    /// among furniture most of the obstacles near are passed over so.
    #[inline]
    pub fn circle_gap(&self, k: usize, a: (DVec2, f64)) -> f64 {
        match self.bounds.get(k) {
            // The slack keeps the two measures' rounding from ever disagreeing.
            Some(&b) if self.bounds.len() == self.obstacles.len() => gap_bound(a, b) - 1e-9,
            _ => f64::NEG_INFINITY,
        }
    }

    /// The circle round obstacle `k` (centre, radius): `bounds`', or found anew without
    /// them.
    pub fn obstacle_bound(&self, k: usize) -> (DVec2, f64) {
        match self.bounds.get(k) {
            Some(&b) if self.bounds.len() == self.obstacles.len() => b,
            _ => self.obstacles[k].bounding_circle(),
        }
    }
}

/// A limit on the step `s`: `s · normal >= -allowed`, `allowed >= 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Limit {
    /// Unit vector from the other body (or the obstacle's nearest point) to the walker.
    normal: DVec2,
    /// How far (m) the step may go against `normal`.
    allowed: f64,
}

impl Limit {
    /// How far (m) step `s` goes past the limit (negative: within it).
    fn excess(&self, s: DVec2) -> f64 {
        -s.dot(self.normal) - self.allowed
    }

    /// The limit of a body at `from` whose disc is `gap` clear of something in direction
    /// `-apart` (from it to the body, not normalised), of which the step may close
    /// `share`; `None` when a step of `reach` cannot close it, or `apart` is zero.
    fn of(apart: DVec2, gap: f64, share: f64, reach: f64) -> Option<Limit> {
        let normal = apart.try_normalize()?;
        (gap * share <= reach).then(|| Limit {
            normal,
            allowed: (gap * share).max(0.0),
        })
    }
}

/// The part of `step` (x, z) that body `me` (where it stood on the previous tick) may take
/// this tick: `step` itself when it closes on nothing, else the nearest step that closes
/// at most half the gap to each neighbour's body and the whole gap to each obstacle (see
/// the module docs).
pub fn limit_step(me: &Body, step: DVec2, around: &Surroundings) -> DVec2 {
    let reach = step.length();
    if reach == 0.0 {
        return step;
    }
    // On the stack: a list on the heap cost each tick's step an allocation.
    let mut limits: SmallVec<[Limit; 16]> = SmallVec::new();
    for other in &around.bodies {
        // A step closes at most its own length of half the gap.
        if gap_bound(me.bound(), other.bound()) > 2.0 * reach + BODY_MARGIN {
            continue;
        }
        let (mine, theirs) = me.nearest_to(other);
        let apart = mine - theirs;
        let gap = apart.length() - me.radius - other.radius - BODY_MARGIN;
        // Segments that cross (bodies placed into each other): apart along their centres.
        let apart = if apart.length_squared() > 0.0 {
            apart
        } else {
            me.centre - other.centre
        };
        limits.extend(Limit::of(apart, gap, 0.5, reach));
    }
    // Against obstacles, the capsule and the disc round its middle: the capsule's length
    // changes with the stride and turns with the body, so one already touching could
    // slide its end along an obstacle while its middle closed on it.
    for body in [me, &me.middle_disc()] {
        for (k, f) in around.obstacles.iter().enumerate() {
            let far = reach + OBSTACLE_MARGIN;
            if around.circle_gap(k, body.bound()) > far
                || footprint_gap_bound(body.bound(), f) > far
            {
                continue;
            }
            let ((a, b), radius) = body.against(f.top);
            let span = FootSpan {
                heel: a,
                toe: b,
                radius,
            };
            let Some((point, nearest)) = nearest_to_footprint(f, &span) else {
                continue;
            };
            // A convex footprint lies wholly behind the tangent at its nearest point: a
            // body whose nearest point stays `radius` in front of the tangent stays clear.
            let apart = point - nearest;
            let gap = apart.length() - radius - OBSTACLE_MARGIN;
            limits.extend(Limit::of(apart, gap, 1.0, reach));
        }
    }
    within(step, &limits)
}

/// The least gap (m) between body `me` and the bodies and obstacles `around` (negative
/// when they overlap), or `within` if none is nearer than that.
pub fn nearest_gap(me: &Body, around: &Surroundings, within: f64) -> f64 {
    let (bodies, obstacles) = nearest_gaps(me, around, within);
    bodies.min(obstacles)
}

/// The least gaps (m) between body `me` and the bodies `around`, and between it and the
/// obstacles `around` (negative when they overlap), each `within` if none is nearer.
pub fn nearest_gaps(me: &Body, around: &Surroundings, within: f64) -> (f64, f64) {
    let bodies = around
        .bodies
        .iter()
        .filter(|other| gap_bound(me.bound(), other.bound()) < within)
        .map(|other| {
            let (mine, theirs) = me.nearest_to(other);
            (mine - theirs).length() - me.radius - other.radius
        });
    let obstacles = (around.obstacles.iter().enumerate())
        .filter(|&(k, f)| {
            around.circle_gap(k, me.bound()) < within && footprint_gap_bound(me.bound(), f) < within
        })
        .map(|(_, f)| {
            let ((heel, toe), radius) = me.against(f.top);
            let span = FootSpan { heel, toe, radius };
            nearest_to_footprint(f, &span).map_or(-radius, |(p, q)| (p - q).length() - radius)
        });
    (
        bodies.fold(within, f64::min),
        obstacles.fold(within, f64::min),
    )
}

/// Whether a foot in the air may move from span `from` to span `to` this tick: it closes
/// on no body or foot `around` by more than half the gap between them (the other may
/// close the other half) and on no obstacle by more than the gap, and goes no deeper into
/// any. The feet count besides their bodies' capsules: a foot already inside a capsule
/// widened by a foot planted wide (the capsule is then mostly floor) could go on along
/// it, no deeper, into that foot.
pub fn foot_may_move(from: &FootSpan, to: &FootSpan, around: &Surroundings) -> bool {
    let gap = |span: &FootSpan, (ends, radius): ((DVec2, DVec2), f64)| {
        let (mine, theirs) = nearest_between((span.heel, span.toe), ends);
        (mine - theirs).length() - span.radius - radius
    };
    // A move of at most `moved` closes at most that much: a body at least twice as far
    // is not closed on by more than half its gap.
    let moved = (to.heel - from.heel)
        .length()
        .max((to.toe - from.toe).length());
    let closes_at_most_half = |bound: (DVec2, f64), other: ((DVec2, DVec2), f64)| {
        if gap_bound(from.bound(), bound) >= 2.0 * moved {
            return true;
        }
        let (before, after) = (gap(from, other), gap(to, other));
        after >= before || before - after <= (before / 2.0).max(0.0)
    };
    let bodies_ok = around
        .bodies
        .iter()
        .all(|body| closes_at_most_half(body.bound(), (body.ends(), body.radius)));
    let feet_ok = around
        .feet
        .iter()
        .all(|foot| closes_at_most_half(foot.bound(), ((foot.heel, foot.toe), foot.radius)));
    let depth = |span: &FootSpan, f: &Footprint| {
        let span = with_leg(span);
        footprint_overlap(f, &span).map_or(f64::NEG_INFINITY, |(_, d)| d + span.radius)
    };
    let obstacles_ok = around.obstacles.iter().enumerate().all(|(k, f)| {
        if around.circle_gap(k, to.bound()) > LEG_CLEARANCE
            || footprint_gap_bound(to.bound(), f) > LEG_CLEARANCE
        {
            return true;
        }
        let after = depth(to, f);
        after <= 0.0 || after <= depth(from, f)
    });
    bodies_ok && feet_ok && obstacles_ok
}

/// How far to move foot `foot` (about to land) so that it is clear of the bodies and the
/// obstacles `around`: zero when it already is; `None` when no such move of at most
/// [`LANDING_SHIFT`] was found (a foot pinched between a body and an obstacle, or among
/// bodies). Each one the foot reaches into pushes it
/// straight out by the overlap, in a fixed order (the bodies, then the obstacles, whose
/// push comes last: a foot is never moved into furniture), for a few rounds.
pub fn clear_foot(foot: FootSpan, around: &Surroundings) -> Option<DVec2> {
    let mut by = DVec2::ZERO;
    for _ in 0..ROUNDS {
        let mut moved = false;
        for body in &around.bodies {
            let span = foot.moved(by);
            if gap_bound(span.bound(), body.bound()) > 0.0 {
                continue;
            }
            let (mine, theirs) = nearest_between((span.heel, span.toe), body.ends());
            let apart = mine - theirs;
            let overlap = span.radius + body.radius - apart.length();
            if overlap > 0.0 {
                // A foot right across the other's segment: out sideways from its middle.
                let out = apart
                    .try_normalize()
                    .or_else(|| (mine - body.centre).try_normalize())
                    .unwrap_or(body.axis.perp());
                by += out * overlap;
                moved = true;
            }
        }
        for (k, f) in around.obstacles.iter().enumerate() {
            let span = with_leg(&foot.moved(by));
            if around.circle_gap(k, span.bound()) > 0.0
                || footprint_gap_bound(span.bound(), f) > 0.0
            {
                continue;
            }
            if let Some((out, depth)) = footprint_overlap(f, &span) {
                by += out * (depth + span.radius);
                moved = true;
            }
        }
        if by.length() > LANDING_SHIFT {
            return None;
        }
        if !moved {
            return Some(by);
        }
    }
    // Still moving after the last round: clear only if nothing is touched now.
    let span = foot.moved(by);
    let touches_body = around.bodies.iter().any(|body| {
        let (mine, theirs) = nearest_between((span.heel, span.toe), body.ends());
        (mine - theirs).length() < span.radius + body.radius - 1e-9
    });
    let touches_obstacle = around.obstacles.iter().any(|f| {
        let span = with_leg(&span);
        footprint_overlap(f, &span).is_some_and(|(_, d)| d + span.radius > 1e-9)
    });
    (!touches_body && !touches_obstacle).then_some(by)
}

/// The point of span `span`'s segment nearest footprint `f` (of its samples) and the
/// footprint's point nearest it; `None` if a sample is inside the footprint (no outward
/// way to tell) or the footprint has no outline.
fn nearest_to_footprint(f: &Footprint, span: &FootSpan) -> Option<(DVec2, DVec2)> {
    let mut best: Option<(DVec2, DVec2)> = None;
    for p in span.samples() {
        if f.contains(p) {
            return None;
        }
        let nearest = f.nearest_point(p)?;
        if best.is_none_or(|(q, n)| (p - nearest).length() < (q - n).length()) {
            best = Some((p, nearest));
        }
    }
    best
}

/// Whether foot span `span`'s segment comes within its radius of footprint `f`: the
/// outward direction and how far (m) the segment is inside the footprint's border
/// (negative: outside, by that much), for the segment point deepest in or nearest it;
/// `None` when it is clear.
fn footprint_overlap(f: &Footprint, span: &FootSpan) -> Option<(DVec2, f64)> {
    let mut worst: Option<(DVec2, f64)> = None;
    for p in span.samples() {
        let Some(nearest) = f.nearest_point(p) else {
            continue;
        };
        let inside = f.contains(p);
        let (out, depth) = if inside {
            (nearest - p, (nearest - p).length())
        } else {
            (p - nearest, -(p - nearest).length())
        };
        if depth + span.radius <= 0.0 || worst.is_some_and(|(_, d)| d >= depth) {
            continue;
        }
        // On the border itself: out from the footprint's centre.
        let out = out
            .try_normalize()
            .or_else(|| (nearest - f.centre()).try_normalize())
            .unwrap_or(DVec2::X);
        worst = Some((out, depth));
    }
    worst
}

/// The nearest points of segments `a` and `b` (on `a`, on `b`); for segments that cross,
/// their crossing point twice.
fn nearest_between(a: (DVec2, DVec2), b: (DVec2, DVec2)) -> (DVec2, DVec2) {
    let (da, db) = (a.1 - a.0, b.1 - b.0);
    let denom = da.perp_dot(db);
    if denom != 0.0 {
        let s = (b.0 - a.0).perp_dot(db) / denom;
        let t = (b.0 - a.0).perp_dot(da) / denom;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            let at = a.0 + da * s;
            return (at, at);
        }
    }
    [
        (a.0, nearest_on_segment(a.0, b.0, b.1)),
        (a.1, nearest_on_segment(a.1, b.0, b.1)),
        (nearest_on_segment(b.0, a.0, a.1), b.0),
        (nearest_on_segment(b.1, a.0, a.1), b.1),
    ]
    .into_iter()
    .min_by(|x, y| (x.0 - x.1).length().total_cmp(&(y.0 - y.1).length()))
    .unwrap_or((a.0, b.0))
}

/// The step nearest `wanted` (by projections in a fixed order) within every limit, each of
/// which holds the zero step.
fn within(wanted: DVec2, limits: &[Limit]) -> DVec2 {
    if limits.iter().all(|l| l.excess(wanted) <= 0.0) {
        return wanted;
    }
    let mut step = wanted;
    for _ in 0..ROUNDS {
        let mut moved = false;
        for l in limits {
            let excess = l.excess(step);
            if excess > 0.0 {
                step += l.normal * excess;
                moved = true;
            }
        }
        if !moved {
            return step;
        }
    }
    // Still past some limit (two neighbours pinching from both sides): shorten the step
    // until it is within all; every limit holds the zero step, so this ends there at
    // worst.
    let scale = limits
        .iter()
        .filter(|l| l.excess(step) > 0.0)
        .map(|l| l.allowed / -step.dot(l.normal))
        .fold(1.0f64, f64::min)
        .max(0.0);
    step * scale
}

#[cfg(test)]
mod tests {
    use super::*;
    use smallvec::smallvec;

    /// A body of radius 0.3 at (x, z) facing +z, a stride of `half` either way.
    fn body(x: f64, z: f64, half: f64) -> Body {
        Body::new(DVec2::new(x, z), DVec2::Y, half, 0.3)
    }

    fn bodies(list: &[Body]) -> Surroundings<'static> {
        Surroundings {
            bodies: list.iter().map(|b| b.shape).collect(),
            ..Surroundings::default()
        }
    }

    fn square(name: &str, lo: (f64, f64), hi: (f64, f64)) -> Footprint {
        Footprint::hull(
            name,
            &[
                DVec2::new(lo.0, lo.1),
                DVec2::new(hi.0, lo.1),
                DVec2::new(hi.0, hi.1),
                DVec2::new(lo.0, hi.1),
            ],
        )
    }

    #[test]
    fn a_step_that_closes_on_nothing_is_kept_bit_for_bit() {
        let step = DVec2::new(0.013, 0.004);
        let around = bodies(&[body(2.0, 0.0, 0.2)]);
        assert_eq!(limit_step(&body(0.0, 0.0, 0.2), step, &around), step);
    }

    #[test]
    fn the_circles_round_the_obstacles_change_no_answer() {
        // Boxes and a body with a foot scattered over a few metres, 300 times: every
        // clearance answer bit for bit the same with the circles round the obstacles as
        // without them, and the circles do pass some obstacles over.
        let mut next = troupe_body::math::draws(7);
        let (mut passed_over, mut measured) = (0, 0);
        for _ in 0..300 {
            let obstacles: Vec<Footprint> = (0..6)
                .map(|_| {
                    let (x, z) = (next() * 4.0 - 2.0, next() * 4.0 - 2.0);
                    let hi = (x + 0.1 + next() * 0.8, z + 0.1 + next() * 0.8);
                    square("box", (x, z), hi)
                })
                .collect();
            let plain = Surroundings {
                obstacles: obstacles.iter().collect(),
                ..Surroundings::default()
            };
            let circled = Surroundings {
                bounds: obstacles.iter().map(Footprint::bounding_circle).collect(),
                ..plain.clone()
            };
            let me = body(next() * 3.0 - 1.5, next() * 3.0 - 1.5, next() * 0.3);
            for k in 0..obstacles.len() {
                if circled.circle_gap(k, me.bound()) > 0.3 {
                    passed_over += 1;
                } else {
                    measured += 1;
                }
            }
            let step = DVec2::new(next() - 0.5, next() - 0.5) * 0.1;
            let heel = me.origin + DVec2::new(next() - 0.5, next() - 0.5);
            let foot = FootSpan {
                heel,
                toe: heel + DVec2::new(0.0, 0.25),
                radius: 0.05,
            };
            let to = foot.moved(step);
            let ask = |around: &Surroundings| {
                (
                    limit_step(&me, step, around),
                    nearest_gaps(&me, around, 0.3),
                    foot_may_move(&foot, &to, around),
                    clear_foot(foot, around),
                )
            };
            assert_eq!(ask(&plain), ask(&circled));
        }
        assert!(
            passed_over > 100 && measured > 100,
            "{passed_over} {measured}"
        );
    }

    #[test]
    fn two_walkers_side_by_side_each_close_half_the_gap_and_never_overlap() {
        // Capsules 0.04 m apart side by side (0.02 m past the margin), each stepping
        // 0.013 m at the other.
        let (a0, b0) = (body(0.0, 0.0, 0.2), body(0.64, 0.0, 0.2));
        let a = limit_step(&a0, DVec2::new(0.013, 0.0), &bodies(&[b0]));
        let b = limit_step(&b0, DVec2::new(-0.013, 0.0), &bodies(&[a0]));
        assert!(
            (a.x - 0.01).abs() < 1e-12 && (b.x + 0.01).abs() < 1e-12,
            "{a} {b}"
        );
        let after = (b0.centre + b - a0.centre - a).length();
        assert!(after >= 0.6 + BODY_MARGIN - 1e-12, "{after}");
    }

    #[test]
    fn one_behind_another_keeps_the_strides_apart_too() {
        // Facing the same way, 1.0 m apart: the strides (0.2 m each way) leave a gap of
        // 1.0 - 0.4 - 0.6 = 0 between the capsules: no step forwards.
        let (me, ahead) = (body(0.0, 0.0, 0.2), body(0.0, 1.0, 0.2));
        let s = limit_step(&me, DVec2::new(0.0, 0.013), &bodies(&[ahead]));
        assert!(s.y.abs() < 1e-12, "{s}");
    }

    #[test]
    fn sliding_past_a_neighbour_stays_free_and_only_the_closing_part_is_cut() {
        let around = bodies(&[body(0.6, 0.0, 0.2)]);
        let me = body(0.0, 0.0, 0.2);
        let s = limit_step(&me, DVec2::new(0.005, 0.012), &around);
        assert_eq!(s, DVec2::new(0.0, 0.012));
        let away = DVec2::new(-0.01, 0.0);
        assert_eq!(limit_step(&me, away, &around), away);
    }

    #[test]
    fn pinched_between_two_neighbours_the_step_shrinks_until_it_fits() {
        let around = bodies(&[body(-0.3, 0.52, 0.0), body(0.3, 0.52, 0.0)]);
        let me = body(0.0, 0.0, 0.0);
        let s = limit_step(&me, DVec2::new(0.0, 0.013), &around);
        for other in &around.bodies {
            let n = (me.centre - other.centre).normalize();
            let gap = (me.centre - other.centre).length() - 0.6;
            assert!(-s.dot(n) <= (gap / 2.0).max(0.0) + 1e-12, "{s}");
        }
    }

    #[test]
    fn a_capsule_stretching_at_a_corner_does_not_carry_its_middle_in() {
        // A walker heads past a planter's corner, its stride growing and its body turning
        // towards the corner each tick, and keeps asking to go straight at it: its capsule
        // soon touches the corner with its front end and may then only slide, but the disc
        // round its middle still keeps the radius and the margin.
        let planter = square("planter", (0.5, 0.4), (2.0, 2.0));
        let around = Surroundings {
            obstacles: smallvec![&planter],
            ..Surroundings::default()
        };
        let mut root = DVec2::ZERO;
        for tick in 0..120 {
            let turn = 0.01 * tick as f64;
            let me = Body::new(
                root,
                DVec2::new(turn.cos(), turn.sin()),
                (0.05 + 0.01 * tick as f64).min(0.5),
                0.3,
            );
            let towards = (DVec2::new(0.5, 0.4) - root).normalize() * 0.013;
            root += limit_step(&me, towards, &around);
            assert!(
                planter.distance(root) >= 0.3 + OBSTACLE_MARGIN - 1e-9,
                "tick {tick}: the middle {root} came {} from the planter",
                planter.distance(root)
            );
        }
    }

    #[test]
    fn a_hand_carried_above_an_obstacle_passes_over_it() {
        // A body facing a table with a hand carried out in front, what it holds reaching
        // 0.7 m from the body's middle and as low as 0.9 m; the table's edge 0.2 m in
        // front of the disc (past the margin).
        let mut me = Body::new(DVec2::ZERO, DVec2::X, 0.0, 0.3);
        let held = std::iter::once((DVec2::new(0.7, 0.0), 0.0));
        let hand = me.reaching(held, std::iter::empty(), 0.9);
        let r = hand.reach;
        assert!((r.front - 0.4).abs() < 1e-12 && (r.back, r.radius) == (0.0, 0.3));
        assert!((hand.ahead - 0.7).abs() < 1e-12);
        me.add_hand(1, hand);
        assert!((me.half_length - 0.2).abs() < 1e-12 && me.bare.radius == 0.3);
        let edge = (0.5 + OBSTACLE_MARGIN, -1.0);
        let step = DVec2::new(0.1, 0.0);
        for (top, passes) in [(0.75, true), (0.85, true), (0.86, false), (0.95, false)] {
            let table = square("table", edge, (1.5, 1.0)).with_top(top);
            let around = Surroundings {
                obstacles: smallvec![&table],
                ..Surroundings::default()
            };
            let s = limit_step(&me, step, &around);
            // Over a low table the disc closes on it as if the hand were not there; as high
            // as the hand (and 5 cm above it), the hand keeps the body back.
            assert_eq!(s == step, passes, "a table {top} m high: step {s}");
            let gap = nearest_gap(&me, &around, 2.0);
            let expected = if passes { 0.2 } else { -0.2 } + OBSTACLE_MARGIN;
            assert!(
                (gap - expected).abs() < 1e-9,
                "a table {top} m high: gap {gap}"
            );
        }
    }

    #[test]
    fn a_tray_carried_in_front_lengthens_the_body_and_does_not_widen_it() {
        // A tray 0.4 m wide carried in both hands 0.5–0.8 m in front of a body of radius
        // 0.25 facing +z, the wrists beside it, between walls 1.3 m apart: the capsule
        // reaches 0.9 m ahead (its rounded end round the tray's corners), and its sides
        // keep 0.4 m from the walls (a radius of 0.8 round the body filled the aisle from
        // wall to wall and held it for good).
        let mut me = Body::new(DVec2::ZERO, DVec2::Y, 0.0, 0.25);
        let corners = [(-0.2, 0.5), (0.2, 0.5), (0.2, 0.8), (-0.2, 0.8)].map(DVec2::from);
        let held = corners.into_iter().map(|p| (p, 0.0));
        let wrist = std::iter::once((DVec2::new(0.2, 0.5), 0.25, 0.2));
        let hand = me.reaching(held, wrist, 0.8);
        assert!((hand.ahead - 0.9).abs() < 1e-12, "{hand:?}");
        me.add_hand(0, hand);
        assert_eq!(me.radius, 0.25);
        assert!((me.centre.y - 0.325).abs() < 1e-12 && (me.half_length - 0.325).abs() < 1e-12);
        let walls = [
            square("left", (0.65, -3.0), (0.75, 3.0)),
            square("right", (-0.75, -3.0), (-0.65, 3.0)),
        ];
        let around = Surroundings {
            obstacles: walls.iter().collect(),
            ..Surroundings::default()
        };
        assert!((nearest_gap(&me, &around, 2.0) - 0.4).abs() < 1e-12);
        let aside = DVec2::new(0.1, 0.0);
        assert_eq!(limit_step(&me, aside, &around), aside);
        // Held out to one side instead, it widens the body on both.
        let mut me = Body::new(DVec2::ZERO, DVec2::Y, 0.0, 0.25);
        let side = corners.map(|p| DVec2::new(p.y - 0.1, p.x));
        me.add_hand(
            0,
            me.reaching(side.into_iter().map(|p| (p, 0.0)), std::iter::empty(), 0.8),
        );
        assert!((me.radius - 0.7).abs() < 1e-12, "{me:?}");
        assert!(nearest_gap(&me, &around, 2.0) < 0.0);
    }

    #[test]
    fn the_nearest_gaps_to_bodies_and_to_obstacles_are_told_apart() {
        // A body of radius 0.25 with another 0.7 m to its side (the gap 0.2 m) and a wall's
        // face 0.55 m away on the other (0.3 m).
        let me = Body::new(DVec2::ZERO, DVec2::Y, 0.0, 0.25);
        let other = Body::new(DVec2::new(0.7, 0.0), DVec2::Y, 0.0, 0.25);
        let wall = square("wall", (-0.65, -1.0), (-0.55, 1.0));
        let around = Surroundings {
            bodies: vec![other.shape],
            obstacles: smallvec![&wall],
            ..Surroundings::default()
        };
        let (bodies, obstacles) = nearest_gaps(&me, &around, 2.0);
        assert!((bodies - 0.2).abs() < 1e-12, "{bodies}");
        assert!((obstacles - 0.3).abs() < 1e-9, "{obstacles}");
        assert_eq!(nearest_gap(&me, &around, 2.0), bodies);
        // Beyond `within`, each is `within`.
        assert_eq!(nearest_gaps(&me, &around, 0.1), (0.1, 0.1));
    }

    #[test]
    fn an_obstacle_is_closed_on_by_the_whole_gap_and_no_further() {
        // A wall 0.01 m past the margin.
        let wall = square("wall", (0.31 + OBSTACLE_MARGIN, -1.0), (0.5, 1.0));
        let around = Surroundings {
            obstacles: smallvec![&wall],
            ..Surroundings::default()
        };
        let s = limit_step(&body(0.0, 0.0, 0.2), DVec2::new(0.013, 0.01), &around);
        assert!((s.x - 0.01).abs() < 1e-12 && s.y == 0.01, "{s}");
        assert!(wall.distance(s) >= 0.3 + OBSTACLE_MARGIN - 1e-12);
        // Walking at a planter: the stride's front end stops short of it by the radius
        // and the margin.
        let planter = square("planter", (-1.0, 0.52 + OBSTACLE_MARGIN), (1.0, 1.0));
        let around = Surroundings {
            obstacles: smallvec![&planter],
            ..Surroundings::default()
        };
        let s = limit_step(&body(0.0, 0.0, 0.2), DVec2::new(0.0, 0.03), &around);
        assert!((s.y - 0.02).abs() < 1e-12, "{s}");
    }

    #[test]
    fn a_foot_lands_clear_of_an_obstacle() {
        let planter = square("planter", (0.0, 0.0), (1.0, 1.0));
        // A foot pointing at the planter, its toe 1 cm inside.
        let foot = FootSpan {
            heel: DVec2::new(-0.3, 0.5),
            toe: DVec2::new(0.01, 0.5),
            radius: 0.04,
        };
        let around = Surroundings {
            obstacles: smallvec![&planter],
            ..Surroundings::default()
        };
        let by = clear_foot(foot, &around).unwrap();
        let landed = foot.moved(by);
        assert!(
            planter.distance(landed.toe) >= 0.04 + LEG_CLEARANCE - 1e-9,
            "{by}"
        );
        assert!(by.y.abs() < 1e-12 && by.x < 0.0, "{by}");
        // Already clear: not moved.
        assert_eq!(
            clear_foot(foot.moved(DVec2::new(-0.3, 0.0)), &around),
            Some(DVec2::ZERO)
        );
        // Pinched between the planter and a body beside it: no landing there.
        let body = Capsule::new(DVec2::new(-0.25, 0.5), DVec2::Y, 0.0, 0.28);
        let around = Surroundings {
            obstacles: smallvec![&planter],
            bodies: vec![body],
            ..Surroundings::default()
        };
        let across = FootSpan {
            heel: DVec2::new(-0.1, 0.4),
            toe: DVec2::new(-0.1, 0.6),
            radius: 0.04,
        };
        assert_eq!(clear_foot(across, &around), None);
    }

    #[test]
    fn a_foot_behind_someone_walking_away_lands_where_that_one_will_have_gone() {
        // A foot landing 1.0 m ahead of its walker, straight into the back of someone
        // 1.3 m ahead walking on at 1.3 m/s, and someone standing beside the way.
        let foot = FootSpan {
            heel: DVec2::new(0.0, 0.9),
            toe: DVec2::new(0.0, 1.15),
            radius: 0.04,
        };
        let ahead = body(0.0, 1.3, 0.2);
        let beside = body(1.0, 1.0, 0.0);
        let around = Surroundings {
            bodies: vec![ahead.shape, beside.shape],
            velocities: vec![DVec2::new(0.0, 1.3), DVec2::ZERO],
            ..Surroundings::default()
        };
        assert_eq!(
            clear_foot(foot, &around),
            None,
            "pinched where they stand now"
        );
        // Striking in 0.6 s: the one ahead has gone on at least 0.39 m; the other stays.
        let then = around.ahead(foot.heel, 0.6).unwrap();
        assert_eq!(then.bodies[0].centre, DVec2::new(0.0, 1.3 + 0.39));
        assert_eq!(then.bodies[1], beside.shape);
        assert_eq!(clear_foot(foot, &then), Some(DVec2::ZERO));
        // Someone walking towards the foot, or nobody walking: nothing moves.
        let coming = Surroundings {
            velocities: vec![DVec2::new(0.0, -1.3), DVec2::ZERO],
            ..around.clone()
        };
        assert!(coming.ahead(foot.heel, 0.6).is_none());
        assert!(bodies(&[ahead]).ahead(foot.heel, 0.6).is_none());
        // A foot striking now sees everyone where they stand.
        assert!(around.ahead(foot.heel, 0.0).is_none());
    }

    #[test]
    fn a_body_holds_its_feet_a_stride_apart() {
        let foot = |z: f64| FootSpan {
            heel: DVec2::new(0.1, z - 0.05),
            toe: DVec2::new(0.1, z + 0.23),
            radius: 0.05,
        };
        let feet = [foot(0.35), foot(-0.3)];
        let c = Body::around(DVec2::ZERO, DVec2::Y, 0.28, 0.0, &feet);
        let (a, b) = c.ends();
        for f in &feet {
            for p in [f.heel, f.toe] {
                let d = (p - nearest_on_segment(p, a, b)).length();
                assert!(d + f.radius <= 0.28 + 1e-12, "{p} {c:?}");
            }
        }
        // Feet under the body: a disc.
        let c = Body::around(
            DVec2::ZERO,
            DVec2::Y,
            0.28,
            0.0,
            &[foot(-0.09), foot(-0.09)],
        );
        assert_eq!(c.half_length, 0.0);
        assert_eq!(c.centre, DVec2::ZERO);
        // Walking: at least the stride either way.
        let c = Body::around(DVec2::ZERO, DVec2::Y, 0.28, 0.2, &[foot(-0.09)]);
        assert_eq!((c.centre, c.half_length), (DVec2::ZERO, 0.2));
    }

    #[test]
    fn a_foot_in_the_air_closes_on_a_body_by_half_the_gap_and_on_an_obstacle_by_all_of_it() {
        let foot = |x: f64| FootSpan {
            heel: DVec2::new(x, 0.0),
            toe: DVec2::new(x, 0.25),
            radius: 0.05,
        };
        // A body whose surface is 0.1 m to the right of the foot's.
        let around = bodies(&[body(0.45, 0.1, 0.0)]);
        assert!(foot_may_move(&foot(0.0), &foot(0.05), &around));
        assert!(!foot_may_move(&foot(0.0), &foot(0.06), &around));
        assert!(foot_may_move(&foot(0.0), &foot(-0.3), &around));
        // An obstacle's edge 0.1 m from the foot's clearance.
        let wall = square("wall", (0.15 + LEG_CLEARANCE, -1.0), (0.3, 1.0));
        let around = Surroundings {
            obstacles: smallvec![&wall],
            ..Surroundings::default()
        };
        assert!(foot_may_move(&foot(0.0), &foot(0.099), &around));
        assert!(!foot_may_move(&foot(0.0), &foot(0.11), &around));
    }

    #[test]
    fn a_foot_in_the_air_inside_a_wide_capsule_keeps_from_the_foot_that_widened_it() {
        let foot = |x: f64, z: f64| FootSpan {
            heel: DVec2::new(x, z),
            toe: DVec2::new(x, z + 0.25),
            radius: 0.05,
        };
        // A body at the origin walking along +z with its left foot planted 0.45 m out,
        // and another's foot in the air inside the capsule that foot widened, 0.1 m
        // behind that foot and coming on along the capsule.
        let planted = foot(0.45, 0.0);
        let capsule = Body::around(DVec2::ZERO, DVec2::Y, 0.28, 0.5, &[planted]);
        let (from, to) = (foot(0.45, -0.45), foot(0.45, -0.39));
        let capsule_only = bodies(&[capsule]);
        assert!(
            foot_may_move(&from, &to, &capsule_only),
            "along the capsule, no deeper into it"
        );
        let with_feet = Surroundings {
            bodies: vec![capsule.shape],
            feet: vec![planted],
            ..Surroundings::default()
        };
        assert!(foot_may_move(&from, &foot(0.45, -0.45 + 0.049), &with_feet));
        assert!(
            !foot_may_move(&from, &to, &with_feet),
            "half the feet's gap at most"
        );
        assert!(foot_may_move(&from, &foot(0.45, -0.6), &with_feet));
    }

    #[test]
    fn the_nearest_points_of_two_segments() {
        let a = (DVec2::new(0.0, 0.0), DVec2::new(1.0, 0.0));
        let b = (DVec2::new(0.5, 0.2), DVec2::new(0.5, 1.0));
        assert_eq!(
            nearest_between(a, b),
            (DVec2::new(0.5, 0.0), DVec2::new(0.5, 0.2))
        );
        let crossing = (DVec2::new(0.5, -1.0), DVec2::new(0.5, 1.0));
        let (p, q) = nearest_between(a, crossing);
        assert_eq!(p, q);
    }
}
