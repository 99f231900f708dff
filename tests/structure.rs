//! The shape of the code, checked: every Rust file opens with its `//!` documentation,
//! no crate has a module import cycle, and no function outside the tests spans more than
//! 200 lines (a few named ones excepted while other work holds their files).
//!
//! A crate's modules are its files, found from its roots through `mod NAME;`
//! declarations. Module A imports module B when A's code (its `#[cfg(test)]` modules left
//! out: tests may use anything) names an item of B by a path: `crate::…`, `super::…`,
//! `self::…`, or a child module's name, in a `use` (groups `{…}` expanded) or in an
//! expression. A path resolves to the module that defines the item it names; a name a
//! module imports (`use`, `pub use`) resolves to where it is defined, so a façade that
//! re-exports (`lib.rs`, a folder's `mod.rs`) is not a step of a cycle.
//!
//! One kind of import is not an edge: a module naming what one of its ancestors defines
//! (a parent is its children's namespace: a model file implements the trait its crate's
//! root defines, a section of the scenario compiler fills the types its folder defines).
//! Every other import goes one way: a module that another imports is never imported back,
//! directly or through others.
//!
//! The parser is deliberately small (comments and literals blanked, paths found by their
//! shape); what it cannot see (a path a macro builds, a path through a name imported
//! from a module) it does not count.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The workspace's folder.
fn workspace() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Every `.rs` file under `folder`, skipping build output.
fn rust_files(folder: &Path, found: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(folder) else {
        return;
    };
    let mut entries: Vec<PathBuf> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for path in entries {
        let name = path.file_name().and_then(|n| n.to_str()).unwrap_or("");
        if path.is_dir() {
            if !matches!(name, "target" | ".git" | "node_modules") && !name.starts_with('.') {
                rust_files(&path, found);
            }
        } else if name.ends_with(".rs") {
            found.push(path);
        }
    }
}

#[test]
fn every_rust_file_opens_with_its_module_documentation() {
    let root = workspace();
    let mut files = Vec::new();
    for folder in ["crates", "tests", "benches"] {
        rust_files(&root.join(folder), &mut files);
    }
    assert!(files.len() > 50, "found only {} files", files.len());
    let undocumented: Vec<String> = files
        .iter()
        .filter(|path| {
            let text = std::fs::read_to_string(path).expect("a source file reads");
            !text.starts_with("//!")
        })
        .map(|path| {
            path.strip_prefix(&root)
                .unwrap_or(path)
                .display()
                .to_string()
        })
        .collect();
    assert!(
        undocumented.is_empty(),
        "files that do not open with a `//!` comment saying what they are: {}",
        undocumented.join(", ")
    );
}

/// The line breaks of a blanked comment or literal, so that the stripped text keeps the
/// source's lines.
fn push_lines(out: &mut String, blanked: &str) {
    out.extend(std::iter::repeat_n('\n', blanked.matches('\n').count()));
}

