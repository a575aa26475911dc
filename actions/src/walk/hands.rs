//! Free hands kept off the furniture: a hand that holds nothing hangs and swings where the
//! gait puts it, and beside a stand or a table it can come down into it, most of all when
//! the walk stops and the elbows straighten (a waiter waiting at an aisle's mouth beside
//! the stand she took her tray from had her free hand 2.2 cm in it). The body's disc
//! keeps the trunk off the furniture (see `troupe_nav::clearance`); this keeps the arm.
//!
//! Each tick, for each arm that holds nothing and that the walk moves, the upper arm,
//! forearm and hand (the capsules covering their solids) are measured against the
//! obstacles near, each a prism from the floor to its top over its footprint. Where one
//! comes within [`HAND_MARGIN`] of an obstacle, the least change of the shoulder's flexion
//! and abduction and the elbow's flexion that takes it out is found (a few Gauss–Newton
//! steps on the deepest point, from the last tick's change); the arm moves towards it
//! by at most [`OUT_RATE`], and back to the gait's own values by at most [`BACK_RATE`]
//! once it is out of the way by a centimetre more. It reads the previous tick's posture
//! for what it skips, and this tick's values for what it computes, so it is the same
//! whatever the thread count.

use troupe_body::collision::Capsule;
use troupe_body::glam::{DVec2, DVec3};
use troupe_body::jacobian::chain_dofs;
use troupe_body::kinematics::joint_frame;
use troupe_body::{Skeleton, Transform};
use troupe_scene::space::{Footprint, Surroundings};
use troupe_scene::GeneratorContext;

/// How far (m) a free arm keeps from an obstacle's sides and top.
pub const HAND_MARGIN: f64 = 0.015;
/// An arm further than this (m) from every obstacle on the last tick, and at the gait's
/// own values, is not looked at: no arm moves that far in a tick.
const LOOKED_AT: f64 = 0.1;
/// The body (the crowd's capsule, see `troupe_nav::clearance::Body`) this far (m) or
/// further from every obstacle, and its arms at the gait's own values, has no arm
/// looked at: a free hand stands out of the capsule towards an obstacle by a few
/// centimetres at most (the capsule holds the wrists as far out as they were on the
/// last tick; measured with the arms left at the gait's values, 2.4 cm in the scenario
/// tests, 5.0 cm in the crowd benchmark), so its arms are [`LOOKED_AT`] or more from
/// any obstacle. In a crowd among pillars, most ticks of a walker near one end here.
const BODY_CLEAR: f64 = 0.15;
/// Largest change (radians per second) of each DOF's departure from the gait as it takes
/// the arm out of an obstacle: a body turning on the spot sweeps a hanging hand round
/// at up to a metre a second, and at 1.5 rad/s a hand swept against a shelf so touched
/// it (0.8 mm); at this rate it keeps off.
pub const OUT_RATE: f64 = 4.0;
/// Largest change (radians per second) of each DOF's departure as the arm goes back to
/// the gait's values.
pub const BACK_RATE: f64 = 1.5;
/// How much further (m) than [`HAND_MARGIN`] an arm held out of an obstacle must stay
/// clear for it to step back towards the gait's values: without it, an arm at the margin
/// stepped back and was pushed out again on alternate ticks.
const HYSTERESIS: f64 = 0.01;
/// Gauss–Newton steps per tick.
const STEPS: usize = 4;
/// How much each DOF (shoulder flexion, shoulder abduction, elbow flexion) is asked to
/// move against the others: the abduction least, since bringing an arm in takes the hand
/// to the thigh.
const WEIGHTS: [f64; 3] = [1.0, 0.3, 1.0];
/// Step (radians) of the numerical derivatives.
const H: f64 = 1e-4;

