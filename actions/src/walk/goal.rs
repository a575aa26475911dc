//! Where a planned walk is going: floor points, an object to grasp or an actor to talk
//! to; turned into a route around the obstacles when the walk starts, from the world as
//! it stood at the end of the previous tick.

use super::replan::STANDING;
use std::f64::consts::PI;
use troupe_body::glam::DVec2;
use troupe_body::{Skeleton, Transform};
use troupe_scene::space::{Footprint, Walking, NEIGHBOUR_RANGE};
use troupe_scene::GeneratorContext;

/// Default distance (m) from an object's footprint edge to the body's centre when walking
/// to it: close enough to grasp it, far enough for the body.
pub const GRASP_DISTANCE: f64 = 0.35;
/// Default distance (m) between two actors' centres when one walks to the other.
pub const CONVERSATION_DISTANCE: f64 = 1.0;
/// The least gap (m) between two actors' discs when one walks to the other: a `distance`
/// that would bring them closer is taken as this close (the discs never overlap, so a
/// walk to closer than that could not end).
pub const LEAST_ACTOR_GAP: f64 = 0.1;
/// How far (m) each side of a planned path's corner the route is pinned, so that the
/// walk's rounding of the corner stays within the clearance.
const CORNER_PIN: f64 = 0.12;

/// What a planned walk goes to.
#[derive(Clone, Debug, PartialEq)]
pub enum Goal {
    /// Through these floor points (x, z) in order, planning each leg.
    Through(Vec<DVec2>),
    /// To a standing point `distance` from object `object`'s footprint, facing it.
    Object {
        /// The object's index in the scene.
        object: usize,
        /// Metres from the object's footprint edge to the body's centre.
        distance: f64,
    },
    /// To `distance` from actor `actor`, facing them.
    Actor {
        /// The other actor's index in the scene.
        actor: usize,
        /// Metres between the two centres (at least the two bodies' radii and
        /// [`LEAST_ACTOR_GAP`]).
        distance: f64,
    },
}

/// The ring round an actor, or round an object walked to be seen, that a walk's body
/// keeps out of on its way (see [`Goal::ring`]): its disc kept out of it, the body's
/// centre comes no nearer than [`AS_GOOD`] inside the ring of standing points. Of
/// thirty sent to a statue at 1 m, with nothing kept round it, one sidestepping those
/// round it ended 0.2 m nearer than its point; in another draw one, as far in, then
/// stood 0.3 m from the statue for good on its way to another place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ring {
    /// Where the actor or the object stands (x, z).
    pub at: DVec2,
    /// How far the ring reaches: from the actor's centre, or from the object's footprint.
    pub reach: f64,
    /// The object, or `None` for an actor.
    object: Option<usize>,
}

/// How near (m) its outline a point is taken to be on it by [`Ring::out_of`]: far below
/// anything a body measures, far above rounding.
const ON_THE_OUTLINE: f64 = 1e-9;

impl Ring {
    /// Whether the disc of `radius` at `p` reaches into the ring.
    pub fn holds(&self, footprint: &Footprint, p: DVec2, radius: f64) -> bool {
        match self.object {
            None => p.distance(self.at) <= self.reach + radius,
            Some(_) => footprint.distance(p) <= radius,
        }
    }

    /// The least move that takes the disc of `radius` at `p` out of the ring (`footprint`
    /// being the ring's own); `None` when it is out.
    pub fn out_of(&self, footprint: &Footprint, p: DVec2, radius: f64) -> Option<DVec2> {
        if !self.holds(footprint, p, radius) {
            return None;
        }
        match self.object {
            None => {
                let from = (p - self.at).try_normalize().unwrap_or(DVec2::X);
                Some(self.at + from * (self.reach + radius) - p)
            }
            Some(_) => {
                let edge = footprint.nearest_point(p)?;
                let away = p - edge;
                let out = if away.length() > ON_THE_OUTLINE {
                    let out = away.normalize();
                    if footprint.contains(p) {
                        -out
                    } else {
                        out
                    }
                } else {
                    // On the outline (within rounding, which points `away` anywhere): out
                    // along its normal there, found from a point just outside (the
                    // footprint is a convex hull).
                    let beyond = p + (p - footprint.centre()).try_normalize()? * 1e-6;
                    (beyond - footprint.nearest_point(beyond)?).try_normalize()?
                };
                Some(edge + out * radius - p)
            }
        }
    }

