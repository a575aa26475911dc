//! Body templates (Bodylib, thesis 6.5.4): one humanoid topology with H-Anim joint names,
//! instantiated with scale parameters. `adult` and `child` differ in proportions only.
//!
//! Frame convention at rest (every DOF zero): Y up, the actor faces +Z, its left side is
//! +X, arms hang at the sides with the palms facing the thighs, and the soles touch the
//! floor y = 0 when `root_y` is 0. Right-side axes mirror the left ones, so a positive
//! value means the same anatomical motion on both sides.

use crate::error::{Error, Result};
use crate::skeleton::{DofKind, Skeleton, SkeletonBuilder};
use crate::solid::{Shape, Solid};
use glam::{DQuat, DVec3};
use std::f64::consts::FRAC_PI_2;

/// Parameters of a template instance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TemplateParams {
    /// Standing height in metres (floor to the top of the head).
    pub height: f64,
    /// Total body mass in kilograms.
    pub mass: f64,
}

/// A body template: a name and the proportions that shape its instances.
#[derive(Clone, Debug)]
pub struct Template {
    /// Template name (`adult`, `child`).
    pub name: &'static str,
    /// One line for listings.
    pub description: &'static str,
    /// Height used when none is given.
    pub default_height: f64,
    /// Mass used when none is given.
    pub default_mass: f64,
    proportions: Proportions,
}

/// Heights and lengths as fractions of standing height (after Drillis & Contini).
#[derive(Clone, Copy, Debug)]
struct Proportions {
    hip: f64,
    knee: f64,
    ankle: f64,
    shoulder: f64,
    skullbase: f64,
    hip_half_width: f64,
    shoulder_half_width: f64,
    upper_arm: f64,
    forearm: f64,
    hand: f64,
    foot: f64,
    head_radii: DVec3,
    trunk_radius: f64,
}

const ADULT: Proportions = Proportions {
    hip: 0.530,
    knee: 0.285,
    ankle: 0.039,
    shoulder: 0.818,
    skullbase: 0.895,
    hip_half_width: 0.052,
    shoulder_half_width: 0.130,
    upper_arm: 0.186,
    forearm: 0.146,
    hand: 0.108,
    foot: 0.152,
    head_radii: DVec3::new(0.046, 0.066, 0.056),
    trunk_radius: 0.085,
};

const CHILD: Proportions = Proportions {
    hip: 0.490,
    knee: 0.262,
    ankle: 0.040,
    shoulder: 0.790,
    skullbase: 0.862,
    hip_half_width: 0.055,
    shoulder_half_width: 0.125,
    upper_arm: 0.178,
    forearm: 0.138,
    hand: 0.105,
    foot: 0.155,
    head_radii: DVec3::new(0.062, 0.083, 0.074),
    trunk_radius: 0.090,
};

/// The templates troupe knows.
pub fn templates() -> Vec<Template> {
    vec![
        Template {
            name: "adult",
            description: "adult humanoid, adult proportions",
            default_height: 1.75,
            default_mass: 70.0,
            proportions: ADULT,
        },
        Template {
            name: "child",
            description: "child of about seven: larger head, shorter legs",
            default_height: 1.20,
            default_mass: 23.0,
            proportions: CHILD,
        },
    ]
}

/// Instantiates template `name` with its default parameters.
pub fn default_skeleton(name: &str) -> Result<Skeleton> {
    let t = template(name)?;
    t.instantiate(t.default_params())
}

/// Looks up a template by name.
pub fn template(name: &str) -> Result<Template> {
    templates()
        .into_iter()
        .find(|t| t.name == name)
        .ok_or_else(|| Error::UnknownTemplate {
            name: name.to_string(),
            known: templates()
                .iter()
                .map(|t| t.name)
                .collect::<Vec<_>>()
                .join(", "),
        })
}