/// One arm's kinematic chain, from the root down to the wrist.
#[derive(Clone, Debug)]
struct Arm {
    /// The joints from the root to the wrist.
    chain: Vec<usize>,
    /// Where in `chain` the shoulder is: the joints above it do not move with the DOFs
    /// changed here.
    shoulder: usize,
    /// The upper arm's, forearm's and hand's capsules, each with its joint's place in
    /// `chain`.
    volumes: Vec<(usize, Capsule)>,
    /// Shoulder flexion, shoulder abduction, elbow flexion.
    dofs: [usize; 3],
    /// Every DOF of the chain's joints (`jacobian::chain_dofs`).
    chain_dofs: Vec<usize>,
    /// From the shoulder to the far side of the hand (m): how far the arm reaches.
    reach: f64,
}

/// The free arms' departures from the gait, and the scratch their measure uses.
#[derive(Clone, Debug, Default)]
pub struct FreeHands {
    /// Left and right, found on the first tick (fewer than two for a body without arms,
    /// which has none kept off).
    arms: Option<Vec<Arm>>,
    /// Each arm's departure from the gait's values (shoulder flexion, shoulder
    /// abduction, elbow flexion), as applied on the last tick.
    offsets: [[f64; 3]; 2],
    /// Scratch: the posture this tick.
    q: Vec<f64>,
    /// Scratch: the chain's frames.
    frames: Vec<Transform>,
    /// Scratch: the obstacles near an arm.
    near: Vec<usize>,
}

impl Arm {
    /// The `prefix` (`l_`, `r_`) arm of `skeleton`, whose gait DOFs are `dofs` (shoulder
    /// flexion, abduction, elbow flexion).
    fn of(skeleton: &Skeleton, prefix: &str, dofs: [usize; 3]) -> Option<Arm> {
        let wrist = skeleton.joint(&format!("{prefix}wrist")).ok()?;
        let joints = skeleton.joints();
        let mut chain = vec![wrist];
        while let Some(parent) = joints[*chain.last()?].parent {
            chain.push(parent);
        }
        chain.reverse();
        let shoulder_joint = skeleton.dofs()[dofs[0]].joint;
        let shoulder = chain.iter().position(|&j| j == shoulder_joint)?;
        let volumes: Vec<(usize, Capsule)> = skeleton
            .solids()
            .iter()
            .filter_map(|(j, s)| {
                let at = chain
                    .iter()
                    .position(|c| c == j)
                    .filter(|&k| k >= shoulder)?;
                Some((at, Capsule::covering(&s.shape, s.center, s.orientation)))
            })
            .collect();
        // Along the chain, from the shoulder to the wrist, then to the hand's far side.
        let to_wrist: f64 = chain[shoulder + 1..]
            .iter()
            .map(|&j| joints[j].offset.length())
            .sum();
        let hand = volumes
            .iter()
            .filter(|&&(at, _)| chain[at] == wrist)
            .map(|(_, c)| c.a.length().max(c.b.length()) + c.ra.max(c.rb))
            .fold(0.0, f64::max);
        let chain_dofs = chain_dofs(skeleton, chain[0], wrist).ok()?;
        Some(Arm {
            chain,
            shoulder,
            volumes,
            dofs,
            chain_dofs,
            reach: to_wrist + hand,
        })
    }

    /// The chain's frames for posture `q`, from place `from` on (`frames` holds those
    /// above it already).
    fn place(&self, skeleton: &Skeleton, q: &[f64], frames: &mut [Transform], from: usize) {
        for k in from..self.chain.len() {
            let parent = k.checked_sub(1).map(|p| &frames[p]);
            frames[k] = joint_frame(skeleton, self.chain[k], parent, q);
        }
    }

    /// How far the arm placed by `frame` (given a joint's place in the chain) comes
    /// within [`HAND_MARGIN`] of the obstacles `near` of `obstacles` (m; at most 0 when
    /// it keeps clear).
    fn worst(
        &self,
        frame: impl Fn(usize) -> Transform,
        (near, obstacles): (&[usize], &[&Footprint]),
    ) -> f64 {
        let mut worst = f64::NEG_INFINITY;
        for &(at, capsule) in &self.volumes {
            let placed = capsule.placed(&frame(at));
            // A sphere (the hand) once; a limb at its ends and middle.
            let samples: &[f64] = if capsule.a == capsule.b {
                &[0.5]
            } else {
                &[0.0, 0.5, 1.0]
            };
            for &t in samples {
                let (p, r) = (placed.point(t), placed.radius(t));
                for &k in near {
                    worst = worst.max(r + HAND_MARGIN - prism_distance(obstacles[k], p));
                }
            }
        }
        worst
    }

