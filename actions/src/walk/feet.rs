//! Where the feet go: each foot's support and swing over the cycle's phases, the landing
//! chosen when it lifts (under the steered body at [`PLACEMENT`] of its next support,
//! clear of what is round it), followed as the steering changes, and a swinging foot
//! held where the clearance stops it.

use super::route::{wrap, Plan, RootSample};
use super::{surroundings, Walk, BLEND_IN_TIME};
use std::f64::consts::PI;
use troupe_body::glam::{DVec2, DVec3};
use troupe_body::math::smoothstep;
use troupe_scene::space::{clear_foot, foot_may_move, Surroundings};

/// Fraction of its support at which a foot is under the body: where it lands is where the
/// body will be at that point of the support.
pub const PLACEMENT: f64 = 0.4;
/// Fraction of the support spent rolling from the heel onto the flat foot.
pub const HEEL_ROCKER: f64 = 0.15;
/// Foot pitch (radians, heel up) at the toe-off of a full-length step: the foot rolls
/// over the ball so that the ankle rises and comes forward, as it must for the leg to
/// stay within its hip extension at the end of a long support (the toes stay flat, within
/// the metatarsal's 60° limit).
pub const MAX_ROLL: f64 = 1.0;
/// Fraction of the support at which the heel starts to rise.
pub const HEEL_OFF: f64 = 0.55;
/// The least part of a swing's time (a fraction of the usual) left for a foot that stayed
/// down to lift after all; with less, it waits for its next support's end.
pub const LATE_SWING: f64 = 0.5;
/// Farthest (radians) the body turns from a planted foot's heading: the hip twists 45°
/// each way (the leg solve stops at 43°), less what the pelvis' own rotation and the
/// hip's flexion take of it. Past it the leg cannot turn the foot with the body, which
/// then pivoted about the ankle (a walk to a point behind the actor slid a sole 1 m and
/// put it 16 cm into the floor). See `Walk::turn_on_planted_feet`.
pub const TURN_ON_PLANTED: f64 = 0.55;
/// Farthest (radians) a landing turns from the other foot's heading: a step takes the
/// body round by at most about this much, twice [`TURN_ON_PLANTED`] less a margin.
pub const STEP_TURN: f64 = 0.9;

/// How fast (m/s) a swinging foot's landing follows the steered body (see
/// `Walk::follow_steering`).
pub const RETARGET_SPEED: f64 = 3.0;

/// A swinging foot's landing farther than this (m) from where the steered body wants it,
/// and getting no nearer, is stuck (see [`Walk::follow_steering`]).
const STUCK_LANDING: f64 = 0.05;

/// Where a swinging foot will land.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Landing {
    pub(super) plant: DVec2,
    pub(super) yaw: f64,
    /// Toes-up pitch at the heel strike.
    pub(super) strike: f64,
    /// Heel-off pitch (toes down, positive) for the support that follows.
    pub(super) roll: f64,
    /// Whether no clear spot was found under the body then, and it steps in place (see
    /// [`Walk::spot`]).
    pub(super) pinched: bool,
}

/// One foot's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Foot {
    Stance {
        /// Floor point under the ankle when the foot is flat.
        plant: DVec2,
        yaw: f64,
        /// Heel-strike pitch this support started with (0: no heel rocker).
        rocker: f64,
        /// Heel-off pitch; `None` until decided at heel-off.
        roll: Option<f64>,
        /// The next landing, decided at heel-off.
        next: Option<Landing>,
        /// Whether the foot stays down instead of swinging (it is already where it should
        /// be: the end of the walk).
        stays: bool,
    },
    Swing {
        from: DVec3,
        from_pitch: f64,
        from_yaw: f64,
        from_toes: f64,
        to: Landing,
        lift: f64,
        /// Initial horizontal progress rate (per unit of swing).
        start_rate: f64,
        /// Local phase at which the swing began when that was after the support's end (a
        /// foot that stayed down and then lifted: its swing is quicker); 0 for a swing
        /// that began with it.
        begin: f64,
    },
}

/// The pose of one foot this tick.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct FootPose {
    pub(super) ankle: DVec3,
    pub(super) yaw: f64,
    pub(super) pitch: f64,
    pub(super) toes: f64,
}

