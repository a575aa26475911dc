//! The body's volumes: the inner layer of the skin (Skinlib's layered model, thesis
//! 6.5.2). Each volume is a rounded cone or an ellipsoid placed on a joint in the rest
//! pose, sized from the skeleton's solids and its height, so that every template and size
//! gets the same anatomy: a torso of stacked ellipsoids, limbs of rounded cones, a palm
//! and five fingers, a head with jaw, nose, ears and eye sockets holding eyeballs.

use crate::error::{Error, Result};
use crate::kinematics::forward_kinematics;
use crate::skeleton::Skeleton;
use crate::solid::Shape;
use crate::transform::Transform;
use glam::{DQuat, DVec3};

/// What a part of the skin is covered with, for colouring.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u8)]
pub enum Region {
    /// Bare skin: face, neck, forearms, hands.
    Skin = 0,
    /// The shirt: chest, belly, upper arms.
    Shirt = 1,
    /// The trousers: pelvis and legs.
    Trousers = 2,
    /// The shoes.
    Shoes = 3,
    /// The white of the eyes.
    Eye = 4,
    /// The pupils (the front of each eyeball), so that gaze reads.
    Pupil = 5,
}

/// A volume's shape in rest-pose coordinates.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Form {
    /// A capsule whose radius goes linearly from `ra` at `a` to `rb` at `b`.
    Cone {
        a: DVec3,
        b: DVec3,
        ra: f64,
        rb: f64,
    },
    /// An ellipsoid with semi-axes `radii` in the frame turned by `rotation`.
    Ellipsoid {
        center: DVec3,
        radii: DVec3,
        rotation: DQuat,
    },
}

/// How a volume joins the field built so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Join {
    /// Added (smoothly where it meets a volume of a neighbouring joint).
    Add,
    /// Carved out (an eye socket).
    Carve,
    /// Added with a sharp crease, after the carving (an eyeball in its socket).
    Insert,
}

/// One volume of the body.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Volume {
    pub form: Form,
    /// The joint it moves with.
    pub joint: usize,
    pub region: Region,
    pub join: Join,
    /// Width (m) of the smooth blend with volumes of neighbouring joints.
    pub blend: f64,
    /// Distance (m) over which a neighbouring joint's weight fades out.
    pub reach: f64,
}

impl Form {
    /// Signed distance (negative inside) from `p`; exact for cones of equal radii,
    /// a close bound for the others, which is all a smooth surface needs.
    pub fn distance(&self, p: DVec3) -> f64 {
        match *self {
            Form::Cone { a, b, ra, rb } => {
                let ab = b - a;
                let t = ((p - a).dot(ab) / ab.length_squared().max(1e-18)).clamp(0.0, 1.0);
                (p - (a + ab * t)).length() - (ra + (rb - ra) * t)
            }
            Form::Ellipsoid {
                center,
                radii,
                rotation,
            } => {
                let q = rotation.inverse() * (p - center);
                let k0 = (q / radii).length();
                let k1 = (q / (radii * radii)).length();
                if k1 < 1e-12 {
                    -radii.min_element()
                } else {
                    k0 * (k0 - 1.0) / k1
                }
            }
        }
    }

    /// The same form carried by the rigid motion `t`.
    pub fn moved(&self, t: &Transform) -> Form {
        match *self {
            Form::Cone { a, b, ra, rb } => Form::Cone {
                a: t.transform_point(a),
                b: t.transform_point(b),
                ra,
                rb,
            },
            Form::Ellipsoid {
                center,
                radii,
                rotation,
            } => Form::Ellipsoid {
                center: t.transform_point(center),
                radii,
                rotation: (t.rotation * rotation).normalize(),
            },
        }
    }

    /// Axis-aligned bounds.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match *self {
            Form::Cone { a, b, ra, rb } => {
                let r = DVec3::splat(ra.max(rb));
                (a.min(b) - r, a.max(b) + r)
            }
            Form::Ellipsoid { center, radii, .. } => {
                let r = DVec3::splat(radii.max_element());
                (center - r, center + r)
            }
        }
    }
}

