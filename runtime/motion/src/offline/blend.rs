//! Weighted blending of two sequences over a transition window (thesis 5.3, eq. 5-8):
//! `q(t) = w(t)·q_A(t) + (1 − w(t))·q_B(t)` with an ease-in/ease-out weight `w`.

use crate::error::{Error, Result};
use crate::sequence::{Sequence, Track};
use troupe_body::math::smoothstep;

/// The ease-in/ease-out weight from 1 down to 0 as `u` goes from 0 to 1 (`1 − smoothstep`);
/// its slope is zero at both ends, so a blend through it is continuous in slope.
pub fn ease_out(u: f64) -> f64 {
    1.0 - smoothstep(u)
}

/// The derivative of [`ease_out`] with respect to `u`.
pub fn ease_out_slope(u: f64) -> f64 {
    if !(0.0..=1.0).contains(&u) {
        return 0.0;
    }
    -6.0 * u * (1.0 - u)
}

/// Where the second sequence B takes over from A: the weight of A falls from 1 to 0 over
/// `[start, start + over]`. With `end` set (B lies inside A, thesis 5.3), the weight comes
/// back from 0 to 1 over `[end − over, end]`; `over` is then at most half of `end − start`,
/// which gives the thesis's weight reaching 0 only at the middle `(t3 + t4) / 2`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transition {
    /// When the transition begins (seconds, on A's time base).
    pub start: f64,
    /// How long the ease lasts (seconds, ≥ 0).
    pub over: f64,
    /// When B ends, if it ends before A does.
    pub end: Option<f64>,
}

impl Transition {
    /// The transition from A to B starting at `start` and lasting `over`.
    pub fn new(start: f64, over: f64, end: Option<f64>) -> Result<Transition> {
        if !(start.is_finite() && over.is_finite() && over >= 0.0) {
            return Err(Error::invalid_value(
                "blend window",
                over,
                "a finite start and a duration ≥ 0",
            ));
        }
        let over = match end {
            Some(e) if e <= start => {
                return Err(Error::invalid_value(
                    "blend end",
                    e,
                    "after the blend start",
                ))
            }
            Some(e) => over.min((e - start) / 2.0),
            None => over,
        };
        Ok(Transition { start, over, end })
    }

    /// The weight of A at time `t` (B gets `1 − w`).
    pub fn weight(&self, t: f64) -> f64 {
        let out = self.step(t - self.start);
        match self.end {
            Some(e) => 1.0 - (1.0 - out) * (1.0 - self.step(e - t)),
            None => out,
        }
    }

    /// The time derivative of [`Transition::weight`].
    pub fn weight_slope(&self, t: f64) -> f64 {
        match self.end {
            None => self.step_slope(t - self.start),
            Some(e) => {
                // w = 1 − (1 − out)·(1 − back), out = step(t − start), back = step(e − t)
                let (out, so) = (self.step(t - self.start), self.step_slope(t - self.start));
                let (back, sb) = (self.step(e - t), self.step_slope(e - t));
                so * (1.0 - back) - (1.0 - out) * sb
            }
        }
    }

    fn step(&self, x: f64) -> f64 {
        if self.over <= 0.0 {
            if x < 0.0 {
                1.0
            } else {
                0.0
            }
        } else {
            ease_out(x / self.over)
        }
    }

    fn step_slope(&self, x: f64) -> f64 {
        if self.over <= 0.0 {
            0.0
        } else {
            ease_out_slope(x / self.over) / self.over
        }
    }
}

/// Two sequences aligned for blending: B is shifted so that its first key falls at
/// `at` on A's time base.
#[derive(Clone, Debug)]
pub struct BlendPair<'a> {
    /// The first sequence.
    pub a: &'a Sequence,
    /// The second sequence.
    pub b: &'a Sequence,
    /// How much to add to a time on A's base to get the time on B's base.
    pub b_shift: f64,
    /// The weighting.
    pub transition: Transition,
}

