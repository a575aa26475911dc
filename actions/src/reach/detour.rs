//! Temporary goals round other bodies (thesis 4.6.3, after Zhao and Badler): when the
//! straight path of a reaching hand would pass through another actor's body or an
//! obstacle, a temporary goal outside it is inserted where the path went deepest, and
//! again on the new segments until the path is clear (at most [`MAX_DETOURS`]). The
//! volumes are those of the world the reach starts in (the previous tick's); while the
//! reach runs, the path point is also pushed out of the volumes as they stand each tick,
//! and the arm's sensors are kept out of them by the IK's secondary task
//! ([`troupe_body::self_collision::CollisionAvoidance::with_external`]).

use troupe_body::collision::{Volume, VolumesAround};
use troupe_body::glam::DVec3;
use troupe_body::self_collision::{BodySensors, SENSOR_SCALE};
use troupe_body::{Skeleton, Transform};
use troupe_scene::space::Walking;
use troupe_scene::World;

use super::quintic;

/// Most temporary goals a reach inserts.
pub const MAX_DETOURS: usize = 4;
/// How far outside a volume a temporary goal puts the hand's surface (m).
pub const DETOUR_CLEARANCE: f64 = 0.04;
/// Another actor counts when its root is within this distance (m) of the reach's start
/// or goal; an obstacle when a sphere round it is.
const NEAR: f64 = 2.5;
/// Path samples are this far apart (m).
const SAMPLE: f64 = 0.01;

/// What a reach by actor `me` must keep its hand out of: the bodies of the other actors
/// and the obstacles near its start or `goal` (see `NEAR`); less every volume that a
/// sphere of `radius` at the goal already enters (the hand is meant to end there: a
/// partner's hand in a hand-over, the table under a cup).
pub fn volumes_around(
    world: &World,
    me: usize,
    start: DVec3,
    goal: DVec3,
    radius: f64,
) -> Vec<Volume> {
    volumes_around_except(world, me, start, goal, radius, None)
}

/// [`volumes_around`], leaving out the obstacle called `except` as well (the object a
/// grasp is reaching for: the hand is meant to touch it).
pub fn volumes_around_except(
    world: &World,
    me: usize,
    start: DVec3,
    goal: DVec3,
    radius: f64,
    except: Option<&str>,
) -> Vec<Volume> {
    let mut out = Vec::new();
    // Where walks do not keep bodies apart, hands do not go round them either (see
    // `Walking::Straight`: bodies stand in one another there).
    if world.space.walking == Walking::Straight {
        return out;
    }
    for (j, state) in world.states.iter().enumerate() {
        let root = state.globals.first().map_or(DVec3::ZERO, |g| g.translation);
        let near = |p: DVec3| (root.x - p.x).hypot(root.z - p.z) < NEAR;
        if j != me && (near(start) || near(goal)) {
            out.extend(world.body_capsules(j).into_iter().map(Volume::Capsule));
        }
    }
    // Obstacles as near as the actors that count: among many (a field of pillars) the
    // reach tested them all, every tick, each IK iteration, for each arm sensor.
    out.extend(
        world
            .obstacle_volumes_near(&[start, goal], NEAR)
            .into_iter()
            .filter(|(name, _)| Some(name.as_str()) != except)
            .map(|(_, v)| v),
    );
    out.retain(|v| v.sphere_depth(goal, radius) <= 0.0);
    out
}

/// Moves a sphere (centre `p`, `radius`) out of every volume until its surface is
/// `clearance` outside each (a few rounds: leaving one may enter another).
pub fn push_out(p: DVec3, radius: f64, clearance: f64, volumes: &[Volume]) -> DVec3 {
    push_out_of(p, radius, clearance, &VolumesAround::new(volumes))
}