impl Template {
    /// The template's default parameters.
    pub fn default_params(&self) -> TemplateParams {
        TemplateParams {
            height: self.default_height,
            mass: self.default_mass,
        }
    }

    /// Builds a skeleton instance; `height` must lie in [0.3, 3] m, `mass` in [1, 500] kg.
    pub fn instantiate(&self, params: TemplateParams) -> Result<Skeleton> {
        if !(0.3..=3.0).contains(&params.height) {
            return Err(Error::invalid_value(
                "template height",
                params.height,
                "0.3 to 3 metres",
            ));
        }
        if !(1.0..=500.0).contains(&params.mass) {
            return Err(Error::invalid_value(
                "template mass",
                params.mass,
                "1 to 500 kg",
            ));
        }
        Body::new(self.name, self.proportions, params).build()
    }
}

/// Mass fractions of the 15 body solids (thesis figure 3-1 (b)); they sum to 1.
pub const MASS_FRACTIONS: [(&str, f64); 9] = [
    ("head_neck", 0.081),
    ("up_torso", 0.216),
    ("down_torso", 0.281),
    ("hand", 0.006),
    ("upper_arm", 0.028),
    ("forearm", 0.016),
    ("thigh", 0.100),
    ("leg", 0.0465),
    ("foot", 0.0145),
];

fn mass_fraction(name: &str) -> f64 {
    MASS_FRACTIONS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, f)| *f)
        .unwrap_or(0.0)
}

/// Which side a limb is on; the right side mirrors the left across the sagittal plane.
#[derive(Clone, Copy, PartialEq)]
enum Side {
    Left,
    Right,
}

impl Side {
    fn prefix(self) -> &'static str {
        match self {
            Side::Left => "l_",
            Side::Right => "r_",
        }
    }
    /// Mirrors a left-side position.
    fn point(self, p: DVec3) -> DVec3 {
        match self {
            Side::Left => p,
            Side::Right => DVec3::new(-p.x, p.y, p.z),
        }
    }
    /// Mirrors a left-side rotation axis so that positive angles mean the same motion.
    fn axis(self, a: DVec3) -> DVec3 {
        match self {
            Side::Left => a,
            Side::Right => DVec3::new(a.x, -a.y, -a.z),
        }
    }
}

/// Builds one instance: positions are computed in the rest pose (actor frame, metres) and
/// turned into parent-relative offsets.
struct Body {
    b: SkeletonBuilder,
    p: Proportions,
    h: f64,
    mass: f64,
    rest: Vec<DVec3>,
}

const X: DVec3 = DVec3::X;
const Y: DVec3 = DVec3::Y;
const Z: DVec3 = DVec3::Z;

/// The thoracolumbar spine's ranges, in degrees, per joint: (flexion's extension and
/// flexion, lateral bend and torsion each way). A person's trunk flexes about 80°
/// against the pelvis, extends 25°, bends 35° to each side and twists 45° each way
/// (American Academy of Orthopaedic Surgeons, *Joint Motion: Method of Measuring and
/// Recording*, 1965, the normal values also in Greene & Heckman, *The Clinical
/// Measurement of Joint Motion*, AAOS 1994); the lumbar spine takes most of the flexion
/// and little of the twist, the thoracic spine the reverse (White & Panjabi, *Clinical
/// Biomechanics of the Spine*, 2nd ed. 1990, chapter 2). The four joints here
/// add up to those ranges less the sacroiliac's 10° each way (the pelvis turning against
/// the trunk): flexion 40 + 15 + 8 + 7 = 70, extension 10 + 5 = 15, lateral bend
/// 8 + 7 + 5 + 5 = 25, torsion 5 + 10 + 10 + 10 = 35. (They were 60° of flexion and 30° of
/// everything else per joint, which summed to a trunk bent double and twisted by 120°.)
const TRUNK: [(&str, (f64, f64), f64, f64); 4] = [
    ("vl5", (-10.0, 40.0), 8.0, 5.0),
    ("vt12", (-5.0, 15.0), 7.0, 10.0),
    ("vt6", (0.0, 8.0), 5.0, 10.0),
    ("vt1", (0.0, 7.0), 5.0, 10.0),
];

