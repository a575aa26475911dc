//! Error values that are not strings, in reports.
//!
//! A script may raise any value: `error({ code = "blocked", msg = "the door is shut" })`.
//! When such an error is not caught, mlua turns it into text with Lua's `tostring`, which
//! makes of a table without `__tostring` only `table: 0x55…`, and Lua adds its place to a
//! string only: the author learnt nothing. The value itself is gone by then (mlua's
//! resume drops the dead coroutine's stack). So troupe's `error` and `assert`, C
//! functions written here that do what Lua's do (a C function's frame is Lua's own: the
//! levels, tail calls and tracebacks read as with Lua's), keep the last table they raised
//! and the place they raised it, in the registry. Where a failure's error is turned into
//! its message ([`explain`], from the sandbox's guarded calls and [`crate::args::caught_text`]),
//! a message that holds that table's `table: 0x…` gets the place and a short rendering
//! of the table's fields in its stead: `scene.lua:12: {code = "blocked", msg = "the door
//! is shut"}` ([`render`]). A table with `__tostring` already reads as its author meant,
//! and a number or a boolean as its value; those are left as Lua wrote them.

use mlua::{ffi, Lua, Table, Value};
use std::os::raw::c_int;

/// The registry slot of the last table raised with `error` or `assert` (`false` when
/// none, or once forgotten).
const RAISED: &str = "troupe.raised";
/// The registry slot of the place that table was raised (`file:line: `, or empty).
const RAISED_AT: &str = "troupe.raised_at";

/// How deep nested tables are rendered; deeper ones show as `{…}`.
const MAX_DEPTH: usize = 2;
/// How many fields of one table are rendered; more show as `…`.
const MAX_FIELDS: usize = 12;
/// How many keys (besides the list part) of one table are read, to sort them.
const MAX_KEYS: usize = 10_000;
/// How many characters of a string value are kept.
const MAX_STRING: usize = 80;
/// How long the whole rendering may grow.
const MAX_LEN: usize = 300;

/// Puts troupe's `error` and `assert` in place of Lua's (before the prelude, which keeps
/// `error` in a local).
pub(crate) fn install(lua: &Lua) -> mlua::Result<()> {
    // Made now, the slots take a table later without growing the registry.
    lua.set_named_registry_value(RAISED, false)?;
    lua.set_named_registry_value(RAISED_AT, "")?;
    let globals = lua.globals();
    // SAFETY: both are C functions of the Lua API's protocol (they read their arguments
    // and raise with lua_error, as Lua's own do; no Rust value needs dropping when
    // lua_error unwinds them).
    unsafe {
        globals.raw_set("error", lua.create_c_function(lua_error_fn)?)?;
        globals.raw_set("assert", lua.create_c_function(lua_assert_fn)?)?;
    }
    Ok(())
}

/// Forgets the table last raised (so that it can be collected).
pub(crate) fn forget(lua: &Lua) {
    if !matches!(
        lua.named_registry_value::<Value>(RAISED),
        Ok(Value::Boolean(false))
    ) {
        let _ = lua.set_named_registry_value(RAISED, false);
    }
}

/// Lua's `error(value [, level])` (lbaselib.c's `luaB_error`), which also notes a table
/// value and where it was raised.
unsafe extern "C-unwind" fn lua_error_fn(state: *mut ffi::lua_State) -> c_int {
    let level = ffi::luaL_optinteger(state, 2, 1);
    ffi::lua_settop(state, 1);
    raise(state, level)
}

/// Lua's `assert(v [, message, …])` (lbaselib.c's `luaB_assert`), whose error is raised as
/// troupe's `error` raises it.
unsafe extern "C-unwind" fn lua_assert_fn(state: *mut ffi::lua_State) -> c_int {
    if ffi::lua_toboolean(state, 1) != 0 {
        return ffi::lua_gettop(state);
    }
    ffi::luaL_checkany(state, 1);
    ffi::lua_remove(state, 1);
    ffi::lua_pushstring(state, c"assertion failed!".as_ptr());
    ffi::lua_settop(state, 1);
    raise(state, 1)
}

