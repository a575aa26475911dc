//! The heuristic grasp decision of thesis 4.3.2 (table after Mas and Thalmann 94): the
//! grasp type from the object's shape and its size relative to the hand, and one or two
//! hands.
//!
//! | shape | size (relative to hand length `L`) | grasp |
//! |---|---|---|
//! | box | thin (smallest side < [`THIN`]·L) | lateral |
//! | box | thick | pinch |
//! | sphere, ellipsoid | small diameter (< [`SMALL`]·L) | tripod |
//! | sphere, ellipsoid | large diameter | wrap |
//! | cylinder, frustum | small diameter (< [`NARROW`]·L) | pinch |
//! | cylinder, frustum | large diameter | wrap |
//! | cylinder, frustum | small height (< half its diameter) | disk |
//!
//! "If the primitive is too small, pinch is applied. If it is too large, two hands are
//! used": anything whose largest size is below [`TINY`]·L is pinched; anything the hand
//! must span more than [`LARGE`]·L across is held with both hands.

use crate::error::OptionError;
use troupe_body::Shape;

/// A box thinner than this fraction of the hand length is thin.
pub const THIN: f64 = 0.15;
/// A sphere (ellipsoid) with a diameter below this fraction of the hand length is small.
pub const SMALL: f64 = 0.35;
/// A cylinder (frustum) with a diameter below this fraction of the hand length is narrow.
pub const NARROW: f64 = 0.2;
/// An object whose largest size is below this fraction of the hand length is pinched.
pub const TINY: f64 = 0.12;
/// A span above this fraction of the hand length needs two hands.
pub const LARGE: f64 = 1.2;

/// The grasp types of table 4.3.2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GraspType {
    /// Thumb pad against the side of the index (thin objects).
    Lateral,
    /// Thumb against index and middle fingertips.
    Pinch,
    /// Thumb, index and middle around a small round object.
    Tripod,
    /// The whole hand wraps around the object.
    Wrap,
    /// Fingers spread around the rim of a flat round object.
    Disk,
}

impl GraspType {
    /// Every type, in table order.
    pub const ALL: [GraspType; 5] = [
        GraspType::Lateral,
        GraspType::Pinch,
        GraspType::Tripod,
        GraspType::Wrap,
        GraspType::Disk,
    ];

    /// The name used in scripts (`lateral`, `pinch`, …).
    pub fn name(self) -> &'static str {
        match self {
            GraspType::Lateral => "lateral",
            GraspType::Pinch => "pinch",
            GraspType::Tripod => "tripod",
            GraspType::Wrap => "wrap",
            GraspType::Disk => "disk",
        }
    }

    /// Parses a script name.
    pub fn parse(name: &str) -> Result<GraspType, OptionError> {
        GraspType::ALL
            .into_iter()
            .find(|g| g.name() == name)
            .ok_or_else(|| {
                OptionError::refused("pattern", format!("unknown grasp pattern `{name}` (expected lateral, pinch, tripod, wrap or disk)"))
            })
    }
}

/// What the table decides.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Decision {
    /// The grasp type.
    pub grasp: GraspType,
    /// One or two hands.
    pub hands: usize,
}

/// The size the hand must span to hold `shape`, in metres.
pub fn span(shape: &Shape) -> f64 {
    match *shape {
        Shape::Box { half_extents } => 2.0 * half_extents.min_element(),
        Shape::Sphere { radius } => 2.0 * radius,
        Shape::Cylinder { radius, .. } => 2.0 * radius,
        Shape::Frustum {
            bottom_radius,
            top_radius,
            ..
        } => bottom_radius + top_radius,
        Shape::Ellipsoid { radii } => {
            // The middle axis: the hand closes across the two smaller ones.
            let mut r = radii.to_array();
            r.sort_by(f64::total_cmp);
            2.0 * r[1]
        }
    }
}

/// The largest size of `shape`, in metres.
pub fn largest(shape: &Shape) -> f64 {
    match *shape {
        Shape::Box { half_extents } => 2.0 * half_extents.max_element(),
        Shape::Sphere { radius } => 2.0 * radius,
        Shape::Cylinder { radius, height } => (2.0 * radius).max(height),
        Shape::Frustum {
            bottom_radius,
            top_radius,
            height,
        } => (2.0 * bottom_radius.max(top_radius)).max(height),
        Shape::Ellipsoid { radii } => 2.0 * radii.max_element(),
    }
}

