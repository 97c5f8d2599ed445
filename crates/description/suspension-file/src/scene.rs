//! Scenes: several suspensions in one file. `[[include]]` brings in a whole suspension (a
//! bundled model or a file, its own `extends` resolved) under a prefix, so that one file can
//! hold two quads (`itm_`, `etm_`) and elements that couple their bodies.
//!
//! An included suspension is read into its own [`Spec`] first (so its errors name its own
//! file and lines), then every name it defines is prefixed ([`Prefix`]), and the prefixed
//! description is added to the scene's ([`Scene`]). Renaming the typed description rather
//! than the TOML tree means each field is renamed as what it is: an expression is parsed and
//! its identifiers renamed, a body reference is renamed, a kind or a blade form is not. The
//! renaming destructures every struct of the description, so a field added later does not
//! compile until someone decides whether it holds a name.
//!
//! What stays shared by the whole scene: the built-in parameters (`temperature`,
//! `wire_terms_early`), `pi` and the functions, gravity (one per scene, see
//! [`Scene::finish`]) and the moves of element kinds between calculation stages
//! (`[elements]`, which are per kind, not per suspension).

use pendkit_expr::Expr;

use crate::read::{Ex, Fields};
use crate::signals::split_top_level;
use crate::source::{At, FileError, Located};
use crate::spec::{
    BladeFields, BodyFile, CoordinateSpec, DampingFile, ElementChoice, ExtraFile, Inertia,
    InstanceFile, LinkFile, MaterialSpec, NameSchemeFile, ParameterSpec, Points, ProfileFile,
    SectionFile, ShapeFile, SignalFile, Spec, SpringSet, StageFile, WireSet,
};
use crate::tree::{Node, Value};

/// One `[[include]]` of a scene.
#[derive(Clone, Debug)]
pub struct Include {
    /// `model`: a bundled model's name, or a path ending in `.toml` relative to the file that
    /// writes the include.
    pub model: Located<String>,
    /// `prefix`: written before every name the included suspension defines.
    pub prefix: Located<String>,
    /// Where the include is written.
    pub at: At,
}

/// The `[[include]]` array of the (merged) tree `root`, taken out of it (the rest of the
/// tree is the scene's own description) and read.
pub fn take_includes(root: &mut Node) -> Result<Vec<Include>, FileError> {
    let at = At {
        origin: root.origin.clone(),
        path: String::new(),
    };
    let Value::Table(table) = &mut root.value else {
        return Ok(Vec::new());
    };
    let Some(i) = table.entries.iter().position(|(k, _, _)| k == "include") else {
        return Ok(Vec::new());
    };
    let (key, key_origin, node) = table.entries.remove(i);
    let array_at = at.child(key_origin, &key);
    let Value::Array(items) = &node.value else {
        return Err(array_at.error(format!(
            "expected an array of tables ([[include]] with `model` and `prefix`), got {}",
            node.value.type_name()
        )));
    };
    let mut includes: Vec<Include> = Vec::new();
    for (k, item) in items.iter().enumerate() {
        let item_at = At {
            origin: item.origin.clone(),
            path: format!("{}[{k}]", array_at.path),
        };
        let mut f = Fields::of(item, item_at.clone())?;
        let model = f.string("model")?.ok_or_else(|| {
            item_at.error("needs `model` (a bundled model's name, or a path ending in .toml)")
        })?;
        let prefix = f.string("prefix")?.ok_or_else(|| {
            item_at.error("needs `prefix` (written before every name it defines, e.g. \"itm_\")")
        })?;
        f.finish()?;
        check_prefix(&prefix)?;
        if let Some(other) = includes.iter().find(|o| o.prefix.value == prefix.value) {
            return Err(prefix.at.error(format!(
                "prefix '{}' is already used by the include at line {}: each include needs its own",
                prefix.value,
                other.at.origin.line()
            )));
        }
        includes.push(Include {
            model,
            prefix,
            at: item_at,
        });
    }
    Ok(includes)
}