    /// The ring as a footprint: a disc round an actor; round an object, its footprint
    /// grown by the reach (`Footprint::inflated`); `None` when the object is gone.
    pub fn footprint(&self, ctx: &GeneratorContext) -> Option<Footprint> {
        let name = "the ring round the one it goes to";
        match self.object {
            None => Some(Footprint::disc(name, self.at, self.reach)),
            Some(object) => {
                let (grown, _) = Footprint::of_object(ctx.world.objects.get(object)?);
                Some(Footprint::hull(name, &grown.inflated(self.reach.max(0.0))))
            }
        }
    }
}

/// Which free standing point a walk to an object or an actor takes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// The first from the side the walker comes from, turning away from it both ways,
    /// then further out (a walk's start).
    First,
    /// The one nearest the walker, further out or not (a walk held on its way because
    /// someone has come to stand on its point: the first free one from its side was on
    /// the far side of a gathering crowd, and the walk went round it, through it).
    Nearest,
}

/// How many metres of walking to a free standing point one metre further out from an
/// object or an actor than the first ring counts as, when the point nearest the walker is
/// chosen ([`Choice::Nearest`]): of four joining one, the last stood in a second row
/// rather than go round to a place in the ring 1.3 m away.
const FURTHER_OUT: f64 = 3.0;
/// How far out (m) beyond the first ring of standing points round an object the points
/// tried go, in steps of [`ROW_STEP`], for a walk to it at [`GRASP_DISTANCE`] or nearer:
/// further, the object is out of reach, and the walk rather waits for a point to come
/// free (a queue at a counter).
const OBJECT_ROWS: f64 = 0.6;
/// The same round an actor, or an object walked to further than [`GRASP_DISTANCE`] (to
/// be seen, not taken): a crowd gathering round a performer stands in rows (of
/// twenty-four sent to one, three found the points 0.6 m out taken and went for free
/// ones on the far side of the crowd, round it and through it, for good; of thirty sent
/// to a statue at 1 m, three waited for good behind the others).
const ACTOR_ROWS: f64 = 1.5;
/// Metres between one row of standing points and the next.
const ROW_STEP: f64 = 0.1;
/// How much nearer or further (m) than asked from an object or an actor a walk held on
/// its way may stand and end there (see [`Goal::stand_here`]).
pub const AS_GOOD: f64 = 0.1;

/// A planned route: the floor points after the start, and the heading to end with.
pub struct Planned {
    /// Points to walk through, ending at the goal; each says whether the planner put it
    /// there (a corner around an obstacle) rather than the script.
    pub points: Vec<(DVec2, bool)>,
    /// Heading to face on arrival (radians about +Y), when the goal asks for one.
    pub heading: Option<f64>,
}

impl Planned {
    /// The route with its planned corners pinned (see [`pin_corners`]), from `start`.
    fn pinned(self, start: DVec2) -> Planned {
        Planned {
            points: pin_corners(start, &self.points),
            heading: self.heading,
        }
    }
}

impl Goal {
    /// Plans the route from `start` for a body of `radius`, or says why there is none;
    /// a standing point where someone stands (but the walker's `companions`) is taken,
    /// and of those free, `choice` says which.
    pub fn plan(
        &self,
        ctx: &GeneratorContext,
        start: DVec2,
        radius: f64,
        (companions, choice): (&[usize], Choice),
    ) -> Result<Planned, String> {
        let world = ctx.world;
        let planned = match self {
            // Walks that do not navigate go straight through the points.
            Goal::Through(points) if world.space.walking == Walking::Straight => Planned {
                points: points.iter().map(|&p| (p, false)).collect(),
                heading: None,
            },
            Goal::Through(points) => {
                let mut route = Vec::new();
                let mut from = start;
                for p in points {
                    let leg = world.path(from, *p, radius).map_err(|e| e.to_string())?;
                    let n = leg.len();
                    route.extend(leg.into_iter().enumerate().map(|(i, q)| (q, i + 1 < n)));
                    from = *p;
                }
                Planned {
                    points: route,
                    heading: None,
                }
            }
            Goal::Object { object, distance } => {
                let o = world.objects.get(*object).ok_or("the object is gone")?;
                let name = &o.name;
                let footprint = Footprint::of_object(o).0;
                let centre = footprint.centre();
                let shoulders = shoulder_height(ctx);
                let height = o.position.y;
                stand_near(
                    ctx,
                    (start, companions, choice),
                    (centre, radius, rows_round_an_object(*distance)),
                    |dir| footprint.reach(dir) + distance,
                    |stand| hidden_by(ctx, (stand, shoulders), (footprint.nearest(stand), height)),
                )
                .map_err(|e| format!("no place to stand within reach of {name}: {e}"))?
            }
            Goal::Actor { actor, distance } => {
                let to = (*actor, *distance);
                to_actor(ctx, (start, radius, companions), to, (false, choice))?
            }
        };
        Ok(planned.pinned(start))
    }

