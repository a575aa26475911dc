//! The Lua API: the `troupe` table, actor, object, action and sequence values.

pub(crate) use crate::args::lua_err;
pub use crate::args::lua_err_message;
use crate::args::{
    bad_arg, check_keys, dot_call_hint, err, euler_degrees, opt_bool, opt_number, opt_string,
    value_name, vec3, vec3_table,
};
use crate::error::Error;
pub use crate::handles::{
    ActionRef, ActorRef, BehaviorRef, HandlerRef, ObjectRef, Pins, SequenceRef,
};
use crate::kinds::BuildContext;
use crate::stage::{add_behavior, stage, BehaviorState, Handler};
use glam::{DQuat, DVec3};
use mlua::{
    AnyUserData, Function, Lua, MetaMethod, MultiValue, Table, UserData, UserDataFields,
    UserDataMethods, Value,
};
use std::path::Path;
use std::sync::Arc;
use troupe_body::skeleton::Skeleton;
use troupe_body::solid::Shape;
use troupe_motion::sequence::{Interpolation, Key, Sequence, Track};
use troupe_scene::action::ActionId;
use troupe_scene::scene::ActorDesc;
use troupe_scene::world::Object;

impl UserData for ActorRef {
    fn add_fields<F: UserDataFields<Self>>(fields: &mut F) {
        fields.add_field_method_get("name", |lua, this| {
            Ok(stage(lua)?.scene.actors()[this.0].name.clone())
        });
        fields.add_field_method_get("template", |lua, this| {
            Ok(stage(lua)?.scene.actors()[this.0].template.clone())
        });
        fields.add_field_method_get("height", |lua, this| {
            Ok(stage(lua)?.scene.actors()[this.0].params.height)
        });
    }

