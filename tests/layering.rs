//! The source's layering (docs/ARCHITECTURE.md), checked over the files in `src/`: no two
//! files import each other, directly or through others, and no layer imports one above it.
//!
//! An import is a `crate::`, `super::` or `self::` path outside comments, resolved to the
//! longest module path that is a file; a module's paths into its own descendants (its `mod`
//! declarations and re-exports) are not counted. A third check sees what that rule leaves
//! out: a parent module that uses a child (`child::f()`, beyond declaring and re-exporting
//! it) while the child imports the parent (`super::X`) is a pair that import each other too.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

type Module = Vec<String>;

/// What each layer may not import (by module path prefix): the GPU backend sits below the
/// estimators, the estimators below the render driver, the driver below shards, experiments
/// and the program.
#[rustfmt::skip]
const FORBIDDEN: &[(&str, &[&str])] = &[
    ("accel", &["estimators", "render", "shard", "experiments", "gpu", "points", "cli"]),
    // The scene is below the CPU's ray casting, which is below the GPU's: the GPU uploads
    // the CPU's wide BVH as it is (gpu/scene.rs reads accel::wide's layout).
    ("scene", &["accel", "estimators", "render", "shard", "experiments", "gpu", "points", "cli"]),
    ("gpu", &["estimators", "render", "shard", "experiments", "points", "cli"]),
    ("estimators", &["render", "cache", "shard", "experiments", "points", "cli"]),
    ("report", &["estimators", "render", "shard", "experiments", "cli"]),
    ("options", &["render", "shard", "experiments", "cli"]),
    ("render", &["cache", "shard", "experiments", "cli"]),
    ("cache", &["shard", "experiments", "cli"]),
    // The denoiser is image arithmetic over a guide: it knows no scene, ray or estimator.
    ("denoise", &["accel", "scene", "estimators", "render", "shard", "experiments", "gpu", "points", "cli", "cache", "report", "options", "image"]),
];

/// Every `.rs` file under `src/` by its module path (`lib.rs` is the root, `main.rs` is
/// `<main>`, `a/mod.rs` is `a`).
fn modules(src: &Path) -> BTreeMap<Module, PathBuf> {
    let mut files = BTreeMap::new();
    let mut dirs = vec![src.to_path_buf()];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let relative = path.strip_prefix(src).unwrap().with_extension("");
            let mut module: Module = relative
                .iter()
                .map(|p| p.to_string_lossy().into_owned())
                .collect();
            match module.iter().map(String::as_str).collect::<Vec<_>>()[..] {
                ["lib"] => module.clear(),
                ["main"] => module = vec!["<main>".into()],
                [.., "mod"] => {
                    module.pop();
                }
                _ => {}
            }
            files.insert(module, path);
        }
    }
    files
}

/// `text` without its `//` comments (doc comments included).
fn without_comments(text: &str) -> String {
    text.lines()
        .map(|line| line.split_once("//").map_or(line, |(code, _)| code))
        .collect::<Vec<_>>()
        .join("\n")
}

/// `a::{b, c::{d, e}}` as `a::b`, `a::c::d`, `a::c::e`.
fn expand(path: &str) -> Vec<String> {
    let Some(open) = path.find("::{") else {
        return vec![path.to_string()];
    };
    let (head, body) = (&path[..open], &path[open + 3..path.len() - 1]);
    let mut items = vec![];
    let (mut depth, mut item) = (0, String::new());
    for c in body.chars() {
        match c {
            '{' => depth += 1,
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(std::mem::take(&mut item));
                continue;
            }
            _ => {}
        }
        item.push(c);
    }
    items.push(item);
    items
        .iter()
        .map(|i| i.trim())
        .filter(|i| !i.is_empty())
        .flat_map(|i| expand(&format!("{head}::{i}")))
        .collect()
}

/// The `crate::`, `super::` and `self::` paths in `text`, braces expanded.
fn paths(text: &str) -> Vec<String> {
    let text = without_comments(text);
    let bytes = text.as_bytes();
    let mut out = vec![];
    for start in (0..bytes.len()).filter(|&i| text.is_char_boundary(i)) {
        let word = ["crate::", "super::", "self::"]
            .into_iter()
            .find(|w| text[start..].starts_with(w));
        let boundary = start == 0 || !(bytes[start - 1].is_ascii_alphanumeric() || bytes[start - 1] == b'_');
        let (Some(_), true) = (word, boundary) else {
            continue;
        };
        let (mut depth, mut end) = (0, start);
        for (i, c) in text[start..].char_indices() {
            match c {
                '{' => depth += 1,
                '}' if depth == 0 => break,
                '}' => depth -= 1,
                c if depth == 0 && !(c.is_alphanumeric() || c == '_' || c == ':') => break,
                _ => {}
            }
            end = start + i + c.len_utf8();
        }
        let path: String = text[start..end].chars().filter(|c| !c.is_whitespace()).collect();
        out.extend(expand(path.trim_end_matches(':')));
    }
    out
}

