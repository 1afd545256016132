//! ARCHITECTURE.md's import table, enforced: every path into the crate's top-level modules
//! (`crate::X`, `crate::{X, ..}`, and `super::…::X` chains that climb to the crate root) in the
//! code of `src/` (comment lines and `#[cfg(test)]` items and files aside) must name a module
//! its own module's row allows. A failure names the file, the line and the module.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// The table between the markers of ARCHITECTURE.md: module → the modules it may import.
fn import_table() -> BTreeMap<String, BTreeSet<String>> {
    let text = std::fs::read_to_string("ARCHITECTURE.md").expect("ARCHITECTURE.md");
    let start = text
        .find("<!-- import table")
        .expect("ARCHITECTURE.md has an import table");
    let end = text[start..]
        .find("<!-- end of import table -->")
        .expect("the import table ends")
        + start;
    let names = |cell: &str| -> BTreeSet<String> {
        cell.split(',')
            .map(|c| c.trim().trim_matches('`').to_string())
            .filter(|c| !c.is_empty() && c != "—")
            .collect()
    };
    let mut table = BTreeMap::new();
    for line in text[start..end].lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 4 || !cells[1].starts_with('`') {
            continue;
        }
        let module = cells[1].trim_matches('`').to_string();
        assert!(
            table.insert(module.clone(), names(cells[2])).is_none(),
            "ARCHITECTURE.md's import table lists `{module}` twice"
        );
    }
    table
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The files a `#[cfg(test)]` declaration includes (`mod x;`, with or without `#[path]`),
/// and the files any `#[path = ..]` includes with the depth of the including module.
fn included_files(files: &[PathBuf]) -> (BTreeSet<PathBuf>, HashMap<PathBuf, PathBuf>) {
    let mut test_only = BTreeSet::new();
    let mut path_parent = HashMap::new();
    for f in files {
        let text = std::fs::read_to_string(f).unwrap();
        let dir = f.parent().unwrap();
        let own_dir = if f.file_name().unwrap() == "mod.rs" {
            dir.to_path_buf()
        } else {
            dir.join(f.file_stem().unwrap())
        };
        let lines: Vec<&str> = text.lines().map(str::trim).collect();
        for (i, l) in lines.iter().enumerate() {
            let decl = l
                .trim_start_matches("pub(crate) ")
                .trim_start_matches("pub ")
                .strip_prefix("mod ")
                .and_then(|r| r.strip_suffix(';'));
            let Some(name) = decl else { continue };
            let mut attrs = Vec::new();
            let mut j = i;
            while j > 0 && lines[j - 1].starts_with("#[") {
                attrs.push(lines[j - 1]);
                j -= 1;
            }
            let path = attrs.iter().find_map(|a| {
                a.strip_prefix("#[path = \"")
                    .and_then(|r| r.strip_suffix("\"]"))
            });
            let target = match path {
                Some(p) => dir.join(p),
                None if own_dir.join(format!("{name}.rs")).exists() => {
                    own_dir.join(format!("{name}.rs"))
                }
                None => own_dir.join(name).join("mod.rs"),
            };
            if path.is_some() {
                path_parent.insert(target.clone(), f.clone());
            }
            if attrs.iter().any(|a| a.starts_with("#[cfg(test)]")) {
                test_only.insert(target);
            }
        }
    }
    (test_only, path_parent)
}

/// How many `super::` a file's code may climb before it names the crate root.
fn depth(f: &Path, src: &Path, path_parent: &HashMap<PathBuf, PathBuf>) -> usize {
    if let Some(parent) = path_parent.get(f) {
        return depth(parent, src, path_parent) + 1;
    }
    let rel = f.strip_prefix(src).unwrap();
    let parts = rel.components().count();
    if f.file_name().unwrap() == "mod.rs" {
        parts - 1
    } else {
        parts
    }
}

