//! The architecture stays as `docs/architecture.md` draws it:
//! - no import cycles between the files of any crate (a file naming an item of another
//!   file while that file names one of its items; a module and its own submodules are one
//!   tree and do not count);
//! - the crate graph of `docs/architecture.dot` is the graph of the `Cargo.toml` files;
//! - the viewer builds without Lua.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The source folders checked for cycles, one per crate.
const CRATES: [&str; 10] = [
    "runtime/body/src",
    "runtime/motion/src",
    "runtime/formats/src",
    "runtime/scene/src",
    "runtime/lua/src",
    "actions/src",
    "drivers/src",
    "viewer/src",
    "net/src",
    "src",
];

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A module's path inside its crate (`["grasp", "plan"]`; the crate root is `[]`).
type ModPath = Vec<String>;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

fn module_of(src: &Path, file: &Path) -> ModPath {
    let rel = file.strip_prefix(src).unwrap().with_extension("");
    let mut parts: ModPath = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if matches!(
        parts.last().map(String::as_str),
        Some("mod" | "lib" | "main")
    ) {
        parts.pop();
    }
    parts
}

/// The code of a file without comments and without its unit-test module (tests may reach
/// anywhere in their crate).
fn code_of(text: &str) -> String {
    let text = match text.find("#[cfg(test)]\nmod tests") {
        Some(i) => &text[..i],
        None => text,
    };
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) => &l[..i],
            None => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// Every path that follows `start` (a position just after `crate::`, `super::` or a child
/// module's `name::`), with use-tree groups `{a, b::{c, d}}` expanded.
fn paths_at(code: &str, start: usize) -> Vec<Vec<String>> {
    let rest = &code[start..];
    if let Some(group) = rest.strip_prefix('{') {
        let mut depth = 1;
        let mut end = 0;
        for (i, c) in group.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                _ => {}
            }
            if depth == 0 {
                end = i;
                break;
            }
        }
        let inner = &group[..end];
        let mut items = Vec::new();
        let (mut depth, mut from) = (0, 0);
        for (i, c) in inner.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                ',' if depth == 0 => {
                    items.push(&inner[from..i]);
                    from = i + 1;
                }
                _ => {}
            }
        }
        items.push(&inner[from..]);
        let offset = start + 1;
        return items
            .into_iter()
            .filter(|item| !item.trim().is_empty())
            .flat_map(|item| {
                let trimmed = item.trim_start();
                let at = offset
                    + (item.as_ptr() as usize - inner.as_ptr() as usize)
                    + (item.len() - trimmed.len());
                paths_at(code, at)
            })
            .collect();
    }
    let ident: String = rest.chars().take_while(|&c| is_ident(c)).collect();
    if ident.is_empty() {
        return vec![Vec::new()];
    }
    let after = start + ident.len();
    if code[after..].starts_with("::") {
        paths_at(code, after + 2)
            .into_iter()
            .map(|mut p| {
                p.insert(0, ident.clone());
                p
            })
            .collect()
    } else {
        vec![vec![ident]]
    }
}

/// The modules a file names items of, as paths from its crate root.
fn references(code: &str, module: &ModPath, modules: &BTreeSet<ModPath>) -> Vec<ModPath> {
    let mut found = Vec::new();
    let bytes: Vec<char> = code.chars().collect();
    let boundary = |i: usize| i == 0 || !is_ident(bytes[i - 1]) && bytes[i - 1] != ':';
    // Byte offsets of every identifier start followed by `::`.
    for (i, _) in code.match_indices("::") {
        let head_start = code[..i]
            .char_indices()
            .rev()
            .take_while(|&(_, c)| is_ident(c))
            .last()
            .map(|(j, _)| j)
            .unwrap_or(i);
        let head = &code[head_start..i];
        let char_index = code[..head_start].chars().count();
        if head.is_empty() || !boundary(char_index) {
            continue;
        }
        let base: ModPath = match head {
            "crate" => Vec::new(),
            "super" => {
                // `super::super::x`: count the chain.
                let mut up = 1;
                let mut at = i + 2;
                while code[at..].starts_with("super::") {
                    up += 1;
                    at += 7;
                }
                let base = module[..module.len().saturating_sub(up)].to_vec();
                for p in paths_at(code, at) {
                    found.push([base.clone(), p].concat());
                }
                continue;
            }
            child => {
                let mut m = module.clone();
                m.push(child.to_string());
                if !modules.contains(&m) {
                    continue;
                }
                module.clone()
            }
        };
        let start = if head == "crate" { i + 2 } else { head_start };
        for p in paths_at(code, start) {
            found.push([base.clone(), p].concat());
        }
    }
    found
}

