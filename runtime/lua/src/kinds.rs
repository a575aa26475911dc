//! The registry of action kinds that Lua can start, and the options every kind shares.
//!
//! Each kind registers one actor method (`play`, `reach`, `walk`, …) with a builder that
//! turns the Lua arguments into a generator and an [`ActionSpec`]; a new kind is one
//! [`ActionKinds::register`] call.

use crate::args::{err, opt_number, opt_string};
use mlua::{Lua, MultiValue, Table, Value};
use std::path::PathBuf;
use std::sync::Arc;
use troupe_body::scope::Scope;
use troupe_body::skeleton::Skeleton;
use troupe_scene::action::{ActionSpec, Generator, Mode};
use troupe_scene::scene::Scene;

/// What a builder may look at while it makes an action.
pub struct BuildContext<'a> {
    /// The Lua state (to read arguments, make values).
    pub lua: &'a Lua,
    /// The index of the actor the method was called on.
    pub actor: usize,
    /// The actor's skeleton.
    pub skeleton: Arc<Skeleton>,
    /// The folder of the scene file, for relative paths.
    pub base_dir: PathBuf,
}

impl BuildContext<'_> {
    /// Reads the scene (as of the last tick). Do not call Lua from inside `f`.
    pub fn with_scene<R>(&self, f: impl FnOnce(&Scene) -> R) -> mlua::Result<R> {
        crate::stage::with_scene(self.lua, f)
    }

    /// Changes the scene (e.g. to start a partner's action for an interaction). Do not
    /// call Lua from inside `f`.
    pub fn with_scene_mut<R>(&self, f: impl FnOnce(&mut Scene) -> R) -> mlua::Result<R> {
        with_scene_mut(self.lua, f)
    }
}

pub use crate::stage::{with_scene, with_scene_mut};

/// Makes a function for the `troupe` table (e.g. `troupe.plan_grasp`).
pub type MakeFunction = fn(&Lua) -> mlua::Result<mlua::Function>;

/// Turns a Lua call's arguments (after `self`) into a generator and its spec.
pub type BuildFn = fn(&BuildContext, MultiValue) -> mlua::Result<(Box<dyn Generator>, ActionSpec)>;

/// One action kind as seen from Lua.
#[derive(Clone, Copy)]
pub struct ActionKind {
    /// The actor method name (`play`).
    pub method: &'static str,
    /// Builds the action.
    pub build: BuildFn,
}

/// The kinds Lua scripts can start.
#[derive(Clone, Default)]
pub struct ActionKinds {
    kinds: Vec<ActionKind>,
    functions: Vec<(&'static str, MakeFunction)>,
}

impl ActionKinds {
    /// Adds (or replaces) a kind.
    pub fn register(&mut self, kind: ActionKind) {
        self.kinds.retain(|k| k.method != kind.method);
        self.kinds.push(kind);
    }

    /// The kind registered under `method`.
    pub fn get(&self, method: &str) -> Option<&ActionKind> {
        self.kinds.iter().find(|k| k.method == method)
    }

    /// Every registered kind.
    pub fn all(&self) -> &[ActionKind] {
        &self.kinds
    }

    /// Adds (or replaces) a function `troupe.<name>` made by `make` when the Lua state
    /// is set up: queries that live outside the runtime crate (`troupe.plan_grasp`).
    pub fn register_function(&mut self, name: &'static str, make: MakeFunction) {
        self.functions.retain(|(n, _)| *n != name);
        self.functions.push((name, make));
    }

