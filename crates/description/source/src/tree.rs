//! A file's TOML as a tree of nodes that remember their source and span, so that values from
//! a file and the files it extends can be merged and still be traced to their line.

#[cfg(feature = "toml")]
use std::sync::Arc;

#[cfg(feature = "toml")]
use toml::Spanned;
#[cfg(feature = "toml")]
use toml::de::{DeTable, DeValue};

use crate::source::Origin;
#[cfg(feature = "toml")]
use crate::source::{FileError, Source};

/// A TOML value with its origin.
#[derive(Clone, Debug)]
pub struct Node {
    /// The value.
    pub value: Value,
    /// Where the value is written.
    pub origin: Origin,
}

/// The TOML values a suspension file uses.
#[derive(Clone, Debug)]
pub enum Value {
    /// A string.
    Str(String),
    /// A number, as its decimal text (integers in other radixes converted; underscores and a
    /// leading `+` removed): parameters keep what the file wrote.
    Num(String),
    /// A boolean.
    Bool(bool),
    /// An array.
    Array(Vec<Node>),
    /// A table.
    Table(Table),
    /// A value no field takes (a date, an infinite or NaN float), named by its TOML type: one
    /// of [`OTHER_KINDS`].
    Other(&'static str),
}

/// The values a file can write that no field takes, by how messages name them.
pub const OTHER_KINDS: [&str; 3] = [
    "a date",
    "an integer out of range",
    "an infinite or NaN number",
];

impl Value {
    /// The TOML type's name for messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Value::Str(_) => "a string",
            Value::Num(_) => "a number",
            Value::Bool(_) => "a boolean",
            Value::Array(_) => "an array",
            Value::Table(_) => "a table",
            Value::Other(what) => what,
        }
    }
}

/// A table's entries in the order the file writes them.
#[derive(Clone, Debug, Default)]
pub struct Table {
    /// Key (with the key's origin) and value.
    pub entries: Vec<(String, Origin, Node)>,
}

impl Table {
    /// The entry called `key`.
    pub fn get(&self, key: &str) -> Option<&Node> {
        self.entries
            .iter()
            .find(|(k, _, _)| k == key)
            .map(|(_, _, n)| n)
    }

    /// Removes and returns the entry called `key`.
    pub fn remove(&mut self, key: &str) -> Option<Node> {
        let i = self.entries.iter().position(|(k, _, _)| k == key)?;
        Some(self.entries.remove(i).2)
    }

    /// Merges `over` into this table: a key both have whose values are both tables is merged
    /// the same way; any other value of `over` replaces this one's; new keys are appended.
    pub fn merge(&mut self, over: Table) {
        for (key, key_origin, node) in over.entries {
            match self.entries.iter_mut().find(|(k, _, _)| *k == key) {
                Some((_, mine_key, mine)) => match (&mut mine.value, node.value) {
                    (Value::Table(base), Value::Table(child)) => base.merge(child),
                    // a replaced value is traced to the file that replaced it
                    (_, value) => {
                        *mine_key = key_origin;
                        *mine = Node {
                            value,
                            origin: node.origin,
                        }
                    }
                },
                None => self.entries.push((key, key_origin, node)),
            }
        }
    }
}

/// Parses `source` into a table of nodes. A TOML syntax error names the file and line.
#[cfg(feature = "toml")]
pub fn parse(source: &Arc<Source>) -> Result<Node, FileError> {
    let table = DeTable::parse(&source.text).map_err(|e| FileError {
        file: source.name.clone(),
        line: e.span().map(|s| source.line(s.start)),
        field: String::new(),
        message: e.message().trim().to_string(),
    })?;
    let origin = Origin {
        source: source.clone(),
        span: 0..0,
    };
    Ok(Node {
        value: Value::Table(table_of(source, table.get_ref())),
        origin,
    })
}

#[cfg(feature = "toml")]
fn table_of(source: &Arc<Source>, table: &DeTable) -> Table {
    let mut entries: Vec<(String, Origin, Node)> = table
        .iter()
        .map(|(key, value)| {
            let key_origin = Origin {
                source: source.clone(),
                span: key.span(),
            };
            (
                key.get_ref().to_string(),
                key_origin,
                node_of(source, value),
            )
        })
        .collect();
    // the parser keeps keys sorted by name; the file's order is that of the keys' spans
    entries.sort_by_key(|(_, origin, _)| origin.span.start);
    Table { entries }
}

#[cfg(feature = "toml")]
fn node_of(source: &Arc<Source>, value: &Spanned<DeValue>) -> Node {
    let origin = Origin {
        source: source.clone(),
        span: value.span(),
    };
    let value = match value.get_ref() {
        DeValue::String(s) => Value::Str(s.to_string()),
        DeValue::Integer(i) => {
            let digits = i.as_str().replace('_', "");
            if i.radix() == 10 {
                Value::Num(digits.trim_start_matches('+').to_string())
            } else {
                match i64::from_str_radix(&digits, i.radix()) {
                    Ok(v) => Value::Num(v.to_string()),
                    Err(_) => Value::Other(OTHER_KINDS[1]),
                }
            }
        }
        DeValue::Float(f) => {
            let text = f.as_str().replace('_', "");
            let text = text.trim_start_matches('+');
            // a literal with digits stays text, even one an f64 cannot hold (`1e-400`,
            // `1e400`): the field's reader names it as such; `inf` and `nan` have none
            if text.bytes().any(|b| b.is_ascii_digit()) {
                Value::Num(text.to_string())
            } else {
                Value::Other(OTHER_KINDS[2])
            }
        }
        DeValue::Boolean(b) => Value::Bool(*b),
        DeValue::Datetime(_) => Value::Other(OTHER_KINDS[0]),
        DeValue::Array(a) => Value::Array(a.iter().map(|v| node_of(source, v)).collect()),
        DeValue::Table(t) => Value::Table(table_of(source, t)),
    };
    Node { value, origin }
}

#[cfg(all(test, feature = "toml"))]
mod tests {
    use super::*;

    fn table(text: &str) -> Table {
        match parse(&Source::new("t.toml", None, text)).unwrap().value {
            Value::Table(t) => t,
            _ => unreachable!(),
        }
    }

    #[test]
    fn entries_keep_the_files_order_and_lines() {
        let t = table("[bodies.top]\nmass = 1\n[bodies.a]\nmass = 0x10\n");
        let Some(Value::Table(bodies)) = t.get("bodies").map(|n| &n.value) else {
            panic!("bodies")
        };
        let keys: Vec<&str> = bodies.entries.iter().map(|e| e.0.as_str()).collect();
        assert_eq!(keys, ["top", "a"]);
        let Some(Value::Table(a)) = bodies.get("a").map(|n| &n.value) else {
            panic!("a")
        };
        let mass = a.get("mass").unwrap();
        assert!(matches!(&mass.value, Value::Num(n) if n == "16"));
        assert_eq!(mass.origin.line(), 4);
    }

    #[test]
    fn merging_replaces_values_and_merges_tables() {
        let mut base = table("a = 1\n[t]\nx = 1\ny = 2\n");
        base.merge(table("[t]\ny = \"3\"\nz = 4\n"));
        let Some(Value::Table(t)) = base.get("t").map(|n| &n.value) else {
            panic!("t")
        };
        let keys: Vec<&str> = t.entries.iter().map(|e| e.0.as_str()).collect();
        assert_eq!(keys, ["x", "y", "z"]);
        assert!(matches!(&t.get("y").unwrap().value, Value::Str(s) if s == "3"));
        assert!(base.get("a").is_some());
    }
}