impl Walk {
    /// The floor spot of foot `leg` for the body at `sample`, `width` scaling the hip
    /// half-width, for a foot that strikes the floor `strike_in` seconds from now: beside
    /// the body, moved until the foot lands clear of what is `around`
    /// (`troupe_nav::clearance::clear_foot`: the body is kept clear by its step's limit,
    /// but a foot lands ahead of it).
    pub(super) fn spot(
        &self,
        around: &Surroundings,
        leg: usize,
        sample: &RootSample,
        width: f64,
        strike_in: f64,
    ) -> (DVec2, bool) {
        let left = DVec2::new(sample.heading.cos(), -sample.heading.sin());
        let side = if leg == 0 { 1.0 } else { -1.0 };
        let offset = left * (side * self.rig.hip_half_width * width);
        let beside = sample.position + offset;
        if let Some(at) = self.cleared(around, leg, beside, sample.heading, strike_in) {
            return (at, false);
        }
        // Pinched there (between a body and an obstacle): a step in place, beside where
        // the body stood on the last tick. (The furthest clear spot on the way there
        // instead put a foot, and the body's capsule with it, into the way of people
        // crossing: the plaza's crowds arrived later.)
        let home = self
            .last_floor
            .and_then(|last| self.cleared(around, leg, last + offset, sample.heading, 0.0));
        (home.unwrap_or(beside), true)
    }

    /// Landing point `at` of foot `leg` heading `yaw`, striking the floor `strike_in`
    /// seconds from now, moved clear of what is `around`
    /// (`troupe_nav::clearance::clear_foot`); `None` if no such place was found. Where
    /// someone walking ahead stands in the way now, clear of where that one will have
    /// gone by then (`Surroundings::ahead`): a walker following another a stride and a
    /// half behind stepped in place, its feet a stride behind its body.
    pub(super) fn cleared(
        &self,
        around: &Surroundings,
        leg: usize,
        at: DVec2,
        yaw: f64,
        strike_in: f64,
    ) -> Option<DVec2> {
        let span = surroundings::foot_span(&self.rig.legs[leg], at, yaw);
        clear_foot(span, around)
            .or_else(|| clear_foot(span, &around.ahead(at, strike_in)?))
            .map(|by| at + by)
    }

    /// The part of a body turn of `turn` radians (from its heading now) that its planted
    /// feet allow: the body stays within [`TURN_ON_PLANTED`] of each planted foot's
    /// heading, or, already further, turns no further from it. A body that must turn
    /// more steps round, each landing turned from the other foot (see
    /// [`Walk::landing_yaw`]). A swinging foot held where it was on the last tick (see
    /// [`Walk::hold_foot`]) holds the body as a planted one does: a foot held by the
    /// clearance as it lifted beside a stand let the body turn on at the catch-up's rate
    /// until the hip twisted past its limit (1.4 rad more than the foot, the leg flipping
    /// round when the foot went on).
    pub(super) fn turn_on_planted_feet(&self, turn: f64) -> f64 {
        (0..2).fold(turn, |turn, leg| {
            let yaw = match self.feet[leg] {
                Foot::Stance { yaw, .. } => yaw,
                Foot::Swing { .. } if self.held[leg] => self.poses[leg].yaw,
                Foot::Swing { .. } => return turn,
            };
            let off = wrap(self.heading - yaw);
            if turn > 0.0 {
                turn.min((TURN_ON_PLANTED - off).max(0.0))
            } else {
                turn.max(-(TURN_ON_PLANTED + off).max(0.0))
            }
        })
    }

    /// The heading foot `leg` lands with when the body is to face `wanted` then: within
    /// [`STEP_TURN`] of the other foot's (planted, or where it lands), so that the body
    /// can face between the two.
    pub(super) fn landing_yaw(&self, leg: usize, wanted: f64) -> f64 {
        let other = match self.feet[1 - leg] {
            Foot::Stance { yaw, .. } => yaw,
            Foot::Swing { to, .. } => to.yaw,
        };
        let turn = wrap(wanted - other);
        if turn.abs() > STEP_TURN {
            other + STEP_TURN.copysign(turn)
        } else {
            wanted
        }
    }

