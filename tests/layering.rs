//! The crate's layering, read from its source (comments and `#[cfg(test)] mod tests` left
//! out). docs/architecture.md draws the layers: data rooms (scene, surfels, cache, ...) below
//! work rooms (bake, gather, render, preview, reference); every arrow points down.
//!
//! Two graphs are checked for cycles:
//! - the folder graph: which top-level module (`src/<name>.rs` or `src/<name>/`) names which
//!   through `crate::` paths;
//! - the file graph: which source file uses which, each `use` and inline path (`crate::`,
//!   `super::`, `self::`, a child module's name) resolved to the file that defines the item,
//!   through the `pub use` re-exports of a `mod.rs` (a re-export is the parent's view of its
//!   children, not a dependency of the children on the parent).
//!
//! Method calls on a type whose `impl` blocks are split across files are not paths, so they
//! do not show; everything named is.
//!
//! It also holds the rule that the gather, the final render and the preview import nothing
//! from the bake or the reference path tracer. Run it alone with
//! `cargo test --release --test layering`.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Graph = BTreeMap<String, BTreeSet<String>>;

/// A source file under `src/` (not `src/bin/`): its module path (`["bake", "bounce"]` for
/// `src/bake/bounce/mod.rs`, empty for `lib.rs`) and its code without comment lines and
/// without its unit tests.
struct SourceFile {
    module: Vec<String>,
    code: String,
}

fn source_files() -> Vec<SourceFile> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    let mut stack: Vec<PathBuf> = vec![src.clone()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).expect("src is readable") {
            let path = entry.expect("a directory entry").path();
            let rel = path.strip_prefix(&src).expect("under src").to_path_buf();
            if path.is_dir() {
                if rel != Path::new("bin") {
                    stack.push(path);
                }
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let mut module: Vec<String> = rel
                .with_extension("")
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            if module.last().is_some_and(|m| m == "mod") || module == ["lib"] {
                module.pop();
            }
            let text = std::fs::read_to_string(&path).expect("a source file");
            let text = match text.find("#[cfg(test)]\nmod tests") {
                Some(i) => &text[..i],
                None => &text[..],
            };
            let code = text
                .lines()
                .filter(|l| !l.trim_start().starts_with("//"))
                .collect::<Vec<_>>()
                .join("\n");
            files.push(SourceFile { module, code });
        }
    }
    files
}

