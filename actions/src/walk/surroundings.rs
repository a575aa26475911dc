//! What a walk's clearance sees round its body each tick (`troupe_nav::clearance`): the
//! other bodies (the crowd's capsules, which hold their feet) and the obstacles near, from
//! the previous tick's world, gathered once per tick for the body's step and the feet's
//! landings.

use super::rig::Leg;
use super::route::direction;
use troupe_body::glam::DVec2;
use troupe_scene::bodies::FOOT_RADIUS;
use troupe_scene::space::{Capsule, FootSpan, FootprintsAround, Surroundings};
use troupe_scene::GeneratorContext;

/// How far (m) past the touching of two bodies' discs a neighbour (or past the body's
/// reach an obstacle) is looked at: a step and two strides.
const RANGE: f64 = 1.0;
/// How far (m) a body's feet may stand out of its disc, along the way it faces.
const FEET_OUT: f64 = 0.6;

/// The lists of the bodies and feet round a walk, kept from one tick to the next so that
/// gathering them does not allocate (with the footprints' list, kept likewise, about
/// 2,000 instructions an actor-tick of the crowd benchmark).
#[derive(Clone, Debug, Default)]
pub struct Lists {
    /// The bodies' list.
    bodies: Vec<Capsule>,
    /// Their velocities' list.
    velocities: Vec<DVec2>,
    /// The feet's list.
    feet: Vec<FootSpan>,
    /// The obstacles' circles' list.
    bounds: Vec<(DVec2, f64)>,
    /// The actors near whose bodies and feet were gathered this tick, in actor order.
    close: Vec<usize>,
}

impl Lists {
    /// Takes back the lists `around` was gathered in, for the next tick.
    pub fn keep(&mut self, around: Surroundings) {
        self.bodies = around.bodies;
        self.velocities = around.velocities;
        self.feet = around.feet;
        self.bounds = around.bounds;
    }

    /// The actors near whose bodies and feet this tick's surroundings hold (every one the
    /// crowd found whose reach, feet out, comes within `RANGE` of the body's), in actor
    /// order.
    pub fn close(&self) -> &[usize] {
        &self.close
    }
}

/// The surroundings of actor `ctx.actor` this tick, leaving out `companions` (a hand
/// held), gathered in `lists` (give them back with [`Lists::keep`]). `near` holds the
/// actors near when `gathered` (the steering found them this tick); else it is filled
/// here. Either way it then holds every actor the crowd finds near the body.
/// `footprints` are the obstacles round the body.
pub fn gather<'a>(
    ctx: &GeneratorContext<'a>,
    companions: &[usize],
    (near, gathered): (&mut Vec<usize>, bool),
    footprints: &FootprintsAround<'a>,
    lists: &mut Lists,
) -> Surroundings<'a> {
    let crowd = ctx.world.crowd;
    let me = ctx.actor;
    let mut around = Surroundings {
        bodies: std::mem::take(&mut lists.bodies),
        velocities: std::mem::take(&mut lists.velocities),
        feet: std::mem::take(&mut lists.feet),
        obstacles: Default::default(),
        bounds: std::mem::take(&mut lists.bounds),
    };
    around.bodies.clear();
    around.velocities.clear();
    around.feet.clear();
    around.bounds.clear();
    lists.close.clear();
    let (Some(&from), Some(&radius)) = (crowd.positions.get(me), crowd.radii.get(me)) else {
        return around;
    };
    let reach = radius + FEET_OUT;
    if !gathered {
        near.clear();
        crowd.near(from, near);
    }
    for &j in near.iter() {
        if j == me || companions.contains(&j) {
            continue;
        }
        if (crowd.positions[j] - from).length() - reach - crowd.radii[j] - FEET_OUT > RANGE {
            continue;
        }
        lists.close.push(j);
        if let Some(&body) = crowd.bodies.get(j) {
            around.bodies.push(body);
            around
                .velocities
                .push(crowd.velocities.get(j).copied().unwrap_or_default());
        }
        if let Some(Some(feet)) = crowd.soles.get(j) {
            around.feet.extend(feet);
        }
    }
    for (footprint, bound) in footprints.within_bounded(reach + RANGE) {
        around.obstacles.push(footprint);
        around.bounds.push(bound);
    }
    around
}

/// The span of `leg`'s foot planted with the point under its ankle at `plant`, heading
/// `yaw`.
pub fn foot_span(leg: &Leg, plant: DVec2, yaw: f64) -> FootSpan {
    let forward = direction(yaw);
    FootSpan {
        heel: plant + forward * leg.heel.z,
        toe: plant + forward * (leg.ball.z + leg.toe_sole.z),
        radius: FOOT_RADIUS,
    }
}