impl<'a> BlendPair<'a> {
    /// Places B at `at` with a transition of `over` seconds; when B ends before A the
    /// weight returns to A at B's end (the "inside" case of 5.3).
    pub fn new(a: &'a Sequence, b: &'a Sequence, at: f64, over: f64) -> Result<BlendPair<'a>> {
        let b_end = at + b.duration();
        let end = (b_end < a.end()).then_some(b_end);
        Ok(BlendPair {
            a,
            b,
            b_shift: b.start() - at,
            transition: Transition::new(at, over, end)?,
        })
    }

    /// First and last time of the blended result.
    pub fn span(&self) -> (f64, f64) {
        let b_start = self.b.start() - self.b_shift;
        let b_end = self.b.end() - self.b_shift;
        (self.a.start().min(b_start), self.a.end().max(b_end))
    }

    /// Every DOF of A then the DOFs only B has.
    pub fn dofs(&self) -> Vec<String> {
        let mut names: Vec<String> = self
            .a
            .tracks()
            .iter()
            .map(|t| t.dof().to_string())
            .collect();
        for t in self.b.tracks() {
            if self.a.track(t.dof()).is_none() {
                names.push(t.dof().to_string());
            }
        }
        names
    }

    /// The two tracks of a DOF (either may be missing).
    pub fn tracks(&self, dof: &str) -> (Option<&'a Track>, Option<&'a Track>) {
        (self.a.track(dof), self.b.track(dof))
    }

    /// The blended value of eq. 5-8 (a DOF only one sequence has takes that one's value).
    pub fn value(&self, dof: &str, t: f64) -> f64 {
        match self.tracks(dof) {
            (Some(a), Some(b)) => {
                let w = self.transition.weight(t);
                w * a.value(t) + (1.0 - w) * b.value(t + self.b_shift)
            }
            (Some(a), None) => a.value(t),
            (None, Some(b)) => b.value(t + self.b_shift),
            (None, None) => 0.0,
        }
    }

    /// The derivative of [`BlendPair::value`] with respect to time.
    pub fn velocity(&self, dof: &str, t: f64) -> f64 {
        match self.tracks(dof) {
            (Some(a), Some(b)) => {
                let w = self.transition.weight(t);
                let dw = self.transition.weight_slope(t);
                let (qa, qb) = (a.value(t), b.value(t + self.b_shift));
                dw * (qa - qb) + w * a.velocity(t) + (1.0 - w) * b.velocity(t + self.b_shift)
            }
            (Some(a), None) => a.velocity(t),
            (None, Some(b)) => b.velocity(t + self.b_shift),
            (None, None) => 0.0,
        }
    }
}

