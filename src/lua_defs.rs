//! `troupe lua-defs OUT.lua`: writes the EmmyLua / LuaLS definition file of the Lua API
//! (from [`troupe_lua::reference`]), for editors and `emmylua_check`.

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use std::process::ExitCode;

/// Options of `troupe lua-defs`.
#[derive(Args)]
pub struct LuaDefsArgs {
    /// The definition file to write (e.g. `.tools/troupe.d.lua`).
    pub out: PathBuf,
}

/// Writes the definitions.
pub fn run(args: LuaDefsArgs) -> Result<ExitCode> {
    if let Some(dir) = args.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    std::fs::write(&args.out, troupe_lua::reference::lua_defs())
        .with_context(|| format!("writing {}", args.out.display()))?;
    println!(
        "wrote {} ({} documented names)",
        args.out.display(),
        troupe_lua::reference::API.len()
    );
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use std::collections::BTreeSet;
    use troupe_lua::reference::{Item, API, CLASSES};
    use troupe_lua::{LuaSession, LuaSessionExt, ScriptLimits};
    use troupe_scene::SceneConfig;

    /// A session with the whole API: the runtime's, the action kinds', the devices'.
    fn session() -> LuaSession {
        let (session, _devices) =
            crate::devices::session(SceneConfig::default(), ScriptLimits::default(), None).unwrap();
        session
    }

    /// The names a table holds as functions (`""`: the globals, less Lua's own).
    fn live_functions(s: &mut LuaSession, table: &str) -> BTreeSet<String> {
        let names: Vec<String> = s
            .eval(&format!(
                "local t = {{}} for k, v in pairs({}) do if type(v) == 'function' then \
                 t[#t + 1] = k end end return t",
                if table.is_empty() { "_G" } else { table }
            ))
            .unwrap();
        const LUA_OWN: &[&str] = &[
            "assert",
            "error",
            "getmetatable",
            "ipairs",
            "next",
            "pairs",
            "pcall",
            "rawequal",
            "rawget",
            "rawlen",
            "rawset",
            "select",
            "setmetatable",
            "tonumber",
            "tostring",
            "type",
            "xpcall",
        ];
        names
            .into_iter()
            .filter(|n| !(table.is_empty() && LUA_OWN.contains(&n.as_str())))
            .collect()
    }

    fn documented(owner: &str) -> BTreeSet<String> {
        API.iter()
            .filter(|e| e.owner == owner && e.item == Item::Function)
            .map(|e| e.name.to_string())
            .collect()
    }

    #[test]
    fn every_global_and_troupe_function_is_documented_and_every_entry_exists() {
        let mut s = session();
        for owner in ["", "troupe", "troupe.devices"] {
            assert_eq!(
                live_functions(&mut s, owner),
                documented(owner),
                "the functions of `{owner}` (live, then documented)"
            );
        }
    }

    #[test]
    fn every_action_kind_is_documented() {
        let kinds = troupe_actions::action_kinds();
        for kind in kinds.all() {
            assert!(
                API.iter()
                    .any(|e| e.owner == "Actor" && e.name == kind.method && e.item == Item::Method),
                "actor:{} has no entry in the reference",
                kind.method
            );
        }
    }

    #[test]
    fn every_action_kinds_options_are_documented_and_accepted() {
        use troupe_lua::kinds::COMMON_OPTIONS;
        use troupe_lua::reference::KIND_OPTIONS;
        let mut s = session();
        s.eval::<()>("ANN = troupe.actor{ name = 'ann' }").unwrap();
        let kinds = troupe_actions::action_kinds();
        assert_eq!(
            KIND_OPTIONS.len(),
            kinds.all().len(),
            "one option class per kind"
        );
        for (kind, _, fields) in KIND_OPTIONS {
            // An unknown option's error lists the options the builder knows.
            let call = if *kind == "play" {
                "ANN:play(troupe.sequence{ r_elbow_flexion = {{0, 0}, {1, 1}} }, { __probe = 1 })"
                    .to_string()
            } else {
                format!("ANN:{kind}{{ __probe = 1 }}")
            };
            let err: String = s
                .eval(&format!(
                    "local ok, e = pcall(function() return {call} end) return tostring(e)"
                ))
                .unwrap();
            let known = err
                .split("(known: ")
                .nth(1)
                .and_then(|k| k.split(')').next())
                .unwrap_or_else(|| panic!("{kind}: {err}"));
            let accepted: BTreeSet<&str> = known.split(", ").collect();
            let documented: BTreeSet<&str> = COMMON_OPTIONS
                .iter()
                .copied()
                .chain(fields.iter().map(|(n, _)| *n))
                .collect();
            assert_eq!(accepted, documented, "the options of actor:{kind}");
        }
    }

    #[test]
    fn every_documented_method_and_field_resolves_on_a_live_handle() {
        let mut s = session();
        s.eval::<()>(
            "H = {}
             H.Actor = troupe.actor{ name = 'ann' }
             H.Object = troupe.object{ name = 'cup', shape = 'sphere', radius = 0.04, at = {0.3, 1, 0.3} }
             H.Sequence = troupe.sequence{ r_elbow_flexion = { {0, 0}, {1, 1} } }
             H.Action = H.Actor:play(H.Sequence)
             H.Behavior = H.Actor:behave(function() end)
             H.Handler = H.Actor:on('action_completed', function() end)",
        )
        .unwrap();
        for (class, _) in CLASSES {
            for e in API.iter().filter(|e| e.owner == *class) {
                let nullable = matches!(e.item, Item::Field(t) if t.ends_with('?'));
                let found: bool = s
                    .eval(&format!(
                        "local ok, v = pcall(function() return H.{class}.{} end) \
                         return ok and (v ~= nil or {nullable})",
                        e.name
                    ))
                    .unwrap();
                assert!(
                    found,
                    "{class}.{} is documented but does not resolve",
                    e.name
                );
            }
        }
    }

    #[test]
    fn the_definitions_name_every_entry_with_its_doc() {
        let defs = troupe_lua::reference::lua_defs();
        assert!(defs.starts_with("---@meta"));
        for e in API {
            assert!(defs.contains(e.doc), "{}: doc line missing", e.name);
        }
        assert!(defs.contains("function Actor:behave(fn) end"), "{defs}");
        assert!(defs.contains("function troupe.actor(opts) end"));
        assert!(defs.contains("---@field status BehaviorStatus"));
    }

    /// Whether `code` calls `path` (`wait`, `troupe.actor`, `:walk`): followed by `(` or
    /// `{`, and for a global not the end of a longer name (`b:wait(` is not `wait(`).
    fn calls(code: &str, path: &str) -> bool {
        code.match_indices(path).any(|(at, _)| {
            let before = code[..at].chars().next_back();
            let after = code[at + path.len()..]
                .trim_start_matches(' ')
                .chars()
                .next();
            let whole = path.starts_with(':')
                || path.contains('.')
                || !before.is_some_and(|c| c.is_alphanumeric() || "_.:".contains(c));
            whole && matches!(after, Some('(' | '{'))
        })
    }

    #[test]
    fn every_function_and_method_has_an_example_in_the_lua_api_doc() {
        let doc = include_str!("../docs/lua-api.md");
        // The text of every Lua code block.
        let code: String = doc
            .split("```lua")
            .skip(1)
            .filter_map(|block| block.split("```").next())
            .collect();
        let missing: Vec<String> = API
            .iter()
            .filter_map(|e| {
                let path = match (e.item, e.owner) {
                    (Item::Field(_), _) => return None,
                    (Item::Method, _) => format!(":{}", e.name),
                    (Item::Function, "") => e.name.to_string(),
                    (Item::Function, owner) => format!("{owner}.{}", e.name),
                };
                (!calls(&code, &path)).then_some(path)
            })
            .collect();
        assert!(
            missing.is_empty(),
            "docs/lua-api.md has no Lua example calling {missing:?}"
        );
        // The check itself: a method call is not a global's, nor a longer name's.
        assert!(calls("b:wait()", ":wait") && !calls("b:wait()", "wait"));
        assert!(!calls("wait_until(f)", "wait") && calls("x = wait (1)", "wait"));
        assert!(calls("troupe.devices.glove(pat)", "troupe.devices.glove"));
    }
}