    fn add_methods<M: UserDataMethods<Self>>(methods: &mut M) {
        crate::dynamics::add_actor_methods(methods);
        methods.add_method("behave", |lua, this, f: Value| {
            let Value::Function(f) = f else {
                return Err(bad_arg("behave", "the argument", "a function", &f));
            };
            add_behavior(lua, Some(this.0), f).map(BehaviorRef)
        });
        methods.add_method("position", |lua, this, ()| {
            let p = {
                let st = stage(lua)?;
                st.scene.states()[this.0].globals[0].translation
            };
            vec3_table(lua, p)
        });
        methods.add_method("joint_position", |lua, this, name: String| {
            let p = {
                let st = stage(lua)?;
                let skel = &st.scene.actors()[this.0].skeleton;
                let j = skel.joint(&name).map_err(|e| err("joint_position", e))?;
                st.scene.states()[this.0].globals[j].translation
            };
            vec3_table(lua, p)
        });
        methods.add_method("dof", |lua, this, name: String| {
            let st = stage(lua)?;
            let d = st.scene.actors()[this.0]
                .skeleton
                .dof(&name)
                .map_err(|e| err("dof", e))?;
            Ok(st.scene.states()[this.0].q[d])
        });
        methods.add_method("dofs", |lua, this, scope: String| {
            let names: Vec<String> = {
                let st = stage(lua)?;
                let skel = &st.scene.actors()[this.0].skeleton;
                let s = skel.scope(&scope).map_err(|e| err("dofs", e))?;
                skel.dof_names(&s).into_iter().map(String::from).collect()
            };
            lua.create_sequence_from(names)
        });
        methods.add_method("holding", |lua, this, ()| {
            let held = stage(lua)?.scene.held_by(this.0);
            lua.create_sequence_from(held.into_iter().map(ObjectRef))
        });
        methods.add_method("actions", |lua, this, ()| {
            let ids: Vec<ActionId> = stage(lua)?
                .scene
                .actions_of(this.0)
                .iter()
                .map(|a| a.id)
                .collect();
            let handles = ids
                .into_iter()
                .map(|id| ActionRef::new(lua, id))
                .collect::<mlua::Result<Vec<_>>>()?;
            lua.create_sequence_from(handles)
        });
        methods.add_method("pose", |lua, this, values: Table| {
            let mut st = stage(lua)?;
            let skel = st.scene.actors()[this.0].skeleton.clone();
            let mut set = Vec::new();
            for pair in values.pairs::<String, f64>() {
                let (name, v) = pair
                    .map_err(|e| lua_err(format!("pose: expects {{dof_name = number, …}}: {e}")))?;
                set.push((skel.dof(&name).map_err(|e| err("pose", e))?, v));
            }
            set.sort_by_key(|(d, _)| *d);
            st.scene.set_dofs(this.0, &set).map_err(|e| err("pose", e))
        });
        methods.add_method("set", |lua, this, t: Table| {
            crate::settings::set(lua, this.0, &t)
        });
        methods.add_method("on", |lua, this, (event, f): (Value, Value)| {
            let name = match &event {
                Value::String(s) => s.to_str()?.to_string(),
                other => return Err(bad_arg("on", "the event", "a string", other)),
            };
            if !EVENTS.contains(&name.as_str()) {
                return Err(lua_err(format!(
                    "on: unknown event `{name}` (known: {})",
                    EVENTS.join(", ")
                )));
            }
            let Value::Function(function) = f else {
                return Err(bad_arg("on", "the handler", "a function", &f));
            };
            let mut st = stage(lua)?;
            let id = st.next_handler;
            st.next_handler += 1;
            st.handlers.push(Handler {
                id,
                actor: this.0,
                event: name,
                function,
            });
            Ok(HandlerRef(id))
        });
        methods.add_method("behavior_status", |lua, this, ()| {
            // Running while any of its behaviors runs; then failed if one failed.
            let st = stage(lua)?;
            let states: Vec<&BehaviorState> = st
                .behaviors
                .iter()
                .filter(|b| b.actor == Some(this.0))
                .map(|b| &b.state)
                .collect();
            Ok(if states.is_empty() {
                "none"
            } else if states
                .iter()
                .any(|s| matches!(s, BehaviorState::Waiting(_)))
            {
                "running"
            } else if states.iter().any(|s| matches!(s, BehaviorState::Failed(_))) {
                "failed"
            } else {
                "done"
            })
        });
        methods.add_method("behavior_error", |lua, this, ()| {
            let st = stage(lua)?;
            Ok(st
                .behaviors
                .iter()
                .filter(|b| b.actor == Some(this.0))
                .find_map(|b| match &b.state {
                    BehaviorState::Failed(e) => Some(e.clone()),
                    _ => None,
                }))
        });
        methods.add_meta_method(MetaMethod::Index, |lua, this, key: String| {
            let kind = lua
                .app_data_ref::<crate::kinds::ActionKinds>()
                .and_then(|kinds| kinds.get(&key).copied());
            match kind {
                Some(kind) => {
                    let actor = this.0;
                    let f = lua.create_function(move |lua, args: MultiValue| {
                        let mut args = args.into_iter();
                        // Method call: the first argument is the actor itself.
                        let is_self = matches!(args.next(),
                            Some(Value::UserData(u)) if u.borrow::<ActorRef>().is_ok());
                        if !is_self {
                            return Err(lua_err(dot_call_hint("actor", kind.method)));
                        }
                        start_kind(lua, actor, kind, args.collect())
                    })?;
                    Ok(Value::Function(f))
                }
                None => Err(no_member("Actor", &key)),
            }
        });
        methods.add_meta_method(MetaMethod::ToString, |lua, this, ()| {
            Ok(format!("actor {}", stage(lua)?.scene.actors()[this.0].name))
        });
        methods.add_meta_method(MetaMethod::Eq, |_, this, other: AnyUserData| {
            Ok(other.borrow::<ActorRef>().is_ok_and(|o| o.0 == this.0))
        });
    }
}

fn start_kind(
    lua: &Lua,
    actor: usize,
    kind: crate::kinds::ActionKind,
    args: MultiValue,
) -> mlua::Result<ActionRef> {
    let ctx = {
        let st = stage(lua)?;
        BuildContext {
            lua,
            actor,
            skeleton: st.scene.actors()[actor].skeleton.clone(),
            base_dir: st.base_dir.clone(),
        }
    };
    let (generator, spec) = {
        (kind.build)(&ctx, args).map_err(|e| match e {
            mlua::Error::RuntimeError(m) if !m.starts_with(kind.method) => {
                lua_err(format!("{}: {m}", kind.method))
            }
            other => other,
        })?
    };
    let id = stage(lua)?
        .scene
        .start_action(actor, spec, generator)
        .map_err(|e| lua_err(format!("{}: {e}", kind.method)))?;
    ActionRef::new(lua, id)
}