fn is_ident(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The paths of the `use` items of `code` (`a::{b, c::{d as e}}` gives `a::b` and `a::c::d`),
/// and with `public_only`, of its `pub use` items only.
fn use_paths(code: &str, public_only: bool) -> Vec<String> {
    fn expand(prefix: &str, body: &str, out: &mut Vec<String>) {
        let mut depth = 0;
        let mut item = String::new();
        let mut items = Vec::new();
        for c in body.chars() {
            match c {
                '{' => depth += 1,
                '}' => depth -= 1,
                _ => {}
            }
            if c == ',' && depth == 0 {
                items.push(std::mem::take(&mut item));
            } else {
                item.push(c);
            }
        }
        items.push(item);
        for item in items {
            let item = item.trim();
            if let Some(open) = item.find('{') {
                let inner = &item[open + 1..item.rfind('}').unwrap_or(item.len())];
                expand(&format!("{prefix}{}", &item[..open]), inner, out);
            } else if !item.is_empty() {
                let name = item.split(" as ").next().unwrap_or(item).trim();
                out.push(format!("{prefix}{name}"));
            }
        }
    }
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(i) = rest.find("use ") {
        let before = &rest[..i];
        let at_item_start = before
            .chars()
            .next_back()
            .is_none_or(|c| c.is_whitespace() || c == ';' || c == '{' || c == '}');
        let line_start = before.rfind('\n').map_or(0, |n| n + 1);
        let lead = before[line_start..].trim();
        let public = lead.starts_with("pub");
        let after = &rest[i + 4..];
        let Some(end) = after.find(';') else { break };
        if at_item_start && (lead.is_empty() || public) && (public || !public_only) {
            expand("", &after[..end].replace('\n', " "), &mut out);
        }
        rest = &after[end..];
    }
    out
}

/// The paths named inline in `code` that start with `crate`, `super`, `self` or one of
/// `children` (child modules declared in the file).
fn inline_paths(code: &str, children: &BTreeSet<String>) -> Vec<String> {
    let mut out = Vec::new();
    let chars: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < chars.len() {
        if is_ident(chars[i]) && (i == 0 || !(is_ident(chars[i - 1]) || chars[i - 1] == ':')) {
            let start = i;
            while i < chars.len() && (is_ident(chars[i]) || chars[i] == ':') {
                i += 1;
            }
            let path: String = chars[start..i].iter().collect();
            let path = path.trim_end_matches(':');
            let head = path.split("::").next().unwrap_or("");
            if path.contains("::")
                && (["crate", "super", "self"].contains(&head) || children.contains(head))
            {
                out.push(path.to_string());
            }
        } else {
            i += 1;
        }
    }
    out
}

/// The child modules `code` declares (`mod x;`, `pub mod x;`, `pub(crate) mod x;`).
fn child_modules(code: &str) -> BTreeSet<String> {
    code.lines()
        .filter_map(|l| {
            let l = l.trim();
            let l = l
                .strip_prefix("pub(crate) ")
                .or_else(|| l.strip_prefix("pub "))
                .unwrap_or(l);
            let name = l.strip_prefix("mod ")?.strip_suffix(';')?;
            name.chars().all(is_ident).then(|| name.to_string())
        })
        .collect()
}

/// `path` as written in the file of `module` made absolute (from the crate root), or `None`
/// for a path into another crate.
fn absolute(module: &[String], path: &str, children: &BTreeSet<String>) -> Option<Vec<String>> {
    let parts: Vec<String> = path.split("::").map(|p| p.trim().to_string()).collect();
    let head = parts.first()?.as_str();
    Some(match head {
        "crate" => parts[1..].to_vec(),
        "self" => [module, &parts[1..]].concat(),
        "super" => {
            let ups = parts.iter().take_while(|p| *p == "super").count();
            let base = module.get(..module.len().checked_sub(ups)?)?;
            [base, &parts[ups..]].concat()
        }
        _ if children.contains(head) => [module, &parts[..]].concat(),
        _ => return None,
    })
}

/// The file graph: file (its module path joined by `/`) to the files it uses.
fn file_graph() -> Graph {
    let files = source_files();
    let modules: BTreeSet<Vec<String>> = files.iter().map(|f| f.module.clone()).collect();
    // Per file: the names it re-exports (`pub use`) and where they really are.
    let mut reexports: BTreeMap<Vec<String>, BTreeMap<String, Vec<String>>> = BTreeMap::new();
    for f in &files {
        let children = child_modules(&f.code);
        let names = reexports.entry(f.module.clone()).or_default();
        for p in use_paths(&f.code, true) {
            if let Some(abs) = absolute(&f.module, &p, &children) {
                if let Some(last) = abs.last() {
                    names.insert(last.clone(), abs.clone());
                }
            }
        }
    }
    let resolve = |mut abs: Vec<String>| -> Option<Vec<String>> {
        for _ in 0..16 {
            let k = (0..=abs.len())
                .rev()
                .find(|&k| modules.contains(&abs[..k]))?;
            let (file, rest) = abs.split_at(k);
            match rest.first().and_then(|name| reexports.get(file)?.get(name)) {
                Some(target) if target != &abs => abs = [&target[..], &rest[1..]].concat(),
                _ => return Some(file.to_vec()),
            }
        }
        None
    };
    let mut graph = Graph::new();
    for f in &files {
        let children = child_modules(&f.code);
        let targets = graph.entry(f.module.join("/")).or_default();
        let paths = use_paths(&f.code, false)
            .into_iter()
            .chain(inline_paths(&f.code, &children));
        for p in paths {
            let Some(target) = absolute(&f.module, &p, &children).and_then(&resolve) else {
                continue;
            };
            if target != f.module && !target.is_empty() {
                targets.insert(target.join("/"));
            }
        }
    }
    graph
}

/// The folder graph: top-level module to the top-level modules it names.
fn folder_graph() -> Graph {
    let mut graph = Graph::new();
    for f in source_files() {
        let Some(top) = f.module.first() else {
            continue;
        };
        let targets = graph.entry(top.clone()).or_default();
        for path in inline_paths(&f.code, &BTreeSet::new()) {
            if let Some(name) = path.strip_prefix("crate::") {
                let name = name.split("::").next().unwrap_or("");
                // Modules only: `crate::VERSION` names an item of lib.rs, not a folder.
                if name.starts_with(|c: char| c.is_lowercase()) && name != top {
                    targets.insert(name.to_string());
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

/// The arrows of `graph` that lie on a cycle.
fn arrows_on_cycles(graph: &Graph) -> Vec<(String, String)> {
    let mut on_cycles = Vec::new();
    for (from, targets) in graph {
        for to in targets {
            if reaches(graph, to, from) {
                on_cycles.push((from.clone(), to.clone()));
            }
        }
    }
    on_cycles
}

#[test]
fn no_folder_imports_a_folder_that_imports_it_back() {
    let graph = folder_graph();
    assert!(graph.len() > 20, "read {} modules", graph.len());
    assert!(
        graph["render"].contains("gather"),
        "the reader misses `crate::` paths: {graph:?}"
    );
    let cycles = arrows_on_cycles(&graph);
    assert!(cycles.is_empty(), "folder import cycles through {cycles:?}");
}

#[test]
fn no_file_imports_a_file_that_imports_it_back() {
    let graph = file_graph();
    assert!(graph.len() > 80, "read {} files", graph.len());
    // The reader sees `super::` paths, child modules and re-exports: pipeline.rs names its
    // sibling `super::baked::Baked`, and `crate::bake::BakeSettings` (re-exported by
    // bake/mod.rs) is bake/settings.rs.
    assert!(graph["bake/pipeline"].contains("bake/baked"), "{graph:?}");
    assert!(graph["compare"].contains("bake/settings"), "{graph:?}");
    let cycles = arrows_on_cycles(&graph);
    assert!(cycles.is_empty(), "file import cycles through {cycles:?}");
}

#[test]
fn gather_render_and_preview_import_nothing_from_bake_or_reference() {
    let graph = folder_graph();
    for room in ["gather", "render", "preview"] {
        let targets = &graph[room];
        for upper in ["bake", "reference"] {
            assert!(!targets.contains(upper), "{room} imports from {upper}");
        }
    }
}
