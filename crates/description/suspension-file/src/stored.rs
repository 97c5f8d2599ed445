//! A bundled file's description as read ([`Spec`]) and the damping it implies, stored as
//! bytes at build time and read back at run time, so that running a bundled model neither
//! unpacks, merges and reads its file (and the files it extends or includes) nor parses an
//! expression: models/bundled/build.rs writes each bundled file's with [`store_bundled`], and
//! [`Suspension::bundled`](crate::Suspension::bundled) reads it back. Every value keeps its
//! place (file, span and field path), so an error about a bundled value still names its line.
//!
//! The form belongs to the build that wrote it (the program embeds it; nothing else reads
//! it): an error reading it means the bytes are not this program's, and names the file.
//!
//! ```text
//! stored = count path* spec tags        (the bundled files the places point into, by index)
//! tags   = count (tag count (field text expression)*)*     (each damping tag's fields)
//! count  = unsigned LEB128 integer      (also lengths, indices, spans and enum tags)
//! f64    = its 8 bytes, little-endian   (exact)
//! string = count bytes                  (UTF-8)
//! option = 0 | 1 value;  vec = count value*;  enum = tag fields
//! place  = file-index start end path    (`At`: the file, its byte span, the field path)
//! ```
//!
//! Each struct lists its fields once, in `stored_struct!`; the list destructures the
//! struct without `..`, so a field added to the description and not here fails to compile.

use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use pendkit_expr::{BinOp, Expr, Func};
use pendkit_model::beads::BeadJoints;
use pendkit_model::schema::{DAMPING_FIELDS, Domain, Field};
use pendkit_model::{DampingSpec, ParsedDamping};
use pendkit_system::{CoordKind, Stage};

use crate::read::Ex;
use crate::source::{At, FileError, Located, Origin, Source};
use crate::spec::{
    BladeFields, BladeForm, BladeSet, BodyFile, CoordinateSpec, DampingFile, ElementChoice,
    ExtraFile, Inertia, InstanceFile, LinkFile, MaterialSpec, NameSchemeFile, Names, ParameterSpec,
    Points, ProfileFile, SectionFile, ShapeFile, SignalFile, Spec, SpringSet, StageFile, WireSet,
};
use crate::{BundledFile, Damping, Library};

/// The stored form of the bundled file `name` of `library`: its description read from its
/// packed tree, merged with what it extends, with what it includes, and the damping it
/// implies (for models/bundled/build.rs).
pub fn store_bundled(name: &str, library: &dyn Library) -> Result<Vec<u8>, FileError> {
    let file = library
        .file(name)
        .ok_or_else(|| FileError::file(name, "no bundled file of this name"))?;
    let (source, root) = file.read()?;
    let spec = crate::read_spec(&source, root, library)?;
    let damping = Damping::of(file.path, &spec)?;
    // each tag's fields with their texts and expressions, parsed again here to be stored
    let mut tags = Vec::new();
    for (tag, d) in &damping.damping {
        let mut fields = Vec::new();
        for (field, text) in d.fields() {
            let expr =
                pendkit_expr::parse(text).map_err(|e| FileError::file(name, e.to_string()))?;
            fields.push((field, (text.to_string(), expr)));
        }
        tags.push((tag.clone(), fields));
    }
    let mut body = Writer::default();
    spec.put(&mut body);
    tags.put(&mut body);
    let mut head = Writer::default();
    head.count(body.files.len());
    for file in &body.files {
        file.name.put(&mut head);
    }
    head.bytes.extend_from_slice(&body.bytes);
    Ok(head.bytes)
}