impl UserData for ObjectRef {
    fn add_fields<F: UserDataFields<Self>>(fields: &mut F) {
        fields.add_field_method_get("name", |lua, this| {
            Ok(stage(lua)?.scene.objects()[this.0].name.clone())
        });
        fields.add_field_method_get("shape", |lua, this| {
            Ok(stage(lua)?.scene.objects()[this.0].shape.kind_name())
        });
        fields.add_field_method_get("mass", |lua, this| {
            Ok(stage(lua)?.scene.objects()[this.0].mass)
        });
        fields.add_field_method_get("holder", |lua, this| {
            Ok(stage(lua)?.scene.holder(this.0).map(|h| ActorRef(h.actor)))
        });
    }
    fn add_methods<M: UserDataMethods<Self>>(methods: &mut M) {
        methods.add_method("position", |lua, this, ()| {
            let p = stage(lua)?.scene.objects()[this.0].position;
            vec3_table(lua, p)
        });
        methods.add_method("up", |lua, this, ()| {
            let r = stage(lua)?.scene.objects()[this.0].rotation;
            vec3_table(lua, r * DVec3::Y)
        });
        methods.add_meta_method(MetaMethod::Index, |_, _, key: String| {
            Err::<Value, _>(no_member("Object", &key))
        });
        methods.add_meta_method(MetaMethod::ToString, |lua, this, ()| {
            Ok(format!(
                "object {}",
                stage(lua)?.scene.objects()[this.0].name
            ))
        });
    }
}

impl UserData for ActionRef {
    fn add_methods<M: UserDataMethods<Self>>(methods: &mut M) {
        methods.add_method("cancel", |lua, this, ()| {
            stage(lua)?.scene.cancel(this.0).map_err(lua_err)
        });
        methods.add_method("stop", |lua, this, ()| {
            stage(lua)?.scene.stop(this.0).map_err(lua_err)
        });
        methods.add_meta_method(MetaMethod::Index, |lua, this, key: String| {
            if key == "wait" {
                return lua
                    .named_registry_value::<Function>("troupe.action_wait")
                    .map(Value::Function);
            }
            let info = stage(lua)?
                .scene
                .action(this.0)
                .ok_or_else(|| lua_err(format!("no action {}", this.0)))?;
            Ok(match key.as_str() {
                "id" => Value::Integer(info.id.0 as i64),
                "status" => Value::String(lua.create_string(info.status.name())?),
                "kind" => Value::String(lua.create_string(&info.kind)?),
                "mode" => Value::String(lua.create_string(info.mode.name())?),
                "weight" => Value::Number(info.weight),
                "dofs" => Value::Integer(info.scope.len() as i64),
                "yielded" => Value::Integer(info.yielded.len() as i64),
                "detours" => Value::Integer(info.detours as i64),
                "error" => match info.reason {
                    Some(r) if info.status != troupe_scene::action::Status::Completed => {
                        Value::String(lua.create_string(&r)?)
                    }
                    _ => Value::Nil,
                },
                _ => return Err(no_member("Action", &key)),
            })
        });
        methods.add_meta_method(MetaMethod::ToString, |_, this, ()| {
            Ok(format!("action {}", this.0))
        });
        methods.add_meta_method(MetaMethod::Eq, |_, this, other: AnyUserData| {
            Ok(other.borrow::<ActionRef>().is_ok_and(|o| o.0 == this.0))
        });
    }
}

/// The events `actor:on` accepts.
pub const EVENTS: [&str; 5] = [
    "action_started",
    "action_completed",
    "action_failed",
    "action_cancelled",
    "action_narrowed",
];

impl UserData for BehaviorRef {
    fn add_methods<M: UserDataMethods<Self>>(methods: &mut M) {
        methods.add_method("stop", |lua, this, ()| {
            let mut st = stage(lua)?;
            let b = &mut st.behaviors[this.0];
            if matches!(b.state, BehaviorState::Waiting(_)) {
                b.state = BehaviorState::Stopped;
                b.thread = None;
            }
            Ok(())
        });
        methods.add_meta_method(MetaMethod::Index, |lua, this, key: String| {
            if key == "wait" {
                return lua
                    .named_registry_value::<Function>("troupe.behavior_wait")
                    .map(Value::Function);
            }
            let st = stage(lua)?;
            let b = &st.behaviors[this.0];
            Ok(match key.as_str() {
                "status" => Value::String(lua.create_string(b.state.name())?),
                "error" => match b.state.error() {
                    Some(e) => Value::String(lua.create_string(e)?),
                    None => Value::Nil,
                },
                "actor" => match b.actor {
                    Some(a) => Value::UserData(lua.create_userdata(ActorRef(a))?),
                    None => Value::Nil,
                },
                _ => return Err(no_member("Behavior", &key)),
            })
        });
        methods.add_meta_method(MetaMethod::ToString, |lua, this, ()| {
            let st = stage(lua)?;
            let who = st.behaviors[this.0]
                .actor
                .map(|a| st.scene.actors()[a].name.clone())
                .unwrap_or_else(|| "test".into());
            Ok(format!("behavior {} of {who}", this.0))
        });
        methods.add_meta_method(MetaMethod::Eq, |_, this, other: AnyUserData| {
            Ok(other.borrow::<BehaviorRef>().is_ok_and(|o| o.0 == this.0))
        });
    }
}

