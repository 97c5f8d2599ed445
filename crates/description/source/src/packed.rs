//! A tree packed into a string at build time and unpacked at run time, so that the bundled
//! files are embedded already read: the program needs no TOML parser for them, and reading a
//! bundled model skips the parse.
//!
//! The packed form is a flat list of tokens, each a letter followed by its fields, integers
//! in decimal ended by `;`, text as its byte length, `:` and the bytes:
//!
//! ```text
//! node  = start ";" end ";" value            (the value's byte span in the file)
//! value = "s" text | "n" text | "t" | "f"    (string, number as written, true, false)
//!       | "o" index ";"                      (one of tree::OTHER_KINDS)
//!       | "a" count ";" node*                (array)
//!       | "m" count ";" (start ";" end ";" text node)*   (table: key span, key, value)
//! text  = length ";" bytes
//! ```

use std::fmt::Write as _;
use std::sync::Arc;

use crate::source::{FileError, Origin, Source};
use crate::tree::{Node, OTHER_KINDS, Table, Value};

/// The packed form of `node`.
pub fn pack(node: &Node) -> String {
    let mut out = String::new();
    pack_node(node, &mut out);
    out
}

fn pack_span(origin: &Origin, out: &mut String) {
    let _ = write!(out, "{};{};", origin.span.start, origin.span.end);
}

fn pack_text(text: &str, out: &mut String) {
    let _ = write!(out, "{};{text}", text.len());
}

fn pack_node(node: &Node, out: &mut String) {
    pack_span(&node.origin, out);
    match &node.value {
        Value::Str(s) => {
            out.push('s');
            pack_text(s, out);
        }
        Value::Num(n) => {
            out.push('n');
            pack_text(n, out);
        }
        Value::Bool(true) => out.push('t'),
        Value::Bool(false) => out.push('f'),
        Value::Other(kind) => {
            let index = OTHER_KINDS.iter().position(|k| k == kind).unwrap_or(0);
            let _ = write!(out, "o{index};");
        }
        Value::Array(items) => {
            let _ = write!(out, "a{};", items.len());
            for item in items {
                pack_node(item, out);
            }
        }
        Value::Table(table) => {
            let _ = write!(out, "m{};", table.entries.len());
            for (key, key_origin, value) in &table.entries {
                pack_span(key_origin, out);
                pack_text(key, out);
                pack_node(value, out);
            }
        }
    }
}

/// The tree packed in `packed` from the file `source` (whose text the spans point into).
/// An error means the packed form does not belong to this program (it is written by the
/// build): it names the file and the byte where reading stopped.
pub fn unpack(source: &Arc<Source>, packed: &str) -> Result<Node, FileError> {
    let mut reader = Reader {
        source,
        packed,
        at: 0,
    };
    let node = reader.node(0)?;
    if reader.at != packed.len() {
        return Err(reader.corrupt());
    }
    Ok(node)
}

/// Deeper nesting than any file writes: a corrupt count cannot recurse without end.
const MAX_DEPTH: usize = 64;

struct Reader<'a> {
    source: &'a Arc<Source>,
    packed: &'a str,
    at: usize,
}

