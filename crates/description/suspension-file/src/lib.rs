//! Suspension files: a whole suspension described in TOML (parameters with units and
//! descriptions, materials, bodies, stages of blades, wires, fibres, springs and rigid links,
//! damping, element stages, named inputs and outputs), read with errors that name the file,
//! the line and the field, and interpreted into a `pendkit_model::Model`.
//!
//! The format's reference is `docs/suspension-files.md`. A file is read in four steps:
//! its TOML becomes a tree of nodes that remember their place ([`tree`]; read at run time
//! with the feature `toml`, packed at build time for the bundled files ([`packed`]), or
//! written with the text for generated files ([`writer`])), the files it
//! `extends` are merged under it, the merged tree is read into a typed description
//! ([`spec`]), and each build evaluates that description against the resolved parameters
//! ([`build`]), deriving the nominal geometry, tensions and preloads as the source's models
//! do.
//!
//! ```
//! # #[cfg(feature = "toml")] {
//! use pendkit_model::{Model, Overrides, build_with};
//! use pendkit_suspension::{NoLibrary, Suspension};
//! let text = r#"
//!     [parameters]
//!     m = { value = 40, unit = "kg", description = "the bob" }
//!     [materials.silica]
//!     youngs_modulus = 72e9
//!     poisson_ratio = 0.17
//!     density = 2200
//!     loss_angle = 1e-7
//!     [bodies.support]
//!     coordinates = "00"
//!     driven = true
//!     [bodies.bob]
//!     coordinates = "1"
//!     dof = "xyz"
//!     mass = "m"
//!     [stages.bob]
//!     from = "support"
//!     [stages.bob.fibres]
//!     upper = { at = [0.005, 0.17, 0], mirror = ["y", "x"] }
//!     lower = { at = [0.005, 0.17, 0], mirror = ["y", "x"], hinged = 1 }
//!     length = 0.6
//!     radius = 0.2e-3
//!     material = "silica"
//! "#;
//! let pendulum = Suspension::from_text("pendulum.toml", text, &NoLibrary)?;
//! let (system, _) = build_with(&pendulum, &Overrides::default())?;
//! assert_eq!(system.wires.len(), 4);
//! assert_eq!(system.coords.iter().find(|c| c.name == "z1").map(|c| c.start), Some(-0.6));
//! # }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod build;
pub mod damping;
pub mod generate;
pub mod read;
pub mod scene;
pub mod signals;
pub mod spec;
pub mod stored;

pub use pendkit_source::{packed, source, tree, writer};

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use pendkit_model::{
    BuildError, ChunkBuild, DampingSpec, DefaultsCache, Model, ParameterInfo, ParsedDamping,
    whole_number,
};
use pendkit_params::{ChunkDual, ParamError, ParamSet, Resolved, Tangent};
use pendkit_system::System;

pub use build::Reads;
pub use pendkit_model::Shape;
pub use source::{At, FileError, Located, Origin, Source};
pub use spec::Spec;

use crate::build::{Ctx, evaluate_shape};
use crate::tree::{Node, Value};
use crate::writer::Written;

/// A file embedded in the program, read at build time.
#[derive(Clone, Copy, Debug)]
pub struct BundledFile {
    /// How errors name it: its path in the repository, e.g. `models/ligo/quad.toml`.
    pub path: &'static str,
    /// Its text.
    pub text: &'static str,
    /// Its tree, packed ([`packed`]): what `extends` and `[[include]]` read.
    pub packed: &'static str,
    /// Its description as read (merged with what it extends, with what it includes),
    /// stored ([`stored`]): what running it as a model reads. Empty when not stored.
    pub stored: &'static [u8],
}

impl BundledFile {
    /// Its text as a source and its tree.
    pub fn read(&self) -> Result<(Arc<Source>, Node), FileError> {
        let source = Source::new(self.path, None, self.text);
        let root = packed::unpack(&source, self.packed)?;
        Ok((source, root))
    }
}