impl UserData for HandlerRef {
    fn add_methods<M: UserDataMethods<Self>>(methods: &mut M) {
        methods.add_method("off", |lua, this, ()| {
            let mut st = stage(lua)?;
            let before = st.handlers.len();
            st.handlers.retain(|h| h.id != this.0);
            Ok(st.handlers.len() < before)
        });
        methods.add_meta_method(MetaMethod::ToString, |_, this, ()| {
            Ok(format!("handler {}", this.0))
        });
        methods.add_meta_method(MetaMethod::Index, |_, _, key: String| {
            Err::<Value, _>(no_member("Handler", &key))
        });
    }
}

impl UserData for SequenceRef {
    fn add_fields<F: UserDataFields<Self>>(fields: &mut F) {
        fields.add_field_method_get("name", |_, this| Ok(this.0.name.clone()));
        fields.add_field_method_get("duration", |_, this| Ok(this.0.duration()));
        fields.add_field_method_get("loop", |_, this| Ok(this.0.looping));
    }
    fn add_methods<M: UserDataMethods<Self>>(methods: &mut M) {
        methods.add_method("dofs", |lua, this, ()| {
            lua.create_sequence_from(this.0.tracks().iter().map(|t| t.dof().to_string()))
        });
        methods.add_method("value", |_, this, (dof, time): (String, f64)| {
            if !time.is_finite() {
                return Err(lua_err(format!(
                    "value: the time must be a finite number of seconds, got {}",
                    value_name(&Value::Number(time))
                )));
            }
            Ok(sequence_track("value", &this.0, &dof)?.value(time))
        });
        methods.add_method("interpolation", |_, this, dof: String| {
            Ok(sequence_track("interpolation", &this.0, &dof)?
                .interpolation()
                .name())
        });
        methods.add_meta_method(MetaMethod::Index, |_, _, key: String| {
            Err::<Value, _>(no_member("Sequence", &key))
        });
    }
}

/// The error of indexing a handle of `class` (as [`crate::reference::CLASSES`] names it)
/// with a name it lacks: the nearest documented one when `key` looks like a slip of it,
/// else the documented names when they are few.
fn no_member(class: &str, key: &str) -> mlua::Error {
    let known: Vec<&str> = crate::reference::API
        .iter()
        .filter(|e| e.owner == class)
        .map(|e| e.name)
        .collect();
    let hint = crate::args::name_hint(key, &known, 12);
    lua_err(format!(
        "{} has no method or field `{key}`{hint}",
        class.to_lowercase()
    ))
}

/// The track of `dof` in `seq`, or an error of `method` naming both.
fn sequence_track<'a>(method: &str, seq: &'a Sequence, dof: &str) -> mlua::Result<&'a Track> {
    seq.track(dof).ok_or_else(|| {
        err(
            method,
            format!(
                "sequence `{}` has no track for `{dof}` (see seq:dofs())",
                seq.name
            ),
        )
    })
}

/// Resolves a path from a script: as given if it exists, else relative to the scene
/// file. A file found in neither place is an error that lists both (once when they are
/// the same: a scene run from its own folder).
pub fn resolve_path(base_dir: &Path, path: &str) -> mlua::Result<std::path::PathBuf> {
    let p = Path::new(path);
    if p.is_absolute() || p.exists() {
        return Ok(p.to_path_buf());
    }
    let beside = base_dir.join(p);
    if beside.exists() {
        return Ok(beside);
    }
    let (given, beside) = (crate::modules::shown(p), crate::modules::shown(&beside));
    let tried = if given == beside {
        format!("{given}, beside the scene")
    } else {
        format!("{given} and, beside the scene, {beside}")
    };
    Err(lua_err(format!(
        "file `{path}` not found; looked for {tried}"
    )))
}

