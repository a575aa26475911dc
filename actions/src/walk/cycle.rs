//! The walking cycle of thesis 2.6 (after Boulic et al. 90 and Inman et al. 81): every
//! spatial value is normalized by the thigh height Ht, the relative cycle length follows
//! from the relative velocity (eq. 2-5) and the phase durations from the cycle duration
//! (eq. 2-6).
//!
//! Phase convention used by the motor: the phase φ ∈ [0, 1) runs over one cycle, starting
//! at the left heel strike. The left foot supports the body during φ ∈ [0, Ds/Dc), the
//! right one during [½, ½ + Ds/Dc) (mod 1); the two double supports are [0, Dds/Dc) and
//! [½, ½ + Dds/Dc). Since Ds = ½ Dc + Dds and Db = ½ Dc − Dds (both follow from eq. 2-6),
//! the balance (swing) of one foot is exactly the single support of the other.

/// Eq. 2-5 coefficient: RLc = 1.346 √RV.
pub const RLC_COEFFICIENT: f64 = 1.346;

/// Fraction of the standing height that is the thigh height Ht (thesis 2.6: 53 %).
pub const THIGH_HEIGHT_FRACTION: f64 = 0.53;

/// Lowest relative velocity the cadence model uses: below it the cycle duration stays
/// that of RV = 0.3 and steps get shorter instead, so that starting and stopping keep a
/// natural rhythm (eq. 2-6 would give a negative double support only above RV ≈ 5.6 and
/// an infinitely slow cycle at RV → 0).
pub const MIN_CADENCE_RV: f64 = 0.3;

/// Highest relative velocity accepted: eq. 2-6 gives Dds = 0 at Dc = 0.567 s, i.e.
/// RV ≈ 5.6; the walking data the model comes from stop near RV = 3.
pub const MAX_RV: f64 = 3.0;

/// The durations of one cycle (seconds), eq. 2-6.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CycleTimes {
    /// Dc: duration of the cycle.
    pub cycle: f64,
    /// Ds: duration of support of one foot.
    pub support: f64,
    /// Db: duration of balance (swing) of one foot.
    pub balance: f64,
    /// Dds: duration of one double support (there are two per cycle).
    pub double_support: f64,
}

impl CycleTimes {
    /// Eq. 2-6 for a cycle of duration `dc` seconds.
    pub fn from_cycle(dc: f64) -> CycleTimes {
        CycleTimes {
            cycle: dc,
            support: 0.752 * dc - 0.143,
            balance: 0.248 * dc + 0.143,
            double_support: 0.252 * dc - 0.143,
        }
    }

    /// The support duration as a fraction of the cycle.
    pub fn support_fraction(&self) -> f64 {
        self.support / self.cycle
    }
}

/// The relative cycle length RLc (cycle length / Ht) for relative velocity `rv` (eq. 2-5).
pub fn relative_cycle_length(rv: f64) -> f64 {
    RLC_COEFFICIENT * rv.max(0.0).sqrt()
}

/// The cycle of a walk at `speed` m/s by a body of thigh height `ht` m, with the step
/// length scaled by `step_scale` (a personification parameter; 1 is the thesis' walk).
///
/// Dc = Lc / V = RLc·Ht / (RV·Ht) = 1.346 / √RV (eq. 2-5), times `step_scale`; the
/// cadence is held at that of [`MIN_CADENCE_RV`] for slower walks.
pub fn cycle_at(speed: f64, ht: f64, step_scale: f64) -> CycleTimes {
    let rv = (speed / ht).max(MIN_CADENCE_RV);
    let dc = relative_cycle_length(rv) / rv * step_scale;
    // Eq. 2-6 leaves no double support below Dc = 0.143 / 0.252 = 0.567 s (shortened
    // steps at a high speed): the cycle is kept above that, so the steps lengthen.
    CycleTimes::from_cycle(dc.max(MIN_CYCLE))
}

/// The shortest cycle (s): eq. 2-6 then still gives about 14 ms of double support.
pub const MIN_CYCLE: f64 = 0.62;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_steps_at_high_speed_keep_a_double_support() {
        let ht = 0.93;
        for rv in [1.0, 1.5, 2.0, 3.0] {
            let c = cycle_at(rv * ht, ht, 0.5);
            assert!(c.double_support > 0.0, "RV {rv}: {c:?}");
            assert!(c.cycle >= MIN_CYCLE);
        }
    }

    #[test]
    fn phase_durations_add_up() {
        for dc in [0.8, 1.0, 1.5, 2.4] {
            let c = CycleTimes::from_cycle(dc);
            assert!((c.support + c.balance - dc).abs() < 1e-12);
            // One cycle = two double supports + two single supports (= two balances).
            assert!((2.0 * c.double_support + 2.0 * c.balance - dc).abs() < 1e-12);
            assert!(c.double_support > 0.0);
        }
    }

    #[test]
    fn cycle_length_follows_eq_2_5() {
        let ht = 0.93;
        for rv in [0.5, 1.0, 1.5, 2.0] {
            let v = rv * ht;
            let c = cycle_at(v, ht, 1.0);
            let rlc = v * c.cycle / ht;
            assert!(
                (rlc - 1.346 * f64::sqrt(rv)).abs() < 1e-12,
                "rv {rv}: {rlc}"
            );
        }
        // Slower than the cadence floor: the cycle duration stops growing.
        let slow = cycle_at(0.05, ht, 1.0);
        assert_eq!(slow, cycle_at(0.3 * ht, ht, 1.0));
    }
}