    /// The time at which the total phase reaches `target`, simulated forward from now with
    /// the plan's speeds (so that a landing is planned where the body will really be).
    pub(super) fn time_of_phase(&self, plan: &Plan, target: f64) -> f64 {
        let h = 0.02;
        let (mut t, mut p) = (self.t, self.phase);
        for _ in 0..2000 {
            if p >= target {
                break;
            }
            let rate = 1.0 / self.cycle(self.cadence_speed(plan, t)).cycle;
            let dp = rate * h;
            if p + dp >= target {
                return t + (target - p) / rate;
            }
            p += dp;
            t += h;
        }
        t
    }

    /// Plans the next landing of foot `leg` (whose local phase is now `lambda`).
    pub(super) fn plan_landing(
        &self,
        around: &Surroundings,
        plan: &Plan,
        leg: usize,
        lambda: f64,
        from: DVec2,
    ) -> Landing {
        let sigma = self.cycle(self.cadence).support_fraction();
        let to_strike = 1.0 - lambda;
        let t_mid = self.time_of_phase(plan, self.phase + to_strike + PLACEMENT * sigma);
        let strike_in = to_strike * self.cycle(self.cadence).cycle;
        self.landing_at(around, plan, leg, (t_mid, strike_in), from)
    }

    /// The landing of foot `leg`, stepping from `from`, under the steered body at walk
    /// time `t_mid`, striking the floor `strike_in` seconds from now, clear of what is
    /// `around` (see [`Walk::spot`]).
    pub(super) fn landing_at(
        &self,
        around: &Surroundings,
        plan: &Plan,
        leg: usize,
        (t_mid, strike_in): (f64, f64),
        from: DVec2,
    ) -> Landing {
        let (sample, width) = if self.steer.plan_time(t_mid, self.t) >= plan.end_time {
            (self.end_sample(plan), 1.0)
        } else {
            (
                self.steer.sample(plan, t_mid, self.t, self.heading),
                self.options.step_width,
            )
        };
        let (plant, pinched) = self.spot(around, leg, &sample, width, strike_in);
        let step = (plant - from).length();
        let q = (step / (0.8 * self.rig.thigh_height)).min(1.0);
        Landing {
            plant,
            yaw: self.landing_yaw(leg, sample.heading),
            strike: 0.26 * q,
            roll: MAX_ROLL * q,
            pinched,
        }
    }

    /// Steers the walk from now if `landing` is pinched (a step in place): then the body
    /// goes no further than its planted feet allow (see [`super::footing`]) and the landing
    /// follows it (see [`Walk::follow_steering`]), where a walk that went on along its
    /// plan left the foot a stride behind and the pelvis sank to reach it.
    pub(super) fn hold_for(&mut self, landing: &Landing) {
        if landing.pinched && !self.steer.engaged {
            self.steer.engage(self.t, DVec2::ZERO);
        }
    }