/// The module file `path`, used in `module`, names; `None` outside the crate's files.
fn resolve(module: &Module, path: &str, files: &BTreeMap<Module, PathBuf>) -> Option<Module> {
    let parts: Vec<&str> = path.split("::").collect();
    let (mut base, mut rest) = if parts[0] == "crate" {
        (vec![], &parts[1..])
    } else {
        (module.clone(), &parts[..])
    };
    while let Some(first) = rest.first().filter(|p| **p == "super" || **p == "self") {
        if *first == "super" {
            base.pop();
        }
        rest = &rest[1..];
    }
    (0..=rest.len()).rev().find_map(|k| {
        let mut candidate = base.clone();
        candidate.extend(rest[..k].iter().map(|s| s.to_string()));
        files.contains_key(&candidate).then_some(candidate)
    })
}

/// Each module file's imports of other module files.
fn graph(files: &BTreeMap<Module, PathBuf>) -> BTreeMap<Module, BTreeSet<Module>> {
    files
        .iter()
        .map(|(module, path)| {
            let text = std::fs::read_to_string(path).unwrap();
            let targets = paths(&text)
                .iter()
                .filter_map(|p| resolve(module, p, files))
                .filter(|t| t != module)
                // A module's own descendants (its `mod`s and re-exports) do not count.
                .filter(|t| module.first().is_some_and(|m| m == "<main>") || !t.starts_with(module))
                .collect();
            (module.clone(), targets)
        })
        .collect()
}

fn reachable(edges: &BTreeMap<Module, BTreeSet<Module>>, from: &Module) -> BTreeSet<Module> {
    let mut seen = BTreeSet::new();
    let mut stack = vec![from.clone()];
    while let Some(m) = stack.pop() {
        for next in &edges[&m] {
            if seen.insert(next.clone()) {
                stack.push(next.clone());
            }
        }
    }
    seen
}

/// The file of `module`, relative to the crate's root.
fn name(files: &BTreeMap<Module, PathBuf>, module: &Module) -> String {
    let path = &files[module];
    path.strip_prefix(env!("CARGO_MANIFEST_DIR"))
        .unwrap_or(path)
        .display()
        .to_string()
}

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The groups of files that import each other, each as a sorted list of paths.
fn cycles(
    files: &BTreeMap<Module, PathBuf>,
    edges: &BTreeMap<Module, BTreeSet<Module>>,
) -> BTreeSet<Vec<String>> {
    let reach: BTreeMap<&Module, BTreeSet<Module>> = files.keys().map(|m| (m, reachable(edges, m))).collect();
    files
        .keys()
        .filter(|m| reach[m].contains(*m))
        .map(|m| {
            let mut group: Vec<String> = files
                .keys()
                .filter(|other| reach[m].contains(*other) && reach[other].contains(m))
                .map(|other| name(files, other))
                .collect();
            group.sort();
            group
        })
        .collect()
}

#[test]
fn no_file_imports_itself_through_others() {
    let files = modules(&src());
    let edges = graph(&files);
    let cycles = cycles(&files, &edges);
    let listed: Vec<String> = cycles.iter().map(|c| c.join(", ")).collect();
    assert!(
        cycles.is_empty(),
        "files that import each other:\n{}",
        listed.join("\n")
    );
}

