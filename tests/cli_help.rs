//! Every `--help` tells the truth about the documentation: each page it names exists, each `#section` it
//! names is a heading of that page, and the top-level help says what `oeg` with no command does.
#![allow(clippy::disallowed_methods, reason = "tests read back the files they wrote")]

mod common;

use common::{oeg, ok, root};

/// GitHub's anchor of a Markdown heading: lower case, punctuation other than `-` and `_` dropped, spaces
/// turned into `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a Markdown file's headings.
fn anchors(markdown: &str) -> Vec<String> {
    markdown
        .lines()
        .filter_map(|l| l.strip_prefix('#'))
        .map(|l| slug(l.trim_start_matches('#')))
        .collect()
}

/// Every command path, from the top-level help's command list down (`sweep` has its own).
fn commands() -> Vec<Vec<String>> {
    let mut out = vec![Vec::new()];
    let mut k = 0;
    while k < out.len() {
        let path = out[k].clone();
        let mut args: Vec<&str> = path.iter().map(String::as_str).collect();
        args.push("--help");
        let text = ok(&oeg(&args));
        let mut in_list = false;
        for line in text.lines() {
            if line.starts_with("Commands:") {
                in_list = true;
                continue;
            }
            if in_list {
                let Some(name) = line.strip_prefix("  ").and_then(|l| l.split_whitespace().next()) else {
                    in_list = false;
                    continue;
                };
                if name != "help" {
                    let mut child = path.clone();
                    child.push(name.to_string());
                    out.push(child);
                }
            }
        }
        k += 1;
    }
    out
}

/// The documentation references of a help text: `docs/x.md`, `docs/x.md#anchor`, `python/README.md`, and
/// any mention of the README.
fn references(text: &str) -> Vec<String> {
    let mut refs = Vec::new();
    for word in text.split(|c: char| c.is_whitespace() || "(),;`'\"".contains(c)) {
        let word = word.trim_end_matches(['.', ':']);
        if word.contains(".md") {
            refs.push(word.to_string());
        }
    }
    refs
}

#[test]
fn every_help_names_pages_and_sections_that_exist() {
    let root = root();
    let commands = commands();
    assert!(
        commands.len() >= 14,
        "the command list was not read: {commands:?}"
    );
    let mut checked = 0;
    for path in &commands {
        let mut args: Vec<&str> = path.iter().map(String::as_str).collect();
        args.push("--help");
        let text = ok(&oeg(&args));
        assert!(
            !text.contains("README, \""),
            "`oeg {}` names a README section by title; name a docs/ page and its anchor",
            path.join(" ")
        );
        for r in references(&text) {
            let (file, anchor) = r.split_once('#').unwrap_or((&r, ""));
            let page = root.join(file);
            let markdown = std::fs::read_to_string(&page)
                .unwrap_or_else(|e| panic!("`oeg {} --help` names {r}: {e}", path.join(" ")));
            if !anchor.is_empty() {
                assert!(
                    anchors(&markdown).iter().any(|a| a == anchor),
                    "`oeg {} --help` names {r}, but {file} has no heading with that anchor",
                    path.join(" ")
                );
            }
            checked += 1;
        }
    }
    assert!(checked >= 5, "only {checked} references found");
}

#[test]
fn the_top_level_help_says_what_oeg_alone_runs() {
    let text = ok(&oeg(&["--help"]));
    assert!(
        text.contains("With no command, `oeg` runs scenarios/default.toml"),
        "{text}"
    );
    // And no command claims to be what `oeg` alone does.
    assert!(!text.contains("what `oeg` with no arguments does"), "{text}");
}

#[test]
fn anchors_follow_github() {
    assert_eq!(slug(" Settings: one door"), "settings-one-door");
    assert_eq!(slug("Map real data"), "map-real-data");
}
