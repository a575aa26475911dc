//! What the device functions read from their option tables beyond `troupe_lua::args`: the
//! known-keys check in their own wording ("unknown option", which scripts and docs quote),
//! and file paths relative to the scene.

use mlua::{Lua, Table, Value};
use std::path::{Path, PathBuf};
use troupe_lua::args;

/// Refuses any key of `t` not in `known`: "`{what}: unknown option `k` (known: …)`".
pub fn check_keys(t: &Table, what: &str, known: &[&str]) -> mlua::Result<()> {
    for pair in t.clone().pairs::<Value, Value>() {
        let (k, _) = pair?;
        let name = k.to_string()?;
        if !known.contains(&name.as_str()) {
            return Err(args::err(
                what,
                format!("unknown option `{name}` (known: {})", known.join(", ")),
            ));
        }
    }
    Ok(())
}

/// A path from a script: absolute as given, else relative to the scene's folder (the
/// working folder when the scene has none).
pub fn resolve(lua: &Lua, p: &str) -> PathBuf {
    let path = Path::new(p);
    if path.is_absolute() {
        path.to_path_buf()
    } else {
        troupe_lua::scene_dir(lua)
            .unwrap_or_else(|| PathBuf::from("."))
            .join(path)
    }
}