/// Source text with comments, string and character literals blanked (their line breaks
/// kept, so the lines stay; nothing inside them looks like a path).
fn strip(source: &str) -> String {
    let bytes = source.as_bytes();
    let mut out = String::with_capacity(source.len());
    let mut i = 0;
    let word_before =
        |i: usize| i > 0 && (bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_');
    while i < bytes.len() {
        let rest = &source[i..];
        if rest.starts_with("//") {
            let end = rest.find('\n').map_or(bytes.len(), |k| i + k);
            i = end;
            continue;
        }
        if rest.starts_with("/*") {
            // Nested block comments.
            let mut depth = 0;
            let mut j = i;
            while j < bytes.len() {
                if source[j..].starts_with("/*") {
                    depth += 1;
                    j += 2;
                } else if source[j..].starts_with("*/") {
                    depth -= 1;
                    j += 2;
                    if depth == 0 {
                        break;
                    }
                } else {
                    j += 1;
                }
            }
            out.push(' ');
            push_lines(&mut out, &source[i..j.min(bytes.len())]);
            i = j;
            continue;
        }
        // Raw strings r"…", r#"…"#, and byte strings br"…".
        if (rest.starts_with('r') || rest.starts_with("br")) && !word_before(i) {
            let start = if rest.starts_with("br") { 2 } else { 1 };
            let hashes = rest[start..].bytes().take_while(|&b| b == b'#').count();
            if rest[start + hashes..].starts_with('"') {
                let close = format!("\"{}", "#".repeat(hashes));
                let body = i + start + hashes + 1;
                let end = source[body..]
                    .find(&close)
                    .map_or(bytes.len(), |k| body + k + close.len());
                out.push_str("\"\"");
                push_lines(&mut out, &source[i..end]);
                i = end;
                continue;
            }
        }
        if bytes[i] == b'"' {
            let mut j = i + 1;
            while j < bytes.len() && bytes[j] != b'"' {
                j += if bytes[j] == b'\\' { 2 } else { 1 };
            }
            out.push_str("\"\"");
            push_lines(&mut out, &source[i..(j + 1).min(bytes.len())]);
            i = j + 1;
            continue;
        }
        if bytes[i] == b'\'' {
            // A character literal ('a', '\n', '\u{3bc}'), not a lifetime ('a).
            let end = if let Some(escaped) = rest.strip_prefix("'\\") {
                escaped.find('\'').map(|k| i + 2 + k + 1)
            } else {
                let mut chars = rest[1..].char_indices();
                match (chars.next(), chars.next()) {
                    (Some((_, _)), Some((k, '\''))) => Some(i + 1 + k + 1),
                    _ => None,
                }
            };
            if let Some(end) = end {
                out.push_str("' '");
                i = end;
                continue;
            }
        }
        let c = rest.chars().next().expect("not at the end");
        out.push(c);
        i += c.len_utf8();
    }
    out
}

/// The text with every `#[cfg(test)]` item that is a module block (`mod tests { … }`)
/// removed, and the names of the `#[cfg(test)] mod NAME;` declarations.
fn without_tests(text: &str) -> (String, BTreeSet<String>) {
    let mut text = text.to_string();
    let mut test_files = BTreeSet::new();
    let mut from = 0;
    while let Some(k) = text[from..].find("#[cfg(test)]") {
        let at = from + k;
        let after = at + "#[cfg(test)]".len();
        let rest = text[after..].trim_start();
        let rest = rest.strip_prefix("pub(crate)").unwrap_or(rest).trim_start();
        let rest = rest.strip_prefix("pub").unwrap_or(rest).trim_start();
        let Some(declaration) = rest.strip_prefix("mod ") else {
            from = after;
            continue;
        };
        let name: String = declaration
            .trim_start()
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let tail = declaration.trim_start()[name.len()..].trim_start();
        if tail.starts_with(';') {
            test_files.insert(name);
            from = after;
            continue;
        }
        let open = text.len() - tail.len();
        let mut depth = 0;
        let mut end = open;
        for (j, b) in text[open..].bytes().enumerate() {
            match b {
                b'{' => depth += 1,
                b'}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = open + j + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        text.replace_range(at..end, "");
        from = at;
    }
    (text, test_files)
}

/// One module (its path in the crate, empty for the root, is its key): its code.
struct Module {
    code: String,
    /// Child modules declared with `mod NAME;` (test modules included).
    children: BTreeSet<String>,
}

type ModulePath = Vec<String>;

/// The modules of the crate whose root file is `root`.
fn crate_modules(root: &Path) -> BTreeMap<ModulePath, Module> {
    let mut modules = BTreeMap::new();
    let mut pending = vec![(Vec::new(), root.to_path_buf())];
    while let Some((path, file)) = pending.pop() {
        let source = std::fs::read_to_string(&file)
            .unwrap_or_else(|err| panic!("{}: {err}", file.display()));
        let (code, _) = without_tests(&strip(&source));
        let mut children = BTreeSet::new();
        // Where this module's children live: next to a root or mod.rs, else in a folder
        // named after the file.
        let stem = file.file_stem().and_then(|s| s.to_str()).unwrap_or("");
        let folder = if path.is_empty() || stem == "mod" {
            file.parent().expect("a file has a folder").to_path_buf()
        } else {
            file.with_extension("")
        };
        let full = strip(&source);
        for declaration in declarations(&full) {
            let flat = folder.join(format!("{declaration}.rs"));
            let nested = folder.join(&declaration).join("mod.rs");
            let child_file = if flat.exists() {
                flat
            } else if nested.exists() {
                nested
            } else {
                continue;
            };
            children.insert(declaration.clone());
            let mut child = path.clone();
            child.push(declaration);
            pending.push((child, child_file));
        }
        modules.insert(path, Module { code, children });
    }
    modules
}

/// The names of the `mod NAME;` declarations of a module's code.
fn declarations(code: &str) -> Vec<String> {
    let mut names = Vec::new();
    for line in code.lines() {
        let line = line.trim();
        let line = line.strip_prefix("pub(crate) ").unwrap_or(line);
        let line = line.strip_prefix("pub ").unwrap_or(line);
        if let Some(rest) = line.strip_prefix("mod ") {
            if let Some(name) = rest.trim().strip_suffix(';') {
                names.push(name.trim().to_string());
            }
        }
    }
    names
}

/// Whether `c` can be part of an identifier.
fn ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// The byte ranges of a module's `use` items (`use` to its `;`).
fn use_items(code: &str) -> Vec<std::ops::Range<usize>> {
    let mut items = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("use ") {
        let at = from + k;
        from = at + 4;
        if at > 0 && code[..at].chars().next_back().is_some_and(ident_char) {
            continue;
        }
        let Some(end) = code[at..].find(';') else {
            break;
        };
        items.push(at..at + end);
        from = at + end;
    }
    items
}

/// The `use` trees of a module's code, expanded to paths (`a::{b, c::d}` gives `a::b` and
/// `a::c::d`; `a::b as c` gives `a::b`; `self` in a group names the group's module).
fn use_paths(code: &str) -> Vec<Vec<String>> {
    let mut paths = Vec::new();
    for item in use_items(code) {
        let tree: String = code[item.start + 4..item.end]
            .chars()
            .map(|c| if c.is_whitespace() { ' ' } else { c })
            .collect();
        expand(&tree, &mut Vec::new(), &mut paths);
    }
    paths
}

/// Expands one use tree under `prefix`.
fn expand(tree: &str, prefix: &mut Vec<String>, out: &mut Vec<Vec<String>>) {
    let tree = tree.trim();
    let tree = tree.strip_prefix("::").unwrap_or(tree);
    if let Some(open) = tree.find('{') {
        let head: Vec<String> = tree[..open]
            .split("::")
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from)
            .collect();
        let close = tree.rfind('}').unwrap_or(tree.len());
        let inner = &tree[open + 1..close];
        let depth = prefix.len();
        prefix.extend(head);
        // Split the group at top-level commas.
        let mut level = 0;
        let mut start = 0;
        for (j, c) in inner.char_indices() {
            match c {
                '{' => level += 1,
                '}' => level -= 1,
                ',' if level == 0 => {
                    expand(&inner[start..j], prefix, out);
                    start = j + 1;
                }
                _ => {}
            }
        }
        expand(&inner[start..], prefix, out);
        prefix.truncate(depth);
        return;
    }
    let tree = tree.split(" as ").next().unwrap_or("").trim();
    if tree.is_empty() {
        return;
    }
    let mut path = prefix.clone();
    for segment in tree.split("::").map(str::trim) {
        if segment != "self" || path.is_empty() {
            path.push(segment.to_string());
        }
    }
    out.push(path);
}

/// The paths a module's code names outside its `use` items: `crate::…`, `super::…`,
/// `self::…` and `CHILD::…` for its children.
fn expression_paths(code: &str, children: &BTreeSet<String>) -> Vec<Vec<String>> {
    let mut code = code.to_string();
    for item in use_items(&code) {
        code.replace_range(item.clone(), &" ".repeat(item.len()));
    }
    let code = code.as_str();
    let mut paths = Vec::new();
    let chars: Vec<(usize, char)> = code.char_indices().collect();
    let mut k = 0;
    while k < chars.len() {
        let (at, c) = chars[k];
        let starts_word = c.is_alphabetic() || c == '_';
        let after_word = k > 0 && (ident_char(chars[k - 1].1) || chars[k - 1].1 == ':');
        if !starts_word || after_word {
            k += 1;
            continue;
        }
        // The longest run of `ident::ident::…` from here.
        let mut segments = Vec::new();
        let mut j = at;
        loop {
            let ident: String = code[j..].chars().take_while(|&c| ident_char(c)).collect();
            if ident.is_empty() {
                break;
            }
            j += ident.len();
            segments.push(ident);
            if code[j..].starts_with("::") {
                j += 2;
            } else {
                break;
            }
        }
        let first = segments[0].as_str();
        if segments.len() > 1
            && (matches!(first, "crate" | "super" | "self") || children.contains(first))
        {
            paths.push(segments.clone());
        }
        while k < chars.len() && chars[k].0 < j {
            k += 1;
        }
    }
    paths
}

/// The crate's import graph: for each module, the modules whose items its code names.
struct Graph {
    modules: BTreeMap<ModulePath, Module>,
    /// Per module, the names its `use` items bring in (a child sees its parent's, and
    /// `pub use` re-exports them): name → the path it stands for (absolute), and the
    /// modules it glob-imports.
    exports: BTreeMap<ModulePath, (BTreeMap<String, ModulePath>, Vec<ModulePath>)>,
}

impl Graph {
    fn new(modules: BTreeMap<ModulePath, Module>) -> Graph {
        let mut graph = Graph {
            modules,
            exports: BTreeMap::new(),
        };
        let mut exports = BTreeMap::new();
        for (path, module) in &graph.modules {
            let mut names = BTreeMap::new();
            let mut globs = Vec::new();
            for used in use_paths(&module.code) {
                let Some(absolute) = graph.absolute(path, &used) else {
                    continue;
                };
                match used.last().map(String::as_str) {
                    Some("*") => globs.push(absolute[..absolute.len() - 1].to_vec()),
                    Some(name) => {
                        names.insert(name.to_string(), absolute);
                    }
                    None => {}
                }
            }
            exports.insert(path.clone(), (names, globs));
        }
        graph.exports = exports;
        graph
    }

    /// `used`, a path written in module `at`, from the crate root; `None` when it leaves
    /// the crate.
    fn absolute(&self, at: &ModulePath, used: &[String]) -> Option<ModulePath> {
        let mut base = at.clone();
        let mut rest = used;
        match rest.first().map(String::as_str) {
            Some("crate") => {
                base.clear();
                rest = &rest[1..];
            }
            Some("self") => rest = &rest[1..],
            Some("super") => {
                while rest.first().map(String::as_str) == Some("super") {
                    base.pop()?;
                    rest = &rest[1..];
                }
            }
            Some(first) if self.modules.get(at)?.children.contains(first) => {}
            _ => return None,
        }
        base.extend(rest.iter().cloned());
        Some(base)
    }

    /// The module that defines what the absolute path `path` names.
    fn definer(&self, path: &[String], depth: usize) -> ModulePath {
        let mut module: ModulePath = Vec::new();
        let mut k = 0;
        while k < path.len() {
            let mut child = module.clone();
            child.push(path[k].clone());
            if !self.modules.contains_key(&child) {
                break;
            }
            module = child;
            k += 1;
        }
        let Some(name) = path.get(k) else {
            return module;
        };
        if depth > 8 || name == "*" || defines(&self.modules[&module].code, name) {
            return module;
        }
        let (names, globs) = &self.exports[&module];
        if let Some(target) = names.get(name) {
            let mut target = target.clone();
            target.extend(path[k + 1..].iter().cloned());
            return self.definer(&target, depth + 1);
        }
        for glob in globs {
            let mut target = glob.clone();
            target.extend(path[k..].iter().cloned());
            let found = self.definer(&target, depth + 1);
            if found != *glob || defines(&self.modules[glob].code, name) {
                return found;
            }
        }
        module
    }

    /// Each module's imports: the other modules that define what it names.
    fn edges(&self) -> BTreeMap<ModulePath, BTreeSet<ModulePath>> {
        let mut edges = BTreeMap::new();
        for (path, module) in &self.modules {
            let mut targets = BTreeSet::new();
            let named = use_paths(&module.code)
                .into_iter()
                .chain(expression_paths(&module.code, &module.children));
            for used in named {
                let Some(absolute) = self.absolute(path, &used) else {
                    continue;
                };
                let target = self.definer(&absolute, 0);
                let ancestor = path.starts_with(&target);
                if !ancestor {
                    targets.insert(target);
                }
            }
            edges.insert(path.clone(), targets);
        }
        edges
    }
}

/// Whether `code` defines an item called `name`.
fn defines(code: &str, name: &str) -> bool {
    [
        "fn",
        "struct",
        "enum",
        "trait",
        "type",
        "const",
        "static",
        "union",
        "macro_rules!",
    ]
    .iter()
    .any(|keyword| {
        let mut from = 0;
        let needle = format!("{keyword} {name}");
        while let Some(k) = code[from..].find(&needle) {
            let at = from + k;
            let before = code[..at].chars().next_back();
            let after = code[at + needle.len()..].chars().next();
            if !before.is_some_and(ident_char) && !after.is_some_and(ident_char) {
                return true;
            }
            from = at + needle.len();
        }
        false
    })
}

/// The cycles of a graph: its strongly connected components of more than one module
/// (Tarjan), each with one of its loops spelt out.
fn cycles(edges: &BTreeMap<ModulePath, BTreeSet<ModulePath>>) -> Vec<Vec<ModulePath>> {
    struct State<'a> {
        edges: &'a BTreeMap<ModulePath, BTreeSet<ModulePath>>,
        index: BTreeMap<&'a ModulePath, usize>,
        low: BTreeMap<&'a ModulePath, usize>,
        stack: Vec<&'a ModulePath>,
        on_stack: BTreeSet<&'a ModulePath>,
        found: Vec<Vec<ModulePath>>,
    }
    fn visit<'a>(state: &mut State<'a>, v: &'a ModulePath) {
        let n = state.index.len();
        state.index.insert(v, n);
        state.low.insert(v, n);
        state.stack.push(v);
        state.on_stack.insert(v);
        let edges = state.edges;
        for w in edges.get(v).into_iter().flatten() {
            if !state.index.contains_key(w) {
                visit(state, w);
                let low = state.low[v].min(state.low[w]);
                state.low.insert(v, low);
            } else if state.on_stack.contains(w) {
                let low = state.low[v].min(state.index[w]);
                state.low.insert(v, low);
            }
        }
        if state.low[v] == state.index[v] {
            let mut component = Vec::new();
            while let Some(w) = state.stack.pop() {
                state.on_stack.remove(w);
                component.push(w.clone());
                if w == v {
                    break;
                }
            }
            if component.len() > 1 {
                component.sort();
                state.found.push(component);
            }
        }
    }
    let mut state = State {
        edges,
        index: BTreeMap::new(),
        low: BTreeMap::new(),
        stack: Vec::new(),
        on_stack: BTreeSet::new(),
        found: Vec::new(),
    };
    for v in edges.keys() {
        if !state.index.contains_key(v) {
            visit(&mut state, v);
        }
    }
    state.found
}

