//! [`Frame`]: an owned snapshot of a scene plus the overlays to draw on it. The simulation
//! builds one per published tick and hands it to a renderer on another thread.

use glam::{Quat, Vec3};
use std::sync::Arc;
use troupe_body::{Shape, Skeleton, Transform};
use troupe_scene::{Scene, Status};

/// The grasp state of one hand (thesis 4.7), shown by tinting the hand solid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum HandState {
    /// FREE_HAND: skin colour.
    #[default]
    Free,
    /// GRASPING_IN_PROGRESS: blue.
    Grasping,
    /// SECURE_GRASP: green.
    Secure,
}

impl HandState {
    /// The sRGB colour the hand is drawn in.
    pub fn color(self) -> [f32; 3] {
        match self {
            HandState::Free => SKIN,
            HandState::Grasping => [0.16, 0.36, 0.95],
            HandState::Secure => [0.12, 0.78, 0.22],
        }
    }

    /// Parses `free`, `grasping` or `secure` (also the thesis names `FREE_HAND`,
    /// `GRASPING_IN_PROGRESS`, `SECURE_GRASP`).
    pub fn parse(s: &str) -> Option<HandState> {
        match s.to_ascii_lowercase().as_str() {
            "free" | "free_hand" => Some(HandState::Free),
            "grasping" | "grasping_in_progress" => Some(HandState::Grasping),
            "secure" | "secure_grasp" => Some(HandState::Secure),
            _ => None,
        }
    }
}

/// Which hand.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Hand {
    /// The left hand (solid `l_hand`).
    Left,
    /// The right hand (solid `r_hand`).
    Right,
}

/// Skin colour (sRGB) of heads and free hands.
pub const SKIN: [f32; 3] = [0.93, 0.74, 0.60];
/// Colour (sRGB) of a sphere sensor that touches nothing.
pub const SENSOR_IDLE: [f32; 3] = [0.22, 0.22, 0.22];
/// Colour (sRGB) of a sphere sensor while it touches something.
pub const SENSOR_TOUCHING: [f32; 3] = [0.80, 0.80, 0.80];
/// Colour (sRGB) of IK target markers.
pub const IK_TARGET: [f32; 3] = [0.95, 0.20, 0.70];
/// Default colour (sRGB) of objects.
pub const OBJECT: [f32; 3] = [0.72, 0.55, 0.34];

/// One actor as drawn: its skeleton, every joint's world transform and its overlays.
#[derive(Clone, Debug)]
pub struct ActorFrame {
    /// The actor's name.
    pub name: String,
    /// The shared skeleton (solids, joint tree, end sites).
    pub skeleton: Arc<Skeleton>,
    /// World transform of every joint, by joint index.
    pub globals: Vec<Transform>,
    /// Grasp state of the left and right hands.
    pub hands: [HandState; 2],
    /// Text labels (e.g. running actions), drawn under the name above the head (printable
    /// ASCII; other characters show as `?`).
    pub labels: Vec<String>,
}

impl ActorFrame {
    /// World position of the joint called `name`.
    pub fn joint_position(&self, name: &str) -> Option<Vec3> {
        let j = self.skeleton.joint(name).ok()?;
        self.globals.get(j).map(|t| t.translation.as_vec3())
    }

    /// World position of the centre of the solid called `name` (e.g. `r_hand`).
    pub fn solid_center(&self, name: &str) -> Option<Vec3> {
        let (joint, solid) = self
            .skeleton
            .solids()
            .iter()
            .find(|(_, s)| s.name == name)?;
        let g = self.globals.get(*joint)?;
        Some(g.transform_point(solid.center).as_vec3())
    }