/// Where `extends` finds files that are not on disk: the bundled ones.
pub trait Library: Sync {
    /// The bundled file called `name` (a model name such as `quad`, or a file name such as
    /// `ligo-materials.toml`).
    fn file(&self, name: &str) -> Option<BundledFile>;
}

/// A library with no files: `extends` can only name files on disk.
pub struct NoLibrary;

impl Library for NoLibrary {
    fn file(&self, _: &str) -> Option<BundledFile> {
        None
    }
}

/// Parameters every model has; a file that does not define them gets them with these units
/// and descriptions (the model builder reads them).
pub(crate) const BUILT_IN: [(&str, f64, &str, &str, &str); 2] = [
    (
        "temperature",
        pendkit_model::DEFAULT_TEMPERATURE,
        "K",
        "temperature of the thermal noise",
        "thermal noise (system temperature)",
    ),
    (
        "wire_terms_early",
        0.0,
        "-",
        "wire terms in the equilibrium: 0 no, 1 yes, 2 equilibrium only",
        "equilibrium (which terms join it)",
    ),
];

/// A suspension whose topology is written by a program from a count parameter (the bundled
/// `chain`): each build with another count writes and reads the file again.
#[derive(Clone, Copy)]
pub struct Generator {
    /// The count parameter, e.g. `n_stages`.
    pub parameter: &'static str,
    /// Its description.
    pub description: &'static str,
    /// Allowed counts.
    pub range: (usize, usize),
    /// The count the file was written for.
    pub default: usize,
    /// Writes the file for a count: its text and its tree.
    pub write: fn(usize) -> Result<Written, FileError>,
    /// The bundled model's one-line summary (the written file's says how many).
    pub summary: &'static str,
}

/// A suspension read from a file: a [`Model`].
pub struct Suspension {
    name: String,
    summary: String,
    source_name: String,
    spec: Spec,
    damping: BTreeMap<String, DampingSpec>,
    /// `damping` parsed when the file was read (which checks it): the defaults take it.
    parsed_damping: BTreeMap<String, ParsedDamping>,
    /// The file's own parameters, with their units and domains, as checked when it was read
    /// ([`Model::parameters`] adds the built-in ones to a copy).
    file_parameters: ParamSet,
    generator: Option<Generator>,
    cache: DefaultsCache,
}

impl std::fmt::Debug for Suspension {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Suspension")
            .field("name", &self.name)
            .field("source", &self.source_name)
            .finish_non_exhaustive()
    }
}

impl Suspension {
    /// Reads the suspension file at `path`; `extends` names files relative to it, or
    /// bundled models by name through `library`.
    #[cfg(feature = "toml")]
    pub fn load(path: &Path, library: &dyn Library) -> Result<Suspension, FileError> {
        let name = path.display().to_string();
        let text = pendkit_limits::read_text(path)
            .map_err(|e| FileError::file(&name, format!("cannot read: {e}")))?;
        Suspension::from_source(Source::new(name, Some(path), text), library)
    }

    /// Reads a suspension from `text`, called `name` in errors (its stem is the default
    /// model name); `extends` can only name bundled files through `library`.
    #[cfg(feature = "toml")]
    pub fn from_text(
        name: &str,
        text: &str,
        library: &dyn Library,
    ) -> Result<Suspension, FileError> {
        Suspension::from_source(Source::new(name, None, text), library)
    }

    /// Reads a suspension from a source (its text parsed as TOML); a source with a path
    /// finds the files it `extends` beside it.
    #[cfg(feature = "toml")]
    pub fn from_source(
        source: Arc<Source>,
        library: &dyn Library,
    ) -> Result<Suspension, FileError> {
        let root = tree::parse(&source)?;
        Suspension::from_tree(source, root, library)
    }

    /// The bundled file called `name` in `library` (a model name or a file name), read from
    /// its packed tree.
    pub fn bundled(name: &str, library: &dyn Library) -> Result<Suspension, FileError> {
        let file = library
            .file(name)
            .ok_or_else(|| FileError::file(name, "no bundled file of this name"))?;
        if file.stored.is_empty() {
            let (source, root) = file.read()?;
            return Suspension::from_tree(source, root, library);
        }
        let (spec, damping) = stored::load_bundled(&file, library)?;
        Suspension::from_spec(file.path, spec, Some(damping))
    }

