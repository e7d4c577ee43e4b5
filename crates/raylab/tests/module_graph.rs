//! The library's top-level modules import downward only: they form a DAG. So do the files of
//! every folder of every crate (the library, the command and the Python module), a folder's
//! module file (`mod.rs`, or `name.rs` beside `name/`) counting as one of them, which depends on
//! a file of its folder when it names a path into it or uses a name it re-exports from it.
//!
//! This test reads the library's sources, finds every path that leaves a top-level module
//! (`crate::scene::Scene`, `use crate::{bvh::Bounds, Ray}`, a `super::` that climbs past the
//! module's root), resolves names the crate root re-exports to the module they come from, and
//! fails on any cycle between top-level modules, naming the modules of each cycle and one place
//! (file and line) for every edge in it. Test code (`#[cfg(test)]` items and the files they
//! declare) may import from anywhere and is not counted.
//!
//! It reads source text, not the compiler's resolution, so it knows Rust's paths only as far
//! as this crate writes them: `use` trees, inline paths, `super::` chains and inline modules.
//! `tests::a_cycle_is_found` checks it against a small crate with a cycle given as text.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// One import from a top-level module into another.
#[derive(Debug, Clone, PartialEq, Eq, PartialOrd, Ord)]
struct Edge {
    from: String,
    to: String,
    file: String,
    line: usize,
}

#[test]
fn the_library_modules_form_a_dag() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    collect_rust_files(&root, &root, &mut files);
    assert!(
        files.iter().any(|(path, _)| path == Path::new("lib.rs")),
        "no lib.rs under {}",
        root.display()
    );
    let edges = module_edges(&files);
    // The check must see the crate's real imports: the path tracer uses the BVH's accelerator
    // interface, so an empty graph means the reader is broken, not that the crate is tidy.
    assert!(
        edges.iter().any(|e| e.from == "integrator" && e.to == "accel"),
        "the reader found no import of accel from integrator: {} edges",
        edges.len()
    );
    let cycles = cycles(&edges);
    assert!(cycles.is_empty(), "{}", describe_cycles(&cycles, &edges));
}

#[test]
fn the_files_of_every_folder_form_a_dag() {
    // Inside each folder of each crate (the library, the command, the Python module) the files
    // import downward only: a module file and the files beside it are the nodes, as in
    // `bvh` (bounds, build, node, leaf, traverse, packet, refit, two_level, and the module's
    // own items), one folder at a time.
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut report = Vec::new();
    let mut folders_seen = 0;
    for krate in ["crates/raylab/src", "crates/raylab-cli/src", "python/src"] {
        let root = workspace.join(krate);
        let mut files = Vec::new();
        collect_rust_files(&root, &root, &mut files);
        assert!(!files.is_empty(), "no sources under {}", root.display());
        if krate == "crates/raylab/src" {
            // The reader must see real imports: bvh's traversal reads its nodes.
            let edges = submodule_edges(&files, &["bvh"]);
            assert!(
                edges.iter().any(|e| e.from == "traverse" && e.to == "node"),
                "the reader found no import of bvh::node from bvh::traverse: {} edges",
                edges.len()
            );
        }
        // The library's top level has a test of its own, above.
        let (folders, cycles) = folder_cycles(&files, krate != "crates/raylab/src");
        folders_seen += folders;
        report.extend(cycles.into_iter().map(|cycle| format!("{krate}/{cycle}")));
    }
    assert!(folders_seen > 20, "only {folders_seen} folders found");
    assert!(report.is_empty(), "{}", report.join("\n\n"));
}

/// The cycles between the files of each folder of a crate (and between its top-level modules
/// if `with_root`), one message per folder that has any; and how many folders were read.
fn folder_cycles(files: &[(PathBuf, String)], with_root: bool) -> (usize, Vec<String>) {
    let mut report = Vec::new();
    if with_root {
        let edges = module_edges(files);
        let cycles = cycles(&edges);
        if !cycles.is_empty() {
            report.push(format!("(top level): {}", describe_cycles(&cycles, &edges)));
        }
    }
    let folders = folders(files);
    for folder in &folders {
        let parent: Vec<&str> = folder.iter().map(String::as_str).collect();
        let edges = submodule_edges(files, &parent);
        let cycles = cycles(&edges);
        if !cycles.is_empty() {
            report.push(format!("{}: {}", folder.join("/"), describe_cycles(&cycles, &edges)));
        }
    }
    (folders.len(), report)
}

/// Every module with files under it (`bvh`, `bvh/leaf`, …), the crate root excepted.
fn folders(files: &[(PathBuf, String)]) -> BTreeSet<Vec<String>> {
    let mut folders = BTreeSet::new();
    for (path, _) in files {
        let module = module_path_of(path);
        for n in 1..module.len() {
            folders.insert(module[..n].to_vec());
        }
    }
    folders
}