/// A prefix must start a valid name and keep it one: a letter or `_`, then letters, digits
/// or `_` (no `.`, which separates the fields of `--set damping.<tag>.<field>`).
fn check_prefix(prefix: &Located<String>) -> Result<(), FileError> {
    let mut chars = prefix.value.chars();
    let valid = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if valid {
        Ok(())
    } else {
        Err(prefix.at.error(format!(
            "'{}' is not a valid prefix: it must start with a letter or '_' and hold only letters, digits and '_' (e.g. \"itm_\")",
            prefix.value
        )))
    }
}

/// Whether `name` is one of the names every model shares: the built-in parameters.
fn shared(name: &str) -> bool {
    crate::BUILT_IN.iter().any(|b| b.0 == name)
}

/// The sections whose entries are named by their key (`bodies.<name>`): a field's path in
/// them names the entry, which a prefix renames.
const NAMED_SECTIONS: [&str; 11] = [
    "parameters",
    "materials",
    "coordinates",
    "bodies",
    "stages",
    "damping",
    "element",
    "inputs",
    "outputs",
    "extra_terms",
    "constraints",
];

/// Renames everything an included suspension names by writing a prefix before it.
pub struct Prefix<'a>(pub &'a str);

impl Prefix<'_> {
    /// `name` with the prefix.
    fn name(&self, name: &mut String) {
        name.insert_str(0, self.0);
    }

    fn located(&self, l: &mut Located<String>) {
        self.name(&mut l.value);
        self.at(&mut l.at);
    }

    fn located_list(&self, l: &mut Located<Vec<String>>) {
        l.value.iter_mut().for_each(|n| self.name(n));
        self.at(&mut l.at);
    }

    /// A field's path: the entry it is in (`bodies.top.mass`) renamed (`bodies.itm_top.mass`),
    /// so that errors and `pendkit params` say which suspension's field it is; the file and
    /// line stay the included file's.
    fn at(&self, at: &mut At) {
        let Some((section, rest)) = at.path.split_once('.') else {
            return;
        };
        let entry = rest.split('.').next().unwrap_or(rest);
        if !NAMED_SECTIONS.contains(&section) || (section == "parameters" && shared(entry)) {
            return;
        }
        at.path = format!("{section}.{}{rest}", self.0);
    }

    /// An expression with every identifier renamed but `pi`, the built-in parameters and,
    /// where `frequency` says so, `f` (the frequency in Hz of a damping field). Function
    /// names are not identifiers of the parsed form.
    fn expr(&self, e: &Expr, frequency: bool) -> Expr {
        let again = |e: &Expr| Box::new(self.expr(e, frequency));
        match e {
            Expr::Num(_) => e.clone(),
            Expr::Sym(s) if s == "pi" || shared(s) || (frequency && s == "f") => e.clone(),
            Expr::Sym(s) => Expr::Sym(format!("{}{s}", self.0)),
            Expr::Neg(a) => Expr::Neg(again(a)),
            Expr::Binary(op, l, r) => Expr::Binary(*op, again(l), again(r)),
            Expr::Call(func, args) => Expr::Call(
                *func,
                args.iter().map(|a| self.expr(a, frequency)).collect(),
            ),
        }
    }

    /// An expression field: its parsed form renamed and its text written from it (the
    /// text is what the damping's expressions are assembled from).
    fn ex_with(&self, ex: &mut Ex, frequency: bool) {
        let renamed = self.expr(&ex.expr, frequency);
        if renamed != ex.expr {
            ex.text = renamed.to_string();
            ex.expr = renamed;
        }
        self.at(&mut ex.at);
    }

    fn ex(&self, ex: &mut Ex) {
        self.ex_with(ex, false);
    }

    fn opt(&self, ex: &mut Option<Ex>) {
        if let Some(ex) = ex {
            self.ex(ex);
        }
    }

    fn exs(&self, list: &mut Located<Vec<Ex>>) {
        list.value.iter_mut().for_each(|e| self.ex(e));
        self.at(&mut list.at);
    }

    fn opt_exs(&self, list: &mut Option<Located<Vec<Ex>>>) {
        if let Some(list) = list {
            self.exs(list);
        }
    }

    /// A signal's text: a linear expression of coordinates, or `<body>@x,y,z/dx,dy,dz`,
    /// either after `force:`.
    fn signal(&self, text: &mut Located<String>) -> Result<(), FileError> {
        let renamed = |t: &str| {
            pendkit_expr::parse(t)
                .map(|e| self.expr(&e, false).to_string())
                .map_err(|e| text.at.error(e.to_string()))
        };
        let (force, body) = match text.value.trim().strip_prefix("force:") {
            Some(rest) => ("force:", rest.trim()),
            None => ("", text.value.trim()),
        };
        let new = match body.split_once('@') {
            None => format!("{force}{}", renamed(body)?),
            Some((name, rest)) => {
                let Some((point, direction)) = rest.split_once('/') else {
                    return Err(text.at.error("expected <body>@x,y,z/dx,dy,dz"));
                };
                let list = |t: &str| -> Result<String, FileError> {
                    let parts: Vec<String> = split_top_level(t)
                        .into_iter()
                        .map(renamed)
                        .collect::<Result<_, _>>()?;
                    Ok(parts.join(", "))
                };
                format!(
                    "{force}{}{}@{} / {}",
                    self.0,
                    name.trim(),
                    list(point)?,
                    list(direction)?
                )
            }
        };
        text.value = new;
        self.at(&mut text.at);
        Ok(())
    }

    /// The whole description with every name it defines prefixed.
    pub fn spec(&self, spec: &mut Spec) -> Result<(), FileError> {
        let Spec {
            name: _,
            summary: _,
            gravity,
            gravity_checks,
            parameters,
            materials,
            blade_defaults,
            coordinates,
            bodies,
            stages,
            damping,
            elements,
            instances,
            inputs,
            outputs,
            extra_terms,
            constraints,
            pins,
            name_schemes,
        } = spec;
        // the scene's gravity is checked against it (Scene::finish)
        self.opt(gravity);
        for (prefix, gravity) in gravity_checks {
            self.located(prefix);
            self.opt(gravity);
        }
        parameters.iter_mut().for_each(|p| self.parameter(p));
        materials.iter_mut().for_each(|m| self.material(m));
        self.blade_fields(blade_defaults);
        coordinates.iter_mut().for_each(|c| self.coordinate(c));
        bodies.iter_mut().for_each(|b| self.body(b));
        stages.iter_mut().for_each(|s| self.stage(s));
        damping.iter_mut().for_each(|d| self.damping(d));
        // element kinds are the registry's names, shared by every suspension
        let _: &mut Vec<ElementChoice> = elements;
        instances.iter_mut().for_each(|i| self.instance(i));
        for s in inputs.iter_mut().chain(outputs.iter_mut()) {
            let SignalFile { name, text } = s;
            self.name(name);
            self.signal(text)?;
        }
        extra_terms.iter_mut().for_each(|t| self.extra(t));
        for (coordinate, stiffness) in constraints {
            self.located(coordinate);
            self.ex(stiffness);
        }
        pins.iter_mut().for_each(|p| self.located(p));
        name_schemes.iter_mut().for_each(|s| self.name_scheme(s));
        Ok(())
    }

    fn parameter(&self, p: &mut ParameterSpec) {
        let ParameterSpec {
            name,
            value,
            unit: _,
            description: _,
            allowed: _,
            domain: _,
            at,
        } = p;
        if !shared(name) {
            self.name(name);
        }
        self.ex(value);
        self.at(at);
    }

    fn material(&self, m: &mut MaterialSpec) {
        self.name(&mut m.name);
        self.at(&mut m.at);
        let MaterialSpec {
            name: _,
            at: _,
            youngs_modulus,
            shear_modulus,
            poisson_ratio,
            density,
            loss_angle,
            specific_heat,
            conductivity,
            thermal_expansion,
            dlne_dt,
            dissipation_depth,
        } = m;
        for ex in [
            youngs_modulus,
            shear_modulus,
            poisson_ratio,
            density,
            loss_angle,
            specific_heat,
            conductivity,
            thermal_expansion,
            dlne_dt,
            dissipation_depth,
        ] {
            self.opt(ex);
        }
    }

    fn coordinate(&self, c: &mut CoordinateSpec) {
        let CoordinateSpec {
            name,
            kind: _,
            start,
            pinned: _,
            at,
        } = c;
        self.name(name);
        self.opt(start);
        self.at(at);
    }

    fn body(&self, b: &mut BodyFile) {
        let BodyFile {
            name,
            at,
            // the suffix stays: the scope is written before the coordinates it makes
            coordinates: _,
            driven: _,
            dof: _,
            pose,
            parent,
            position,
            mass,
            inertia,
            centre_of_mass,
            shape,
            // a family (`violin`) is a kind of mode, not a name of this suspension's
            mode_family: _,
            scope,
        } = b;
        self.name(name);
        self.at(at);
        self.opt_exs(pose);
        if let Some(p) = parent {
            self.located(p);
        }
        self.opt_exs(position);
        self.opt(mass);
        match inertia {
            Some(Inertia::Diagonal(list)) => self.exs(list),
            Some(Inertia::Tensor(at, rows)) => {
                rows.iter_mut().flatten().for_each(|e| self.ex(e));
                self.at(at);
            }
            None => {}
        }
        self.opt_exs(centre_of_mass);
        match shape {
            Some(ShapeFile::Box { half_sizes }) => self.exs(half_sizes),
            Some(ShapeFile::Cylinder {
                radius,
                half_length,
                axis: _,
            }) => {
                self.ex(radius);
                self.ex(half_length);
            }
            None => {}
        }
        self.name(scope);
    }

    fn stage(&self, s: &mut StageFile) {
        let StageFile {
            body,
            at,
            from,
            blades,
            wires,
            fibres,
            springs,
            link,
            scope,
        } = s;
        self.name(body);
        self.at(at);
        self.located(from);
        if let Some(b) = blades {
            // tip names stay: the build writes the scope before the names they make
            self.points(&mut b.tips);
            self.blade_fields(&mut b.fields);
            self.at(&mut b.at);
        }
        for set in wires.iter_mut().chain(fibres.iter_mut()) {
            self.wire_set(set);
        }
        if let Some(set) = springs {
            self.spring_set(set);
        }
        if let Some(LinkFile { at, offset, angles }) = link {
            self.at(at);
            self.exs(offset);
            self.opt_exs(angles);
        }
        self.name(scope);
    }

    fn points(&self, p: &mut Points) {
        let Points {
            at,
            base,
            mirror: _,
            hinged,
            direction,
            angles,
        } = p;
        self.at(at);
        base.iter_mut().for_each(|point| self.exs(point));
        self.opt(hinged);
        self.opt_exs(direction);
        self.opt_exs(angles);
    }

    fn blade_fields(&self, f: &mut BladeFields) {
        let BladeFields {
            form: _,
            stiffness,
            tip_mass,
            tip_inertia,
            transverse_stiffness,
            rotational_stiffness,
            lateral_stiffness,
            lateral_ratio,
            material,
            tag,
            thickness,
            temperature,
        } = f;
        for ex in [
            stiffness,
            tip_mass,
            tip_inertia,
            transverse_stiffness,
            rotational_stiffness,
            lateral_stiffness,
            lateral_ratio,
            thickness,
            temperature,
        ] {
            self.opt(ex);
        }
        for name in [material, tag].into_iter().flatten() {
            self.located(name);
        }
    }

    fn wire_set(&self, w: &mut WireSet) {
        let WireSet {
            slot: _,
            at,
            // the names stay: the build writes the stage's scope before them
            names: _,
            upper,
            lower,
            length,
            radius,
            section,
            material,
            youngs_modulus,
            shear_modulus,
            beads,
            bead_joints: _,
            tags,
            profile,
            surface_loss: _,
            temperature,
            dilution,
            continuum: _,
        } = w;
        self.at(at);
        self.points(upper);
        self.points(lower);
        self.ex(length);
        for ex in [
            radius,
            youngs_modulus,
            shear_modulus,
            beads,
            temperature,
            dilution,
        ] {
            self.opt(ex);
        }
        if let Some(SectionFile {
            at,
            area,
            moments,
            torsion_constant,
            polar_moment,
            principal_axis,
        }) = section
        {
            self.at(at);
            for ex in [area, torsion_constant, polar_moment]
                .into_iter()
                .chain(moments.iter_mut())
            {
                self.ex(ex);
            }
            self.opt_exs(principal_axis);
        }
        if let Some(m) = material {
            self.located(m);
        }
        self.located(tags);
        if let Some(ProfileFile {
            at,
            neck_length,
            neck_radius,
        }) = profile
        {
            self.at(at);
            self.ex(neck_length);
            self.ex(neck_radius);
        }
    }

    fn spring_set(&self, s: &mut SpringSet) {
        let SpringSet {
            at,
            names: _,
            upper,
            lower,
            stiffness,
            diagonal: _,
            preload,
            tag,
        } = s;
        self.at(at);
        for p in [upper, lower].into_iter().flatten() {
            self.points(p);
        }
        stiffness.iter_mut().flatten().for_each(|e| self.ex(e));
        self.opt_exs(preload);
        self.located(tag);
    }

    fn damping(&self, d: &mut DampingFile) {
        let DampingFile { tag, at, fields } = d;
        self.name(tag);
        self.at(at);
        for (_, ex) in fields {
            self.ex_with(ex, true);
        }
    }

    fn instance(&self, i: &mut InstanceFile) {
        let InstanceFile {
            kind: _,
            name,
            between,
            points,
            values,
            values_at,
            tag,
            at,
        } = i;
        self.name(name);
        self.located_list(between);
        if let Some(points) = points {
            points.value.iter_mut().for_each(|p| self.exs(p));
            self.at(&mut points.at);
        }
        for (field, ex) in values {
            // the kind's field names (`k`) are the kind's, not this suspension's
            self.at(&mut field.at);
            self.ex(ex);
        }
        self.at(values_at);
        if let Some(tag) = tag {
            self.located(tag);
        }
        self.at(at);
    }

    fn extra(&self, t: &mut ExtraFile) {
        let ExtraFile {
            name,
            energy,
            tag,
            after_equilibrium: _,
            at,
        } = t;
        self.name(name);
        self.ex(energy);
        self.name(tag);
        self.at(at);
    }

    fn name_scheme(&self, s: &mut NameSchemeFile) {
        // the scheme (`ligo`) is shared: the scene's `--naming ligo` names every
        // suspension's bodies, each alias prefixed (`itm_L3`, coordinates `itm_L3_P`)
        let NameSchemeFile {
            scheme: _,
            at: _,
            dofs: _,
            bodies,
        } = s;
        for (body, alias) in bodies {
            self.located(body);
            self.name(alias);
        }
    }
}