    /// Moves the landing of swinging foot `leg` (local phase `lambda`) towards where the
    /// steered body will be at its mid-support, at most [`RETARGET_SPEED`]: avoidance
    /// changes the pace and the sidestep after the foot lifted, and a landing chosen for
    /// the old ones would leave it a stride ahead of (or beside) a body that stopped.
    pub(super) fn follow_steering(
        &mut self,
        around: &Surroundings,
        plan: &Plan,
        leg: usize,
        lambda: f64,
    ) {
        let Foot::Swing { from, to, .. } = self.feet[leg] else {
            return;
        };
        // The time of its mid-support at the cadence of now: finding it as a new landing
        // does (simulating the cadence ahead) every tick cost the crowd benchmark 40 % of
        // its speed.
        let cycle = self.cycle(self.cadence);
        let ahead = 1.0 - lambda + PLACEMENT * cycle.support_fraction();
        let t_mid = self.t + ahead * cycle.cycle;
        let strike_in = (1.0 - lambda) * cycle.cycle;
        let times = (t_mid, strike_in);
        let fresh = self.landing_at(around, plan, leg, times, DVec2::new(from.x, from.z));
        let step = RETARGET_SPEED * self.dt;
        let plant = to.plant + (fresh.plant - to.plant).clamp_length_max(step);
        let mut yaw = to.yaw + wrap(fresh.yaw - to.yaw).clamp(-2.0 * step, 2.0 * step);
        // Wherever the retargeting has got to, the foot lands clear (a jump of the
        // landing, not of the foot, which swings towards it).
        let mut plant = self
            .cleared(around, leg, plant, yaw, strike_in)
            .unwrap_or(plant);
        // Across a corner of furniture from the body's new landing, the step towards it
        // goes into the corner and clearing puts it back where it was: the landing stayed
        // on the far side, the foot was held (its way crossed the corner) and came down
        // there at the swing's end, through the corner (0.22 m deep in a planter). A
        // landing that gets no nearer jumps to the new one, if that is clear.
        let gap = (to.plant - fresh.plant).length();
        if gap > STUCK_LANDING && (plant - fresh.plant).length() > gap - 0.25 * step {
            if let Some(clear) = self.cleared(around, leg, fresh.plant, fresh.yaw, strike_in) {
                (plant, yaw) = (clear, fresh.yaw);
            }
        }
        if let Foot::Swing { to: landing, .. } = &mut self.feet[leg] {
            landing.plant = plant;
            landing.yaw = yaw;
        }
    }