fn collect_rust_files(root: &Path, dir: &Path, out: &mut Vec<(PathBuf, String)>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|entry| entry.expect("a directory entry").path())
        .collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            collect_rust_files(root, &path, out);
        } else if path.extension().is_some_and(|ext| ext == "rs") {
            let text = std::fs::read_to_string(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let relative = path.strip_prefix(root).expect("under the root").to_path_buf();
            out.push((relative, text));
        }
    }
}

/// The module path of a file relative to `src/`: `lib.rs` (or `main.rs`) is the root (empty), `a.rs` and
/// `a/mod.rs` are `[a]`, `a/b.rs` is `[a, b]`.
fn module_path_of(file: &Path) -> Vec<String> {
    let mut parts: Vec<String> =
        file.iter().map(|part| part.to_string_lossy().into_owned()).collect();
    let last = parts.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    if stem != "mod" && !(parts.is_empty() && (stem == "lib" || stem == "main")) {
        parts.push(stem.to_owned());
    }
    parts
}

/// Every edge between distinct top-level modules, from non-test code.
fn module_edges(files: &[(PathBuf, String)]) -> BTreeSet<Edge> {
    let lib = files
        .iter()
        .find(|(path, _)| path == Path::new("lib.rs") || path == Path::new("main.rs"))
        .map(|(_, text)| strip_comments_and_literals(text))
        .unwrap_or_default();
    let top_modules: BTreeSet<String> =
        files.iter().filter_map(|(path, _)| module_path_of(path).first().cloned()).collect();
    let reexports = root_reexports(&tokens(&lib), &top_modules);

    let test_files = test_files(files);

    let mut edges = BTreeSet::new();
    for (path, text) in files {
        let module = module_path_of(path);
        if module.is_empty() || (1..=module.len()).any(|n| test_files.contains(&module[..n])) {
            continue;
        }
        let clean = strip_comments_and_literals(text);
        for (target, line) in outside_references(&tokens(&clean), &module) {
            let to = if top_modules.contains(&target) {
                Some(target)
            } else {
                reexports.get(&target).cloned()
            };
            if let Some(to) = to
                && to != module[0]
            {
                edges.insert(Edge {
                    from: module[0].clone(),
                    to,
                    file: path.display().to_string(),
                    line,
                });
            }
        }
    }
    edges
}

/// The modules declared by `#[cfg(test)] mod name;`: test code in files of their own.
fn test_files(files: &[(PathBuf, String)]) -> BTreeSet<Vec<String>> {
    let mut test_files = BTreeSet::new();
    for (path, text) in files {
        let module = module_path_of(path);
        for name in test_module_declarations(&tokens(&strip_comments_and_literals(text))) {
            let mut child = module.clone();
            child.push(name);
            test_files.insert(child);
        }
    }
    test_files
}

/// The source text with comments, string and character literals blanked out (newlines kept,
/// so that lines still count).
fn strip_comments_and_literals(text: &str) -> String {
    let chars: Vec<char> = text.chars().collect();
    let mut out = String::with_capacity(text.len());
    let mut i = 0;
    let blank = |c: char| if c == '\n' { '\n' } else { ' ' };
    while i < chars.len() {
        let c = chars[i];
        let next = chars.get(i + 1).copied();
        if c == '/' && next == Some('/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
        } else if c == '/' && next == Some('*') {
            let mut depth = 0;
            while i < chars.len() {
                if chars[i] == '/' && chars.get(i + 1) == Some(&'*') {
                    depth += 1;
                    i += 2;
                } else if chars[i] == '*' && chars.get(i + 1) == Some(&'/') {
                    depth -= 1;
                    i += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    out.push(blank(chars[i]));
                    i += 1;
                }
            }
        } else if c == 'r'
            && (next == Some('"') || next == Some('#'))
            && !chars[..i].last().is_some_and(|p| p.is_alphanumeric() || *p == '_')
        {
            // A raw string r"…" or r#"…"#.
            let mut j = i + 1;
            let mut hashes = 0;
            while chars.get(j) == Some(&'#') {
                hashes += 1;
                j += 1;
            }
            if chars.get(j) != Some(&'"') {
                out.push(c);
                i += 1;
                continue;
            }
            j += 1;
            loop {
                match chars.get(j) {
                    None => break,
                    Some('"') if (1..=hashes).all(|k| chars.get(j + k) == Some(&'#')) => {
                        j += 1 + hashes;
                        break;
                    }
                    Some(&other) => {
                        out.push(blank(other));
                        j += 1;
                    }
                }
            }
            i = j;
        } else if c == '"' {
            i += 1;
            while i < chars.len() && chars[i] != '"' {
                if chars[i] == '\\' {
                    i += 1;
                }
                if let Some(&other) = chars.get(i) {
                    out.push(blank(other));
                }
                i += 1;
            }
            i += 1;
        } else if c == '\'' {
            // A character literal ('x', '\n', '\u{..}'), not a lifetime ('a).
            let close = if next == Some('\\') {
                (i + 2..chars.len().min(i + 12)).find(|&j| chars[j] == '\'')
            } else if chars.get(i + 2) == Some(&'\'') {
                Some(i + 2)
            } else {
                None
            };
            match close {
                Some(end) => i = end + 1,
                None => {
                    out.push(c);
                    i += 1;
                }
            }
        } else {
            out.push(c);
            i += 1;
        }
    }
    out
}