    /// Whether a bound from above of [`Arm::worst`] for the arm placed by `frame` (given
    /// a joint's place in the chain) reaches `floor`: each volume taken as the sphere round
    /// it, three distances to each obstacle `near` (of `around`'s) where the measure takes
    /// seven; and an obstacle whose circle (`Surroundings::circle_gap`) already keeps a
    /// sphere under `floor` is not measured against it, the prism over the footprint
    /// being never nearer than the circle.
    fn bound_reaches(
        &self,
        frame: impl Fn(usize) -> Transform,
        (near, around): (&[usize], &Surroundings),
        floor: f64,
    ) -> bool {
        for &(at, capsule) in &self.volumes {
            let (centre, radius) = capsule.placed(&frame(at)).bound();
            let under = DVec2::new(centre.x, centre.z);
            for &k in near {
                if around.circle_gap(k, (under, 0.0)) > radius + HAND_MARGIN - floor {
                    continue;
                }
                let prism = prism_distance(around.obstacles[k], centre);
                if radius + HAND_MARGIN - prism >= floor {
                    return true;
                }
            }
        }
        false
    }
}

impl FreeHands {
    /// Moves the free arms' values `arms` (per arm, as the gait wrote them: shoulder
    /// flexion, abduction, elbow flexion, twist) off the obstacles near the body
    /// (`around`'s), the nearest `gap` (m) from the body's capsule; `free[i]` says whether
    /// arm `i` (left, right) holds nothing and is the walk's to move, and `upper` holds
    /// this tick's root, pelvis and spine values.
    pub fn keep_clear(
        &mut self,
        ctx: &GeneratorContext,
        (arm_dofs, free): ([[usize; 4]; 2], [bool; 2]),
        upper: &[(usize, f64)],
        (around, gap): (&Surroundings, f64),
        arms: &mut [[f64; 4]; 2],
    ) {
        if gap >= BODY_CLEAR && self.offsets == [[0.0; 3]; 2] {
            return;
        }
        let sk = ctx.skeleton;
        let found = self.arms.get_or_insert_with(|| {
            [("l_", arm_dofs[0]), ("r_", arm_dofs[1])]
                .iter()
                .map_while(|(prefix, d)| Arm::of(sk, prefix, [d[0], d[1], d[2]]))
                .collect()
        });
        if found.len() < 2 {
            return;
        }
        let obstacles = &around.obstacles[..];
        let last = &ctx.posture.globals;
        let steps = (OUT_RATE * ctx.dt, BACK_RATE * ctx.dt);
        for (i, arm) in found.iter().enumerate() {
            // Back towards the gait, unless the obstacles say otherwise.
            let mut next = self.offsets[i].map(|o| o - o.clamp(-steps.1, steps.1));
            let shoulder = last[arm.chain[arm.shoulder]].translation;
            let at = DVec2::new(shoulder.x, shoulder.z);
            self.near.clear();
            if free[i] {
                let range = arm.reach + LOOKED_AT;
                self.near.extend((0..obstacles.len()).filter(|&k| {
                    around.circle_gap(k, (at, 0.0)) < range && obstacles[k].distance(at) < range
                }));
            }
            let near = (self.near.as_slice(), obstacles);
            let resting = self.offsets[i] == [0.0; 3];
            if near.0.is_empty() && resting {
                continue;
            }
            // An arm at the gait's values that was far from everything on the last tick
            // stays so this tick: told first by the spheres round its parts, then by the
            // measure itself.
            let measured = !near.0.is_empty()
                && (!resting
                    || (arm.bound_reaches(|at| last[arm.chain[at]], (near.0, around), -LOOKED_AT)
                        && arm.worst(|at| last[arm.chain[at]], near) >= -LOOKED_AT));
            if measured {
                // The values as the posture will have them: within their DOFs' limits (the
                // spine's torsions, turned by the shoulders, often are not; unclamped, the
                // arm was measured 3.5 cm from where it ended up).
                let dofs = sk.dofs();
                // Only the chain's values are read: those, not the whole posture, are
                // taken from the last tick's.
                if self.q.len() != ctx.posture.q.len() {
                    self.q.clear();
                    self.q.extend_from_slice(&ctx.posture.q);
                }
                for &d in &arm.chain_dofs {
                    self.q[d] = ctx.posture.q[d];
                }
                for &(d, v) in upper {
                    self.q[d] = dofs[d].clamp(v);
                }
                for (k, &v) in arms[i][..3].iter().enumerate() {
                    self.q[arm.dofs[k]] = dofs[arm.dofs[k]].clamp(v);
                }
                let twist = arm_dofs[i][3];
                self.q[twist] = dofs[twist].clamp(arms[i][3]);
                self.frames.resize(arm.chain.len(), Transform::IDENTITY);
                arm.place(sk, &self.q, &mut self.frames, 0);
                let last = (self.offsets[i], steps);
                next = departure(sk, arm, (&mut self.q, &mut self.frames), near, last);
            }
            self.offsets[i] = next;
            for (value, offset) in arms[i].iter_mut().zip(next) {
                *value += offset;
            }
        }
    }
}

