//! 3Dconnexion SpaceMouse family over USB HID: device table and report decoding.
//!
//! Facts from `shared/reference/devices.md`, section "3Dconnexion SpaceMouse family".

use serde::Serialize;

/// Vendor IDs: Logitech (older devices) and 3Dconnexion (newer).
pub const VENDORS: [u16; 2] = [0x046D, 0x256F];

/// Known products (reference: the product list).
pub const PRODUCTS: [(u16, &str, ReportKind); 14] = [
    (0xC603, "SpaceMouse", ReportKind::Wired),
    (0xC621, "SpaceBall 5000", ReportKind::Wired),
    (0xC623, "SpaceTraveler", ReportKind::Wired),
    (0xC625, "SpacePilot", ReportKind::Wired),
    (0xC626, "SpaceNavigator", ReportKind::Wired),
    (0xC627, "SpaceExplorer", ReportKind::Wired),
    (0xC628, "SpaceNavigator for Notebooks", ReportKind::Wired),
    (0xC629, "SpacePilot Pro", ReportKind::Wired),
    (0xC62B, "SpaceMouse Pro", ReportKind::Wired),
    (0xC62E, "SpaceMouse Wireless (cabled)", ReportKind::Wired),
    (0xC62F, "SpaceMouse Wireless", ReportKind::Wired),
    (0xC631, "SpaceMouse Pro Wireless", ReportKind::Combined),
    (0xC635, "SpaceMouse Compact", ReportKind::Wired),
    (
        0xC652,
        "3Dconnexion Universal Receiver",
        ReportKind::Combined,
    ),
];

/// How a product lays out its motion reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum ReportKind {
    /// 7-byte reports: ID 1 translation, ID 2 rotation.
    Wired,
    /// 13-byte reports: ID 1 carries all six axes.
    Combined,
}

/// The product name and report layout of a vendor/product pair, if it is a SpaceMouse.
pub fn lookup(vendor: u16, product: u16) -> Option<(&'static str, ReportKind)> {
    if !VENDORS.contains(&vendor) {
        return None;
    }
    PRODUCTS
        .iter()
        .find(|(p, _, _)| *p == product)
        .map(|(_, n, k)| (*n, *k))
}

/// Accumulated state of a SpaceMouse: the latest axes and buttons.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct SpaceMouseState {
    /// Translation X, Y, Z (raw, about ±350…±400 full scale).
    pub translation: [i16; 3],
    /// Rotation Rx, Ry, Rz (raw).
    pub rotation: [i16; 3],
    /// Button bit field (bit n = button n).
    pub buttons: u32,
}

/// Full scale of an axis, used to normalize to −1…1 (reference: "about ±350…±400").
pub const FULL_SCALE: f64 = 350.0;

impl SpaceMouseState {
    /// Translation normalized to about −1…1 (clamped).
    pub fn translation_unit(&self) -> [f64; 3] {
        self.translation
            .map(|v| (f64::from(v) / FULL_SCALE).clamp(-1.0, 1.0))
    }

    /// Rotation normalized to about −1…1 (clamped).
    pub fn rotation_unit(&self) -> [f64; 3] {
        self.rotation
            .map(|v| (f64::from(v) / FULL_SCALE).clamp(-1.0, 1.0))
    }
}

fn i16_at(r: &[u8], i: usize) -> i16 {
    i16::from_le_bytes([r[i], r[i + 1]])
}

/// A HID report the layout does not know.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ReportError {
    /// A read returned no bytes.
    #[error("empty HID report")]
    Empty,
    /// The report ends before its last axis (byte 0 is the report ID).
    #[error("HID report {id} has {len} bytes, expected {expected}")]
    Short {
        /// The report ID.
        id: u8,
        /// Bytes received.
        len: usize,
        /// Bytes the report ID needs.
        expected: usize,
    },
    /// Byte 0 is no report ID the layout has.
    #[error("unknown HID report ID {0}")]
    UnknownId(u8),
}