    /// [`Goal::plan`] for a walk to an actor who comes to meet the walker: the two meet
    /// halfway, `distance` apart; `None` for other goals.
    pub fn plan_meeting(
        &self,
        ctx: &GeneratorContext,
        start: DVec2,
        radius: f64,
        companions: &[usize],
    ) -> Option<Result<Planned, String>> {
        let Goal::Actor { actor, distance } = self else {
            return None;
        };
        let to = (*actor, *distance);
        let planned = to_actor(ctx, (start, radius, companions), to, (true, Choice::First));
        Some(planned.map(|planned| planned.pinned(start)))
    }

    /// The route of a walk that ends where its body stands, `here`, facing the object or
    /// the actor it goes to, if that is as good a place as its standing point `end`: no
    /// nearer than asked and no further out than `end` (within [`AS_GOOD`] each way),
    /// clear of the obstacles, nothing between the two (in a crowd gathered round a
    /// performer, one held in the first row on its way round to a free point stood
    /// there for good, and another held in the second row on its way to the third). A
    /// body `boxed` in where it stands may have someone between the two and stand as far
    /// out as the rows of standing points go. `None` for floor points, or where `here` is
    /// no such place.
    pub fn stand_here(
        &self,
        ctx: &GeneratorContext,
        (here, end): (DVec2, DVec2),
        radius: f64,
        boxed: bool,
    ) -> Option<Planned> {
        let world = ctx.world;
        let shoulders = shoulder_height(ctx);
        // What the walk goes to, how far beyond the first ring of standing points round
        // it the body and the walk's end are, and what stands between the body and it.
        let (centre, [beyond, end_beyond], hidden, rows) = match self {
            Goal::Through(_) => return None,
            Goal::Object { object, distance } => {
                let o = world.objects.get(*object)?;
                let footprint = Footprint::of_object(o).0;
                let centre = footprint.centre();
                let out = [here, end].map(|p| {
                    let dir = (centre - p).normalize_or_zero();
                    p.distance(centre) - footprint.reach(dir) - distance
                });
                let nearest = footprint.nearest(here);
                let hidden = hidden_by(ctx, (here, shoulders), (nearest, o.position.y));
                (centre, out, hidden, rows_round_an_object(*distance))
            }
            Goal::Actor { actor, distance } => {
                let other = world.states.get(*actor)?;
                let at = other.globals[0].translation;
                let them = DVec2::new(at.x, at.z);
                let skeleton = &world.actors[*actor].skeleton;
                let their_shoulders = shoulders_of(skeleton, &other.globals);
                let hidden = hidden_by(ctx, (here, shoulders), (them, their_shoulders));
                let wanted = actor_distance(ctx, radius, *actor, *distance);
                let out = [here, end].map(|p| p.distance(them) - wanted);
                (them, out, hidden, ACTOR_ROWS)
            }
        };
        let inflated = radius + troupe_scene::space::CLEARANCE;
        let blocked = world
            .crowd
            .footprints_near(here, inflated)
            .any(|o| o.distance(here) < inflated);
        let furthest = if boxed {
            rows.max(end_beyond)
        } else {
            end_beyond.max(0.0)
        };
        if beyond < -AS_GOOD
            || beyond > furthest + AS_GOOD
            || blocked
            || (hidden.is_some() && !boxed)
        {
            return None;
        }
        let towards = centre - here;
        Some(Planned {
            points: vec![(here, false)],
            heading: Some(towards.x.atan2(towards.y)),
        })
    }

