//! The camera: what it looks at (all actors, one actor, a fixed point) and from where
//! (yaw and pitch about the focus, distance), with the projection shared by the renderer
//! and by tests that need to know where a world point lands on screen.

use crate::frame::Frame;
use crate::ViewerError;
use glam::{Mat4, Vec2, Vec3, Vec4};
use std::str::FromStr;

/// What the camera looks at.
#[derive(Clone, Debug, PartialEq)]
pub enum Focus {
    /// The centre of every actor and object; the distance fits them all when automatic.
    FitAll,
    /// The pelvis (root joint) of the actor with this name; falls back to
    /// [`Focus::FitAll`] while no such actor is in the frame.
    Actor(String),
    /// A fixed world point.
    Point(Vec3),
}

/// A perspective camera orbiting a focus point.
///
/// The eye sits at `focus + pan + distance · (sin yaw · cos pitch, sin pitch, cos yaw · cos pitch)`:
/// yaw 0 looks at the actors' faces (they face +Z), positive pitch looks down.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// What it looks at.
    pub focus: Focus,
    /// Offset added to the focus point (mouse panning).
    pub pan: Vec3,
    /// Orbit angle about +Y in degrees.
    pub yaw_degrees: f32,
    /// Elevation in degrees (−89 … 89).
    pub pitch_degrees: f32,
    /// Eye distance from the focus in metres; `None` picks one that frames the focus.
    pub distance: Option<f32>,
    /// Vertical field of view in degrees.
    pub fov_y_degrees: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera::fit()
    }
}

/// Default distance when following one actor.
const FOLLOW_DISTANCE: f32 = 3.6;

impl Camera {
    /// Frames every actor (the default): a three-quarter front view from slightly above.
    pub fn fit() -> Camera {
        Camera {
            focus: Focus::FitAll,
            pan: Vec3::ZERO,
            yaw_degrees: 25.0,
            pitch_degrees: 12.0,
            distance: None,
            fov_y_degrees: 40.0,
        }
    }

    /// Follows the actor called `name`.
    pub fn follow(name: impl Into<String>) -> Camera {
        Camera {
            focus: Focus::Actor(name.into()),
            ..Camera::fit()
        }
    }

    /// A fixed eye looking at `target`.
    pub fn fixed(eye: Vec3, target: Vec3) -> Camera {
        let d = eye - target;
        let distance = d.length().max(1e-3);
        Camera {
            focus: Focus::Point(target),
            pan: Vec3::ZERO,
            yaw_degrees: d.x.atan2(d.z).to_degrees(),
            pitch_degrees: (d.y / distance).clamp(-1.0, 1.0).asin().to_degrees(),
            distance: Some(distance),
            fov_y_degrees: 40.0,
        }
    }

    /// Sets the orbit angles (degrees).
    pub fn with_angles(mut self, yaw_degrees: f32, pitch_degrees: f32) -> Camera {
        self.yaw_degrees = yaw_degrees;
        self.pitch_degrees = pitch_degrees.clamp(-89.0, 89.0);
        self
    }

    /// Sets the eye distance (metres).
    pub fn with_distance(mut self, distance: f32) -> Camera {
        self.distance = Some(distance);
        self
    }

    fn direction(&self) -> Vec3 {
        let (yaw, pitch) = (
            self.yaw_degrees.to_radians(),
            self.pitch_degrees.clamp(-89.0, 89.0).to_radians(),
        );
        Vec3::new(
            yaw.sin() * pitch.cos(),
            pitch.sin(),
            yaw.cos() * pitch.cos(),
        )
    }

