//! Bodies against bodies and obstacles in the scene: every actor's solids as collision
//! capsules ([`troupe_body::collision`]), every obstacle (a wall, an object standing on
//! the floor) as its exact shape, and the deepest interpenetration between them.
//!
//! Generators read these from the world of the previous tick (a reach bending round
//! another body), so what they decide does not depend on the thread count; the scene's
//! [`Scene::deepest_interpenetration`] measures the world as it stands, for tests and
//! reports.

use crate::world::World;
use crate::Scene;
use troupe_body::collision::{deepest_between, BodyVolumes, Capsule, Volume};
use troupe_body::glam::{DQuat, DVec3};
use troupe_body::{Shape, Transform};

/// What an actor's solid runs into.
#[derive(Clone, Debug, PartialEq)]
pub enum Other {
    /// Another actor's solid: the actor's index and the solid's.
    Actor {
        /// Index of the actor.
        actor: usize,
        /// Index of its solid (in its skeleton's solids).
        solid: usize,
    },
    /// An obstacle: its name (`table`, `wall 2`).
    Obstacle(String),
}

/// The deepest interpenetration in the scene: which solid of which actor, into what,
/// how deep.
#[derive(Clone, Debug, PartialEq)]
pub struct Interpenetration {
    /// How deep (m, > 0).
    pub depth: f64,
    /// Index of the actor.
    pub actor: usize,
    /// Index of its solid (in its skeleton's solids).
    pub solid: usize,
    /// What it runs into.
    pub other: Other,
}

impl World<'_> {
    /// Every obstacle that has a body, with its name: walls (boxes from the floor up to
    /// their height), then the objects that are obstacles now (see
    /// [`World::is_obstacle`]). Holes in the floor have no body and are not listed.
    pub fn obstacle_volumes(&self) -> Vec<(String, Volume)> {
        self.obstacle_volumes_where(|_| true)
    }

    /// [`World::obstacle_volumes`] that come within `range` (m, measured on the floor)
    /// of one of `points` (by a sphere round each volume): what a reach by a body there
    /// can touch. Objects farther off are left out before their footprint is made.
    pub fn obstacle_volumes_near(&self, points: &[DVec3], range: f64) -> Vec<(String, Volume)> {
        self.obstacle_volumes_where(|v| {
            let (centre, radius) = v.bound();
            points
                .iter()
                .any(|p| (p.x - centre.x).hypot(p.z - centre.z) < range + radius)
        })
    }

    /// The obstacles' volumes for which `wanted` holds (asked before an object is
    /// checked for being an obstacle).
    fn obstacle_volumes_where(&self, wanted: impl Fn(&Volume) -> bool) -> Vec<(String, Volume)> {
        let walls = self.space.walls.iter().enumerate().map(|(i, w)| {
            let along = w.to - w.from;
            let mid = (w.from + w.to) / 2.0;
            // A turn about Y by θ takes +X to (cos θ, 0, −sin θ): onto the wall's line.
            let yaw = (-along.y).atan2(along.x);
            let volume = Volume::Shape {
                shape: Shape::Box {
                    half_extents: DVec3::new(
                        along.length() / 2.0,
                        w.height / 2.0,
                        w.thickness / 2.0,
                    ),
                },
                pose: Transform::new(
                    DQuat::from_rotation_y(yaw),
                    DVec3::new(mid.x, w.height / 2.0, mid.y),
                ),
            };
            (i, volume)
        });
        let walls = walls
            .filter(|(_, v)| wanted(v))
            .map(|(i, v)| (format!("wall {}", i + 1), v));
        let objects = self.objects.iter().enumerate().filter_map(|(i, o)| {
            let volume = Volume::Shape {
                shape: o.shape,
                pose: Transform::new(o.rotation, o.position),
            };
            (wanted(&volume) && self.is_obstacle(i)).then(|| (o.name.clone(), volume))
        });
        walls.chain(objects).collect()
    }

    /// Actor `actor`'s solids as world capsules, in its skeleton's solid order.
    pub fn body_capsules(&self, actor: usize) -> Vec<Capsule> {
        let mut out = Vec::new();
        if let (Some(info), Some(state)) = (self.actors.get(actor), self.states.get(actor)) {
            BodyVolumes::new(&info.skeleton).place(&state.globals, &mut out);
        }
        out
    }

    /// The deepest interpenetration between two actors' solids or an actor's solid and
    /// an obstacle, or `None` when nothing interpenetrates.
    pub fn deepest_interpenetration(&self) -> Option<Interpenetration> {
        let bodies: Vec<Vec<Capsule>> = (0..self.states.len())
            .map(|i| self.body_capsules(i))
            .collect();
        let bounds: Vec<(DVec3, DVec3)> = bodies.iter().map(|b| bound_of(b)).collect();
        let obstacles = self.obstacle_volumes();
        let mut deepest: Option<Interpenetration> = None;
        let mut note = |found: Interpenetration| {
            if found.depth > 0.0 && deepest.as_ref().is_none_or(|d| found.depth > d.depth) {
                deepest = Some(found);
            }
        };
        let overlap = |(alo, ahi): (DVec3, DVec3), (blo, bhi): (DVec3, DVec3)| {
            alo.cmple(bhi).all() && blo.cmple(ahi).all()
        };
        // Sweep along x: the actors sorted by the low x of their boxes.
        let mut order: Vec<usize> = (0..bodies.len()).collect();
        order.sort_by(|&i, &j| bounds[i].0.x.total_cmp(&bounds[j].0.x).then(i.cmp(&j)));
        for (n, &i) in order.iter().enumerate() {
            for &j in &order[n + 1..] {
                if bounds[j].0.x > bounds[i].1.x {
                    break;
                }
                if !overlap(bounds[i], bounds[j]) {
                    continue;
                }
                let (a, b) = (i.min(j), i.max(j));
                if let Some((depth, sa, sb)) = deepest_between(&bodies[a], &bodies[b]) {
                    note(Interpenetration {
                        depth,
                        actor: a,
                        solid: sa,
                        other: Other::Actor {
                            actor: b,
                            solid: sb,
                        },
                    });
                }
            }
        }
        for (i, body) in bodies.iter().enumerate() {
            for (name, volume) in &obstacles {
                let (c, r) = volume.bound();
                if !overlap(bounds[i], (c - DVec3::splat(r), c + DVec3::splat(r))) {
                    continue;
                }
                for (k, capsule) in body.iter().enumerate() {
                    let (ck, rk) = capsule.bound();
                    if (ck - c).length() >= rk + r || !volume.may_touch(capsule) {
                        continue;
                    }
                    let (depth, _) = volume.capsule_depth(capsule);
                    note(Interpenetration {
                        depth,
                        actor: i,
                        solid: k,
                        other: Other::Obstacle(name.clone()),
                    });
                }
            }
        }
        deepest
    }
}

