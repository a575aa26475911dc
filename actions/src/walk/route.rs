//! Where the body goes: the route of a walk turned into a root plan, a function of time
//! giving the pelvis' floor position, heading and speed (thesis 6.4.2: "the walking
//! function is driven by continuously providing the new position vector of the
//! skeleton").
//!
//! The plan is known in advance for every kind of route, so the foot placement can ask
//! where the body will be when a foot that is about to swing reaches mid-stance.

use crate::error::OptionError;
use std::cell::Cell;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;
use troupe_body::glam::DVec2;
use troupe_body::math::smoothstep;
use troupe_motion::{Sequence, Track};

/// Seconds to speed up from standing to the cruising speed, and to slow down to a stop
/// (the start and stop transitions).
pub const RAMP_TIME: f64 = 1.0;
/// Seconds over which the body turns from its initial heading onto the route.
pub const TURN_TIME: f64 = 0.8;
/// Largest turn (radians) from the way a route arrives to its requested end heading that
/// the route takes by a last straight leg along that heading; past it that leg would be a
/// hairpin (the body going beyond the goal and coming back to it backwards), so the body
/// arrives as it comes and turns on the spot (`EndTurn`).
pub const LARGEST_APPROACH_TURN: f64 = std::f64::consts::FRAC_PI_2;
/// Largest turn (radians) from the body's heading to the route's first direction that
/// the body takes while setting off (over [`TURN_TIME`], the speed rising); past it the
/// body turns on the spot first, stepping round, and then sets off.
pub const LARGEST_SETTING_OFF_TURN: f64 = std::f64::consts::FRAC_PI_3;
/// How fast (rad/s) a plan turns the body on the spot, before setting off or after its
/// route's end: a half turn in about 2.1 s, stepping round (each step turns the body at
/// most [`super::STEP_TURN`]).
pub const SPOT_TURN_RATE: f64 = 1.5;
/// Fastest (rad/s) a route's corners turn the body: the speed drops where the route
/// turns faster than this at the planned pace (see `slowed_for_corners`). The feet
/// step the body round at most [`super::STEP_TURN`] a step, about half a second at a
/// walking pace.
pub const CORNER_TURN_RATE: f64 = 1.5;
/// Braking and speeding up (m/s²) before and after a corner that slows the body.
const CORNER_ACCELERATION: f64 = 0.8;
/// Corner-cutting passes applied to a polyline path (Chaikin); three passes round a
/// corner over about a quarter of the shorter adjacent segment.
const SMOOTHING_PASSES: usize = 3;
/// Sampling period of a speed profile given as samples.
pub const PROFILE_DT: f64 = 0.01;
/// Time constant of the critically damped filter that makes a requested speed change
/// continuous in speed and acceleration (seconds).
pub const SPEED_FILTER_TIME: f64 = 0.25;

/// What a walk was asked to do (validated by [`Route::check`]).
#[derive(Clone, Debug)]
pub enum Route {
    /// Walk through these floor points (x, z), ending at the last one; optionally face
    /// `heading` (radians about +Y, 0 faces +Z) on arrival.
    Path {
        /// Points to pass through, in order.
        points: Vec<DVec2>,
        /// Heading to face on arrival.
        heading: Option<f64>,
        /// Cruising speed in m/s.
        speed: f64,
    },
    /// Walk straight ahead at a speed given over time.
    Velocity {
        /// The speed.
        speed: Speed,
        /// Seconds of walking (ramps included); `None` walks until cancelled.
        duration: Option<f64>,
    },
    /// Follow the keyframed root position (`root_x`, `root_z`, optionally `root_yaw`) of a
    /// sequence: the `Global_motion` of 6.4.2. The path is translated (and turned by the
    /// yaw difference) so that it starts where the actor stands.
    Follow(Arc<Sequence>),
}

/// A requested walking speed over time.
#[derive(Clone, Debug)]
pub enum Speed {
    /// A constant speed in m/s.
    Constant(f64),
    /// Samples every [`PROFILE_DT`] seconds from t = 0, in m/s.
    Samples(Vec<f64>),
}