/// The code of `text` without comment lines, `//` tails and `#[cfg(test)]` items, with its
/// line numbers.
fn code_lines(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let lines: Vec<&str> = text.lines().collect();
    let mut i = 0;
    while i < lines.len() {
        let t = lines[i].trim();
        if t.starts_with("#[cfg(test)]") {
            // Skip the item: to its `;` on one line, or to the brace that closes it.
            let mut j = i + 1;
            while j < lines.len() && lines[j].trim().starts_with("#[") {
                j += 1;
            }
            let mut depth = 0i32;
            let mut opened = false;
            while j < lines.len() {
                let l = lines[j].split("//").next().unwrap();
                depth += l.matches('{').count() as i32 - l.matches('}').count() as i32;
                opened |= l.contains('{');
                j += 1;
                if (opened && depth <= 0) || (!opened && l.trim_end().ends_with(';')) {
                    break;
                }
            }
            i = j;
            continue;
        }
        if !t.starts_with("//") {
            out.push((i + 1, lines[i].split("//").next().unwrap().to_string()));
        }
        i += 1;
    }
    out
}

/// The top-level modules a line names: `crate::x`, `crate::{x, y::z}` and `super::` chains
/// of at least `climb` steps.
fn named_modules(line: &str, climb: usize) -> Vec<String> {
    let ident = |s: &str| -> String {
        s.chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
            .collect()
    };
    let mut out = Vec::new();
    let mut roots: Vec<usize> = line.match_indices("crate::").map(|(i, _)| i + 7).collect();
    let supers = "super::".repeat(climb);
    if climb > 0 {
        let mut from = 0;
        while let Some(i) = line[from..].find(&supers) {
            let at = from + i + supers.len();
            if !line[at..].starts_with("super::") {
                roots.push(at);
            }
            from = at;
        }
    }
    for at in roots {
        if at > 7 && line[..at - 7].ends_with("$") {
            continue; // `$crate::` in a macro
        }
        let rest = &line[at..];
        if let Some(group) = rest.strip_prefix('{') {
            let mut level = 0;
            let mut item = String::new();
            for c in group.chars() {
                match c {
                    '{' => level += 1,
                    '}' if level == 0 => break,
                    '}' => level -= 1,
                    ',' if level == 0 => {
                        out.push(ident(item.trim()));
                        item.clear();
                        continue;
                    }
                    _ => {}
                }
                if level == 0 || c != '{' {
                    item.push(c);
                }
            }
            out.push(ident(item.trim()));
        } else {
            out.push(ident(rest));
        }
    }
    out.retain(|m| !m.is_empty() && m != "self");
    out
}

