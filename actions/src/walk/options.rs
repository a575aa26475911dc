//! The options of `walk` besides its route: the cruising speed, the heading on arrival
//! and the personification of the gait (fig. 6-11).

use crate::error::OptionError;

/// The personification, speed and patience options of a walk (fig. 6-11); 1 is the
/// thesis' walk for every scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkOptions {
    /// Cruising speed in m/s for `to` and `path` walks.
    pub speed: f64,
    /// Heading to face on arrival (radians about +Y, 0 faces +Z); `None` faces the
    /// direction of travel.
    pub heading: Option<f64>,
    /// Step (and cycle) length scale at a given speed: longer, slower steps above 1.
    pub step_length: f64,
    /// Scale of the lateral distance between the feet.
    pub step_width: f64,
    /// Scale of the pelvis' rotation, list and sway ("the movement of the pelvis").
    pub pelvis: f64,
    /// Scale of the arm swing.
    pub arm_swing: f64,
    /// Scale of the vertical bounce of the pelvis.
    pub bounce: f64,
    /// 0 for a walk, up to 1 for a run-like gait: bent knees, forward lean, flexed
    /// elbows, larger bounce and foot lift (fig. 6-11 a, b).
    pub run: f64,
    /// Whether the walk swings the arms (false leaves the arm DOFs to other actions).
    pub arms: bool,
    /// Seconds a `to` or `path` walk may go without getting nearer its goal (held by
    /// people standing in its way) before it fails naming them; `None` waits as long as
    /// it takes (see [`super::patience`]).
    pub patience: Option<f64>,
}

impl Default for WalkOptions {
    fn default() -> Self {
        WalkOptions {
            speed: 1.3,
            heading: None,
            step_length: 1.0,
            step_width: 1.0,
            pelvis: 1.0,
            arm_swing: 1.0,
            bounce: 1.0,
            run: 0.0,
            arms: true,
            patience: None,
        }
    }
}

impl WalkOptions {
    /// Checks every option; the error names the offending one and its valid range.
    pub fn validate(&self) -> Result<(), OptionError> {
        for (name, v, lo, hi) in [
            ("step_length", self.step_length, 0.5, 1.5),
            ("step_width", self.step_width, 0.0, 3.0),
            ("pelvis", self.pelvis, 0.0, 3.0),
            ("arm_swing", self.arm_swing, 0.0, 3.0),
            ("bounce", self.bounce, 0.0, 3.0),
            ("run", self.run, 0.0, 1.0),
        ] {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return Err(OptionError::invalid(
                    name,
                    format!("a number in [{lo}, {hi}]"),
                    v,
                ));
            }
        }
        match self.patience {
            Some(v) if !(v.is_finite() && v > 0.0) => Err(OptionError::invalid(
                "patience",
                "a number of seconds above 0",
                v,
            )),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_thesis_walk_passes() {
        WalkOptions::default().validate().unwrap();
        WalkOptions {
            run: 1.0,
            step_length: 0.5,
            arms: false,
            ..WalkOptions::default()
        }
        .validate()
        .unwrap();
    }

    #[test]
    fn each_scale_out_of_range_is_refused_naming_it() {
        let o = WalkOptions::default;
        for (name, options) in [
            (
                "step_length",
                WalkOptions {
                    step_length: 1.6,
                    ..o()
                },
            ),
            (
                "step_width",
                WalkOptions {
                    step_width: -0.1,
                    ..o()
                },
            ),
            (
                "pelvis",
                WalkOptions {
                    pelvis: f64::NAN,
                    ..o()
                },
            ),
            (
                "arm_swing",
                WalkOptions {
                    arm_swing: 3.5,
                    ..o()
                },
            ),
            (
                "bounce",
                WalkOptions {
                    bounce: -1.0,
                    ..o()
                },
            ),
            ("run", WalkOptions { run: 3.0, ..o() }),
        ] {
            let e = options.validate().expect_err(name);
            assert_eq!(e.option(), name);
            assert!(
                e.to_string()
                    .starts_with(&format!("`{name}` must be a number in [")),
                "{e}"
            );
        }
    }

    #[test]
    fn a_patience_of_no_time_is_refused() {
        for v in [0.0, -1.0, f64::INFINITY, f64::NAN] {
            let e = WalkOptions {
                patience: Some(v),
                ..WalkOptions::default()
            }
            .validate()
            .expect_err("patience");
            assert_eq!(e.option(), "patience");
            assert!(e.to_string().contains("seconds above 0"), "{e}");
        }
        WalkOptions {
            patience: Some(0.5),
            ..WalkOptions::default()
        }
        .validate()
        .unwrap();
    }
}