    /// The eye position and the point looked at, for `frame` seen at `aspect` (width / height).
    pub fn eye_target(&self, frame: &Frame, aspect: f32) -> (Vec3, Vec3) {
        let back = self.direction();
        let fit = |frame: &Frame| -> (Vec3, f32) {
            let Some((lo, hi)) = frame.bounds() else {
                return (Vec3::new(0.0, 0.9, 0.0), 4.0);
            };
            let center = (lo + hi) * 0.5;
            // Pad the box so a lone actor is not framed edge to edge.
            let half = ((hi - lo) * 0.5).max(Vec3::splat(0.25)) + Vec3::splat(0.1);
            let right = Vec3::Y.cross(back).normalize();
            let up = back.cross(right);
            let tan_y = (self.fov_y_degrees.clamp(5.0, 150.0) * 0.5)
                .to_radians()
                .tan();
            let tan_x = tan_y * aspect.max(0.05);
            // Each corner of the box must lie inside the view frustum: with (x, y, z) its
            // offset along (right, up, back), |x| ≤ (d − z)·tan_x and |y| ≤ (d − z)·tan_y.
            let mut d: f32 = 0.5;
            for i in 0..8 {
                let sign = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
                let p = half * Vec3::new(sign(1), sign(2), sign(4));
                let (x, y, z) = (p.dot(right), p.dot(up), p.dot(back));
                d = d.max(z + x.abs() / tan_x).max(z + y.abs() / tan_y);
            }
            (center, d)
        };
        let (center, auto) = match &self.focus {
            Focus::FitAll => fit(frame),
            Focus::Actor(name) => match frame.actor(name) {
                Some(a) => {
                    let root = a.globals.first().map(|t| t.translation.as_vec3());
                    (root.unwrap_or(Vec3::ZERO), FOLLOW_DISTANCE)
                }
                None => fit(frame),
            },
            Focus::Point(p) => (*p, 4.0),
        };
        let target = center + self.pan;
        let distance = self.distance.unwrap_or(auto).max(0.05);
        (target + self.direction() * distance, target)
    }

    /// The view-projection matrix (wgpu clip space, depth 0…1) for `frame` at `aspect`.
    pub fn view_projection(&self, frame: &Frame, aspect: f32) -> Mat4 {
        let (eye, target) = self.eye_target(frame, aspect);
        let distance = (eye - target).length();
        let far = (distance * 4.0 + 100.0).max(200.0);
        let proj = perspective(
            self.fov_y_degrees.clamp(5.0, 150.0).to_radians(),
            aspect.max(1e-3),
            0.05,
            far,
        );
        proj * look_at(eye, target, Vec3::Y)
    }

    /// Where the world point `p` lands in a `width`×`height` picture of `frame`, in pixels
    /// from the top-left corner; `None` when it is behind the eye.
    pub fn project(&self, frame: &Frame, width: u32, height: u32, p: Vec3) -> Option<Vec2> {
        let vp = self.view_projection(frame, width as f32 / height as f32);
        let c = vp * Vec4::new(p.x, p.y, p.z, 1.0);
        if c.w <= 1e-6 {
            return None;
        }
        let ndc = c.truncate() / c.w;
        Some(Vec2::new(
            (ndc.x * 0.5 + 0.5) * width as f32,
            (0.5 - ndc.y * 0.5) * height as f32,
        ))
    }
}

/// Right-handed perspective projection onto wgpu's clip space (depth 0 at `near`, 1 at `far`).
fn perspective(fov_y: f32, aspect: f32, near: f32, far: f32) -> Mat4 {
    let f = 1.0 / (fov_y * 0.5).tan();
    let r = far / (near - far);
    Mat4::from_cols(
        Vec4::new(f / aspect, 0.0, 0.0, 0.0),
        Vec4::new(0.0, f, 0.0, 0.0),
        Vec4::new(0.0, 0.0, r, -1.0),
        Vec4::new(0.0, 0.0, r * near, 0.0),
    )
}

/// Right-handed view matrix: the eye looks down −Z with `up` roughly +Y.
fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let f = (target - eye).normalize();
    let s = f.cross(up).normalize();
    let u = s.cross(f);
    Mat4::from_cols(
        Vec4::new(s.x, u.x, -f.x, 0.0),
        Vec4::new(s.y, u.y, -f.y, 0.0),
        Vec4::new(s.z, u.z, -f.z, 0.0),
        Vec4::new(-s.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
    )
}

fn parse_floats<const N: usize>(s: &str, what: &str) -> Result<[f32; N], ViewerError> {
    let bad = || {
        ViewerError::Invalid(format!(
            "camera: `{s}` is not {N} comma-separated numbers ({what})"
        ))
    };
    let v: Vec<f32> = s
        .split(',')
        .map(|t| t.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad())?;
    if v.iter().any(|x| !x.is_finite()) {
        return Err(bad());
    }
    v.try_into().map_err(|_| bad())
}

