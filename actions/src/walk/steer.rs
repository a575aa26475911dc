//! Local avoidance for a walk: how the body departs from its planned route to let others
//! pass (thesis 6.5.3; reciprocal velocity obstacles, see `troupe_nav::avoid`).
//!
//! The plan stays a function of time; steering bends how it is followed: the plan's
//! clock runs at a `rate` between 0 (wait) and 1 (as planned), and the body keeps an
//! `offset` from the planned path that drifts sideways (a sidestep), or back in a
//! corridor's stand-off ([`super::standoff`]), and returns to it.
//! Each tick the walk picks a velocity from the previous tick's crowd and turns it into a
//! new rate and drift, both changing no faster than the legs can follow; the foot
//! placement reads the same steered plan, so the feet stay planted. Until avoidance first
//! acts, the steered plan is the plan itself, bit for bit. Where ways cross, the walker
//! without the way also stops at a line before the crossing (`troupe_nav::way`); in a
//! counter-flow the pull back onto the plan keeps a lane to the right ([`super::lanes`]).

use super::goal::Ring;
use super::lanes;
use super::route::{direction, Plan, RootSample};
use super::standoff::Standoff;
use troupe_body::glam::DVec2;
use troupe_scene::space::{
    choose_velocity, choose_velocity_bounded, wait_line, Agent, Footprint, FootprintsAround,
    Walker, GAP, NEIGHBOUR_RANGE,
};
use troupe_scene::GeneratorContext;

/// Largest change of the plan's clock rate per second (1 → 0 in 0.8 s).
const RATE_CHANGE: f64 = 1.25;
/// Largest sideways speed of the offset (m/s).
const MAX_DRIFT: f64 = 0.35;
/// Largest change of the sideways speed per second (m/s²).
const DRIFT_CHANGE: f64 = 2.5;
/// How fast the body returns to its planned path once free (1/s).
const RETURN: f64 = 0.8;
/// How fast the body returns to its planned path in the last seconds and after (1/s).
const END_RETURN: f64 = 2.0;
/// The cadence (as a walking speed, m/s) a steered walk keeps at least while its plan
/// moves (see [`Steer::cadence_floor`]).
pub const STEERED_CADENCE: f64 = 1.0;
/// Deceleration (m/s²) of a walker stopping to wait for one that has the way: what the
/// rate's change limit allows at a cruising speed, with a margin.
const WAIT_BRAKING: f64 = 0.6;
/// Obstacles within this distance (m) are looked at while steering.
const OBSTACLE_RANGE: f64 = 2.0;

/// How far (m) what the ring a walk keeps out of goes round moves, or the ring's reach
/// changes, before the ring is made again (see [`Steer::keep_out_of`]).
const KEEP_OUT_MOVED: f64 = 0.02;
/// How far (m) a body's disc may be inside the ring a walk keeps out of and still be
/// kept out of it (see [`Steer::keep_out_of`]).
const INSIDE_THE_RING: f64 = 0.05;
/// How far (m) outside the ring a walk keeps out of its steered point is kept: the body
/// follows it a few millimetres behind.
const RING_MARGIN: f64 = 0.01;
/// Within this gap (m) between the disc and an obstacle, the sideways drift may not go
/// towards it.
const WALL_GUARD: f64 = 0.02;
/// Lists a walk's decisions fill anew each tick, kept from one tick to the next so that
/// a decision does not allocate them (1,400 instructions an actor-tick of the crowd
/// benchmark).
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    /// The actors a decision's look further ahead adds to those near the body, for the
    /// give-way rule (see `Crowd::near_beyond`).
    beyond: Vec<usize>,
    /// The neighbours avoidance weighs.
    agents: Vec<Agent>,
}

/// How near (m) one actor's wrist and another's are when their hands are joined (held,
/// shaken): a held hand's wrist is 6–8 cm from the holding one's.
pub const HANDS_JOINED: f64 = 0.12;

