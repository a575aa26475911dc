//! Moving a scene object with a SpaceMouse (`troupe.devices.spacemouse{…}`).
//!
//! Each tick, in the session's input phase (after the performers' input, before the
//! scripts), every SpaceMouse mover takes the readings that are due — from its device thread
//! (never blocking: the thread's channel is drained with `try_recv`, and the tick that
//! took them is marked in the recording), from a replay of the whole run's inputs at the
//! ticks the recorded run took them, or from a `replay =` recording by scene time
//! (deterministic either way) — and moves its object for one tick: a linear
//! velocity from the three translation axes and an angular velocity from the three rotation
//! axes, both mapped from the device frame to the scene frame.
//!
//! Frames: the SpaceMouse's HID axes are X right, Y towards the user, Z down (right-handed),
//! rotations right-handed about those axes. The user is taken to sit in front of the scene
//! looking along −Z (scene Y up), so device (x, y, z) becomes scene (x, −z, y): pushing the
//! cap right moves the object along +X, lifting it moves it up (+Y), pulling it towards the
//! user moves it along +Z, and twisting the cap counter-clockwise seen from above turns the
//! object counter-clockwise about +Y. The same proper rotation maps the rotation axes.

use crate::device::health::{HealthReport, HealthState};
use crate::device::reading::Reading;
use crate::device::thread::DeviceHandle;
use crate::record::feed::SharedFeed;
use crate::record::writer::Recorder;
use crate::spacemouse::decoder::SpaceMouseState;
use glam::{DQuat, DVec3};
use std::sync::{Arc, Mutex};
use troupe_scene::{Input, Scene};

/// How deflection becomes motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MoveOptions {
    /// Metres per second at full deflection.
    pub speed: f64,
    /// Radians per second at full deflection.
    pub turn: f64,
    /// Fraction of full scale (0…1) under which an axis counts as at rest.
    pub deadzone: f64,
}

impl Default for MoveOptions {
    /// 1 m/s, 90°/s, 5 % deadzone.
    fn default() -> MoveOptions {
        MoveOptions {
            speed: 1.0,
            turn: 90f64.to_radians(),
            deadzone: 0.05,
        }
    }
}

/// One axis with the deadzone removed and the rest rescaled so full deflection stays 1: an
/// axis resting a little off zero does not creep, and the range stays continuous.
pub fn deadzoned(u: f64, deadzone: f64) -> f64 {
    let a = u.abs();
    if a <= deadzone {
        0.0
    } else {
        u.signum() * ((a - deadzone) / (1.0 - deadzone)).min(1.0)
    }
}

/// Device axes (X right, Y towards the user, Z down) to scene axes (Y up, user looking
/// along −Z): (x, y, z) ↦ (x, −z, y).
pub fn device_to_scene(v: [f64; 3]) -> DVec3 {
    DVec3::new(v[0], -v[2], v[1])
}

/// Linear (m/s) and angular (rad/s, scaled axis) velocity in the scene frame for a state.
pub fn velocity(state: &SpaceMouseState, o: &MoveOptions) -> (DVec3, DVec3) {
    let t = state.translation_unit().map(|u| deadzoned(u, o.deadzone));
    let r = state.rotation_unit().map(|u| deadzoned(u, o.deadzone));
    (device_to_scene(t) * o.speed, device_to_scene(r) * o.turn)
}

/// Moves a pose for `dt` seconds at the given velocities; the rotation is about the object's
/// centre, with the angular velocity in the scene frame (so it turns as the cap turns,
/// whatever the object's own orientation).
pub fn integrate(
    position: DVec3,
    rotation: DQuat,
    linear: DVec3,
    angular: DVec3,
    dt: f64,
) -> (DVec3, DQuat) {
    let turn = DQuat::from_scaled_axis(angular * dt);
    (position + linear * dt, (turn * rotation).normalize())
}

