//! `troupe.publish(key, value)` and `troupe.subscribe(expr, function(value, key) … end)`:
//! messages between scenes and tools, Lua values ↔ JSON. The scene's [`Mailbox`] holds
//! them; the director calls the subscribers at the start of the next tick's script
//! phase, in the mailbox's order, each subscriber in the order it subscribed.
//!
//! [`Mailbox`]: troupe_scene::Mailbox

use crate::args::{bad_arg, lua_err};
use crate::stage::stage;
use mlua::{Lua, LuaSerdeExt, Table, Value};

/// Adds `publish` and `subscribe` to the `troupe` table.
pub(crate) fn install(lua: &Lua, troupe: &Table) -> mlua::Result<()> {
    troupe.set(
        "publish",
        lua.create_function(|lua, (key, value): (Value, Value)| {
            let key = string_arg("publish", "argument 1 (the key)", key)?;
            let json = to_json(lua, &value).map_err(|e| lua_err(format!("publish {key}: {e}")))?;
            stage(lua)?
                .scene
                .mailbox_mut()
                .publish(&key, json)
                .map_err(|e| lua_err(format!("publish: {e}")))
        })?,
    )?;
    troupe.set(
        "subscribe",
        lua.create_function(|lua, (expr, f): (Value, Value)| {
            let expr = string_arg("subscribe", "argument 1 (the key expression)", expr)?;
            let Value::Function(f) = f else {
                return Err(bad_arg(
                    "subscribe",
                    "argument 2",
                    "a function(value, key)",
                    &f,
                ));
            };
            let mut st = stage(lua)?;
            st.scene
                .mailbox_mut()
                .subscribe(&expr)
                .map_err(|e| lua_err(format!("subscribe: {e}")))?;
            st.subscriptions.push((expr, f));
            Ok(())
        })?,
    )?;
    Ok(())
}

/// Argument `what` of `method`, which must be a string.
fn string_arg(method: &str, what: &str, v: Value) -> mlua::Result<String> {
    match v {
        Value::String(s) => Ok(s.to_str()?.to_string()),
        other => Err(bad_arg(method, what, "a string", &other)),
    }
}

/// How deeply tables may nest in a message: serde_json, which reads the messages here
/// and in other troupe processes, refuses JSON nested deeper than 128.
const DEEPEST: usize = 100;

/// How many values (tables and what they hold) a message may have: a table held in two
/// places is written out twice, so a few tables that each hold the next twice would make
/// a message of 2⁶⁴ parts.
const MOST_PARTS: usize = 1_000_000;

/// A Lua value as JSON: tables with keys exactly 1…n are arrays, tables with string keys
/// objects (an empty table an empty object, unless it came from a JSON array, as a list a
/// subscriber received: that stays an array, its holes null); a table with both, with
/// integer keys that are not 1…n, or with other keys, is refused, as are numbers that are not finite (JSON
/// has none), functions, userdata, a table that holds itself, nesting deeper than
/// [`DEEPEST`] and more than [`MOST_PARTS`] parts. Errors say where (`value.y[2]`).
fn to_json(lua: &Lua, value: &Value) -> Result<serde_json::Value, String> {
    let mut walk = JsonWalk {
        path: Vec::new(),
        open: Vec::new(),
        parts: 0,
        array_mark: lua.array_metatable(),
    };
    walk.value(value)
}

/// One part of a path into a published value.
enum Step {
    Index(i64),
    Field(String),
}

/// The state of [`to_json`]'s walk: where it is, the tables it is inside, the parts seen,
/// and mlua's mark of a table that came from a JSON array.
struct JsonWalk {
    path: Vec<Step>,
    open: Vec<*const std::ffi::c_void>,
    parts: usize,
    array_mark: Table,
}

/// Where a key sorts: integers by value first, then strings, then anything else.
fn order(k: &Value) -> f64 {
    match k {
        Value::Integer(i) => *i as f64,
        Value::Number(x) => *x,
        Value::String(_) => f64::MAX,
        _ => f64::INFINITY,
    }
}

