//! The source's import structure (docs/ARCHITECTURE.md, "Import order"): no top-level
//! module imports one above it in `ORDER`, and no circle of files imports itself. Read
//! from the text of `src/` (test code left out), so a new back edge fails here.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Top-level modules, lowest first: each may import the ones before it only.
const ORDER: &[&str] = &[
    "math",
    "input",
    "progress",
    "spectrum",
    "sampling",
    "image_io",
    "metrics",
    "texture",
    "film",
    "options",
    "material",
    "accel",
    "light",
    "scene",
    "radiosity",
    "integrator",
    "filter",
    "pipeline",
    "render",
    "report",
    "cli",
    "lib",
    "main",
];

/// Back edges the code still has (module, imported module, why): none.
const KNOWN: &[(&str, &str)] = &[];

/// Files whose circles are still known.
const KNOWN_CIRCLE_EDGES: &[(&str, &str)] = &[];

/// Every non-test source file (path relative to `src/`, text without test modules and
/// comments).
fn sources() -> BTreeMap<String, String> {
    fn walk(dir: &Path, out: &mut BTreeMap<String, String>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().to_string();
            if p.is_dir() {
                if name != "tests" {
                    walk(&p, out);
                }
            } else if name.ends_with(".rs") && name != "tests.rs" {
                let mut s = std::fs::read_to_string(&p).unwrap();
                if let Some(i) = s.find("#[cfg(test)]\nmod tests {") {
                    s.truncate(i);
                }
                let code: Vec<&str> = s.lines().map(|l| l.split("//").next().unwrap()).collect();
                let rel = p
                    .strip_prefix("src")
                    .unwrap()
                    .to_string_lossy()
                    .replace('\\', "/");
                out.insert(rel, code.join("\n"));
            }
        }
    }
    let mut out = BTreeMap::new();
    walk(Path::new("src"), &mut out);
    out
}

/// The identifiers of `s` after each occurrence of `prefix` joined by `::`.
fn paths_after<'a>(s: &'a str, prefix: &str) -> Vec<Vec<&'a str>> {
    let mut out = Vec::new();
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    for (i, _) in s.match_indices(prefix) {
        if i > 0 && s[..i].ends_with(|c: char| ident(c) || c == ':') {
            continue;
        }
        let rest = &s[i + prefix.len()..];
        let end = rest
            .find(|c: char| !(ident(c) || c == ':'))
            .unwrap_or(rest.len());
        let comps: Vec<&str> = rest[..end].split("::").filter(|c| !c.is_empty()).collect();
        out.push(comps.clone());
        // `prefix{a, b::c}` groups
        if rest[end..].starts_with('{') {
            if let Some(close) = rest[end..].find('}') {
                for item in rest[end + 1..end + close].split(',') {
                    let item = item.trim();
                    if !item.is_empty() && item != "self" {
                        let mut c = comps.clone();
                        c.extend(item.split("::").map(|x| x.split(' ').next().unwrap()));
                        out.push(c);
                    }
                }
            }
        }
    }
    out
}

fn top_module(file: &str) -> &str {
    let first = file.split('/').next().unwrap();
    first.strip_suffix(".rs").unwrap_or(first)
}

/// The module path of a file: `integrator/mod.rs` -> [integrator].
fn module_of(file: &str) -> Vec<String> {
    let mut parts: Vec<String> = file
        .trim_end_matches(".rs")
        .split('/')
        .map(String::from)
        .collect();
    if parts
        .last()
        .is_some_and(|p| p == "mod" || p == "lib" || p == "main")
    {
        parts.pop();
    }
    parts
}

#[test]
fn no_module_imports_a_later_stage() {
    let rank = |m: &str| ORDER.iter().position(|&o| o == m);
    let mut bad = BTreeSet::new();
    for (file, code) in sources() {
        let me = top_module(&file);
        let my_rank = rank(me).unwrap_or_else(|| panic!("{file}: module {me} not in ORDER"));
        for comps in paths_after(&code, "crate::") {
            let Some(&m) = comps.first() else { continue };
            match rank(m) {
                Some(r) if r > my_rank && !KNOWN.contains(&(me, m)) => {
                    bad.insert(format!("{file} imports {m}"));
                }
                _ => {}
            }
        }
    }
    assert!(bad.is_empty(), "imports of a later stage:\n{bad:#?}");
}

#[test]
fn no_circle_of_files() {
    let files = sources();
    let by_module: BTreeMap<Vec<String>, String> =
        files.keys().map(|f| (module_of(f), f.clone())).collect();
    // the file that holds a path's longest known module prefix
    let resolve = |comps: &[String]| {
        (1..=comps.len())
            .rev()
            .find_map(|k| by_module.get(&comps[..k]))
            .cloned()
    };
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    for (file, code) in &files {
        let me = module_of(file);
        let mut targets = Vec::new();
        for comps in paths_after(code, "crate::") {
            targets.push(comps.iter().map(|c| c.to_string()).collect::<Vec<_>>());
        }
        for comps in paths_after(code, "super::") {
            // `super::super::x` is two levels up
            let ups = 1 + comps.iter().take_while(|&&c| c == "super").count();
            let mut t: Vec<String> = me[..me.len().saturating_sub(ups)].to_vec();
            t.extend(comps.iter().skip(ups - 1).map(|c| c.to_string()));
            targets.push(t);
        }
        for t in targets {
            let Some(to) = resolve(&t) else { continue };
            // a folder's front (`mod.rs`) is its children's to import
            let to_mod = module_of(&to);
            if to != *file && !me.starts_with(&to_mod) && !KNOWN_CIRCLE_EDGES.contains(&(file, &to))
            {
                edges.entry(file.clone()).or_default().insert(to);
            }
        }
    }
    // depth-first search for a back edge
    fn visit(
        f: &str,
        edges: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(f.to_string(), 1);
        stack.push(f.to_string());
        for to in edges.get(f).into_iter().flatten() {
            match state.get(to.as_str()).copied().unwrap_or(0) {
                1 => {
                    let i = stack.iter().position(|s| s == to).unwrap();
                    let mut c = stack[i..].to_vec();
                    c.push(to.clone());
                    return Some(c);
                }
                0 => {
                    if let Some(c) = visit(to, edges, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(f.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for f in files.keys() {
        if state.get(f.as_str()).copied().unwrap_or(0) == 0 {
            let mut stack = Vec::new();
            if let Some(c) = visit(f, &edges, &mut state, &mut stack) {
                panic!("a circle of imports: {}", c.join(" -> "));
            }
        }
    }
}
