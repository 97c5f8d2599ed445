//! The README's library example is the crate documentation's first example, which
//! `cargo test --doc` compiles and runs: this test keeps the two copies the same, so the
//! README shows code that is known to work.

/// The lines of the first fenced block that opens with `opening`, in `text`.
fn first_block(text: &str, opening: &str) -> Vec<String> {
    text.lines()
        .skip_while(|l| l.trim_end() != opening)
        .skip(1)
        .take_while(|l| l.trim_end() != "```")
        .map(str::to_string)
        .collect()
}

#[test]
fn the_readme_example_is_the_tested_crate_example() {
    let readme = include_str!("../../../../../README.md");
    let lib = include_str!("../../src/lib.rs");
    let in_readme = first_block(readme, "```rust");
    // the crate documentation without its `//!` prefixes and hidden (`# `) lines
    let docs: String = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .map(|l| l.strip_prefix(' ').unwrap_or(l))
        .collect::<Vec<_>>()
        .join("\n");
    let in_docs: Vec<String> = first_block(&docs, "```")
        .into_iter()
        .filter(|l| !l.starts_with("# "))
        .collect();
    assert!(in_docs.len() > 10, "no example in the crate documentation");
    assert_eq!(
        in_readme, in_docs,
        "the README's ```rust block differs from the first example of crates/interface/pendkit/src/lib.rs"
    );
}

/// The crate root stays small (issue 32: at most 30 names, the layers reachable as modules):
/// every name `lib.rs` makes public at the root, counted from its `pub` items and the names
/// in its `pub use` lists.
#[test]
fn the_crate_root_has_at_most_thirty_names() {
    let lib = include_str!("../../src/lib.rs");
    let mut names = Vec::new();
    for line in lib.lines() {
        let Some(item) = line.strip_prefix("pub ") else {
            continue;
        };
        let words: Vec<&str> = item.split_whitespace().collect();
        match words.first().copied() {
            Some("use") => {
                let path = item.trim_start_matches("use ").trim_end_matches(';');
                match path.split_once('{') {
                    Some((_, list)) => names.extend(
                        list.trim_end_matches('}')
                            .split(',')
                            .map(|n| n.trim().to_string())
                            .filter(|n| !n.is_empty()),
                    ),
                    None => names.push(path.rsplit([' ', ':']).next().unwrap_or("").to_string()),
                }
            }
            Some("mod" | "fn" | "struct" | "enum" | "const" | "trait" | "type") => {
                let name = words[1]
                    .split(['(', ':', '<', ';', '{'])
                    .next()
                    .unwrap_or("");
                names.push(name.to_string());
            }
            _ => {}
        }
    }
    for expected in [
        "Case",
        "Override",
        "StageResult",
        "run_stage",
        "Error",
        "model",
        "catalogue",
    ] {
        assert!(
            names.iter().any(|n| n == expected),
            "{expected} missing from {names:?}"
        );
    }
    assert!(
        names.len() <= 30,
        "{} names at the crate root: {names:?}",
        names.len()
    );
}