/// Loads a sequence file once per path (and per skeleton for BVH and glTF) with
/// [`troupe_formats::load_sequence`]: a `.trk` as it is, a `.bvh`, `.gltf` or `.glb` onto
/// `skeleton` (the default adult when `None`).
pub fn load_sequence(
    lua: &Lua,
    path: &str,
    skeleton: Option<&Arc<Skeleton>>,
) -> mlua::Result<Arc<Sequence>> {
    let base = stage(lua)?.base_dir.clone();
    load_resolved(lua, resolve_path(&base, path)?, skeleton)
}

/// [`load_sequence`] of the file at `full`, its path resolved.
fn load_resolved(
    lua: &Lua,
    full: std::path::PathBuf,
    skeleton: Option<&Arc<Skeleton>>,
) -> mlua::Result<Arc<Sequence>> {
    stage(lua)?.loaded_files.push(full.clone());
    // BVH and glTF motions are bound to a body when loaded; .trk keeps DOF names. The
    // cache key names the body (none: a .trk, or the default adult).
    let bound_to_body = troupe_formats::Format::of(&full)
        .map_err(lua_err)?
        .binds_to_body();
    let key = (
        full.clone(),
        skeleton
            .filter(|_| bound_to_body)
            .map(|s| Arc::as_ptr(s) as usize),
    );
    if let Some(s) = stage(lua)?.sequences.get(&key) {
        return Ok(s.clone());
    }
    let skeleton = match (bound_to_body, skeleton) {
        (false, _) => None,
        (true, Some(s)) => Some(s.clone()),
        (true, None) => Some(Arc::new(
            troupe_body::template::default_skeleton("adult").map_err(lua_err)?,
        )),
    };
    let seq = troupe_formats::load_sequence(&full, skeleton.as_deref()).map_err(lua_err)?;
    let seq = Arc::new(seq);
    stage(lua)?.sequences.insert(key, seq.clone());
    Ok(seq)
}

/// The sequence of file `path` for the actor called `part` (`chosen`: named by the
/// script, else the actor's own name): of a `.trk` that records several actors (`troupe
/// run --record`), the sequence named so; of any other file, its one sequence, as
/// [`load_sequence`] loads it. A part chosen that the file does not hold is an error.
pub fn load_part(
    lua: &Lua,
    path: &str,
    skeleton: Option<&Arc<Skeleton>>,
    (part, chosen): (&str, bool),
) -> mlua::Result<Arc<Sequence>> {
    let base = stage(lua)?.base_dir.clone();
    let full = resolve_path(&base, path)?;
    if troupe_formats::Format::of(&full).map_err(lua_err)? != troupe_formats::Format::Trk {
        if chosen {
            return Err(lua_err(format!(
                "`part` chooses an actor's part of a .trk recording; `{path}` holds one motion"
            )));
        }
        return load_resolved(lua, full, skeleton);
    }
    let cached = stage(lua)?.recordings.get(&full).cloned();
    let set = match cached {
        Some(set) => set,
        None => {
            let read = troupe_formats::trk::read_trk_set(&full).map_err(lua_err)?;
            let set = Arc::new(read.into_iter().map(Arc::new).collect::<Vec<_>>());
            let mut st = stage(lua)?;
            st.loaded_files.push(full.clone());
            st.recordings.insert(full, set.clone());
            set
        }
    };
    if let [one] = set.as_slice() {
        if chosen && one.name != part {
            return Err(lua_err(format!(
                "`{path}` holds one sequence, `{}`, not `{part}`",
                one.name
            )));
        }
        return Ok(one.clone());
    }
    set.iter().find(|s| s.name == part).cloned().ok_or_else(|| {
        let names: Vec<&str> = set.iter().map(|s| s.name.as_str()).collect();
        lua_err(format!(
            "`{path}` records {} actors ({}), none of them `{part}`: choose one with `part = …`",
            set.len(),
            names.join(", ")
        ))
    })
}

/// The `interpolation` option of `troupe.sequence`, if given.
fn sequence_interpolation(t: &Table) -> mlua::Result<Option<Interpolation>> {
    opt_string(t, "sequence", "interpolation")?
        .map(|name| {
            Interpolation::from_name(&name).ok_or_else(|| {
                lua_err(format!(
                    "sequence: unknown interpolation `{name}` (expected cubic, hermite, linear or step)"
                ))
            })
        })
        .transpose()
}