/// A token: an identifier or keyword, `::`, or one punctuation character; with its line.
fn tokens(text: &str) -> Vec<(String, usize)> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut line = 1;
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        if c == '\n' {
            line += 1;
            i += 1;
        } else if c.is_whitespace() {
            i += 1;
        } else if c.is_alphanumeric() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            out.push((chars[start..i].iter().collect(), line));
        } else if c == ':' && chars.get(i + 1) == Some(&':') {
            out.push(("::".to_owned(), line));
            i += 2;
        } else {
            out.push((c.to_string(), line));
            i += 1;
        }
    }
    out
}

/// The index just past the item that starts at `start`: a `;` at brace depth 0, or the brace
/// that closes the first `{` opened at depth 0.
fn item_end(tokens: &[(String, usize)], start: usize) -> usize {
    let mut depth = 0usize;
    let mut i = start;
    while i < tokens.len() {
        match tokens[i].0.as_str() {
            "{" | "(" | "[" => depth += 1,
            "}" | ")" | "]" => {
                depth = depth.saturating_sub(1);
                if depth == 0 && tokens[i].0 == "}" {
                    return i + 1;
                }
            }
            ";" if depth == 0 => return i + 1,
            _ => {}
        }
        i += 1;
    }
    tokens.len()
}

/// Where `#[cfg(test)]` starts at `i`, the index past the attribute.
fn cfg_test_at(tokens: &[(String, usize)], i: usize) -> Option<usize> {
    let pattern = ["#", "[", "cfg", "(", "test", ")", "]"];
    let matches =
        pattern.iter().enumerate().all(|(k, p)| tokens.get(i + k).is_some_and(|(t, _)| t == p));
    matches.then_some(i + pattern.len())
}

/// Names of `#[cfg(test)] mod name;` declarations (test code in a file of its own).
fn test_module_declarations(tokens: &[(String, usize)]) -> Vec<String> {
    let mut names = Vec::new();
    for i in 0..tokens.len() {
        if let Some(mut j) = cfg_test_at(tokens, i) {
            while matches!(tokens.get(j).map(|t| t.0.as_str()), Some("pub" | "(" | "crate" | ")")) {
                j += 1;
            }
            if tokens.get(j).is_some_and(|t| t.0 == "mod")
                && tokens.get(j + 2).is_some_and(|t| t.0 == ";")
            {
                names.push(tokens[j + 1].0.clone());
            }
        }
    }
    names
}

/// What the crate root re-exports: a name to the top-level module it comes from
/// (`pub use bvh::{Bvh, BuildSettings};` maps `Bvh` and `BuildSettings` to `bvh`).
fn root_reexports(
    tokens: &[(String, usize)],
    top_modules: &BTreeSet<String>,
) -> BTreeMap<String, String> {
    let mut map = BTreeMap::new();
    let mut i = 0;
    while i < tokens.len() {
        if tokens[i].0 == "use" {
            let end = item_end(tokens, i);
            let mut j = i + 1;
            if tokens.get(j).is_some_and(|t| t.0 == "crate") {
                j += 2;
            }
            if let Some(module) = tokens.get(j).map(|t| &t.0)
                && top_modules.contains(module)
            {
                // Every name the tree brings in: an identifier followed by `,`, `}` or `;`
                // (or `as NAME`, whose alias is the name).
                for k in j + 1..end {
                    let name = &tokens[k].0;
                    let follows = tokens.get(k + 1).map(|t| t.0.as_str());
                    let is_name = name.chars().all(|c| c.is_alphanumeric() || c == '_')
                        && name != "self"
                        && matches!(follows, Some("," | "}" | ";"));
                    if is_name {
                        map.insert(name.clone(), module.clone());
                    }
                }
            }
            i = end;
        } else {
            i += 1;
        }
    }
    map
}

/// Every name that a path in this module's non-test code reaches at the crate root, with its
/// line: `crate::a`, `crate::{a, b::c}`, and `super::…` chains that climb to the root.
fn outside_references(tokens: &[(String, usize)], module: &[String]) -> Vec<(String, usize)> {
    absolute_references(tokens, module)
        .into_iter()
        .filter_map(|(path, line)| path.first().map(|first| (first.clone(), line)))
        .collect()
}