/// An entry of a named section: its key and its place.
trait Entry {
    fn key(&self) -> &str;
    fn place(&self) -> &At;
}

macro_rules! entry {
    ($t:ty, $key:ident, $($at:ident).+) => {
        impl Entry for $t {
            fn key(&self) -> &str {
                &self.$key
            }
            fn place(&self) -> &At {
                &self.$($at).+
            }
        }
    };
}

entry!(ParameterSpec, name, at);
entry!(MaterialSpec, name, at);
entry!(CoordinateSpec, name, at);
entry!(BodyFile, name, at);
entry!(StageFile, body, at);
entry!(DampingFile, tag, at);
entry!(InstanceFile, name, at);
entry!(SignalFile, name, text.at);
entry!(ExtraFile, name, at);

impl Entry for (Located<String>, Ex) {
    fn key(&self) -> &str {
        &self.0.value
    }
    fn place(&self) -> &At {
        &self.0.at
    }
}

/// `file:line` of a place, for messages that point at a second one.
fn line_of(at: &At) -> String {
    format!("{}:{}", at.origin.source.name, at.origin.line())
}

/// Appends `items` to `into`, refusing a key `into` has already: the error is at `blame`
/// (the include that brought the item) or, for the scene's own items, at the item.
fn append<T: Entry>(
    what: &str,
    into: &mut Vec<T>,
    items: Vec<T>,
    blame: Option<&At>,
) -> Result<(), FileError> {
    for item in items {
        if let Some(other) = into.iter().find(|o| o.key() == item.key()) {
            let at = blame.unwrap_or(item.place());
            return Err(at.error(format!(
                "name collision: {what} '{}' is defined twice in the scene ({} and {}); give the includes other prefixes or the scene's own {what} another name",
                item.key(),
                line_of(other.place()),
                line_of(item.place())
            )));
        }
        into.push(item);
    }
    Ok(())
}