#[test]
fn no_layer_imports_one_above_it() {
    let files = modules(&src());
    let edges = graph(&files);
    let mut wrong = vec![];
    for (module, targets) in &edges {
        let Some((layer, above)) = FORBIDDEN
            .iter()
            .find(|(l, _)| module.first().is_some_and(|m| m == l))
        else {
            continue;
        };
        for target in targets {
            if target.first().is_some_and(|t| above.contains(&t.as_str())) {
                wrong.push(format!(
                    "{} ({layer}) imports {}",
                    name(&files, module),
                    name(&files, target)
                ));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports against the layering:\n{}",
        wrong.join("\n")
    );
}

/// The children of `module` (files one level below it) that its code uses, not counting
/// `mod child;` and `pub use child::...` (declaring and re-exporting), by `child::`,
/// `self::child::` or `crate::...::child::` paths.
fn children_used(module: &Module, files: &BTreeMap<Module, PathBuf>) -> BTreeSet<Module> {
    let text = without_comments(&std::fs::read_to_string(&files[module]).unwrap());
    let code: String = text
        .lines()
        .filter(|l| {
            let l = l.trim_start();
            !(l.starts_with("mod ")
                || l.starts_with("pub mod ")
                || l.starts_with("pub use ")
                || l.starts_with("pub(crate) mod "))
        })
        .collect::<Vec<_>>()
        .join("\n");
    files
        .keys()
        .filter(|c| c.len() == module.len() + 1 && c.starts_with(module))
        .filter(|child| {
            let name = child.last().unwrap();
            let pattern = format!("{name}::");
            code.match_indices(&pattern).any(|(at, _)| {
                let before = &code[..at];
                let prefix_ok = before.ends_with("self::")
                    || before.ends_with(&format!("{}::", module.last().map_or("crate", String::as_str)))
                    || !before.ends_with("::");
                let boundary = before
                    .chars()
                    .next_back()
                    .is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
                prefix_ok && boundary
            })
        })
        .cloned()
        .collect()
}

/// Whether `child`'s code imports `parent`, not counting its inline test module (whose
/// `super::` is the child itself).
fn imports_parent(child: &Module, parent: &Module, files: &BTreeMap<Module, PathBuf>) -> bool {
    let text = std::fs::read_to_string(&files[child]).unwrap();
    let code = text.split("#[cfg(test)]\nmod ").next().unwrap_or(&text);
    paths(code)
        .iter()
        .any(|p| resolve(child, p, files).as_ref() == Some(parent))
}

/// Pairs of a parent module and a child that import each other ([`children_used`] one way,
/// [`imports_parent`] the other), as file names.
fn parent_child_pairs(files: &BTreeMap<Module, PathBuf>) -> Vec<String> {
    files
        .keys()
        .flat_map(|parent| {
            children_used(parent, files)
                .into_iter()
                .filter(|child| imports_parent(child, parent, files))
                .map(|child| format!("{} and {}", name(files, parent), name(files, &child)))
                .collect::<Vec<_>>()
        })
        .collect()
}

#[test]
fn no_parent_and_child_import_each_other() {
    let files = modules(&src());
    let pairs = parent_child_pairs(&files);
    assert!(
        pairs.is_empty(),
        "a parent and a child that import each other:\n{}",
        pairs.join("\n")
    );
}

/// The checks see what they must: a made-up pair of files that import each other is a
/// cycle, brace groups and `super::` resolve, and comments are not imports.
#[test]
fn the_checks_find_a_cycle_when_there_is_one() {
    let dir = std::env::temp_dir().join(format!("hmdist-layering-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("a")).unwrap();
    std::fs::write(dir.join("lib.rs"), "mod a;\nmod b;\n// use crate::c::X;\n").unwrap();
    std::fs::write(dir.join("a/mod.rs"), "mod inner;\n").unwrap();
    std::fs::write(dir.join("a/inner.rs"), "use super::super::{b::Y, c};\n").unwrap();
    std::fs::write(dir.join("b.rs"), "fn f() { crate::a::inner::g() }\n").unwrap();
    std::fs::write(dir.join("c.rs"), "/// crate::b\n").unwrap();
    let files = modules(&dir);
    let edges = graph(&files);
    let cycles = cycles(&files, &edges);
    std::fs::remove_dir_all(&dir).unwrap();
    let expected: Vec<String> = ["a/inner.rs", "b.rs"]
        .iter()
        .map(|f| dir.join(f).display().to_string())
        .collect();
    assert_eq!(cycles.into_iter().collect::<Vec<_>>(), vec![expected]);
    let c = vec!["c".to_string()];
    assert!(edges[&vec![]].is_empty(), "a comment counted as an import");
    assert!(edges[&c].is_empty(), "a doc comment counted as an import");
    assert!(edges[&vec!["a".to_string(), "inner".to_string()]].contains(&c));
    // A parent that calls its child while the child imports the parent.
    let dir = std::env::temp_dir().join(format!("hmdist-layering-parent-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("p")).unwrap();
    std::fs::write(dir.join("lib.rs"), "mod p;\n").unwrap();
    std::fs::write(
        dir.join("p/mod.rs"),
        "mod k;\nmod q;\npub use k::X;\nfn f() { q::g() }\n",
    )
    .unwrap();
    std::fs::write(dir.join("p/q.rs"), "use super::Thing;\npub fn g() {}\n").unwrap();
    std::fs::write(dir.join("p/k.rs"), "use super::Thing;\npub struct X;\n").unwrap();
    let files = modules(&dir);
    let pairs = parent_child_pairs(&files);
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(pairs.len(), 1, "{pairs:?}");
    assert!(
        pairs[0].ends_with("p/q.rs"),
        "{pairs:?}: only the child the parent calls, not the re-exported one"
    );
}

#[test]
fn a_render_key_is_built_in_one_place() {
    // `RenderKey::new` is the one place that fills a key's fields (the render driver, the
    // experiment cache and the photon map call it): a field added to the key cannot be
    // forgotten by one of them. Its struct literal appears in `report/` alone.
    let files = modules(&src());
    let mut literals = vec![];
    for path in files.values() {
        let text = without_comments(&std::fs::read_to_string(path).unwrap());
        // A literal, not a signature's return type (`-> RenderKey {`) nor an `impl`.
        let count = text
            .match_indices("RenderKey {")
            .filter(|&(at, _)| !text[..at].ends_with("-> ") && !text[..at].ends_with("impl "))
            .count();
        if count > 0 && !path.ends_with("report/mod.rs") {
            literals.push(format!("{}: {count}", path.display()));
        }
    }
    assert!(
        literals.is_empty(),
        "RenderKey written out field by field outside report/mod.rs: {literals:?}"
    );
    let report = without_comments(&std::fs::read_to_string(src().join("report/mod.rs")).unwrap());
    assert!(report.contains("pub fn new("), "RenderKey::new is gone");
}