#[test]
fn every_module_imports_only_what_the_architecture_table_allows() {
    let table = import_table();
    let src = Path::new("src");
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let (test_only, path_parent) = included_files(&files);
    let tops: BTreeSet<String> = table.keys().cloned().collect();
    let mut problems = Vec::new();
    let mut seen_tops = BTreeSet::new();
    for f in &files {
        let rel = f.strip_prefix(src).unwrap();
        let top = rel
            .components()
            .next()
            .unwrap()
            .as_os_str()
            .to_string_lossy()
            .trim_end_matches(".rs")
            .to_string();
        if top == "lib" || top == "bin" {
            continue;
        }
        let Some(allowed) = table.get(&top) else {
            problems.push(format!(
                "{}: module `{top}` has no row in ARCHITECTURE.md's import table",
                f.display()
            ));
            continue;
        };
        seen_tops.insert(top.clone());
        let name = f.file_name().unwrap().to_string_lossy();
        if test_only.contains(f) || name.ends_with("_tests.rs") {
            continue;
        }
        let climb = depth(f, src, &path_parent);
        let text = std::fs::read_to_string(f).unwrap();
        for (n, line) in code_lines(&text) {
            for m in named_modules(&line, climb) {
                if m != top && tops.contains(&m) && !allowed.contains(&m) {
                    problems.push(format!(
                        "{}:{n}: `{top}` imports `{m}`, which ARCHITECTURE.md's table does not \
                         allow: {}",
                        f.display(),
                        line.trim()
                    ));
                }
            }
        }
    }
    // Every row is a real module, and no module lacks a row.
    for m in &tops {
        assert!(
            seen_tops.contains(m),
            "ARCHITECTURE.md's import table lists `{m}`, which src/ does not have"
        );
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_import_scanner_finds_grouped_nested_and_climbing_paths() {
    // The scanner itself, on lines written to break it: a test that cannot fail is worth
    // nothing, so it must see each of these.
    assert_eq!(
        named_modules("use crate::render::Visibility;", 0),
        ["render"]
    );
    assert_eq!(
        named_modules("use crate::{field::X, render::{a, b}, trace};", 0),
        ["field", "render", "trace"]
    );
    assert_eq!(
        named_modules(
            "let t = crate::trace::Tracer::new(&crate::geometry::x());",
            0
        ),
        ["trace", "geometry"]
    );
    assert_eq!(named_modules("use super::super::render::X;", 2), ["render"]);
    assert!(named_modules("use super::super::render::X;", 3).is_empty());
    assert!(named_modules("use super::render::X;", 2).is_empty());
    let code = code_lines(
        "use crate::a;\n// use crate::b;\n#[cfg(test)]\nmod tests {\n    use crate::c;\n}\nuse crate::d; // crate::e\n",
    );
    let names: Vec<String> = code.iter().flat_map(|(_, l)| named_modules(l, 0)).collect();
    assert_eq!(names, ["a", "d"]);
}

/// The module a file under `src/` is: `experiment/run/mod.rs` → `experiment::run`,
/// `experiment/spec/mesh.rs` → `experiment::spec::mesh`.
fn module_path(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    let file = parts.pop().unwrap();
    let stem = file.trim_end_matches(".rs");
    if stem != "mod" && stem != "lib" {
        parts.push(stem.to_string());
    }
    parts
}

/// The paths of a `use` tree (or a plain path) at the start of `s`, relative to where it
/// starts, `{…}` groups expanded: `a::{b::C, d}` gives `a::b::C` and `a::d`.
fn use_tree(s: &str) -> Vec<Vec<String>> {
    fn tree(s: &[char], i: &mut usize) -> Vec<Vec<String>> {
        let mut prefix = Vec::new();
        loop {
            while *i < s.len() && s[*i].is_whitespace() {
                *i += 1;
            }
            if *i < s.len() && s[*i] == '{' {
                *i += 1;
                let mut out = Vec::new();
                loop {
                    while *i < s.len() && (s[*i].is_whitespace() || s[*i] == ',') {
                        *i += 1;
                    }
                    if *i >= s.len() {
                        break;
                    }
                    if s[*i] == '}' {
                        *i += 1;
                        break;
                    }
                    let start = *i;
                    for mut p in tree(s, i) {
                        let mut full = prefix.clone();
                        full.append(&mut p);
                        out.push(full);
                    }
                    // Skip what the item leaves (`as x`) up to its comma or the brace.
                    let mut depth = 0;
                    while *i < s.len() && (depth > 0 || (s[*i] != ',' && s[*i] != '}')) {
                        match s[*i] {
                            '{' => depth += 1,
                            '}' => depth -= 1,
                            _ => {}
                        }
                        *i += 1;
                    }
                    if *i == start {
                        *i += 1;
                    }
                }
                return out;
            }
            let start = *i;
            while *i < s.len() && (s[*i].is_ascii_alphanumeric() || s[*i] == '_') {
                *i += 1;
            }
            if *i == start {
                break;
            }
            prefix.push(s[start..*i].iter().collect());
            if s[*i..].starts_with(&[':', ':']) {
                *i += 2;
            } else {
                break;
            }
        }
        vec![prefix]
    }
    let chars: Vec<char> = s.chars().collect();
    tree(&chars, &mut 0)
}

/// Every path `text` names through `crate::`, `self::` or `super::`, resolved against the
/// module `module` to a path from the crate root, with the byte offset it starts at.
fn resolved_paths(text: &str, module: &[String]) -> Vec<(usize, Vec<String>)> {
    let mut out = Vec::new();
    for root in ["crate::", "super::", "self::"] {
        for (at, _) in text.match_indices(root) {
            let before = text[..at].chars().last();
            if before.is_some_and(|c| c.is_ascii_alphanumeric() || "_$:".contains(c)) {
                continue; // `$crate::`, or the second `super::` of a chain
            }
            for p in use_tree(&text[at..]) {
                let mut base: Vec<String> = match p.first().map(String::as_str) {
                    Some("crate") => Vec::new(),
                    _ => module.to_vec(),
                };
                let mut rest = p.as_slice();
                if rest.first().is_some_and(|s| s == "crate" || s == "self") {
                    rest = &rest[1..];
                }
                while rest.first().is_some_and(|s| s == "super") {
                    base.pop();
                    rest = &rest[1..];
                }
                base.extend(rest.iter().filter(|s| *s != "self").cloned());
                out.push((at, base));
            }
        }
    }
    out
}

/// The strongly connected components of a graph with more than one node (Tarjan).
fn cycles(edges: &BTreeMap<String, BTreeSet<String>>) -> Vec<BTreeSet<String>> {
    struct T<'a> {
        edges: &'a BTreeMap<String, BTreeSet<String>>,
        index: HashMap<&'a str, usize>,
        low: HashMap<&'a str, usize>,
        stack: Vec<&'a str>,
        on: BTreeSet<&'a str>,
        out: Vec<BTreeSet<String>>,
    }
    fn visit<'a>(t: &mut T<'a>, v: &'a str) {
        let n = t.index.len();
        t.index.insert(v, n);
        t.low.insert(v, n);
        t.stack.push(v);
        t.on.insert(v);
        let edges = t.edges;
        for w in edges.get(v).into_iter().flatten() {
            let w = w.as_str();
            if !t.index.contains_key(w) {
                visit(t, w);
                let l = t.low[v].min(t.low[w]);
                t.low.insert(v, l);
            } else if t.on.contains(w) {
                let l = t.low[v].min(t.index[w]);
                t.low.insert(v, l);
            }
        }
        if t.low[v] == t.index[v] {
            let mut comp = BTreeSet::new();
            loop {
                let w = t.stack.pop().unwrap();
                t.on.remove(w);
                comp.insert(w.to_string());
                if w == v {
                    break;
                }
            }
            if comp.len() > 1 {
                t.out.push(comp);
            }
        }
    }
    let mut t = T {
        edges,
        index: HashMap::new(),
        low: HashMap::new(),
        stack: Vec::new(),
        on: BTreeSet::new(),
        out: Vec::new(),
    };
    for v in edges.keys() {
        if !t.index.contains_key(v.as_str()) {
            visit(&mut t, v);
        }
    }
    t.out
}