/// A scene's description being assembled: each include's prefixed description in the
/// order written, then the scene file's own ([`Scene::finish`]).
#[derive(Default)]
pub struct Scene {
    spec: Spec,
    /// The first include's gravity (`None`: it writes none, 9.81 m/s²), the scene's when
    /// the scene file gives none.
    first_gravity: Option<Option<Ex>>,
}

impl Scene {
    /// Adds the description `sub` of `include`, read and prefixed.
    pub fn add(&mut self, mut sub: Spec, include: &Include) -> Result<(), FileError> {
        let blame = Some(&include.prefix.at);
        // an included file's blade defaults are for its own blades only
        resolve_blade_defaults(&mut sub);
        let spec = &mut self.spec;
        let gravity = sub.gravity.take();
        match &self.first_gravity {
            None => self.first_gravity = Some(gravity),
            Some(_) => spec.gravity_checks.push((include.prefix.clone(), gravity)),
        }
        spec.gravity_checks.append(&mut sub.gravity_checks);
        for p in sub.parameters {
            // the built-in parameters are the scene's: one definition, the first include's
            // unless the scene gives its own; two includes must not disagree
            if shared(&p.name)
                && let Some(other) = spec.parameters.iter().find(|o| o.name == p.name)
            {
                if other.value.expr != p.value.expr {
                    return Err(p.at.error(format!(
                        "'{}' is shared by the whole scene, and this include defines it as `{}` but {} as `{}`: define it once in the scene's [parameters]",
                        p.name,
                        p.value.text,
                        line_of(&other.at),
                        other.value.text
                    )));
                }
                continue;
            }
            append("parameter", &mut spec.parameters, vec![p], blame)?;
        }
        append("material", &mut spec.materials, sub.materials, blame)?;
        append("coordinate", &mut spec.coordinates, sub.coordinates, blame)?;
        append("body", &mut spec.bodies, sub.bodies, blame)?;
        append("stage", &mut spec.stages, sub.stages, blame)?;
        append("damping tag", &mut spec.damping, sub.damping, blame)?;
        for choice in sub.elements {
            if let Some(other) = spec.elements.iter().find(|o| o.kind == choice.kind)
                && other.stage != choice.stage
            {
                return Err(choice.at.error(format!(
                    "element kind '{}' is moved differently by two includes ({} and {}): move it once in the scene's [elements]",
                    choice.kind,
                    line_of(&other.at),
                    line_of(&choice.at)
                )));
            }
            spec.elements.push(choice);
        }
        append(
            "element instance",
            &mut spec.instances,
            sub.instances,
            blame,
        )?;
        append("input", &mut spec.inputs, sub.inputs, blame)?;
        append("output", &mut spec.outputs, sub.outputs, blame)?;
        append("extra term", &mut spec.extra_terms, sub.extra_terms, blame)?;
        append("constraint", &mut spec.constraints, sub.constraints, blame)?;
        spec.pins.extend(sub.pins);
        spec.name_schemes.extend(sub.name_schemes);
        Ok(())
    }