/// The departure (shoulder flexion, abduction, elbow flexion) from the values in `q` that
/// keeps `arm` out of the obstacles `near` (see [`Arm::worst`]) this tick, within the
/// DOFs' limits: from the last tick's, `last`, the least further change that takes it
/// out (a few Gauss–Newton steps on its deepest point), each DOF within `out` (radians)
/// of `last`; or where it is already out, `back` towards the gait if that keeps it out
/// by [`HYSTERESIS`] more. Starting from the last tick's keeps the arm going round the
/// obstacle one way (from the gait's own values each tick, it went over a stand's corner
/// and back by its side in turn, through it). Where the arm hangs straight into what is
/// under it, the first steps' direction is all the derivatives tell (moving it up is of
/// the second order there); at `out` a tick it goes that way until it is out. `frames`
/// holds the chain's frames for `q`; `q` and the frames below the shoulder are scratch.
fn departure(
    sk: &Skeleton,
    arm: &Arm,
    (q, frames): (&mut [f64], &mut [Transform]),
    near: (&[usize], &[&Footprint]),
    (last, (out, back)): ([f64; 3], (f64, f64)),
) -> [f64; 3] {
    let base = arm.dofs.map(|d| q[d]);
    let measure = |delta: [f64; 3], q: &mut [f64], frames: &mut [Transform]| {
        for k in 0..3 {
            q[arm.dofs[k]] = base[k] + delta[k];
        }
        arm.place(sk, q, frames, arm.shoulder);
        arm.worst(|at| frames[at], near)
    };
    // A departure `wanted` of DOF `k`, within its limits and `step` of the last tick's.
    let within = |k: usize, wanted: f64, step: f64| {
        let dof = &sk.dofs()[arm.dofs[k]];
        dof.clamp(base[k] + wanted.clamp(last[k] - step, last[k] + step)) - base[k]
    };
    let mut delta = [0, 1, 2].map(|k| within(k, last[k], 0.0));
    let mut worst = measure(delta, q, frames);
    if worst <= 0.0 {
        if delta == [0.0; 3] {
            return delta;
        }
        let back = [0, 1, 2].map(|k| within(k, 0.0, back));
        return if measure(back, q, frames) <= -HYSTERESIS {
            back
        } else {
            delta
        };
    }
    for _ in 0..STEPS {
        let mut gradient = [0.0; 3];
        for k in 0..3 {
            let mut moved = delta;
            moved[k] += H;
            gradient[k] = (measure(moved, q, frames) - worst) / H;
        }
        let norm: f64 = (0..3).map(|k| WEIGHTS[k] * gradient[k] * gradient[k]).sum();
        if norm < 1e-9 {
            break;
        }
        let before = delta;
        for k in 0..3 {
            delta[k] = within(k, delta[k] - WEIGHTS[k] * gradient[k] * worst / norm, out);
        }
        // Every DOF at its limit or its step: no further step moves it.
        if delta == before {
            break;
        }
        worst = measure(delta, q, frames);
        if worst <= 0.0 {
            break;
        }
    }
    delta
}

