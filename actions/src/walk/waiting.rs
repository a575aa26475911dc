//! A walk held up on its way: whom it waits for, when it is stuck or gives up, the new
//! routes round those standing and the other places it takes, and the actor it goes to
//! followed as they move.
//!
//! Local avoidance ([`super::steer`]) decides each tick how the body follows its plan;
//! what is here decides whether the plan itself should change (a new route, another
//! standing point, the place where the body stands, a route to where the actor went) or
//! the walk end (stuck against the furniture with nobody to wait for, or out of
//! [`super::patience`]).

use super::goal::{self, Goal};
use super::replan;
use super::route::{self, Plan, Route};
use super::standoff;
use super::Walk;
use troupe_body::glam::DVec2;
use troupe_scene::space::{segment_distance, Crowd, FootprintsAround};
use troupe_scene::GeneratorContext;

/// Below this speed (m/s) on the previous tick, a body whose plan goes on is stalled (see
/// [`Walk::stalled`]).
const STALLED_SPEED: f64 = 0.05;

/// A stalled body with nobody moving within this distance (m) is held by the furniture or
/// by people standing, not by a crowd on the move (see [`Walk::stalled`]).
const ALONE: f64 = 1.5;

/// Seconds a navigated walk's body may stay within [`PROGRESS`] of where it stood, with
/// nobody within [`UNATTENDED`] it may be waiting for when it gives up, before the walk
/// gives up as stuck (it stops, then fails): held by the furniture or the walls where it
/// cannot pass (a cup carried out in front against a counter as high as the hand), with
/// nobody there who might move out of its way.
pub const STUCK_TIME: f64 = 10.0;
/// How far (m) a walk's body must move to count as getting on (see [`STUCK_TIME`]).
pub const PROGRESS: f64 = 0.05;
/// Seconds before it would give up as stuck in which a walk takes a last look for a
/// route, however long the wait between its attempts has grown (see [`Walk::stuck_soon`]).
const LAST_LOOK: f64 = 5.0;
/// With another actor within this distance (m) who is on the move or stands in its way
/// on, a walk that gets no nearer its goal may be waiting for them (to pass, to move off
/// its way or its goal), and is not stuck (see `Walk::waiting_for_someone`).
pub const UNATTENDED: f64 = 3.0;
/// How many of those in its way a walk that gives up names (see [`super::patience`]); the
/// others are counted.
const NAMED: usize = 3;
/// Seconds between two looks at where the actor a walk goes to stands (see
/// [`Walk::follow_actor`]).
const FOLLOW_INTERVAL: f64 = 0.5;
/// How far (m) the actor a walk goes to must have moved since its route was planned
/// for the walk to plan it again (see [`Walk::follow_actor`]).
const FOLLOW_MOVED: f64 = 0.25;
/// Speed (m/s) towards a walk's body at which the actor it goes to comes to meet it
/// (see [`Walk::follow_actor`]).
const COMING: f64 = 0.3;
/// How much further (m) than its `distance` from the actor it goes to a walk must be for
/// it to follow them (see [`Walk::follow_actor`]).
const FOLLOW_SLACK: f64 = 0.5;
/// Seconds a walk's body may stand held, on its way or short of its plan's end, before it
/// ends where it stands if that is as good a place, or, someone standing by its point
/// at its end, looks for another (see [`Walk::held`]).
const HELD_AT_END: f64 = 2.0;
/// Seconds a walk to an object or an actor may stand in one place, nobody moving within
/// [`ALONE`], before it ends there if it can (see [`Walk::boxed_in`]).
const BOXED_IN: f64 = 5.0;
/// How near (m) its end a walk to a point or along a path ends where its body stands
/// held, its plan's clock held (see [`Walk::held_near_end`]): a waiter carrying a cup
/// out in front along a path ending 0.9 m before the guest it was for was held 13 cm
/// short by the guest's body, and waited for the guest to make room for good, the guest
/// waiting for the cup.
const NEAR_END: f64 = 0.3;
/// Seconds a walk to a point or along a path stands held near its end by someone
/// standing there before it ends where it stands (see [`NEAR_END`]).
const HELD_NEAR_END: f64 = 5.0;
/// Seconds of its plan a walk held near its end may get on and still count as held (see
/// [`NEAR_END`]).
const PLAN_PROGRESS: f64 = 0.05;
/// How much further (m) than [`goal::LEAST_ACTOR_GAP`] from a walk's standing point
/// someone stands by it (see [`Walk::held`]): the clearance keeps bodies
/// closer than that.
const HELD_MARGIN: f64 = 0.2;
/// How much further (m) from its object or actor than the one taken a walk's new
/// standing point may be, but in the open (see [`Walk::another_place`]).
const AS_NEAR: f64 = 0.05;
/// Seconds of its plan ahead that make a held walk's way on (see [`UNATTENDED`]).
const WAY_ON: f64 = 2.0;
/// Gap (m) between two bodies' discs under which one standing beside a held walk's way
/// on stands in it (see [`UNATTENDED`]).
const IN_THE_WAY: f64 = 0.5;