/// A module's name as its crate writes it.
fn shown(path: &ModulePath) -> String {
    if path.is_empty() {
        "crate".to_string()
    } else {
        path.join("::")
    }
}

/// One loop through a cycle's modules: a → b → … → a.
fn one_loop(
    component: &[ModulePath],
    edges: &BTreeMap<ModulePath, BTreeSet<ModulePath>>,
) -> String {
    let inside: BTreeSet<&ModulePath> = component.iter().collect();
    let start = &component[0];
    // Breadth-first from the start back to it, inside the component.
    let mut previous: BTreeMap<&ModulePath, &ModulePath> = BTreeMap::new();
    let mut queue = std::collections::VecDeque::from([start]);
    while let Some(v) = queue.pop_front() {
        for w in &edges[v] {
            if !inside.contains(w) || previous.contains_key(w) {
                continue;
            }
            previous.insert(w, v);
            if w == start {
                let mut route = vec![shown(start)];
                let mut at = previous[start];
                while at != start {
                    route.push(shown(at));
                    at = previous[at];
                }
                route.push(shown(start));
                route.reverse();
                return route.join(" → ");
            }
            queue.push_back(w);
        }
    }
    component.iter().map(shown).collect::<Vec<_>>().join(", ")
}

/// The root files of every crate of the workspace (its libraries, binaries, integration
/// tests and benches).
fn crate_roots() -> Vec<PathBuf> {
    let root = workspace();
    let mut roots = Vec::new();
    let mut members: Vec<PathBuf> = std::fs::read_dir(root.join("crates"))
        .expect("crates/ lists")
        .flatten()
        .map(|e| e.path())
        .collect();
    members.sort();
    for member in members {
        for file in ["src/lib.rs", "src/main.rs"] {
            if member.join(file).exists() {
                roots.push(member.join(file));
            }
        }
    }
    for file in [
        "tests/lib.rs",
        "tests/integration.rs",
        "benches/lib.rs",
        "benches/throughput.rs",
    ] {
        if root.join(file).exists() {
            roots.push(root.join(file));
        }
    }
    roots
}