/// The folders whose sub-modules must not import each other in a cycle.
const LAYERED: &[&str] = &["experiment", "gpu"];

/// A module graph: each module and the modules it imports.
type Graph = BTreeMap<String, BTreeSet<String>>;
/// The places (`file:line`) that make each edge of a [`Graph`].
type Places = BTreeMap<(String, String), Vec<String>>;

/// The imports among the sub-modules of each [`LAYERED`] folder (`experiment::kinds` →
/// `experiment::spec`), from the code of `src/` (comments and tests aside), each edge with
/// the places that make it.
fn sub_module_edges() -> (Graph, Places) {
    let src = Path::new("src");
    let mut files = Vec::new();
    rust_files(src, &mut files);
    files.sort();
    let (test_only, _) = included_files(&files);
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let mut why: BTreeMap<(String, String), Vec<String>> = BTreeMap::new();
    for parent in LAYERED {
        let dir = src.join(parent);
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            if name != "mod" && (p.is_dir() || p.extension().is_some_and(|x| x == "rs")) {
                edges.entry(format!("{parent}::{name}")).or_default();
            }
        }
    }
    for f in &files {
        let name = f.file_name().unwrap().to_string_lossy();
        if test_only.contains(f) || name.ends_with("_tests.rs") {
            continue;
        }
        let rel = f.strip_prefix(src).unwrap();
        let module = module_path(rel);
        if module.len() < 2 || !LAYERED.contains(&module[0].as_str()) {
            continue;
        }
        let from = format!("{}::{}", module[0], module[1]);
        let text = std::fs::read_to_string(f).unwrap();
        let lines = code_lines(&text);
        let mut joined = String::new();
        let mut starts = Vec::new();
        for (n, l) in &lines {
            starts.push((joined.len(), *n));
            joined.push_str(l);
            joined.push('\n');
        }
        for (at, path) in resolved_paths(&joined, &module) {
            if path.len() < 2 || path[0] != module[0] {
                continue;
            }
            let to = format!("{}::{}", path[0], path[1]);
            if to == from || !edges.contains_key(&to) {
                continue;
            }
            let line = starts
                .iter()
                .rev()
                .find(|(o, _)| *o <= at)
                .map_or(0, |s| s.1);
            edges.get_mut(&from).unwrap().insert(to.clone());
            let place = format!("{}:{line}", f.display());
            let places = why.entry((from.clone(), to)).or_default();
            if !places.contains(&place) {
                places.push(place);
            }
        }
    }
    (edges, why)
}