/// Every path in this module's non-test code that starts at the crate root (`crate::…`),
/// climbs with `super::…` or starts at the module itself (`self::…`, outside a `pub use`
/// re-export), as the absolute path it names (`use crate::{a, b::{c, d}}` gives `[a]`,
/// `[b, c]` and `[b, d]`), with its line.
fn absolute_references(tokens: &[(String, usize)], module: &[String]) -> Vec<(Vec<String>, usize)> {
    let mut out = Vec::new();
    // The module path at each point: the file's, plus inline `mod name { … }` blocks.
    let mut inline: Vec<(String, usize)> = Vec::new(); // (name, brace depth it closes at)
    let mut depth = 0usize;
    let mut i = 0;
    while i < tokens.len() {
        if let Some(after) = cfg_test_at(tokens, i) {
            i = item_end(tokens, after);
            continue;
        }
        let token = tokens[i].0.as_str();
        match token {
            "{" => depth += 1,
            "}" => {
                depth = depth.saturating_sub(1);
                if inline.last().is_some_and(|(_, d)| *d == depth) {
                    inline.pop();
                }
            }
            "mod" if tokens.get(i + 2).is_some_and(|t| t.0 == "{") => {
                inline.push((tokens[i + 1].0.clone(), depth));
            }
            _ => {}
        }
        let preceded_by_path = i > 0 && tokens[i - 1].0 == "::";
        let reexport =
            i >= 2 && tokens[i - 1].0 == "use" && matches!(tokens[i - 2].0.as_str(), "pub" | ")");
        let starts_here = token == "self"
            && tokens.get(i + 1).is_some_and(|t| t.0 == "::")
            && !(preceded_by_path || reexport);
        if (token == "crate" || token == "super") && !preceded_by_path || starts_here {
            // Climb: `crate` goes to the root; each `super` one level up; `self` stays.
            let here: Vec<String> =
                module.iter().cloned().chain(inline.iter().map(|(name, _)| name.clone())).collect();
            let mut level = here.len();
            let mut j = i;
            if token == "crate" {
                level = 0;
                j += 1;
            } else if token == "self" {
                j += 1;
            } else {
                while tokens.get(j).is_some_and(|t| t.0 == "super") {
                    level = level.saturating_sub(1);
                    j += 1;
                    if tokens.get(j).is_some_and(|t| t.0 == "::") {
                        j += 1;
                    } else {
                        break;
                    }
                }
                j -= 1; // back onto the `::` (or the last `super`)
            }
            if tokens.get(j).is_some_and(|t| t.0 == "::") {
                for (path, line) in tree_paths(tokens, j + 1) {
                    if !path.is_empty() || level > 0 {
                        let mut absolute = here[..level].to_vec();
                        absolute.extend(path);
                        out.push((absolute, line));
                    }
                }
            }
        }
        i += 1;
    }
    out
}

/// The paths of the use tree or path that starts at `start` (just after a `::`): `a::b` gives
/// `[a, b]`; `{a, b::{c, self}}` gives `[a]`, `[b, c]` and `[b]`. A path ends at anything that
/// is not an identifier followed by `::` (generics, calls, `as`, `;`).
fn tree_paths(tokens: &[(String, usize)], start: usize) -> Vec<(Vec<String>, usize)> {
    let is_ident =
        |t: &str| t.chars().next().is_some_and(|c| c.is_alphabetic() || c == '_') && t != "as";
    let mut segments = Vec::new();
    let mut j = start;
    while let Some((token, line)) = tokens.get(j) {
        if token == "{" {
            // A group: each top-level entry, after these segments.
            let end = item_end(tokens, j).saturating_sub(1); // the closing brace
            let mut out = Vec::new();
            let mut entry = j + 1;
            let mut nesting = 0;
            for k in j + 1..=end {
                match tokens[k].0.as_str() {
                    "{" => nesting += 1,
                    "}" if nesting > 0 => nesting -= 1,
                    "," | "}" if nesting == 0 => {
                        if entry < k {
                            for (path, line) in tree_paths(&tokens[..k], entry) {
                                let mut full = segments.clone();
                                full.extend(path.into_iter().filter(|s| s != "self"));
                                out.push((full, line));
                            }
                        }
                        entry = k + 1;
                    }
                    _ => {}
                }
            }
            return out;
        }
        if !is_ident(token) {
            break;
        }
        segments.push(token.clone());
        if tokens.get(j + 1).is_some_and(|t| t.0 == "::") {
            j += 2;
        } else {
            return vec![(segments, *line)];
        }
    }
    let line = tokens.get(start).map_or(0, |t| t.1);
    if segments.is_empty() { Vec::new() } else { vec![(segments, line)] }
}