    /// Advances foot `leg` to local phase `lambda` (support fraction `sigma`) and returns
    /// its pose.
    pub(super) fn step_foot(
        &mut self,
        around: &Surroundings,
        plan: &Plan,
        leg: usize,
        lambda: f64,
        sigma: f64,
    ) -> FootPose {
        let wrapped = lambda < self.lambda[leg];
        self.lambda[leg] = lambda;
        // Transitions first.
        match self.feet[leg] {
            Foot::Swing { to, .. } if wrapped => {
                self.feet[leg] = Foot::Stance {
                    plant: to.plant,
                    yaw: to.yaw,
                    rocker: to.strike,
                    roll: None,
                    next: None,
                    stays: false,
                };
            }
            Foot::Stance { plant, yaw, .. } if wrapped => {
                // A foot that stayed down through its swing starts a new support in place.
                self.feet[leg] = Foot::Stance {
                    plant,
                    yaw,
                    rocker: 0.0,
                    roll: None,
                    next: None,
                    stays: false,
                };
            }
            _ => {}
        }
        if let Foot::Stance {
            plant,
            yaw,
            rocker,
            roll,
            next,
            stays,
        } = self.feet[leg]
        {
            if roll.is_none() && lambda >= HEEL_OFF * sigma {
                let landing = self.plan_landing(around, plan, leg, lambda, plant);
                self.hold_for(&landing);
                let still = self.stays_at(plant, yaw, (landing.plant, landing.yaw));
                self.feet[leg] = Foot::Stance {
                    plant,
                    yaw,
                    rocker,
                    roll: Some(if still { 0.0 } else { landing.roll }),
                    next: Some(landing),
                    stays: still,
                };
            } else if lambda >= sigma && (!stays || lambda <= 1.0 - LATE_SWING * (1.0 - sigma)) {
                let pose = self.poses[leg];
                let to = match next {
                    Some(n) if !stays => n,
                    // A foot that chose to stay down (the body was to stand) lifts after
                    // all once the body has moved on, while enough of its swing is left:
                    // else the body walked on from it, the leg reached back for it and the
                    // pelvis sank to the floor.
                    _ => self.plan_landing(around, plan, leg, lambda, plant),
                };
                self.hold_for(&to);
                let in_place = self.stays_at(plant, yaw, (to.plant, to.yaw)) && pose.pitch == 0.0;
                if in_place {
                    // Already where it should land (a foot that started where the walk
                    // ends, or one staying down whose landing has not moved): it stays
                    // down rather than stepping in place.
                    if let Foot::Stance { stays, .. } = &mut self.feet[leg] {
                        *stays = true;
                    }
                } else {
                    let from_plant = DVec2::new(pose.ankle.x, pose.ankle.z);
                    let step = (to.plant - from_plant).length();
                    let lift = (0.35 * step).clamp(0.02, 0.055 * self.rig.thigh_height)
                        * (1.0 + self.options.run);
                    let swing_time = (1.0 - sigma) * self.cycle(self.cadence).cycle;
                    let body = self.steer.speed(plan, self.t, self.t);
                    let start_rate = if step > 1e-6 {
                        (body * swing_time / step).clamp(0.0, 1.5)
                    } else {
                        0.0
                    };
                    self.feet[leg] = Foot::Swing {
                        from: pose.ankle,
                        from_pitch: pose.pitch,
                        from_yaw: pose.yaw,
                        from_toes: pose.toes,
                        to,
                        lift,
                        start_rate,
                        begin: if stays { lambda } else { 0.0 },
                    };
                }
            }
        }
        // A stop changes where the body will be as much as a steering does: a foot that
        // lifted for the pace before it landed a stride past where the body then stood,
        // and stepped back (0.79 m) to stand.
        if self.steer.engaged || self.stopped_at.is_some() {
            self.follow_steering(around, plan, leg, lambda);
        }
        let rig = &self.rig;
        match self.feet[leg] {
            Foot::Stance {
                plant,
                yaw,
                rocker,
                roll,
                ..
            } => {
                let u = (lambda / sigma).clamp(0.0, 1.0);
                let mut pitch = 0.0;
                if rocker > 0.0 && u < HEEL_ROCKER {
                    pitch = rocker * (1.0 - smoothstep(u / HEEL_ROCKER));
                }
                let roll = roll.unwrap_or(0.0);
                if roll > 0.0 && u > HEEL_OFF {
                    pitch = -roll * smoothstep((u - HEEL_OFF) / (1.0 - HEEL_OFF));
                }
                // A heel that was raised when the walk started comes down as the pelvis
                // rises (see `Walk::legs_at`), over the second half of the rise: put down
                // at once, under a pelvis still crouched, it bent the ankle past its limit
                // and the toes went 8 cm into the floor (1.5 cm, coming down as the
                // pelvis rose).
                let down = smoothstep(2.0 * self.t / BLEND_IN_TIME - 1.0);
                let raised = self.start_pitch[leg] * (1.0 - down);
                if raised < 0.0 && raised < pitch {
                    pitch = raised;
                }
                FootPose {
                    ankle: rig.ankle_from_plant(leg, plant, yaw, pitch),
                    yaw,
                    pitch,
                    toes: pitch.min(0.0),
                }
            }
            Foot::Swing {
                from,
                from_pitch,
                from_yaw,
                from_toes,
                to,
                lift,
                start_rate,
                begin,
            } => {
                let (w, s, ease) = swing_progress(begin, sigma, lambda, start_rate);
                let target = rig.ankle_from_plant(leg, to.plant, to.yaw, to.strike);
                let pitch = from_pitch + (to.strike - from_pitch) * ease;
                let toes = from_toes * (1.0 - smoothstep(w / 0.5));
                // The foot's lowest point rises and falls on a parabola (zero at lift-off
                // and at the strike), so the sole never goes below the floor and leaves
                // and meets it exactly at the phase boundaries.
                let clearance = lift * 4.0 * w * (1.0 - w);
                let mut ankle = from + (target - from) * s;
                let yaw = from_yaw + wrap(to.yaw - from_yaw) * ease;
                // A foot in the air closes on another body or foot by at most half the
                // gap, like the body's step (`troupe_nav::clearance`): held where it was,
                // it swings on to its landing from there. Held whole, its pitch, toes and
                // height too: the clearance sees a foot from above as if it were flat, so
                // a foot rolled onto its toes that went on flattening where it was held
                // put its toes into what held it (a planter's corner, another's foot).
                let before = self.poses[leg];
                let span = |a: DVec3, yaw: f64| {
                    surroundings::foot_span(&rig.legs[leg], DVec2::new(a.x, a.z), yaw)
                };
                let blocked = s < 1.0
                    && ease < 1.0
                    && !foot_may_move(&span(before.ankle, before.yaw), &span(ankle, yaw), around);
                if blocked && self.hold_foot(leg, before, sigma) {
                    return before;
                }
                ankle.y = clearance - self.rig.lowest_offset(leg, pitch, toes);
                FootPose {
                    ankle,
                    yaw,
                    pitch,
                    toes,
                }
            }
        }
    }