/// The description and damping stored with the bundled `file` by [`store_bundled`], its
/// places in the bundled files of `library` (each found by its file name, and checked to be
/// the same file).
pub(crate) fn load_bundled(
    file: &BundledFile,
    library: &dyn Library,
) -> Result<(Spec, Damping), FileError> {
    let corrupt = |at: usize| {
        FileError::file(
            file.path,
            format!(
                "the embedded (stored) description of this file is corrupt at byte {at}: \
                 rebuild the program"
            ),
        )
    };
    let mut r = Reader {
        bytes: file.stored,
        at: 0,
        files: Vec::new(),
        depth: 0,
    };
    let count = r.length().map_err(|Corrupt| corrupt(r.at))?;
    for _ in 0..count {
        let path = String::take(&mut r).map_err(|Corrupt| corrupt(r.at))?;
        let found = Path::new(&path)
            .file_name()
            .and_then(|n| library.file(n.to_str()?))
            .filter(|f| f.path == path)
            .ok_or_else(|| corrupt(r.at))?;
        r.files.push(Source::new(found.path, None, found.text));
    }
    let spec = Spec::take(&mut r).map_err(|Corrupt| corrupt(r.at))?;
    let tags = Tags::take(&mut r).map_err(|Corrupt| corrupt(r.at))?;
    if r.at != r.bytes.len() {
        return Err(corrupt(r.at));
    }
    let mut damping = Damping {
        damping: BTreeMap::new(),
        parsed: BTreeMap::new(),
    };
    for (tag, fields) in tags {
        let mut d = DampingSpec::default();
        let mut parts = Vec::with_capacity(fields.len());
        for (field, (text, expr)) in fields {
            // the field came from the schema's list: it has its slot
            d.set_field(field.name, &text).map_err(|_| corrupt(r.at))?;
            parts.push((field, expr));
        }
        damping
            .parsed
            .insert(tag.clone(), ParsedDamping::from_parts(d.clone(), parts));
        damping.damping.insert(tag, d);
    }
    Ok((spec, damping))
}

