//! The options of `look_at`: what to watch.

use super::LookAt;
use crate::error::{OptionError, Result};
use crate::reach::Target;
use troupe_body::Skeleton;

/// The options of a look-at action.
#[derive(Clone, Debug, PartialEq)]
pub struct LookAtOptions {
    /// What the eyes follow.
    pub target: Target,
}

impl LookAtOptions {
    /// Checks the options that do not depend on a body: a point target must be finite.
    pub fn validate(&self) -> Result<(), OptionError> {
        self.target.check()
    }

    /// The look-at generator for `skeleton`, once the options are valid.
    pub fn look_at(&self, skeleton: &Skeleton) -> Result<LookAt> {
        self.validate()?;
        LookAt::new(skeleton, self.target.clone())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::glam::DVec3;

    #[test]
    fn a_finite_point_or_a_named_target_passes() {
        for target in [
            Target::Point(DVec3::new(0.0, 1.6, 2.0)),
            Target::Object("cup".into()),
        ] {
            LookAtOptions { target }.validate().unwrap();
        }
    }

    #[test]
    fn a_point_that_is_not_finite_is_refused_naming_the_target() {
        let e = LookAtOptions {
            target: Target::Point(DVec3::new(f64::NAN, 0.0, 0.0)),
        }
        .validate()
        .expect_err("refused");
        assert_eq!(e.option(), "target");
        assert!(e.to_string().contains("target"), "{e}");
    }
}
