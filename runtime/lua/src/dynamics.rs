//! `actor:inverse_dynamics{…}` and `actor:forward_dynamics{…}`: plain functions (not
//! actions) over tables keyed by DOF name.

use crate::args::{check_keys, err, number, vec3};
use crate::handles::ActorRef;
use mlua::{Lua, Table, UserDataMethods, Value};
use troupe_body::dynamics::{check_state, Dynamics, ExternalForces};

/// Adds the dynamics methods to actor handles.
pub(crate) fn add_actor_methods<M: UserDataMethods<ActorRef>>(methods: &mut M) {
    methods.add_method("inverse_dynamics", |lua, this, t: Table| {
        call(lua, this.0, &t, true)
    });
    methods.add_method("forward_dynamics", |lua, this, t: Table| {
        call(lua, this.0, &t, false)
    });
}

/// Reads `{dof_name = number, …}` into `out` (missing entries stay as they are).
fn read(
    t: &Table,
    key: &str,
    method: &str,
    skeleton: &troupe_body::Skeleton,
    out: &mut [f64],
) -> mlua::Result<bool> {
    let values = match t.get::<Value>(key)? {
        Value::Nil => return Ok(false),
        Value::Table(v) => v,
        other => {
            return Err(err(
                method,
                format!(
                    "`{key}` must be a table {{dof_name = number, …}}, got {}",
                    other.type_name()
                ),
            ))
        }
    };
    for pair in values.pairs::<Value, Value>() {
        let (k, v) = pair?;
        let Value::String(name) = k else {
            return Err(err(method, format!("`{key}` keys must be DOF names")));
        };
        let name = name.to_str()?.to_string();
        let d = skeleton
            .dof(&name)
            .map_err(|e| err(method, format!("{key}: {e}")))?;
        out[d] = number(&v).ok_or_else(|| {
            err(
                method,
                format!("{key}.{name} must be a number, got {}", v.type_name()),
            )
        })?;
    }
    Ok(true)
}

fn call(lua: &Lua, actor: usize, t: &Table, inverse: bool) -> mlua::Result<Table> {
    let method = if inverse {
        "inverse_dynamics"
    } else {
        "forward_dynamics"
    };
    let input = if inverse { "qdd" } else { "tau" };
    check_keys(t, method, &["q", "qd", input, "fixed_root", "gravity"])?;
    let (skeleton, posture) = {
        let stage = crate::stage::stage(lua)?;
        (
            stage.scene.actors()[actor].skeleton.clone(),
            stage.scene.states()[actor].q.clone(),
        )
    };
    let n = skeleton.dof_count();
    let mut q = vec![0.0; n];
    if !read(t, "q", method, &skeleton, &mut q)? {
        q = posture; // no `q`: the actor's current posture
    }
    let mut qd = vec![0.0; n];
    read(t, "qd", method, &skeleton, &mut qd)?;
    let mut x = vec![0.0; n];
    read(t, input, method, &skeleton, &mut x)?;
    let fixed_root = match t.get::<Value>("fixed_root")? {
        Value::Nil => false,
        Value::Boolean(b) => b,
        other => {
            return Err(err(
                method,
                format!("fixed_root must be a boolean, got {}", other.type_name()),
            ))
        }
    };
    for (what, v) in [("q", &q), ("qd", &qd), (input, &x)] {
        check_state(&skeleton, what, v).map_err(|e| err(method, e))?;
    }
    let mut dynamics = Dynamics::new(&skeleton).map_err(|e| err(method, e))?;
    let g: Value = t.get("gravity")?;
    if !g.is_nil() {
        dynamics.set_gravity(vec3(&g, &format!("{method}: gravity"))?);
    }
    let ext = ExternalForces::new(&skeleton);
    let mut out = vec![0.0; n];
    if inverse {
        dynamics.inverse_dynamics(&q, &qd, &x, &ext, fixed_root, &mut out);
    } else {
        dynamics
            .forward_dynamics(&q, &qd, &x, &ext, fixed_root, &mut out)
            .map_err(|e| err(method, e))?;
    }
    let result = lua.create_table_with_capacity(0, n)?;
    for (d, v) in skeleton.dofs().iter().zip(out) {
        result.raw_set(d.name.as_str(), v)?;
    }
    Ok(result)
}
