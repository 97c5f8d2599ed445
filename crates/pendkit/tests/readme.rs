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
    let readme = include_str!("../../../README.md");
    let lib = include_str!("../src/lib.rs");
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
        "the README's ```rust block differs from the first example of crates/pendkit/src/lib.rs"
    );
}