    /// For a walk to an actor, or to an object it goes to see (further than
    /// [`GRASP_DISTANCE`]), the ring round them that its body's disc keeps out of on its
    /// way, [`AS_GOOD`] inside the ring it is to stand on (see `Steer::keep_out_of`);
    /// `None` for other goals, or when the actor or the object is gone.
    pub fn ring(&self, ctx: &GeneratorContext, radius: f64) -> Option<Ring> {
        match self {
            Goal::Actor { actor, distance } => {
                let them = *ctx.world.crowd.positions.get(*actor)?;
                let wanted = actor_distance(ctx, radius, *actor, *distance);
                Some(Ring {
                    at: them,
                    reach: wanted - radius - AS_GOOD,
                    object: None,
                })
            }
            Goal::Object { object, distance } if *distance > GRASP_DISTANCE => {
                let o = ctx.world.objects.get(*object)?;
                Some(Ring {
                    at: DVec2::new(o.position.x, o.position.z),
                    reach: distance - radius - AS_GOOD,
                    object: Some(*object),
                })
            }
            _ => None,
        }
    }

    /// How far floor point `p` is from what the walk goes to: from an object's footprint
    /// or from an actor's centre, as they stand now; `None` for floor points, or when the
    /// object or the actor is gone.
    pub fn how_far(&self, ctx: &GeneratorContext, p: DVec2) -> Option<f64> {
        let world = ctx.world;
        match self {
            Goal::Through(_) => None,
            Goal::Object { object, .. } => Some(
                Footprint::of_object(world.objects.get(*object)?)
                    .0
                    .distance(p),
            ),
            Goal::Actor { actor, .. } => Some(world.crowd.positions.get(*actor)?.distance(p)),
        }
    }
}

/// The route of a walk from `start` for a body of `radius` (with its `companions`) to
/// `distance` from `actor`, facing them; `halfway`, to half that distance from the
/// point halfway between the body and the other, who comes to meet it.
fn to_actor(
    ctx: &GeneratorContext,
    (start, radius, companions): (DVec2, f64, &[usize]),
    (actor, distance): (usize, f64),
    (halfway, choice): (bool, Choice),
) -> Result<Planned, String> {
    let world = ctx.world;
    let other = world.states.get(actor).ok_or("the actor is gone")?;
    let name = &world.actors[actor].name;
    let at = other.globals[0].translation;
    let distance = actor_distance(ctx, radius, actor, distance);
    let them = DVec2::new(at.x, at.z);
    let (centre, distance) = if halfway {
        ((start + them) * 0.5, distance * 0.5)
    } else {
        (them, distance)
    };
    // Face to face, shoulders to shoulders: a point from which a wall (or a cupboard)
    // stands between the two is no place to talk from.
    let shoulders = shoulder_height(ctx);
    let their_shoulders = shoulders_of(&world.actors[actor].skeleton, &other.globals);
    stand_near(
        ctx,
        (start, companions, choice),
        (centre, radius, ACTOR_ROWS),
        |_| distance,
        |stand| hidden_by(ctx, (stand, shoulders), (them, their_shoulders)),
    )
    .map_err(|e| format!("no place to stand near {name}: {e}"))
}

/// How far out the standing points round an object go for a walk to it at `distance`
/// (see [`OBJECT_ROWS`], [`ACTOR_ROWS`]).
fn rows_round_an_object(distance: f64) -> f64 {
    if distance > GRASP_DISTANCE {
        ACTOR_ROWS
    } else {
        OBJECT_ROWS
    }
}

/// How far (m) from `actor`'s centre a walk of a body of `radius` asked to stand
/// `distance` from them stands: at least the two bodies' radii and [`LEAST_ACTOR_GAP`]
/// apart.
fn actor_distance(ctx: &GeneratorContext, radius: f64, actor: usize, distance: f64) -> f64 {
    let crowd = &ctx.world.crowd;
    let theirs = crowd.radii.get(actor).copied().unwrap_or(radius);
    // What the hands hold lengthens the body as the clearance sees it (see
    // `troupe_scene::bodies`): nearer than that reaches, the walk stood held by the other
    // for good (a cup carried to one asked for at 0.8 m).
    let mine = crowd
        .cores
        .get(ctx.actor)
        .map_or(radius, |core| radius.max(core.hands_ahead()));
    distance.max(mine + theirs + LEAST_ACTOR_GAP)
}