/// Strongly connected components of more than one module.
fn cycles(edges: &BTreeMap<ModPath, BTreeSet<ModPath>>) -> Vec<Vec<ModPath>> {
    struct Tarjan<'a> {
        edges: &'a BTreeMap<ModPath, BTreeSet<ModPath>>,
        index: BTreeMap<ModPath, usize>,
        low: BTreeMap<ModPath, usize>,
        stack: Vec<ModPath>,
        out: Vec<Vec<ModPath>>,
    }
    impl Tarjan<'_> {
        fn visit(&mut self, v: &ModPath) {
            let n = self.index.len();
            self.index.insert(v.clone(), n);
            self.low.insert(v.clone(), n);
            self.stack.push(v.clone());
            for w in &self.edges[v] {
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let lw = self.low[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(lw);
                } else if self.stack.contains(w) {
                    let iw = self.index[w];
                    let lv = self.low.get_mut(v).unwrap();
                    *lv = (*lv).min(iw);
                }
            }
            if self.low[v] == self.index[v] {
                let mut component = Vec::new();
                loop {
                    let w = self.stack.pop().unwrap();
                    let done = w == *v;
                    component.push(w);
                    if done {
                        break;
                    }
                }
                if component.len() > 1 {
                    self.out.push(component);
                }
            }
        }
    }
    let mut t = Tarjan {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !t.index.contains_key(v) {
            t.visit(v);
        }
    }
    t.out
}

/// The import graph of one crate's files.
fn import_graph(src: &Path) -> BTreeMap<ModPath, BTreeSet<ModPath>> {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeMap<ModPath, PathBuf> = files
        .iter()
        .map(|f| (module_of(src, f), f.clone()))
        .collect();
    let known: BTreeSet<ModPath> = modules.keys().cloned().collect();
    let mut edges = BTreeMap::new();
    for (module, file) in &modules {
        let code = code_of(&std::fs::read_to_string(file).unwrap());
        let mut to = BTreeSet::new();
        for path in references(&code, module, &known) {
            // The deepest module the path names.
            let Some(target) = (0..=path.len())
                .rev()
                .map(|n| path[..n].to_vec())
                .find(|p| known.contains(p))
            else {
                continue;
            };
            let related = target.starts_with(module) || module.starts_with(&target);
            if !related {
                to.insert(target);
            }
        }
        edges.insert(module.clone(), to);
    }
    edges
}

#[test]
fn no_crate_has_an_import_cycle_between_its_files() {
    let mut found = Vec::new();
    for src in CRATES {
        for cycle in cycles(&import_graph(&repo().join(src))) {
            let names: Vec<String> = cycle.iter().map(|m| m.join("/")).collect();
            found.push(format!("{src}: {}", names.join(" <-> ")));
        }
    }
    assert!(found.is_empty(), "import cycles:\n{}", found.join("\n"));
}

