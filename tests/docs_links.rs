//! The documentation's links hold: every relative link in README.md and docs/*.md names a
//! file that exists and, with `#anchor`, a heading (GitHub's anchor for it) or an
//! `<a id>` of that page.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn repo() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// The pages: README.md and every docs/*.md.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![repo().join("README.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(repo().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    pages.extend(docs);
    pages
}

/// The lines of `text` outside its fenced code blocks, whose brackets and hashes are
/// code, not links or headings.
fn outside_fences(text: &str) -> impl Iterator<Item = &str> {
    let mut fenced = false;
    text.lines().filter(move |line| {
        let fence = line.trim_start().starts_with("```");
        fenced ^= fence;
        !fence && !fenced
    })
}

/// `text` without its fenced code blocks and inline code spans.
fn prose(text: &str) -> String {
    let mut out = String::new();
    for line in outside_fences(text) {
        // Split on backticks: the odd pieces are code spans.
        let plain: String = line.split('`').step_by(2).collect();
        out.push_str(&plain);
        out.push('\n');
    }
    out
}

/// Each `[text](target)` of `text`: its target.
fn links(text: &str) -> Vec<&str> {
    text.match_indices("](")
        .filter_map(|(at, _)| {
            let rest = &text[at + 2..];
            let end = rest.find(')')?;
            Some(rest[..end].trim())
        })
        .collect()
}

/// `text` with each `[label](target)` as its label.
fn without_links(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(open) = rest.find('[') {
        let after = &rest[open + 1..];
        match after.find("](").and_then(|close| {
            let end = after[close + 2..].find(')')?;
            Some((close, close + 2 + end + 1))
        }) {
            Some((close, past)) => {
                out.push_str(&rest[..open]);
                out.push_str(&after[..close]);
                rest = &after[past..];
            }
            None => {
                out.push_str(&rest[..=open]);
                rest = after;
            }
        }
    }
    out.push_str(rest);
    out
}

/// GitHub's anchor for a heading's text: lower case, links as their labels, code marks
/// and punctuation dropped (letters, digits, `-` and `_` kept), spaces as `-`.
fn slug(heading: &str) -> String {
    without_links(heading)
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, '-' | '_' | ' '))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a page: its headings' (a repeated one gets `-1`, `-2`, … as on GitHub)
/// and its `<a id="…">`s.
fn anchors(text: &str) -> BTreeSet<String> {
    let mut found = BTreeSet::new();
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    for line in outside_fences(text) {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && line[hashes..].starts_with(' ') {
            let base = slug(&line[hashes..].replace('`', ""));
            let n = seen.entry(base.clone()).or_insert(0);
            found.insert(if *n == 0 {
                base.clone()
            } else {
                format!("{base}-{n}")
            });
            *n += 1;
        }
        for (at, _) in line.match_indices("<a id=\"") {
            let rest = &line[at + 7..];
            if let Some(end) = rest.find('"') {
                found.insert(rest[..end].to_string());
            }
        }
    }
    found
}

/// The broken relative links of `pages`: (page, link, what is wrong).
fn broken(pages: &[PathBuf]) -> Vec<(String, String, &'static str)> {
    // Each linked page's anchors, found once.
    let mut anchors_of: BTreeMap<PathBuf, BTreeSet<String>> = BTreeMap::new();
    let mut bad = Vec::new();
    for page in pages {
        let text = std::fs::read_to_string(page).unwrap();
        for link in links(&prose(&text)) {
            if link.contains(':') || link.is_empty() {
                continue; // https:, mailto:, …
            }
            let (path, anchor) = link.split_once('#').unwrap_or((link, ""));
            let target = if path.is_empty() {
                page.clone()
            } else {
                page.parent().unwrap().join(path)
            };
            let name = || {
                page.strip_prefix(repo())
                    .unwrap_or(page)
                    .display()
                    .to_string()
            };
            if !target.exists() {
                bad.push((name(), link.to_string(), "no such file"));
                continue;
            }
            if anchor.is_empty() || target.extension().is_none_or(|e| e != "md") {
                continue;
            }
            let known = anchors_of
                .entry(target.canonicalize().unwrap())
                .or_insert_with_key(|path| anchors(&std::fs::read_to_string(path).unwrap()));
            if !known.contains(anchor) {
                bad.push((name(), link.to_string(), "no such heading or <a id>"));
            }
        }
    }
    bad
}

#[test]
fn every_relative_link_of_the_docs_names_a_file_and_an_anchor_that_exist() {
    let pages = pages();
    let anchored = pages
        .iter()
        .map(|p| {
            let text = prose(&std::fs::read_to_string(p).unwrap());
            links(&text)
                .into_iter()
                .filter(|l| !l.contains(':') && l.contains('#'))
                .count()
        })
        .sum::<usize>();
    assert!(anchored > 100, "only {anchored} links to an anchor found");
    let bad = broken(&pages);
    assert!(bad.is_empty(), "broken links: {bad:#?}");
}

#[test]
fn the_link_check_sees_a_wrong_file_and_a_wrong_anchor() {
    let dir = std::env::temp_dir().join(format!("troupe-doc-links-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let a = dir.join("a.md");
    std::fs::write(
        &a,
        "# A page\n## Seeing it: `--debug nav`\n## Twice\n## Twice\n<a id=\"here\"></a>\n\
         [ok](#seeing-it---debug-nav) [ok](#twice-1) [ok](b.md#here) [ok](#a-page)\n\
         `[code](#not-a-link)`\n[bad](#nowhere) [bad](c.md) [bad](b.md#twice-1)\n",
    )
    .unwrap();
    std::fs::write(dir.join("b.md"), "<a id=\"here\"></a>\n## Twice\n").unwrap();
    let bad = broken(&[a, dir.join("b.md")]);
    let links: Vec<&str> = bad.iter().map(|(_, l, _)| l.as_str()).collect();
    assert_eq!(links, ["#nowhere", "c.md", "b.md#twice-1"], "{bad:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_heading_with_a_link_and_code_has_githubs_anchor() {
    assert_eq!(
        slug("A shared space: obstacles, walls, paths ([navigation.md](navigation.md))"),
        "a-shared-space-obstacles-walls-paths-navigationmd"
    );
    assert_eq!(slug("Seeing it: --debug nav"), "seeing-it---debug-nav");
    assert_eq!(
        slug("Deciding less often: a third try (2026-12-04, night)"),
        "deciding-less-often-a-third-try-2026-12-04-night"
    );
}
