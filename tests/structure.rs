//! The crate's layering: the only import cycle is Radiance's shading recursion (render,
//! material, light, modifier call each other), and the scene and geometry stay below it.
//!
//! The graph is read from the sources: a file's module imports every module that a
//! `crate::…` or `super::…` path in its code (comments and `#[cfg(test)]` parts left out)
//! names, to the longest prefix that is a module of the crate.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The modules whose files may import each other in a circle.
const RECURSION: [&str; 4] = ["render", "material", "light", "modifier"];

/// What the scene's and geometry's files may not name.
const ABOVE: [&str; 12] = [
    "render", "material", "light", "modifier", "ambient", "session", "job", "ttrace", "tpict",
    "image", "options", "rif",
];

/// Module path (`scene::world`, `` for lib.rs) → the file's code without comments and tests.
fn modules() -> BTreeMap<String, String> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut out = BTreeMap::new();
    let mut stack = vec![root.clone()];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
                continue;
            }
            if p.extension().and_then(|x| x.to_str()) != Some("rs") {
                continue;
            }
            let rel = p.strip_prefix(&root).unwrap().with_extension("");
            let mut name = rel.to_string_lossy().replace('/', "::");
            if name == "lib" {
                name.clear();
            } else if let Some(s) = name.strip_suffix("::mod") {
                name = s.to_string();
            }
            let text = std::fs::read_to_string(&p).unwrap();
            let code = text.split("#[cfg(test)]").next().unwrap();
            let code: String = code
                .lines()
                .map(|l| l.split("//").next().unwrap())
                .collect::<Vec<_>>()
                .join("\n");
            out.insert(name, code);
        }
    }
    out
}

/// The module `path` (`a::b::c`) belongs to: its longest prefix that is a module.
fn resolve(mods: &BTreeMap<String, String>, path: &[&str]) -> Option<String> {
    (1..=path.len())
        .rev()
        .map(|k| path[..k].join("::"))
        .find(|m| mods.contains_key(m))
}

/// Each module's imports of other modules.
fn graph(mods: &BTreeMap<String, String>) -> BTreeMap<String, BTreeSet<String>> {
    let mut g = BTreeMap::new();
    for (m, code) in mods {
        let parent: Vec<&str> = m.split("::").filter(|s| !s.is_empty()).collect();
        let parent = &parent[..parent.len().saturating_sub(1)];
        let mut deps = BTreeSet::new();
        let bytes = code.as_bytes();
        for (base, skip) in [("crate::", 0usize), ("super::", 1)] {
            for (i, _) in code.match_indices(base) {
                if i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_') {
                    continue;
                }
                let rest = &code[i + base.len()..];
                let prefix: Vec<&str> = if skip == 1 {
                    parent.to_vec()
                } else {
                    Vec::new()
                };
                // `use super::{a, b::c}`: each item.
                let items: Vec<&str> = if let Some(list) = rest.strip_prefix('{') {
                    list.split('}').next().unwrap().split(',').collect()
                } else {
                    vec![rest]
                };
                for item in items {
                    let path: Vec<&str> = item
                        .trim()
                        .split("::")
                        .map(|s| {
                            s.split(|c: char| !(c.is_alphanumeric() || c == '_'))
                                .next()
                                .unwrap()
                        })
                        .take_while(|s| !s.is_empty())
                        .collect();
                    let mut full = prefix.clone();
                    full.extend(path);
                    if let Some(t) = resolve(mods, &full) {
                        if &t != m {
                            deps.insert(t);
                        }
                    }
                }
            }
        }
        g.insert(m.clone(), deps);
    }
    g
}

/// Strongly connected components of more than one module (Tarjan's algorithm).
fn cycles(g: &BTreeMap<String, BTreeSet<String>>) -> Vec<Vec<String>> {
    struct T<'a> {
        g: &'a BTreeMap<String, BTreeSet<String>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<Vec<String>>,
    }
    impl<'a> T<'a> {
        fn visit(&mut self, v: &'a str) {
            let n = self.index.len();
            self.index.insert(v, n);
            self.low.insert(v, n);
            self.stack.push(v);
            self.on.insert(v);
            for w in &self.g[v] {
                let w = w.as_str();
                if !self.index.contains_key(w) {
                    self.visit(w);
                    let l = self.low[v].min(self.low[w]);
                    self.low.insert(v, l);
                } else if self.on.contains(w) {
                    let l = self.low[v].min(self.index[w]);
                    self.low.insert(v, l);
                }
            }
            if self.low[v] == self.index[v] {
                let mut comp = Vec::new();
                loop {
                    let w = self.stack.pop().unwrap();
                    self.on.remove(w);
                    comp.push(w.to_string());
                    if w == v {
                        break;
                    }
                }
                if comp.len() > 1 {
                    comp.sort();
                    self.out.push(comp);
                }
            }
        }
    }
    let mut t = T {
        g,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in g.keys() {
        if !t.index.contains_key(v.as_str()) {
            t.visit(v);
        }
    }
    t.out
}

fn top(m: &str) -> &str {
    m.split("::").next().unwrap()
}

#[test]
fn the_only_import_cycle_is_the_shading_recursion() {
    let mods = modules();
    let g = graph(&mods);
    // The reader sees the known circle (so that a broken reader cannot pass).
    assert!(
        g["render::trace"].contains("material"),
        "{:?}",
        g["render::trace"]
    );
    assert!(
        g["material"].iter().any(|d| top(d) == "render"),
        "{:?}",
        g["material"]
    );
    for comp in cycles(&g) {
        assert!(
            comp.iter().all(|m| RECURSION.contains(&top(m))),
            "an import cycle outside render/material/light/modifier: {comp:?}"
        );
    }
}

#[test]
fn scene_and_geometry_stay_below_the_shading_recursion() {
    let mods = modules();
    let g = graph(&mods);
    let mut bad = Vec::new();
    for (m, deps) in &g {
        if !matches!(top(m), "scene" | "geometry") {
            continue;
        }
        for d in deps {
            if ABOVE.contains(&top(d)) {
                bad.push(format!("{m} -> {d}"));
            }
        }
    }
    assert!(
        bad.is_empty(),
        "scene/geometry import what is above them: {bad:?}"
    );
    assert!(g["scene::instance"].contains("scene::sets"));
}
