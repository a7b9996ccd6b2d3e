//! The published pages and docs link only files that exist: every relative `href` and `src`
//! of the HTML reports under docs/ and every relative Markdown link of README.md and docs/
//! names a file in the repository, and every `#anchor` names a section: an `id` of an HTML
//! page, or a heading of a Markdown page (by GitHub's rule for its anchor).

use std::path::{Path, PathBuf};

/// Every file under `dir` whose name ends in one of `extensions`.
fn files(dir: &Path, extensions: &[&str], found: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files(&path, extensions, found);
        } else if extensions
            .iter()
            .any(|e| path.extension().is_some_and(|x| x == *e))
        {
            found.push(path);
        }
    }
}

/// The targets of `attribute="…"` in `html`.
fn attribute_targets(html: &str, attribute: &str) -> Vec<String> {
    let key = format!("{attribute}=\"");
    html.split(&key)
        .skip(1)
        .map(|s| s[..s.find('"').unwrap()].to_string())
        .collect()
}

/// The targets of Markdown links `[text](target)` in `markdown`, outside code blocks.
fn markdown_targets(markdown: &str) -> Vec<String> {
    let mut targets = vec![];
    let mut in_code = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
            continue;
        }
        if in_code {
            continue;
        }
        for piece in line.split("](").skip(1) {
            if let Some(end) = piece.find(')') {
                targets.push(piece[..end].to_string());
            }
        }
    }
    targets
}

/// Whether `target` points outside the repository (a web address) and so is not checked.
fn external(target: &str) -> bool {
    target.contains("://") || target.starts_with("mailto:")
}

/// GitHub's anchor of a Markdown heading: lower case, spaces as hyphens, punctuation other
/// than `-` and `_` dropped ("Final gathering (`--method gather`)": `final-gathering---method-gather`).
fn heading_anchor(heading: &str) -> String {
    heading
        .trim()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            '-' | '_' => Some(c),
            c if c.is_alphanumeric() => Some(c),
            _ => None,
        })
        .flat_map(char::to_lowercase)
        .collect()
}

/// Whether `text` (an HTML page or, for `markdown`, a Markdown one) has a section `anchor`.
fn has_section(text: &str, markdown: bool, anchor: &str) -> bool {
    if !markdown {
        return text.contains(&format!("id=\"{anchor}\""));
    }
    let mut in_code = false;
    text.lines().any(|line| {
        if line.trim_start().starts_with("```") {
            in_code = !in_code;
        }
        !in_code && line.starts_with('#') && heading_anchor(line.trim_start_matches('#')) == anchor
    })
}

/// Checks one link of the page `page`: a file beside it, and the anchor, if any, of that file
/// (or of `page_text` itself).
fn check(page: &Path, page_text: &str, target: &str, broken: &mut Vec<String>) {
    if external(target) {
        return;
    }
    let (file, anchor) = match target.split_once('#') {
        Some((file, anchor)) => (file, Some(anchor)),
        None => (target, None),
    };
    let path = if file.is_empty() {
        page.to_path_buf()
    } else {
        page.parent().unwrap().join(file)
    };
    if !path.exists() {
        broken.push(format!("{}: {target} does not exist", page.display()));
        return;
    }
    let Some(anchor) = anchor else { return };
    let markdown = path.extension().is_some_and(|e| e == "md");
    let html = path.extension().is_some_and(|e| e == "html");
    if !markdown && !html {
        return;
    }
    let text = if file.is_empty() {
        page_text.to_string()
    } else {
        std::fs::read_to_string(&path).unwrap()
    };
    if !has_section(&text, markdown, anchor) {
        broken.push(format!(
            "{}: {target}: #{anchor} names no section",
            page.display()
        ));
    }
}

#[test]
fn a_headings_anchor_is_githubs() {
    assert_eq!(
        heading_anchor(" Final gathering (`--method gather`)"),
        "final-gathering---method-gather"
    );
    assert_eq!(
        heading_anchor(" Reliability: what hmdist promises"),
        "reliability-what-hmdist-promises"
    );
    assert_eq!(
        heading_anchor(" Accuracy against cost: f_diff"),
        "accuracy-against-cost-f_diff"
    );
}