/// How a walk currently departs from its plan.
#[derive(Clone, Debug, Default)]
pub struct Steer {
    /// Whether avoidance has acted yet; until then the plan's time is the walk's time.
    pub engaged: bool,
    /// The plan's time now.
    pub tau: f64,
    /// Seconds of plan per second of walking.
    pub rate: f64,
    /// The body's offset (x, z) from the planned path.
    pub offset: DVec2,
    /// The offset's velocity.
    pub drift: DVec2,
    /// Actors whose bodies already touched this one's, or whose hands held its hands,
    /// when the walk started (a group walking together, a hand held): they are not
    /// avoided.
    pub companions: Vec<usize>,
    /// The last decision's preferred and chosen velocities (x, z): the rate and the drift
    /// head for the chosen one (the preferred one while the way is clear). For the debug
    /// view; `None` before the first and once the plan has ended.
    pub decision: Option<(DVec2, DVec2)>,
    /// The rate and drift that velocity asks for.
    target: (f64, DVec2),
    /// Whether the walk stands face to face with someone in its way, and steps back (see
    /// [`super::standoff`]).
    standoff: Standoff,
    /// The plan's time on the last tick: [`Steer::hold`] does not take the clock back
    /// past it.
    tau_before: f64,
    /// A ring avoidance keeps the body out of, as it does the obstacles, and its
    /// footprint (see [`Steer::keep_out_of`]).
    keep_out: Option<(Ring, Footprint)>,
}

impl Steer {
    /// The plan's time at walk time `t`, `now` being the walk's time now.
    pub fn plan_time(&self, t: f64, now: f64) -> f64 {
        if self.engaged {
            self.tau + (t - now) * self.rate
        } else {
            t
        }
    }

    /// The steered plan at walk time `t`: position with the offset (as it drifts, for up
    /// to half a second ahead), speed with the rate and the drift.
    pub fn sample(&self, plan: &Plan, t: f64, now: f64, fallback: f64) -> RootSample {
        let tau = self.plan_time(t, now);
        let mut s = plan.sample(tau, fallback);
        if self.engaged {
            s.position += self.offset + self.drift * (t - now).clamp(0.0, 0.5);
            s.speed = self.steered_speed(plan.motion(tau));
        }
        s
    }

    /// The steered speed at walk time `t` (see [`Steer::sample`]), found without the
    /// plan's position and heading.
    pub fn speed(&self, plan: &Plan, t: f64, now: f64) -> f64 {
        if self.engaged {
            self.steered_speed(plan.motion(self.plan_time(t, now)))
        } else {
            plan.speed(t)
        }
    }

    /// The speed of the steered body where the plan moves it along the unit `way` at
    /// `speed` (see [`Plan::motion`]): the plan's velocity at the clock's rate, plus the
    /// drift.
    fn steered_speed(&self, (way, speed): (DVec2, f64)) -> f64 {
        (way * speed * self.rate + self.drift).length()
    }

    /// The least speed (m/s) that sets the cadence at walk time `t` (`now` being the
    /// walk's time now) while steering: the planned pace, up to [`STEERED_CADENCE`]. A
    /// walker slowed by avoidance takes short quick steps rather than slowing to the
    /// slowest cycle (2.5 s), so that a foot planted for the pace it lifted at is soon
    /// under the body again instead of staying out in front for seconds.
    pub fn cadence_floor(&self, plan: &Plan, t: f64, now: f64) -> f64 {
        if self.engaged {
            plan.speed(self.plan_time(t, now)).min(STEERED_CADENCE)
        } else {
            0.0
        }
    }

    /// A fresh steering for a walk starting now: notes the companions (see
    /// [`Steer::companions`]).
    pub fn start(ctx: &GeneratorContext) -> Steer {
        let crowd = ctx.world.crowd;
        let me = ctx.actor;
        let mut companions = Vec::new();
        if let (Some(&p), Some(&r)) = (crowd.positions.get(me), crowd.radii.get(me)) {
            crowd.near(p, &mut companions);
            let wrists = |i: usize| {
                let skeleton = &ctx.world.actors[i].skeleton;
                let globals = &ctx.world.states[i].globals;
                ["l_wrist", "r_wrist"]
                    .map(|w| skeleton.joint(w).ok().map(|j| globals[j].translation))
            };
            let mine = wrists(me);
            companions.retain(|&j| {
                let touching = (crowd.positions[j] - p).length() < r + crowd.radii[j] + GAP;
                // Hand in hand further apart than their bodies touch: they walk together
                // too (two walkers 0.6 m apart holding hands pushed each other away until
                // the hold broke).
                let hands_joined = || {
                    let theirs = wrists(j);
                    mine.iter().flatten().any(|a| {
                        theirs
                            .iter()
                            .flatten()
                            .any(|b| (*a - *b).length() < HANDS_JOINED)
                    })
                };
                j != me && (touching || hands_joined())
            });
        }
        Steer {
            companions,
            ..Steer::default()
        }
    }