/// The first free standing point around `centre` (first on the side the body comes from,
/// then turning away from it both ways, then further out, up to `rows` metres) for a
/// body of `radius`, from which nothing is `hidden_by` an obstacle (see [`hidden_by`]), with the
/// path to it (a straight line when walks do not navigate) and the heading that faces
/// `centre`.
fn stand_near<'w>(
    ctx: &'w GeneratorContext,
    (start, companions, choice): (DVec2, &[usize], Choice),
    (centre, radius, rows): (DVec2, f64, f64),
    distance: impl Fn(DVec2) -> f64,
    hidden_by: impl Fn(DVec2) -> Option<&'w str>,
) -> Result<Planned, String> {
    let towards = (centre - start).try_normalize().unwrap_or(DVec2::Y);
    // The crowd's footprints are the world's obstacles, made once for every walk
    // (whether walks navigate or go straight).
    let obstacles = &ctx.world.crowd.footprints;
    let inflated = radius + troupe_scene::space::CLEARANCE;
    // Whether a body standing at `stand` would touch an obstacle. The crowd's grid gives
    // the footprints that may come that close (every one whose bounding circle does),
    // rather than measuring all of them (in the crowd benchmark, 500 footprints for each
    // standing point tried: 3 % of its instructions).
    let blocked = |stand: DVec2| {
        ctx.world
            .crowd
            .footprints_near(stand, inflated)
            .any(|o| o.distance(stand) < inflated)
    };
    // Those standing round the goal (not the walker's companions): a point where one
    // stands is taken, as long as another is free. Going to a point someone stands on,
    // the walk waited for them to leave it, and they (a waiter at the counter) waited
    // for it to let them by.
    let mut taken = people_standing(ctx, companions, radius);
    let mut last = String::from("every side is blocked");
    // What stood between the first free point and the goal, for the reason when no point
    // is left.
    let mut behind: Option<&str> = None;
    // The points tried, in order: out from the side the walker comes from, turning away
    // from it both ways in 15° steps, then a row further out; free of people first.
    let last_row = (rows / ROW_STEP).round() as usize;
    let points = [true, false].into_iter().flat_map(move |avoiding_people| {
        (0..=last_row).flat_map(move |further| {
            (0..=12).flat_map(move |turn| {
                [1.0, -1.0]
                    .into_iter()
                    .filter(move |&side| turn > 0 || side > 0.0)
                    .map(move |side| (avoiding_people, further, side * turn as f64 * PI / 12.0))
            })
        })
    });
    let candidates = points.map(|(avoiding_people, further, a)| {
        let (s, c) = a.sin_cos();
        let dir = DVec2::new(towards.x * c - towards.y * s, towards.x * s + towards.y * c);
        let out = further as f64 * ROW_STEP;
        let stand = centre - dir * (distance(dir) + out);
        (avoiding_people, out, stand, dir)
    });
    // In that order (the first free one is taken, the rest not even made), or those
    // free of people nearest the walker first, each metre further out than the first
    // ring counting as [`FURTHER_OUT`] metres to walk, then the rest as they were.
    // Near means round the centre, not through it: a free point across a crowd that
    // gathered round a performer is a walk round the crowd (in, through it, the walker
    // stood among those in the first row for good).
    let round_the_centre = |stand: DVec2| {
        let (from, to) = (start - centre, stand - centre);
        let turn = from.angle_to(to).abs();
        stand
            .distance(start)
            .max((from.length() - to.length()).abs() + from.length().min(to.length()) * turn)
    };
    let candidates: Box<dyn Iterator<Item = (bool, f64, DVec2, DVec2)>> = match choice {
        Choice::First => Box::new(candidates),
        Choice::Nearest => {
            let key = |&(people, out, stand, _): &(bool, f64, DVec2, DVec2)| {
                let walk = if people {
                    round_the_centre(stand) + FURTHER_OUT * out
                } else {
                    0.0
                };
                (!people, walk)
            };
            let mut all: Vec<_> = candidates.collect();
            all.sort_by(|a, b| {
                let (ka, kb) = (key(a), key(b));
                ka.0.cmp(&kb.0).then(ka.1.total_cmp(&kb.1))
            });
            Box::new(all.into_iter())
        }
    };
    for (avoiding_people, _, stand, dir) in candidates {
        if blocked(stand) || avoiding_people && taken(stand) {
            continue;
        }
        if let Some(obstacle) = hidden_by(stand) {
            behind.get_or_insert(obstacle);
            continue;
        }
        // Walks that do not navigate go there straight (see [`Walking`]).
        let path = match ctx.world.space.walking {
            Walking::Navigated => ctx.world.space.path(obstacles, start, stand, radius),
            Walking::Straight => Ok(vec![stand]),
        };
        match path {
            Ok(points) => {
                let n = points.len();
                return Ok(Planned {
                    points: points
                        .into_iter()
                        .enumerate()
                        .map(|(i, q)| (q, i + 1 < n))
                        .collect(),
                    heading: Some(dir.x.atan2(dir.y)),
                });
            }
            Err(e) => last = e.to_string(),
        }
    }
    match behind {
        Some(obstacle) if last == "every side is blocked" => {
            Err(format!("every side is blocked or behind {obstacle}"))
        }
        _ => Err(last),
    }
}

