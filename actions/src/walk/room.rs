//! Room for the feet among other walkers: a stepping foot lands half a stride ahead of
//! the body, past the disc that avoidance keeps clear, so two walkers that meet head-on
//! could put their feet on the same spot. Each walker keeps its landings on its own side
//! of the line halfway between it and every neighbour (the bisector of their roots, from
//! the previous tick's crowd), a [`FOOT_GAP`] short of it: both sides read the same
//! line, so their feet never meet, whatever the thread count. A neighbour's feet and
//! shanks already down past that line (planted before the two came close) are kept clear
//! too: a landing steps round them.

use super::rig::Leg;
use troupe_body::glam::DVec2;
use troupe_scene::GeneratorContext;

/// Neighbours whose roots are within this distance (m) fence the feet.
pub const FENCE_RANGE: f64 = 1.6;
/// How far short of the bisector a foot's heel and toe stay (m): the foot solid's radius
/// (4.2 cm for an adult) and a margin.
pub const FOOT_GAP: f64 = 0.055;

/// The half-plane a walker's feet keep to: the points `p` with `(p − mid)·normal ≤
/// −FOOT_GAP`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fence {
    /// Halfway between the two roots.
    pub mid: DVec2,
    /// Unit vector from this walker towards the neighbour.
    pub normal: DVec2,
}

/// A neighbour's foot or shank seen from above: a floor segment and its radius.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Limb {
    /// One end (x, z).
    pub a: DVec2,
    /// The other end.
    pub b: DVec2,
    /// Its radius (m).
    pub radius: f64,
}

/// What a walker's feet keep clear of this tick.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Room {
    /// One half-plane per neighbour.
    pub fences: Vec<Fence>,
    /// The neighbours' feet and shanks.
    pub limbs: Vec<Limb>,
}

/// Refills `room` for actor `ctx.actor` (its `companions` left out) from the previous
/// tick's world.
pub fn survey(ctx: &GeneratorContext, companions: &[usize], room: &mut Room) {
    room.fences.clear();
    room.limbs.clear();
    let out = &mut room.fences;
    let crowd = ctx.world.crowd;
    let Some(&me) = crowd.positions.get(ctx.actor) else {
        return;
    };
    let mut near = Vec::new();
    crowd.near(me, &mut near);
    for j in near {
        if j == ctx.actor || companions.contains(&j) {
            continue;
        }
        let apart = crowd.positions[j] - me;
        let d = apart.length();
        if d < FENCE_RANGE && d > 1e-6 {
            out.push(Fence {
                mid: me + apart / 2.0,
                normal: apart / d,
            });
            let solids = ctx.world.actors[j].skeleton.solids();
            let capsules = ctx.world.body_capsules(j);
            let flat = |p: troupe_body::glam::DVec3| DVec2::new(p.x, p.z);
            room.limbs.extend(
                capsules
                    .iter()
                    .zip(solids)
                    .filter(|(_, (_, s))| s.name.ends_with("foot") || s.name.ends_with("_leg"))
                    .map(|(c, _)| Limb {
                        a: flat(c.a),
                        b: flat(c.b),
                        radius: c.ra.max(c.rb),
                    }),
            );
        }
    }
}

/// Moves the floor point `plant` of a foot (of `leg`, heading `yaw`) back inside `room`:
/// its heel, ball and toe tip end at least [`FOOT_GAP`] short of each bisector, and as
/// far from the neighbours' feet and shanks.
pub fn keep_inside(plant: DVec2, yaw: f64, leg: &Leg, room: &Room) -> DVec2 {
    let forward = DVec2::new(yaw.sin(), yaw.cos());
    let left = DVec2::new(yaw.cos(), -yaw.sin());
    let at = |x: f64, z: f64| left * x + forward * z;
    let toe = leg.ball + leg.toe_sole;
    let ends = [
        at(leg.heel.x, leg.heel.z),
        at(leg.ball.x, leg.ball.z),
        at(toe.x, toe.z),
    ];
    let mut p = plant;
    // A few passes: pushing out of one fence or limb may cross another.
    for _ in 0..3 {
        for f in &room.fences {
            let over = ends
                .iter()
                .map(|e| (p + *e - f.mid).dot(f.normal) + FOOT_GAP)
                .fold(f64::NEG_INFINITY, f64::max);
            if over > 0.0 {
                p -= f.normal * over;
            }
        }
        for limb in &room.limbs {
            for e in &ends {
                let q = p + *e;
                let ab = limb.b - limb.a;
                let t = ((q - limb.a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
                let off = q - (limb.a + ab * t);
                let over = limb.radius + FOOT_GAP - off.length();
                if over > 0.0 {
                    p += off.try_normalize().unwrap_or(-forward) * over;
                }
            }
        }
    }
    p
}