    /// Moves the steered body by `by` (x, z) from where the plan and the offset put it now:
    /// held back by its planted feet (see [`super::footing`]). What is along the plan
    /// moves the plan's clock, never back past where it stood on the last tick; the rest
    /// joins the offset.
    pub fn hold(&mut self, plan: &Plan, by: DVec2) {
        // Along the way the plan goes (`Plan::forward`): a followed path's own, not its
        // heading (one turned to face back as it walked on had its clock pushed on, not
        // held, when held: the body jumped 0.13 m in a tick once let go); a route's
        // heading's, which turns onto a new route as the body sets off, not the route's
        // own (held against that, of 2,400 walkers crossing the plaza's twelve layouts
        // 2,291 arrived in time, not 2,381).
        let forward = plan.forward(self.tau);
        let speed = plan.speed(self.tau);
        let mut along = 0.0;
        if speed > 0.05 {
            let tau = (self.tau + by.dot(forward) / speed).max(self.tau_before);
            along = (tau - self.tau) * speed;
            self.tau = tau;
        }
        self.offset += by - forward * along;
    }

    /// Keeps the body out of `ring` from now on, as avoidance keeps it out of the
    /// obstacles, or out of none: a walk to an actor, or to an object it goes to see,
    /// keeps out of the ring it is to stand on (see [`super::goal::Ring`]; a crowd
    /// gathering round a performer: those going round the first row to a free place
    /// sidestepped into the ring, between the performer and the first row, and stood
    /// there for good). Not once the body's disc (`body`: centre, radius) is more than
    /// 5 cm inside it (`INSIDE_THE_RING`).
    pub fn keep_out_of(
        &mut self,
        ctx: &GeneratorContext,
        ring: Option<Ring>,
        (at, radius): (DVec2, f64),
    ) {
        let Some(ring) = ring else {
            self.keep_out = None;
            return;
        };
        // Made again only once what it goes round has moved (a footprint is a polygon).
        let moved = self.keep_out.as_ref().is_none_or(|(made, _)| {
            made.at.distance(ring.at) > KEEP_OUT_MOVED
                || (made.reach - ring.reach).abs() > KEEP_OUT_MOVED
        });
        if moved {
            self.keep_out = ring.footprint(ctx).map(|footprint| (ring, footprint));
        }
        // A body that has only touched the ring is still kept out of it (see
        // `Steer::decide`); one further in (set down there, or sent to someone who came
        // to stand beside it) walks out as it may.
        if let Some((_, footprint)) = &self.keep_out {
            if ring.holds(footprint, at, radius - INSIDE_THE_RING) {
                self.keep_out = None;
            }
        }
    }

    /// Follows a new plan from its start, which is where the body is now (a new route
    /// taken mid-walk, see [`super::replan`]): the offset is gone, the drift carries on.
    pub fn restart(&mut self) {
        self.engage(0.0, self.drift);
    }

    /// Starts steering at plan time `tau`, on the plan (no offset), at its full rate and
    /// with `drift`; the companions, the last decision, the disc kept out of and the
    /// stand-off (how long the walk has waited face to face, whether it steps back)
    /// carry on. A walk held by the clearance takes a new route every two seconds or
    /// so, and each one forgot the stand-off: two waiters with trays in an aisle stood
    /// face to face for good, the one stepping back stopped by its next route and
    /// neither waiting the two seconds it takes to step back again.
    pub(super) fn engage(&mut self, tau: f64, drift: DVec2) {
        *self = Steer {
            engaged: true,
            tau,
            rate: 1.0,
            offset: DVec2::ZERO,
            drift,
            companions: std::mem::take(&mut self.companions),
            decision: self.decision,
            target: (1.0, drift),
            tau_before: tau,
            standoff: std::mem::take(&mut self.standoff),
            keep_out: self.keep_out.take(),
        };
    }

    /// Advances by `dt` seconds of walking.
    pub fn advance(&mut self, dt: f64) {
        if self.engaged {
            self.tau_before = self.tau;
            self.tau += dt * self.rate;
            self.offset += self.drift * dt;
        }
    }