/// Raises the value at index 1 (the only one on the stack) as Lua's `error` does: a
/// string gets the place `level` names in front. A table is noted first, with that place.
unsafe fn raise(state: *mut ffi::lua_State, level: ffi::lua_Integer) -> ! {
    let level = level.clamp(0, c_int::MAX as ffi::lua_Integer) as c_int;
    match ffi::lua_type(state, 1) {
        ffi::LUA_TSTRING if level > 0 => {
            ffi::luaL_where(state, level);
            ffi::lua_pushvalue(state, 1);
            ffi::lua_concat(state, 2);
        }
        ffi::LUA_TTABLE => {
            ffi::lua_pushstring(state, c"troupe.raised".as_ptr());
            ffi::lua_rawget(state, ffi::LUA_REGISTRYINDEX);
            let again = ffi::lua_rawequal(state, 1, -1) != 0;
            ffi::lua_pop(state, 1);
            // A table raised again without a place (the prelude's coroutine.wrap passing
            // on the error of the coroutine) keeps the place it was first raised at.
            if !(again && level == 0) {
                if level > 0 {
                    ffi::luaL_where(state, level);
                } else {
                    ffi::lua_pushstring(state, c"".as_ptr());
                }
                ffi::lua_setfield(state, ffi::LUA_REGISTRYINDEX, c"troupe.raised_at".as_ptr());
                ffi::lua_pushvalue(state, 1);
                ffi::lua_setfield(state, ffi::LUA_REGISTRYINDEX, c"troupe.raised".as_ptr());
            }
        }
        _ => {}
    }
    // The top: the string with its place, or the value as it was given.
    ffi::lua_error(state)
}

/// `message` (the text of a failure) with the `table: 0x…` of the table last raised,
/// when it holds it, replaced by where that table was raised and its fields:
/// `scene.lua:12: {code = "blocked", msg = "the door is shut"}`.
pub(crate) fn explain(lua: &Lua, message: String) -> String {
    let Ok(Value::Table(table)) = lua.named_registry_value::<Value>(RAISED) else {
        return message;
    };
    if has_tostring(&table) {
        return message;
    }
    // Lua's `tostring` of a table without `__tostring`: what mlua wrote.
    let Ok(lua_text) = Value::Table(table.clone()).to_string() else {
        return message;
    };
    // The error's own text: the message, or what follows a prefix (`in an event
    // handler: `, `walk: `velocity` failed at t = 0.00 s: `), up to the traceback.
    let Some(at) = message.match_indices(&lua_text).map(|(i, _)| i).find(|&i| {
        let before = &message[..i];
        let after = &message[i + lua_text.len()..];
        (before.is_empty() || before.ends_with(": ") || before.ends_with('\n'))
            && (after.is_empty() || after.starts_with('\n'))
    }) else {
        return message;
    };
    let end = at + lua_text.len();
    let place = lua
        .named_registry_value::<String>(RAISED_AT)
        .unwrap_or_default();
    format!(
        "{}{place}{}{}",
        &message[..at],
        render(&Value::Table(table)),
        &message[end..]
    )
}

/// A short, deterministic rendering of a Lua value for a message: a table as
/// `{1, 2, code = "blocked", [true] = 3}` (list items first, then the other keys sorted,
/// nested tables down to a depth, bounded in fields and length); a table with
/// `__tostring` or a userdata as Lua's `tostring` says; anything else as its value.
pub(crate) fn render(value: &Value) -> String {
    let mut out = String::new();
    render_into(value, 0, &mut out);
    if out.chars().count() > MAX_LEN {
        out = out.chars().take(MAX_LEN - 1).collect();
        out.push('…');
    }
    out
}

fn render_into(value: &Value, depth: usize, out: &mut String) {
    match value {
        Value::String(s) => {
            let s = s.to_string_lossy();
            out.push('"');
            for (i, c) in s.chars().enumerate() {
                if i == MAX_STRING {
                    out.push('…');
                    break;
                }
                match c {
                    '"' => out.push_str("\\\""),
                    '\\' => out.push_str("\\\\"),
                    '\n' => out.push_str("\\n"),
                    c => out.push(c),
                }
            }
            out.push('"');
        }
        Value::Number(x) => out.push_str(&number(*x)),
        Value::Table(t) if !has_tostring(t) => render_table(t, depth, out),
        Value::Function(_) => out.push_str("function"),
        Value::Thread(_) => out.push_str("thread"),
        other => out.push_str(
            &other
                .to_string()
                .unwrap_or_else(|_| other.type_name().to_string()),
        ),
    }
}

/// Whether `t`'s metatable has a `__tostring` field (read raw).
fn has_tostring(t: &Table) -> bool {
    t.metatable()
        .is_some_and(|m| !matches!(m.raw_get::<Value>("__tostring"), Ok(Value::Nil) | Err(_)))
}

