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