/// The distance (m) from `p` to the prism standing on footprint `f` up to its top;
/// negative inside, by how far the nearest face is.
pub fn prism_distance(f: &Footprint, p: DVec3) -> f64 {
    let h = DVec2::new(p.x, p.z);
    let outside = f.distance(h);
    let across = if outside > 0.0 {
        outside
    } else {
        -f.nearest_point(h).map_or(0.0, |n| (n - h).length())
    };
    let above = p.y - f.top;
    if above <= 0.0 || across <= 0.0 {
        across.max(above)
    } else {
        across.hypot(above)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::walk::Rig;

    /// The adult's left arm hanging at rest (its chain's frames for `q`, all zero), and a
    /// stand under its hand, its top `into` metres above the hand's lowest point.
    fn hanging_over_a_stand(into: f64) -> (Skeleton, Arm, Vec<f64>, Vec<Transform>, Footprint) {
        let sk = troupe_body::template::default_skeleton("adult").unwrap();
        let d = Rig::new(&sk).unwrap().arms[0];
        let arm = Arm::of(&sk, "l_", [d[0], d[1], d[2]]).unwrap();
        let q = vec![0.0; sk.dof_count()];
        let mut frames = vec![Transform::IDENTITY; arm.chain.len()];
        arm.place(&sk, &q, &mut frames, 0);
        let &(at, hand) = arm.volumes.last().unwrap();
        let hand = hand.placed(&frames[at]);
        let (c, r) = (hand.point(0.5), hand.radius(0.5));
        let corners = [(-0.1, -0.1), (0.4, -0.1), (0.4, 0.1), (-0.1, 0.1)];
        let points: Vec<DVec2> = corners
            .iter()
            .map(|&(x, z)| DVec2::new(c.x + x, c.z + z))
            .collect();
        let stand = Footprint::hull("stand", &points).with_top(c.y - r + into);
        (sk, arm, q, frames, stand)
    }

    /// The departures of `arm` tick after tick (100 Hz) from the gait's values
    /// `q` for `ticks` ticks, and how far it then comes within the margin of `stand`.
    fn ticks(
        sk: &Skeleton,
        arm: &Arm,
        q: &[f64],
        stand: &Footprint,
        ticks: usize,
    ) -> ([f64; 3], f64) {
        let obstacles = [stand];
        let near = (&[0usize][..], &obstacles[..]);
        let mut frames = vec![Transform::IDENTITY; arm.chain.len()];
        let mut delta = [0.0; 3];
        for _ in 0..ticks {
            let mut q = q.to_vec();
            arm.place(sk, &q, &mut frames, 0);
            let steps = (OUT_RATE * 0.01, BACK_RATE * 0.01);
            delta = departure(sk, arm, (&mut q, &mut frames), near, (delta, steps));
        }
        let mut q = q.to_vec();
        for k in 0..3 {
            q[arm.dofs[k]] += delta[k];
        }
        arm.place(sk, &q, &mut frames, 0);
        (delta, arm.worst(|at| frames[at], near))
    }

    #[test]
    fn the_circles_change_no_answer_of_the_spheres_bound() {
        // The hanging arm beside stands moved about it, 3,000 times: `bound_reaches` says
        // what the spheres' bound measured against every stand says, whether the circles
        // passed a stand over or not.
        let (_, arm, _, frames, stand) = hanging_over_a_stand(0.02);
        let mut next = troupe_body::math::draws(5);
        let (mut reached, mut not) = (0, 0);
        for _ in 0..3000 {
            let mut moved = |f: &Footprint| {
                let by = DVec2::new(next() - 0.5, next() - 0.5) * 1.2;
                let outline: Vec<DVec2> = f.outline.iter().map(|&p| p + by).collect();
                Footprint::hull("stand", &outline).with_top(f.top + (next() - 0.5) * 0.4)
            };
            let stands = [moved(&stand), moved(&stand)];
            let around = Surroundings {
                obstacles: stands.iter().collect(),
                bounds: stands.iter().map(Footprint::bounding_circle).collect(),
                ..Surroundings::default()
            };
            let floor = -LOOKED_AT;
            let measured = arm.volumes.iter().any(|&(at, capsule)| {
                let (centre, radius) = capsule.placed(&frames[at]).bound();
                (stands.iter()).any(|f| radius + HAND_MARGIN - prism_distance(f, centre) >= floor)
            });
            let near = [0, 1];
            assert_eq!(
                arm.bound_reaches(|at| frames[at], (&near, &around), floor),
                measured
            );
            if measured {
                reached += 1;
            } else {
                not += 1;
            }
        }
        assert!(reached > 300 && not > 300, "{reached} {not}");
    }

    #[test]
    fn a_hand_hanging_into_a_stand_is_taken_out_of_it_within_a_second() {
        let (sk, arm, q, frames, stand) = hanging_over_a_stand(0.02);
        let obstacles = [&stand];
        let before = arm.worst(|at| frames[at], (&[0], &obstacles));
        assert!(before > 0.03, "{before}");
        let (delta, after) = ticks(&sk, &arm, &q, &stand, 100);
        assert!(after <= 0.0, "{after} with {delta:?}");
        assert!(delta.iter().all(|d| d.abs() < 0.6), "{delta:?}");
        // Not by bringing the arm in, which takes the hand to the thigh.
        assert!(delta[1] > -0.02, "{delta:?}");
        // Held there: stepping back towards the gait would take it in again.
        let (held, _) = ticks(&sk, &arm, &q, &stand, 200);
        assert_eq!(held, delta);
    }

    #[test]
    fn an_arm_clear_of_the_furniture_goes_back_to_the_gait_one_step_at_a_time() {
        let (sk, arm, mut q, mut frames, stand) = hanging_over_a_stand(-0.2);
        let obstacles = [&stand];
        let near = (&[0usize][..], &obstacles[..]);
        let steps = (0.1, 0.05);
        let delta = departure(
            &sk,
            &arm,
            (&mut q, &mut frames),
            near,
            ([0.2, 0.0, 0.2], steps),
        );
        for (got, want) in delta.iter().zip([0.15, 0.0, 0.15]) {
            assert!((got - want).abs() < 1e-12, "{delta:?}");
        }
    }

    fn stand() -> Footprint {
        let corners = [(-0.25, -0.2), (0.25, -0.2), (0.25, 0.2), (-0.25, 0.2)];
        let points: Vec<DVec2> = corners.iter().map(|&(x, z)| DVec2::new(x, z)).collect();
        Footprint::hull("stand", &points).with_top(0.8)
    }

    #[test]
    fn a_prism_is_measured_from_its_sides_its_top_and_its_edge() {
        let f = stand();
        let near = |a: f64, b: f64| (a - b).abs() < 1e-9;
        // Beside it, below its top: from the side.
        assert!(near(prism_distance(&f, DVec3::new(0.35, 0.5, 0.0)), 0.1));
        // Above it: from the top.
        assert!(near(prism_distance(&f, DVec3::new(0.0, 0.9, 0.0)), 0.1));
        // Beyond its edge and above it: from the edge.
        let d = prism_distance(&f, DVec3::new(0.28, 0.84, 0.0));
        assert!(near(d, 0.05), "{d}");
        // Inside: the nearer face, negative.
        assert!(near(prism_distance(&f, DVec3::new(0.2, 0.5, 0.0)), -0.05));
        assert!(near(prism_distance(&f, DVec3::new(0.0, 0.78, 0.0)), -0.02));
    }
}