impl FromStr for Camera {
    type Err = ViewerError;

    /// Parses a camera spec:
    /// - `fit` — frame every actor (default);
    /// - `follow:NAME` — follow the actor `NAME`;
    /// - `fixed:EX,EY,EZ:TX,TY,TZ` — eye and target in metres;
    ///
    /// `fit` and `follow` take an optional `@YAW,PITCH[,DISTANCE]` suffix (degrees, metres),
    /// e.g. `fit@-30,20` or `follow:ann@180,10,4`.
    fn from_str(spec: &str) -> Result<Camera, ViewerError> {
        let spec = spec.trim();
        if let Some(rest) = spec.strip_prefix("fixed:") {
            let (eye, target) = rest.split_once(':').ok_or_else(|| {
                ViewerError::Invalid(format!(
                    "camera: `{spec}` should be fixed:EX,EY,EZ:TX,TY,TZ"
                ))
            })?;
            let e = parse_floats::<3>(eye, "eye x,y,z")?;
            let t = parse_floats::<3>(target, "target x,y,z")?;
            return Ok(Camera::fixed(Vec3::from(e), Vec3::from(t)));
        }
        let (base, angles) = match spec.split_once('@') {
            Some((b, a)) => (b, Some(a)),
            None => (spec, None),
        };
        let mut camera = if base == "fit" {
            Camera::fit()
        } else if let Some(name) = base.strip_prefix("follow:").filter(|n| !n.is_empty()) {
            Camera::follow(name)
        } else {
            return Err(ViewerError::Invalid(format!(
                "camera: unknown spec `{spec}`; use fit, follow:NAME or fixed:EX,EY,EZ:TX,TY,TZ \
                 (fit and follow accept @YAW,PITCH[,DISTANCE])"
            )));
        };
        if let Some(a) = angles {
            let n = a.split(',').count();
            let v: Vec<f32> = match n {
                2 => parse_floats::<2>(a, "yaw,pitch")?.to_vec(),
                _ => parse_floats::<3>(a, "yaw,pitch,distance")?.to_vec(),
            };
            camera = camera.with_angles(v[0], v[1]);
            if let Some(&d) = v.get(2) {
                if d <= 0.0 {
                    return Err(ViewerError::Invalid(format!(
                        "camera: distance {d} must be > 0 metres"
                    )));
                }
                camera = camera.with_distance(d);
            }
        }
        Ok(camera)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_specs() {
        assert_eq!("fit".parse::<Camera>().unwrap(), Camera::fit());
        let c: Camera = "follow:ann@180,10,4".parse().unwrap();
        assert_eq!(c.focus, Focus::Actor("ann".into()));
        assert_eq!((c.yaw_degrees, c.pitch_degrees), (180.0, 10.0));
        assert_eq!(c.distance, Some(4.0));
        let f: Camera = "fixed:0,1,5:0,1,0".parse().unwrap();
        assert_eq!(f.focus, Focus::Point(Vec3::new(0.0, 1.0, 0.0)));
        assert!((f.distance.unwrap() - 5.0).abs() < 1e-5);
        assert!(f.yaw_degrees.abs() < 1e-4 && f.pitch_degrees.abs() < 1e-4);
        assert!("orbit".parse::<Camera>().is_err());
        assert!("fit@1".parse::<Camera>().is_err());
        assert!("fixed:1,2:3,4,5".parse::<Camera>().is_err());
    }

    #[test]
    fn fixed_camera_projects_target_to_centre() {
        let c = Camera::fixed(Vec3::new(2.0, 3.0, 4.0), Vec3::new(0.0, 1.0, 0.0));
        let (eye, target) = c.eye_target(&Frame::default(), 1.0);
        assert!((eye - Vec3::new(2.0, 3.0, 4.0)).length() < 1e-4);
        assert!((target - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-6);
        let p = c
            .project(&Frame::default(), 200, 100, Vec3::new(0.0, 1.0, 0.0))
            .unwrap();
        assert!((p - Vec2::new(100.0, 50.0)).length() < 1e-3);
        // A point above the target appears above the centre (smaller y).
        let up = c
            .project(&Frame::default(), 200, 100, Vec3::new(0.0, 1.5, 0.0))
            .unwrap();
        assert!(up.y < 50.0);
    }
}