    /// Keeps foot `leg` at its pose `pose` of the previous tick, if it is rolling onto its
    /// toes or swinging; a swinging one then swings on to its landing from there. Whether
    /// it was kept.
    pub(super) fn hold_foot(&mut self, leg: usize, pose: FootPose, sigma: f64) -> bool {
        let rig = &self.rig;
        let lambda = self.lambda[leg];
        match &mut self.feet[leg] {
            Foot::Stance { roll: Some(_), .. } => {}
            Foot::Swing {
                from,
                from_pitch,
                from_yaw,
                from_toes,
                to,
                lift,
                start_rate,
                begin,
            } => {
                let (w, s, ease) = swing_progress(*begin, sigma, lambda, *start_rate);
                if s >= 1.0 || ease >= 1.0 {
                    return false;
                }
                // The swing's start moved so that this tick's progress gives the pose held.
                let target = rig.ankle_from_plant(leg, to.plant, to.yaw, to.strike);
                swing_through(
                    from,
                    from_yaw,
                    (to, target),
                    (s, ease),
                    (pose.ankle, pose.yaw),
                );
                *from_pitch = (pose.pitch - to.strike * ease) / (1.0 - ease);
                let toes_left = 1.0 - smoothstep(w / 0.5);
                if toes_left > 1e-3 {
                    *from_toes = pose.toes / toes_left;
                }
                // The height: the parabola through the held foot's, never higher than
                // the swing's own.
                let arc = 4.0 * w * (1.0 - w);
                if arc > 0.05 {
                    let above = pose.ankle.y + rig.lowest_offset(leg, pose.pitch, pose.toes);
                    *lift = (above / arc).clamp(0.0, lift.max(above));
                }
            }
            _ => return false,
        }
        self.poses[leg] = pose;
        self.held[leg] = true;
        true
    }
}

/// How far a swing that began at local phase `begin` (or at the support's end `sigma`,
/// whichever is later) has got at local phase `lambda`: `(w, s, ease)`, the swing's
/// fraction, its horizontal progress and its eased progress (pitch and yaw).
pub(super) fn swing_progress(
    begin: f64,
    sigma: f64,
    lambda: f64,
    start_rate: f64,
) -> (f64, f64, f64) {
    let begin = begin.max(sigma);
    let w = ((lambda - begin) / (1.0 - begin)).clamp(0.0, 1.0);
    // Horizontal progress: a cubic that leaves at `start_rate` (the foot keeps up with the
    // body, so the hip need not extend further) and arrives at rest.
    let s = (w * w * w - 2.0 * w * w + w) * start_rate + (3.0 - 2.0 * w) * w * w;
    (w, s, smoothstep(w))
}

/// Moves a swing's start (`from` on the floor, and `from_yaw`) so that at horizontal
/// progress `s` and eased progress `ease` towards landing `to` (its ankle at `target`) the
/// swing puts the ankle over `ankle` (x, z) and the foot at heading `yaw`: a foot held
/// where it was swings on to its landing from there. Both progresses must be below 1.
pub(super) fn swing_through(
    from: &mut DVec3,
    from_yaw: &mut f64,
    (to, target): (&Landing, DVec3),
    (s, ease): (f64, f64),
    (ankle, yaw): (DVec3, f64),
) {
    let rebased = (ankle - target * s) / (1.0 - s);
    from.x = rebased.x;
    from.z = rebased.z;
    // The swing turns the nearer way from `from_yaw` to the landing's, so the start stays
    // within a half turn of it: a foot held late in its swing, its start put ever further
    // back, crossed the half turn and swung round the other way (the hip twisting 1.4 rad
    // in a tick). Kept there, the foot, still held whole, turns the rest of the way
    // quickly once let go. (Turning it towards its landing while held, as far as the
    // start allows, turned toes into what held it: in the plaza's twelve layouts 27
    // contacts deeper than 1 cm against 4.)
    const HALF_TURN: f64 = PI - 0.05;
    *from_yaw = to.yaw + (wrap(yaw - to.yaw) / (1.0 - ease)).clamp(-HALF_TURN, HALF_TURN);
}