    /// A bundled suspension whose file is written by `generator` (for its default count),
    /// called `name` in errors.
    pub fn generated(
        name: &str,
        generator: Generator,
        library: &dyn Library,
    ) -> Result<Suspension, FileError> {
        let Written { source, root } = (generator.write)(generator.default)?.named(name);
        let mut s = Suspension::from_tree(source, root, library)?;
        s.summary = generator.summary.to_string();
        s.generator = Some(generator);
        Ok(s)
    }

    /// Reads a suspension from the tree `root` read from `source`'s text.
    pub fn from_tree(
        source: Arc<Source>,
        root: Node,
        library: &dyn Library,
    ) -> Result<Suspension, FileError> {
        let spec = read_spec(&source, root, library)?;
        Suspension::from_spec(&source.name, spec, None)
    }

    /// A suspension from its description `spec`, read from the file called `source_name`:
    /// its parameters checked, and its damping as `damping` gives it (stored) or else
    /// derived and parsed here.
    fn from_spec(
        source_name: &str,
        spec: Spec,
        damping: Option<Damping>,
    ) -> Result<Suspension, FileError> {
        // an empty file, or a case file's text without its `model` line, reads as a
        // suspension with nothing in it: say that, not "no variables" later
        if spec.bodies.is_empty() {
            return Err(FileError::file(
                source_name,
                "no bodies: a suspension file describes its bodies in [bodies.NAME] tables, \
                 and a case file names its model first (model = \"quad\")",
            ));
        }
        let stem = Path::new(source_name)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let name = spec.name.as_ref().map_or(stem, |n| n.value.clone());
        let summary = spec.summary.as_ref().map_or_else(
            || format!("suspension file {source_name}"),
            |s| s.value.clone(),
        );
        let file_parameters = file_parameters(&spec)?;
        let Damping { damping, parsed } = match damping {
            Some(d) => d,
            None => Damping::of(source_name, &spec)?,
        };
        Ok(Suspension {
            name,
            summary,
            source_name: source_name.to_string(),
            spec,
            damping,
            parsed_damping: parsed,
            file_parameters,
            generator: None,
            cache: DefaultsCache::new(),
        })
    }

    /// The description as read.
    pub fn spec(&self) -> &Spec {
        &self.spec
    }

    /// How errors name the file.
    pub fn source_name(&self) -> &str {
        &self.source_name
    }

    /// The description to build at `params`: the file's, or for a generated suspension the
    /// one written for the count `params` asks for.
    fn spec_for(&self, params: &Resolved) -> Result<std::borrow::Cow<'_, Spec>, BuildError> {
        let Some(g) = &self.generator else {
            return Ok(std::borrow::Cow::Borrowed(&self.spec));
        };
        let n = whole_number(params, g.parameter, g.range.0..=g.range.1)?;
        if n == g.default {
            return Ok(std::borrow::Cow::Borrowed(&self.spec));
        }
        let generated = |e: FileError| BuildError::Invalid {
            item: format!("generated {} with {n} {}", self.name, g.parameter),
            message: e.to_string(),
        };
        let Written { source, root } = (g.write)(n).map_err(generated)?.named(&self.source_name);
        // the description only: the damping and the parameters are the bundled file's
        let other = read_spec(&source, root, &NoLibrary).map_err(generated)?;
        Ok(std::borrow::Cow::Owned(other))
    }

    /// The drawing shape of each body that gives one, at `params` (sizes in m).
    pub fn shapes(&self, params: &Resolved) -> Result<Vec<(String, Shape)>, BuildError> {
        let ctx = Ctx {
            params,
            reads: None,
            values: params,
            lost: None,
        };
        self.spec
            .bodies
            .iter()
            .filter_map(|b| b.shape.as_ref().map(|s| (b, s)))
            .map(|(b, s)| Ok((b.name.clone(), evaluate_shape(&ctx, s)?)))
            .collect()
    }

    /// The model at `params`, its expressions evaluated with `values` of the build's scalar
    /// (`params` itself for the `f64` model, a tangent for the dual-number one); `lost`
    /// collects the derivatives a dual build cannot carry (see [`build::Ctx::lost`]).
    fn build_in<S: build::BuildScalar>(
        &self,
        params: &Resolved,
        values: &dyn pendkit_params::Values<S>,
        lost: Option<&build::Lost>,
    ) -> Result<System<S>, BuildError> {
        let spec = self.spec_for(params)?;
        build::build(
            &spec,
            &Ctx {
                params,
                reads: None,
                values,
                lost,
            },
        )
    }

    /// Builds at `params`, recording which field read which parameter.
    pub fn build_recorded(&self, params: &Resolved) -> Result<(System, Reads), BuildError> {
        let reads = RefCell::new(Reads::default());
        let spec = self.spec_for(params)?;
        let ctx = Ctx {
            params,
            reads: Some(&reads),
            values: params,
            lost: None,
        };
        let system = build::build(&spec, &ctx)?;
        if let Some(g) = &self.generator {
            reads
                .borrow_mut()
                .add(g.parameter, "the generator (the stages it writes)");
        }
        Ok((system, reads.into_inner()))
    }
}