/// Each damping tag with its fields set, each field's text and expression.
type Tags = Vec<(String, Vec<(&'static Field, (String, Expr))>)>;

/// The bytes end early or hold something no [`store_bundled`] writes.
#[derive(Debug)]
struct Corrupt;

#[derive(Default)]
struct Writer {
    bytes: Vec<u8>,
    /// The files the places written so far point into, in the order of their indices.
    files: Vec<Arc<Source>>,
}

impl Writer {
    fn count(&mut self, mut n: usize) {
        loop {
            let low = (n & 0x7f) as u8;
            n >>= 7;
            if n == 0 {
                self.bytes.push(low);
                return;
            }
            self.bytes.push(low | 0x80);
        }
    }

    /// The index of `source` among the files (added if new).
    fn file(&mut self, source: &Arc<Source>) -> usize {
        if let Some(i) = self.files.iter().position(|f| f.name == source.name) {
            return i;
        }
        self.files.push(source.clone());
        self.files.len() - 1
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
    files: Vec<Arc<Source>>,
    /// How deep in an expression the reader is: corrupt bytes cannot recurse without end.
    depth: usize,
}

/// Deeper than any expression the parser accepts.
const MAX_DEPTH: usize = 256;

impl Reader<'_> {
    fn byte(&mut self) -> Result<u8, Corrupt> {
        let b = *self.bytes.get(self.at).ok_or(Corrupt)?;
        self.at += 1;
        Ok(b)
    }

    fn count(&mut self) -> Result<usize, Corrupt> {
        let mut n: usize = 0;
        for shift in (0..usize::BITS).step_by(7) {
            let b = self.byte()?;
            n |= usize::from(b & 0x7f).checked_shl(shift).ok_or(Corrupt)?;
            if b & 0x80 == 0 {
                return Ok(n);
            }
        }
        Err(Corrupt)
    }

    /// A count of items that each take at least one byte: a corrupt count cannot ask for
    /// more memory than the bytes left.
    fn length(&mut self) -> Result<usize, Corrupt> {
        let n = self.count()?;
        if n > self.bytes.len() - self.at {
            return Err(Corrupt);
        }
        Ok(n)
    }

    fn slice(&mut self, len: usize) -> Result<&[u8], Corrupt> {
        let end = self.at.checked_add(len).ok_or(Corrupt)?;
        let s = self.bytes.get(self.at..end).ok_or(Corrupt)?;
        self.at = end;
        Ok(s)
    }
}

/// A value that can be stored.
trait Stored: Sized {
    fn put(&self, w: &mut Writer);
    fn take(r: &mut Reader) -> Result<Self, Corrupt>;
}

impl Stored for usize {
    fn put(&self, w: &mut Writer) {
        w.count(*self);
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        r.count()
    }
}

impl Stored for bool {
    fn put(&self, w: &mut Writer) {
        w.bytes.push(u8::from(*self));
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        match r.byte()? {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(Corrupt),
        }
    }
}

impl Stored for f64 {
    fn put(&self, w: &mut Writer) {
        w.bytes.extend_from_slice(&self.to_le_bytes());
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        let bytes = r.slice(8)?.try_into().map_err(|_| Corrupt)?;
        Ok(f64::from_le_bytes(bytes))
    }
}

impl Stored for String {
    fn put(&self, w: &mut Writer) {
        w.count(self.len());
        w.bytes.extend_from_slice(self.as_bytes());
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        let len = r.count()?;
        let bytes = r.slice(len)?;
        std::str::from_utf8(bytes)
            .map(str::to_string)
            .map_err(|_| Corrupt)
    }
}

/// The only `&'static str` of a description is a wire set's slot.
impl Stored for &'static str {
    fn put(&self, w: &mut Writer) {
        w.count(usize::from(*self == "fibres"));
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        ["wires", "fibres"].get(r.count()?).copied().ok_or(Corrupt)
    }
}

impl<T: Stored> Stored for Option<T> {
    fn put(&self, w: &mut Writer) {
        match self {
            None => w.bytes.push(0),
            Some(v) => {
                w.bytes.push(1);
                v.put(w);
            }
        }
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        match r.byte()? {
            0 => Ok(None),
            1 => Ok(Some(T::take(r)?)),
            _ => Err(Corrupt),
        }
    }
}

impl<T: Stored> Stored for Vec<T> {
    fn put(&self, w: &mut Writer) {
        w.count(self.len());
        self.iter().for_each(|v| v.put(w));
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        let len = r.length()?;
        (0..len).map(|_| T::take(r)).collect()
    }
}

impl<T: Stored, const N: usize> Stored for [T; N] {
    fn put(&self, w: &mut Writer) {
        self.iter().for_each(|v| v.put(w));
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        let items: Vec<T> = (0..N).map(|_| T::take(r)).collect::<Result<_, _>>()?;
        items.try_into().map_err(|_| Corrupt)
    }
}

impl<A: Stored, B: Stored> Stored for (A, B) {
    fn put(&self, w: &mut Writer) {
        self.0.put(w);
        self.1.put(w);
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        Ok((A::take(r)?, B::take(r)?))
    }
}

/// A place: its file as an index into the stored form's files, its span and its path.
impl Stored for At {
    fn put(&self, w: &mut Writer) {
        let file = w.file(&self.origin.source);
        w.count(file);
        w.count(self.origin.span.start);
        w.count(self.origin.span.end);
        self.path.put(w);
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        let file = r.count()?;
        let source = r.files.get(file).ok_or(Corrupt)?.clone();
        let (start, end) = (r.count()?, r.count()?);
        if start > end || end > source.text.len() {
            return Err(Corrupt);
        }
        Ok(At {
            origin: Origin {
                source,
                span: start..end,
            },
            path: String::take(r)?,
        })
    }
}

impl<T: Stored> Stored for Located<T> {
    fn put(&self, w: &mut Writer) {
        self.value.put(w);
        self.at.put(w);
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        Ok(Located {
            value: T::take(r)?,
            at: At::take(r)?,
        })
    }
}

/// An expression as its tree (so that loading parses nothing).
impl Stored for Expr {
    fn put(&self, w: &mut Writer) {
        match self {
            Expr::Num(x) => {
                w.count(0);
                x.put(w);
            }
            Expr::Sym(s) => {
                w.count(1);
                s.put(w);
            }
            Expr::Neg(a) => {
                w.count(2);
                a.put(w);
            }
            Expr::Binary(op, a, b) => {
                w.count(3);
                w.count(match op {
                    BinOp::Add => 0,
                    BinOp::Sub => 1,
                    BinOp::Mul => 2,
                    BinOp::Div => 3,
                    BinOp::Pow => 4,
                });
                a.put(w);
                b.put(w);
            }
            Expr::Call(f, args) => {
                w.count(4);
                f.name().to_string().put(w);
                args.put(w);
            }
        }
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        r.depth += 1;
        if r.depth > MAX_DEPTH {
            return Err(Corrupt);
        }
        let e = match r.count()? {
            0 => Expr::Num(f64::take(r)?),
            1 => Expr::Sym(String::take(r)?),
            2 => Expr::Neg(Box::new(Expr::take(r)?)),
            3 => {
                let op = [BinOp::Add, BinOp::Sub, BinOp::Mul, BinOp::Div, BinOp::Pow]
                    .get(r.count()?)
                    .copied()
                    .ok_or(Corrupt)?;
                Expr::Binary(op, Box::new(Expr::take(r)?), Box::new(Expr::take(r)?))
            }
            4 => {
                let f = Func::from_name(&String::take(r)?).ok_or(Corrupt)?;
                Expr::Call(f, Vec::take(r)?)
            }
            _ => return Err(Corrupt),
        };
        r.depth -= 1;
        Ok(e)
    }
}

/// A damping field, by its index in the schema.
impl Stored for &'static Field {
    fn put(&self, w: &mut Writer) {
        let i = DAMPING_FIELDS.iter().position(|f| f.name == self.name);
        // every field a description holds is one of the schema's (spec::damping)
        w.count(i.unwrap_or(DAMPING_FIELDS.len()));
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        DAMPING_FIELDS.get(r.count()?).ok_or(Corrupt)
    }
}