/// The rest-pose joint frames of `skeleton` (every DOF at zero).
pub fn rest_globals(skeleton: &Skeleton) -> Vec<Transform> {
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &vec![0.0; skeleton.dof_count()], &mut globals);
    globals
}

/// How far the arms are raised sideways in the pose the skin is made in (radians): an
/// A-pose, as rigs are bound in. With the arms hanging (every DOF zero) an arm raised
/// overhead bent the armpit by 180° from where its weights were made, and the arm's skin
/// lay against the chest's; from 45° the largest bend is 135° and the armpit is open.
/// It took the worst full-range posture of the skin test from 35-75 inverted triangles
/// to 27-40, the shoulders' inversions over the 50 postures of the 1.75 m adult from 102
/// to none, and the worst stray from 0.047 to 0.036 × height; 30° and 60° each failed the
/// test for the 0.96 m child (11 inverted triangles at half ranges, and one at a
/// quarter).
pub const BIND_ABDUCTION: f64 = 45.0 * std::f64::consts::PI / 180.0;

/// How far each finger is spread at its first joint (its `pivot`, degrees, towards the
/// thumb) in the pose the skin is made in: the fingers apart, as rigs bind a hand, so that
/// the webs between them are open where the surface and the weights are made. Touching
/// (every DOF zero), the webs were one or two grid cells wide and the skin of a finger's
/// knuckle was shared with its neighbour's; a finger bent 75-90° beside a straight one
/// tore the web and turned its triangles over (85 of the skin test's 147 inverted
/// triangles were at the hands, summed over its six sizes' 50 full-range postures; 8-24
/// with the fingers spread 8-10° apart and [`BIND_METACARPAL`]). The ring finger's is
/// 9.9° rather than 10°: the worst posture of the 1.40 m adult (the armpit) and of the
/// 1.20 m child moves by 2-3 triangles with any change of the hand's mesh, and this is the
/// spread, of those measured, that makes no size's worst posture worse (see
/// `docs/skin-notes.md`, "The hands").
pub const BIND_FINGER_SPREAD: [(&str, f64); 4] = [
    ("index", 9.0),
    ("middle", 0.0),
    ("ring", -9.9),
    ("pinky", -18.0),
];

/// How far the ring and little fingers' metacarpals are flexed (degrees) in the pose the
/// skin is made in: the middle of their 0-20° range. The palm's skin is the wrist's, and
/// a metacarpal flexed 20° carries its knuckle about 2 cm towards the palm (a 1.75 m
/// adult's), against the still palm and the middle finger's knuckle beside it; from the
/// middle of the range it moves half as far either way. Alone it took the hands' inverted
/// triangles in the skin test from 85 to 44 (with the metacarpals held still in the
/// sampled postures, a throwaway measure, the skin made as before turned 39 over).
pub const BIND_METACARPAL: f64 = 10.0;

/// The posture the skin is made in: the rest pose with the arms raised sideways by
/// [`BIND_ABDUCTION`], the fingers spread ([`BIND_FINGER_SPREAD`]) and the ring and little
/// fingers' metacarpals half flexed ([`BIND_METACARPAL`]).
pub fn bind_posture(skeleton: &Skeleton) -> Vec<f64> {
    let mut q = vec![0.0; skeleton.dof_count()];
    for side in ["l_", "r_"] {
        if let Ok(d) = skeleton.dof(&format!("{side}shoulder_abduction")) {
            q[d] = BIND_ABDUCTION;
        }
        for (finger, spread) in BIND_FINGER_SPREAD {
            if let Ok(d) = skeleton.dof(&format!("{side}{finger}1_pivot")) {
                q[d] = spread.to_radians();
            }
            // Only the ring and little fingers' metacarpals have a DOF.
            if let Ok(d) = skeleton.dof(&format!("{side}{finger}0_flexion")) {
                q[d] = BIND_METACARPAL.to_radians();
            }
        }
    }
    q
}

/// The joint frames of `skeleton` in its [`bind_posture`].
pub fn bind_globals(skeleton: &Skeleton) -> Vec<Transform> {
    let mut globals = vec![Transform::IDENTITY; skeleton.joints().len()];
    forward_kinematics(skeleton, &bind_posture(skeleton), &mut globals);
    globals
}

