//! Lanes in counter-flows (Helbing's keep-right bias, as Recast/Detour's crowd and
//! Unreal's Mass avoidance bias theirs): where two or more walkers face a walker from
//! ahead on its way, it keeps to the right of its plan, where its sidesteps put it,
//! instead of being pulled back onto the plan's line into the oncoming walkers; two
//! streams then pass each other in lanes. Beside furniture the walk keeps to its plan,
//! which keeps clear of it. See `docs/navigation.md`, "The plaza".

use troupe_body::glam::DVec2;
use troupe_scene::space::FootprintsAround;
use troupe_scene::GeneratorContext;

/// Sideways speed (m/s, to the right) a walker keeps in a counter-flow.
const LANE_BIAS: f64 = 0.15;
/// Furthest (m) a walker keeps to the right of its plan in a counter-flow.
const LANE_WIDTH: f64 = 0.5;
/// Gap (m) to an obstacle within which a walker keeps no lane.
const LANE_CLEARANCE: f64 = 1.0;
/// Distance (m) ahead within which walkers facing me make a counter-flow.
const ONCOMING_RANGE: f64 = 4.0;
/// Half the width (m) of my way in which they count.
const ONCOMING_WIDTH: f64 = 1.2;
/// Largest cosine between my way and the way an oncoming walker faces (25° off
/// head-on): a counter-flow, not walkers converging from several sides (eight on a
/// circle swapping places meet at 45° steps, and lanes there pushed bodies together).
const ONCOMING_COS: f64 = -0.9;

/// Whether actor `ctx.actor` at `position`, going along the unit `along`, walks in a
/// counter-flow: two or more others face it within `ONCOMING_RANGE` ahead on its way
/// (walking towards it or waiting to), and no obstacle is within `LANE_CLEARANCE`.
/// `around` are the actors the crowd finds near `position` (`Crowd::near`), which the
/// steering gathers once a tick for this and for avoidance, and `footprints` the
/// obstacles round it.
pub fn in_counter_flow(
    ctx: &GeneratorContext,
    position: DVec2,
    along: DVec2,
    (around, footprints): (&[usize], &FootprintsAround),
) -> bool {
    let crowd = ctx.world.crowd;
    let radius = crowd.radii.get(ctx.actor).copied().unwrap_or(0.0);
    if footprints
        .within(radius + LANE_CLEARANCE)
        .any(|f| f.distance(position) < radius + LANE_CLEARANCE)
    {
        return false;
    }
    let facing_me = around.iter().filter(|&&j| {
        let o = crowd.positions[j] - position;
        let ahead = o.dot(along);
        j != ctx.actor
            && ahead > 0.0
            && ahead < ONCOMING_RANGE
            && along.perp_dot(o).abs() < ONCOMING_WIDTH
            && crowd
                .facings
                .get(j)
                .is_some_and(|f| f.dot(along) < ONCOMING_COS)
    });
    // One walker head-on is passed by plain avoidance; two or more make a flow.
    facing_me.count() >= 2
}

/// The velocity a walker in a counter-flow would like: its `planned` one, the part of
/// its `offset` from the plan that lies outside the lane (0 to `LANE_WIDTH` to the
/// right of `along`) returning at `gain`, and a drift to the right of `LANE_BIAS`
/// that fades as the lane's edge nears.
pub fn preferred(planned: DVec2, offset: DVec2, along: DVec2, gain: f64) -> DVec2 {
    let right = along.perp();
    let kept = offset.dot(right).clamp(0.0, LANE_WIDTH);
    let room = ((LANE_WIDTH - kept) / 0.2).min(1.0);
    planned - (offset - right * kept) * gain + right * LANE_BIAS * room
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lane_keeps_a_sidestep_to_the_right_and_returns_the_rest() {
        let along = DVec2::Y; // walking +z: the right is −x
        let planned = DVec2::new(0.0, 1.3);
        let right = along.perp();
        assert_eq!(right, DVec2::new(-1.0, 0.0));
        // On the plan: drift right.
        let v = preferred(planned, DVec2::ZERO, along, 0.8);
        assert!((v - (planned + right * LANE_BIAS)).length() < 1e-12, "{v}");
        // Halfway into the lane: kept, still drifting right.
        let v = preferred(planned, right * 0.2, along, 0.8);
        assert!((v - (planned + right * LANE_BIAS)).length() < 1e-12, "{v}");
        // At the lane's edge: kept, no more drift.
        let v = preferred(planned, right * LANE_WIDTH, along, 0.8);
        assert!((v - planned).length() < 1e-12, "{v}");
        // Beyond it, or to the left: back towards the lane.
        let v = preferred(planned, right * 0.9, along, 0.8);
        assert!(v.dot(right) < 0.0, "{v}");
        let v = preferred(planned, -right * 0.3, along, 0.8);
        assert!(v.dot(right) > 0.0, "{v}");
    }
}