/// Enums without fields, stored as the index of their variant in the list of all.
macro_rules! stored_choice {
    ($($ty:ty: $all:expr;)*) => {$(
        impl Stored for $ty {
            fn put(&self, w: &mut Writer) {
                let all = $all;
                w.count(all.iter().position(|v| v == self).unwrap_or(all.len()));
            }
            fn take(r: &mut Reader) -> Result<Self, Corrupt> {
                $all.get(r.count()?).copied().ok_or(Corrupt)
            }
        }
    )*};
}

stored_choice! {
    BeadJoints: [BeadJoints::Clamped, BeadJoints::Hinged];
    CoordKind: [CoordKind::Variable, CoordKind::Float, CoordKind::Parameter];
    Stage: Stage::ALL;
    BladeForm: [BladeForm::XtraLite, BladeForm::Lite, BladeForm::Full, BladeForm::Lateral];
}

impl Stored for Domain {
    fn put(&self, w: &mut Writer) {
        match self {
            Domain::Finite => w.count(0),
            Domain::Positive => w.count(1),
            Domain::NonNegative => w.count(2),
            Domain::Between(low, high) => {
                w.count(3);
                low.put(w);
                high.put(w);
            }
        }
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        Ok(match r.count()? {
            0 => Domain::Finite,
            1 => Domain::Positive,
            2 => Domain::NonNegative,
            3 => Domain::Between(f64::take(r)?, f64::take(r)?),
            _ => return Err(Corrupt),
        })
    }
}

impl Stored for Inertia {
    fn put(&self, w: &mut Writer) {
        match self {
            Inertia::Diagonal(d) => {
                w.count(0);
                d.put(w);
            }
            Inertia::Tensor(at, rows) => {
                w.count(1);
                at.put(w);
                rows.put(w);
            }
        }
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        Ok(match r.count()? {
            0 => Inertia::Diagonal(Stored::take(r)?),
            1 => Inertia::Tensor(At::take(r)?, Stored::take(r)?),
            _ => return Err(Corrupt),
        })
    }
}

impl Stored for ShapeFile {
    fn put(&self, w: &mut Writer) {
        match self {
            ShapeFile::Box { half_sizes } => {
                w.count(0);
                half_sizes.put(w);
            }
            ShapeFile::Cylinder {
                radius,
                half_length,
                axis,
            } => {
                w.count(1);
                radius.put(w);
                half_length.put(w);
                axis.put(w);
            }
        }
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        Ok(match r.count()? {
            0 => ShapeFile::Box {
                half_sizes: Stored::take(r)?,
            },
            1 => ShapeFile::Cylinder {
                radius: Ex::take(r)?,
                half_length: Ex::take(r)?,
                axis: usize::take(r)?,
            },
            _ => return Err(Corrupt),
        })
    }
}