/// Applies one HID report to the state; the error says what was wrong when the report is
/// not one the layout knows (too short, unknown ID).
///
/// Reference: wired devices send 7-byte reports, report ID first: ID 1 = translation X, Y, Z
/// as int16 little-endian; ID 2 = rotation; ID 3 = buttons, bit n in byte 1 + n/8. Pro
/// Wireless sends 13-byte reports: ID 1 carries all six axes.
pub fn apply_report(
    state: &mut SpaceMouseState,
    kind: ReportKind,
    report: &[u8],
) -> Result<(), ReportError> {
    let Some(&id) = report.first() else {
        return Err(ReportError::Empty);
    };
    let need = |n: usize| {
        if report.len() < n {
            Err(ReportError::Short {
                id,
                len: report.len(),
                expected: n,
            })
        } else {
            Ok(())
        }
    };
    match (id, kind) {
        (1, ReportKind::Wired) => {
            need(7)?;
            state.translation = [i16_at(report, 1), i16_at(report, 3), i16_at(report, 5)];
        }
        (1, ReportKind::Combined) => {
            need(13)?;
            state.translation = [i16_at(report, 1), i16_at(report, 3), i16_at(report, 5)];
            state.rotation = [i16_at(report, 7), i16_at(report, 9), i16_at(report, 11)];
        }
        (2, _) => {
            need(7)?;
            state.rotation = [i16_at(report, 1), i16_at(report, 3), i16_at(report, 5)];
        }
        (3, _) => {
            need(2)?;
            let mut b = 0u32;
            for (i, &byte) in report[1..].iter().take(4).enumerate() {
                b |= u32::from(byte) << (8 * i);
            }
            state.buttons = b;
        }
        _ => return Err(ReportError::UnknownId(id)),
    }
    Ok(())
}

/// The report layout a single HID report uses, told by its length: only Pro Wireless style
/// devices send a 13-byte report ID 1 (all six axes); wired devices send 7 bytes. A hidraw
/// read returns exactly one report, so a recording needs no per-device setting to decode.
pub fn kind_of_report(report: &[u8]) -> ReportKind {
    if report.first() == Some(&1) && report.len() >= 13 {
        ReportKind::Combined
    } else {
        ReportKind::Wired
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_lookup() {
        assert_eq!(
            lookup(0x046D, 0xC626),
            Some(("SpaceNavigator", ReportKind::Wired))
        );
        assert_eq!(
            lookup(0x256F, 0xC631).map(|x| x.1),
            Some(ReportKind::Combined)
        );
        assert_eq!(lookup(0x1234, 0xC626), None);
        assert_eq!(lookup(0x046D, 0x0001), None);
    }

    #[test]
    fn wired_reports_decode_exactly() {
        let mut s = SpaceMouseState::default();
        // ID 1: X = 350 (0x015E), Y = −2 (0xFFFE), Z = 0x0100.
        apply_report(
            &mut s,
            ReportKind::Wired,
            &[1, 0x5E, 0x01, 0xFE, 0xFF, 0x00, 0x01],
        )
        .unwrap();
        assert_eq!(s.translation, [350, -2, 256]);
        // ID 2: Rx = −350 (0xFEA2).
        apply_report(&mut s, ReportKind::Wired, &[2, 0xA2, 0xFE, 0, 0, 1, 0]).unwrap();
        assert_eq!(s.rotation, [-350, 0, 1]);
        assert_eq!(
            s.translation,
            [350, -2, 256],
            "rotation report keeps translation"
        );
        // ID 3: buttons 0 and 9.
        apply_report(&mut s, ReportKind::Wired, &[3, 0x01, 0x02, 0, 0, 0, 0]).unwrap();
        assert_eq!(s.buttons, 0b10_0000_0001);
        assert_eq!(s.translation_unit()[0], 1.0);
    }

    #[test]
    fn pro_wireless_combined_report() {
        let mut s = SpaceMouseState::default();
        let r = [1, 1, 0, 2, 0, 3, 0, 0xFF, 0xFF, 0xFE, 0xFF, 0xFD, 0xFF];
        apply_report(&mut s, ReportKind::Combined, &r).unwrap();
        assert_eq!(s.translation, [1, 2, 3]);
        assert_eq!(s.rotation, [-1, -2, -3]);
    }

    #[test]
    fn bad_reports_are_errors_not_panics() {
        let mut s = SpaceMouseState::default();
        assert!(apply_report(&mut s, ReportKind::Wired, &[]).is_err());
        assert!(
            apply_report(&mut s, ReportKind::Combined, &[1, 0, 0, 0, 0, 0, 0])
                .unwrap_err()
                .to_string()
                .contains("expected 13")
        );
        assert!(apply_report(&mut s, ReportKind::Wired, &[9, 0])
            .unwrap_err()
            .to_string()
            .contains("unknown"));
        assert_eq!(s, SpaceMouseState::default());
    }
}
