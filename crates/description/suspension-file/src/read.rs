//! Reading typed fields out of the node tree: every value keeps its place, every table
//! reports the keys it does not know (with the closest known one), and every expression is
//! parsed where it is read, so that a problem names its file, line and field.

use pendkit_expr::Expr;

use crate::source::{At, FileError, Located};
use crate::tree::{Node, Table, Value};

/// An expression field: its text, parsed form and place. A TOML number is an expression too.
#[derive(Clone, Debug)]
pub struct Ex {
    /// The text as written (numbers as their decimal text).
    pub text: String,
    /// The parsed expression.
    pub expr: Expr,
    /// Where it is written.
    pub at: At,
}

impl Ex {
    /// Reads an expression from a number or a string node.
    pub fn read(node: &Node, at: At) -> Result<Ex, FileError> {
        let text = match &node.value {
            Value::Num(t) | Value::Str(t) => t.clone(),
            other => {
                return Err(at.error(format!(
                    "expected a number or an expression string, got {}",
                    other.type_name()
                )));
            }
        };
        let expr = pendkit_expr::parse(&text).map_err(|e| at.error(e.to_string()))?;
        Ok(Ex { text, expr, at })
    }

    /// A constant expression written by the program itself (a default), placed at `at`.
    pub fn constant(value: f64, at: At) -> Ex {
        Ex {
            text: value.to_string(),
            expr: Expr::Num(value),
            at,
        }
    }

    /// The text in parentheses, for building larger expressions from it.
    pub fn paren(&self) -> String {
        format!("({})", self.text)
    }
}

/// The fields of one table being read.
pub struct Fields<'a> {
    table: &'a Table,
    /// The table's own place.
    pub at: At,
    /// Keys the reader asked for (the known fields).
    asked: Vec<&'static str>,
}