impl Stored for Names {
    fn put(&self, w: &mut Writer) {
        match self {
            Names::Prefix(p) => {
                w.count(0);
                p.put(w);
            }
            Names::List(list) => {
                w.count(1);
                list.put(w);
            }
        }
    }
    fn take(r: &mut Reader) -> Result<Self, Corrupt> {
        Ok(match r.count()? {
            0 => Names::Prefix(String::take(r)?),
            1 => Names::List(Stored::take(r)?),
            _ => return Err(Corrupt),
        })
    }
}

/// Structs, stored field after field in the order listed (the list names every field: the
/// destructuring has no `..`).
macro_rules! stored_struct {
    ($($ty:ident { $($field:ident),* $(,)? })*) => {$(
        impl Stored for $ty {
            fn put(&self, w: &mut Writer) {
                let $ty { $($field),* } = self;
                $($field.put(w);)*
            }
            fn take(r: &mut Reader) -> Result<Self, Corrupt> {
                Ok($ty { $($field: Stored::take(r)?),* })
            }
        }
    )*};
}

stored_struct! {
    Ex { text, expr, at }
    Spec {
        name, summary, gravity, gravity_checks, parameters, materials, blade_defaults,
        coordinates, bodies, stages, damping, elements, instances, inputs, outputs,
        extra_terms, constraints, pins, name_schemes,
    }
    NameSchemeFile { scheme, at, dofs, bodies }
    ParameterSpec { name, value, unit, description, allowed, domain, at }
    MaterialSpec {
        name, at, youngs_modulus, shear_modulus, poisson_ratio, density, loss_angle,
        specific_heat, conductivity, thermal_expansion, dlne_dt, dissipation_depth,
    }
    CoordinateSpec { name, kind, start, pinned, at }
    BodyFile {
        name, at, coordinates, driven, dof, pose, parent, position, mass, inertia,
        centre_of_mass, shape, mode_family, scope,
    }
    StageFile { body, at, from, blades, wires, fibres, springs, link, scope }
    Points { at, base, mirror, hinged, direction, angles }
    BladeFields {
        form, stiffness, tip_mass, tip_inertia, transverse_stiffness, rotational_stiffness,
        lateral_stiffness, lateral_ratio, material, tag, thickness, temperature,
    }
    BladeSet { at, names, tips, fields }
    WireSet {
        slot, at, names, upper, lower, length, radius, section, material, youngs_modulus,
        shear_modulus, beads, bead_joints, tags, profile, surface_loss, temperature, dilution,
        continuum,
    }
    ProfileFile { at, neck_length, neck_radius }
    SectionFile { at, area, moments, torsion_constant, polar_moment, principal_axis }
    SpringSet { at, names, upper, lower, stiffness, diagonal, preload, tag }
    LinkFile { at, offset, angles }
    DampingFile { tag, at, fields }
    ElementChoice { kind, stage, at }
    InstanceFile { kind, name, between, points, values, values_at, tag, at }
    SignalFile { name, text }
    ExtraFile { name, energy, tag, after_equilibrium, at }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A library of one file, `m.toml`, whose stored form is `stored`.
    struct One(&'static [u8]);

    impl Library for One {
        fn file(&self, _: &str) -> Option<BundledFile> {
            Some(BundledFile {
                path: "models/m.toml",
                text: "a = 1\n",
                packed: "",
                stored: self.0,
            })
        }
    }

    /// Damaged stored forms are errors naming the file, never a panic.
    #[test]
    fn corrupt_stored_forms_are_errors() {
        for bad in [
            &b""[..],
            b"\x01",
            b"\x01\x0dmodels/m.toml",
            b"\x01\x0dmodels/x.toml\x00",
            b"\x00\x05",
            b"\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff\xff",
            b"\x00\x00\x00\x02",
        ] {
            let library = One(bad);
            let file = library.file("m").unwrap();
            let Err(e) = load_bundled(&file, &library) else {
                panic!("{bad:?} loaded")
            };
            assert!(e.to_string().starts_with("models/m.toml: "), "{e}");
        }
    }
}