/// Edges between the submodules of `parent` (`["bvh"]`): the same reading as for the top-level
/// modules, one level down. The parent's own file is a node of its own, named `parent (mod.rs)`,
/// for the items it defines; its `pub use` re-exports make no edges (a name it re-exports counts
/// as the submodule it comes from), its other paths into its submodules (`use node::WideBvh`,
/// `traverse::closest_hit(..)`) do.
fn submodule_edges(files: &[(PathBuf, String)], parent: &[&str]) -> BTreeSet<Edge> {
    let parent: Vec<String> = parent.iter().map(|s| (*s).to_owned()).collect();
    let own = format!("{} (mod.rs)", parent.join("::"));
    let children: BTreeSet<String> = files
        .iter()
        .map(|(path, _)| module_path_of(path))
        .filter(|m| m.len() > parent.len() && m.starts_with(&parent))
        .map(|m| m[parent.len()].clone())
        .collect();
    let parent_tokens = files
        .iter()
        .find(|(path, _)| module_path_of(path) == parent)
        .map(|(_, text)| tokens(&strip_comments_and_literals(text)))
        .unwrap_or_default();
    let reexports = submodule_reexports(&parent_tokens, &children);
    // A path to a name the crate root re-exports (`crate::Bvh`) goes where the name comes
    // from (`crate::bvh::Bvh`).
    let top_modules: BTreeSet<String> =
        files.iter().filter_map(|(path, _)| module_path_of(path).first().cloned()).collect();
    let root_tokens = files
        .iter()
        .find(|(path, _)| module_path_of(path).is_empty())
        .map(|(_, text)| tokens(&strip_comments_and_literals(text)))
        .unwrap_or_default();
    let root_names = root_reexports(&root_tokens, &top_modules);
    let test_files = test_files(files);
    let mut edges = BTreeSet::new();
    for (path, text) in files {
        let module = module_path_of(path);
        if !module.starts_with(&parent)
            || (1..=module.len()).any(|n| test_files.contains(&module[..n]))
        {
            continue;
        }
        let from = module.get(parent.len()).cloned().unwrap_or_else(|| own.clone());
        let clean = tokens(&strip_comments_and_literals(text));
        let mut targets: Vec<(String, usize)> = absolute_references(&clean, &module)
            .into_iter()
            .map(|(absolute, line)| match absolute.first().and_then(|n| root_names.get(n)) {
                Some(module) if !top_modules.contains(&absolute[0]) => {
                    (std::iter::once(module.clone()).chain(absolute).collect(), line)
                }
                _ => (absolute, line),
            })
            .filter(|(absolute, _)| absolute.len() > parent.len() && absolute.starts_with(&parent))
            .map(|(absolute, line)| (absolute[parent.len()].clone(), line))
            .collect();
        if module == parent {
            targets.extend(relative_child_paths(&clean, &children));
            targets.extend(reexported_name_uses(&clean, &reexports));
        }
        for (name, line) in targets {
            let to = if children.contains(&name) {
                name
            } else {
                reexports.get(&name).cloned().unwrap_or_else(|| own.clone())
            };
            if to != from {
                edges.insert(Edge {
                    from: from.clone(),
                    to,
                    file: path.display().to_string(),
                    line,
                });
            }
        }
    }
    edges
}

/// What a module file re-exports from its submodules (`pub use node::{A, B};`, also
/// `pub(crate)`): a name to the submodule it comes from.
fn submodule_reexports(
    tokens: &[(String, usize)],
    children: &BTreeSet<String>,
) -> BTreeMap<String, String> {
    let mut map = BTreeMap::new();
    for (i, _) in tokens.iter().enumerate().filter(|(_, t)| t.0 == "use") {
        if i > 0 && (tokens[i - 1].0 == "pub" || tokens[i - 1].0 == ")") {
            let after =
                if tokens.get(i + 1).is_some_and(|t| t.0 == "self") { i + 3 } else { i + 1 };
            for (path, _) in tree_paths(tokens, after) {
                if let (Some(child), Some(name)) = (path.first(), path.last())
                    && children.contains(child)
                {
                    map.insert(name.clone(), child.clone());
                }
            }
        }
    }
    map
}

/// Paths from a module file into its own submodules by their bare names (`use node::X`,
/// `traverse::f(..)`), outside `pub use` re-exports, `mod` declarations and test code.
fn relative_child_paths(
    tokens: &[(String, usize)],
    children: &BTreeSet<String>,
) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        if let Some(after) = cfg_test_at(tokens, i) {
            i = item_end(tokens, after);
            continue;
        }
        let token = tokens[i].0.as_str();
        let reexport = token == "use" && i > 0 && matches!(tokens[i - 1].0.as_str(), "pub" | ")");
        if reexport || token == "mod" && tokens.get(i + 2).is_some_and(|t| t.0 == ";") {
            i = item_end(tokens, i);
            continue;
        }
        let preceded_by_path = i > 0 && tokens[i - 1].0 == "::";
        if children.contains(token)
            && !preceded_by_path
            && tokens.get(i + 1).is_some_and(|t| t.0 == "::")
        {
            out.push((token.to_owned(), tokens[i].1));
        }
        i += 1;
    }
    out
}