/// Blends `b` into `a` (eq. 5-8): B starts at time `at` of A, the weight eases from A to
/// B over `over` seconds. The result is sampled every `dt` seconds (the smaller frame time
/// of the two when `None`), with keys whose slopes are the exact derivative of the blend.
pub fn blend(a: &Sequence, b: &Sequence, at: f64, over: f64, dt: Option<f64>) -> Result<Sequence> {
    let pair = BlendPair::new(a, b, at, over)?;
    let dt = dt.unwrap_or_else(|| a.frame_time().min(b.frame_time()));
    if !(dt.is_finite() && dt > 0.0) {
        return Err(Error::invalid_value("blend sampling period", dt, "> 0"));
    }
    let (t0, t1) = pair.span();
    // Up to the end: a span that is not a whole number of frames ends on a shorter one.
    let n = ((t1 - t0) / dt - 1e-9).ceil().max(0.0) as usize + 1;
    let mut out = a.empty_like();
    out.name = format!("{}+{}", a.name, b.name);
    out.meta.insert("rate".into(), format!("{}", 1.0 / dt));
    for dof in pair.dofs() {
        let (ta, tb) = pair.tracks(&dof);
        let (mut ca, mut cb) = (0, 0);
        let keys = (0..n)
            .map(|i| {
                let t = (t0 + i as f64 * dt).min(t1);
                let tbt = t + pair.b_shift;
                let (w, dw) = (pair.transition.weight(t), pair.transition.weight_slope(t));
                let (value, slope) = match (ta, tb) {
                    (Some(a), Some(b)) => {
                        let (qa, qb) = (a.value_at(t, &mut ca), b.value_at(tbt, &mut cb));
                        (
                            w * qa + (1.0 - w) * qb,
                            dw * (qa - qb) + w * a.velocity(t) + (1.0 - w) * b.velocity(tbt),
                        )
                    }
                    (Some(a), None) => (a.value_at(t, &mut ca), a.velocity(t)),
                    (None, Some(b)) => (b.value_at(tbt, &mut cb), b.velocity(tbt)),
                    (None, None) => (0.0, 0.0),
                };
                crate::sequence::Key::with_slope(t, value, slope)
            })
            .collect();
        out.add_track(Track::new(dof, keys)?)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sequence::Key;

    pub(crate) fn wave(name: &str, f: impl Fn(f64) -> f64, t0: f64, n: usize) -> Sequence {
        let mut s = Sequence::new(name);
        s.meta.insert("rate".into(), "100".into());
        let values: Vec<f64> = (0..n).map(|i| f(t0 + i as f64 * 0.01)).collect();
        s.add_track(Track::from_samples("x", t0, 0.01, &values).unwrap())
            .unwrap();
        s
    }

    #[test]
    fn blend_is_continuous_in_value_and_slope_across_the_window() {
        let a = wave("a", |t| (3.0 * t).sin(), 0.0, 201);
        let b = wave("b", |t| 0.5 + (5.0 * t).cos(), 0.0, 201);
        for (at, over) in [(1.0, 0.4), (0.5, 1.0), (1.2, 0.0), (0.2, 0.6)] {
            let pair = BlendPair::new(&a, &b, at, over).unwrap();
            let e = 1e-9;
            for edge in [at, at + over] {
                if over > 0.0 {
                    let (l, r) = (pair.value("x", edge - e), pair.value("x", edge + e));
                    assert!((l - r).abs() < 1e-7, "value jump at {edge}: {l} {r}");
                    let (l, r) = (pair.velocity("x", edge - e), pair.velocity("x", edge + e));
                    assert!((l - r).abs() < 1e-6, "slope jump at {edge}: {l} {r}");
                }
            }
            // The analytic velocity is the derivative of the value.
            for i in 1..300 {
                let t = i as f64 * 0.01 + 0.003;
                let fd = (pair.value("x", t + 1e-6) - pair.value("x", t - 1e-6)) / 2e-6;
                if over > 0.0 || (t - at).abs() > 0.01 {
                    assert!((fd - pair.velocity("x", t)).abs() < 1e-4, "{t}");
                }
            }
        }
        let s = blend(&a, &b, 1.0, 0.4, None).unwrap();
        let x = s.track("x").unwrap();
        assert!((x.value(0.5) - (1.5f64).sin()).abs() < 1e-9);
        assert!((x.value(1.9) - (0.5 + (5.0 * 0.9f64).cos())).abs() < 1e-9);
        assert_eq!(x.keys().len(), 301);
    }

    #[test]
    fn inside_blend_returns_to_the_first_sequence() {
        let a = wave("a", |_| 0.0, 0.0, 401);
        let b = wave("b", |_| 1.0, 0.0, 101);
        let pair = BlendPair::new(&a, &b, 1.0, 5.0).unwrap();
        let tr = pair.transition;
        assert_eq!(tr.end, Some(2.0));
        assert_eq!(tr.over, 0.5);
        assert_eq!(tr.weight(1.0), 1.0);
        assert!(tr.weight(1.5).abs() < 1e-12, "0 at the middle");
        assert_eq!(tr.weight(2.0), 1.0);
        assert!((pair.value("x", 1.5) - 1.0).abs() < 1e-12);
        assert_eq!(pair.value("x", 3.0), 0.0);
    }

    #[test]
    fn a_dof_of_one_sequence_only_is_kept() {
        let a = wave("a", |_| 1.0, 0.0, 11);
        let mut b = Sequence::new("b");
        b.add_track(Track::new("y", vec![Key::new(0.0, 2.0), Key::new(0.1, 2.0)]).unwrap())
            .unwrap();
        let s = blend(&a, &b, 0.05, 0.02, None).unwrap();
        assert_eq!(s.tracks().len(), 2);
        assert_eq!(s.track("y").unwrap().value(0.1), 2.0);
    }
}
