//! Files written by a program: a [`Writer`] writes a TOML file's text and, at the same time,
//! the tree a reader would read from it (every value traced to its line in that text). A
//! generated suspension is thus read without a parser, and the text is there for the user
//! to see or edit (`pendkit chain-file N`).

use std::fmt::Write as _;
use std::ops::Range;
use std::sync::Arc;

use crate::source::{Origin, Source};
use crate::tree::{Node, Table, Value};

/// A value to write.
#[derive(Clone, Debug)]
pub enum Item {
    /// A string (written as a basic string, escaped).
    Str(String),
    /// A number, written as given (it must be a TOML integer or float, e.g. `0.5e-3`).
    Num(String),
    /// A boolean.
    Bool(bool),
    /// An array.
    Array(Vec<Item>),
    /// An inline table, `{ key = value, ... }`.
    Inline(Vec<(String, Item)>),
}

impl Item {
    /// A string item.
    pub fn str(text: impl Into<String>) -> Item {
        Item::Str(text.into())
    }

    /// A number item from its TOML text.
    pub fn num(text: impl Into<String>) -> Item {
        Item::Num(text.into())
    }
}

/// A written file: its text and the tree read from it.
#[derive(Clone, Debug)]
pub struct Written {
    /// The text, with the name errors give the file.
    pub source: Arc<Source>,
    /// The top-level table.
    pub root: Node,
}

impl Written {
    /// The same file under another name (how errors name it).
    pub fn named(self, name: &str) -> Written {
        if self.source.name == name {
            return self;
        }
        let source = Source::new(name, None, self.source.text.as_str());
        let mut root = self.root;
        point_to(&mut root, &source);
        Written { source, root }
    }
}

/// Writes a file: comments, blank lines, `key = value` entries and `[section]` headers, in
/// the order called.
#[derive(Debug)]
pub struct Writer {
    text: String,
    root: Table,
    // the current section, as entry indices from the root (a long file's entries find
    // their table without comparing names)
    section: Vec<usize>,
    // every origin points here until `finish` knows the whole text
    pending: Arc<Source>,
}

impl Default for Writer {
    fn default() -> Self {
        Writer::new()
    }
}

impl Writer {
    /// An empty file.
    pub fn new() -> Writer {
        Writer {
            text: String::new(),
            root: Table::default(),
            section: Vec::new(),
            pending: Source::new("", None, ""),
        }
    }

    /// `# text`, one comment line per line of `text`.
    pub fn comment(&mut self, text: &str) {
        for line in text.lines() {
            if line.is_empty() {
                self.text.push_str("#\n");
            } else {
                let _ = writeln!(self.text, "# {line}");
            }
        }
    }

    /// An empty line.
    pub fn blank(&mut self) {
        self.text.push('\n');
    }

    /// A `[a.b.c]` header: the entries that follow go into that table (created, with the
    /// tables on its way, where missing).
    pub fn section(&mut self, path: &[&str]) {
        self.text.push('[');
        let mut spans = Vec::with_capacity(path.len());
        for (i, key) in path.iter().enumerate() {
            if i > 0 {
                self.text.push('.');
            }
            let start = self.text.len();
            write_key(key, &mut self.text);
            spans.push(start..self.text.len());
        }
        self.text.push_str("]\n");
        let pending = self.pending.clone();
        let mut table = &mut self.root;
        self.section.clear();
        for (key, span) in path.iter().zip(spans) {
            let (i, inner) = table_in(table, key, &pending, span);
            self.section.push(i);
            table = inner;
        }
    }

    /// `key = value` in the current section.
    pub fn entry(&mut self, key: &str, item: Item) {
        let key_start = self.text.len();
        write_key(key, &mut self.text);
        let key_span = key_start..self.text.len();
        self.text.push_str(" = ");
        let node = self.write_item(&item);
        self.text.push('\n');
        let pending = self.pending.clone();
        let mut table = &mut self.root;
        for &i in &self.section {
            table = table_at(table, i);
        }
        table.entries.retain(|(k, _, _)| k != key);
        table.entries.push((
            key.to_string(),
            Origin {
                source: pending,
                span: key_span,
            },
            node,
        ));
    }

    fn write_item(&mut self, item: &Item) -> Node {
        let start = self.text.len();
        let value = match item {
            Item::Str(s) => {
                write_string(s, &mut self.text);
                Value::Str(s.clone())
            }
            Item::Num(n) => {
                self.text.push_str(n);
                Value::Num(n.clone())
            }
            Item::Bool(b) => {
                let _ = write!(self.text, "{b}");
                Value::Bool(*b)
            }
            Item::Array(items) => {
                self.text.push('[');
                let mut nodes = Vec::with_capacity(items.len());
                for (i, item) in items.iter().enumerate() {
                    if i > 0 {
                        self.text.push_str(", ");
                    }
                    nodes.push(self.write_item(item));
                }
                self.text.push(']');
                Value::Array(nodes)
            }
            Item::Inline(entries) => {
                self.text.push('{');
                let mut table = Table::default();
                for (i, (key, item)) in entries.iter().enumerate() {
                    self.text.push_str(if i > 0 { ", " } else { " " });
                    let key_start = self.text.len();
                    write_key(key, &mut self.text);
                    let key_span = key_start..self.text.len();
                    self.text.push_str(" = ");
                    let node = self.write_item(item);
                    table
                        .entries
                        .push((key.clone(), self.origin(key_span), node));
                }
                self.text
                    .push_str(if entries.is_empty() { "}" } else { " }" });
                Value::Table(table)
            }
        };
        Node {
            value,
            origin: self.origin(start..self.text.len()),
        }
    }