/// Builds a sequence from `{ [dof] = {{t, v}, {t, v, slope}, …}, loop = bool, name = …,
/// interpolation = … }`; without a name, it is named after the place that made it
/// (`sequence@scene.lua:12`).
fn inline_sequence(lua: &Lua, t: &Table) -> mlua::Result<Sequence> {
    let name = match opt_string(t, "sequence", "name")? {
        Some(n) => n,
        None => lua
            .inspect_stack(1, |d| {
                let src = d
                    .source()
                    .short_src
                    .map(|s| s.to_string())
                    .unwrap_or_default();
                format!("sequence@{src}:{}", d.current_line().unwrap_or(0))
            })
            .unwrap_or_else(|| "sequence@?".into()),
    };
    let mut seq = Sequence::new(name);
    seq.looping = crate::args::opt_bool(t, "sequence", "loop")?.unwrap_or(false);
    let interpolation = sequence_interpolation(t)?.unwrap_or_default();
    let mut tracks = Vec::new();
    for pair in t.pairs::<String, Value>() {
        let (dof, keys) = pair?;
        match dof.as_str() {
            "loop" | "name" | "interpolation" => continue,
            _ => {}
        }
        let Value::Table(keys) = keys else {
            return Err(lua_err(format!(
                "sequence: track `{dof}` must be a list of {{t, value[, slope]}}"
            )));
        };
        let mut list = Vec::new();
        for (i, key) in keys.sequence_values::<Table>().enumerate() {
            let key = key.map_err(|_| {
                lua_err(format!(
                    "sequence: track `{dof}` key {} must be {{t, value[, slope]}}",
                    i + 1
                ))
            })?;
            let n = |k: i64| -> mlua::Result<Option<f64>> {
                match key.get::<Value>(k)? {
                    Value::Nil => Ok(None),
                    Value::Integer(i) => Ok(Some(i as f64)),
                    Value::Number(x) => Ok(Some(x)),
                    other => Err(lua_err(format!(
                        "sequence: track `{dof}` key {}: expected numbers, got {}",
                        i + 1,
                        other.type_name()
                    ))),
                }
            };
            let (Some(time), Some(value)) = (n(1)?, n(2)?) else {
                return Err(lua_err(format!(
                    "sequence: track `{dof}` key {} needs a time and a value",
                    i + 1
                )));
            };
            list.push(Key {
                time,
                value,
                slope: n(3)?,
            });
        }
        let track = Track::new(dof, list).map_err(|e| lua_err(format!("sequence: {e}")))?;
        tracks.push(track.with_interpolation(interpolation));
    }
    // Table iteration order is not stable across runs: sort for determinism.
    tracks.sort_by(|a, b| a.dof().cmp(b.dof()));
    for track in tracks {
        seq.add_track(track).map_err(lua_err)?;
    }
    Ok(seq)
}

fn object_shape(t: &Table) -> mlua::Result<Shape> {
    let shape = opt_string(t, "object", "shape")?.unwrap_or_else(|| "box".into());
    let num = |k: &str| -> mlua::Result<f64> {
        opt_number(t, "object", k)?.ok_or_else(|| lua_err(format!("object: a {shape} needs `{k}`")))
    };
    let shape = match shape.as_str() {
        "box" => Shape::Box {
            half_extents: vec3(&t.get::<Value>("size")?, "object: size")? / 2.0,
        },
        "sphere" => Shape::Sphere {
            radius: num("radius")?,
        },
        "cylinder" => Shape::Cylinder {
            radius: num("radius")?,
            height: num("height")?,
        },
        "frustum" => Shape::Frustum {
            bottom_radius: num("bottom_radius")?,
            top_radius: num("top_radius")?,
            height: num("height")?,
        },
        "ellipsoid" => Shape::Ellipsoid {
            radii: vec3(&t.get::<Value>("radii")?, "object: radii")?,
        },
        other => {
            return Err(lua_err(format!(
                "object: unknown shape `{other}` (known: box, sphere, cylinder, frustum, ellipsoid)"
            )))
        }
    };
    shape
        .validate()
        .map_err(|e| lua_err(format!("object: {e}")))?;
    Ok(shape)
}