    /// Decides this tick's rate and drift from the crowd of the previous tick, for actor
    /// `ctx.actor` walking `plan` at walk time `now`, among the obstacles round the body
    /// (`footprints`). `others` and `scratch` are scratch space; true when `others` then
    /// holds, in actor order, every actor the crowd finds near the body (`Crowd::near`).
    pub fn decide(
        &mut self,
        ctx: &GeneratorContext,
        (plan, footprints): (&Plan, &FootprintsAround),
        now: f64,
        (others, scratch): (&mut Vec<usize>, &mut Scratch),
    ) -> bool {
        let crowd = ctx.world.crowd;
        let me = ctx.actor;
        let (Some(&position), Some(&velocity), Some(&radius)) = (
            crowd.positions.get(me),
            crowd.velocities.get(me),
            crowd.radii.get(me),
        ) else {
            return false;
        };
        let pt = self.plan_time(now, now);
        let dt = ctx.dt;
        // Nor does the steered point (the plan's, moved by the offset) go into the ring
        // kept out of: avoidance keeps the body out of it only as it weighs everything
        // else, and among forty gathering round a performer one walker's offset grew
        // 0.4 m inwards as it went round those in its way, the plan's own point outside
        // the ring, and it ended 1.36 m from him, asked 1.5 m.
        if let Some((ring, footprint)) = &self.keep_out {
            let steered = plan.sample(pt, 0.0).position + self.offset;
            if let Some(out) = ring.out_of(footprint, steered, radius + RING_MARGIN) {
                self.offset += out;
            }
        }
        if pt >= plan.end_time {
            // The plan has ended: step back onto its end, then settle.
            let back = (-self.offset * END_RETURN).clamp_length_max(MAX_DRIFT);
            let back = if self.offset.length() < 0.005 {
                DVec2::ZERO
            } else {
                back
            };
            self.drift += (back - self.drift).clamp_length_max(DRIFT_CHANGE * dt);
            self.decision = None;
            return false;
        }
        let here = plan.sample(pt, 0.0);
        let planned = (plan.position(pt + 0.1) - here.position) / 0.1;
        // Back to the path, more firmly as the end nears so the walk ends at its goal.
        let remaining = plan.end_time - pt;
        let gain = if remaining < 2.0 { END_RETURN } else { RETURN };
        let along = planned.try_normalize().unwrap_or(direction(here.heading));
        // Those near, for the lanes and for avoidance (whose give-way rule also looks
        // further ahead).
        others.clear();
        crowd.near(position, others);
        let backing = self.engaged
            && self.standoff.update(
                ctx,
                (position, along),
                (others, &self.companions, footprints),
                self.rate,
                now,
            );
        let mut preferred = if backing {
            Standoff::preferred(position, along, radius, footprints)
        } else if remaining >= 2.0
            && lanes::in_counter_flow(ctx, position, along, (others, footprints))
        {
            lanes::preferred(planned, self.offset, along, gain)
        } else {
            planned - self.offset * gain
        };
        if self.engaged {
            let cap = planned.length().max(0.3);
            preferred = preferred.clamp_length_max(cap);
        }
        let body = Agent {
            position,
            velocity,
            radius,
            feet: feet_of(ctx, me),
        };
        let around = (others.as_slice(), footprints, scratch);
        self.decide_now(ctx, &body, preferred, (planned, along), now, around);
        if !self.engaged {
            return true;
        }
        let (rate, drift) = self.target;
        self.rate += (rate - self.rate).clamp(-RATE_CHANGE * dt, RATE_CHANGE * dt);
        self.drift += (drift - self.drift).clamp_length_max(DRIFT_CHANGE * dt);
        // The drift never takes the disc into an obstacle, nor into the ring it keeps out
        // of: the velocity it chose may, while the drift changes within its limits, carry
        // the body on sideways.
        let ring = self.keep_out.as_ref().map(|(_, footprint)| footprint);
        for f in footprints.within(radius + WALL_GUARD).chain(ring) {
            let gap = f.distance(position) - radius;
            if gap < WALL_GUARD {
                let h = 0.01;
                let away = DVec2::new(
                    f.distance(position + DVec2::X * h) - f.distance(position - DVec2::X * h),
                    f.distance(position + DVec2::Y * h) - f.distance(position - DVec2::Y * h),
                )
                .normalize_or_zero();
                let towards = -self.drift.dot(away);
                if towards > 0.0 {
                    self.drift += away * towards;
                }
            }
        }
        true
    }