/// `volumes`, laid out in the rest pose, each carried with its joint to the bind pose.
pub(crate) fn to_bind(skeleton: &Skeleton, volumes: &mut [Volume]) {
    let (rest, bind) = (rest_globals(skeleton), bind_globals(skeleton));
    for v in volumes {
        let motion = bind[v.joint].mul(&rest[v.joint].inverse());
        v.form = v.form.moved(&motion);
    }
}

/// Lays out the body volumes of a skeleton built from a troupe template (it needs the
/// template's H-Anim joint names and solids).
pub(crate) fn body_volumes(skeleton: &Skeleton) -> Result<Vec<Volume>> {
    Layout::new(skeleton)?.volumes()
}

struct Layout<'a> {
    skeleton: &'a Skeleton,
    rest: Vec<Transform>,
    /// Standing height: the top of the head.
    h: f64,
    out: Vec<Volume>,
}

impl<'a> Layout<'a> {
    fn new(skeleton: &'a Skeleton) -> Result<Self> {
        let rest = rest_globals(skeleton);
        let skull = skeleton.joint("skullbase")?;
        let top = skeleton
            .end_sites()
            .iter()
            .find(|(j, _)| *j == skull)
            .map(|(_, off)| rest[skull].transform_point(*off))
            .ok_or_else(|| {
                Error::Invalid(
                    "skin: the skullbase joint has no end site (the top of the head)".into(),
                )
            })?;
        Ok(Layout {
            skeleton,
            rest,
            h: top.y,
            out: Vec::new(),
        })
    }

    fn at(&self, joint: &str) -> Result<DVec3> {
        Ok(self.rest[self.skeleton.joint(joint)?].translation)
    }

    fn end(&self, joint: &str) -> Result<DVec3> {
        let j = self.skeleton.joint(joint)?;
        self.skeleton
            .end_sites()
            .iter()
            .find(|(e, _)| *e == j)
            .map(|(_, off)| self.rest[j].transform_point(*off))
            .ok_or_else(|| Error::Invalid(format!("skin: joint `{joint}` has no end site")))
    }

    /// The solid called `name`: its shape and rest-pose centre.
    fn solid(&self, name: &str) -> Result<(Shape, DVec3)> {
        let (j, s) = self
            .skeleton
            .solids()
            .iter()
            .find(|(_, s)| s.name == name)
            .ok_or_else(|| Error::Invalid(format!("skin: the skeleton has no solid `{name}`")))?;
        Ok((s.shape, self.rest[*j].transform_point(s.center)))
    }

    /// The bottom and top radii of a frustum solid.
    fn frustum_radii(&self, name: &str) -> Result<(f64, f64)> {
        match self.solid(name)?.0 {
            Shape::Frustum {
                bottom_radius,
                top_radius,
                ..
            } => Ok((bottom_radius, top_radius)),
            Shape::Cylinder { radius, .. } => Ok((radius, radius)),
            other => Err(Error::Invalid(format!(
                "skin: solid `{name}` is a {}, a frustum was expected",
                other.kind_name()
            ))),
        }
    }

    fn push(
        &mut self,
        joint: &str,
        region: Region,
        form: Form,
        blend: f64,
        reach: f64,
    ) -> Result<()> {
        let joint = self.skeleton.joint(joint)?;
        self.out.push(Volume {
            form,
            joint,
            region,
            join: Join::Add,
            blend: blend * self.h,
            reach: reach * self.h,
        });
        Ok(())
    }

    fn ellipsoid(
        &mut self,
        joint: &str,
        region: Region,
        center: DVec3,
        radii: DVec3,
        blend: f64,
        reach: f64,
    ) -> Result<()> {
        let form = Form::Ellipsoid {
            center,
            radii: radii * self.h,
            rotation: DQuat::IDENTITY,
        };
        self.push(joint, region, form, blend, reach)
    }

    fn volumes(mut self) -> Result<Vec<Volume>> {
        self.torso()?;
        self.head()?;
        for s in ["l_", "r_"] {
            self.arm(s)?;
            self.hand(s)?;
            self.leg(s)?;
        }
        Ok(self.out)
    }

