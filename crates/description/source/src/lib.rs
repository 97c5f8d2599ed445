//! Suspension-file text as a tree of values that remember their file and line, from one of
//! three places: a TOML reader (feature `toml`, for files read at run time), a packed form
//! written at build time (so that the bundled files embed without a parser in the program),
//! or a [`writer::Writer`] that writes a file's text and its tree together (for files that
//! programs generate, such as the bundled `chain` for any number of stages).

pub mod packed;
pub mod source;
pub mod tree;
pub mod writer;

pub use source::{At, FileError, Located, Origin, Source, join};
pub use tree::{Node, Table, Value};