impl Reader<'_> {
    fn corrupt(&self) -> FileError {
        FileError::file(
            &self.source.name,
            format!(
                "the embedded (packed) form of this file is corrupt at byte {}: rebuild the program",
                self.at
            ),
        )
    }

    fn letter(&mut self) -> Result<u8, FileError> {
        let b = *self
            .packed
            .as_bytes()
            .get(self.at)
            .ok_or_else(|| self.corrupt())?;
        self.at += 1;
        Ok(b)
    }

    fn integer(&mut self) -> Result<usize, FileError> {
        // digits up to the `;`, read in the one pass that finds it (most of a packed file
        // is these integers: `str::parse` after a search for the `;` was a tenth of reading
        // the quad). The packed form is ASCII up to its texts, which `text` skips whole.
        let bytes = self.packed.as_bytes();
        let mut value: usize = 0;
        let mut at = self.at;
        loop {
            match bytes.get(at) {
                Some(b';') if at > self.at => break,
                Some(&d @ b'0'..=b'9') => {
                    value = value
                        .checked_mul(10)
                        .and_then(|v| v.checked_add(usize::from(d - b'0')))
                        .ok_or_else(|| self.corrupt())?;
                    at += 1;
                }
                _ => return Err(self.corrupt()),
            }
        }
        self.at = at + 1;
        Ok(value)
    }

    fn text(&mut self) -> Result<String, FileError> {
        let len = self.integer()?;
        let text = self
            .packed
            .get(self.at..self.at.saturating_add(len))
            .ok_or_else(|| self.corrupt())?;
        self.at += len;
        Ok(text.to_string())
    }

    fn origin(&mut self) -> Result<Origin, FileError> {
        let start = self.integer()?;
        let end = self.integer()?;
        if start > end || end > self.source.text.len() {
            return Err(self.corrupt());
        }
        Ok(Origin {
            source: self.source.clone(),
            span: start..end,
        })
    }

    fn node(&mut self, depth: usize) -> Result<Node, FileError> {
        if depth > MAX_DEPTH {
            return Err(self.corrupt());
        }
        let origin = self.origin()?;
        let value = match self.letter()? {
            b's' => Value::Str(self.text()?),
            b'n' => Value::Num(self.text()?),
            b't' => Value::Bool(true),
            b'f' => Value::Bool(false),
            b'o' => {
                let index = self.integer()?;
                Value::Other(OTHER_KINDS.get(index).ok_or_else(|| self.corrupt())?)
            }
            b'a' => {
                let count = self.integer()?;
                // each node takes at least 5 bytes: a count beyond what is left is corrupt
                if count > self.packed.len() - self.at {
                    return Err(self.corrupt());
                }
                let items = (0..count)
                    .map(|_| self.node(depth + 1))
                    .collect::<Result<_, _>>()?;
                Value::Array(items)
            }
            b'm' => {
                let count = self.integer()?;
                if count > self.packed.len() - self.at {
                    return Err(self.corrupt());
                }
                let mut entries = Vec::with_capacity(count);
                for _ in 0..count {
                    let key_origin = self.origin()?;
                    let key = self.text()?;
                    entries.push((key, key_origin, self.node(depth + 1)?));
                }
                Value::Table(Table { entries })
            }
            _ => return Err(self.corrupt()),
        };
        Ok(Node { value, origin })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::writer::{Item, Writer};

    fn same(a: &Node, b: &Node) -> bool {
        a.origin.span == b.origin.span
            && match (&a.value, &b.value) {
                (Value::Str(x), Value::Str(y)) | (Value::Num(x), Value::Num(y)) => x == y,
                (Value::Bool(x), Value::Bool(y)) => x == y,
                (Value::Other(x), Value::Other(y)) => x == y,
                (Value::Array(x), Value::Array(y)) => {
                    x.len() == y.len() && x.iter().zip(y).all(|(p, q)| same(p, q))
                }
                (Value::Table(x), Value::Table(y)) => {
                    x.entries.len() == y.entries.len()
                        && x.entries
                            .iter()
                            .zip(&y.entries)
                            .all(|(p, q)| p.0 == q.0 && p.1.span == q.1.span && same(&p.2, &q.2))
                }
                _ => false,
            }
    }

    /// Packing and unpacking gives back every value, key and span (strings with the
    /// packed form's own delimiters and multi-byte characters included).
    #[test]
    fn unpack_inverts_pack() {
        let mut w = Writer::new();
        w.entry("name", Item::str("a;b:c 3;x — µ"));
        w.section(&["parameters"]);
        w.entry(
            "m",
            Item::Inline(vec![
                ("value".into(), Item::num("40")),
                ("unit".into(), Item::str("kg")),
            ]),
        );
        w.entry("on", Item::Bool(false));
        w.entry("at", Item::Array(vec![Item::num("1e-3"), Item::str("a")]));
        let written = w.finish("t.toml");
        let packed = pack(&written.root);
        let back = unpack(&written.source, &packed).unwrap();
        assert!(same(&back, &written.root));
    }

    /// A damaged packed form is an error naming the file, never a panic.
    #[test]
    fn corrupt_packed_forms_are_errors() {
        let source = Source::new("x.toml", None, "a = 1\n");
        for bad in [
            "",
            "0;0;",
            "0;0;m1;",
            "0;0;m99999;",
            "0;9;t",
            "0;0;q",
            "0;0;s5;ab",
            "0;0;tt",
        ] {
            let e = unpack(&source, bad).unwrap_err();
            assert!(e.to_string().starts_with("x.toml: "), "{e}");
        }
    }
}
