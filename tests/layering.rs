//! The crate's layering, read from its source: which top-level module (`src/<name>.rs` or
//! `src/<name>/`) refers to which through `crate::` paths (comments and `#[cfg(test)]`
//! modules left out). docs/architecture.md draws the layers: data rooms (scene, surfels,
//! cache, ...) below work rooms (bake, bounce, gather, render, preview, reference); every
//! arrow should point down.
//!
//! The test fails when a new arrow closes a cycle, and when one of the cycles still listed in
//! [`KNOWN_BACK_EDGES`] is gone (so the list only shrinks). It also holds the rule that the
//! gather, the final render and the preview import nothing from the bake or the reference
//! path tracer.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Arrows that still point up (each lies on a cycle), to be removed, not added to.
/// - `bounce -> bake`: the bounces read and extend the bake's `Baked`, which the bake's
///   pipeline hands them.
const KNOWN_BACK_EDGES: &[(&str, &str)] = &[("bounce", "bake")];

type Graph = BTreeMap<String, BTreeSet<String>>;

/// The top-level modules each module refers to.
fn module_graph() -> Graph {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut graph = Graph::new();
    let mut stack = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("src is readable") {
            let path = entry.expect("a directory entry").path();
            let rel = path.strip_prefix(&src).expect("under src");
            if path.is_dir() {
                if rel != Path::new("bin") {
                    stack.push(path);
                }
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") || rel == Path::new("lib.rs") {
                continue;
            }
            let first = rel.components().next().expect("a path");
            let module = first
                .as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string();
            let text = std::fs::read_to_string(&path).expect("a source file");
            let code = match text.find("#[cfg(test)]\nmod tests") {
                Some(i) => &text[..i],
                None => &text,
            };
            let targets = graph.entry(module.clone()).or_default();
            for line in code.lines().filter(|l| !l.trim_start().starts_with("//")) {
                for (i, _) in line.match_indices("crate::") {
                    let name: String = line[i + 7..]
                        .chars()
                        .take_while(|c| c.is_alphanumeric() || *c == '_')
                        .collect();
                    if !name.is_empty() && name != module {
                        targets.insert(name);
                    }
                }
            }
        }
    }
    graph
}

fn reaches(graph: &Graph, from: &str, to: &str) -> bool {
    let mut seen = BTreeSet::new();
    let mut stack = vec![from.to_string()];
    while let Some(m) = stack.pop() {
        if m == to {
            return true;
        }
        if seen.insert(m.clone()) {
            stack.extend(graph.get(&m).into_iter().flatten().cloned());
        }
    }
    false
}

#[test]
fn arrows_point_down_except_the_known_ones() {
    let graph = module_graph();
    assert!(graph.len() > 20, "read {} modules", graph.len());
    let mut back_edges = BTreeSet::new();
    for (from, targets) in &graph {
        for to in targets {
            if reaches(&graph, to, from) {
                back_edges.insert((from.clone(), to.clone()));
            }
        }
    }
    let known: BTreeSet<(String, String)> = KNOWN_BACK_EDGES
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    // Without the known arrows, no arrow may lie on a cycle.
    let mut pruned = graph.clone();
    for (from, to) in &known {
        pruned.entry(from.clone()).or_default().remove(to);
    }
    let cycles: Vec<_> = back_edges
        .iter()
        .filter(|(from, to)| pruned[from].contains(to) && reaches(&pruned, to, from))
        .collect();
    assert!(cycles.is_empty(), "new import cycles through {cycles:?}");
    for k in &known {
        assert!(
            back_edges.contains(k),
            "{} -> {} no longer closes a cycle: remove it from KNOWN_BACK_EDGES",
            k.0,
            k.1
        );
    }
}

#[test]
fn gather_render_and_preview_import_nothing_from_bake_or_reference() {
    let graph = module_graph();
    for room in ["gather", "render", "preview"] {
        let targets = &graph[room];
        for upper in ["bake", "bounce", "reference"] {
            assert!(!targets.contains(upper), "{room} imports from {upper}");
        }
    }
}