    /// Picks the velocity for `body` to go at, about `preferred`, from the crowd around,
    /// and turns it into the rate and drift to head for along the plan (`planned`
    /// velocity, in direction `along`), among `others` and the obstacles round the body
    /// (`scratch` holding the lists it makes).
    fn decide_now(
        &mut self,
        ctx: &GeneratorContext,
        body: &Agent,
        preferred: DVec2,
        (planned, along): (DVec2, DVec2),
        now: f64,
        (others, footprints, scratch): (&[usize], &FootprintsAround, &mut Scratch),
    ) {
        let crowd = ctx.world.crowd;
        let me = ctx.actor;
        let position = body.position;
        // Those who may cross my way further ahead, for the give-way rule, besides those
        // near (`others`, as `decide` gathered them).
        let beyond = &mut scratch.beyond;
        beyond.clear();
        crowd.near_beyond(position + along * NEIGHBOUR_RANGE, position, beyond);
        // Neither this walker nor its companions are avoided: passed over as they are
        // read (taking them out of the lists first cost a little more).
        let avoided = |j: &&usize| **j != me && !self.companions.contains(j);
        // The feet are found below, for the neighbours avoidance weighs.
        let disc = |j: usize| Agent::disc(crowd.positions[j], crowd.velocities[j], crowd.radii[j]);
        let near = |j: usize| Walker {
            body: disc(j),
            facing: crowd.facings.get(j).copied().unwrap_or_default(),
            rank: crowd.ranks.get(j).copied().flatten(),
        };
        // Where ways cross, one walker has the way (see `troupe_nav::way`): the other
        // waits before the crossing. (The line is the nearest of those each one asks
        // for, so the two lists need no merging.)
        let wait = wait_line(
            body,
            along,
            planned.length(),
            others
                .iter()
                .chain(beyond.iter())
                .filter(avoided)
                .map(|&j| near(j)),
        );
        // Everyone within range is near the body (`Crowd::near` finds every actor
        // within a cell).
        let agents = &mut scratch.agents;
        agents.clear();
        agents.extend(
            others
                .iter()
                .filter(avoided)
                .filter(|&&j| (crowd.positions[j] - position).length() < NEIGHBOUR_RANGE)
                .map(|&j| Agent {
                    feet: feet_of(ctx, j),
                    ..disc(j)
                }),
        );
        if agents.is_empty() && !self.engaged && wait.is_none() {
            self.decision = Some((preferred, preferred));
            return;
        }
        let (v, free) = if self.engaged {
            let ring = (self.keep_out.as_ref()).map(|(_, disc)| (disc, disc.bounding_circle()));
            let obstacles = footprints.within_bounded(OBSTACLE_RANGE).chain(ring);
            choose_velocity_bounded(body, preferred, agents, obstacles)
        } else {
            choose_velocity(body, preferred, agents, [])
        };
        self.decision = Some((preferred, v));
        if free && !self.engaged && wait.is_none() {
            return;
        }
        if !self.engaged {
            self.engage(now, DVec2::ZERO);
        }
        let speed = planned.length();
        let side = along.perp();
        let mut rate = if speed > 0.05 {
            (v.dot(along) / speed).clamp(0.0, 1.0)
        } else {
            1.0
        };
        if let (Some(d), true) = (wait, speed > 0.05) {
            // Slow down so as to stop at the line: v² = 2·a·d.
            rate = rate.min((2.0 * WAIT_BRAKING * d).sqrt() / speed);
        }
        // Stepping back, the body drifts back as well as sideways (the plan's clock
        // stands: `rate` is 0 for a velocity back along the way).
        let drift = if self.standoff.backing() {
            v.clamp_length_max(MAX_DRIFT)
        } else {
            side * v.dot(side).clamp(-MAX_DRIFT, MAX_DRIFT)
        };
        self.target = (rate, drift);
    }
}

/// The floor points under actor `j`'s ankles at the end of the previous tick (see
/// [`Agent::feet`], `Crowd::feet`).
fn feet_of(ctx: &GeneratorContext, j: usize) -> [DVec2; 2] {
    let crowd = ctx.world.crowd;
    crowd
        .feet
        .get(j)
        .copied()
        .unwrap_or([crowd.positions[j]; 2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::walk::route::Route;

    #[test]
    fn a_steered_walk_keeps_a_quick_cadence_however_slow_its_rate() {
        let route = Route::Path {
            points: vec![DVec2::new(0.0, 8.0)],
            heading: None,
            speed: 1.3,
        };
        let plan = Plan::new(&route, DVec2::ZERO, 0.0);
        let mut steer = Steer::default();
        // Not steering: the plan's own speeds set the cadence.
        assert_eq!(steer.cadence_floor(&plan, 2.0, 2.0), 0.0);
        steer.engaged = true;
        steer.tau = 2.0;
        steer.rate = 0.05;
        assert_eq!(steer.cadence_floor(&plan, 2.0, 2.0), STEERED_CADENCE);
        // Where the plan itself slows to its end, so does the cadence.
        steer.tau = plan.end_time;
        assert_eq!(
            steer.cadence_floor(&plan, 2.0, 2.0),
            plan.speed(plan.end_time)
        );
    }
}
