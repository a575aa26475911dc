//! The `capture` action: a performer's actor follows its devices. Its generator writes the
//! device-driven DOFs of the performer's capture target within the action's scope; the
//! glove hand's fingers go through the grasping automaton (thesis 4.7).

use crate::glove_grasp::GloveHand;
use crate::performer::registry::{CaptureTarget, Performer, SharedPerformers};
use mlua::MultiValue;
use std::sync::{Arc, Mutex};
use troupe_body::Scope;
use troupe_lua::api::lua_err_message;
use troupe_lua::args;
use troupe_lua::kinds::{ActionKind, ActionKinds, BuildContext, CommonOptions};
use troupe_scene::action::{ActionSpec, DofWriter, Generator, GeneratorContext, Step};
use troupe_scene::StartError;

/// The `capture` generator: writes the performer's device-driven DOFs within its scope;
/// the glove hand's fingers go through the grasping automaton ([`GloveHand`]).
pub struct Capture {
    target: Arc<Mutex<CaptureTarget>>,
    hand: Option<GloveHand>,
}

impl Generator for Capture {
    fn start(&mut self, ctx: &GeneratorContext) -> Result<(), StartError> {
        match &mut self.hand {
            Some(h) => h.start(ctx).map_err(|e| StartError::new(e.to_string())),
            None => Ok(()),
        }
    }

    fn step(&mut self, ctx: &GeneratorContext, out: &mut DofWriter) -> Step {
        let Ok(t) = self.target.lock() else {
            return Step::Failed("capture target lock poisoned".into());
        };
        let scope = out.scope();
        let fingers = self
            .hand
            .as_ref()
            .map(|h| h.fingers())
            .unwrap_or(Scope::EMPTY);
        for d in scope.iter() {
            if t.mask.get(d).copied().unwrap_or(false) && !fingers.contains(d) {
                out.set(d, t.q[d]);
            }
        }
        if let Some(h) = &mut self.hand {
            if let Err(e) = h.step(ctx, &t.q, &t.mask, out) {
                return Step::Failed(format!("capture: {e}"));
            }
        }
        Step::Running
    }
}

/// `actor:capture{ <common options> }` on a performer: follow the devices (runs until
/// cancelled). Default scope: every DOF the devices drive.
fn build_capture(
    ctx: &BuildContext,
    args: MultiValue,
) -> mlua::Result<(Box<dyn Generator>, ActionSpec)> {
    let t = args::opt_table_arg("capture", args)?;
    let common = CommonOptions::parse(ctx, "capture", t.as_ref(), &[])?;
    let shared = ctx
        .lua
        .app_data_ref::<SharedPerformers>()
        .ok_or_else(|| lua_err_message("capture: devices are not enabled in this run"))?
        .clone();
    let perf = shared
        .0
        .lock()
        .map_err(|_| lua_err_message("capture: performer lock poisoned"))?;
    let p = perf
        .list
        .iter()
        .find(|p| p.actor == ctx.actor)
        .ok_or_else(|| {
            lua_err_message(
                "capture: this actor is not a performer (create it with troupe.performer)",
            )
        })?;
    let natural = device_scope(p);
    let target = p.target.clone();
    let glove = p
        .glove
        .as_ref()
        .zip(p.hand.clone())
        .map(|(g, status)| (g.side, status));
    drop(perf);
    let spec = common.spec("capture", natural);
    let hand = match glove {
        // The automaton runs when this capture drives the glove hand's fingers.
        Some((side, status)) => {
            let fingers = troupe_body::sensors::HandSensors::new(&ctx.skeleton, side)
                .map_err(|e| args::err("capture", e))?
                .scope;
            if spec.scope.intersection(&fingers).is_empty() {
                None
            } else {
                Some(GloveHand::new(side, status))
            }
        }
        None => None,
    };
    let mut spec = spec;
    spec.duration = None;
    Ok((Box::new(Capture { target, hand }), spec))
}

/// Every DOF a performer's devices drive: the natural scope of its `capture`.
fn device_scope(p: &Performer) -> Scope {
    let mut dofs: Vec<usize> = Vec::new();
    let converters = p
        .fob
        .iter()
        .map(|f| &f.converter)
        .chain(p.osc.iter().map(|o| &o.converter));
    for c in converters {
        dofs.extend(c.driven_dofs());
    }
    if let Some(g) = &p.glove {
        dofs.extend(g.map.all_dofs());
    }
    dofs.into_iter().collect()
}

/// Registers the `capture` action kind.
pub fn register(kinds: &mut ActionKinds) {
    kinds.register(ActionKind {
        method: "capture",
        build: build_capture,
    });
}
