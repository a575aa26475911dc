//! `emmylua_check` (crates.io) with the definitions `troupe lua-defs` writes: the
//! repository's Lua has no errors, a correct script is clean even with warnings as errors,
//! and a misspelt API name is caught. Skipped with a note when `scripts/setup.sh` has not
//! installed the checker.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn checker() -> Option<PathBuf> {
    let tools = std::env::var_os("TROUPE_TOOLS")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| Path::new(&h).join(".cache/troupe-tools")))?;
    let bin = tools.join("bin/emmylua_check");
    bin.is_file().then_some(bin)
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().unwrap()
}

fn defs(out: &Path) {
    let o = run(Command::new(env!("CARGO_BIN_EXE_troupe"))
        .arg("lua-defs")
        .arg(out));
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn the_repository_lua_checks_without_errors() {
    let Some(bin) = checker() else {
        eprintln!("emmylua_check is not installed (scripts/setup.sh installs it): skipped");
        return;
    };
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    defs(&root.join(".tools/lua/troupe.d.lua"));
    let o = run(Command::new(bin).arg(".").current_dir(root));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let errors: Vec<&str> = text.lines().filter(|l| l.starts_with("error")).collect();
    assert!(errors.is_empty(), "{errors:?}");
}

#[test]
fn the_definitions_catch_a_misspelt_method_and_pass_a_correct_script() {
    let Some(bin) = checker() else {
        eprintln!("emmylua_check is not installed (scripts/setup.sh installs it): skipped");
        return;
    };
    let dir = std::env::temp_dir().join(format!("troupe-luacheck-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("types")).unwrap();
    defs(&dir.join("types/troupe.d.lua"));
    std::fs::write(
        dir.join(".emmyrc.json"),
        r#"{ "runtime": { "version": "Lua5.4" }, "workspace": { "library": ["types"] } }"#,
    )
    .unwrap();
    let scene = |body: &str| {
        std::fs::write(
            dir.join("scene.lua"),
            format!(
                "local ann = troupe.actor{{ name = \"ann\" }}\n\
                 local b = ann:behave(function(self)\n  {body}\nend)\n\
                 print(b.status)\n"
            ),
        )
        .unwrap();
        run(Command::new(&bin)
            .args(["--warnings-as-errors", "."])
            .current_dir(&dir))
    };
    let good = scene("self:walk{ to = {1, 0, 0} }:wait()");
    assert!(
        good.status.success(),
        "{}",
        String::from_utf8_lossy(&good.stdout)
    );
    let bad = scene("self:wlak{ to = {1, 0, 0} }:wait()");
    assert!(!bad.status.success(), "a misspelt method is flagged");
    assert!(String::from_utf8_lossy(&bad.stdout).contains("wlak"));
    std::fs::remove_dir_all(&dir).ok();
}