/// Where a module file's own code (outside `use` lines, `mod` declarations and test code) names
/// an item it re-exports from one of its submodules (`pub use keyframes::Keyframe;` then
/// `keyframes: Vec<Keyframe>`): the submodule it comes from, with the line. Such a use depends
/// on that submodule as much as a path into it does.
fn reexported_name_uses(
    tokens: &[(String, usize)],
    reexports: &BTreeMap<String, String>,
) -> Vec<(String, usize)> {
    let mut out = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        if let Some(after) = cfg_test_at(tokens, i) {
            i = item_end(tokens, after);
            continue;
        }
        let token = tokens[i].0.as_str();
        if token == "use" || token == "mod" && tokens.get(i + 2).is_some_and(|t| t.0 == ";") {
            i = item_end(tokens, i);
            continue;
        }
        let preceded_by_path = i > 0 && tokens[i - 1].0 == "::";
        if let Some(child) = reexports.get(token)
            && !preceded_by_path
        {
            out.push((child.clone(), tokens[i].1));
        }
        i += 1;
    }
    out
}

/// The cycles: each strongly connected component of more than one module (Tarjan's
/// algorithm), its modules sorted.
fn cycles(edges: &BTreeSet<Edge>) -> Vec<Vec<String>> {
    let mut graph: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
    for edge in edges {
        graph.entry(&edge.from).or_default().insert(&edge.to);
        graph.entry(&edge.to).or_default();
    }
    let nodes: Vec<&str> = graph.keys().copied().collect();

    struct Tarjan<'a> {
        graph: &'a BTreeMap<&'a str, BTreeSet<&'a str>>,
        index: BTreeMap<&'a str, usize>,
        low: BTreeMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on_stack: BTreeSet<&'a str>,
        components: Vec<Vec<String>>,
    }
    impl<'a> Tarjan<'a> {
        fn visit(&mut self, node: &'a str) {
            let n = self.index.len();
            self.index.insert(node, n);
            self.low.insert(node, n);
            self.stack.push(node);
            self.on_stack.insert(node);
            for &next in &self.graph[node] {
                if !self.index.contains_key(next) {
                    self.visit(next);
                    let low = self.low[node].min(self.low[next]);
                    self.low.insert(node, low);
                } else if self.on_stack.contains(next) {
                    let low = self.low[node].min(self.index[next]);
                    self.low.insert(node, low);
                }
            }
            if self.low[node] == self.index[node] {
                let mut component = Vec::new();
                loop {
                    let member = self.stack.pop().expect("on the stack");
                    self.on_stack.remove(member);
                    component.push(member.to_owned());
                    if member == node {
                        break;
                    }
                }
                if component.len() > 1 {
                    component.sort();
                    self.components.push(component);
                }
            }
        }
    }
    let mut tarjan = Tarjan {
        graph: &graph,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        components: Vec::new(),
    };
    for node in nodes {
        if !tarjan.index.contains_key(node) {
            tarjan.visit(node);
        }
    }
    tarjan.components.sort();
    tarjan.components
}

/// A failure message: each cycle's modules and, for each edge inside it, one place it is made.
fn describe_cycles(cycles: &[Vec<String>], edges: &BTreeSet<Edge>) -> String {
    let mut message = format!("{} import cycle(s) between modules of src/:", cycles.len());
    for cycle in cycles {
        message.push_str(&format!("\n\ncycle: {}", cycle.join(", ")));
        let mut seen = BTreeSet::new();
        for edge in edges {
            if cycle.contains(&edge.from)
                && cycle.contains(&edge.to)
                && seen.insert((&edge.from, &edge.to))
            {
                message.push_str(&format!(
                    "\n  {} -> {}  ({}:{})",
                    edge.from, edge.to, edge.file, edge.line
                ));
            }
        }
    }
    message
}

mod tests {
    use super::*;

    fn crate_of(files: &[(&str, &str)]) -> Vec<(PathBuf, String)> {
        files.iter().map(|(path, text)| (PathBuf::from(path), (*text).to_owned())).collect()
    }