fn deg(d: f64) -> f64 {
    d.to_radians()
}

impl Body {
    fn new(name: &str, p: Proportions, params: TemplateParams) -> Self {
        Body {
            b: SkeletonBuilder::new(name),
            p,
            h: params.height,
            mass: params.mass,
            rest: Vec::new(),
        }
    }

    /// Adds a joint at rest position `at` (fractions of height) under `parent`.
    fn joint(&mut self, name: &str, parent: Option<&str>, at: DVec3) -> Result<()> {
        let at = at * self.h;
        let offset = match parent {
            Some(p) => at - self.rest[self.b.current().joint(p)?],
            None => at,
        };
        self.b.joint(name, parent, offset)?;
        self.rest.push(at);
        Ok(())
    }

    fn rot(&mut self, name: &str, axis: DVec3, min_deg: f64, max_deg: f64) -> Result<()> {
        self.b
            .dof(name, DofKind::Rotation, axis, deg(min_deg), deg(max_deg))
            .map(|_| ())
    }

    fn solid(
        &mut self,
        joint: &str,
        name: &str,
        shape: Shape,
        center: DVec3,
        o: DQuat,
    ) -> Result<()> {
        let fraction = mass_fraction(name.trim_start_matches("l_").trim_start_matches("r_"));
        let solid = Solid::new(name, shape, center * self.h, o, fraction * self.mass);
        self.b.solid(joint, solid)
    }

    fn frustum(&self, bottom: f64, top: f64, length: f64) -> Shape {
        Shape::Frustum {
            bottom_radius: bottom * self.h,
            top_radius: top * self.h,
            height: length * self.h,
        }
    }

    fn build(mut self) -> Result<Skeleton> {
        let p = self.p;
        let root_y = p.hip + 0.02;
        let inf = f64::INFINITY;

        self.joint("HumanoidRoot", None, DVec3::new(0.0, root_y, 0.0))?;
        for (name, axis) in [("root_x", X), ("root_y", Y), ("root_z", Z)] {
            self.b.dof(name, DofKind::Translation, axis, -inf, inf)?;
        }
        for (name, axis) in [("root_yaw", Y), ("root_pitch", X), ("root_roll", Z)] {
            self.b.dof(name, DofKind::Rotation, axis, -inf, inf)?;
        }

        self.joint(
            "sacroiliac",
            Some("HumanoidRoot"),
            DVec3::new(0.0, root_y, 0.0),
        )?;
        // The pelvis turns against the trunk (whose spine hangs from the root too), so its
        // range is part of the thoracolumbar spine's: see `TRUNK` in `spine_and_head`.
        self.rot("sacroiliac_tilt", X, -10.0, 10.0)?;
        self.rot("sacroiliac_obliquity", -Z, -10.0, 10.0)?;
        self.rot("sacroiliac_rotation", Y, -10.0, 10.0)?;

        for side in [Side::Left, Side::Right] {
            self.leg(side)?;
        }
        self.spine_and_head()?;
        for side in [Side::Left, Side::Right] {
            self.arm(side)?;
            self.hand(side)?;
        }
        self.scopes()?;
        self.b.build()
    }

