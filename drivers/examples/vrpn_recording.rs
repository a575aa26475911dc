//! Writes `scripts/examples/performer_vrpn.rec`: what a VRPN server would stream for the
//! example scene `performer_vrpn.lua`, as troupe records a live VRPN connection.
//!
//! A tracker `Tracker0` with three sensors (0 pelvis, 1 right wrist, 2 left wrist) on a
//! performer standing at (−0.45, 0, 0.8) facing 180°, 50 reports a second for 12 s, each
//! sensor's pose the forward kinematics of a scripted posture: standing for a second (the
//! calibration), then raising the right forearm to hold the hand out from 1.5 s to 3 s, the
//! left hand swinging a little. A wand `Wand0` whose button 0 goes down at 3.5 s and up
//! at 3.7 s, and whose analog channel 0 (a trigger) rises from 0 to 1 over 3.0–3.5 s,
//! reported ten times a second while it changes. The messages are encoded as the wire carries them, with sender and type
//! descriptions first, so the replay runs the very decoder a live connection does.
//!
//! Run: `cargo run -p troupe-drivers --example vrpn_recording -- scripts/examples/performer_vrpn.rec`

use std::path::PathBuf;
use troupe_body::glam::DVec3;
use troupe_body::kinematics::forward_kinematics;
use troupe_body::transform::Transform;
use troupe_drivers::record::Recorder;
use troupe_drivers::vrpn::wire::{encode, name_payload, system};
use troupe_drivers::vrpn::{types, VrpnConfig};
use troupe_scene::{ActorDesc, Scene, SceneConfig};

/// Smooth 0 → 1 between `a` and `b` seconds.
fn ramp(t: f64, a: f64, b: f64) -> f64 {
    let x = ((t - a) / (b - a)).clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = PathBuf::from(
        std::env::args()
            .nth(1)
            .unwrap_or_else(|| "scripts/examples/performer_vrpn.rec".into()),
    );
    let mut scene = Scene::new(SceneConfig::default())?;
    let pat = scene.add_actor(&ActorDesc {
        at: DVec3::new(-0.45, 0.0, 0.8),
        facing_degrees: 180.0,
        ..ActorDesc::new("pat")
    })?;
    let sk = scene.actors()[pat].skeleton.clone();
    let rest = scene.states()[pat].q.clone();
    let joints = ["HumanoidRoot", "r_wrist", "l_wrist"].map(|j| sk.joint(j).unwrap());
    let dof = |n: &str| sk.dof(n).unwrap();
    let (r_sh, r_el, l_sh) = (
        dof("r_shoulder_flexion"),
        dof("r_elbow_flexion"),
        dof("l_shoulder_flexion"),
    );

    let rec = Recorder::create(&out)?;
    let config = VrpnConfig {
        device: "Tracker0@localhost".into(),
        senders: vec!["Tracker0".into(), "Wand0".into()],
    };
    let s = rec.add_stream("pat.vrpn", "vrpn", serde_json::to_value(&config)?);
    // Server ids: senders 0 Tracker0, 1 Wand0; types 0 Pos_Quat, 1 Button Change,
    // 2 Analog Channel.
    let start_sec = 1_800_000_000u32;
    let descriptions = [
        encode(
            start_sec,
            0,
            0,
            system::SENDER_DESCRIPTION,
            &name_payload("Tracker0"),
        ),
        encode(
            start_sec,
            0,
            1,
            system::SENDER_DESCRIPTION,
            &name_payload("Wand0"),
        ),
        encode(
            start_sec,
            0,
            0,
            system::TYPE_DESCRIPTION,
            &name_payload(types::POS_QUAT),
        ),
        encode(
            start_sec,
            0,
            1,
            system::TYPE_DESCRIPTION,
            &name_payload(types::BUTTON_CHANGE),
        ),
        encode(
            start_sec,
            0,
            2,
            system::TYPE_DESCRIPTION,
            &name_payload(types::ANALOG),
        ),
    ]
    .concat();
    rec.data_at(s, 0, &descriptions);
    let rate = 50.0;
    let mut globals = vec![Transform::IDENTITY; sk.joints().len()];
    let mut button_down = false;
    for frame in 0..(12.0 * rate) as u64 {
        let t = frame as f64 / rate;
        let micros = frame * 1_000_000 / rate as u64;
        let (sec, usec) = (
            start_sec + (micros / 1_000_000) as u32,
            (micros % 1_000_000) as u32,
        );
        let mut q = rest.clone();
        let raise = ramp(t, 1.5, 3.0);
        q[r_sh] = 0.7 * raise;
        q[r_el] = 0.6 * raise;
        q[l_sh] = 0.15 * (0.8 * t).sin().abs() * ramp(t, 1.0, 2.0);
        forward_kinematics(&sk, &q, &mut globals);
        let mut bytes = Vec::new();
        for (sensor, &j) in joints.iter().enumerate() {
            let g = globals[j];
            let mut p = Vec::with_capacity(64);
            p.extend_from_slice(&(sensor as i32).to_be_bytes());
            p.extend_from_slice(&(sensor as i32).to_be_bytes());
            for v in g.translation.to_array() {
                p.extend_from_slice(&v.to_be_bytes());
            }
            for v in g.rotation.to_array() {
                p.extend_from_slice(&v.to_be_bytes());
            }
            bytes.extend(encode(sec, usec, 0, 0, &p));
        }
        let want_down = (3.5..3.7).contains(&t);
        if want_down != button_down {
            button_down = want_down;
            bytes.extend(encode(
                sec,
                usec,
                1,
                1,
                &[0, 0, 0, 0, 0, 0, 0, u8::from(want_down)],
            ));
        }
        // The trigger: a report every fifth frame while it moves (VRPN sends on change).
        if frame % 5 == 0 && (2.9..3.6).contains(&t) {
            let trigger = ramp(t, 3.0, 3.5);
            let payload = [1.0f64.to_be_bytes(), trigger.to_be_bytes()].concat();
            bytes.extend(encode(sec, usec, 1, 2, &payload));
        }
        rec.data_at(s, micros, &bytes);
    }
    rec.finish()?;
    println!("wrote {}", out.display());
    Ok(())
}