    #[test]
    fn a_cycle_is_found() {
        // a → b by a re-exported name, b → c by a grouped use, c → a by `super::` from a
        // nested file; d → a is outside the cycle.
        let files = crate_of(&[
            (
                "lib.rs",
                "pub mod a; pub mod b; pub mod c; pub mod d;\npub use b::{Thing, Other as O};",
            ),
            ("a.rs", "use crate::Thing;\n"),
            ("b/mod.rs", "mod inner;\n"),
            ("b/inner.rs", "use crate::{c::{X, Y}, float};\n"),
            ("c/mod.rs", "mod deep;"),
            ("c/deep.rs", "fn f() { super::super::a::g() }"),
            ("d.rs", "use crate::a::g;"),
        ]);
        let edges = module_edges(&files);
        let found = cycles(&edges);
        assert_eq!(found, vec![vec!["a".to_owned(), "b".to_owned(), "c".to_owned()]]);
        let message = describe_cycles(&found, &edges);
        assert!(message.contains("c -> a  (c/deep.rs:1)"), "{message}");
        assert!(message.contains("b -> c  (b/inner.rs:1)"), "{message}");
    }

    #[test]
    fn test_code_comments_and_strings_make_no_edges() {
        let files = crate_of(&[
            ("lib.rs", "pub mod a; pub mod b;"),
            ("a.rs", "use crate::b::B;\n#[cfg(test)]\nmod tests;\n"),
            ("a/tests.rs", "use crate::b::x;"),
            (
                "b.rs",
                "// use crate::a::A;\n/* crate::a */\nconst S: &str = \"crate::a::A\";\n\
                 const R: &str = r#\"crate::a\"#;\nfn f<'a>(c: &'a char) -> bool { *c == '{' }\n\
                 #[cfg(test)]\nmod tests { use crate::a::A; }\n",
            ),
        ]);
        let edges = module_edges(&files);
        assert_eq!(
            edges.iter().map(|e| (e.from.as_str(), e.to.as_str())).collect::<Vec<_>>(),
            vec![("a", "b")]
        );
        assert!(cycles(&edges).is_empty());
    }

    #[test]
    fn inline_modules_and_super_stay_inside() {
        // `super::` from an inline module of a nested file stays in the top-level module; one
        // more `super` would leave it.
        let files = crate_of(&[
            ("lib.rs", "pub mod a; pub mod b;"),
            ("a/mod.rs", "mod x;"),
            ("a/x.rs", "mod simd { use super::super::y; fn g() { super::super::super::b::f() } }"),
            ("b.rs", "use super::a::z;"),
        ]);
        let edges = module_edges(&files);
        let pairs: Vec<_> =
            edges.iter().map(|e| (e.from.as_str(), e.to.as_str(), e.line)).collect();
        assert_eq!(pairs, vec![("a", "b", 1), ("b", "a", 1)]);
        assert_eq!(cycles(&edges), vec![vec!["a".to_owned(), "b".to_owned()]]);
    }

    #[test]
    fn a_cycle_between_submodules_is_found() {
        // Inside `p`: x -> y by a re-export of the parent, y -> x through `crate::p::x`, and
        // the parent file's own item reached from z, while the parent uses z by a relative
        // path: two cycles. `pub use` and `mod` lines of the parent make no edges.
        let files = crate_of(&[
            ("lib.rs", "pub mod p; pub mod q;"),
            (
                "p/mod.rs",
                "mod x; mod y; mod z;\npub use y::Thing;\npub struct Own;\nfn f() { z::g() }",
            ),
            ("p/x.rs", "use super::Thing;\nuse crate::q::Q;"),
            ("p/y.rs", "use crate::p::{x::{A, self}, z};"),
            ("p/z.rs", "use super::Own;"),
            ("q.rs", "use crate::p::x::A;"),
        ]);
        let edges = submodule_edges(&files, &["p"]);
        let pairs: Vec<_> = edges.iter().map(|e| (e.from.as_str(), e.to.as_str())).collect();
        assert_eq!(
            pairs,
            vec![("p (mod.rs)", "z"), ("x", "y"), ("y", "x"), ("y", "z"), ("z", "p (mod.rs)")]
        );
        assert_eq!(
            cycles(&edges),
            vec![
                vec!["p (mod.rs)".to_owned(), "z".to_owned()],
                vec!["x".to_owned(), "y".to_owned()]
            ]
        );
    }

    #[test]
    fn a_module_file_using_what_it_reexports_depends_on_that_file() {
        // `p/mod.rs` re-exports `k::K` and its own struct holds one; `k.rs` uses that struct:
        // a circle, although no path in `p/mod.rs` names `k::`. A module file `q.rs` beside a
        // folder `q/` is read the same way.
        let files = crate_of(&[
            ("lib.rs", "pub mod p; pub mod q;"),
            ("p/mod.rs", "mod k;\npub use k::K;\npub struct S {\n    k: K,\n}"),
            ("p/k.rs", "use super::S;\npub struct K;"),
            ("q.rs", "mod r;\npub use r::R;\npub fn f(_: R) {}"),
            ("q/r.rs", "pub struct R;\nfn g() { super::f(R) }"),
        ]);
        let (folders, report) = folder_cycles(&files, false);
        assert_eq!(folders, 2, "p and q");
        assert_eq!(report.len(), 2, "{report:?}");
        assert!(report[0].contains("p (mod.rs) -> k  (p/mod.rs:4)"), "{}", report[0]);
        assert!(report[1].starts_with("q: "), "{}", report[1]);
        // Re-exporting alone, or a child that does not use the module file, is no circle.
        let files = crate_of(&[
            ("lib.rs", "pub mod p;"),
            ("p/mod.rs", "mod k;\npub use k::K;\npub struct S {\n    k: K,\n}"),
            ("p/k.rs", "pub struct K;"),
        ]);
        assert_eq!(folder_cycles(&files, false), (1, Vec::new()));
    }