/// The box (lowest and highest corners) around a body's capsules.
pub fn bound_of(capsules: &[Capsule]) -> (DVec3, DVec3) {
    capsules.iter().fold(
        (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY)),
        |(lo, hi), c| {
            let r = DVec3::splat(c.ra.max(c.rb));
            (lo.min(c.a.min(c.b) - r), hi.max(c.a.max(c.b) + r))
        },
    )
}

impl Scene {
    /// The deepest interpenetration of solids now (see
    /// [`World::deepest_interpenetration`]).
    pub fn deepest_interpenetration(&self) -> Option<Interpenetration> {
        self.world().deepest_interpenetration()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{ActorDesc, SceneConfig};
    use troupe_body::glam::DVec2;
    use troupe_nav::Wall;

    fn scene_with(at: &[[f64; 3]]) -> Scene {
        let mut scene = Scene::new(SceneConfig::default()).unwrap();
        for (i, p) in at.iter().enumerate() {
            let mut desc = ActorDesc::new(format!("a{i}"));
            desc.at = DVec3::from(*p);
            scene.add_actor(&desc).unwrap();
        }
        scene
    }

    #[test]
    fn two_bodies_apart_do_not_touch_and_close_ones_do() {
        let scene = scene_with(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
        assert_eq!(scene.deepest_interpenetration(), None);
        let scene = scene_with(&[[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 0.0, 0.25]]);
        let found = scene.deepest_interpenetration().unwrap();
        assert_eq!(found.actor, 0);
        assert!(
            matches!(found.other, Other::Actor { actor: 2, .. }),
            "{found:?}"
        );
        // Torsos of radius ~0.14 with centres 0.25 m apart.
        assert!(found.depth > 0.02 && found.depth < 0.3, "{found:?}");
    }

    #[test]
    fn a_body_in_a_wall_is_found_and_named() {
        let mut scene = scene_with(&[[0.0, 0.0, 0.0]]);
        scene
            .add_wall(Wall {
                from: DVec2::new(0.1, -2.0),
                to: DVec2::new(0.1, 2.0),
                thickness: 0.1,
                height: 2.0,
            })
            .unwrap();
        let found = scene.deepest_interpenetration().unwrap();
        assert_eq!(found.other, Other::Obstacle("wall 1".into()));
        assert!(found.depth > 0.1, "{found:?}");
    }
}