/// The table of 4.3.2 for a hand of length `hand_length` (wrist to middle fingertip).
pub fn decide(shape: &Shape, hand_length: f64) -> Decision {
    let l = hand_length;
    let two = if span(shape) > LARGE * l { 2 } else { 1 };
    if largest(shape) < TINY * l {
        return Decision {
            grasp: GraspType::Pinch,
            hands: 1,
        };
    }
    let grasp = match *shape {
        Shape::Box { half_extents } => {
            if 2.0 * half_extents.min_element() < THIN * l {
                GraspType::Lateral
            } else {
                GraspType::Pinch
            }
        }
        Shape::Sphere { .. } | Shape::Ellipsoid { .. } => {
            if span(shape) < SMALL * l {
                GraspType::Tripod
            } else {
                GraspType::Wrap
            }
        }
        Shape::Cylinder { height, .. } | Shape::Frustum { height, .. } => {
            let diameter = span(shape);
            if height < 0.5 * diameter {
                GraspType::Disk
            } else if diameter < NARROW * l {
                GraspType::Pinch
            } else {
                GraspType::Wrap
            }
        }
    };
    Decision { grasp, hands: two }
}

#[cfg(test)]
mod tests {
    use super::*;
    use troupe_body::glam::DVec3;

    const L: f64 = 0.19;

    fn d(shape: Shape) -> (GraspType, usize) {
        let x = decide(&shape, L);
        (x.grasp, x.hands)
    }

    #[test]
    fn table_small_and_large_for_every_shape() {
        use GraspType::*;
        let bx = |x: f64, y: f64, z: f64| Shape::Box {
            half_extents: DVec3::new(x, y, z) / 2.0,
        };
        // Box: thin book → lateral; thick brick → pinch; a large crate → two hands.
        assert_eq!(d(bx(0.15, 0.02, 0.2)), (Lateral, 1));
        assert_eq!(d(bx(0.06, 0.06, 0.1)), (Pinch, 1));
        assert_eq!(d(bx(0.4, 0.3, 0.4)), (Pinch, 2));
        // Sphere: ball of 5 cm → tripod; 10 cm → wrap; 40 cm → wrap with two hands.
        assert_eq!(d(Shape::Sphere { radius: 0.025 }), (Tripod, 1));
        assert_eq!(d(Shape::Sphere { radius: 0.05 }), (Wrap, 1));
        assert_eq!(d(Shape::Sphere { radius: 0.2 }), (Wrap, 2));
        // Cylinder: pencil-thin → pinch; cup → wrap; coaster → disk; barrel → two hands.
        let cyl = |radius: f64, height: f64| Shape::Cylinder { radius, height };
        assert_eq!(d(cyl(0.012, 0.15)), (Pinch, 1));
        assert_eq!(d(cyl(0.04, 0.1)), (Wrap, 1));
        assert_eq!(d(cyl(0.05, 0.02)), (Disk, 1));
        assert_eq!(d(cyl(0.2, 0.6)), (Wrap, 2));
        // Frustum follows the cylinder rule on its mean diameter.
        let fr = |b: f64, t: f64, h: f64| Shape::Frustum {
            bottom_radius: b,
            top_radius: t,
            height: h,
        };
        assert_eq!(d(fr(0.03, 0.045, 0.12)), (Wrap, 1));
        assert_eq!(d(fr(0.01, 0.015, 0.1)), (Pinch, 1));
        assert_eq!(d(fr(0.25, 0.2, 0.5)), (Wrap, 2));
        // Ellipsoid follows the sphere rule on its middle axis.
        let el = |x: f64, y: f64, z: f64| Shape::Ellipsoid {
            radii: DVec3::new(x, y, z),
        };
        assert_eq!(d(el(0.02, 0.03, 0.025)), (Tripod, 1));
        assert_eq!(d(el(0.04, 0.07, 0.05)), (Wrap, 1));
        assert_eq!(d(el(0.2, 0.3, 0.25)), (Wrap, 2));
        // Too small for anything else: pinch.
        assert_eq!(d(Shape::Sphere { radius: 0.008 }), (Pinch, 1));
    }

    #[test]
    fn names_round_trip() {
        for g in GraspType::ALL {
            assert_eq!(GraspType::parse(g.name()), Ok(g));
        }
        let e = GraspType::parse("fist").unwrap_err();
        assert_eq!(e.option(), "pattern");
        assert!(e.to_string().contains("fist"), "{e}");
    }
}
