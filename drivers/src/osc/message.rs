//! Decoding OSC input: a pose or glove message for a performer, bundles included.
//!
//! | address | arguments |
//! |---|---|
//! | `/troupe/<performer>/<joint>` | `x y z qw qx qy qz`: the joint's world position (m) and orientation, scene frame |
//! | `/troupe/<performer>/glove`   | one value per glove sensor, raw 1…255 |

use glam::{DQuat, DVec3};
use rosc::{OscMessage, OscPacket, OscType};

/// An OSC message that is not a troupe input; each error names the address.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MessageError {
    /// The address is not `/troupe/<performer>/<joint|glove>`.
    #[error("{0}: expected /troupe/<performer>/<joint|glove>")]
    Address(String),
    /// An argument is not a number.
    #[error("{0}: arguments must be numbers")]
    NotNumbers(String),
    /// A glove message without values.
    #[error("{0}: no glove values")]
    NoGloveValues(String),
    /// A pose message without seven finite numbers.
    #[error("{address}: expected 7 finite numbers x y z qw qx qy qz, got {got}")]
    PoseArity {
        /// The message's address.
        address: String,
        /// Numbers it carried.
        got: usize,
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
        if nums.is_empty() {
            return Err(MessageError::NoGloveValues(m.addr.clone()));
        }
        let raw = nums
            .iter()
            .map(|v| v.round().clamp(1.0, 255.0) as u8)
            .collect();
        return Ok(OscInput::Glove { performer, raw });
    }
    if nums.len() != 7 || nums.iter().any(|v| !v.is_finite()) {
        return Err(MessageError::PoseArity {
            address: m.addr.clone(),
            got: nums.len(),
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
        let g = msg(
            "/troupe/pat/glove",
            vec![OscType::Int(3), OscType::Float(300.0), OscType::Int(0)],
        );
        assert_eq!(
            parse_message(&g).unwrap(),
            OscInput::Glove {
                performer: "pat".into(),
                raw: vec![3, 255, 1]
            }
        );
    }

    #[test]
    fn bad_messages_name_the_problem() {
        assert!(parse_message(&msg("/other/x", vec![]))
            .unwrap_err()
            .to_string()
            .contains("/troupe/<performer>"));
        assert!(
            parse_message(&msg("/troupe/pat/head", vec![OscType::Float(1.0)]))
                .unwrap_err()
                .to_string()
                .contains("7 finite numbers")
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