/// [`push_out`] out of volumes whose bounds are found.
fn push_out_of(p: DVec3, radius: f64, clearance: f64, around: &VolumesAround) -> DVec3 {
    let mut q = p;
    for _ in 0..8 {
        let mut moved = false;
        for k in 0..around.volumes.len() {
            // The point moves as it is pushed: each volume is judged from where it is.
            if !around.may_reach(k, q, radius, clearance) {
                continue;
            }
            let pen = around.volumes[k].sphere(q, radius);
            if pen.depth > -clearance {
                q += pen.normal * (pen.depth + clearance);
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
    q
}

/// A hand's path from its start through via points to a goal, each segment travelled
/// with the [`quintic`] ease, its share of the duration proportional to its length as
/// the path was planned (the goal may move afterwards: the last segment follows it).
#[derive(Clone, Debug, Default)]
pub struct HandPath {
    start: DVec3,
    via: Vec<DVec3>,
    lengths: Vec<f64>,
}

impl HandPath {
    /// The path from `start` through `via` to `goal` (where the goal is now).
    pub fn new(start: DVec3, via: Vec<DVec3>, goal: DVec3) -> HandPath {
        let mut prev = start;
        let mut lengths = Vec::with_capacity(via.len() + 1);
        for p in via.iter().chain(std::iter::once(&goal)) {
            lengths.push((*p - prev).length());
            prev = *p;
        }
        HandPath {
            start,
            via,
            lengths,
        }
    }

    /// Where the path starts.
    pub fn start(&self) -> DVec3 {
        self.start
    }

    /// The via points, temporary goals included.
    pub fn via(&self) -> &[DVec3] {
        &self.via
    }

    /// The point at `tau` (0 to 1, the fraction of the duration) for the goal now at
    /// `goal`.
    pub fn at(&self, tau: f64, goal: DVec3) -> DVec3 {
        if self.lengths.iter().sum::<f64>() <= 1e-12 || self.via.is_empty() {
            return self.start.lerp(goal, quintic(tau.clamp(0.0, 1.0)));
        }
        let (i, local) = self.segment(tau);
        let point = |i: usize| match i {
            0 => self.start,
            i if i <= self.via.len() => self.via[i - 1],
            _ => goal,
        };
        point(i).lerp(point(i + 1), quintic(local))
    }

    /// Which segment the path is on at `tau` (0 to 1) and how far along it (0 to 1,
    /// before the ease); the last segment ends at the goal.
    pub fn segment(&self, tau: f64) -> (usize, f64) {
        let tau = tau.clamp(0.0, 1.0);
        let total: f64 = self.lengths.iter().sum();
        if total <= 1e-12 || self.via.is_empty() {
            return (self.via.len(), tau);
        }
        let mut begin = 0.0;
        for (i, len) in self.lengths.iter().enumerate() {
            let share = len / total;
            if tau <= begin + share || i + 1 == self.lengths.len() {
                let local = if share > 0.0 {
                    (tau - begin) / share
                } else {
                    1.0
                };
                return (i, local);
            }
            begin += share;
        }
        (self.via.len(), 1.0)
    }
}

/// The deepest point of the polyline `points` for a sphere of `radius` into the volumes
/// `around`: the segment's index, the point and the depth; `None` when it stays clear.
fn deepest(points: &[DVec3], radius: f64, around: &VolumesAround) -> Option<(usize, DVec3, f64)> {
    let mut best: Option<(usize, DVec3, f64)> = None;
    for (seg, pair) in points.windows(2).enumerate() {
        let n = ((pair[1] - pair[0]).length() / SAMPLE).ceil().max(1.0) as usize;
        for k in 0..=n {
            let p = pair[0].lerp(pair[1], k as f64 / n as f64);
            for v in around.near(p, radius, 0.0) {
                let depth = v.sphere_depth(p, radius);
                if depth > 0.0 && best.is_none_or(|b| depth > b.2) {
                    best = Some((seg, p, depth));
                }
            }
        }
    }
    best
}

/// The arm a reaching hand hangs from, so that a temporary goal keeps the arm as well as
/// the hand out of what it goes round.
#[derive(Clone, Copy, Debug)]
pub struct Arm {
    /// The shoulder's centre when the reach starts.
    pub shoulder: DVec3,
    /// The arm's radius: the upper arm's, a quarter of the way from the shoulder.
    pub radius: f64,
}

impl Arm {
    /// The arm that effector joint `hand` ends, in joint frames `globals`: its shoulder is
    /// the nearest ancestor called `…shoulder`, its radius the upper arm's sensor's at full
    /// size. `None` for an effector that is not on an arm.
    pub fn of(
        skeleton: &Skeleton,
        sensors: &BodySensors,
        hand: usize,
        globals: &[Transform],
    ) -> Option<Arm> {
        let joints = skeleton.joints();
        let shoulder = std::iter::successors(Some(hand), |&j| joints[j].parent)
            .find(|&j| joints[j].name.ends_with("shoulder"))?;
        let side = joints[shoulder].name.strip_suffix("shoulder")?;
        let sensor = sensors.index_of(&format!("{side}upper_arm_25"))?;
        Some(Arm {
            shoulder: globals[shoulder].translation,
            radius: sensors.sensors()[sensor].radius / SENSOR_SCALE,
        })
    }
}

/// Where along the line from the shoulder to the hand the arm is sampled: the elbow's
/// region and the forearm (the hand has its own sphere; nearer the shoulder the line
/// hardly moves).
const ARM_SAMPLES: [f64; 5] = [0.35, 0.5, 0.65, 0.8, 0.9];

/// Directions round the hand's path a temporary goal is looked for in, when the arm
/// decides between them.
const DIRECTIONS: usize = 8;

/// How far from the path's deepest point a temporary goal is looked for (m).
const FARTHEST: f64 = 0.6;

/// The deepest an arm held straight from `arm.shoulder` to the hand goes into the volumes
/// `around` while the hand goes along the polyline `points` (0 when it stays clear): a
/// straight line stands for the arm, so a hand that passes in front of another's arm from
/// behind it shows the forearm trailing across.
fn arm_depth(points: &[DVec3], arm: Arm, around: &VolumesAround) -> f64 {
    let mut worst = 0.0f64;
    for pair in points.windows(2) {
        let n = ((pair[1] - pair[0]).length() / (2.0 * SAMPLE))
            .ceil()
            .max(1.0) as usize;
        for k in 0..=n {
            let hand = pair[0].lerp(pair[1], k as f64 / n as f64);
            for s in ARM_SAMPLES {
                let p = arm.shoulder.lerp(hand, s);
                for v in around.near(p, arm.radius, 0.0) {
                    worst = worst.max(v.sphere_depth(p, arm.radius));
                }
            }
        }
    }
    worst
}

/// A temporary goal for the path's deepest point `p` on segment `a`–`b`: pushed out of
/// the volumes `around` along their normals; or, when an `arm` would cross a volume that
/// way, the nearest clear point in one of [`DIRECTIONS`] round the segment that keeps
/// the arm out (or in least), the shortest of those that do.
fn temporary_goal(
    (a, b): (DVec3, DVec3),
    p: DVec3,
    radius: f64,
    around: &VolumesAround,
    arm: Option<Arm>,
) -> DVec3 {
    let pushed = push_out_of(p, radius, DETOUR_CLEARANCE, around);
    let Some(arm) = arm else {
        return pushed;
    };
    let cost = |q: DVec3| {
        let depth = arm_depth(&[a, q, b], arm, around);
        // Millimetres: below that two ways are as good, and the shorter wins.
        (
            (depth * 1000.0).round(),
            (q - a).length() + (b - q).length(),
        )
    };
    let normal_way = cost(pushed);
    if normal_way.0 == 0.0 {
        return pushed;
    }
    let along = (b - a).normalize_or(DVec3::Y);
    let e1 = along.any_orthonormal_vector();
    let e2 = along.cross(e1);
    let clear = |q: DVec3| {
        around
            .near(q, radius, DETOUR_CLEARANCE)
            .all(|v| v.sphere_depth(q, radius) <= -DETOUR_CLEARANCE)
    };
    let mut best = (normal_way, pushed);
    for k in 0..DIRECTIONS {
        let angle = std::f64::consts::TAU * k as f64 / DIRECTIONS as f64;
        let d = e1 * angle.cos() + e2 * angle.sin();
        let steps = (FARTHEST / SAMPLE) as usize;
        let Some(q) = (1..=steps)
            .map(|m| p + d * (m as f64 * SAMPLE))
            .find(|&q| clear(q))
        else {
            continue;
        };
        let c = cost(q);
        if c.0 < best.0 .0 || (c.0 == best.0 .0 && c.1 < best.0 .1) {
            best = (c, q);
        }
    }
    best.1
}

/// The via points of a hand (a sphere of `radius`) going from `start` through `via` to
/// `goal` with the temporary goals that keep it out of `volumes` inserted; `via` as given
/// when the straight path is clear. With the `arm` the hand hangs from, each temporary
/// goal also keeps the arm out where it can (see `temporary_goal`).
pub fn temporary_goals(
    start: DVec3,
    via: &[DVec3],
    goal: DVec3,
    radius: f64,
    volumes: &[Volume],
    arm: Option<Arm>,
) -> Vec<DVec3> {
    let mut points: Vec<DVec3> = std::iter::once(start)
        .chain(via.iter().copied())
        .chain(std::iter::once(goal))
        .collect();
    let around = VolumesAround::new(volumes);
    for _ in 0..MAX_DETOURS {
        let Some((seg, p, _)) = deepest(&points, radius, &around) else {
            break;
        };
        let q = temporary_goal((points[seg], points[seg + 1]), p, radius, &around, arm);
        if (q - p).length() < 1e-6 {
            break;
        }
        points.insert(seg + 1, q);
    }
    points[1..points.len() - 1].to_vec()
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::collision::Capsule;

    #[test]
    fn a_hand_path_stops_at_each_via_point_and_follows_the_goal() {
        let (start, via, goal) = (
            DVec3::ZERO,
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 3.0, 0.0),
        );
        let path = HandPath::new(start, vec![via], goal);
        assert_eq!(path.at(0.0, goal), start);
        // The first segment is a quarter of the length: a quarter of the time.
        assert_eq!(path.segment(0.25), (0, 1.0));
        assert!((path.at(0.25, goal) - via).length() < 1e-12);
        assert_eq!(path.segment(0.625).0, 1);
        assert!((path.at(0.625, goal) - DVec3::new(1.0, 1.5, 0.0)).length() < 1e-12);
        // The goal moved: the last segment ends where it is now.
        let moved = DVec3::new(2.0, 3.0, 0.0);
        assert!((path.at(1.0, moved) - moved).length() < 1e-12);
        // Without via points: one eased segment.
        let straight = HandPath::new(start, Vec::new(), goal);
        assert_eq!(straight.segment(0.3), (0, 0.3));
        assert!((straight.at(0.5, goal) - goal * 0.5).length() < 1e-12);
    }

    #[test]
    fn a_path_through_an_arm_gets_a_temporary_goal_beside_it() {
        // An arm lying along x at (y 1.45, z 0.3); the hand goes from below it to above.
        let arm = Volume::Capsule(Capsule {
            a: DVec3::new(-0.7, 1.45, 0.3),
            b: DVec3::new(-0.1, 1.45, 0.3),
            ra: 0.04,
            rb: 0.03,
        });
        let start = DVec3::new(-0.3, 0.9, 0.2);
        let goal = DVec3::new(-0.3, 1.8, 0.4);
        let via = temporary_goals(start, &[], goal, 0.05, &[arm], None);
        assert!(!via.is_empty());
        let mut points = vec![start];
        points.extend(&via);
        points.push(goal);
        assert!(
            deepest(&points, 0.05, &VolumesAround::new(&[arm])).is_none(),
            "{points:?}"
        );
        // A clear path is left alone.
        let clear = temporary_goals(start, &[], DVec3::new(0.5, 1.8, 0.4), 0.05, &[arm], None);
        assert!(clear.is_empty(), "{clear:?}");
    }

    #[test]
    fn a_hand_going_over_an_arm_takes_its_own_arm_over_too() {
        // Another's arm straight across in front of the chest (z 0.3, below the
        // shoulder); the hand starts low and a little forward, and ends above it.
        let other = Volume::Capsule(Capsule {
            a: DVec3::new(-0.6, 1.3, 0.3),
            b: DVec3::new(0.2, 1.3, 0.3),
            ra: 0.045,
            rb: 0.035,
        });
        let arm = Arm {
            shoulder: DVec3::new(-0.2, 1.43, 0.0),
            radius: 0.045,
        };
        let start = DVec3::new(-0.23, 0.95, 0.28);
        let goal = DVec3::new(-0.25, 1.7, 0.4);
        let path = |via: Vec<DVec3>| {
            let mut points = vec![start];
            points.extend(via);
            points.push(goal);
            points
        };
        // Pushed out along the arm's normal, the hand clears it but passes in front of it
        // from behind: the line from the shoulder crosses it.
        let pushed = path(temporary_goals(start, &[], goal, 0.05, &[other], None));
        let around = VolumesAround::new(std::slice::from_ref(&other));
        assert!(deepest(&pushed, 0.05, &around).is_none(), "{pushed:?}");
        let trailing = arm_depth(&pushed, arm, &around);
        assert!(trailing > 0.03, "{trailing}");
        // With the arm known, the temporary goal keeps the hand behind the other's arm
        // until it is above it.
        let over = path(temporary_goals(start, &[], goal, 0.05, &[other], Some(arm)));
        assert!(deepest(&over, 0.05, &around).is_none(), "{over:?}");
        assert_eq!(arm_depth(&over, arm, &around), 0.0, "{over:?}");
    }
}