    fn torso(&mut self) -> Result<()> {
        let h = self.h;
        let hip = self.at("l_hip")?.y;
        let (vl5, vt12, vt6, vt1) = (
            self.at("vl5")?,
            self.at("vt12")?,
            self.at("vt6")?,
            self.at("vt1")?,
        );
        let r = self.frustum_radii("up_torso")?.0 / h;
        // Centres on one vertical line and radii that change slowly from one to the
        // next, so that the smooth unions bulge evenly instead of leaving rings.
        let at = |y: f64| DVec3::new(0.0, y, 0.0);
        let stack = [
            (
                "sacroiliac",
                Region::Trousers,
                at(hip + 0.012 * h),
                DVec3::new(r * 1.08, 0.08, r * 0.76),
            ),
            (
                "vl5",
                Region::Shirt,
                at(vl5.y + 0.035 * h),
                DVec3::new(r * 1.0, 0.09, r * 0.72),
            ),
            (
                "vt12",
                Region::Shirt,
                at(vt12.y + 0.02 * h),
                DVec3::new(r * 1.04, 0.09, r * 0.74),
            ),
            (
                "vt6",
                Region::Shirt,
                at(vt6.y + 0.012 * h),
                DVec3::new(r * 1.1, 0.085, r * 0.76),
            ),
            (
                "vt1",
                Region::Shirt,
                at(vt1.y - 0.012 * h),
                DVec3::new(r * 1.18, 0.045, r * 0.62),
            ),
        ];
        for (joint, region, center, radii) in stack {
            self.ellipsoid(joint, region, center, radii, 0.03, 0.07)?;
        }
        Ok(())
    }

    fn head(&mut self) -> Result<()> {
        let h = self.h;
        let vt1 = self.at("vt1")?;
        let skull = self.at("skullbase")?;
        self.push(
            "vc4",
            Region::Skin,
            Form::Cone {
                a: vt1 + DVec3::new(0.0, 0.01 * h, 0.0),
                b: skull + DVec3::new(0.0, 0.012 * h, 0.0),
                ra: 0.030 * h,
                rb: 0.026 * h,
            },
            0.02,
            0.04,
        )?;
        let (shape, center) = self.solid("head_neck")?;
        let Shape::Ellipsoid { radii } = shape else {
            return Err(Error::Invalid(
                "skin: the head_neck solid is not an ellipsoid".into(),
            ));
        };
        let r = radii / h;
        self.ellipsoid("skullbase", Region::Skin, center, r, 0.015, 0.03)?;
        // Jaw and chin: a smaller ellipsoid low and forward.
        let jaw = center + DVec3::new(0.0, -0.5 * radii.y, 0.3 * radii.z);
        self.ellipsoid(
            "skullbase",
            Region::Skin,
            jaw,
            r * DVec3::new(0.75, 0.5, 0.6),
            0.012,
            0.03,
        )?;
        let eye_l = self.at("l_eyeball_joint")?;
        let front = |x: f64, y: f64| {
            center.z
                + radii.z
                    * (1.0 - (x / radii.x).powi(2) - ((y - center.y) / radii.y).powi(2))
                        .max(0.0)
                        .sqrt()
        };
        // Nose: from between the eyes down and out.
        let root = DVec3::new(0.0, eye_l.y - 0.004 * h, front(0.0, eye_l.y) - 0.006 * h);
        let tip = DVec3::new(
            0.0,
            eye_l.y - 0.024 * h,
            front(0.0, eye_l.y - 0.024 * h) + 0.009 * h,
        );
        self.push(
            "skullbase",
            Region::Skin,
            Form::Cone {
                a: root,
                b: tip,
                ra: 0.0035 * h,
                rb: 0.0065 * h,
            },
            0.006,
            0.02,
        )?;
        for s in ["l_", "r_"] {
            let eye = self.at(&format!("{s}eyeball_joint"))?;
            let side = eye.x.signum();
            // Ears: flat ellipsoids on the sides, at eye height, a little behind centre.
            let ear = DVec3::new(
                side * (radii.x + 0.002 * h),
                eye.y - 0.006 * h,
                center.z - 0.012 * h,
            );
            self.ellipsoid(
                "skullbase",
                Region::Skin,
                ear,
                DVec3::new(0.006, 0.018, 0.011),
                0.006,
                0.02,
            )?;
            // The socket is carved where the eyeball sits, the eyeball set in afterwards.
            let socket_joint = self.skeleton.joint("skullbase")?;
            let eyeball_z = front(eye.x, eye.y) - 0.009 * h;
            self.out.push(Volume {
                form: Form::Ellipsoid {
                    center: DVec3::new(eye.x, eye.y, eyeball_z + 0.006 * h),
                    radii: DVec3::new(0.014, 0.010, 0.009) * h,
                    rotation: DQuat::IDENTITY,
                },
                joint: socket_joint,
                region: Region::Skin,
                join: Join::Carve,
                blend: 0.005 * h,
                reach: 0.02 * h,
            });
            self.out.push(Volume {
                form: Form::Ellipsoid {
                    center: DVec3::new(eye.x, eye.y, eyeball_z),
                    radii: DVec3::splat(0.0072 * h),
                    rotation: DQuat::IDENTITY,
                },
                joint: self.skeleton.joint(&format!("{s}eyeball_joint"))?,
                region: Region::Eye,
                join: Join::Insert,
                blend: 0.0,
                reach: 0.003 * h,
            });
        }
        Ok(())
    }

