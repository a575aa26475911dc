//! `require(name)`: a module from the scene's folder, else from troupe's standard library,
//! which is embedded in the binary (so it is found from any working folder).

use crate::args::lua_err;
use crate::stage::Stage;
use mlua::{Lua, Table, Value};
use std::path::Path;

/// The standard library: module name and source, from `scripts/lib/`.
pub const STANDARD_LIBRARY: &[(&str, &str)] = &[(
    "gestures",
    include_str!("../../../scripts/lib/gestures.lua"),
)];

/// `require(name)`: loads `name.lua` (dots are folders) from the scene's folder, else the
/// standard library module `name`, once; later calls return the first result.
pub(crate) fn require(lua: &Lua, name: Value) -> mlua::Result<Value> {
    let name = match &name {
        Value::String(s) => s.to_str()?.to_string(),
        other => {
            return Err(crate::args::bad_arg(
                "require",
                "the module name",
                "a string",
                other,
            ))
        }
    };
    if name.is_empty()
        || !name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '.' || c == '-')
    {
        return Err(lua_err(format!(
            "require: invalid module name `{name}` (letters, digits, `_`, `-`; `.` between folders)"
        )));
    }
    let modules: Table = lua.named_registry_value("troupe.modules")?;
    if let Some(v) = modules.get::<Option<Value>>(name.as_str())? {
        return Ok(v);
    }
    let base = lua
        .app_data_ref::<Stage>()
        .map(|st| st.base_dir.clone())
        .unwrap_or_default();
    let local = base.join(format!("{}.lua", name.replace('.', "/")));
    let (code, chunk) = if local.is_file() {
        let code = std::fs::read_to_string(&local)
            .map_err(|e| lua_err(format!("require: {}: {e}", local.display())))?;
        if let Some(mut st) = lua.app_data_mut::<Stage>() {
            st.loaded_files.push(local.clone());
        }
        (code, format!("@{}", local.display()))
    } else if let Some((_, code)) = STANDARD_LIBRARY.iter().find(|(n, _)| *n == name) {
        (code.to_string(), format!("@[troupe]/{name}.lua"))
    } else {
        return Err(lua_err(format!(
            "require: module `{name}` not found; looked for {} and in the standard library ({})",
            shown(&local),
            STANDARD_LIBRARY
                .iter()
                .map(|(n, _)| *n)
                .collect::<Vec<_>>()
                .join(", ")
        )));
    };
    let value: Value = lua.load(code).set_name(chunk).call(())?;
    let value = if value.is_nil() {
        Value::Boolean(true)
    } else {
        value
    };
    modules.set(name.as_str(), value.clone())?;
    Ok(value)
}

/// A path as a user can find it: absolute when it can be made so.
pub(crate) fn shown(p: &Path) -> String {
    std::path::absolute(p)
        .unwrap_or_else(|_| p.to_path_buf())
        .display()
        .to_string()
}