/// Whether a body of `radius` standing at a point would come within [`LEAST_ACTOR_GAP`]
/// of an actor standing now (slower than `STANDING`), other than the walker and its
/// `companions` (see `Steer::companions`).
pub fn people_standing<'w: 'c, 'c>(
    ctx: &GeneratorContext<'w>,
    companions: &'c [usize],
    radius: f64,
) -> impl FnMut(DVec2) -> bool + 'c {
    let crowd = ctx.world.crowd;
    let me = ctx.actor;
    let mut near = Vec::new();
    move |stand| {
        near.clear();
        // Everyone within a cell of the point (`Crowd::near`), far beyond any body.
        crowd.near(stand, &mut near);
        near.iter().any(|&j| {
            let (p, r) = (crowd.positions[j], crowd.radii[j]);
            j != me
                && !companions.contains(&j)
                && crowd.velocities[j].length() < STANDING
                && (p - stand).length() < radius + r + LEAST_ACTOR_GAP
        })
    }
}

/// The obstacle (a wall, furniture) that stands between a body at `stand` and the point
/// `target` (x, z) it would reach for at `height` (m), from its shoulders
/// `shoulders` m high: one that the straight reach from the shoulders to the point goes
/// through, not over, other than one the object rests on. A painting hung on one face of
/// a wall is not within reach from the other side, however near; a cup on a table is,
/// and one on a high cupboard too, from the cupboard's side. For a walk to an actor the
/// point is the other's shoulders: a wall between the two hides them, a table does not.
fn hidden_by<'w>(
    ctx: &'w GeneratorContext,
    (stand, shoulders): (DVec2, f64),
    (target, height): (DVec2, f64),
) -> Option<&'w str> {
    let crowd = &ctx.world.crowd;
    let length = (target - stand).length();
    // The crowd's grid holds the footprints near a point within its cell; a longer reach
    // (a `distance` the script set) looks at them all.
    let near: Box<dyn Iterator<Item = &Footprint>> = if length <= NEIGHBOUR_RANGE {
        Box::new(crowd.footprints_near(stand, length))
    } else {
        Box::new(crowd.footprints.iter())
    };
    // Just past the point, inside what the object stands on (the table under a cup): the
    // reach ends over it, however high. Not so a wall that a painting hangs flush on,
    // whose face the point lies on.
    let past = target + (target - stand).normalize_or_zero() * THROUGH;
    near.filter_map(|o| {
        if o.contains(past) {
            return None;
        }
        let (enter, leave) = o.span(stand, target)?;
        // Touching a face (a painting flush on its wall, seen from the front) is no
        // crossing: the reach must go a millimetre through.
        if (leave - enter) * length < THROUGH {
            return None;
        }
        // The reach goes down (or up) in a straight line: it is lowest over the obstacle
        // where it goes in or comes out.
        let at = |t: f64| shoulders + (height - shoulders) * t;
        (o.top > at(enter).min(at(leave))).then_some(o.name.as_str())
    })
    .next()
}

