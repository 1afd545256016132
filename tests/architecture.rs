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
