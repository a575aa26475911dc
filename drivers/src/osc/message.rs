//! Decoding OSC input: a pose or glove message for a performer, bundles included.
//!
//! | address | arguments |
//! |---|---|
//! | `/troupe/<performer>/<joint>` | `x y z qw qx qy qz`: the joint's world position (m) and orientation, scene frame |
//! | `/troupe/<performer>/glove`   | one value per glove sensor, raw 1…255 |

use glam::{DQuat, DVec3};
use rosc::{OscMessage, OscPacket, OscType};

/// An OSC message that is not a troupe input; each error names the address.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum MessageError {
    /// The address is not `/troupe/<performer>/<joint|glove>`.
    #[error("{0}: expected /troupe/<performer>/<joint|glove>")]
    Address(String),
    /// An argument is not a number.
    #[error("{0}: arguments must be numbers")]
    NotNumbers(String),
    /// A glove message whose value count is not a glove's (18 or 22 sensors).
    #[error("{address}: expected 18 or 22 glove values (one per sensor), got {got}")]
    GloveCount {
        /// The message's address.
        address: String,
        /// Values it carried.
        got: usize,
    },
    /// A glove message with a NaN or infinite value.
    #[error("{address}: glove value {index} is {value}, not a finite number")]
    GloveNotFinite {
        /// The message's address.
        address: String,
        /// The value's place, from 0.
        index: usize,
        /// The value.
        value: f64,
    },
    /// A pose message without seven numbers.
    #[error("{address}: expected 7 numbers x y z qw qx qy qz, got {got}")]
    PoseArity {
        /// The message's address.
        address: String,
        /// Numbers it carried.
        got: usize,
    },
    /// A pose message with a NaN or infinite number.
    #[error("{address}: {name} is {value}, not a finite number")]
    PoseNotFinite {
        /// The message's address.
        address: String,
        /// The argument's name (`x`, `qw`, …).
        name: &'static str,
        /// Its value.
        value: f64,
    },
    /// A pose whose quaternion is zero.
    #[error("{0}: zero quaternion")]
    ZeroQuaternion(String),
}

/// One decoded OSC input.
#[derive(Clone, Debug, PartialEq)]
pub enum OscInput {
    /// A joint's world pose for a performer.
    Pose {
        /// Performer name.
        performer: String,
        /// Joint name (template names, or the aliases `pelvis`, `root`, `head`).
        joint: String,
        /// World position, metres.
        position: DVec3,
        /// World orientation.
        rotation: DQuat,
    },
    /// Raw glove values for a performer.
    Glove {
        /// Performer name.
        performer: String,
        /// Raw values 1…255.
        raw: Vec<u8>,
    },
}

/// The sensor counts a CyberGlove has: a glove message carries one of them.
pub const GLOVE_SENSORS: [usize; 2] = [18, 22];

fn number(a: &OscType) -> Option<f64> {
    match a {
        OscType::Float(f) => Some(f64::from(*f)),
        OscType::Double(d) => Some(*d),
        OscType::Int(i) => Some(f64::from(*i)),
        OscType::Long(l) => Some(*l as f64),
        _ => None,
    }
}

/// Decodes one message; the error names the address and what was wrong.
pub fn parse_message(m: &OscMessage) -> Result<OscInput, MessageError> {
    let parts: Vec<&str> = m.addr.trim_start_matches('/').split('/').collect();
    let (performer, what) = match parts.as_slice() {
        ["troupe", p, w] if !p.is_empty() && !w.is_empty() => (p.to_string(), *w),
        _ => return Err(MessageError::Address(m.addr.clone())),
    };
    let nums: Option<Vec<f64>> = m.args.iter().map(number).collect();
    let nums = nums.ok_or_else(|| MessageError::NotNumbers(m.addr.clone()))?;
    if what == "glove" {
        // A glove reports every sensor at once: fewer values would leave the others at
        // their old values, more would be dropped; NaN would be clamped to a value.
        if !GLOVE_SENSORS.contains(&nums.len()) {
            return Err(MessageError::GloveCount {
                address: m.addr.clone(),
                got: nums.len(),
            });
        }
        if let Some((index, &value)) = nums.iter().enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(MessageError::GloveNotFinite {
                address: m.addr.clone(),
                index,
                value,
            });
        }
        let raw = nums
            .iter()
            .map(|v| v.round().clamp(1.0, 255.0) as u8)
            .collect();
        return Ok(OscInput::Glove { performer, raw });
    }
    if nums.len() != 7 {
        return Err(MessageError::PoseArity {
            address: m.addr.clone(),
            got: nums.len(),
        });
    }
    const NAMES: [&str; 7] = ["x", "y", "z", "qw", "qx", "qy", "qz"];
    if let Some((i, &value)) = nums.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        return Err(MessageError::PoseNotFinite {
            address: m.addr.clone(),
            name: NAMES[i],
            value,
        });
    }
    let q = DQuat::from_xyzw(nums[4], nums[5], nums[6], nums[3]);
    if q.length() < 1e-6 {
        return Err(MessageError::ZeroQuaternion(m.addr.clone()));
    }
    Ok(OscInput::Pose {
        performer,
        joint: what.to_string(),
        position: DVec3::new(nums[0], nums[1], nums[2]),
        rotation: q.normalize(),
    })
}