    fn leg(&mut self, side: Side) -> Result<()> {
        let p = self.p;
        let s = side.prefix();
        let x = p.hip_half_width;
        let j = |n: &str| format!("{s}{n}");
        let at = |v: DVec3| side.point(v);
        self.joint(&j("hip"), Some("sacroiliac"), at(DVec3::new(x, p.hip, 0.0)))?;
        // The AAOS's normal ranges (see `TRUNK`): flexion 120°, extension 30°, abduction
        // 45°, adduction 30°, rotation 45° each way.
        self.rot(&j("hip_flexion"), side.axis(-X), -30.0, 120.0)?;
        self.rot(&j("hip_abduction"), side.axis(Z), -30.0, 45.0)?;
        self.rot(&j("hip_twist"), side.axis(-Y), -45.0, 45.0)?;
        self.joint(&j("knee"), Some(&j("hip")), at(DVec3::new(x, p.knee, 0.0)))?;
        self.rot(&j("knee_flexion"), side.axis(X), 0.0, 150.0)?;
        self.joint(
            &j("ankle"),
            Some(&j("knee")),
            at(DVec3::new(x, p.ankle, 0.0)),
        )?;
        self.rot(&j("ankle_flexion"), side.axis(-X), -50.0, 30.0)?;
        let subtalar_y = p.ankle * 0.8;
        self.joint(
            &j("subtalar"),
            Some(&j("ankle")),
            at(DVec3::new(x, subtalar_y, 0.0)),
        )?;
        self.rot(&j("subtalar_inversion"), side.axis(-Z), -25.0, 35.0)?;
        let ball = DVec3::new(x + 0.004, 0.012, p.foot * 0.69);
        self.joint(&j("metatarsal"), Some(&j("subtalar")), at(ball))?;
        self.rot(&j("metatarsal_flexion"), side.axis(X), -60.0, 40.0)?;
        let tip = (at(DVec3::new(x + 0.006, 0.008, p.foot * 0.85)) - at(ball)) * self.h;
        self.b.end_site(&j("metatarsal"), tip)?;

        let hip_to_knee = p.hip - p.knee;
        let knee_to_ankle = p.knee - p.ankle;
        let thigh = self.frustum(0.030, 0.046, hip_to_knee);
        self.solid(
            &j("hip"),
            &j("thigh"),
            thigh,
            DVec3::new(0.0, -hip_to_knee / 2.0, 0.0),
            DQuat::IDENTITY,
        )?;
        let leg = self.frustum(0.020, 0.030, knee_to_ankle);
        self.solid(
            &j("knee"),
            &j("leg"),
            leg,
            DVec3::new(0.0, -knee_to_ankle / 2.0, 0.0),
            DQuat::IDENTITY,
        )?;
        // The foot runs from the heel (-Z) to the toes (+Z): rotate the frustum's +Y onto +Z.
        let heel = -p.foot * 0.2;
        let toes = p.foot * 0.85;
        let foot = self.frustum(0.020, 0.024, toes - heel);
        let center = side.point(DVec3::new(0.003, -subtalar_y + 0.022, (toes + heel) / 2.0));
        self.solid(
            &j("subtalar"),
            &j("foot"),
            foot,
            center,
            DQuat::from_rotation_x(FRAC_PI_2),
        )?;
        Ok(())
    }