impl<'a> Fields<'a> {
    /// The fields of `node`, which must be a table.
    pub fn of(node: &'a Node, at: At) -> Result<Fields<'a>, FileError> {
        match &node.value {
            Value::Table(table) => Ok(Fields {
                table,
                at,
                asked: Vec::new(),
            }),
            other => Err(at.error(format!("expected a table, got {}", other.type_name()))),
        }
    }

    /// The node of `key` and its place, if the table has it.
    pub fn node(&mut self, key: &'static str) -> Option<(&'a Node, At)> {
        self.asked.push(key);
        let (_, key_origin, node) = self.table.entries.iter().find(|(k, _, _)| k == key)?;
        Some((node, self.at.child(key_origin.clone(), key)))
    }

    /// Whether the table has `key` (without reading it).
    pub fn has(&self, key: &str) -> bool {
        self.table.get(key).is_some()
    }

    /// An expression.
    pub fn expr(&mut self, key: &'static str) -> Result<Option<Ex>, FileError> {
        self.node(key).map(|(n, at)| Ex::read(n, at)).transpose()
    }

    /// An expression that must be given.
    pub fn required_expr(&mut self, key: &'static str, what: &str) -> Result<Ex, FileError> {
        self.expr(key)?
            .ok_or_else(|| self.at.error(format!("needs `{key}` ({what})")))
    }

    /// A string.
    pub fn string(&mut self, key: &'static str) -> Result<Option<Located<String>>, FileError> {
        match self.node(key) {
            None => Ok(None),
            Some((node, at)) => match &node.value {
                Value::Str(s) => Ok(Some(Located {
                    value: s.clone(),
                    at,
                })),
                other => Err(at.error(format!("expected a string, got {}", other.type_name()))),
            },
        }
    }

    /// A boolean.
    pub fn bool(&mut self, key: &'static str) -> Result<Option<Located<bool>>, FileError> {
        match self.node(key) {
            None => Ok(None),
            Some((node, at)) => match &node.value {
                Value::Bool(b) => Ok(Some(Located { value: *b, at })),
                other => {
                    Err(at.error(format!("expected true or false, got {}", other.type_name())))
                }
            },
        }
    }

    /// An array of `len` expressions (any length if `len` is `None`).
    pub fn exprs(
        &mut self,
        key: &'static str,
        len: Option<usize>,
    ) -> Result<Option<Located<Vec<Ex>>>, FileError> {
        match self.node(key) {
            None => Ok(None),
            Some((node, at)) => expr_array(node, at, len).map(Some),
        }
    }

    /// An array of strings, or one string taken as a one-element array.
    pub fn strings(
        &mut self,
        key: &'static str,
    ) -> Result<Option<Located<Vec<String>>>, FileError> {
        match self.node(key) {
            None => Ok(None),
            Some((node, at)) => {
                let items =
                    match &node.value {
                        Value::Str(s) => vec![s.clone()],
                        Value::Array(items) => items
                            .iter()
                            .map(|n| match &n.value {
                                Value::Str(s) => Ok(s.clone()),
                                other => Err(at
                                    .error(format!("expected strings, got {}", other.type_name()))),
                            })
                            .collect::<Result<_, _>>()?,
                        other => {
                            return Err(at.error(format!(
                                "expected a string or an array of strings, got {}",
                                other.type_name()
                            )));
                        }
                    };
                Ok(Some(Located { value: items, at }))
            }
        }
    }

    /// A sub-table.
    pub fn table(&mut self, key: &'static str) -> Result<Option<Fields<'a>>, FileError> {
        self.node(key).map(|(n, at)| Fields::of(n, at)).transpose()
    }

    /// The entries of a table whose keys are names (parameters, bodies, stages, ...), in the
    /// file's order, each with its place.
    pub fn named(&mut self, key: &'static str) -> Result<Vec<(String, &'a Node, At)>, FileError> {
        match self.node(key) {
            None => Ok(Vec::new()),
            Some((node, at)) => match &node.value {
                Value::Table(t) => Ok(t
                    .entries
                    .iter()
                    .map(|(k, key_origin, n)| (k.clone(), n, at.child(key_origin.clone(), k)))
                    .collect()),
                other => Err(at.error(format!(
                    "expected a table of named entries, got {}",
                    other.type_name()
                ))),
            },
        }
    }

    /// A field the format reserves for physics that is planned but not implemented yet: an
    /// error if the file uses it.
    pub fn planned(&mut self, key: &'static str, what: &str) -> Result<(), FileError> {
        match self.node(key) {
            Some((_, at)) => Err(at.error(format!(
                "{what} is planned (issue 12, item 3) but not implemented yet; remove the field"
            ))),
            None => Ok(()),
        }
    }

    /// Checks that the table has no key the reader did not ask for.
    pub fn finish(self) -> Result<(), FileError> {
        for (key, key_origin, _) in &self.table.entries {
            if !self.asked.contains(&key.as_str()) {
                let at = self.at.child(key_origin.clone(), key);
                let hint = closest(key, &self.asked)
                    .map(|k| format!("; did you mean `{k}`?"))
                    .unwrap_or_default();
                let mut known = self.asked.clone();
                known.sort_unstable();
                known.dedup();
                return Err(at.error(format!(
                    "unknown field{hint} (known here: {})",
                    known.join(", ")
                )));
            }
        }
        Ok(())
    }
}

/// An array of expressions read from `node`.
pub fn expr_array(node: &Node, at: At, len: Option<usize>) -> Result<Located<Vec<Ex>>, FileError> {
    let Value::Array(items) = &node.value else {
        return Err(at.error(format!(
            "expected an array{}, got {}",
            len.map(|n| format!(" of {n} numbers or expressions"))
                .unwrap_or_default(),
            node.value.type_name()
        )));
    };
    if let Some(n) = len
        && items.len() != n
    {
        return Err(at.error(format!("expected {n} entries, got {}", items.len())));
    }
    let value = items
        .iter()
        .enumerate()
        .map(|(i, n)| {
            Ex::read(
                n,
                At {
                    origin: n.origin.clone(),
                    path: format!("{}[{i}]", at.path),
                },
            )
        })
        .collect::<Result<_, _>>()?;
    Ok(Located { value, at })
}

/// The known key closest to `key` (at most 2 edits away).
fn closest<'k>(key: &str, known: &[&'k str]) -> Option<&'k str> {
    known
        .iter()
        .map(|k| (edits(key, k), *k))
        .filter(|(d, _)| *d <= 2)
        .min()
        .map(|(_, k)| k)
}

/// Levenshtein distance in characters.
fn edits(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitute = diagonal + usize::from(ca != cb);
            diagonal = row[j + 1];
            row[j + 1] = substitute.min(row[j] + 1).min(diagonal + 1);
        }
    }
    row[b.len()]
}