/// The damping a description implies: each tag's fields, and the same parsed.
pub(crate) struct Damping {
    damping: BTreeMap<String, DampingSpec>,
    parsed: BTreeMap<String, ParsedDamping>,
}

impl Damping {
    /// The damping `spec` (read from the file called `source_name`) implies, each tag's
    /// fields parsed, which checks them.
    fn of(source_name: &str, spec: &Spec) -> Result<Damping, FileError> {
        let damping = damping::damping(spec)?;
        let mut parsed = BTreeMap::new();
        for (tag, d) in &damping {
            let p = d.parse(tag).map_err(|e| {
                spec.damping.iter().find(|x| &x.tag == tag).map_or_else(
                    || FileError::file(source_name, e.to_string()),
                    |x| x.at.error(e.to_string()),
                )
            })?;
            parsed.insert(tag.clone(), p);
        }
        Ok(Damping { damping, parsed })
    }
}

/// The description read from the tree `root` of `source`, merged over the files it extends,
/// with the suspensions it includes.
pub(crate) fn read_spec(
    source: &Arc<Source>,
    root: Node,
    library: &dyn Library,
) -> Result<Spec, FileError> {
    read_scene(source, root, library, &mut Vec::new(), &mut 0)
}

/// Deepest nesting of `extends` and `[[include]]` a suspension may have: every file in the
/// chain is read recursively, and no suspension needs more than a few levels (the bundled
/// `arm-cavity` has 4). Not raisable: the recursion's stack, not time, is what it guards.
pub const MAX_FILE_DEPTH: usize = 32;

/// Counts the file about to be read at `at`, `chain` the files that lead to it: refused
/// past [`MAX_FILE_DEPTH`] levels, or past [`pendkit_limits::INCLUDED_FILES`] files read
/// for one suspension (`read`, counted over every branch: includes nest, and a file that
/// includes another twice, which includes another twice, ... would read 2^depth files).
fn count_file(at: &At, chain: &[String], read: &mut usize) -> Result<(), FileError> {
    if chain.len() >= MAX_FILE_DEPTH {
        return Err(at.error(format!(
            "`extends` and includes nested {} deep: at most {MAX_FILE_DEPTH} ({})",
            chain.len() + 1,
            chain.join(" -> ")
        )));
    }
    *read += 1;
    pendkit_limits::INCLUDED_FILES
        .check(*read)
        .map_err(|e| at.error(e.to_string()))
}