    fn spine_and_head(&mut self) -> Result<()> {
        let p = self.p;
        let root_y = p.hip + 0.02;
        let vl5 = root_y + 0.03;
        let vt1 = p.shoulder - 0.005;
        let vt12 = vl5 + (vt1 - vl5) * 0.35;
        let vt6 = vl5 + (vt1 - vl5) * 0.7;
        let vc4 = (vt1 + p.skullbase) / 2.0;
        let chain = [
            ("vl5", "HumanoidRoot", DVec3::new(0.0, vl5, -0.010)),
            ("vt12", "vl5", DVec3::new(0.0, vt12, -0.015)),
            ("vt6", "vt12", DVec3::new(0.0, vt6, -0.012)),
            ("vt1", "vt6", DVec3::new(0.0, vt1, -0.006)),
            ("vc4", "vt1", DVec3::new(0.0, vc4, 0.0)),
            ("skullbase", "vc4", DVec3::new(0.0, p.skullbase, 0.005)),
        ];
        for (name, parent, at) in chain {
            self.joint(name, Some(parent), at)?;
            let (flex, lat, tor) = match name {
                "vc4" => ((-40.0, 40.0), 30.0, 40.0),
                "skullbase" => ((-40.0, 40.0), 30.0, 50.0),
                _ => TRUNK
                    .iter()
                    .find(|(joint, ..)| *joint == name)
                    .map(|&(_, flex, lat, tor)| (flex, lat, tor))
                    .expect("every trunk joint has its range"),
            };
            self.rot(&format!("{name}_flexion"), X, flex.0, flex.1)?;
            self.rot(&format!("{name}_lateral_bend"), -Z, -lat, lat)?;
            self.rot(&format!("{name}_torsion"), Y, -tor, tor)?;
        }
        let eye_y = p.skullbase + p.head_radii.y * 0.6;
        for side in [Side::Left, Side::Right] {
            let name = format!("{}eyeball_joint", side.prefix());
            let at = side.point(DVec3::new(0.018, eye_y, p.head_radii.z * 0.9));
            self.joint(&name, Some("skullbase"), at)?;
            self.rot(&format!("{}eyeball_pan", side.prefix()), Y, -45.0, 45.0)?;
            self.rot(&format!("{}eyeball_tilt", side.prefix()), X, -35.0, 35.0)?;
        }
        let top = DVec3::new(0.0, (1.0 - p.skullbase) * self.h, 0.01 * self.h);
        self.b.end_site("skullbase", top)?;

        let head = Shape::Ellipsoid {
            radii: p.head_radii * self.h,
        };
        let head_center = DVec3::new(0.0, 1.0 - p.head_radii.y - p.skullbase, 0.012);
        self.solid("skullbase", "head_neck", head, head_center, DQuat::IDENTITY)?;
        let r = p.trunk_radius * self.h;
        let upper = Shape::Cylinder {
            radius: r,
            height: (vt1 - vt12) * self.h,
        };
        let upper_center = DVec3::new(0.0, (vt1 + vt12) / 2.0 - vt6, 0.005);
        self.solid("vt6", "up_torso", upper, upper_center, DQuat::IDENTITY)?;
        let lower = Shape::Cylinder {
            radius: r * 0.95,
            height: (vt12 - p.hip + 0.02) * self.h,
        };
        let lower_center = DVec3::new(0.0, (vt12 + p.hip - 0.02) / 2.0 - vl5, 0.005);
        self.solid("vl5", "down_torso", lower, lower_center, DQuat::IDENTITY)?;
        Ok(())
    }

    fn arm(&mut self, side: Side) -> Result<()> {
        let p = self.p;
        let s = side.prefix();
        let j = |n: &str| format!("{s}{n}");
        let at = |v: DVec3| side.point(v);
        let x = p.shoulder_half_width;
        let clavicle = DVec3::new(0.015, p.shoulder - 0.013, 0.03);
        self.joint(&j("sternoclavicular"), Some("vt1"), at(clavicle))?;
        self.rot(&j("sternoclavicular_elevation"), side.axis(Z), -10.0, 40.0)?;
        self.rot(
            &j("sternoclavicular_protraction"),
            side.axis(-Y),
            -20.0,
            30.0,
        )?;
        self.joint(
            &j("shoulder"),
            Some(&j("sternoclavicular")),
            at(DVec3::new(x, p.shoulder, 0.0)),
        )?;
        self.rot(&j("shoulder_flexion"), side.axis(-X), -60.0, 180.0)?;
        self.rot(&j("shoulder_abduction"), side.axis(Z), -30.0, 180.0)?;
        self.rot(&j("shoulder_twist"), side.axis(-Y), -90.0, 90.0)?;
        let elbow = p.shoulder - p.upper_arm;
        let wrist = elbow - p.forearm;
        self.joint(
            &j("elbow"),
            Some(&j("shoulder")),
            at(DVec3::new(x, elbow, 0.0)),
        )?;
        self.rot(&j("elbow_flexion"), side.axis(-X), 0.0, 150.0)?;
        self.rot(&j("elbow_pronation"), side.axis(-Y), -90.0, 90.0)?;
        self.joint(
            &j("wrist"),
            Some(&j("elbow")),
            at(DVec3::new(x, wrist, 0.0)),
        )?;
        self.rot(&j("wrist_flexion"), side.axis(-Z), -70.0, 80.0)?;
        self.rot(&j("wrist_deviation"), side.axis(-X), -30.0, 20.0)?;

        let upper = self.frustum(0.018, 0.024, p.upper_arm);
        self.solid(
            &j("shoulder"),
            &j("upper_arm"),
            upper,
            DVec3::new(0.0, -p.upper_arm / 2.0, 0.0),
            DQuat::IDENTITY,
        )?;
        let fore = self.frustum(0.013, 0.018, p.forearm);
        self.solid(
            &j("elbow"),
            &j("forearm"),
            fore,
            DVec3::new(0.0, -p.forearm / 2.0, 0.0),
            DQuat::IDENTITY,
        )?;
        let k = p.hand / ADULT.hand;
        let hand = Shape::Sphere {
            radius: 0.030 * k * self.h,
        };
        self.solid(
            &j("wrist"),
            &j("hand"),
            hand,
            DVec3::new(0.0, -0.042 * k, 0.003 * k),
            DQuat::IDENTITY,
        )?;
        Ok(())
    }