fn render_table(t: &Table, depth: usize, out: &mut String) {
    if depth >= MAX_DEPTH {
        out.push_str("{…}");
        return;
    }
    // The list part, 1 to the border; then the other keys, sorted (Lua's walk order
    // varies between runs), a huge table's first MAX_KEYS only.
    let len = t.raw_len() as i64;
    let list = (1..=len.min(MAX_FIELDS as i64))
        .map(|i| (None, t.raw_get::<Value>(i).unwrap_or(Value::Nil)));
    let mut named: Vec<(String, Value)> = Vec::new();
    let mut more = len > MAX_FIELDS as i64;
    for pair in t.pairs::<Value, Value>() {
        let Ok((k, v)) = pair else { continue };
        if matches!(k, Value::Integer(i) if (1..=len).contains(&i)) {
            continue;
        }
        if named.len() == MAX_KEYS {
            more = true;
            break;
        }
        named.push((key(&k), v));
    }
    named.sort_by(|a, b| a.0.cmp(&b.0));
    let items = list.chain(named.into_iter().map(|(k, v)| (Some(k), v)));
    out.push('{');
    for (count, (k, v)) in items.enumerate() {
        if count > 0 {
            out.push_str(", ");
        }
        if count == MAX_FIELDS || out.len() > MAX_LEN {
            more = true;
            break;
        }
        if let Some(k) = k {
            out.push_str(&k);
            out.push_str(" = ");
        }
        render_into(&v, depth + 1, out);
    }
    if more {
        if !out.ends_with(", ") && !out.ends_with('{') {
            out.push_str(", ");
        }
        out.push('…');
    }
    out.push('}');
}

/// A table key as a Lua constructor writes it: `name` for an identifier, else `[key]`.
fn key(k: &Value) -> String {
    if let Value::String(s) = k {
        let s = s.to_string_lossy();
        let mut chars = s.chars();
        if chars
            .next()
            .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        {
            return s.to_string();
        }
    }
    let mut inner = String::new();
    render_into(k, MAX_DEPTH, &mut inner);
    format!("[{inner}]")
}

/// A float as Lua 5.4 prints it, near enough for a message: `1.0`, `0.5`, `1e+300`.
fn number(x: f64) -> String {
    if x.is_nan() {
        return if x.is_sign_negative() { "-nan" } else { "nan" }.into();
    }
    if x.is_infinite() {
        return if x > 0.0 { "inf" } else { "-inf" }.into();
    }
    if x.fract() == 0.0 && x.abs() < 1e15 {
        return format!("{x:.1}");
    }
    if x.abs() >= 1e15 || x.abs() < 1e-4 {
        return format!("{x:e}");
    }
    format!("{x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rendered(lua: &Lua, code: &str) -> String {
        render(&lua.load(code).eval::<Value>().unwrap())
    }

    #[test]
    fn a_table_renders_its_list_then_its_sorted_keys() {
        let lua = Lua::new();
        assert_eq!(
            rendered(
                &lua,
                r#"return { msg = "the door is shut", code = "blocked" }"#
            ),
            r#"{code = "blocked", msg = "the door is shut"}"#
        );
        assert_eq!(
            rendered(
                &lua,
                r#"return { "a", 2, 0.5, x = true, [10] = 1, ["a b"] = 3.0 }"#
            ),
            r#"{"a", 2, 0.5, ["a b"] = 3.0, [10] = 1, x = true}"#
        );
        assert_eq!(rendered(&lua, "return {}"), "{}");
    }

    #[test]
    fn a_rendering_is_bounded_in_depth_fields_and_length() {
        let lua = Lua::new();
        assert_eq!(
            rendered(&lua, "return { a = { b = { c = 1 } } }"),
            "{a = {b = {…}}}"
        );
        let cyclic = rendered(&lua, "local t = {}; t.self = t; return t");
        assert_eq!(cyclic, "{self = {self = {…}}}");
        let many = rendered(
            &lua,
            "local t = {}; for i = 1, 100 do t[i] = i end; return t",
        );
        assert_eq!(many, "{1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, …}");
        let long = rendered(&lua, "return { s = string.rep('x', 1000) }");
        assert!(long.chars().count() < 100, "{long}");
        let wide = rendered(
            &lua,
            "local t = {}; for i = 1, 12 do t['k' .. i] = string.rep('y', 70) end; return t",
        );
        assert!(wide.chars().count() <= MAX_LEN, "{wide}");
        assert!(wide.ends_with('…'), "{wide}");
    }

    #[test]
    fn a_table_with_tostring_reads_as_its_author_meant() {
        let lua = Lua::new();
        assert_eq!(
            rendered(
                &lua,
                "return { inner = setmetatable({}, { __tostring = function() return 'door' end }) }"
            ),
            "{inner = door}"
        );
    }
}