    fn origin(&self, span: Range<usize>) -> Origin {
        Origin {
            source: self.pending.clone(),
            span,
        }
    }

    /// The text, called `name` in errors, and its tree.
    pub fn finish(self, name: &str) -> Written {
        let source = Source::new(name, None, self.text);
        let mut root = Node {
            value: Value::Table(self.root),
            origin: Origin {
                source: source.clone(),
                span: 0..0,
            },
        };
        point_to(&mut root, &source);
        Written { source, root }
    }
}

/// The table `key` of `table` and its index, created if missing (a non-table value there is
/// replaced: the writer's caller decides what the file says).
fn table_in<'t>(
    table: &'t mut Table,
    key: &str,
    pending: &Arc<Source>,
    span: Range<usize>,
) -> (usize, &'t mut Table) {
    let i = match table.entries.iter().position(|(k, _, _)| k == key) {
        Some(i) => i,
        None => {
            let origin = Origin {
                source: pending.clone(),
                span,
            };
            table.entries.push((
                key.to_string(),
                origin.clone(),
                Node {
                    value: Value::Table(Table::default()),
                    origin,
                },
            ));
            table.entries.len() - 1
        }
    };
    let node = &mut table.entries[i].2;
    if !matches!(node.value, Value::Table(_)) {
        node.value = Value::Table(Table::default());
    }
    (i, table_at(table, i))
}

/// The table at entry `i` of `table` (a section's table, which `table_in` made a table).
fn table_at(table: &mut Table, i: usize) -> &mut Table {
    match &mut table.entries[i].2.value {
        Value::Table(t) => t,
        _ => unreachable!("sections are tables"),
    }
}

/// Points every origin of `node` at the finished `source`.
fn point_to(node: &mut Node, source: &Arc<Source>) {
    node.origin.source = source.clone();
    match &mut node.value {
        Value::Array(items) => items.iter_mut().for_each(|n| point_to(n, source)),
        Value::Table(table) => {
            for (_, key_origin, value) in &mut table.entries {
                key_origin.source = source.clone();
                point_to(value, source);
            }
        }
        _ => {}
    }
}

/// A key bare where TOML allows it (`A-Za-z0-9_-`), quoted otherwise.
fn write_key(key: &str, out: &mut String) {
    let bare = !key.is_empty()
        && key
            .bytes()
            .all(|b| b.is_ascii_alphanumeric() || b == b'_' || b == b'-');
    if bare {
        out.push_str(key);
    } else {
        write_string(key, out);
    }
}

/// A TOML basic string: quotes, backslashes and control characters escaped.
fn write_string(s: &str, out: &mut String) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

#[cfg(all(test, feature = "toml"))]
mod tests {
    use super::*;
    use crate::tree::parse;

    /// What a TOML reader reads from the written text is the writer's tree: the same keys
    /// in the same order, the same values, each on the same line.
    fn agree(written: &Node, read: &Node) {
        match (&written.value, &read.value) {
            (Value::Table(w), Value::Table(r)) => {
                let wk: Vec<&str> = w.entries.iter().map(|e| e.0.as_str()).collect();
                let rk: Vec<&str> = r.entries.iter().map(|e| e.0.as_str()).collect();
                assert_eq!(wk, rk);
                for (we, re) in w.entries.iter().zip(&r.entries) {
                    if !matches!(we.2.value, Value::Table(_)) {
                        assert_eq!(we.1.line(), re.1.line(), "key {}", we.0);
                    }
                    agree(&we.2, &re.2);
                }
            }
            (Value::Array(w), Value::Array(r)) => {
                assert_eq!(w.len(), r.len());
                w.iter().zip(r).for_each(|(a, b)| agree(a, b));
            }
            (w, r) => {
                assert_eq!(format!("{w:?}"), format!("{r:?}"));
                assert_eq!(written.origin.line(), read.origin.line());
            }
        }
    }

    #[test]
    fn a_reader_reads_the_writers_tree() {
        let mut w = Writer::new();
        w.comment("a generated file\n\nwith a blank comment line");
        w.entry("name", Item::str("q\"uo\\te\ttab\u{1}"));
        w.blank();
        w.section(&["parameters"]);
        w.entry(
            "g",
            Item::Inline(vec![
                ("value".into(), Item::num("9.81")),
                ("unit".into(), Item::str("m/s^2")),
            ]),
        );
        w.entry("empty", Item::Inline(vec![]));
        w.section(&["stages", "mass 1", "wires"]);
        w.entry(
            "upper",
            Item::Inline(vec![(
                "at".into(),
                Item::Array(vec![Item::str("a"), Item::num("0"), Item::num("-1e-3")]),
            )]),
        );
        w.entry("hinged", Item::Bool(true));
        w.section(&["stages", "mass 1"]);
        w.entry("from", Item::str("support"));
        let written = w.finish("w.toml");
        let read = parse(&written.source).unwrap();
        agree(&written.root, &read);
    }
}