    fn arm(&mut self, s: &str) -> Result<()> {
        let h = self.h;
        let j = |n: &str| format!("{s}{n}");
        let (clavicle, shoulder, elbow, wrist) = (
            self.at(&j("sternoclavicular"))?,
            self.at(&j("shoulder"))?,
            self.at(&j("elbow"))?,
            self.at(&j("wrist"))?,
        );
        let (ue, us) = self.frustum_radii(&j("upper_arm"))?;
        let (fw, fe) = self.frustum_radii(&j("forearm"))?;
        // Trapezius from the base of the neck to the shoulder, the deltoid capping it.
        let neck = DVec3::new(clavicle.x * 0.3, clavicle.y + 0.012 * h, -0.01 * h);
        self.push(
            &j("sternoclavicular"),
            Region::Shirt,
            Form::Cone {
                a: neck,
                b: shoulder + DVec3::new(0.0, 0.004 * h, -0.004 * h),
                ra: 0.03 * h,
                rb: 0.024 * h,
            },
            0.02,
            0.04,
        )?;
        self.ellipsoid(
            &j("shoulder"),
            Region::Shirt,
            shoulder + DVec3::new(0.0, -0.02 * h, 0.0),
            DVec3::new(0.026, 0.04, 0.027),
            0.02,
            0.05,
        )?;
        self.push(
            &j("shoulder"),
            Region::Shirt,
            Form::Cone {
                a: shoulder,
                b: elbow,
                ra: us,
                rb: ue,
            },
            0.02,
            0.05,
        )?;
        self.push(
            &j("elbow"),
            Region::Skin,
            Form::Cone {
                a: elbow,
                b: wrist,
                ra: fe,
                rb: fw,
            },
            0.015,
            0.05,
        )?;
        Ok(())
    }

    fn hand(&mut self, s: &str) -> Result<()> {
        let h = self.h;
        let j = |n: &str| format!("{s}{n}");
        let wrist = self.at(&j("wrist"))?;
        let knuckles: Vec<DVec3> = ["index1", "middle1", "ring1", "pinky1"]
            .iter()
            .map(|f| self.at(&j(f)))
            .collect::<Result<_>>()?;
        let base = knuckles.iter().copied().sum::<DVec3>() / 4.0;
        let along = base - wrist;
        let across = knuckles[0] - knuckles[3];
        let finger_r = 0.0042 * (along.length() / (0.046 * 1.75)) * 1.75;
        let rotation = DQuat::from_rotation_arc(DVec3::Y, -along.normalize());
        let palm = Form::Ellipsoid {
            center: wrist + along * 0.55,
            radii: DVec3::new(
                0.55 * finger_r * 2.4,
                along.length() * 0.62,
                across.length() * 0.5 + finger_r * 1.1,
            ),
            rotation,
        };
        let joint = self.skeleton.joint(&j("wrist"))?;
        self.out.push(Volume {
            form: palm,
            joint,
            region: Region::Skin,
            join: Join::Add,
            blend: 0.008 * h,
            reach: 0.02 * h,
        });
        let r = finger_r / h;
        for (finger, scale) in [
            ("index", 1.0),
            ("middle", 1.04),
            ("ring", 0.97),
            ("pinky", 0.86),
        ] {
            let radii = [1.0, 0.93, 0.86, 0.78].map(|k| k * r * scale * h);
            self.digit(&j(finger), radii, 0.002, 0.007)?;
        }
        let radii = [1.5, 1.15, 1.05, 0.9].map(|k| k * r * h);
        self.digit(&j("thumb"), radii, 0.004, 0.01)?;
        Ok(())
    }