/// A key's text, to sort strings (and the rest) among themselves.
fn text(k: &Value) -> Vec<u8> {
    match k {
        Value::String(s) => s.as_bytes().to_vec(),
        other => other.type_name().as_bytes().to_vec(),
    }
}

impl JsonWalk {
    /// Where the walk is, as a script would write it: `value.y[2]`.
    fn here(&self) -> String {
        let mut at = String::from("value");
        let n = self.path.len();
        for (k, step) in self.path.iter().enumerate() {
            // A deep path keeps its first and last few steps.
            if n > 12 && (4..n - 4).contains(&k) {
                if k == 4 {
                    at.push_str(&format!("…({} more)…", n - 8));
                }
                continue;
            }
            match step {
                Step::Index(i) => at.push_str(&format!("[{i}]")),
                Step::Field(f) => at.push_str(&format!(".{f}")),
            }
        }
        at
    }

    fn value(&mut self, value: &Value) -> Result<serde_json::Value, String> {
        self.parts += 1;
        if self.parts > MOST_PARTS {
            return Err(format!("the value has more than {MOST_PARTS} parts"));
        }
        use serde_json::Value as Json;
        Ok(match value {
            Value::Nil => Json::Null,
            Value::Boolean(b) => Json::Bool(*b),
            Value::Integer(i) => Json::from(*i),
            Value::Number(n) => serde_json::Number::from_f64(*n)
                .map(Json::Number)
                .ok_or_else(|| format!("{} is not a finite number", self.here()))?,
            Value::String(s) => Json::String(
                s.to_str()
                    .map_err(|_| format!("{} is not UTF-8 text", self.here()))?
                    .to_string(),
            ),
            Value::Table(t) => self.table(t)?,
            other => {
                return Err(format!(
                    "{} is a {}, which JSON cannot carry",
                    self.here(),
                    other.type_name()
                ))
            }
        })
    }

    /// A JSON array of `len` items from `pairs`, whose keys are integers 1…`len` (the
    /// missing ones null).
    fn list(&mut self, pairs: &[(Value, Value)], len: i64) -> Result<serde_json::Value, String> {
        let mut items = vec![serde_json::Value::Null; len as usize];
        for (k, v) in pairs {
            let Value::Integer(i) = k else { unreachable!() };
            self.path.push(Step::Index(*i));
            items[(*i - 1) as usize] = self.value(v)?;
            self.path.pop();
        }
        Ok(serde_json::Value::Array(items))
    }

