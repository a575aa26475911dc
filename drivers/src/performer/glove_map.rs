//! The glove on the template's hand: which DOFs each CyberGlove sensor drives, the coupling
//! of the 18-sensor glove's missing DIJ sensors, and a nominal calibration from the
//! template's joint limits.

use crate::cyberglove::calibration::GloveCalibration;
use crate::cyberglove::decoder::sensor_names;
use troupe_body::skeleton::Skeleton;

/// Which template DOFs each sensor of a glove drives, for one hand.
#[derive(Clone, Debug)]
pub struct GloveMap {
    /// DOF indices per sensor, in wire order.
    pub dofs: Vec<Vec<usize>>,
    /// (DIJ DOF, PIJ sensor index) for an 18-sensor glove.
    pub coupled: Vec<(usize, usize)>,
}

impl GloveMap {
    /// The map of a `sensors`-sensor glove on the hand `side` (`r_` or `l_`) of `skeleton`;
    /// sensors whose DOF the template lacks drive nothing.
    pub fn new(skeleton: &Skeleton, sensors: usize, side: &str) -> GloveMap {
        let names = sensor_names(sensors);
        let dofs: Vec<Vec<usize>> = names
            .iter()
            .map(|n| {
                glove_dof_names(n, side)
                    .iter()
                    .filter_map(|d| skeleton.dof(d).ok())
                    .collect()
            })
            .collect();
        let mut coupled = Vec::new();
        if sensors == 18 {
            for finger in ["index", "middle", "ring", "pinky"] {
                let pij = names.iter().position(|n| *n == format!("{finger}_pij"));
                if let (Some(p), Ok(d)) = (pij, skeleton.dof(&format!("{side}{finger}3_flexion"))) {
                    coupled.push((d, p));
                }
            }
        }
        GloveMap { dofs, coupled }
    }

    /// Every DOF the glove drives: the sensors' in wire order, then the coupled ones.
    pub fn all_dofs(&self) -> impl Iterator<Item = usize> + '_ {
        self.dofs
            .iter()
            .flatten()
            .copied()
            .chain(self.coupled.iter().map(|c| c.0))
    }

    /// Writes calibrated sensor angles (radians) into `q`, clamped to each DOF's limits,
    /// and marks the DOFs in `mask`; a coupled DIJ takes two thirds of its PIJ.
    pub fn apply(&self, skeleton: &Skeleton, angles: &[f64], q: &mut [f64], mask: &mut [bool]) {
        for (i, dofs) in self.dofs.iter().enumerate() {
            for &d in dofs {
                if let Some(&a) = angles.get(i) {
                    q[d] = skeleton.dofs()[d].clamp(a);
                    mask[d] = true;
                }
            }
        }
        for &(d, pij) in &self.coupled {
            if let Some(&a) = angles.get(pij) {
                q[d] = skeleton.dofs()[d].clamp(a * 2.0 / 3.0);
                mask[d] = true;
            }
        }
    }
}

/// Glove sensors to the template's hand DOFs (`s` = `r_` or `l_`); the 18-sensor glove has
/// no DIJ sensors, so each distal flexion follows two thirds of its PIJ (a usual coupling).
pub fn glove_dof_names(sensor: &str, s: &str) -> Vec<String> {
    let f = |n: &str| vec![format!("{s}{n}")];
    match sensor {
        "thumb_rotation" => f("thumb1_flexion"),
        "thumb_mpj" => f("thumb2_flexion"),
        "thumb_ij" => f("thumb3_flexion"),
        "thumb_index_abduction" => f("thumb1_abduction"),
        "middle_index_abduction" => f("index1_pivot"),
        "ring_middle_abduction" => f("ring1_pivot"),
        "pinky_ring_abduction" => f("pinky1_pivot"),
        "palm_arch" => vec![format!("{s}ring0_flexion"), format!("{s}pinky0_flexion")],
        "wrist_pitch" => f("wrist_flexion"),
        "wrist_yaw" => f("wrist_deviation"),
        other => {
            let (finger, joint) = other.split_once('_').unwrap_or((other, ""));
            let k = match joint {
                "mpj" => 1,
                "pij" => 2,
                "dij" => 3,
                _ => return Vec::new(),
            };
            vec![format!("{s}{finger}{k}_flexion")]
        }
    }
}

/// A nominal glove calibration for a template: each sensor's raw range 1…255 spans its
/// DOF's range from 0 (or its lower limit when 0 is outside) to its upper limit.
pub fn nominal_glove_calibration(
    skeleton: &Skeleton,
    sensors: usize,
    side: &str,
) -> GloveCalibration {
    let mut c = GloveCalibration::nominal(sensors);
    for (i, name) in c.sensors.clone().iter().enumerate() {
        if let Some(d) = glove_dof_names(name, side)
            .first()
            .and_then(|n| skeleton.dof(n).ok())
        {
            let dof = &skeleton.dofs()[d];
            let lo = if dof.min <= 0.0 && dof.max >= 0.0 {
                0.0
            } else {
                dof.min
            };
            let g = (dof.max - lo) / 254.0;
            c.gain[i] = g;
            c.offset[i] = 1.0 - lo / g;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::performer::converter::tests::adult;

    #[test]
    fn glove_sensors_map_to_hand_dofs() {
        let sk = adult();
        for sensors in [18, 22] {
            for name in sensor_names(sensors) {
                let dofs = glove_dof_names(name, "r_");
                assert!(!dofs.is_empty(), "{name} maps to a DOF");
                for d in dofs {
                    assert!(sk.dof(&d).is_ok(), "{name} → {d} exists in the template");
                }
            }
        }
        let c = nominal_glove_calibration(&sk, 18, "r_");
        let d = &sk.dofs()[sk.dof("r_index1_flexion").unwrap()];
        let a = c.angles(&[1, 1, 1, 1, 1, 255]);
        assert!(
            a[4].abs() < 1e-12
                && (a[5] - sk.dofs()[sk.dof("r_index2_flexion").unwrap()].max).abs() < 1e-12
        );
        assert!(d.max > 0.0);
    }
}