/// Where a mover's readings come from.
pub(crate) enum Source {
    /// A live HID device thread (local or relayed), made `opened` ticks into the scene.
    Live { handle: DeviceHandle, opened: u64 },
    /// A recording, delivered by scene time since the first scene step the mover took
    /// part in (`start`, set then): whether the mover was made before the first tick or by
    /// a script mid-tick, its first recorded report then moves the object for a whole tick.
    Replay {
        readings: Vec<(f64, Reading)>,
        next: usize,
        start: Option<f64>,
    },
    /// The mover's stream in a replay of the whole run's inputs (`--replay-devices`,
    /// `--zenoh-follow`): readings at the ticks the recorded run took them (by scene time
    /// from `start`, when it was made, for a recording without tick marks).
    Replayed {
        feed: SharedFeed,
        opened: u64,
        start: f64,
    },
}

/// One SpaceMouse moving one object.
pub(crate) struct Mover {
    /// The mover's name (`troupe.devices.health` and recordings).
    pub(crate) name: String,
    /// Object index in the scene.
    pub(crate) object: usize,
    /// Where its readings come from.
    pub(crate) source: Source,
    /// The device's state after the latest reading.
    pub(crate) state: SpaceMouseState,
    /// How deflection becomes motion.
    pub(crate) options: MoveOptions,
}

impl Mover {
    /// Takes the readings due at `tick` (scene time `time`) into the state.
    fn update(&mut self, tick: u64, time: f64) {
        match &mut self.source {
            Source::Live { handle, opened } => {
                for s in handle.drain_at_tick(tick.saturating_sub(*opened)) {
                    if let Reading::SpaceMouse(m) = s.reading {
                        self.state = m;
                    }
                }
                // A device that went away must not keep the object flying with its last axes.
                if matches!(
                    handle.health.state(),
                    HealthState::Reconnecting | HealthState::Failed
                ) {
                    self.state = SpaceMouseState::default();
                }
            }
            Source::Replay {
                readings,
                next,
                start,
            } => {
                let start = *start.get_or_insert(time);
                while *next < readings.len() && readings[*next].0 <= time - start + 1e-9 {
                    if let Reading::SpaceMouse(m) = &readings[*next].1 {
                        self.state = *m;
                    }
                    *next += 1;
                }
            }
            Source::Replayed {
                feed,
                opened,
                start,
            } => {
                let due = match feed.lock() {
                    Ok(mut f) => f.take(tick.saturating_sub(*opened), time - *start),
                    Err(_) => Vec::new(),
                };
                for r in due {
                    if let Reading::SpaceMouse(m) = r {
                        self.state = m;
                    }
                }
            }
        }
    }

    fn health(&self) -> Option<HealthReport> {
        match &self.source {
            Source::Live { handle, .. } => Some(handle.health.report()),
            Source::Replay { .. } | Source::Replayed { .. } => None,
        }
    }
}

/// Every SpaceMouse mover of a scene, and the recorder for live devices.
#[derive(Default)]
pub struct SpaceMice {
    /// The movers, in creation order.
    pub(crate) movers: Vec<Mover>,
    /// Records live SpaceMouse reports.
    pub(crate) recorder: Option<Arc<Recorder>>,
}

/// Lua app data: the shared movers.
#[derive(Clone)]
pub struct SharedSpaceMice(pub Arc<Mutex<SpaceMice>>);

impl SpaceMice {
    /// The scene step: take due readings, then move each object not held by an actor.
    pub fn step(&mut self, scene: &mut Scene) {
        let (tick, time) = (scene.tick(), scene.time());
        let dt = scene.dt();
        for m in &mut self.movers {
            m.update(tick, time);
            // A held object follows its holder's hand (crate::holding); moving it here
            // would fight the hand, so a held object is left alone.
            if scene.holder(m.object).is_some() {
                continue;
            }
            let (lin, ang) = velocity(&m.state, &m.options);
            if lin == DVec3::ZERO && ang == DVec3::ZERO {
                continue;
            }
            if let Some(o) = scene.objects_mut().get_mut(m.object) {
                (o.position, o.rotation) = integrate(o.position, o.rotation, lin, ang, dt);
            }
        }
    }