#[test]
fn no_crate_has_a_module_import_cycle() {
    let roots = crate_roots();
    assert!(roots.len() >= 8, "found only {} crate roots", roots.len());
    let mut problems = Vec::new();
    for root in roots {
        let graph = Graph::new(crate_modules(&root));
        let edges = graph.edges();
        for component in cycles(&edges) {
            problems.push(format!(
                "{}: {} (the cycle's modules: {})",
                root.strip_prefix(workspace()).unwrap_or(&root).display(),
                one_loop(&component, &edges),
                component.iter().map(shown).collect::<Vec<_>>().join(", ")
            ));
        }
    }
    assert!(
        problems.is_empty(),
        "module import cycles (a module that imports another must not be imported back):\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_cycle_finder_sees_a_cycle_through_a_group_and_a_re_export() {
    let dir = std::env::temp_dir().join(format!("rvtol-structure-{}", std::process::id()));
    let src = dir.join("src");
    std::fs::create_dir_all(src.join("outer")).expect("a scratch folder");
    let write = |name: &str, text: &str| std::fs::write(src.join(name), text).expect("writes");
    write("lib.rs", "//! x\nmod a;\nmod outer;\npub use a::Thing;\n");
    write(
        "a.rs",
        "//! a\nuse crate::outer::{inner::{self, Other}};\n// crate::nothing::here\npub struct Thing;\nfn f() { let _ = \"crate::b\"; }\n",
    );
    write(
        "outer/mod.rs",
        "//! o\npub mod inner;\npub struct Shell;\nfn h() { inner::g(); }\n",
    );
    write(
        "outer/inner.rs",
        "//! i\nuse super::Shell;\npub struct Other;\npub fn g() -> crate::Thing { crate::Thing }\n#[cfg(test)]\nmod tests { use crate::nothing; }\n",
    );
    let graph = Graph::new(crate_modules(&src.join("lib.rs")));
    let edges = graph.edges();
    let found = cycles(&edges);
    std::fs::remove_dir_all(&dir).ok();
    let names: Vec<Vec<String>> = found
        .iter()
        .map(|c| c.iter().map(shown).collect())
        .collect();
    assert_eq!(
        names,
        vec![vec!["a".to_string(), "outer::inner".to_string()]]
    );
    let list = |module: &str| {
        let path: ModulePath = module.split("::").map(String::from).collect();
        edges[&path].iter().map(shown).collect::<Vec<_>>()
    };
    // `outer` calls its child, whose use of `outer::Shell` is no edge (an ancestor's).
    assert_eq!(list("a"), vec!["outer::inner"]);
    assert_eq!(list("outer"), vec!["outer::inner"]);
    assert_eq!(list("outer::inner"), vec!["a"]);
}

/// Most lines a function outside the tests may span, from its `fn` line to its closing
/// brace (its documentation and attributes not counted): a longer one is cut where its
/// code has seams, so that a contributor adds to a function that fits on a few screens.
const MAX_FUNCTION_LINES: usize = 200;

/// Functions allowed beyond [`MAX_FUNCTION_LINES`] for now: (file, function, why). Each
/// names the issue that holds its file; the entry goes when the function is cut. Empty:
/// a function that grows past the limit is cut where its code has seams.
const LONG_FUNCTIONS_ALLOWED: &[(&str, &str, &str)] = &[];

/// Every function of `code` (comments and literals blanked by [`strip`], which keeps the
/// lines) with the lines it spans.
fn function_lengths(code: &str) -> Vec<(String, usize)> {
    let bytes = code.as_bytes();
    let mut found = Vec::new();
    let mut from = 0;
    while let Some(k) = code[from..].find("fn ") {
        let at = from + k;
        from = at + 3;
        if at > 0 && ident_char(code[..at].chars().next_back().expect("not at the start")) {
            continue;
        }
        let name: String = code[at + 3..]
            .trim_start()
            .chars()
            .take_while(|&c| ident_char(c))
            .collect();
        if name.is_empty() {
            continue;
        }
        // The body opens at the first `{` outside parentheses and brackets (an array type
        // `[f64; 6]` has a `;`); a `;` there first is a declaration without a body.
        let mut depth = 0i32;
        let mut open = None;
        for (j, &b) in bytes.iter().enumerate().skip(at) {
            match b {
                b'(' | b'[' => depth += 1,
                b')' | b']' => depth -= 1,
                b'{' if depth == 0 => {
                    open = Some(j);
                    break;
                }
                b';' if depth == 0 => break,
                _ => {}
            }
        }
        let Some(open) = open else {
            continue;
        };
        let mut braces = 0i32;
        let mut close = code.len();
        for (j, &b) in bytes.iter().enumerate().skip(open) {
            match b {
                b'{' => braces += 1,
                b'}' => {
                    braces -= 1;
                    if braces == 0 {
                        close = j;
                        break;
                    }
                }
                _ => {}
            }
        }
        let lines = code[at..close].matches('\n').count() + 1;
        found.push((name, lines));
    }
    found
}

#[test]
fn no_function_outside_the_tests_exceeds_200_lines() {
    let root = workspace();
    let mut files = Vec::new();
    rust_files(&root.join("crates"), &mut files);
    rust_files(&root.join("benches"), &mut files);
    let mut too_long = Vec::new();
    let mut allowed_seen = BTreeSet::new();
    for path in &files {
        let shown = path
            .strip_prefix(&root)
            .unwrap_or(path)
            .display()
            .to_string();
        // Integration tests (a crate's tests/ folder) and test modules in their own file.
        if shown.contains("/tests/") || shown.ends_with("/tests.rs") {
            continue;
        }
        let text = std::fs::read_to_string(path).expect("a source file reads");
        let (code, _) = without_tests(&strip(&text));
        for (name, lines) in function_lengths(&code) {
            if lines <= MAX_FUNCTION_LINES {
                continue;
            }
            if LONG_FUNCTIONS_ALLOWED
                .iter()
                .any(|(file, function, _)| *file == shown && *function == name)
            {
                allowed_seen.insert((shown.clone(), name));
            } else {
                too_long.push(format!("{shown}: fn {name} ({lines} lines)"));
            }
        }
    }
    assert!(
        too_long.is_empty(),
        "functions over {MAX_FUNCTION_LINES} lines (cut them where the code has seams): {}",
        too_long.join(", ")
    );
    // An entry whose function was cut (or renamed) goes.
    let stale: Vec<String> = LONG_FUNCTIONS_ALLOWED
        .iter()
        .filter(|(file, function, _)| {
            !allowed_seen.contains(&(file.to_string(), function.to_string()))
        })
        .map(|(file, function, _)| format!("{file}: fn {function}"))
        .collect();
    assert!(
        stale.is_empty(),
        "allowed long functions that are no longer over {MAX_FUNCTION_LINES} lines (remove their entries): {}",
        stale.join(", ")
    );
}

#[test]
fn the_function_lengths_are_counted_from_fn_to_the_closing_brace() {
    let code = "pub fn short(x: [f64; 6]) -> f64 {\n    x[0]\n}\nfn two() {\n    let f = |a: u8| { a };\n    f(1);\n}\ntrait T { fn declared(&self); }\n";
    assert_eq!(
        function_lengths(code),
        vec![("short".to_string(), 3), ("two".to_string(), 4)]
    );
}
