//! The published pages and docs link only files that exist: every relative `href` and `src`
//! of the HTML reports under docs/ and every relative Markdown link of README.md and docs/
//! names a file in the repository, and every `#anchor` of an HTML page names a section on it.

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

/// Checks one link of the page `page`: a file beside it, or an anchor of `page_text` (HTML).
fn check(page: &Path, page_text: &str, target: &str, broken: &mut Vec<String>) {
    if external(target) {
        return;
    }
    let (file, anchor) = match target.split_once('#') {
        Some((file, anchor)) => (file, Some(anchor)),
        None => (target, None),
    };
    if file.is_empty() {
        let is_html = page.extension().is_some_and(|e| e == "html");
        if let (Some(anchor), true) = (anchor, is_html) {
            if !page_text.contains(&format!("id=\"{anchor}\"")) {
                broken.push(format!("{}: #{anchor} names no section", page.display()));
            }
        }
        return;
    }
    let path = page.parent().unwrap().join(file);
    if !path.exists() {
        broken.push(format!("{}: {target} does not exist", page.display()));
    }
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