    /// Health of a mover by name: `Some(None)` for a replay, `None` for an unknown name.
    pub fn health(&self, name: &str) -> Option<Option<HealthReport>> {
        self.movers
            .iter()
            .find(|m| m.name == name)
            .map(|m| m.health())
    }

    /// Health of every live SpaceMouse: (name, report).
    pub fn live_health(&self) -> Vec<(String, HealthReport)> {
        self.movers
            .iter()
            .filter_map(|m| m.health().map(|h| (m.name.clone(), h)))
            .collect()
    }

    /// The latest state of a mover by name.
    pub fn state(&self, name: &str) -> Option<SpaceMouseState> {
        self.movers.iter().find(|m| m.name == name).map(|m| m.state)
    }
}

/// Moves the objects of every SpaceMouse (the session's input phase).
pub(crate) struct SpaceMouseInput(pub(crate) SharedSpaceMice);

impl Input for SpaceMouseInput {
    fn name(&self) -> String {
        "spacemouse".into()
    }

    fn poll(&mut self, scene: &mut Scene) -> troupe_scene::Result<()> {
        self.0
             .0
            .lock()
            .map_err(|_| troupe_scene::Error::Input {
                input: "spacemouse".into(),
                message: "lock poisoned by a panic".into(),
            })?
            .step(scene);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn full(translation: [i16; 3], rotation: [i16; 3]) -> SpaceMouseState {
        SpaceMouseState {
            translation,
            rotation,
            buttons: 0,
        }
    }

    /// Integrates a constant state for `seconds` at 100 Hz.
    fn run(state: SpaceMouseState, o: &MoveOptions, seconds: f64) -> (DVec3, DQuat) {
        let (lin, ang) = velocity(&state, o);
        let mut pose = (DVec3::ZERO, DQuat::IDENTITY);
        let steps = (seconds * 100.0).round() as usize;
        for _ in 0..steps {
            pose = integrate(pose.0, pose.1, lin, ang, 0.01);
        }
        pose
    }

    #[test]
    fn full_deflection_for_one_second_moves_speed_metres_along_the_right_axis() {
        let o = MoveOptions {
            speed: 0.5,
            ..MoveOptions::default()
        };
        // Cap pushed right: +X.
        let (p, _) = run(full([350, 0, 0], [0; 3]), &o, 1.0);
        assert!((p - DVec3::new(0.5, 0.0, 0.0)).length() < 1e-9, "{p}");
        // Cap pulled towards the user: +Z.
        let (p, _) = run(full([0, 350, 0], [0; 3]), &o, 1.0);
        assert!((p - DVec3::new(0.0, 0.0, 0.5)).length() < 1e-9, "{p}");
        // Cap lifted (device −Z): up, +Y.
        let (p, _) = run(full([0, 0, -350], [0; 3]), &o, 1.0);
        assert!((p - DVec3::new(0.0, 0.5, 0.0)).length() < 1e-9, "{p}");
        // Beyond full scale is clamped to full speed.
        let (p, _) = run(full([400, 0, 0], [0; 3]), &o, 1.0);
        assert!((p.x - 0.5).abs() < 1e-9);
    }

    #[test]
    fn full_twist_for_one_second_turns_turn_degrees_about_up() {
        let o = MoveOptions {
            turn: 90f64.to_radians(),
            ..MoveOptions::default()
        };
        // Twist about device −Z (up): counter-clockwise from above, +Y in the scene.
        let (p, q) = run(full([0; 3], [0, 0, -350]), &o, 1.0);
        assert_eq!(p, DVec3::ZERO);
        let want = DQuat::from_rotation_y(90f64.to_radians());
        assert!(q.angle_between(want) < 1e-9, "{q:?}");
        // Device Rx (about right) is scene X.
        let (_, q) = run(full([0; 3], [350, 0, 0]), &o, 1.0);
        assert!(q.angle_between(DQuat::from_rotation_x(90f64.to_radians())) < 1e-9);
    }

    #[test]
    fn deadzone_holds_small_deflections_and_keeps_full_scale() {
        let o = MoveOptions {
            deadzone: 0.1,
            ..MoveOptions::default()
        };
        // 30 / 350 < 0.1: nothing moves.
        let (lin, ang) = velocity(&full([30, -30, 30], [-30, 30, 0]), &o);
        assert_eq!((lin, ang), (DVec3::ZERO, DVec3::ZERO));
        // Just past the deadzone moves slowly; full scale is still full speed.
        assert!(deadzoned(0.2, 0.1) > 0.0 && deadzoned(0.2, 0.1) < 0.2);
        assert_eq!(deadzoned(1.0, 0.1), 1.0);
        assert_eq!(deadzoned(-1.0, 0.1), -1.0);
        assert_eq!(deadzoned(0.1, 0.1), 0.0);
    }

    #[test]
    fn a_held_object_is_not_moved_and_a_free_one_is() {
        use troupe_body::Shape;
        use troupe_scene::holding::HoldRequest;
        use troupe_scene::{ActorDesc, SceneConfig};
        let mut scene = Scene::new(SceneConfig {
            rate: 100.0,
            threads: 1,
            seed: 0,
        })
        .unwrap();
        let ann = scene.add_actor(&ActorDesc::new("ann")).unwrap();
        let ball = Shape::Sphere { radius: 0.05 };
        let held = scene
            .add_object(Scene::object("held", ball, DVec3::new(0.0, 1.0, 0.3), 1.0))
            .unwrap();
        let free = scene
            .add_object(Scene::object("free", ball, DVec3::new(1.0, 1.0, 0.0), 1.0))
            .unwrap();
        let wrist = scene.actors()[ann].skeleton.joint("r_wrist").unwrap();
        assert!(scene.request_hold(
            ann,
            HoldRequest::Attach {
                object: held,
                joint: wrist,
                also: None,
                from: None
            }
        ));
        let pushed = || Source::Replay {
            readings: vec![(0.0, Reading::SpaceMouse(full([350, 0, 0], [0; 3])))],
            next: 0,
            start: None,
        };
        let mut mice = SpaceMice::default();
        for (name, object) in [("a", held), ("b", free)] {
            mice.movers.push(Mover {
                name: name.into(),
                object,
                source: pushed(),
                state: SpaceMouseState::default(),
                options: MoveOptions::default(),
            });
        }
        let before = scene.objects()[held].position;
        mice.step(&mut scene);
        assert_eq!(scene.objects()[held].position, before, "held: not moved");
        assert!(
            (scene.objects()[free].position.x - (1.0 + scene.dt())).abs() < 1e-12,
            "free: moved one tick at full speed"
        );
        assert_eq!(mice.state("a").map(|s| s.translation), Some([350, 0, 0]));
        assert_eq!(
            mice.health("b"),
            Some(None),
            "a replay has no device health"
        );
        assert_eq!(mice.health("c"), None);
    }

    #[test]
    fn device_frame_maps_to_a_proper_rotation() {
        // Right × towards-user = down in the device frame; the mapping must keep
        // handedness: scene X × scene Z = −Y (down).
        let x = device_to_scene([1.0, 0.0, 0.0]);
        let y = device_to_scene([0.0, 1.0, 0.0]);
        let z = device_to_scene([0.0, 0.0, 1.0]);
        assert_eq!(x.cross(y), z);
        assert_eq!(z, DVec3::new(0.0, -1.0, 0.0));
    }
}