    /// The scene: the includes' descriptions with the scene file's own `own` over them. The
    /// scene's parameters replace included ones of the same (prefixed) name, keeping the
    /// unit, description, domain and allowed values the include wrote unless the scene
    /// gives its own; its `[damping.<tag>]` tables change an included tag's fields; its
    /// `[elements]` moves replace the includes'; anything else it defines must be new.
    pub fn finish(self, mut own: Spec) -> Result<Spec, FileError> {
        let Scene {
            mut spec,
            first_gravity,
        } = self;
        resolve_blade_defaults(&mut own);
        spec.name = own.name;
        spec.summary = own.summary;
        // gravity is one per scene: the scene's own, or else the first include's, which
        // every other include must then agree with (the build checks their values)
        spec.gravity = match own.gravity {
            Some(g) => {
                spec.gravity_checks.clear();
                Some(g)
            }
            None => first_gravity.flatten(),
        };
        spec.gravity_checks.append(&mut own.gravity_checks);
        for p in own.parameters {
            match spec.parameters.iter_mut().find(|o| o.name == p.name) {
                Some(included) => {
                    included.value = p.value;
                    included.at = p.at;
                    if !p.unit.is_empty() {
                        included.unit = p.unit;
                    }
                    if !p.description.is_empty() {
                        included.description = p.description;
                    }
                    included.allowed = p.allowed.or(included.allowed.take());
                    included.domain = p.domain.or(included.domain.take());
                }
                None => spec.parameters.push(p),
            }
        }
        append("material", &mut spec.materials, own.materials, None)?;
        append("coordinate", &mut spec.coordinates, own.coordinates, None)?;
        append("body", &mut spec.bodies, own.bodies, None)?;
        append("stage", &mut spec.stages, own.stages, None)?;
        // applied after the included tables of the same tag: field by field over them
        spec.damping.extend(own.damping);
        for choice in own.elements {
            spec.elements.retain(|o| o.kind != choice.kind);
            spec.elements.push(choice);
        }
        append("element instance", &mut spec.instances, own.instances, None)?;
        append("input", &mut spec.inputs, own.inputs, None)?;
        append("output", &mut spec.outputs, own.outputs, None)?;
        append("extra term", &mut spec.extra_terms, own.extra_terms, None)?;
        append("constraint", &mut spec.constraints, own.constraints, None)?;
        spec.pins.extend(own.pins);
        spec.name_schemes.extend(own.name_schemes);
        Ok(spec)
    }
}