/// [`read_spec`] of a file reached through `chain` (the files that extend or include it, in
/// order: a file met again goes round in a circle); `read` counts the files read so far for
/// the whole suspension ([`count_file`]).
fn read_scene(
    source: &Arc<Source>,
    root: Node,
    library: &dyn Library,
    chain: &mut Vec<String>,
    read: &mut usize,
) -> Result<Spec, FileError> {
    let mut root = load_tree(source, root, library, chain, read)?;
    let includes = scene::take_includes(&mut root)?;
    let at = At {
        origin: root.origin.clone(),
        path: String::new(),
    };
    let own = spec::read(&root, at)?;
    if includes.is_empty() {
        return Ok(own);
    }
    let mut assembled = scene::Scene::default();
    for include in &includes {
        let at = At {
            origin: include.model.at.origin.clone(),
            path: include.model.at.path.clone(),
        };
        count_file(&include.model.at, chain, read)?;
        let (sub_source, sub_root) = open(&include.model.value, &at, library)?;
        if chain.contains(&sub_source.name) {
            return Err(include.model.at.error(format!(
                "include goes round in a circle: {} -> {}",
                chain.join(" -> "),
                sub_source.name
            )));
        }
        // each include starts from this file's chain: two includes of one file are fine
        let mut sub_chain = chain.clone();
        let mut sub = read_scene(&sub_source, sub_root, library, &mut sub_chain, read)?;
        scene::Prefix(&include.prefix.value).spec(&mut sub)?;
        assembled.add(sub, include)?;
    }
    assembled.finish(own)
}

/// The file an `extends` or an `include` at `at` names: a path ending in `.toml` relative to
/// the file that names it (when that file was read from disk), or a bundled file's name.
fn open(target: &str, at: &At, library: &dyn Library) -> Result<(Arc<Source>, Node), FileError> {
    let naming = &at.origin.source;
    if target.ends_with(".toml")
        && let Some(path) = &naming.path
    {
        let dir = path.parent().unwrap_or_else(|| Path::new(""));
        return read_beside(&dir.join(target), at);
    }
    let file = library.file(target).ok_or_else(|| {
        at.error(format!(
            "no file '{target}'{}",
            if target.ends_with(".toml") {
                " among the bundled files"
            } else {
                " (a bundled model name, or a path ending in .toml)"
            }
        ))
    })?;
    file.read()
}

/// Defines the file's parameters and resolves them, reporting a problem at the parameter it
/// concerns.
/// The file's parameters as a set (each expression as its reader parsed it), with their units
/// and domains, checked: each resolves, without cycles, inside its domain.
fn file_parameters(spec: &Spec) -> Result<ParamSet, FileError> {
    let mut set = ParamSet::new();
    let at_param = |name: &str| spec.parameters.iter().find(|p| p.name == name);
    let fail = |name: &str, e: ParamError| match at_param(name) {
        Some(p) => p.at.error(e.to_string()),
        None => FileError::file("parameters", e.to_string()),
    };
    for p in &spec.parameters {
        set.define_parsed(&p.name, p.value.expr.clone(), &p.value.text)
            .map_err(|e| p.at.error(e.to_string()))?;
        if !p.unit.is_empty() {
            set.set_unit(&p.name, unit_of(&p.unit))
                .map_err(|e| p.at.error(e.to_string()))?;
        }
        // a default outside its own declared domain is the file's error, at its line
        if let Some(domain) = &p.domain {
            set.set_domain(&p.name, domain.value)
                .map_err(|e| p.at.error(e.to_string()))?;
        }
    }
    match set.resolve() {
        Ok(_) => Ok(set),
        Err(e) => Err(match &e {
            ParamError::Cycle { chain } => fail(&chain[0], e.clone()),
            ParamError::Undefined { used_in, .. } => fail(used_in, e.clone()),
            ParamError::NotFinite { name, .. }
            | ParamError::Syntax { name, .. }
            | ParamError::OutOfRange { name, .. } => fail(name, e.clone()),
            _ => FileError::file("parameters", e.to_string()),
        }),
    }
}