/// Reads the character file of an actor's `look` option (a `.glb`, `.gltf` or `.vrm`
/// beside the scene or as given) with its `bones` map (`{ hips = "NodeName", … }`).
fn load_character(lua: &Lua, path: &str, opts: &Table) -> mlua::Result<troupe_body::Character> {
    let base = stage(lua)?.base_dir.clone();
    // The message alone: mlua's `runtime error:` prefix is no part of it.
    let full = resolve_path(&base, path)
        .map_err(|e| lua_err(format!("actor: look: {}", crate::args::error_text(&e))))?;
    stage(lua)?.loaded_files.push(full.clone());
    let mut bones = Vec::new();
    match opts.get::<Value>("bones")? {
        Value::Nil => {}
        Value::Table(map) => {
            for pair in map.pairs::<Value, Value>() {
                let (key, node) = pair?;
                match (key, node) {
                    (Value::String(k), Value::String(n)) => {
                        bones.push((k.to_str()?.to_string(), n.to_str()?.to_string()))
                    }
                    (k, n) => {
                        return Err(lua_err(format!(
                            "actor: bones: expected `bone = \"NodeName\"` pairs of strings, found a {} = {}",
                            k.type_name(),
                            n.type_name()
                        )))
                    }
                }
            }
        }
        other => {
            return Err(lua_err(format!(
                "actor: bones: expected a table `{{ hips = \"NodeName\", … }}`, found a {}",
                other.type_name()
            )))
        }
    }
    // Lua tables have no order: sort, so that the same map gives the same character.
    bones.sort();
    troupe_formats::character::read_character(&full, &bones)
        .map_err(|e| lua_err(format!("actor: look: {e}")))
}

/// The actor that `troupe.actor`'s options `name`, `template`, `height`, `mass`, `at` and
/// `facing` describe (`troupe.performer` reads the same options).
pub fn actor_desc(t: &Table) -> mlua::Result<ActorDesc> {
    let name =
        opt_string(t, "actor", "name")?.ok_or_else(|| lua_err("actor: `name` is required"))?;
    let at: Value = t.get("at")?;
    Ok(ActorDesc {
        name,
        template: opt_string(t, "actor", "template")?.unwrap_or_else(|| "adult".into()),
        height: opt_number(t, "actor", "height")?,
        mass: opt_number(t, "actor", "mass")?,
        at: if at.is_nil() {
            DVec3::ZERO
        } else {
            vec3(&at, "actor: at")?
        },
        facing_degrees: opt_number(t, "actor", "facing")?.unwrap_or(0.0),
    })
}

