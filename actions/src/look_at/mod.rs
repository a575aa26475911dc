//! The look-at generator: the neck, the head and the eyes turn toward a target and follow
//! it while the action runs — "the actor watches the performer".
//!
//! Each tick the direction from between the eyes to the target is taken in the frame of
//! the upper spine (`vt1`); its yaw and pitch are shared between the neck (`vc4`, 40 %)
//! and the head (`skullbase`, 60 %), each clamped to its limits and approached with a
//! time constant of [`HEAD_TIME_CONSTANT`]. The eyes then aim exactly (pan, tilt, within
//! their limits) from where the head is, with the faster [`EYE_TIME_CONSTANT`].

#[cfg(feature = "lua")]
pub(crate) mod lua;
pub mod options;

pub use options::LookAtOptions;

use crate::error::Result;
use crate::reach::Target;
use troupe_body::glam::DVec3;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::{Skeleton, Transform};
use troupe_scene::{DofWriter, Generator, GeneratorContext, StartError, Step};

/// Seconds for the head to cover 63 % of the way to a new direction.
pub const HEAD_TIME_CONSTANT: f64 = 0.15;
/// Seconds for the eyes to cover 63 % of the way.
pub const EYE_TIME_CONSTANT: f64 = 0.04;
/// The neck's share of the head's turn.
pub const NECK_SHARE: f64 = 0.4;

/// DOF indices the generator drives.
struct Dofs {
    neck_flexion: usize,
    neck_torsion: usize,
    head_flexion: usize,
    head_torsion: usize,
    /// (joint, pan, tilt) per eye.
    eyes: Vec<(usize, usize, usize)>,
    vt1: usize,
    skullbase: usize,
}

/// The look-at generator.
pub struct LookAt {
    target: Target,
    dofs: Dofs,
    q: Vec<f64>,
    globals: Vec<Transform>,
}

/// `(yaw, pitch)` of direction `d`: yaw about +Y toward +X, pitch downward positive.
fn yaw_pitch(d: DVec3) -> (f64, f64) {
    (d.x.atan2(d.z), (-d.y).atan2(d.x.hypot(d.z)))
}

impl LookAt {
    /// A look-at on a humanoid `skeleton` (needs `vt1`, `vc4`, `skullbase` and eyeball
    /// joints).
    pub fn new(skeleton: &Skeleton, target: Target) -> Result<LookAt> {
        let d = |n: &str| skeleton.dof(n);
        let j = |n: &str| skeleton.joint(n);
        let mut eyes = Vec::new();
        for side in ["l", "r"] {
            eyes.push((
                j(&format!("{side}_eyeball_joint"))?,
                d(&format!("{side}_eyeball_pan"))?,
                d(&format!("{side}_eyeball_tilt"))?,
            ));
        }
        target.check()?;
        Ok(LookAt {
            target,
            dofs: Dofs {
                neck_flexion: d("vc4_flexion")?,
                neck_torsion: d("vc4_torsion")?,
                head_flexion: d("skullbase_flexion")?,
                head_torsion: d("skullbase_torsion")?,
                eyes,
                vt1: j("vt1")?,
                skullbase: j("skullbase")?,
            },
            q: Vec::new(),
            globals: vec![Transform::IDENTITY; skeleton.joints().len()],
        })
    }

    /// The DOFs it drives.
    pub fn scope_dofs(&self) -> Vec<usize> {
        let d = &self.dofs;
        let mut v = vec![
            d.neck_flexion,
            d.neck_torsion,
            d.head_flexion,
            d.head_torsion,
        ];
        for (_, p, t) in &d.eyes {
            v.extend([*p, *t]);
        }
        v
    }
}

impl Generator for LookAt {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        self.target.position(ctx.world).map_err(|e| e.to_string())?;
        self.q = ctx.posture.q.clone();
        Ok(())
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let target = match self.target.position(ctx.world) {
            Ok(p) => p,
            Err(e) => return Step::Failed(e.to_string()),
        };
        if self.q.len() != ctx.posture.q.len() {
            self.q = ctx.posture.q.clone();
        }
        let d = &self.dofs;
        // A `scope` option may leave it part of the head and eyes (`scope = "eyes"`): the
        // rest follows the posture, and the eyes aim from where the head really is.
        let own: Vec<usize> = self
            .scope_dofs()
            .into_iter()
            .filter(|&i| ctx.scope.contains(i))
            .collect();
        // The body as it is, with the head and eyes where this action last put them.
        let saved: Vec<f64> = own.iter().map(|&i| self.q[i]).collect();
        self.q.copy_from_slice(&ctx.posture.q);
        for (&i, v) in own.iter().zip(saved) {
            self.q[i] = v;
        }
        let skeleton = ctx.skeleton;
        forward_kinematics(skeleton, &self.q, &mut self.globals);
        let eyes_mid = d
            .eyes
            .iter()
            .map(|(j, _, _)| self.globals[*j].translation)
            .sum::<DVec3>()
            / d.eyes.len() as f64;
        let base = self.globals[d.vt1];
        let dir = base.rotation.inverse() * (target - eyes_mid);
        if dir.length() < 1e-6 {
            return Step::Running;
        }
        let (yaw, pitch) = yaw_pitch(dir);
        let head_k = 1.0 - (-ctx.dt / HEAD_TIME_CONSTANT).exp();
        let eye_k = 1.0 - (-ctx.dt / EYE_TIME_CONSTANT).exp();
        let dofs = skeleton.dofs();
        let approach = |i: usize, want: f64, k: f64, q: &mut [f64]| {
            if ctx.scope.contains(i) {
                let want = dofs[i].clamp(want);
                q[i] += (want - q[i]) * k;
            }
        };
        approach(d.neck_torsion, yaw * NECK_SHARE, head_k, &mut self.q);
        approach(d.neck_flexion, pitch * NECK_SHARE, head_k, &mut self.q);
        let neck_t = self.q[d.neck_torsion];
        let neck_f = self.q[d.neck_flexion];
        approach(d.head_torsion, yaw - neck_t, head_k, &mut self.q);
        approach(d.head_flexion, pitch - neck_f, head_k, &mut self.q);
        // The eyes aim from where the head now is.
        forward_kinematics(skeleton, &self.q, &mut self.globals);
        let head = self.globals[d.skullbase];
        for &(joint, pan, tilt) in &d.eyes {
            let eye = self.globals[joint].translation;
            let local = head.rotation.inverse() * (target - eye);
            let (p, t) = yaw_pitch(local);
            approach(pan, p, eye_k, &mut self.q);
            approach(tilt, t, eye_k, &mut self.q);
        }
        for i in own {
            out.set(i, self.q[i]);
        }
        Step::Running
    }
}