#[test]
fn every_link_and_image_of_the_docs_and_the_reports_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut pages = vec![root.join("README.md")];
    files(&root.join("docs"), &["md", "html"], &mut pages);
    let mut broken = vec![];
    let mut checked = 0;
    for page in &pages {
        let text = std::fs::read_to_string(page).unwrap();
        let targets = if page.extension().is_some_and(|e| e == "html") {
            let mut t = attribute_targets(&text, "href");
            t.extend(attribute_targets(&text, "src"));
            t
        } else {
            markdown_targets(&text)
        };
        for target in targets {
            checked += 1;
            check(page, &text, &target, &mut broken);
        }
    }
    assert!(checked > 100, "only {checked} links found: the scan is broken");
    assert!(
        broken.is_empty(),
        "{} broken links:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

/// The section numbers of `docs/spec.md`'s headings ("## 3. The estimators": `3`, "### 3.1
/// …": `3.1`).
fn spec_sections(root: &Path) -> Vec<String> {
    let spec = std::fs::read_to_string(root.join("docs/spec.md")).unwrap();
    spec.lines()
        .filter(|line| line.starts_with('#'))
        .filter_map(|line| {
            let number = line.trim_start_matches('#').trim().split(' ').next()?;
            let number = number.trim_end_matches('.');
            (!number.is_empty() && number.chars().all(|c| c.is_ascii_digit() || c == '.'))
                .then(|| number.to_string())
        })
        .collect()
}

/// The section numbers cited as `spec §N` (or `§N` right after one: "spec §7, §8") in `text`.
fn spec_citations(text: &str) -> Vec<String> {
    let mut cited = vec![];
    for piece in text.replace("spec.md §", "spec §").split("spec §").skip(1) {
        // "§3.1", "§4's", "§2." at a sentence's end, "§7, §8", "§1–§3".
        let mut rest = piece;
        loop {
            let number: String = rest
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            // "spec §N", the form itself, names no section.
            if !number.is_empty() {
                cited.push(number.trim_end_matches('.').to_string());
            }
            rest = &rest[number.len()..];
            match rest
                .strip_prefix(", §")
                .or_else(|| rest.strip_prefix("–§"))
                .or_else(|| rest.strip_prefix(" and §"))
            {
                Some(next) => rest = next,
                None => break,
            }
        }
    }
    cited
}

/// Every tracked text file of the repository (by `git ls-files`), with its text.
fn tracked_texts(root: &Path) -> Vec<(PathBuf, String)> {
    let listed = std::process::Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root)
        .output()
        .expect("git lists the repository's files");
    assert!(listed.status.success(), "git ls-files failed");
    String::from_utf8(listed.stdout)
        .unwrap()
        .split('\0')
        .filter(|name| !name.is_empty())
        .filter_map(|name| {
            let path = root.join(name);
            let text = String::from_utf8(std::fs::read(&path).ok()?).ok()?;
            Some((path, text))
        })
        .collect()
}

#[test]
fn every_spec_section_cited_in_the_repository_and_in_help_exists() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let sections = spec_sections(root);
    assert!(
        ["1", "3.1", "3.3", "8"]
            .iter()
            .all(|s| sections.contains(&s.to_string())),
        "the spec's headings were not read: {sections:?}"
    );
    assert_eq!(
        spec_citations("f_diff (spec §4), spec §7, §8 and spec §2."),
        ["4", "7", "8", "2"]
    );
    let mut broken = vec![];
    let mut cited = 0;
    for (path, text) in tracked_texts(root) {
        if path.ends_with("tests/doc_links.rs") {
            continue; // this file's own examples
        }
        for (n, line) in text.lines().enumerate() {
            for section in spec_citations(line) {
                cited += 1;
                if !sections.contains(&section) {
                    broken.push(format!("{}:{}: spec §{section}", path.display(), n + 1));
                }
            }
        }
    }
    // What a user reads in `--help` names the file, so it can be followed.
    let hmdist = env!("CARGO_BIN_EXE_hmdist");
    let commands: [&[&str]; 11] = [
        &[],
        &["render"],
        &["diff"],
        &["merge"],
        &["points"],
        &["cache"],
        &["experiment"],
        &["photons", "build"],
        &["scene", "info"],
        &["scene", "export"],
        &["gpu", "list"],
    ];
    let mut in_help = 0;
    for command in commands {
        let out = std::process::Command::new(hmdist)
            .args(command)
            .arg("--help")
            .output()
            .unwrap();
        let help = String::from_utf8_lossy(&out.stdout);
        assert!(
            out.status.success() && help.contains("Usage"),
            "{command:?} --help: {help}"
        );
        for section in spec_citations(&help) {
            in_help += 1;
            if !sections.contains(&section) {
                broken.push(format!("hmdist {} --help: spec §{section}", command.join(" ")));
            }
        }
        for (n, line) in help.lines().enumerate() {
            if line.contains("spec §") && !line.contains("docs/spec.md §") {
                broken.push(format!(
                    "hmdist {} --help, line {}: 'spec §' without the file: {line}",
                    command.join(" "),
                    n + 1
                ));
            }
        }
    }
    assert!(
        cited > 100 && in_help > 5,
        "{cited} citations, {in_help} in help: the scan is broken"
    );
    assert!(
        broken.is_empty(),
        "{} citations name no section of docs/spec.md:\n{}",
        broken.len(),
        broken.join("\n")
    );
}

#[test]
fn nothing_in_the_repository_points_outside_it() {
    // Where the project is developed is not part of it: no path above the repository, no
    // name of the place (spelled here in two pieces, so that this file does not hold it).
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let outside = ["../".to_string() + "shared", "work".to_string() + "place"];
    let mut found = vec![];
    for (path, text) in tracked_texts(root) {
        for (n, line) in text.lines().enumerate() {
            let lower = line.to_lowercase();
            if let Some(word) = outside.iter().find(|w| lower.contains(w.as_str())) {
                found.push(format!("{}:{}: {word}", path.display(), n + 1));
            }
        }
    }
    assert!(found.is_empty(), "{}", found.join("\n"));
}