    /// The hand of thesis 4.2: a metacarpus flex (ring and pinky metacarpals), four fingers
    /// with flex, pivot, flex, flex, and a thumb with two DOFs at its base and two flexes.
    fn hand(&mut self, side: Side) -> Result<()> {
        let s = side.prefix();
        let k = self.p.hand / ADULT.hand;
        let wrist_name = format!("{s}wrist");
        let wrist = self.rest[self.b.current().joint(&wrist_name)?] / self.h;
        let at = |v: DVec3| wrist + side.point(v * k);
        // Rest positions relative to the wrist (fractions of an adult's height); the palm
        // faces -X on the left hand, fingers hang along -Y, the index is in front (+Z).
        let fingers: [(&str, [DVec3; 5]); 4] = [
            (
                "index",
                [
                    DVec3::new(0.0, -0.006, 0.012),
                    DVec3::new(0.0, -0.048, 0.016),
                    DVec3::new(0.0, -0.070, 0.017),
                    DVec3::new(0.0, -0.084, 0.017),
                    DVec3::new(0.0, -0.096, 0.017),
                ],
            ),
            (
                "middle",
                [
                    DVec3::new(0.0, -0.006, 0.004),
                    DVec3::new(0.0, -0.049, 0.005),
                    DVec3::new(0.0, -0.074, 0.005),
                    DVec3::new(0.0, -0.090, 0.005),
                    DVec3::new(0.0, -0.103, 0.005),
                ],
            ),
            (
                "ring",
                [
                    DVec3::new(0.0, -0.006, -0.004),
                    DVec3::new(0.0, -0.047, -0.006),
                    DVec3::new(0.0, -0.070, -0.007),
                    DVec3::new(0.0, -0.085, -0.007),
                    DVec3::new(0.0, -0.097, -0.007),
                ],
            ),
            (
                "pinky",
                [
                    DVec3::new(0.0, -0.006, -0.011),
                    DVec3::new(0.0, -0.043, -0.016),
                    DVec3::new(0.0, -0.060, -0.018),
                    DVec3::new(0.0, -0.071, -0.019),
                    DVec3::new(0.0, -0.081, -0.019),
                ],
            ),
        ];
        // Flexion curls a finger toward the palm (-X on the left hand): axis = -Z.
        // The pivot moves it toward the thumb (+Z): axis = -X.
        for (finger, pts) in fingers {
            let name = |i: usize| format!("{s}{finger}{i}");
            self.joint(&name(0), Some(&wrist_name), at(pts[0]))?;
            if finger == "ring" || finger == "pinky" {
                self.rot(&format!("{}_flexion", name(0)), side.axis(-Z), 0.0, 20.0)?;
            }
            self.joint(&name(1), Some(&name(0)), at(pts[1]))?;
            self.rot(&format!("{}_flexion", name(1)), side.axis(-Z), -20.0, 90.0)?;
            self.rot(&format!("{}_pivot", name(1)), side.axis(-X), -20.0, 20.0)?;
            self.joint(&name(2), Some(&name(1)), at(pts[2]))?;
            self.rot(&format!("{}_flexion", name(2)), side.axis(-Z), 0.0, 110.0)?;
            self.joint(&name(3), Some(&name(2)), at(pts[3]))?;
            self.rot(&format!("{}_flexion", name(3)), side.axis(-Z), 0.0, 80.0)?;
            self.b
                .end_site(&name(3), (at(pts[4]) - at(pts[3])) * self.h)?;
        }
        let thumb = [
            DVec3::new(-0.006, -0.012, 0.014),
            DVec3::new(-0.008, -0.030, 0.026),
            DVec3::new(-0.009, -0.046, 0.032),
            DVec3::new(-0.009, -0.058, 0.036),
        ];
        let palm_normal = -X;
        let axis_toward_palm = |from: DVec3, to: DVec3| (to - from).normalize().cross(palm_normal);
        let name = |i: usize| format!("{s}thumb{i}");
        self.joint(&name(1), Some(&wrist_name), at(thumb[0]))?;
        let base_axis = axis_toward_palm(thumb[0], thumb[1]);
        self.rot(
            &format!("{}_flexion", name(1)),
            side.axis(base_axis),
            -20.0,
            60.0,
        )?;
        self.rot(
            &format!("{}_abduction", name(1)),
            side.axis(-X),
            -10.0,
            70.0,
        )?;
        self.joint(&name(2), Some(&name(1)), at(thumb[1]))?;
        let a2 = axis_toward_palm(thumb[1], thumb[2]);
        self.rot(&format!("{}_flexion", name(2)), side.axis(a2), -10.0, 60.0)?;
        self.joint(&name(3), Some(&name(2)), at(thumb[2]))?;
        let a3 = axis_toward_palm(thumb[2], thumb[3]);
        self.rot(&format!("{}_flexion", name(3)), side.axis(a3), -15.0, 80.0)?;
        self.b
            .end_site(&name(3), (at(thumb[3]) - at(thumb[2])) * self.h)?;
        Ok(())
    }