    #[test]
    fn self_paths_and_the_crate_root_s_reexports_are_followed() {
        // `q.rs` reaches `r` by `self::r`, and `r` uses the module file's `Q`: a circle. In
        // `p`, `x` names `crate::Y`, which the crate root re-exports from `p::y`, and `y`
        // names `x`: a circle although neither path spells the other's file.
        let files = crate_of(&[
            (
                "lib.rs",
                "pub mod p; pub mod q;
pub use p::Y;",
            ),
            (
                "q.rs",
                "mod r;
pub struct Q;
fn f() { self::r::g() }",
            ),
            (
                "q/r.rs",
                "pub fn g() {}
fn h(_: super::Q) {}",
            ),
            (
                "p/mod.rs",
                "mod x; mod y;
pub use y::Y;",
            ),
            (
                "p/x.rs",
                "pub struct X;
fn f(_: crate::Y) {}",
            ),
            (
                "p/y.rs",
                "pub struct Y;
fn g(_: super::x::X) {}",
            ),
        ]);
        let (folders, report) = folder_cycles(&files, false);
        assert_eq!(folders, 2, "p and q");
        assert_eq!(report.len(), 2, "{report:?}");
        assert!(report[0].contains("x -> y  (p/x.rs:2)"), "{}", report[0]);
        assert!(report[1].contains("q (mod.rs) -> r  (q.rs:3)"), "{}", report[1]);
        // A re-export through `self::` is no edge, and neither is a root name from elsewhere.
        let files = crate_of(&[
            (
                "lib.rs",
                "pub mod p; pub mod q;
pub use q::Q;",
            ),
            ("q.rs", "pub struct Q;"),
            (
                "p/mod.rs",
                "mod x; mod y;
pub use self::y::Y;
pub struct P;",
            ),
            ("p/x.rs", "fn f(_: crate::Q, _: super::y::Y) {}"),
            (
                "p/y.rs",
                "pub struct Y;
fn g(_: super::P) {}",
            ),
        ]);
        assert_eq!(folder_cycles(&files, false), (1, Vec::new()));
    }

    #[test]
    fn a_cycle_inside_a_nested_folder_or_a_binary_is_found() {
        // `p/q/x.rs` and `p/q/y.rs` import each other, two folders down; `p/r.rs` and
        // `p/q/x.rs` only import downward.
        let library = crate_of(&[
            ("lib.rs", "pub mod p;"),
            ("p/mod.rs", "mod q; mod r;"),
            ("p/r.rs", "use super::q::x::X;"),
            ("p/q/mod.rs", "mod x; mod y;"),
            ("p/q/x.rs", "use super::y::Y;\npub struct X;"),
            ("p/q/y.rs", "pub struct Y;\nfn f() { crate::p::q::x::g() }"),
        ]);
        let (folders, report) = folder_cycles(&library, false);
        assert_eq!(folders, 2, "p and p/q");
        assert_eq!(report.len(), 1, "{report:?}");
        assert!(report[0].starts_with("p/q: "), "{}", report[0]);
        assert!(report[0].contains("x -> y  (p/q/x.rs:1)"), "{}", report[0]);
        assert!(report[0].contains("y -> x  (p/q/y.rs:2)"), "{}", report[0]);
        // A command's top level, rooted at main.rs.
        let command = crate_of(&[
            ("main.rs", "mod a; mod b;\nfn main() {}"),
            ("a.rs", "use crate::b::B;\npub struct A;"),
            ("b.rs", "pub struct B;\nfn f(_: crate::a::A) {}"),
        ]);
        let (_, report) = folder_cycles(&command, true);
        assert_eq!(report.len(), 1, "{report:?}");
        assert!(report[0].contains("cycle: a, b"), "{}", report[0]);
        // Untied, nothing is reported.
        let untied = crate_of(&[
            ("main.rs", "mod a; mod b;"),
            ("a.rs", "use crate::b::B;"),
            ("b.rs", "pub struct B;"),
        ]);
        assert_eq!(folder_cycles(&untied, true), (0, Vec::new()));
    }
}