#[test]
fn the_sub_modules_of_experiment_and_gpu_import_each_other_in_no_cycle() {
    let (edges, why) = sub_module_edges();
    let mut problems = Vec::new();
    for comp in cycles(&edges) {
        let mut lines = vec![format!(
            "an import cycle among {}:",
            comp.iter().cloned().collect::<Vec<_>>().join(", ")
        )];
        for a in &comp {
            for b in edges[a].iter().filter(|b| comp.contains(*b)) {
                let places = &why[&(a.clone(), b.clone())];
                lines.push(format!("  {a} → {b} ({})", places.join(", ")));
            }
        }
        problems.push(lines.join("\n"));
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn relief_and_gpu_do_not_import_each_other_and_the_table_has_no_cycle() {
    let table = import_table();
    let edges: BTreeMap<String, BTreeSet<String>> = table
        .iter()
        .map(|(m, allowed)| {
            let to = allowed.iter().filter(|a| table.contains_key(*a)).cloned();
            (m.clone(), to.collect())
        })
        .collect();
    assert!(
        cycles(&edges).is_empty(),
        "ARCHITECTURE.md's import table has a cycle: {:?}",
        cycles(&edges)
    );
    // `gpu` reads relief's height maps; `relief` never names `gpu` (the table, which the test
    // above holds the code to, says so).
    assert!(
        !table["relief"].contains("gpu"),
        "relief may not import gpu"
    );
}

#[test]
fn the_module_resolver_expands_groups_and_climbs_super() {
    let m = |s: &str| -> Vec<String> { s.split("::").map(String::from).collect() };
    let paths = |text: &str, module: &str| -> Vec<String> {
        resolved_paths(text, &m(module))
            .into_iter()
            .map(|(_, p)| p.join("::"))
            .collect()
    };
    assert_eq!(
        module_path(Path::new("experiment/run/mod.rs")),
        m("experiment::run")
    );
    assert_eq!(
        module_path(Path::new("experiment/spec/mesh.rs")),
        m("experiment::spec::mesh")
    );
    assert_eq!(
        paths("use super::{a::X, b};", "experiment::c"),
        ["experiment::a::X", "experiment::b"]
    );
    assert_eq!(
        paths("use super::super::kinds::Kind;", "experiment::run::steps"),
        ["experiment::kinds::Kind"]
    );
    assert_eq!(
        paths(
            "use crate::experiment::{\n    spec::{Spec, self},\n    kinds as k,\n};",
            "gpu::x"
        ),
        [
            "experiment::spec::Spec",
            "experiment::spec",
            "experiment::kinds"
        ]
    );
    assert!(paths("$crate::x::y", "gpu::x").is_empty());
    // A cycle is found, and a chain is not one.
    let g = |pairs: &[(&str, &str)]| {
        let mut e: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
        for (a, b) in pairs {
            e.entry(a.to_string()).or_default().insert(b.to_string());
            e.entry(b.to_string()).or_default();
        }
        e
    };
    assert_eq!(cycles(&g(&[("a", "b"), ("b", "c")])).len(), 0);
    assert_eq!(
        cycles(&g(&[("a", "b"), ("b", "c"), ("c", "a"), ("c", "d")])),
        [["a", "b", "c"].iter().map(|s| s.to_string()).collect()]
    );
}