/// Fills each blade set's fields from the description's `[defaults.blade]` and clears the
/// defaults, so that in a scene each file's defaults reach its own blades only.
fn resolve_blade_defaults(spec: &mut Spec) {
    let defaults = std::mem::take(&mut spec.blade_defaults);
    for blades in spec.stages.iter_mut().filter_map(|s| s.blades.as_mut()) {
        blades.fields = blades.fields.or(&defaults);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::source::{Origin, Source};

    fn at(path: &str) -> At {
        At {
            origin: Origin {
                source: Source::new("s.toml", None, ""),
                span: 0..0,
            },
            path: path.into(),
        }
    }

    /// Identifiers are renamed in the parsed expression, never by matching text: `m1` in
    /// `m10` or in `sqrt` stays, `pi`, the functions and the built-in parameters stay.
    #[test]
    fn expressions_rename_their_identifiers_only() {
        let p = Prefix("a_");
        let renamed = |text: &str, frequency: bool| {
            p.expr(&pendkit_expr::parse(text).unwrap(), frequency)
                .to_string()
        };
        assert_eq!(
            renamed("sqrt(m1*m10)*2*pi + temperature*x1.eq", false),
            "sqrt(a_m1*a_m10)*2*pi + temperature*a_x1.eq"
        );
        assert_eq!(renamed("phi*(1 + f/100)", true), "a_phi*(1 + f/100)");
        assert_eq!(renamed("phi*(1 + f/100)", false), "a_phi*(1 + a_f/100)");
    }

    #[test]
    fn signals_rename_bodies_and_expressions() {
        let p = Prefix("itm_");
        let mut text = Located {
            value: "force:optic@-0.5*t_optic, max(h, 0), 0 / 1, 0, 0".to_string(),
            at: at("outputs.beam"),
        };
        p.signal(&mut text).unwrap();
        assert_eq!(
            text.value,
            "force:itm_optic@-0.5*itm_t_optic, max(itm_h, 0), 0 / 1, 0, 0"
        );
        assert_eq!(text.at.path, "outputs.itm_beam");
        let mut linear = Located {
            value: "x3 + theta*z3".to_string(),
            at: at("outputs.tm"),
        };
        p.signal(&mut linear).unwrap();
        assert_eq!(linear.value, "itm_x3 + itm_theta*itm_z3");
    }

    #[test]
    fn paths_name_the_prefixed_entry() {
        let p = Prefix("a_");
        for (path, renamed) in [
            ("bodies.top.mass", "bodies.a_top.mass"),
            ("parameters.m1", "parameters.a_m1"),
            ("parameters.temperature", "parameters.temperature"),
            ("element[0].kind", "element[0].kind"),
            ("gravity", "gravity"),
            ("names.ligo.bodies.top", "names.ligo.bodies.top"),
        ] {
            let mut a = at(path);
            p.at(&mut a);
            assert_eq!(a.path, renamed);
        }
    }
}