    /// A finger or thumb `digit` (e.g. `l_index`): a rounded cone per phalanx, from the
    /// joints `digit1` to `digit3` to the end site, radii tapering as given, the tip
    /// rounded within the end site.
    fn digit(&mut self, digit: &str, radii: [f64; 4], blend: f64, reach: f64) -> Result<()> {
        let pts = [
            self.at(&format!("{digit}1"))?,
            self.at(&format!("{digit}2"))?,
            self.at(&format!("{digit}3"))?,
            self.end(&format!("{digit}3"))?,
        ];
        for i in 0..3 {
            let tip = if i == 2 {
                pts[3] - (pts[3] - pts[2]).normalize() * radii[3]
            } else {
                pts[i + 1]
            };
            let form = Form::Cone {
                a: pts[i],
                b: tip,
                ra: radii[i],
                rb: radii[i + 1],
            };
            self.push(
                &format!("{digit}{}", i + 1),
                Region::Skin,
                form,
                blend,
                reach,
            )?;
        }
        Ok(())
    }

    fn leg(&mut self, s: &str) -> Result<()> {
        let h = self.h;
        let j = |n: &str| format!("{s}{n}");
        let (hip, knee, ankle) = (
            self.at(&j("hip"))?,
            self.at(&j("knee"))?,
            self.at(&j("ankle"))?,
        );
        let (tk, th) = self.frustum_radii(&j("thigh"))?;
        let (la, lk) = self.frustum_radii(&j("leg"))?;
        self.push(
            &j("hip"),
            Region::Trousers,
            Form::Cone {
                a: hip + DVec3::new(0.0, 0.01 * h, -0.004 * h),
                b: knee,
                ra: th,
                rb: tk,
            },
            0.025,
            0.06,
        )?;
        self.push(
            &j("knee"),
            Region::Trousers,
            Form::Cone {
                a: knee,
                b: ankle + DVec3::new(0.0, 0.012 * h, 0.0),
                ra: lk,
                rb: la,
            },
            0.02,
            0.05,
        )?;
        // The foot: a heel-to-ball ellipsoid whose sole touches the floor, and the toes.
        let ball = self.at(&j("metatarsal"))?;
        let toe = self.end(&j("metatarsal"))?;
        let (_, foot_center) = self.solid(&j("foot"))?;
        let heel_z = foot_center.z - (ball.z - foot_center.z) * 0.75;
        let sole = 0.022 * h;
        let center = DVec3::new(
            ankle.x + (ball.x - ankle.x) * 0.5,
            sole,
            (heel_z + ball.z) * 0.5,
        );
        let half = (ball.z - heel_z) * 0.5 / h;
        self.ellipsoid(
            &j("subtalar"),
            Region::Shoes,
            center,
            DVec3::new(0.024, 0.022, half * 1.1),
            0.015,
            0.04,
        )?;
        let toes = DVec3::new(ball.x, 0.013 * h, (ball.z + toe.z) * 0.5);
        self.ellipsoid(
            &j("metatarsal"),
            Region::Shoes,
            toes,
            DVec3::new(0.025, 0.013, (toe.z - ball.z) / h * 0.75 + 0.01),
            0.012,
            0.03,
        )?;
        Ok(())
    }
}