    /// Every registered `troupe` function.
    pub fn functions(&self) -> &[(&'static str, MakeFunction)] {
        &self.functions
    }
}

/// The option names every action constructor accepts.
pub const COMMON_OPTIONS: [&str; 7] = [
    "scope", "mode", "weight", "ease_in", "ease_out", "delay", "duration",
];

/// The common options of an action call, parsed and checked.
#[derive(Clone, Debug, PartialEq)]
pub struct CommonOptions {
    /// `scope`: a scope expression resolved on the actor's skeleton.
    pub scope: Option<Scope>,
    /// `mode`.
    pub mode: Mode,
    /// `weight` (default 1).
    pub weight: f64,
    /// `ease_in` seconds.
    pub ease_in: f64,
    /// `ease_out` seconds.
    pub ease_out: f64,
    /// `delay` seconds.
    pub delay: f64,
    /// `duration` seconds.
    pub duration: Option<f64>,
}

impl CommonOptions {
    /// Reads the common options from `opts` (which may be absent); any key that is
    /// neither common nor in `extra` is an error naming it.
    pub fn parse(
        ctx: &BuildContext,
        method: &str,
        opts: Option<&Table>,
        extra: &[&str],
    ) -> mlua::Result<CommonOptions> {
        let mut o = CommonOptions {
            scope: None,
            mode: Mode::Default,
            weight: 1.0,
            ease_in: 0.0,
            ease_out: 0.0,
            delay: 0.0,
            duration: None,
        };
        let Some(opts) = opts else { return Ok(o) };
        for pair in opts.pairs::<Value, Value>() {
            let (key, _) = pair?;
            let name = match &key {
                Value::String(s) => s.to_str()?.to_string(),
                other => {
                    return Err(err(
                        method,
                        format!("option names must be strings, got {}", other.type_name()),
                    ))
                }
            };
            if !COMMON_OPTIONS.contains(&name.as_str()) && !extra.contains(&name.as_str()) {
                let mut known: Vec<&str> = COMMON_OPTIONS.to_vec();
                known.extend_from_slice(extra);
                return Err(err(
                    method,
                    format!("unknown option `{name}` (known: {})", known.join(", ")),
                ));
            }
        }
        let skeleton = &ctx.skeleton;
        if let Some(expr) = opt_string(opts, method, "scope")? {
            o.scope = Some(
                skeleton
                    .scope(&expr)
                    .map_err(|e| err(method, format!("option `scope`: {e}")))?,
            );
        }
        if let Some(mode) = opt_string(opts, method, "mode")? {
            o.mode = Mode::parse(&mode).map_err(|e| err(method, format!("option `mode`: {e}")))?;
        }
        if let Some(w) = opt_number(opts, method, "weight")? {
            o.weight = w;
        }
        o.ease_in = opt_number(opts, method, "ease_in")?.unwrap_or(0.0);
        o.ease_out = opt_number(opts, method, "ease_out")?.unwrap_or(0.0);
        o.delay = opt_number(opts, method, "delay")?.unwrap_or(0.0);
        o.duration = opt_number(opts, method, "duration")?;
        Ok(o)
    }

    /// The spec for an action of `kind` whose generator naturally drives `natural_scope`
    /// (used when no `scope` option was given).
    pub fn spec(&self, kind: &str, natural_scope: Scope) -> ActionSpec {
        ActionSpec {
            kind: kind.to_string(),
            scope: self.scope.unwrap_or(natural_scope),
            mode: self.mode,
            weight: self.weight,
            delay: self.delay,
            duration: self.duration,
            ease_in: self.ease_in,
            ease_out: self.ease_out,
            yields: Scope::EMPTY,
            takes_back: false,
        }
    }

    /// Like [`CommonOptions::spec`], but refuses a `scope` option that holds none of
    /// `needed`, the DOFs that move `what` (the part the action exists to move): such
    /// an action would run to completion having moved nothing.
    pub fn spec_moving(
        &self,
        ctx: &BuildContext,
        kind: &str,
        natural_scope: Scope,
        needed: Scope,
        what: &str,
    ) -> mlua::Result<ActionSpec> {
        if let Some(scope) = self.scope {
            if !scope.overlaps(&needed) {
                let dofs = ctx.skeleton.dofs();
                let names: Vec<&str> = needed.iter().map(|k| dofs[k].name.as_str()).collect();
                // A short list helps; the forty DOFs of an arm and its hand would not.
                let which = if names.len() <= 8 {
                    format!(" ({})", names.join(", "))
                } else {
                    String::new()
                };
                return Err(err(
                    kind,
                    format!("option `scope` must hold a DOF that moves {what}{which}, got none"),
                ));
            }
        }
        Ok(self.spec(kind, natural_scope))
    }
}