    fn table(&mut self, t: &Table) -> Result<serde_json::Value, String> {
        let me = t.to_pointer();
        if self.open.contains(&me) {
            return Err(format!("{} holds itself", self.here()));
        }
        if self.open.len() >= DEEPEST {
            return Err(format!(
                "{} nests tables more than {DEEPEST} deep",
                self.here()
            ));
        }
        let mut pairs: Vec<(Value, Value)> = t
            .pairs()
            .collect::<mlua::Result<_>>()
            .map_err(|e| e.to_string())?;
        // Lua's `pairs` order changes from run to run: walked in key order, the same
        // table always gives the same message and the same error.
        pairs.sort_by(|(a, _), (b, _)| {
            order(a)
                .total_cmp(&order(b))
                .then_with(|| text(a).cmp(&text(b)))
        });
        if let Some((k, _)) = pairs
            .iter()
            .find(|(k, _)| matches!(k, Value::String(s) if s.to_str().is_err()))
        {
            return Err(format!(
                "{} has a key that is not UTF-8 text ({k:?})",
                self.here()
            ));
        }
        let n = pairs.len() as i64;
        // A list a subscriber received keeps mlua's array mark, and its nulls are holes.
        let marked = t.metatable().is_some_and(|m| m == self.array_mark);
        let received = marked
            .then(|| {
                pairs
                    .iter()
                    .try_fold(t.raw_len() as i64, |last, (k, _)| match k {
                        Value::Integer(i) if *i >= 1 => Some(last.max(*i)),
                        _ => None,
                    })
            })
            .flatten()
            .filter(|&last| last <= MOST_PARTS as i64);
        let listed = pairs
            .iter()
            .all(|(k, _)| matches!(k, Value::Integer(i) if (1..=n).contains(i)));
        let named = pairs.iter().all(|(k, _)| matches!(k, Value::String(_)));
        self.open.push(me);
        let json = if let Some(len) = received {
            self.list(&pairs, len)?
        } else if listed && n > 0 {
            self.list(&pairs, n)?
        } else if named {
            let mut fields = serde_json::Map::new();
            for (k, v) in &pairs {
                let Value::String(name) = k else {
                    unreachable!()
                };
                let name = name.to_str().map_err(|e| e.to_string())?.to_string();
                self.path.push(Step::Field(name.clone()));
                let v = self.value(v)?;
                self.path.pop();
                fields.insert(name, v);
            }
            serde_json::Value::Object(fields)
        } else {
            let key_of = |k: &Value| match k {
                Value::Integer(i) => format!("[{i}]"),
                Value::Number(x) => format!("[{x}]"),
                other => format!("a {} key", other.type_name()),
            };
            let odd = pairs.iter().map(|(k, _)| k).find(|k| match k {
                Value::String(_) => false,
                Value::Integer(i) => !(1..=n).contains(i),
                _ => true,
            });
            let why = match odd {
                Some(k @ Value::Integer(_)) => {
                    format!("{} among {n} keys (a list's are 1…{n})", key_of(k))
                }
                Some(k) => key_of(k),
                None => "both list keys (1, 2, …) and string keys".to_string(),
            };
            return Err(format!(
                "{} is neither a list nor a record (string keys): it has {why}",
                self.here()
            ));
        };
        self.open.pop();
        Ok(json)
    }
}

/// A JSON value as a Lua value (objects and arrays as tables, null as nil).
pub(crate) fn to_lua(lua: &Lua, value: &serde_json::Value) -> mlua::Result<Value> {
    lua.to_value_with(
        value,
        mlua::serde::SerializeOptions::new()
            .serialize_none_to_null(false)
            .serialize_unit_to_null(false),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What a subscriber received goes out again as it came: lists (empty ones, and ones
    /// with nulls) stay lists.
    #[test]
    fn a_received_value_is_published_back_unchanged() {
        let lua = Lua::new();
        let json: serde_json::Value = serde_json::from_str(
            r#"{"empty": [], "holes": [1, null, 3], "nested": [[], {"a": [null, 2]}], "n": null}"#,
        )
        .unwrap();
        let received = to_lua(&lua, &json).unwrap();
        let back = to_json(&lua, &received).unwrap();
        // `null` at the top of a record is a missing field in Lua (and a list's trailing
        // nulls are lost the same way).
        let mut expected = json.clone();
        expected.as_object_mut().unwrap().remove("n");
        assert_eq!(back, expected);
    }

    /// The same table gives the same error whatever order `pairs` takes.
    #[test]
    fn errors_name_the_first_bad_value_in_key_order() {
        let lua = Lua::new();
        let t: Value = lua
            .load("return { b = 0/0, a = 0/0, c = { z = 1/0, y = 1/0 } }")
            .eval()
            .unwrap();
        assert_eq!(
            to_json(&lua, &t).unwrap_err(),
            "value.a is not a finite number"
        );
        let t: Value = lua
            .load("return { [3] = 1, x = 1, [5] = 2 }")
            .eval()
            .unwrap();
        assert!(to_json(&lua, &t)
            .unwrap_err()
            .ends_with("it has [5] among 3 keys (a list's are 1…3)"));
    }
}