#[test]
fn the_cycle_check_sees_a_cycle() {
    // Two sibling files that name each other's items, one through a use-tree group.
    let dir = std::env::temp_dir().join(format!("troupe-cycles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("lib.rs"), "mod a;\nmod b;\nmod c;\n").unwrap();
    std::fs::write(dir.join("a.rs"), "use crate::{c::Z, b::{X, Y}};\n").unwrap();
    std::fs::write(dir.join("b.rs"), "pub fn f() -> super::a::W { todo() }\n").unwrap();
    std::fs::write(
        dir.join("c.rs"),
        "// crate::a::W in a comment is no reference\n",
    )
    .unwrap();
    let found = cycles(&import_graph(&dir));
    std::fs::remove_dir_all(&dir).ok();
    assert_eq!(found.len(), 1, "{found:?}");
    let mut names: Vec<String> = found[0].iter().map(|m| m.join("/")).collect();
    names.sort();
    assert_eq!(names, ["a", "b"]);
}

/// `troupe-x` dependencies on workspace crates, from a `Cargo.toml`.
fn workspace_dependencies(manifest: &Path) -> BTreeSet<String> {
    let text = std::fs::read_to_string(manifest).unwrap();
    let mut section = String::new();
    let mut deps = BTreeSet::new();
    for line in text.lines() {
        let line = line.trim();
        if line.starts_with('[') {
            section = line.to_string();
            continue;
        }
        if section == "[dependencies]" && line.starts_with("troupe-") {
            let name = line.split(['.', ' ', '=']).next().unwrap();
            deps.insert(name.to_string());
        }
    }
    deps
}

/// The crate each node of the diagram stands for.
fn crate_of_node(node: &str) -> String {
    match node {
        "cli" => "troupe".into(),
        other => format!("troupe-{other}"),
    }
}

#[test]
fn the_architecture_diagram_draws_the_real_crate_graph() {
    let manifests = [
        ("troupe-body", "runtime/body"),
        ("troupe-motion", "runtime/motion"),
        ("troupe-formats", "runtime/formats"),
        ("troupe-nav", "runtime/nav"),
        ("troupe-scene", "runtime/scene"),
        ("troupe-lua", "runtime/lua"),
        ("troupe-actions", "actions"),
        ("troupe-drivers", "drivers"),
        ("troupe-viewer", "viewer"),
        ("troupe-net", "net"),
        ("troupe", "."),
    ];
    let mut direct: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (name, dir) in manifests {
        direct.insert(
            name.to_string(),
            workspace_dependencies(&repo().join(dir).join("Cargo.toml")),
        );
    }
    // The diagram draws the transitive reduction: a dependency that another arrow's path
    // already implies is not drawn.
    let reaches = |from: &str, to: &str| {
        let mut todo = vec![from.to_string()];
        let mut seen = BTreeSet::new();
        while let Some(n) = todo.pop() {
            if n == to {
                return true;
            }
            if seen.insert(n.clone()) {
                todo.extend(direct.get(&n).into_iter().flatten().cloned());
            }
        }
        false
    };
    let mut real = BTreeSet::new();
    for (name, deps) in &direct {
        for dep in deps {
            let implied = deps.iter().any(|other| other != dep && reaches(other, dep));
            if !implied {
                real.insert((name.clone(), dep.clone()));
            }
        }
    }
    let dot = std::fs::read_to_string(repo().join("docs/architecture.dot")).unwrap();
    let mut drawn = BTreeSet::new();
    for statement in dot.split([';', '\n']) {
        let parts: Vec<&str> = statement.split("->").map(str::trim).collect();
        if parts.len() == 2 && !parts[0].starts_with("//") {
            drawn.insert((crate_of_node(parts[0]), crate_of_node(parts[1])));
        }
    }
    let missing: Vec<_> = real.difference(&drawn).collect();
    let extra: Vec<_> = drawn.difference(&real).collect();
    assert!(
        missing.is_empty() && extra.is_empty(),
        "docs/architecture.dot is out of date: not drawn {missing:?}, drawn but not real {extra:?}"
    );
}

#[test]
fn the_viewer_builds_without_lua() {
    // Every workspace crate the viewer depends on, transitively, and none uses mlua.
    let dirs: BTreeMap<&str, &str> = [
        ("troupe-body", "runtime/body"),
        ("troupe-motion", "runtime/motion"),
        ("troupe-formats", "runtime/formats"),
        ("troupe-nav", "runtime/nav"),
        ("troupe-scene", "runtime/scene"),
        ("troupe-lua", "runtime/lua"),
        ("troupe-viewer", "viewer"),
    ]
    .into();
    let mut todo = vec!["troupe-viewer".to_string()];
    let mut seen = BTreeSet::new();
    while let Some(name) = todo.pop() {
        if !seen.insert(name.clone()) {
            continue;
        }
        let dir = dirs.get(name.as_str()).unwrap_or_else(|| {
            panic!("the viewer now depends on {name}: add its folder to this test")
        });
        let manifest = repo().join(dir).join("Cargo.toml");
        let text = std::fs::read_to_string(&manifest).unwrap();
        assert!(
            !text.lines().any(|l| l.trim_start().starts_with("mlua")),
            "{name} depends on mlua"
        );
        todo.extend(workspace_dependencies(&manifest));
    }
    assert!(
        !seen.contains("troupe-lua"),
        "the viewer reaches troupe-lua"
    );
}