/// How far (m) a reach must go through an obstacle's footprint to count as through it.
const THROUGH: f64 = 0.001;

/// How high (m) the walker's shoulders are, as it stood at the end of the last tick: where
/// a reach for an object starts (the root's height for a body without shoulders).
fn shoulder_height(ctx: &GeneratorContext) -> f64 {
    shoulders_of(ctx.skeleton, &ctx.posture.globals)
}

/// How high (m) the shoulders of a body of `skeleton` are in the posture of `globals`
/// (the root's height for a body without shoulders).
fn shoulders_of(skeleton: &Skeleton, globals: &[Transform]) -> f64 {
    skeleton
        .joints()
        .iter()
        .zip(globals)
        .filter(|(j, _)| j.name.ends_with("shoulder"))
        .map(|(_, g)| g.translation.y)
        .reduce(f64::max)
        .unwrap_or_else(|| globals.first().map_or(0.0, |g| g.translation.y))
}

/// `points` with extra points [`CORNER_PIN`] before and after each corner the planner
/// made, so that the walk rounds such a corner only that close to it (the script's own
/// points are rounded as the walk always did).
fn pin_corners(start: DVec2, points: &[(DVec2, bool)]) -> Vec<(DVec2, bool)> {
    let mut out = Vec::with_capacity(points.len() * 3);
    let mut prev = start;
    for (i, &(p, planned)) in points.iter().enumerate() {
        match points.get(i + 1) {
            Some(&(next, _)) if planned => {
                let (before, after) = (p - prev, next - p);
                if before.length() > 2.0 * CORNER_PIN {
                    out.push((p - before.normalize() * CORNER_PIN, true));
                }
                out.push((p, true));
                if after.length() > 2.0 * CORNER_PIN {
                    out.push((p + after.normalize() * CORNER_PIN, true));
                }
            }
            _ => out.push((p, planned)),
        }
        prev = p;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_inside_an_actors_ring_is_moved_out_to_its_edge() {
        let ring = Ring {
            at: DVec2::new(1.0, 2.0),
            reach: 1.2,
            object: None,
        };
        let disc = Footprint::disc("ring", ring.at, ring.reach);
        let p = ring.at + DVec2::new(0.0, 1.0);
        let out = ring.out_of(&disc, p, 0.2).expect("inside");
        assert!(((p + out).distance(ring.at) - 1.4).abs() < 1e-12);
        assert!(out.x.abs() < 1e-12 && out.y > 0.0, "straight out: {out}");
        assert_eq!(
            ring.out_of(&disc, ring.at + DVec2::new(1.41, 0.0), 0.2),
            None
        );
    }

    #[test]
    fn a_point_inside_an_objects_ring_is_moved_out_beside_its_nearest_side() {
        // An object's ring is its footprint grown: here a 2 m × 1 m box's.
        let grown = Footprint::hull(
            "ring",
            &[
                DVec2::new(-1.0, -0.5),
                DVec2::new(1.0, -0.5),
                DVec2::new(1.0, 0.5),
                DVec2::new(-1.0, 0.5),
            ],
        );
        let ring = Ring {
            at: DVec2::ZERO,
            reach: 0.5,
            object: Some(0),
        };
        // Inside it, near its long side: out across that side, the disc just clear.
        let out = ring
            .out_of(&grown, DVec2::new(0.3, 0.4), 0.2)
            .expect("inside");
        assert!((out - DVec2::new(0.0, 0.3)).length() < 1e-12, "{out}");
        // Outside it but within the disc's radius: out to the radius.
        let out = ring
            .out_of(&grown, DVec2::new(1.1, 0.0), 0.2)
            .expect("touching");
        assert!((out - DVec2::new(0.1, 0.0)).length() < 1e-12, "{out}");
        assert_eq!(ring.out_of(&grown, DVec2::new(1.3, 0.0), 0.2), None);
        // On the outline itself: out across that side too.
        let out = ring
            .out_of(&grown, DVec2::new(1.0, 0.2), 0.2)
            .expect("on the outline");
        assert!((out - DVec2::new(0.2, 0.0)).length() < 1e-9, "{out}");
    }
}