    fn scopes(&mut self) -> Result<()> {
        let b = &mut self.b;
        b.scope("global", "HumanoidRoot")?;
        b.scope("pelvis", "sacroiliac")?;
        b.scope("spine", "vl5+vt12+vt6+vt1")?;
        b.scope("eyes", "l_eyeball_joint+r_eyeball_joint")?;
        b.scope("neck", "vc4")?;
        b.scope("head", "vc4+skullbase+eyes")?;
        for (side, s) in [("left", "l_"), ("right", "r_")] {
            let arm = format!("{s}sternoclavicular+{s}shoulder+{s}elbow+{s}wrist");
            b.scope(&format!("{side}_arm"), &arm)?;
            let leg = format!("{s}hip+{s}knee+{s}ankle+{s}subtalar+{s}metatarsal");
            b.scope(&format!("{side}_leg"), &leg)?;
            let hand: Vec<String> = b
                .current()
                .joints()
                .iter()
                .filter(|j| {
                    j.name.starts_with(s)
                        && ["thumb", "index", "middle", "ring", "pinky"]
                            .iter()
                            .any(|f| j.name[2..].starts_with(f))
                })
                .map(|j| j.name.clone())
                .collect();
            b.scope(&format!("{side}_hand"), &hand.join("+"))?;
        }
        b.scope("arms", "left_arm+right_arm")?;
        b.scope("hands", "left_hand+right_hand")?;
        b.scope("legs", "left_leg+right_leg")?;
        b.scope("torso", "pelvis+spine")?;
        b.scope("upper_body", "spine+head+arms+hands")?;
        b.scope("lower_body", "pelvis+legs")?;
        let all = b.current().all();
        b.scope_from("all", all);
        b.scope("body", "all-global")?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn adult() -> Skeleton {
        crate::template::default_skeleton("adult").unwrap()
    }

    #[test]
    fn dof_counts_meet_the_thesis_model() {
        let s = adult();
        let hand = s.scope("left_hand").unwrap().len();
        assert!(hand >= 20, "hand has {hand} DOFs");
        assert_eq!(hand, s.scope("right_hand").unwrap().len());
        let body = s.dof_count() - s.scope("hands").unwrap().len();
        assert!(body >= 60, "body has {body} DOFs");
        assert_eq!(s.scope("global").unwrap().len(), 6);
        assert_eq!(s.scope("body").unwrap().len(), s.dof_count() - 6);
    }

    #[test]
    fn adult_and_child_share_topology() {
        let a = adult();
        let c = template("child")
            .unwrap()
            .instantiate(template("child").unwrap().default_params())
            .unwrap();
        let names = |s: &Skeleton| s.dofs().iter().map(|d| d.name.clone()).collect::<Vec<_>>();
        assert_eq!(names(&a), names(&c));
        assert_eq!(
            a.scopes().keys().collect::<Vec<_>>(),
            c.scopes().keys().collect::<Vec<_>>()
        );
    }

    #[test]
    fn total_mass_is_the_parameter() {
        for mass in [23.0, 70.0, 120.5] {
            let s = template("adult")
                .unwrap()
                .instantiate(TemplateParams { height: 1.8, mass })
                .unwrap();
            assert!((s.total_mass() - mass).abs() < 1e-9, "{}", s.total_mass());
            assert_eq!(s.solids().len(), 15);
        }
        let sum: f64 = MASS_FRACTIONS
            .iter()
            .map(|(n, f)| {
                if ["head_neck", "up_torso", "down_torso"].contains(n) {
                    *f
                } else {
                    2.0 * f
                }
            })
            .sum();
        assert!((sum - 1.0).abs() < 1e-12);
    }

    #[test]
    fn h_anim_names_are_present() {
        let s = adult();
        for j in [
            "HumanoidRoot",
            "sacroiliac",
            "l_hip",
            "l_knee",
            "l_ankle",
            "vl5",
            "skullbase",
            "r_shoulder",
            "r_elbow",
            "r_wrist",
            "r_index1",
            "l_thumb3",
        ] {
            s.joint(j).unwrap();
        }
        s.dof("r_elbow_flexion").unwrap();
    }

    #[test]
    fn bad_parameters_are_errors() {
        let t = template("adult").unwrap();
        assert!(t
            .instantiate(TemplateParams {
                height: -1.0,
                mass: 70.0
            })
            .is_err());
        assert!(t
            .instantiate(TemplateParams {
                height: 1.7,
                mass: f64::NAN
            })
            .is_err());
        assert!(matches!(
            template("giant"),
            Err(Error::UnknownTemplate { .. })
        ));
    }

    #[test]
    fn scope_expressions() {
        let s = adult();
        let arm = s.scope("right_arm").unwrap();
        let both = s.scope("right_arm+right_hand").unwrap();
        assert_eq!(both.len(), arm.len() + s.scope("right_hand").unwrap().len());
        assert_eq!(s.scope("right_arm-r_elbow").unwrap().len(), arm.len() - 2);
        assert_eq!(s.scope("r_elbow_flexion").unwrap().len(), 1);
        assert_eq!(s.scope("arms&right_arm").unwrap(), arm);
        assert!(matches!(
            s.scope("right_arm+tail"),
            Err(Error::UnknownScope { .. })
        ));
        assert!(s.scope("right_arm+").is_err());
    }
}