/// The tree `node` of `source` merged over the files it extends (the extending file's values
/// win).
fn load_tree(
    source: &Arc<Source>,
    mut node: Node,
    library: &dyn Library,
    chain: &mut Vec<String>,
    read: &mut usize,
) -> Result<Node, FileError> {
    if chain.contains(&source.name) {
        chain.push(source.name.clone());
        return Err(FileError::file(
            &source.name,
            format!("`extends` goes round in a circle: {}", chain.join(" -> ")),
        ));
    }
    chain.push(source.name.clone());
    let Value::Table(table) = &mut node.value else {
        return Ok(node);
    };
    let Some(extends) = table.remove("extends") else {
        return Ok(node);
    };
    let at = At {
        origin: extends.origin.clone(),
        path: "extends".into(),
    };
    let Value::Str(target) = &extends.value else {
        return Err(at.error("expected the name of a file or of a bundled model"));
    };
    count_file(&at, chain, read)?;
    let (base_source, base) = open(target, &at, library)?;
    let mut base = load_tree(&base_source, base, library, chain, read)?;
    let Value::Table(base_table) = &mut base.value else {
        return Ok(node);
    };
    // a file's name and summary are its own
    base_table.remove("name");
    base_table.remove("summary");
    keep_parameter_documentation(base_table, &mut node);
    if let Value::Table(mut child) = std::mem::replace(&mut node.value, Value::Bool(false)) {
        carry_entries(base_table, &mut child, "element", "name");
        carry_entries(base_table, &mut child, "include", "prefix");
        base_table.merge(child);
    }
    Ok(Node {
        value: base.value,
        origin: node.origin,
    })
}

/// Arrays of tables that add up along `extends` (`[[element]]` instances, a scene's
/// `[[include]]`s): the extending file's entries follow the base's, and one with the `id`
/// (`name`, `prefix`) of a base entry replaces it (as a key replaces a key). Anything but
/// two arrays is left to the ordinary merge.
fn carry_entries(base: &mut tree::Table, child: &mut tree::Table, key: &str, id: &str) {
    let (Some(mine), Some(theirs)) = (base.get(key), child.get(key)) else {
        return;
    };
    let (Value::Array(mine), Value::Array(theirs)) = (&mine.value, &theirs.value) else {
        return;
    };
    let name = |n: &Node| match &n.value {
        Value::Table(t) => t.get(id).and_then(|v| match &v.value {
            Value::Str(s) => Some(s.clone()),
            _ => None,
        }),
        _ => None,
    };
    let replaced: Vec<String> = theirs.iter().filter_map(name).collect();
    let mut all: Vec<Node> = mine
        .iter()
        .filter(|n| name(n).is_none_or(|m| !replaced.contains(&m)))
        .cloned()
        .collect();
    all.extend(theirs.iter().cloned());
    if let Some((_, _, node)) = child.entries.iter_mut().find(|(k, _, _)| k == key) {
        node.value = Value::Array(all);
    }
}

/// The file at `path` that an `extends` at `at` names, read.
#[cfg(feature = "toml")]
fn read_beside(path: &Path, at: &At) -> Result<(Arc<Source>, Node), FileError> {
    let text = pendkit_limits::read_text(path)
        .map_err(|e| at.error(format!("cannot read {}: {e}", path.display())))?;
    let source = Source::new(path.display().to_string(), Some(path), text);
    let root = tree::parse(&source)?;
    Ok((source, root))
}

/// Without a TOML reader only bundled files can be extended (files on disk come with one:
/// their `Source` has a path only when `Suspension::load` read them).
#[cfg(not(feature = "toml"))]
fn read_beside(path: &Path, at: &At) -> Result<(Arc<Source>, Node), FileError> {
    Err(at.error(format!(
        "cannot read {}: reading suspension files needs the `toml` feature of pendkit-suspension",
        path.display()
    )))
}