/// Decodes a packet (bundles recursively) into inputs; bad messages are counted in `bad`.
pub fn parse_packet(p: &OscPacket, out: &mut Vec<OscInput>, bad: &mut Vec<MessageError>) {
    match p {
        OscPacket::Message(m) => match parse_message(m) {
            Ok(i) => out.push(i),
            Err(e) => bad.push(e),
        },
        OscPacket::Bundle(b) => b.content.iter().for_each(|c| parse_packet(c, out, bad)),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A message to `addr` with `args`.
    pub(crate) fn msg(addr: &str, args: Vec<OscType>) -> OscMessage {
        OscMessage {
            addr: addr.into(),
            args,
        }
    }

    #[test]
    fn poses_and_glove_values_parse() {
        let m = msg(
            "/troupe/pat/r_wrist",
            [0.1f32, 1.2, 0.3, 1.0, 0.0, 0.0, 0.0]
                .iter()
                .map(|v| OscType::Float(*v))
                .collect(),
        );
        match parse_message(&m).unwrap() {
            OscInput::Pose {
                performer,
                joint,
                position,
                rotation,
            } => {
                assert_eq!((performer.as_str(), joint.as_str()), ("pat", "r_wrist"));
                assert!((position - DVec3::new(0.1, 1.2, 0.3)).length() < 1e-6);
                assert_eq!(rotation, DQuat::IDENTITY);
            }
            other => panic!("{other:?}"),
        }
        let mut values = vec![OscType::Int(3), OscType::Float(300.0), OscType::Int(0)];
        values.extend((3..18).map(|_| OscType::Int(128)));
        let g = msg("/troupe/pat/glove", values);
        let mut raw = vec![3, 255, 1];
        raw.extend([128; 15]);
        assert_eq!(
            parse_message(&g).unwrap(),
            OscInput::Glove {
                performer: "pat".into(),
                raw
            }
        );
        let g22 = msg("/troupe/pat/glove", vec![OscType::Float(9.0); 22]);
        assert!(matches!(parse_message(&g22), Ok(OscInput::Glove { raw, .. }) if raw.len() == 22));
    }

    #[test]
    fn glove_messages_with_another_count_or_non_finite_values_are_refused() {
        for n in [0, 3, 17, 19, 23, 40] {
            let e = parse_message(&msg("/troupe/pat/glove", vec![OscType::Int(100); n]));
            assert_eq!(
                e.unwrap_err().to_string(),
                format!(
                    "/troupe/pat/glove: expected 18 or 22 glove values (one per sensor), got {n}"
                )
            );
        }
        let mut values = vec![OscType::Float(100.0); 18];
        values[4] = OscType::Float(f32::NAN);
        let e = parse_message(&msg("/troupe/pat/glove", values.clone())).unwrap_err();
        assert_eq!(
            e.to_string(),
            "/troupe/pat/glove: glove value 4 is NaN, not a finite number"
        );
        values[4] = OscType::Double(f64::NEG_INFINITY);
        assert!(parse_message(&msg("/troupe/pat/glove", values)).is_err());
    }

    #[test]
    fn bad_messages_name_the_problem() {
        assert!(parse_message(&msg("/other/x", vec![]))
            .unwrap_err()
            .to_string()
            .contains("/troupe/<performer>"));
        assert_eq!(
            parse_message(&msg("/troupe/pat/head", vec![OscType::Float(1.0)]))
                .unwrap_err()
                .to_string(),
            "/troupe/pat/head: expected 7 numbers x y z qw qx qy qz, got 1"
        );
        let mut nan = vec![OscType::Float(0.0); 7];
        nan[3] = OscType::Float(f32::NAN);
        assert_eq!(
            parse_message(&msg("/troupe/pat/head", nan))
                .unwrap_err()
                .to_string(),
            "/troupe/pat/head: qw is NaN, not a finite number"
        );
        assert!(
            parse_message(&msg("/troupe/pat/head", vec![OscType::String("a".into())]))
                .unwrap_err()
                .to_string()
                .contains("numbers")
        );
        let zero: Vec<OscType> = (0..7).map(|_| OscType::Float(0.0)).collect();
        assert!(parse_message(&msg("/troupe/pat/head", zero))
            .unwrap_err()
            .to_string()
            .contains("zero quaternion"));
    }
}