/// A walk's way on from where its body is (see [`Walk::way_on`]).
struct WayOn {
    /// The walking actor.
    me: usize,
    /// Where its body is.
    at: DVec2,
    /// Where the way on ends.
    end: DVec2,
    /// Its body's radius.
    radius: f64,
}

impl WayOn {
    /// Whether actor `j` is another within [`UNATTENDED`] of the body.
    fn within(&self, crowd: &Crowd, j: usize) -> bool {
        j != self.me && (crowd.positions[j] - self.at).length() < UNATTENDED
    }

    /// Whether actor `j`'s body is in the way (within [`IN_THE_WAY`] of touching the
    /// walker's on it).
    fn in_it(&self, crowd: &Crowd, j: usize) -> bool {
        let reach = self.radius + crowd.radii[j] + IN_THE_WAY;
        segment_distance(crowd.positions[j], self.at, self.end) < reach
    }
}

impl Walk {
    /// Why the walk is stuck, if it is (see [`STUCK_TIME`]): how far from its goal (or a
    /// followed path's end), and the obstacle nearest the body, among `footprints`.
    pub(super) fn stuck(
        &mut self,
        ctx: &GeneratorContext,
        plan: &Plan,
        footprints: &FootprintsAround,
    ) -> Option<String> {
        let crowd = ctx.world.crowd;
        let at = *crowd.positions.get(ctx.actor)?;
        // A followed or a velocity walk whose plan stands (a speed of 0 asked for) stands
        // by request; only one held back while its plan goes on is stuck.
        let path = matches!(self.route, Route::Path { .. });
        if !path && plan.speed(self.steer.plan_time(self.t, self.t)) < STALLED_SPEED {
            self.progress = Some((at, self.t));
            return None;
        }
        match self.progress {
            // Along the way, not towards the goal: a path may lead away from its end.
            Some((stood, _)) if (at - stood).length() < PROGRESS => {}
            _ => {
                self.progress = Some((at, self.t));
                return None;
            }
        }
        let (_, since) = self.progress?;
        if self.t - since < STUCK_TIME || self.stopped_at.is_some() {
            return None;
        }
        if self.waiting_for_someone(ctx, plan, at) {
            // Waiting for someone, who may move: the time counts again from now.
            self.progress = Some((at, self.t));
            return None;
        }
        let left = match &self.route {
            Route::Path { points, .. } => {
                format!(" {:.2} m from its goal", (*points.last()? - at).length())
            }
            Route::Follow(_) => {
                let end = self.end_sample(plan).position;
                format!(" {:.2} m from its path's end", (end - at).length())
            }
            Route::Velocity { .. } => String::new(),
        };
        let against = footprints
            .within(1.0)
            .map(|f| (f.distance(at), &f.name))
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, name)| format!(", held by {name}"))
            .unwrap_or_default();
        Some(format!("stuck{left} for {STUCK_TIME} s{against}"))
    }

    /// Whether the walk would give up as stuck within [`LAST_LOOK`], its body not having
    /// got on: then, held with nobody moving near, it looks for a route whatever the wait
    /// between attempts. Pressed against the wall beside a doorway as three walkers came
    /// through it, a walker looked for routes round them three times (each round the
    /// wall's far end, too long) and was to wait 16 s for the next; the doorway cleared,
    /// and it gave up as stuck 5 s later, 4.9 m from its goal through the doorway.
    pub(super) fn stuck_soon(&self) -> bool {
        self.progress
            .is_some_and(|(_, since)| self.t - since >= STUCK_TIME - LAST_LOOK)
    }

    /// Whether the walk, its body held at `at`, may be waiting for another actor within
    /// [`UNATTENDED`]: one on the move (who may be passing), or one standing in its way
    /// on (the plan's next [`WAY_ON`] seconds, at most [`UNATTENDED`] long), who may move
    /// off it. Anyone else there (a barista behind the counter that holds the walk back)
    /// is no reason to wait for ever.
    fn waiting_for_someone(&self, ctx: &GeneratorContext, plan: &Plan, at: DVec2) -> bool {
        let (passing, standing_in_it) = self.who_holds(ctx, plan, at);
        passing || standing_in_it
    }

    /// Whether anyone within [`UNATTENDED`] of the walk's body, held at `at`, is on the
    /// move, and whether anyone there stands in its way on (see [`Walk::way_on`]).
    fn who_holds(&self, ctx: &GeneratorContext, plan: &Plan, at: DVec2) -> (bool, bool) {
        let crowd = ctx.world.crowd;
        let mut near = Vec::new();
        crowd.near(at, &mut near);
        let way = self.way_on(ctx, plan, at);
        let near = near.into_iter().filter(|&j| way.within(crowd, j));
        near.fold((false, false), |(passing, standing_in_it), j| {
            (
                passing || crowd.velocities[j].length() > replan::STANDING,
                standing_in_it || way.in_it(crowd, j),
            )
        })
    }

    /// The actors in the walk's way on from `at` (see [`Walk::waiting_for_someone`]),
    /// nearest first.
    fn in_its_way(&self, ctx: &GeneratorContext, plan: &Plan, at: DVec2) -> Vec<usize> {
        let crowd = ctx.world.crowd;
        let mut near = Vec::new();
        crowd.near(at, &mut near);
        let way = self.way_on(ctx, plan, at);
        near.retain(|&j| way.within(crowd, j) && way.in_it(crowd, j));
        near.sort_by(|&a, &b| {
            let d = |j: usize| (crowd.positions[j] - at).length();
            d(a).total_cmp(&d(b)).then(a.cmp(&b))
        });
        near
    }

    /// The body's way on from `at`: the plan's next [`WAY_ON`] seconds, at most
    /// [`UNATTENDED`] long.
    fn way_on(&self, ctx: &GeneratorContext, plan: &Plan, at: DVec2) -> WayOn {
        let crowd = ctx.world.crowd;
        let me = ctx.actor;
        let radius = crowd.radii.get(me).copied().unwrap_or_default();
        let pt = self.steer.plan_time(self.t, self.t);
        let onward = self.steer.offset + plan.sample(pt + WAY_ON, self.heading).position;
        let end = at + (onward - at).clamp_length_max(UNATTENDED);
        WayOn {
            me,
            at,
            end,
            radius,
        }
    }

    /// Why the walk gives up, if its patience has run out (see [`super::patience`]): how
    /// long it waited, how far from its goal, and who stands in its way.
    pub(super) fn impatient(&mut self, ctx: &GeneratorContext, plan: &Plan) -> Option<String> {
        let (Some(patience), Route::Path { points, .. }) = (&mut self.patience, &self.route) else {
            return None;
        };
        let goal = *points.last()?;
        if self.stopped_at.is_some() {
            return None;
        }
        let left = plan.end_time - self.steer.plan_time(self.t, self.t);
        if left <= 0.0 {
            // At its end, settling its feet or turning to face the way asked: arriving,
            // not waiting (a new plan from there, to another place, counts afresh).
            patience.restart();
            return None;
        }
        if !patience.run_out(self.t, left) {
            return None;
        }
        let limit = patience.limit();
        let at = *ctx.world.crowd.positions.get(ctx.actor)?;
        let names: Vec<String> = self
            .in_its_way(ctx, plan, at)
            .into_iter()
            .filter_map(|j| ctx.world.actors.get(j).map(|a| format!("`{}`", a.name)))
            .collect();
        let who = match names.len() {
            0 => String::new(),
            1 => format!(": {} in its way", names[0]),
            n if n <= NAMED => {
                let (first, last) = names.split_at(n - 1);
                format!(": {} and {} in its way", first.join(", "), last[0])
            }
            n => format!(
                ": {} and {} more in its way",
                names[..NAMED].join(", "),
                n - NAMED
            ),
        };
        Some(format!(
            "waited {limit} s (its `patience`) getting no nearer its goal, {:.2} m from \
             it{who}",
            (goal - at).length()
        ))
    }

    /// A new plan round the actors standing in the way, from where the body is now to
    /// the route's end (see [`replan`]), the body `stalled` or not (see
    /// [`Walk::stalled`]); `None` leaves the plan as it is.
    pub(super) fn new_route(
        &mut self,
        ctx: &GeneratorContext,
        plan: &Plan,
        stalled: bool,
    ) -> Option<Plan> {
        let Route::Path { points, .. } = &self.route else {
            return None;
        };
        let goal = *points.last()?;
        let here = self
            .steer
            .sample(plan, self.t, self.t, self.heading)
            .position;
        if let Some(new) = self.another_place(ctx, (here, goal), 0.0) {
            return Some(new);
        }
        let Route::Path { heading, speed, .. } = &self.route else {
            return None;
        };
        let companions = &self.steer.companions;
        let ends = (here, goal);
        let points = self
            .replan
            .route(ctx, self.t, ends, self.radius, (companions, stalled))?;
        let route = Route::Path {
            points,
            heading: *heading,
            speed: *speed,
        };
        Some(self.take_route(route, here))
    }

    /// A new plan from `here` to another free standing point, for a walk to an object or
    /// an actor whose own point `end` someone now stands on (within `margin` m more than
    /// [`goal::LEAST_ACTOR_GAP`] of its body there); `None` leaves the plan as it is.
    ///
    /// Three sent to join bob at once: the one that came last stood behind the other two
    /// for good. It goes to the free point nearest it ([`goal::Choice::Nearest`]) if that
    /// is as near the object or the actor, or, in the open, further out, behind those who
    /// stand there (twenty gathering round a performer: the last eight stood for good in
    /// a second row); not further out in a passage (at the mouth of a niche whose only
    /// place is taken, its occupant could not come out).
    fn another_place(
        &mut self,
        ctx: &GeneratorContext,
        (here, end): (DVec2, DVec2),
        margin: f64,
    ) -> Option<Plan> {
        // Floor points are where the script asked: the walk waits for them.
        if !matches!(self.goal, Some(Goal::Object { .. } | Goal::Actor { .. })) {
            return None;
        }
        let Route::Path { speed, .. } = self.route else {
            return None;
        };
        if !goal::people_standing(ctx, &self.steer.companions, self.radius + margin)(end) {
            return None;
        }
        // Where the body stands may do as well (held by those round its point, a few
        // centimetres short of it, one went round a crowd to a free point, through it).
        if let Some(new) = self.end_here(ctx, (here, end), false) {
            return Some(new);
        }
        let kind = self.goal.as_ref()?;
        let companions = self.steer.companions.as_slice();
        let far = |p| kind.how_far(ctx, p).unwrap_or(f64::INFINITY);
        let open = |at: DVec2, heading: Option<f64>| {
            let around = ctx.world.crowd.footprints_around(at, Vec::new());
            let facing = heading.map_or(DVec2::Y, route::direction);
            standoff::in_the_open(at, facing, &around)
        };
        let planned = kind
            .plan(ctx, here, self.radius, (companions, goal::Choice::Nearest))
            .ok()?;
        // With none free, the plan is the first point, taken, as the walk's own was: the
        // walk keeps its own.
        let &(new_end, _) = planned.points.last()?;
        if new_end.distance(end) <= PROGRESS
            || goal::people_standing(ctx, companions, self.radius)(new_end)
            || far(new_end) > far(end) + AS_NEAR && !open(new_end, planned.heading)
        {
            return None;
        }
        Some(self.take_route(self.route_to(planned, speed), here))
    }

    /// For a walk to an object or an actor whose body has stood held for [`HELD_AT_END`]
    /// (looked at again every [`HELD_AT_END`]), on its way or short of its plan's end: a
    /// plan that ends where it stands, facing what it goes to, if that is as good a place
    /// ([`Goal::stand_here`]); else, its plan ended (someone came to stand by its point as
    /// it arrived), [`Walk::another_place`]. For a walk to a point or along a path,
    /// [`Walk::held_near_end`].
    pub(super) fn held(&mut self, ctx: &GeneratorContext, plan: &Plan) -> Option<Plan> {
        let tau = self.steer.plan_time(self.t, self.t);
        if !matches!(self.goal, Some(Goal::Object { .. } | Goal::Actor { .. })) {
            return self.held_near_end(ctx, plan, tau);
        }
        let crowd = ctx.world.crowd;
        let standing = crowd
            .velocities
            .get(ctx.actor)
            .is_some_and(|v| v.length() < STALLED_SPEED);
        let ended = tau >= plan.end_time;
        // Held on its way: standing where the plan moves (not turning on the spot).
        let held = ended || plan.speed(tau) >= STALLED_SPEED;
        if !standing || !held {
            self.held_since = None;
            return None;
        }
        let since = *self.held_since.get_or_insert(self.t);
        if self.t - since < HELD_AT_END {
            return None;
        }
        self.held_since = Some(self.t);
        let here = *crowd.positions.get(ctx.actor)?;
        let end = self.end_sample(plan).position;
        if let Some(new) = self.end_here(ctx, (here, end), false) {
            return Some(new);
        }
        if !ended {
            return None;
        }
        self.another_place(ctx, (here, end), HELD_MARGIN)
    }

    /// For a walk to a point or along a path (plan time `tau` on `plan`) whose body has
    /// stood within [`NEAR_END`] of its end for [`HELD_NEAR_END`], its plan's clock held
    /// (getting no more than [`PLAN_PROGRESS`] on), someone standing in its way and
    /// nobody passing: a plan that ends where it stands, with the heading the route was
    /// to end with. The body shuffles as it is held, so whether it stands is read on the
    /// plan's clock.
    fn held_near_end(&mut self, ctx: &GeneratorContext, plan: &Plan, tau: f64) -> Option<Plan> {
        let Route::Path { speed, heading, .. } = self.route else {
            return None;
        };
        let here = *ctx.world.crowd.positions.get(ctx.actor)?;
        if here.distance(self.end_sample(plan).position) >= NEAR_END {
            self.held_near_end = None;
            return None;
        }
        // Held by someone standing there, not by someone passing.
        let (passing, standing_in_it) = self.who_holds(ctx, plan, here);
        if passing || !standing_in_it {
            self.held_near_end = None;
            return None;
        }
        let (since, then) = *self.held_near_end.get_or_insert((self.t, tau));
        if tau - then > PLAN_PROGRESS {
            self.held_near_end = Some((self.t, tau));
            return None;
        }
        if self.t - since < HELD_NEAR_END {
            return None;
        }
        self.held_near_end = None;
        let route = Route::Path {
            points: vec![here],
            heading,
            speed,
        };
        Some(self.take_route(route, here))
    }

    /// Takes `route` from `here`, where the body is, mid-walk: its plan, the steering
    /// following it from its start (see [`super::steer::Steer::restart`]).
    fn take_route(&mut self, route: Route, here: DVec2) -> Plan {
        self.route = route;
        self.steer.restart();
        Plan::new(&self.route, here, self.heading)
    }

    /// A plan that ends at `here`, where the body stands, facing the object or the actor
    /// the walk goes to, if that is as good a place as its standing point `end`
    /// ([`goal::Goal::stand_here`]); `None` leaves the plan as it is.
    fn end_here(
        &mut self,
        ctx: &GeneratorContext,
        (here, end): (DVec2, DVec2),
        boxed: bool,
    ) -> Option<Plan> {
        let Route::Path { speed, .. } = self.route else {
            return None;
        };
        let planned = self
            .goal
            .as_ref()?
            .stand_here(ctx, (here, end), self.radius, boxed)?;
        Some(self.take_route(self.route_to(planned, speed), here))
    }

    /// For a walk to an object or an actor whose body has stood within [`PROGRESS`] of one
    /// place, with nobody moving within [`ALONE`], for [`BOXED_IN`] while its plan goes
    /// on: a plan that ends where it stands, facing what it goes to, if it stands no
    /// nearer than asked and within the rows of standing points ([`Goal::stand_here`],
    /// `boxed`), whoever stands between. Boxed in by those who arrived round it in a crowd
    /// gathered round a performer, one walker in the second row, its point in the third,
    /// took a new route out between two of them every two seconds, each too narrow for
    /// avoidance to let it through, and stood for good.
    ///
    /// `stalled` is [`Walk::stalled`] this tick: when it holds, nobody moves near, found
    /// once; when it does not, the plan's own speed may be why (each new route starts
    /// from standing, and a walk held so takes one every two seconds), and who moves near
    /// is looked at here (`gathered`: as for [`Walk::stalled`]).
    pub(super) fn boxed_in(
        &mut self,
        ctx: &GeneratorContext,
        plan: &Plan,
        (stalled, gathered): (bool, bool),
    ) -> Option<Plan> {
        let here = *ctx.world.crowd.positions.get(ctx.actor)?;
        let tau = self.steer.plan_time(self.t, self.t);
        let boxed = matches!(self.goal, Some(Goal::Object { .. } | Goal::Actor { .. }))
            && tau < plan.end_time
            && (stalled || self.nobody_moving_near(ctx, gathered));
        let stood = self
            .stalled_since
            .filter(|&(_, at)| boxed && at.distance(here) < PROGRESS);
        let Some((since, _)) = stood else {
            self.stalled_since = boxed.then_some((self.t, here));
            return None;
        };
        if self.t - since < BOXED_IN {
            return None;
        }
        self.stalled_since = None;
        let end = self.end_sample(plan).position;
        self.end_here(ctx, (here, end), true)
    }

    /// A new plan to where the actor this walk goes to now stands, when it has moved
    /// [`FOLLOW_MOVED`] or more since the route was planned (looked at every
    /// [`FOLLOW_INTERVAL`]): a walk to someone who walks on follows them, and two sent
    /// to each other meet (each ended a metre from where the other had set off, the two
    /// 4 m apart, their backs to each other). `None` leaves the plan as it is.
    pub(super) fn follow_actor(&mut self, ctx: &GeneratorContext, plan: &Plan) -> Option<Plan> {
        let (aimed, when) = self.aimed?;
        let Some(Goal::Actor { actor, distance }) = &self.goal else {
            return None;
        };
        if self.t - when < FOLLOW_INTERVAL {
            return None;
        }
        let now_at = *ctx.world.crowd.positions.get(*actor)?;
        if now_at.distance(aimed) < FOLLOW_MOVED {
            return None;
        }
        // Looked at again after the interval, whether a route is found or not.
        self.aimed = Some((now_at, self.t));
        let Route::Path { speed, .. } = self.route else {
            return None;
        };
        let here = self.steer.sample(plan, self.t, self.t, self.heading);
        // Near enough already: the walk ends as planned (two sent to each other, the
        // last look finding the other just past where the walk ends, turned round on the
        // spot for a step back and round again); or, the other having come on to where
        // it ends, here, slowing down now (both stood held by each other for good).
        if here.position.distance(now_at) < distance + FOLLOW_SLACK {
            let end = self.end_sample(plan).position;
            let theirs = ctx
                .world
                .crowd
                .radii
                .get(*actor)
                .copied()
                .unwrap_or(self.radius);
            if end.distance(now_at) >= self.radius + theirs + goal::LEAST_ACTOR_GAP {
                return None;
            }
            let mut stopping = plan.clone();
            stopping.stop_at(self.steer.plan_time(self.t, self.t));
            return Some(stopping);
        }
        let goal = self.goal.as_ref()?;
        // One coming towards the body (two sent to each other) is met halfway: aiming a
        // metre from where the other was at each look, the two came on to 0.65 m.
        let towards = (here.position - now_at).normalize_or_zero();
        let coming = ctx
            .world
            .crowd
            .velocities
            .get(*actor)
            .copied()
            .unwrap_or_default()
            .dot(towards)
            > COMING;
        let companions = &self.steer.companions;
        let planned = match coming {
            true => goal.plan_meeting(ctx, here.position, self.radius, companions)?,
            false => goal.plan(
                ctx,
                here.position,
                self.radius,
                (companions, goal::Choice::First),
            ),
        }
        .ok()?;
        let route = self.route_to(planned, speed);
        // Going on at the body's pace; with the new point behind the body (the other
        // walked past it), from where it stands once its plan has brought it to a stop.
        let new = match Plan::continuing(&route, here.position, self.heading, here.speed) {
            Some(new) => new,
            None if here.speed < STALLED_SPEED => Plan::new(&route, here.position, self.heading),
            None => return None,
        };
        self.route = route;
        self.steer.restart();
        Some(new)
    }

    /// Whether the body stands (slower than [`STALLED_SPEED`] on the previous tick) while
    /// its plan has not ended, with nobody moving within [`ALONE`]: held back by the
    /// clearance against the furniture or people standing, or by its feet, where the plan
    /// goes on (see [`replan::Replan::route`]). A body held by a moving crowd waits for
    /// it instead: counted stalled too, bodies pressed in `troupe bench`'s crowd took new
    /// routes every 2 s and cost it a fifth of its speed. `gathered`: the steering found
    /// this tick's neighbours in `Walk::near` (see `Walk::nobody_moving_near`).
    pub(super) fn stalled(&self, ctx: &GeneratorContext, plan: &Plan, gathered: bool) -> bool {
        let tau = self.steer.plan_time(self.t, self.t);
        // A plan that itself goes slower (turning on the spot, or round a sharp corner)
        // does not stall the body.
        tau < plan.end_time
            && plan.speed(tau) >= STALLED_SPEED
            && self.nobody_moving_near(ctx, gathered)
    }

    /// Whether the body stands (slower than [`STALLED_SPEED`] on the previous tick) with
    /// nobody moving within [`ALONE`]: among the actors the crowd finds near it, which
    /// `Walk::near` holds when `gathered` (the steering found them this tick), else
    /// found here.
    fn nobody_moving_near(&self, ctx: &GeneratorContext, gathered: bool) -> bool {
        let crowd = ctx.world.crowd;
        let (Some(&at), Some(velocity)) = (
            crowd.positions.get(ctx.actor),
            crowd.velocities.get(ctx.actor),
        ) else {
            return false;
        };
        if velocity.length() >= STALLED_SPEED {
            return false;
        }
        let mut found = Vec::new();
        let near = if gathered {
            &self.near
        } else {
            crowd.near(at, &mut found);
            &found
        };
        near.iter().all(|&j| {
            j == ctx.actor
                || (crowd.positions[j] - at).length() > ALONE
                || crowd.velocities[j].length() < replan::STANDING
        })
    }
}