/// A parameter that an extending file gives in the short form (`n_beads = 5`) keeps the
/// unit and description of the extended file's long form: the short form becomes
/// `{ value = 5 }`, which the merge folds into the long one.
fn keep_parameter_documentation(base: &tree::Table, child: &mut Node) {
    let Some(Value::Table(base_parameters)) = base.get("parameters").map(|n| &n.value) else {
        return;
    };
    let Value::Table(child) = &mut child.value else {
        return;
    };
    let Some((_, _, parameters)) = child.entries.iter_mut().find(|(k, _, _)| k == "parameters")
    else {
        return;
    };
    let Value::Table(parameters) = &mut parameters.value else {
        return;
    };
    for (name, key_origin, value) in &mut parameters.entries {
        let documented = matches!(
            base_parameters.get(name).map(|n| &n.value),
            Some(Value::Table(_))
        );
        if documented && !matches!(value.value, Value::Table(_)) {
            let short = value.clone();
            *value = Node {
                value: Value::Table(tree::Table {
                    entries: vec![("value".to_string(), key_origin.clone(), short)],
                }),
                origin: value.origin.clone(),
            };
        }
    }
}

/// A unit as reports print it: the file's `-` (a pure number or a count) is no unit.
fn unit_of(written: &str) -> &str {
    if written.trim() == "-" { "" } else { written }
}

impl Model for Suspension {
    fn name(&self) -> &str {
        &self.name
    }

    fn summary(&self) -> &str {
        &self.summary
    }

    fn parameters(&self) -> Result<ParamSet, ParamError> {
        let mut set = self.file_parameters.clone();
        if let Some(g) = &self.generator {
            set.define_value(g.parameter, g.default as f64)?;
            set.set_unit(g.parameter, "")?;
        }
        for (name, value, unit, ..) in BUILT_IN {
            if !set.contains(name) {
                set.define_value(name, value)?;
                set.set_unit(name, unit_of(unit))?;
            }
        }
        Ok(set)
    }

    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        self.damping.clone()
    }

    fn parsed_damping(&self) -> Result<BTreeMap<String, ParsedDamping>, BuildError> {
        Ok(self.parsed_damping.clone())
    }

    fn build(&self, params: &Resolved) -> Result<System, BuildError> {
        self.build_in(params, params, None)
    }

    fn defaults_cache(&self) -> Option<&DefaultsCache> {
        Some(&self.cache)
    }

    fn build_tangents(
        &self,
        params: &Resolved,
        tangent: &Tangent<ChunkDual>,
    ) -> Result<ChunkBuild, BuildError> {
        let lost = build::Lost::default();
        if let Some(g) = &self.generator
            && let Some(k) = tangent.seeds().iter().position(|s| **s == *g.parameter)
        {
            lost.borrow_mut().push((
                1 << k,
                BuildError::Invalid {
                    item: format!("parameter '{}'", g.parameter),
                    message: "no exact derivative: it is a count (the generator's)".into(),
                },
            ));
        }
        let system = self.build_in(params, tangent, Some(&lost))?;
        Ok(ChunkBuild {
            system,
            lost: lost.into_inner(),
        })
    }

    fn parameter_info(&self, params: &Resolved) -> Result<Vec<ParameterInfo>, BuildError> {
        let (_, mut reads) = self.build_recorded(params)?;
        for (tag, symbols) in build::damping_reads(&self.damping) {
            for s in symbols {
                if params.get(&s).is_ok() {
                    reads.add(&s, &format!("damping.{tag}"));
                }
            }
        }
        for (name, _, _, _, reader) in BUILT_IN {
            reads.add(name, reader);
        }
        Ok(params
            .iter()
            .map(|(name, _)| {
                let file = self.spec.parameters.iter().find(|p| p.name == name);
                let built_in = BUILT_IN.iter().find(|b| b.0 == name);
                let generated = self.generator.filter(|g| g.parameter == name);
                let (unit, description) = match (file, built_in, generated) {
                    (Some(p), _, _) => (p.unit.clone(), p.description.clone()),
                    (None, Some(b), _) => (b.2.to_string(), b.3.to_string()),
                    (None, None, Some(g)) => ("-".to_string(), g.description.to_string()),
                    _ => (String::new(), String::new()),
                };
                ParameterInfo {
                    name: name.to_string(),
                    unit,
                    description,
                    read_by: reads.of(name).to_vec(),
                }
            })
            .collect())
    }
}