impl Route {
    /// Checks every number of the route; the error names what is wrong and where.
    pub fn check(&self, ht: f64) -> Result<(), OptionError> {
        let max_speed = super::cycle::MAX_RV * ht;
        let speed_ok = |v: f64, option: &'static str, what: &str| -> Result<(), OptionError> {
            if !v.is_finite() || v <= 0.0 {
                // As Lua writes it (Rust writes "NaN").
                let got = if v.is_nan() {
                    "nan".to_string()
                } else {
                    v.to_string()
                };
                return Err(OptionError::refused(
                    option,
                    format!("{what} must be a finite number > 0 m/s, got {got}"),
                ));
            }
            if v > max_speed {
                return Err(OptionError::refused(option, format!(
                    "{what} {v} m/s is beyond the walking model (relative velocity {:.2} > {} for a thigh height of {ht:.3} m, i.e. at most {max_speed:.2} m/s)",
                    v / ht,
                    super::cycle::MAX_RV
                )));
            }
            Ok(())
        };
        match self {
            Route::Path {
                points,
                heading,
                speed,
            } => {
                speed_ok(*speed, "speed", "`speed`")?;
                if points.is_empty() {
                    return Err(OptionError::refused(
                        "path",
                        "the path is empty: give at least one point",
                    ));
                }
                for (i, p) in points.iter().enumerate() {
                    if !p.is_finite() {
                        return Err(OptionError::refused(
                            "path",
                            format!("path point {} is not finite ({p})", i + 1),
                        ));
                    }
                    if p.length() > 10_000.0 {
                        return Err(OptionError::refused(
                            "path",
                            format!(
                                "path point {} ({p}) is more than 10 km away: unreachable",
                                i + 1
                            ),
                        ));
                    }
                }
                if let Some(h) = heading {
                    if !h.is_finite() {
                        return Err(OptionError::refused(
                            "heading",
                            format!("`heading` must be finite, got {h}"),
                        ));
                    }
                }
            }
            Route::Velocity { speed, duration } => {
                if let Some(d) = duration {
                    if !d.is_finite() || *d <= 0.0 {
                        return Err(OptionError::refused(
                            "duration",
                            format!("`duration` must be a finite number > 0 s, got {d}"),
                        ));
                    }
                }
                match speed {
                    Speed::Constant(v) => speed_ok(*v, "velocity", "`velocity`")?,
                    Speed::Samples(s) => {
                        if s.is_empty() {
                            return Err(OptionError::refused(
                                "velocity",
                                "`velocity` gave no samples",
                            ));
                        }
                        if s.len() < 2 && duration.is_none() {
                            // The walk's length comes from the samples: one sample spans
                            // no time at all.
                            return Err(OptionError::refused(
                                "velocity",
                                "`velocity` samples need a `duration` or at least two samples",
                            ));
                        }
                        for (i, &v) in s.iter().enumerate() {
                            let t = i as f64 * PROFILE_DT;
                            if !v.is_finite() || v < 0.0 {
                                return Err(OptionError::refused("velocity", format!(
                                    "`velocity` returned {v} at t = {t:.2} s: expected a finite speed ≥ 0 m/s"
                                )));
                            }
                            if v > max_speed {
                                speed_ok(v, "velocity", &format!("`velocity` at t = {t:.2} s"))?;
                            }
                        }
                    }
                }
            }
            Route::Follow(seq) => {
                for dof in ["root_x", "root_z"] {
                    if seq.track(dof).is_none() {
                        return Err(OptionError::refused("follow", format!(
                            "the followed sequence `{}` has no `{dof}` track (it needs root_x and root_z, and optionally root_yaw)",
                            seq.name
                        )));
                    }
                }
                if seq.duration().is_nan() || seq.duration() <= 0.0 {
                    return Err(OptionError::refused(
                        "follow",
                        format!("the followed sequence `{}` is empty", seq.name),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// The body's floor position, heading and speed at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RootSample {
    /// Floor position (x, z).
    pub position: DVec2,
    /// Heading in radians about +Y (0 faces +Z).
    pub heading: f64,
    /// Speed along the route in m/s.
    pub speed: f64,
}

/// The unit floor direction of heading `h`.
pub fn direction(h: f64) -> DVec2 {
    DVec2::new(h.sin(), h.cos())
}

/// The heading of floor direction `d`.
pub fn heading_of(d: DVec2) -> f64 {
    d.x.atan2(d.y)
}

/// `a` wrapped to (−π, π].
pub fn wrap(a: f64) -> f64 {
    let t = std::f64::consts::TAU;
    // The remainder of a value smaller than the divisor is that value, exactly; most
    // angles wrapped are, and `%` is a call to `fmod` (0.6 % of the crowd benchmark's tick).
    let mut x = if a.abs() < t { a } else { a % t };
    if x > std::f64::consts::PI {
        x -= t;
    } else if x <= -std::f64::consts::PI {
        x += t;
    }
    x
}

/// ∫₀ᵘ smoothstep, for u in [0, 1] (u³ − u⁴/2).
fn smoothstep_integral(u: f64) -> f64 {
    let u = u.clamp(0.0, 1.0);
    u * u * u - 0.5 * u * u * u * u
}

/// Progress along a route over time: distance s(t) and speed v(t).
#[derive(Clone, Debug)]
enum Profile {
    /// Smooth ramp up from `v0` over `ramp` seconds, cruise at `v`, smooth ramp down
    /// ending at `end` (no ramp down when `end` is infinite).
    Trapezoid {
        v0: f64,
        v: f64,
        ramp: f64,
        end: f64,
    },
    /// Samples of s and v every [`PROFILE_DT`] seconds; s is cubic-Hermite between them.
    Samples { s: Vec<f64>, v: Vec<f64> },
}

impl Profile {
    fn at(&self, t: f64) -> (f64, f64) {
        match self {
            Profile::Trapezoid { v0, v, ramp, end } => {
                let t = t.max(0.0);
                let (v0, v, r, end) = (*v0, *v, *ramp, *end);
                // Distance covered by the ramp up: (v0 + v)·r/2.
                let up = |t: f64| v0 * t + (v - v0) * r * smoothstep_integral(t / r);
                if t >= end {
                    let total = up(r) + v * (end - 2.0 * r) + v * r * 0.5;
                    return (total, 0.0);
                }
                let mut s = up(t.min(r)) + v * (t - r).max(0.0);
                let mut speed = v0 + (v - v0) * smoothstep(t / r);
                if end.is_finite() && t > end - r {
                    // Mirror of the ramp up: the speed is v·(1 − smoothstep(x)), so
                    // remove v·∫smoothstep from what a cruise would have covered.
                    let x = (t - (end - r)) / r;
                    s -= v * r * smoothstep_integral(x);
                    speed = v * smoothstep((end - t) / r);
                }
                (s, speed)
            }
            Profile::Samples { s, v } => {
                let n = s.len();
                let x = (t.max(0.0) / PROFILE_DT).min((n - 1) as f64);
                // `x` is not negative: its truncation is its floor, without a call to `floor`.
                let i = (x as usize).min(n.saturating_sub(2));
                if n < 2 {
                    return (s[0], v[0]);
                }
                let u = x - i as f64;
                let h = PROFILE_DT;
                let (p0, p1, m0, m1) = (s[i], s[i + 1], v[i] * h, v[i + 1] * h);
                let u2 = u * u;
                let u3 = u2 * u;
                let pos = (2.0 * u3 - 3.0 * u2 + 1.0) * p0
                    + (u3 - 2.0 * u2 + u) * m0
                    + (-2.0 * u3 + 3.0 * u2) * p1
                    + (u3 - u2) * m1;
                let vel = ((6.0 * u2 - 6.0 * u) * p0
                    + (3.0 * u2 - 4.0 * u + 1.0) * m0
                    + (-6.0 * u2 + 6.0 * u) * p1
                    + (3.0 * u2 - 2.0 * u) * m1)
                    / h;
                (pos, vel.max(0.0))
            }
        }
    }
}

/// A floor polyline with its cumulative arc length.
#[derive(Clone, Debug)]
struct Polyline {
    points: Vec<DVec2>,
    length: Vec<f64>,
    /// The unit direction of each segment, by the index of its end point (the first
    /// entry, before any segment, unused): found once, where [`Polyline::at`] found two
    /// each time (a walk samples its plan a dozen times a tick and more).
    directions: Vec<DVec2>,
}

impl Polyline {
    fn new(points: Vec<DVec2>) -> Polyline {
        let mut length = Vec::with_capacity(points.len());
        let mut directions = Vec::with_capacity(points.len());
        let mut total = 0.0;
        for (i, p) in points.iter().enumerate() {
            if i > 0 {
                total += (*p - points[i - 1]).length();
                directions.push((*p - points[i - 1]).normalize_or(DVec2::Y));
            } else {
                directions.push(DVec2::Y);
            }
            length.push(total);
        }
        Polyline {
            points,
            length,
            directions,
        }
    }

    fn total(&self) -> f64 {
        *self.length.last().unwrap_or(&0.0)
    }

    /// Position and unit tangent at arc length `s` (clamped to the ends).
    fn at(&self, s: f64) -> (DVec2, DVec2) {
        let n = self.points.len();
        if n < 2 {
            return (self.points[0], DVec2::Y);
        }
        let s = s.clamp(0.0, self.total());
        // First index whose cumulative length exceeds s.
        let i = self.length.partition_point(|&l| l <= s).clamp(1, n - 1);
        let (a, b) = (self.points[i - 1], self.points[i]);
        let seg = self.length[i] - self.length[i - 1];
        let u = if seg > 0.0 {
            (s - self.length[i - 1]) / seg
        } else {
            0.0
        };
        // The tangent turns linearly from one segment's middle to the next one's, so the
        // heading has no jump at the vertices.
        let here = self.direction(i);
        let tangent = if u < 0.5 && i > 1 {
            self.direction(i - 1).lerp(here, 0.5 + u)
        } else if u >= 0.5 && i + 1 < n {
            here.lerp(self.direction(i + 1), u - 0.5)
        } else {
            here
        };
        (a + (b - a) * u, tangent.normalize_or(here))
    }

    /// The unit direction of segment `k` (from point `k − 1` to point `k`).
    fn direction(&self, k: usize) -> DVec2 {
        self.directions[k]
    }

    /// How far (radians, unsigned) the route turns at inner point `k`.
    fn turn_at(&self, k: usize) -> f64 {
        self.direction(k).angle_to(self.direction(k + 1)).abs()
    }
}

/// The speed profile of `trapezoid` (ending at `end`) slowed so that the body turns no
/// faster than [`CORNER_TURN_RATE`] along `line`'s corners, braking before each and
/// speeding up after at [`CORNER_ACCELERATION`]; `None` when no corner asks for less than
/// the trapezoid's speed (the plan keeps it, bit for bit). Else the samples of the new
/// profile and its end.
fn slowed_for_corners(line: &Polyline, trapezoid: &Profile, end: f64) -> Option<(Profile, f64)> {
    const DS: f64 = 0.01;
    let total = line.total();
    let n = line.points.len();
    if n < 3 || total < 2.0 * DS || !end.is_finite() {
        return None;
    }
    let cruise = trapezoid.at(0.5 * end).1.max(1e-9);
    // The tangent turns at a constant rate from one segment's middle to the next one's
    // (`Polyline::at`): over that stretch the heading turns by the angle at the vertex
    // between them. Each grid cell (DS long, centred on its point) sums the turns of the
    // stretches over it, so that a corner shorter than a cell, or several in one, asks
    // for the time all of its turn takes, and no more.
    let steps = (total / DS).ceil() as usize;
    let ds = total / steps as f64;
    let mut turning = vec![0.0; steps + 1];
    let cell = |x: f64| ((x / ds + 0.5).floor().max(0.0) as usize).min(steps);
    for k in 1..n - 1 {
        let angle = line.turn_at(k);
        if angle <= 0.0 {
            continue;
        }
        let from = line.length[k] - 0.5 * (line.length[k] - line.length[k - 1]);
        let to = line.length[k] + 0.5 * (line.length[k + 1] - line.length[k]);
        if to - from < 1e-12 {
            turning[cell(from)] += angle;
            continue;
        }
        let first = cell(from);
        for (j, turn) in (first..).zip(&mut turning[first..=cell(to)]) {
            let (lo, hi) = ((j as f64 - 0.5) * ds, (j as f64 + 0.5) * ds);
            let overlap = hi.min(to) - lo.max(from);
            if overlap > 0.0 {
                *turn += angle * overlap / (to - from);
            }
        }
    }
    // The fastest through each cell: its turn in no less than turn / CORNER_TURN_RATE.
    let limit: Vec<f64> = turning
        .iter()
        .map(|&turn| {
            if turn > 0.0 {
                CORNER_TURN_RATE * ds / turn
            } else {
                f64::INFINITY
            }
        })
        .collect();
    let slowed = limit.iter().any(|&l| l < cruise);
    if !slowed {
        return None;
    }
    // The trapezoid's own speed at each arc length (it ramps up and down at the ends).
    let mut speed = vec![0.0; steps + 1];
    let (mut t, dt) = (0.0, 0.002);
    let mut at = trapezoid.at(0.0);
    for (j, v) in speed.iter_mut().enumerate() {
        let s = j as f64 * ds;
        while at.0 < s && t < end {
            t += dt;
            at = trapezoid.at(t);
        }
        *v = at.1.min(limit[j]);
    }
    speed[0] = trapezoid.at(0.0).1;
    speed[steps] = 0.0;
    // Brake before and speed up after each slow stretch (v² changes by 2·a·ds a step).
    let dv2 = 2.0 * CORNER_ACCELERATION * ds;
    for j in 1..=steps {
        speed[j] = speed[j].min((speed[j - 1] * speed[j - 1] + dv2).sqrt());
    }
    for j in (0..steps).rev() {
        speed[j] = speed[j].min((speed[j + 1] * speed[j + 1] + dv2).sqrt());
    }
    // Time at each arc length (constant acceleration within a step), then samples of
    // distance and speed every PROFILE_DT.
    let mut time = vec![0.0; steps + 1];
    for j in 1..=steps {
        time[j] = time[j - 1] + 2.0 * ds / (speed[j - 1] + speed[j]).max(1e-9);
    }
    let end = time[steps];
    let count = (end / PROFILE_DT).ceil() as usize;
    let (mut s, mut v) = (Vec::with_capacity(count + 1), Vec::with_capacity(count + 1));
    let mut j = 0;
    for i in 0..count {
        let t = i as f64 * PROFILE_DT;
        while j + 1 < steps && time[j + 1] <= t {
            j += 1;
        }
        let span = time[j + 1] - time[j];
        let a = (speed[j + 1] - speed[j]) / span.max(1e-12);
        let u = t - time[j];
        s.push(j as f64 * ds + speed[j] * u + 0.5 * a * u * u);
        v.push(speed[j] + a * u);
    }
    s.push(total);
    v.push(0.0);
    Some((Profile::Samples { s, v }, count as f64 * PROFILE_DT))
}

/// Chaikin corner cutting, keeping both ends (and so the first and last directions).
fn chaikin(points: &[DVec2], passes: usize) -> Vec<DVec2> {
    let mut pts = points.to_vec();
    for _ in 0..passes {
        if pts.len() < 3 {
            break;
        }
        let mut next = Vec::with_capacity(pts.len() * 2);
        next.push(pts[0]);
        for w in pts.windows(2) {
            let (a, b) = (w[0], w[1]);
            next.push(a * 0.75 + b * 0.25);
            next.push(a * 0.25 + b * 0.75);
        }
        next.push(*pts.last().expect("at least 3 points"));
        // The first and last cut points sit on the end segments, so the route still
        // leaves the start and reaches the goal along them.
        pts = next;
    }
    pts
}

/// A route made concrete from the actor's starting pose: a function of time.
#[derive(Clone, Debug)]
pub struct Plan {
    kind: PlanKind,
    start_heading: f64,
    /// The turn (radians, within ±π) from the start heading to the route's first
    /// direction: the side the body sets out to turn to, kept while it turns.
    start_turn: f64,
    /// When the body stops (infinite for an open-ended walk).
    pub end_time: f64,
    /// A stop asked before the route's end (see [`Plan::stop_at`]).
    stop: Option<Stop>,
    /// The last samples taken (see [`Recent`]).
    recent: Recent,
}

/// How many of a plan's last samples [`Recent`] keeps.
const RECENT: usize = 4;

/// The last few samples of a plan, by time: one tick of a steered walk asks for the plan
/// at the clock's time up to four times (the steering's decision, the pose, the cadence,
/// the hold on the feet), each a search along the route, a heading and a speed. The same
/// time gives the same sample, bit for bit.
#[derive(Clone, Debug, Default)]
struct Recent {
    /// (time's bits, fallback heading's bits where it matters, the sample and, on a
    /// route, the way it moves), oldest replaced first.
    slots: [Cell<Option<(u64, u64, Sampled)>>; RECENT],
    /// The slot the next new sample goes in.
    next: Cell<usize>,
}

/// One sample as [`Recent`] keeps it: on a route, with the route's unit direction there
/// (what [`Plan::motion`] asks for), found with the sample at no cost.
#[derive(Clone, Copy, Debug)]
struct Sampled {
    sample: RootSample,
    way: Option<DVec2>,
}

impl Recent {
    /// The sample at the time and fallback of bits `key`, if it is one of the last few.
    fn get(&self, key: (u64, u64)) -> Option<Sampled> {
        self.slots.iter().find_map(|slot| match slot.get() {
            Some((t, f, sampled)) if (t, f) == key => Some(sampled),
            _ => None,
        })
    }

    /// Keeps `sampled`, at the time and fallback of bits `key`, in place of the oldest.
    fn keep(&self, key: (u64, u64), sampled: Sampled) {
        let next = self.next.get();
        self.slots[next].set(Some((key.0, key.1, sampled)));
        self.next.set((next + 1) % RECENT);
    }
}

/// The time step (s) over which [`Plan::forward`] finds a followed path's way.
const FORWARD_DT: f64 = 0.01;

/// Fastest a stop may bring the body to rest, in seconds from cruising speed: the
/// cadence keeps its rhythm for [`super::CADENCE_LOOKBACK`] after, so the feet catch up
/// within a step.
pub const STOP_TIME: f64 = 0.8;

/// A stop before the route's end: from `at`, the speed falls from `speed` to 0 along a
/// smoothstep over `ramp` seconds, the body going on the way it was going.
#[derive(Clone, Copy, Debug)]
struct Stop {
    at: f64,
    speed: f64,
    ramp: f64,
    /// Arc length along the route at `at` (a route along a line).
    s: f64,
    /// Where the body was at `at` (a followed path goes straight on from there).
    from: RootSample,
}

impl Stop {
    /// Distance covered since `at`, and the speed, at `t`.
    fn at(&self, t: f64) -> (f64, f64) {
        (
            self.eased(t, self.speed),
            self.speed * (1.0 - smoothstep(self.u(t))),
        )
    }

    /// How far something going at `rate` at `at` has gone by `t`, slowing down as the body
    /// does: its rate falls along the same smoothstep over the ramp.
    fn eased(&self, t: f64, rate: f64) -> f64 {
        let u = self.u(t);
        // ∫(1 − smoothstep) = u − ∫smoothstep.
        rate * self.ramp * (u - smoothstep_integral(u))
    }

    /// The part of the ramp gone by `t`.
    fn u(&self, t: f64) -> f64 {
        ((t - self.at) / self.ramp).clamp(0.0, 1.0)
    }
}

/// A turn on the spot after a route's end, onto the requested heading: from `at` the
/// heading turns by `turn` more (radians) along a smoothstep over `duration` seconds.
#[derive(Clone, Copy, Debug)]
struct EndTurn {
    at: f64,
    turn: f64,
    duration: f64,
}

#[derive(Clone, Debug)]
enum PlanKind {
    Along {
        line: Polyline,
        profile: Profile,
        end_heading: Option<f64>,
        end_turn: Option<EndTurn>,
        /// Seconds the body turns on the spot before it sets off (0: it turns as it
        /// sets off, over [`TURN_TIME`]); the speed profile starts after them.
        spot_turn: f64,
    },
    Follow {
        seq: Arc<Sequence>,
        offset: DVec2,
        turn: f64,
        yaw0: f64,
    },
}

/// A track's value at `t`, clamped to its time range.
fn track_at(track: &Track, t: f64) -> f64 {
    track.value(t.clamp(track.start(), track.end()))
}

impl Plan {
    /// The plan of `route` for a body standing at `start` with heading `heading`.
    pub fn new(route: &Route, start: DVec2, heading: f64) -> Plan {
        Plan::setting_off_at(route, start, heading, 0.0)
    }

    /// The plan of a body already walking at `speed` (m/s) along `heading`: `route` from
    /// `start`, its speed going on from `speed` rather than from standing (a walk that
    /// follows someone plans anew every half second or so, and each plan from standing
    /// slowed it to a crawl). `None` when the route sets off with a turn on the spot
    /// (see [`LARGEST_SETTING_OFF_TURN`]), or is not a path.
    pub fn continuing(route: &Route, start: DVec2, heading: f64, speed: f64) -> Option<Plan> {
        if !matches!(route, Route::Path { .. }) {
            return None;
        }
        let plan = Plan::setting_off_at(route, start, heading, speed);
        match &plan.kind {
            PlanKind::Along { spot_turn, .. } if *spot_turn > 0.0 => None,
            _ => Some(plan),
        }
    }

    /// [`Plan::new`], the body walking at `v0` (m/s) as it starts (a path only).
    fn setting_off_at(route: &Route, start: DVec2, heading: f64, v0: f64) -> Plan {
        match route {
            Route::Path {
                points,
                heading: end_heading,
                speed,
            } => {
                let mut pts = vec![start];
                let goal = *points.last().expect("checked: the path is not empty");
                for p in &points[..points.len() - 1] {
                    if (*p - *pts.last().expect("non-empty")).length() > 1e-3 {
                        pts.push(*p);
                    }
                }
                let prev = *pts.last().expect("non-empty");
                let arrival = goal - prev;
                // Whether the body turns onto the requested heading on the spot.
                let mut turns_at_end = false;
                if let Some(h) = end_heading {
                    if arrival.length() > 1e-3
                        && wrap(*h - heading_of(arrival)).abs() > LARGEST_APPROACH_TURN
                    {
                        turns_at_end = true;
                    } else {
                        // Arrive along the requested heading: the last leg is straight
                        // and points that way, so the body faces it when it stops.
                        let d = (arrival.length() * 0.4).min(0.8);
                        let approach = goal - direction(*h) * d;
                        if d > 1e-3 && (approach - prev).length() > 1e-3 {
                            pts.push(approach);
                        }
                    }
                }
                if (goal - *pts.last().expect("non-empty")).length() > 1e-4 || pts.len() == 1 {
                    pts.push(goal);
                }
                let line = Polyline::new(chaikin(&pts, SMOOTHING_PASSES));
                let total = line.total();
                let (v, ramp) = (*speed, RAMP_TIME);
                // A short walk cannot reach the cruising speed: lower the peak so that the
                // two ramps cover exactly the distance. (A body already under way starts
                // no faster than that.)
                let v0 = v0.min(v).min(total / ramp);
                let v = v.min(total / ramp - 0.5 * v0);
                let end = if v > 0.0 {
                    // The ramps cover (v0 + v)·r/2 and v·r/2.
                    2.0 * ramp + (total - v * ramp - 0.5 * v0 * ramp) / v
                } else {
                    0.0
                };
                let trapezoid = Profile::Trapezoid { v0, v, ramp, end };
                let (profile, end) =
                    slowed_for_corners(&line, &trapezoid, end).unwrap_or((trapezoid, end));
                let start_turn = first_turn(&line, *end_heading, heading);
                // A route of no length is a turn on the spot onto its heading, however small.
                let setting_off = if start_turn.abs() > LARGEST_SETTING_OFF_TURN || end == 0.0 {
                    start_turn.abs() / SPOT_TURN_RATE
                } else {
                    0.0
                };
                let end = end + setting_off;
                let end_turn = match end_heading {
                    Some(h) if turns_at_end => {
                        let arrived = heading_of(line.at(line.total()).1);
                        let turn = wrap(h - arrived);
                        Some(EndTurn {
                            at: end,
                            turn,
                            duration: turn.abs() / SPOT_TURN_RATE,
                        })
                    }
                    _ => None,
                };
                Plan {
                    kind: PlanKind::Along {
                        line,
                        profile,
                        end_heading: *end_heading,
                        end_turn,
                        spot_turn: setting_off,
                    },
                    start_heading: heading,
                    start_turn,
                    end_time: end + end_turn.map_or(0.0, |e| e.duration),
                    stop: None,
                    recent: Recent::default(),
                }
            }
            Route::Velocity { speed, duration } => {
                let far = start + direction(heading) * 1.0e5;
                let line = Polyline::new(vec![start, far]);
                let (profile, end) = match (speed, duration) {
                    (Speed::Constant(v), None) => (
                        Profile::Trapezoid {
                            v0: 0.0,
                            v: *v,
                            ramp: RAMP_TIME,
                            end: f64::INFINITY,
                        },
                        f64::INFINITY,
                    ),
                    (Speed::Constant(v), Some(d)) => {
                        let ramp = RAMP_TIME.min(d / 2.0);
                        (
                            Profile::Trapezoid {
                                v0: 0.0,
                                v: *v,
                                ramp,
                                end: *d,
                            },
                            *d,
                        )
                    }
                    (Speed::Samples(samples), d) => {
                        let d = d.unwrap_or((samples.len() - 1) as f64 * PROFILE_DT);
                        let profile = filtered_profile(samples, d);
                        (profile, d)
                    }
                };
                let start_turn = first_turn(&line, None, heading);
                Plan {
                    kind: PlanKind::Along {
                        line,
                        profile,
                        end_heading: None,
                        end_turn: None,
                        spot_turn: 0.0,
                    },
                    start_heading: heading,
                    start_turn,
                    end_time: end,
                    stop: None,
                    recent: Recent::default(),
                }
            }
            Route::Follow(seq) => {
                let t0 = seq.start();
                let x = seq.track("root_x").expect("checked");
                let z = seq.track("root_z").expect("checked");
                let p0 = DVec2::new(track_at(x, t0), track_at(z, t0));
                let yaw0 = seq.track("root_yaw").map(|y| track_at(y, t0));
                // Turn the keyframed path so that its start heading is the actor's.
                let turn = match yaw0 {
                    Some(y) => wrap(heading - y),
                    None => 0.0,
                };
                Plan {
                    kind: PlanKind::Follow {
                        seq: seq.clone(),
                        offset: start - rotate(p0, turn),
                        turn,
                        yaw0: yaw0.unwrap_or(heading),
                    },
                    start_heading: heading,
                    // A followed path takes its headings from the sequence.
                    start_turn: 0.0,
                    end_time: seq.duration(),
                    stop: None,
                    recent: Recent::default(),
                }
            }
        }
    }

    /// Brings the body to rest from `t` (seconds after the start) on, going on the way it
    /// was going, within [`STOP_TIME`] (less from a slower speed); the plan then ends
    /// there. Does nothing when the plan already ends that soon.
    pub fn stop_at(&mut self, t: f64) {
        if self.stop.is_some() {
            return;
        }
        let from = self.sample(t, self.start_heading);
        let ramp = STOP_TIME * (from.speed / 1.2).clamp(0.5, 1.0);
        if self.end_time <= t + ramp {
            return;
        }
        let s = match &self.kind {
            PlanKind::Along {
                profile, spot_turn, ..
            } => profile.at(t - spot_turn).0,
            PlanKind::Follow { .. } => 0.0,
        };
        // The samples after `t` change.
        self.recent = Recent::default();
        self.stop = Some(Stop {
            at: t,
            speed: from.speed,
            ramp,
            s,
            from,
        });
        self.end_time = t + ramp;
    }

    /// Whether the body turns on the spot at `t` seconds after the start: onto the
    /// route before setting off (see [`LARGEST_SETTING_OFF_TURN`]), or onto the requested
    /// heading after the route's end (`EndTurn`).
    pub fn turns_on_the_spot(&self, t: f64) -> bool {
        match &self.kind {
            PlanKind::Along {
                end_turn,
                spot_turn,
                ..
            } => t < *spot_turn || end_turn.is_some_and(|e| t > e.at && t < e.at + e.duration),
            PlanKind::Follow { .. } => false,
        }
    }

    /// The body's speed `t` seconds after the start: [`Plan::sample`]'s `speed`, without
    /// finding the position and heading (the cadence asks for several speeds a tick).
    pub fn speed(&self, t: f64) -> f64 {
        match &self.kind {
            PlanKind::Along {
                profile, spot_turn, ..
            } => self.covered(profile, *spot_turn, t).1,
            // A followed path's sample has its stop in it.
            PlanKind::Follow { .. } => self.sample(t, 0.0).speed,
        }
    }

    /// The unit floor direction (x, z) the plan moves the body along at `t`: its heading's
    /// on a route, which faces the way it goes; a followed path's own way, since its
    /// heading may be a `root_yaw` track facing anywhere (a body turning round to walk on
    /// backwards), its heading's where it stands still.
    pub fn forward(&self, t: f64) -> DVec2 {
        let sample = self.sample(t, 0.0);
        let along = match &self.kind {
            PlanKind::Follow { .. } => {
                let ahead = self.sample(t + FORWARD_DT, 0.0);
                (ahead.position - sample.position).try_normalize()
            }
            PlanKind::Along { .. } => None,
        };
        along.unwrap_or_else(|| direction(sample.heading))
    }

    /// The plan's velocity at `t` as a unit floor direction (x, z) and a speed (the
    /// speed [`Plan::sample`]'s): on a route, the route's own direction at the distance
    /// covered, where [`Plan::forward`] has the heading's, the same but as the body turns
    /// onto a new route while setting off; on a followed path, [`Plan::forward`]. No
    /// heading is found on a route: the cadence asks for the steered speed at three times
    /// a tick, and at three every 20 ms over a second ahead for each landing planned.
    pub fn motion(&self, t: f64) -> (DVec2, f64) {
        match &self.kind {
            PlanKind::Along {
                line,
                profile,
                spot_turn,
                ..
            } => {
                if let Some(Sampled {
                    sample,
                    way: Some(way),
                }) = self.recent.get((t.to_bits(), 0))
                {
                    return (way, sample.speed);
                }
                let (s, speed) = self.covered(profile, *spot_turn, t);
                (line.at(s).1, speed)
            }
            PlanKind::Follow { .. } => (self.forward(t), self.sample(t, 0.0).speed),
        }
    }

    /// The distance along a route (`profile`, after `spot_turn` seconds on the spot)
    /// covered by `t`, and the speed there, the stop asked for included.
    fn covered(&self, profile: &Profile, spot_turn: f64, t: f64) -> (f64, f64) {
        match self.stop.filter(|s| t > s.at) {
            Some(stop) => {
                let (d, v) = stop.at(t);
                (stop.s + d, v)
            }
            None => profile.at(t - spot_turn),
        }
    }

    /// The body's position, heading and speed `t` seconds after the start; `fallback` is
    /// the heading to keep where the route gives none (a followed path at rest).
    pub fn sample(&self, t: f64, fallback: f64) -> RootSample {
        // Only a followed path's heading at rest depends on the fallback.
        let fallback_bits = match self.kind {
            PlanKind::Along { .. } => 0,
            PlanKind::Follow { .. } => fallback.to_bits(),
        };
        let key = (t.to_bits(), fallback_bits);
        if let Some(sampled) = self.recent.get(key) {
            return sampled.sample;
        }
        let sampled = self.sample_anew(t, fallback);
        self.recent.keep(key, sampled);
        sampled.sample
    }

    /// Where [`Plan::sample`] puts the body at `t`, found without its heading on a route
    /// (the steering's look a tenth of a second ahead, every tick, wants no more: the
    /// heading was a third of its cost). Not kept among the recent samples.
    pub fn position(&self, t: f64) -> DVec2 {
        match &self.kind {
            PlanKind::Along {
                line,
                profile,
                spot_turn,
                ..
            } => line.at(self.covered(profile, *spot_turn, t).0).0,
            PlanKind::Follow { .. } => self.sample(t, 0.0).position,
        }
    }

    /// [`Plan::sample`], found from the route and the speed profile; on a route with the
    /// route's direction there.
    fn sample_anew(&self, t: f64, fallback: f64) -> Sampled {
        let stopping = self.stop.filter(|s| t > s.at);
        match &self.kind {
            PlanKind::Along {
                line,
                profile,
                end_heading,
                end_turn,
                spot_turn,
            } => {
                let (s, speed) = self.covered(profile, *spot_turn, t);
                let (position, tangent) = line.at(s);
                let k = if *spot_turn > 0.0 {
                    match stopping {
                        // Stopped during the turn on the spot: the turn slows down with
                        // the body and ends part way (it would take up to 3 s more).
                        Some(stop) if stop.at < *spot_turn => {
                            let u = stop.at / spot_turn;
                            let rate = 6.0 * u * (1.0 - u) / spot_turn;
                            (smoothstep(u) + stop.eased(t, rate)).min(1.0)
                        }
                        _ => smoothstep(t / spot_turn),
                    }
                } else {
                    smoothstep(t / TURN_TIME)
                };
                let path = path_heading(line, tangent, *end_heading, self.start_heading);
                let mut turn = wrap(path - self.start_heading);
                // The body turns the way it set out to: a route that starts nearly behind
                // it wavers across the back as the body sets off, and the nearer way round
                // would flip sides between two ticks (a jump of 360° times `k`).
                if turn - self.start_turn > PI {
                    turn -= TAU;
                } else if turn - self.start_turn < -PI {
                    turn += TAU;
                }
                let mut heading = self.start_heading + turn * k;
                if let Some(e) = end_turn.filter(|e| t > e.at) {
                    heading += e.turn * smoothstep((t - e.at) / e.duration);
                }
                Sampled {
                    sample: RootSample {
                        position,
                        heading,
                        speed,
                    },
                    way: Some(tangent),
                }
            }
            PlanKind::Follow { .. } if stopping.is_some() => {
                let stop = stopping.expect("matched");
                let (d, speed) = stop.at(t);
                Sampled {
                    sample: RootSample {
                        position: stop.from.position + direction(stop.from.heading) * d,
                        heading: stop.from.heading,
                        speed,
                    },
                    way: None,
                }
            }
            PlanKind::Follow {
                seq,
                offset,
                turn,
                yaw0,
            } => {
                let t = (seq.start() + t).min(seq.end());
                let x = seq.track("root_x").expect("checked");
                let z = seq.track("root_z").expect("checked");
                let p = DVec2::new(track_at(x, t), track_at(z, t));
                let inside = t > seq.start() && t < seq.end();
                let vel = if inside {
                    DVec2::new(x.velocity(t), z.velocity(t))
                } else {
                    DVec2::ZERO
                };
                let vel = rotate(vel, *turn);
                let heading = match seq.track("root_yaw") {
                    Some(y) => self.start_heading + (track_at(y, t) - yaw0),
                    None if vel.length() > 0.05 => heading_of(vel),
                    None => fallback,
                };
                Sampled {
                    sample: RootSample {
                        position: offset + rotate(p, *turn),
                        heading,
                        speed: vel.length(),
                    },
                    way: None,
                }
            }
        }
    }
}

/// The heading along `line` where its tangent is `tangent`; for a route of no length,
/// `end_heading`, else `start_heading`.
fn path_heading(
    line: &Polyline,
    tangent: DVec2,
    end_heading: Option<f64>,
    start_heading: f64,
) -> f64 {
    if line.total() < 1e-6 {
        end_heading.unwrap_or(start_heading)
    } else {
        heading_of(tangent)
    }
}

/// The turn (within ±π) from `heading` to the route's first direction along `line` (see
/// [`path_heading`]): the side a plan's body sets out to turn to.
fn first_turn(line: &Polyline, end_heading: Option<f64>, heading: f64) -> f64 {
    wrap(path_heading(line, line.at(0.0).1, end_heading, heading) - heading)
}

/// `p` turned by `a` radians about +Y (the floor's x, z).
fn rotate(p: DVec2, a: f64) -> DVec2 {
    let (s, c) = a.sin_cos();
    // A heading h maps +Z to (sin h, cos h): x' = x cos a + z sin a, z' = −x sin a + z cos a.
    DVec2::new(p.x * c + p.y * s, -p.x * s + p.y * c)
}

/// Samples of a requested speed, passed through a critically damped filter (so a step
/// change becomes continuous in speed and acceleration) and ramped to zero at both ends,
/// then integrated into distance.
fn filtered_profile(samples: &[f64], duration: f64) -> Profile {
    let n = ((duration / PROFILE_DT).round() as usize).max(1) + 1;
    let w = 1.0 / SPEED_FILTER_TIME;
    let (mut x, mut xd) = (0.0f64, 0.0f64);
    let mut v = Vec::with_capacity(n);
    for i in 0..n {
        let t = i as f64 * PROFILE_DT;
        let target = samples[i.min(samples.len() - 1)];
        // Semi-implicit Euler of x'' = w²(target − x) − 2w x', sub-stepped for accuracy.
        for _ in 0..10 {
            let h = PROFILE_DT / 10.0;
            xd += (w * w * (target - x) - 2.0 * w * xd) * h;
            x += xd * h;
        }
        let ramp = smoothstep((duration - t) / RAMP_TIME.min(duration / 2.0));
        v.push(x.max(0.0) * ramp);
    }
    let mut s = Vec::with_capacity(n);
    let mut total = 0.0;
    for i in 0..n {
        if i > 0 {
            total += 0.5 * (v[i] + v[i - 1]) * PROFILE_DT;
        }
        s.push(total);
    }
    Profile::Samples { s, v }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrapping_skips_the_remainder_only_where_it_changes_nothing() {
        // What `wrap` was before it skipped `%` for angles within a turn.
        let by_remainder = |a: f64| {
            let t = TAU;
            let mut x = a % t;
            if x > PI {
                x -= t;
            } else if x <= -PI {
                x += t;
            }
            x
        };
        let mut angles = vec![
            0.0,
            -0.0,
            1e-300,
            -1e-300,
            PI,
            -PI,
            TAU,
            -TAU,
            1e9,
            -1e9,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MAX,
            f64::MIN_POSITIVE,
        ];
        for edge in [PI, TAU, 3.0 * PI] {
            let mut below = edge;
            let mut above = edge;
            for _ in 0..4 {
                below = below.next_down();
                above = above.next_up();
                angles.extend([below, above, -below, -above]);
            }
        }
        // And a sweep over ten turns either way.
        angles.extend((-20_000..=20_000).map(|i| i as f64 * 0.003_141_7));
        for a in angles {
            let (got, want) = (wrap(a), by_remainder(a));
            assert!(
                got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                "wrap({a:e}) = {got:e}, by the remainder {want:e}"
            );
        }
    }

    #[test]
    fn trapezoid_ends_at_the_goal_with_zero_speed() {
        let route = Route::Path {
            points: vec![DVec2::new(3.0, 4.0)],
            heading: None,
            speed: 1.2,
        };
        let plan = Plan::new(&route, DVec2::ZERO, 0.0);
        let end = plan.sample(plan.end_time, 0.0);
        assert!((end.position - DVec2::new(3.0, 4.0)).length() < 1e-9);
        assert!(end.speed.abs() < 1e-12);
        // Mid-route it cruises at the requested speed.
        let mid = plan.sample(plan.end_time / 2.0, 0.0);
        assert!((mid.speed - 1.2).abs() < 1e-9, "{}", mid.speed);
        // The distance is continuous at the ramp boundaries and at the end, and the
        // reported speed is its derivative everywhere.
        for t in [RAMP_TIME, plan.end_time - RAMP_TIME, plan.end_time] {
            let a = plan.sample(t - 1e-7, 0.0).position;
            let b = plan.sample(t + 1e-7, 0.0).position;
            assert!((a - b).length() < 1e-6, "jump at {t}");
        }
        assert_speed_is_the_distance_rate(&plan, 0.0);
    }

    /// Every 0.05 s from `from` to its end, `plan`'s speed is the rate of its distance
    /// (by central differences), and `Plan::speed` and `Plan::position` are exactly the
    /// sample's speed and position.
    fn assert_speed_is_the_distance_rate(plan: &Plan, from: f64) {
        let mut t = from;
        while t < plan.end_time {
            let h = 1e-6;
            let d = (plan.sample(t + h, 0.0).position - plan.sample(t - h, 0.0).position).length()
                / (2.0 * h);
            assert!(
                (d - plan.sample(t, 0.0).speed).abs() < 1e-4,
                "speed at {t}: {d}"
            );
            let sample = plan.sample(t, 0.0);
            assert_eq!(plan.speed(t).to_bits(), sample.speed.to_bits());
            let position = plan.position(t);
            assert_eq!(
                (position.x.to_bits(), position.y.to_bits()),
                (sample.position.x.to_bits(), sample.position.y.to_bits())
            );
            t += 0.05;
        }
    }

    #[test]
    fn a_plan_for_a_body_under_way_keeps_its_pace_and_still_ends_at_the_goal() {
        // Heading +z at 1.1 m/s, the new route straight on (a walk following someone).
        let far = Route::Path {
            points: vec![DVec2::new(0.0, 4.0)],
            heading: None,
            speed: 1.2,
        };
        let plan = Plan::continuing(&far, DVec2::ZERO, 0.0, 1.1).expect("straight on");
        assert!((plan.speed(0.0) - 1.1).abs() < 1e-12, "{}", plan.speed(0.0));
        let end = plan.sample(plan.end_time, 0.0);
        assert!((end.position - DVec2::new(0.0, 4.0)).length() < 1e-9);
        assert!(end.speed.abs() < 1e-12);
        // Sooner than from standing, by about half the ramp at that pace.
        let standing = Plan::new(&far, DVec2::ZERO, 0.0);
        let saved = standing.end_time - plan.end_time;
        assert!(
            (saved - 0.5 * RAMP_TIME * 1.1 / 1.2).abs() < 1e-9,
            "{saved}"
        );
        // The distance is continuous and the speed its rate (after the start, where the
        // plan's time stops at 0 and the difference is one-sided).
        assert_speed_is_the_distance_rate(&plan, 0.05);
        // Too short to stop from that pace at the ramp's deceleration: it starts slower,
        // and still stops on the goal.
        let near = Route::Path {
            points: vec![DVec2::new(0.0, 0.3)],
            heading: None,
            speed: 1.2,
        };
        let plan = Plan::continuing(&near, DVec2::ZERO, 0.0, 1.1).expect("straight on");
        assert!(
            plan.speed(0.0) <= 0.3 / RAMP_TIME + 1e-12,
            "{}",
            plan.speed(0.0)
        );
        let end = plan.sample(plan.end_time, 0.0);
        assert!((end.position - DVec2::new(0.0, 0.3)).length() < 1e-9);
        // A route behind the body would set off with a turn on the spot: none.
        let behind = Route::Path {
            points: vec![DVec2::new(0.0, -2.0)],
            heading: None,
            speed: 1.2,
        };
        assert!(Plan::continuing(&behind, DVec2::ZERO, 0.0, 1.1).is_none());
        // From standing, the plan is the one `Plan::new` makes, to the bit.
        let again = Plan::continuing(&far, DVec2::ZERO, 0.0, 0.0).expect("straight on");
        assert_eq!(again.end_time.to_bits(), standing.end_time.to_bits());
    }

    #[test]
    fn a_route_setting_off_behind_the_body_turns_it_one_way_round() {
        // The route leaves nearly straight behind the body (heading +z) and its direction
        // then crosses the back: the heading must turn smoothly all the way, not flip to
        // the other side as the nearer way round changes.
        let route = Route::Path {
            points: vec![DVec2::new(0.02, -1.0), DVec2::new(-0.4, -2.0)],
            heading: None,
            speed: 1.3,
        };
        let plan = Plan::new(&route, DVec2::ZERO, 0.0);
        let dt = 0.01;
        let mut last = plan.sample(0.0, 0.0).heading;
        let mut fastest: f64 = 0.0;
        for i in 1..=200 {
            let h = plan.sample(i as f64 * dt, 0.0).heading;
            fastest = fastest.max((h - last).abs() / dt);
            last = h;
        }
        // Turned on the spot first (more than 60°): a smoothstep over the turn at
        // SPOT_TURN_RATE peaks at 1.5 times that rate.
        assert!(
            fastest < 1.5 * SPOT_TURN_RATE + 0.05,
            "the heading turned at {fastest:.2} rad/s"
        );
        // And it ends facing along the route's last leg.
        let end = plan.sample(plan.end_time, 0.0).heading;
        let along = heading_of(DVec2::new(-0.42, -1.0));
        assert!(wrap(end - along).abs() < 0.05, "{end} against {along}");
    }

    #[test]
    fn corners_slow_the_plan_so_that_it_turns_no_faster_than_the_feet_follow() {
        let square = |speed: f64| Route::Path {
            points: vec![
                DVec2::new(0.0, 2.0),
                DVec2::new(2.0, 2.0),
                DVec2::new(2.0, 0.0),
                DVec2::new(0.0, 0.0),
            ],
            heading: None,
            speed,
        };
        // (Its rounded corners turn 90° over about 1 m of the route: at 0.8 m/s the
        // heading turns at about 1.3 rad/s and the plan keeps the trapezoid.)
        for speed in [1.2, 1.6, 2.0] {
            let plan = Plan::new(&square(speed), DVec2::ZERO, 0.0);
            assert!(matches!(
                plan.kind,
                PlanKind::Along {
                    profile: Profile::Samples { .. },
                    ..
                }
            ));
            let dt = 0.01;
            let mut last = plan.sample(0.0, 0.0);
            let (mut fastest_turn, mut fastest): (f64, f64) = (0.0, 0.0);
            let mut t = dt;
            while t <= plan.end_time {
                let now = plan.sample(t, 0.0);
                // Past the setting off's turn (over TURN_TIME).
                if t > TURN_TIME {
                    fastest_turn = fastest_turn.max(wrap(now.heading - last.heading).abs() / dt);
                }
                fastest = fastest.max(now.speed);
                last = now;
                t += dt;
            }
            assert!(
                fastest_turn < CORNER_TURN_RATE * 1.1,
                "{speed} m/s: the heading turned at {fastest_turn:.2} rad/s"
            );
            assert!(fastest <= speed + 1e-9, "{speed} m/s: {fastest}");
            let end = plan.sample(plan.end_time, 0.0);
            assert!(
                end.position.length() < 1e-9,
                "{speed} m/s: ends at {}",
                end.position
            );
            assert_eq!(end.speed, 0.0);
        }
        // A straight route keeps the trapezoid: those plans are as they were, bit for bit.
        let straight = Route::Path {
            points: vec![DVec2::new(0.0, 5.0)],
            heading: None,
            speed: 1.4,
        };
        let plan = Plan::new(&straight, DVec2::ZERO, 0.0);
        assert!(matches!(
            plan.kind,
            PlanKind::Along {
                profile: Profile::Trapezoid { .. },
                ..
            }
        ));
    }

    #[test]
    fn any_route_ends_at_its_goal_in_the_time_its_length_and_turns_ask() {
        // Random routes of 2-5 points, some only centimetres apart (a new route round
        // people standing has such legs): a corner shorter than the grid of
        // `slowed_for_corners` once spread its turn's limit over whole cells: a plaza
        // walker 5 m from its goal got plans of 20-24 s and stood for over 100 s.
        let mut random = troupe_body::math::draws(12345);
        for case in 0..2000 {
            let count = 2 + (random() * 4.0) as usize;
            let mut points = Vec::new();
            let mut p = DVec2::ZERO;
            for _ in 0..count {
                let scale = if random() < 0.3 { 0.05 } else { 1.0 };
                p += DVec2::new(random() * 4.0 - 2.0, random() * 4.0 - 2.0) * scale;
                points.push(p);
            }
            let goal = p;
            let route = Route::Path {
                points,
                heading: None,
                speed: 1.3,
            };
            let plan = Plan::new(&route, DVec2::ZERO, random() * 6.0);
            let PlanKind::Along { line, .. } = &plan.kind else {
                unreachable!("a path's plan is along a line");
            };
            // The whole turn of the route at the corners' rate (half as long again for the
            // braking and speeding up round them), a half turn on the spot to set off, and
            // the rest at a third of the pace.
            let turns: f64 = (1..line.points.len() - 1).map(|k| line.turn_at(k)).sum();
            let bound = line.total() / (1.3 / 3.0)
                + 2.0 * RAMP_TIME
                + 1.5 * turns / CORNER_TURN_RATE
                + PI / SPOT_TURN_RATE;
            assert!(
                plan.end_time <= bound,
                "case {case}: {:.2} s for {:.2} m turning {turns:.2} rad (bound {bound:.2} s)",
                plan.end_time,
                line.total()
            );
            let end = plan.sample(plan.end_time, 0.0);
            assert!((end.position - goal).length() < 1e-9, "case {case}");
            assert!(end.speed.abs() < 1e-9, "case {case}: {}", end.speed);
        }
    }

    #[test]
    fn arrival_heading_is_the_requested_one() {
        let route = Route::Path {
            points: vec![DVec2::new(2.0, 2.0)],
            heading: Some(std::f64::consts::FRAC_PI_2),
            speed: 1.0,
        };
        let plan = Plan::new(&route, DVec2::ZERO, 0.0);
        let end = plan.sample(plan.end_time, 0.0);
        assert!(wrap(end.heading - std::f64::consts::FRAC_PI_2).abs() < 1e-6);
    }

    #[test]
    fn filtered_speed_is_continuous_across_a_step() {
        let samples: Vec<f64> = (0..600).map(|i| if i < 300 { 1.0 } else { 1.6 }).collect();
        let profile = filtered_profile(&samples, 6.0);
        let mut prev = profile.at(0.0).1;
        for k in 1..6000 {
            let v = profile.at(k as f64 * 0.001).1;
            assert!((v - prev).abs() < 0.01, "jump at {k}: {prev} → {v}");
            prev = v;
        }
    }

    /// Asserts that `route` is refused, naming `option`, with `needle` in the message.
    fn refused(route: &Route, option: &str, needle: &str) {
        let e = route.check(0.93).expect_err(needle);
        assert_eq!(e.option(), option, "{e}");
        assert!(e.to_string().contains(needle), "{e}");
    }

    #[test]
    fn bad_routes_are_named() {
        let empty = Route::Path {
            points: vec![],
            heading: None,
            speed: 1.0,
        };
        refused(&empty, "path", "empty");
        let nan = Route::Path {
            points: vec![DVec2::new(1.0, 1.0), DVec2::new(f64::NAN, 0.0)],
            heading: None,
            speed: 1.0,
        };
        refused(&nan, "path", "path point 2");
        for v in [0.0, -1.0, f64::NAN, 50.0] {
            let r = Route::Velocity {
                speed: Speed::Constant(v),
                duration: None,
            };
            refused(&r, "velocity", "velocity");
        }
        let one = Route::Velocity {
            speed: Speed::Samples(vec![1.0]),
            duration: None,
        };
        refused(&one, "velocity", "duration");
    }
}