    /// Every joint position and end site in world space.
    pub fn points(&self) -> impl Iterator<Item = Vec3> + '_ {
        let joints = self.globals.iter().map(|t| t.translation.as_vec3());
        let ends = self
            .skeleton
            .end_sites()
            .iter()
            .filter_map(|(j, off)| Some(self.globals.get(*j)?.transform_point(*off).as_vec3()));
        joints.chain(ends)
    }

    /// Where the name and labels are anchored: 12 cm above the top of the head (the end
    /// site of the `skullbase` joint), or above the highest point without one.
    pub fn label_anchor(&self) -> Option<Vec3> {
        let head = self.skeleton.joint("skullbase").ok().and_then(|j| {
            let (_, off) = self.skeleton.end_sites().iter().find(|(e, _)| *e == j)?;
            Some(self.globals.get(j)?.transform_point(*off).as_vec3())
        });
        let top = head.or_else(|| self.points().reduce(|a, b| if b.y > a.y { b } else { a }))?;
        Some(top + Vec3::Y * 0.12)
    }

    /// Sets the grasp state of one hand.
    pub fn set_hand(&mut self, hand: Hand, state: HandState) {
        self.hands[hand as usize] = state;
    }
}

/// One rigid object as drawn.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectFrame {
    /// The object's name.
    pub name: String,
    /// Its shape in the canonical frame.
    pub shape: Shape,
    /// World position of the shape's centre.
    pub position: Vec3,
    /// World orientation.
    pub rotation: Quat,
    /// sRGB colour.
    pub color: [f32; 3],
}

/// A sphere sensor (thesis 4.7): dark grey, light grey while touching.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sensor {
    /// World position of the centre.
    pub position: Vec3,
    /// Radius in metres.
    pub radius: f32,
    /// Whether it touches something.
    pub touching: bool,
}

/// An owned snapshot of a scene ready to render, with overlays.
#[derive(Clone, Debug, Default)]
pub struct Frame {
    /// Scene time in seconds.
    pub time: f64,
    /// The actors, in scene order.
    pub actors: Vec<ActorFrame>,
    /// The objects, in scene order.
    pub objects: Vec<ObjectFrame>,
    /// Sphere sensors to draw.
    pub sensors: Vec<Sensor>,
    /// IK targets (world points) to draw as small markers.
    pub ik_targets: Vec<Vec3>,
    /// Lines of text shown in the top-left corner whatever the options (e.g. the error
    /// of a scene that failed to reload, over the last good one).
    pub notice: Vec<String>,
}

impl Frame {
    /// Snapshots every actor and object of `scene`; each actor's labels are its actions
    /// that have not ended (`kind (status)`). Hands start free; add other overlays after.
    pub fn from_scene(scene: &Scene) -> Frame {
        let actors = scene
            .actors()
            .iter()
            .zip(scene.states())
            .enumerate()
            .map(|(i, (info, state))| ActorFrame {
                name: info.name.clone(),
                skeleton: info.skeleton.clone(),
                globals: state.globals.clone(),
                hands: [HandState::Free; 2],
                labels: scene
                    .actions_of(i)
                    .iter()
                    .filter(|a| a.status != Status::Pending)
                    .map(|a| format!("{} ({})", a.kind, a.status.name()))
                    .collect(),
            })
            .collect();
        let objects = scene
            .objects()
            .iter()
            .map(|o| ObjectFrame {
                name: o.name.clone(),
                shape: o.shape,
                position: o.position.as_vec3(),
                rotation: o.rotation.as_quat(),
                color: OBJECT,
            })
            .collect();
        Frame {
            time: scene.time(),
            actors,
            objects,
            sensors: Vec::new(),
            ik_targets: Vec::new(),
            notice: Vec::new(),
        }
    }

    /// The actor called `name`.
    pub fn actor(&self, name: &str) -> Option<&ActorFrame> {
        self.actors.iter().find(|a| a.name == name)
    }

    /// Mutable access to the actor called `name`.
    pub fn actor_mut(&mut self, name: &str) -> Option<&mut ActorFrame> {
        self.actors.iter_mut().find(|a| a.name == name)
    }

    /// Axis-aligned bounds `(min, max)` of every actor point and object centre, or `None`
    /// for an empty frame.
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let mut pts = self
            .actors
            .iter()
            .flat_map(|a| a.points())
            .chain(self.objects.iter().map(|o| o.position))
            .peekable();
        let first = *pts.peek()?;
        Some(pts.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p))))
    }
}