/// Installs the `troupe` table.
pub(crate) fn install(lua: &Lua) -> mlua::Result<()> {
    let troupe = lua.create_table()?;
    troupe.set(
        "actor",
        lua.create_function(|lua, t: Table| {
            check_keys(
                &t,
                "actor",
                &[
                    "name", "template", "height", "mass", "at", "facing", "look", "bones",
                ],
            )?;
            let desc = actor_desc(&t)?;
            let look = match opt_string(&t, "actor", "look")? {
                Some(path) => Some(load_character(lua, &path, &t)?),
                None if !t.get::<Value>("bones")?.is_nil() => {
                    return Err(lua_err(
                        "actor: `bones` maps the bones of a `look` file; give `look` too",
                    ))
                }
                None => None,
            };
            let index = stage(lua)?
                .scene
                .add_dressed_actor(&desc, look.as_ref())
                .map_err(|e| lua_err(format!("actor: {e}")))?;
            Ok(ActorRef(index))
        })?,
    )?;
    troupe.set(
        "object",
        lua.create_function(|lua, t: Table| {
            check_keys(
                &t,
                "object",
                &[
                    "name",
                    "shape",
                    "size",
                    "radius",
                    "height",
                    "bottom_radius",
                    "top_radius",
                    "radii",
                    "at",
                    "mass",
                    "rotation",
                    "obstacle",
                ],
            )?;
            let name = opt_string(&t, "object", "name")?
                .ok_or_else(|| lua_err("object: `name` is required"))?;
            let shape = object_shape(&t)?;
            let at: Value = t.get("at")?;
            let rot: Value = t.get("rotation")?;
            let rotation = if rot.is_nil() {
                DQuat::IDENTITY
            } else {
                euler_degrees(&rot, "object: rotation (degrees about x, y, z)")?
            };
            let object = Object {
                name,
                shape,
                position: if at.is_nil() {
                    DVec3::ZERO
                } else {
                    vec3(&at, "object: at")?
                },
                rotation,
                mass: opt_number(&t, "object", "mass")?.unwrap_or(1.0),
            };
            let obstacle = opt_bool(&t, "object", "obstacle")?;
            let mut stage = stage(lua)?;
            let index = stage
                .scene
                .add_object(object)
                .map_err(|e| lua_err(format!("object: {e}")))?;
            stage
                .scene
                .set_obstacle(index, obstacle)
                .map_err(|e| lua_err(format!("object: {e}")))?;
            Ok(ObjectRef(index))
        })?,
    )?;
    troupe.set(
        "time",
        lua.create_function(|lua, ()| Ok(stage(lua)?.scene.time()))?,
    )?;
    troupe.set(
        "tick",
        lua.create_function(|lua, ()| Ok(stage(lua)?.scene.tick()))?,
    )?;
    troupe.set(
        "seed",
        lua.create_function(|lua, ()| Ok(stage(lua)?.scene.config().seed))?,
    )?;
    troupe.set(
        "rate",
        lua.create_function(|lua, ()| Ok(stage(lua)?.scene.config().rate))?,
    )?;
    troupe.set(
        "sequence",
        lua.create_function(|lua, (v, options): (Value, Option<Table>)| match v {
            Value::String(s) => {
                let loaded = load_sequence(lua, &s.to_str()?, None)
                    .map_err(|e| lua_err(format!("sequence: {}", crate::args::error_text(&e))))?;
                let interpolation = match &options {
                    Some(o) => {
                        check_keys(o, "sequence", &["interpolation"])?;
                        sequence_interpolation(o)?
                    }
                    None => None,
                };
                Ok(SequenceRef(match interpolation {
                    // The loaded file stays cached as written; this copy interpolates anew.
                    Some(i) => {
                        let mut seq = (*loaded).clone();
                        seq.set_interpolation(i);
                        Arc::new(seq)
                    }
                    None => loaded,
                }))
            }
            Value::Table(t) => Ok(SequenceRef(Arc::new(inline_sequence(lua, &t)?))),
            other => Err(lua_err(format!(
                "sequence: expects a file path or a table of tracks, got {}",
                other.type_name()
            ))),
        })?,
    )?;
    troupe.set(
        "actors",
        lua.create_function(|lua, ()| {
            let n = stage(lua)?.scene.actors().len();
            lua.create_sequence_from((0..n).map(ActorRef))
        })?,
    )?;
    troupe.set(
        "get_actor",
        lua.create_function(|lua, name: Value| {
            let Value::String(name) = &name else {
                return Err(bad_arg("get_actor", "the name", "a string", &name));
            };
            // Finding by name answers nil for a name the scene lacks (the one exception
            // to the unknown-names rule of docs/lua-api.md).
            let i = stage(lua)?.scene.actor_index(&name.to_str()?).ok();
            Ok(i.map(ActorRef))
        })?,
    )?;
    troupe.set(
        "get_object",
        lua.create_function(|lua, name: Value| {
            let Value::String(name) = &name else {
                return Err(bad_arg("get_object", "the name", "a string", &name));
            };
            let i = stage(lua)?.scene.object_index(&name.to_str()?).ok();
            Ok(i.map(ObjectRef))
        })?,
    )?;
    crate::messages::install(lua, &troupe)?;
    crate::space::install(lua, &troupe)?;
    lua.globals().set("troupe", troupe)?;
    Ok(())
}

/// Turns a runtime error into a Lua error (for builders in other crates).
pub fn to_lua_error(e: Error) -> mlua::Error {
    lua_err(e)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_missing_file_lists_each_place_it_looked_once() {
        let here = std::env::current_dir().unwrap();
        let message = |base: &Path| match resolve_path(base, "no_such_clip.bvh") {
            Err(mlua::Error::RuntimeError(m)) => m,
            other => panic!("{other:?}"),
        };
        // The scene's folder is where troupe runs: one place, named once.
        let once = message(&here);
        let path = here.join("no_such_clip.bvh").display().to_string();
        assert_eq!(
            once,
            format!("file `no_such_clip.bvh` not found; looked for {path}, beside the scene")
        );
        // Elsewhere: both.
        let elsewhere = here.join("no_such_folder");
        let both = message(&elsewhere);
        let beside = elsewhere.join("no_such_clip.bvh").display().to_string();
        assert_eq!(
            both,
            format!("file `no_such_clip.bvh` not found; looked for {path} and, beside the scene, {beside}")
        );
    }
}
