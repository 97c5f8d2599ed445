//! The interpreter: turns a [`Spec`] and resolved parameter values into a [`System`] through
//! the validated [`SystemBuilder`], deriving the nominal geometry the way the source's models
//! do: body heights from the wires' vertical extents and break-offs, each wire's static
//! tension from the weight hung below (shared equally by the stage's wires), unstretched
//! lengths l0 = l − T/k with k = E A / l, and blade preloads from the wires' pull, so that
//! the equilibrium sits on the nominal geometry.
//!
//! Every expression is evaluated through [`Ctx::eval`], which can record which field read
//! which parameter (what `pendkit params` lists).

use std::cell::RefCell;
use std::collections::{BTreeSet, HashMap};

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use num_dual::Derivative;
use pendkit_energy::Part;
use pendkit_expr::{Expr, number_text};
use pendkit_model::beads::{BeadedFibre, add_beaded_fibre, beads_mass};
use pendkit_model::schema::{self, MATERIAL_FIELDS};
use pendkit_model::{BodySpec, BuildError, FibreProfile, Shape, SystemBuilder};
use pendkit_params::{ChunkDual, Resolved, Values};
use pendkit_system::{
    BodyId, CoordKind, EndDirection, ExtraPhase, NamedSignal, PluginElement, Real, SignalTerm,
    SpringEnd, Stage, System, WireEnd, WireSection, WireTags,
};

use crate::damping::{blade_tag, find_material};
use crate::read::Ex;
use crate::signals::{linear_form, point_form};
use crate::source::{At, Located};
use crate::spec::{
    AXES, BladeFields, BladeForm, BladeSet, BodyFile, Inertia, InstanceFile, MaterialSpec, Points,
    ShapeFile, Spec, SpringSet, StageFile, WireSet,
};

/// Largest number of violin beads per wire (the model crate's limit).
pub use pendkit_model::beads::MAX_BEADS;

/// Which fields read which parameter, in the order first read.
#[derive(Clone, Debug, Default)]
pub struct Reads {
    /// Parameter name and the fields that read it.
    pub by_parameter: Vec<(String, Vec<String>)>,
}

impl Reads {
    /// Records that `field` read `parameter`.
    pub fn add(&mut self, parameter: &str, field: &str) {
        match self.by_parameter.iter_mut().find(|(p, _)| p == parameter) {
            Some((_, fields)) => {
                if !fields.iter().any(|f| f == field) {
                    fields.push(field.to_string());
                }
            }
            None => self
                .by_parameter
                .push((parameter.to_string(), vec![field.to_string()])),
        }
    }

    /// The fields that read `parameter`.
    pub fn of(&self, parameter: &str) -> &[String] {
        self.by_parameter
            .iter()
            .find(|(p, _)| p == parameter)
            .map_or(&[], |(_, f)| f.as_slice())
    }
}

/// An error at a place of the file.
pub fn invalid(at: &At, message: impl Into<String>) -> BuildError {
    BuildError::Invalid {
        item: at.label(),
        message: message.into(),
    }
}

/// A builder error (whose message names the part) placed at the field that made the part.
fn placed(at: &At) -> impl Fn(BuildError) -> BuildError + '_ {
    move |e| invalid(at, e.to_string())
}

/// The scalar a suspension file is built in: `f64` (the model) or [`ChunkDual`] (the model
/// with the exact derivatives of every number with respect to up to
/// [`pendkit_params::TANGENT_CHUNK`] parameters at once, one direction each).
pub trait BuildScalar: Real {
    /// The directions (bit k: the k-th seed) in which the number has a non-zero derivative:
    /// where it becomes the text of an expression, a count or a switch, those are lost.
    fn moving(&self) -> u64;

    /// Whether the number has a derivative in any direction.
    fn moves(&self) -> bool {
        self.moving() != 0
    }
}

impl BuildScalar for f64 {
    fn moving(&self) -> u64 {
        0
    }
}

// one bit per direction of a chunk
const _: () = assert!(pendkit_params::TANGENT_CHUNK <= 64);

impl BuildScalar for ChunkDual {
    fn moving(&self) -> u64 {
        let Derivative(eps) = &self.eps;
        eps.as_ref().map_or(0, |v| {
            v.iter()
                .enumerate()
                .filter(|(_, d)| **d != 0.0)
                .fold(0, |bits, (k, _)| bits | 1 << k)
        })
    }
}

/// The error for a number whose derivative would be lost at `at` (`what` says how).
fn no_derivative(at: &At, what: &str) -> BuildError {
    invalid(at, format!("no exact derivative: {what}"))
}

/// Derivatives a chunk build could not carry: each entry, the directions (bit k: the k-th
/// seed) lost at one place and why.
pub type Lost = RefCell<Vec<(u64, BuildError)>>;

/// Evaluation of the file's expressions against resolved parameters.
pub struct Ctx<'a, S: BuildScalar = f64> {
    /// Parameter values (what is recorded as read, and the messages).
    pub params: &'a Resolved,
    /// Where reads are recorded, if they are.
    pub reads: Option<&'a RefCell<Reads>>,
    /// The values the expressions evaluate with, of the build's scalar: `params` itself
    /// for `f64`, a [`pendkit_params::Tangent`] for the dual numbers.
    pub values: &'a dyn Values<S>,
    /// Where a build over several seeds records the derivatives it loses and goes on with
    /// the numbers' values (what the `f64` build does), so the chunk's other seeds keep
    /// theirs; `None`: a lost derivative is an error.
    pub lost: Option<&'a Lost>,
}

impl<S: BuildScalar> Ctx<'_, S> {
    /// The derivatives of `x` are lost at `at` (`what` says how): recorded when the build
    /// records them, else an error if `x` has any.
    fn lose(&self, x: S, at: &At, what: &str) -> Result<(), BuildError> {
        self.lose_directions(x.moving(), at, what)
    }

    /// [`Ctx::lose`] for the directions themselves (bit k: the k-th seed).
    fn lose_directions(&self, directions: u64, at: &At, what: &str) -> Result<(), BuildError> {
        if directions == 0 {
            return Ok(());
        }
        let error = no_derivative(at, what);
        match self.lost {
            Some(lost) => {
                lost.borrow_mut().push((directions, error));
                Ok(())
            }
            None => Err(error),
        }
    }

    /// The directions in which parameter `name`'s value moves (none if it is not one).
    fn moving(&self, name: &str) -> u64 {
        self.values.value(name).map_or(0, |v| v.moving())
    }

    /// Records that `field` reads the symbols of `expr` that are parameters.
    pub fn record(&self, expr: &Expr, field: &str) {
        if let Some(reads) = self.reads {
            let mut reads = reads.borrow_mut();
            for s in expr.symbols() {
                if self.params.get(&s).is_ok() {
                    reads.add(&s, field);
                }
            }
        }
    }

    /// The value of `ex` (the field's unit is the caller's).
    pub fn eval(&self, ex: &Ex) -> Result<S, BuildError> {
        self.eval_for(ex, None)
    }

    /// The value of `ex` where only a plain number can go (`what`: a count, a switch, a
    /// constant the model keeps in `f64`): an error if it has a derivative.
    fn fixed(&self, ex: &Ex, what: &str) -> Result<f64, BuildError> {
        let v = self.eval(ex)?;
        self.lose(v, &ex.at, &format!("`{}` is {what}", ex.text))?;
        Ok(v.re())
    }

    /// [`Ctx::eval`], recording the read as made for `user` (a part using a material).
    pub fn eval_for(&self, ex: &Ex, user: Option<&str>) -> Result<S, BuildError> {
        if self.reads.is_some() {
            let field = match user {
                Some(u) => format!("{} (for {u})", ex.at.path),
                None => ex.at.path.clone(),
            };
            self.record(&ex.expr, &field);
        }
        let value = ex
            .expr
            .eval(&|s| self.values.value(s))
            .map_err(|e| match e {
                pendkit_expr::ExprError::UnknownSymbol { name } => {
                    // the parameter set says why: unknown (with a suggestion) or symbolic
                    let why = self
                        .params
                        .get(&name)
                        .err()
                        .map_or_else(|| format!("unknown symbol '{name}'"), |p| p.to_string());
                    invalid(&ex.at, format!("`{}`: {why}", ex.text))
                }
                other => invalid(&ex.at, format!("`{}`: {other}", ex.text)),
            })?;
        if value.re().is_finite() {
            Ok(value)
        } else {
            Err(invalid(
                &ex.at,
                format!(
                    "`{}` = {} is not a finite number",
                    ex.text,
                    number_text(value.re())
                ),
            ))
        }
    }

    /// A value that must be positive (`unit` for the message).
    fn positive(&self, ex: &Ex, unit: &str) -> Result<S, BuildError> {
        let v = self.eval(ex)?;
        if v.re() > 0.0 {
            Ok(v)
        } else {
            Err(invalid(
                &ex.at,
                format!(
                    "`{}` = {} {unit} must be positive",
                    ex.text,
                    number_text(v.re())
                ),
            ))
        }
    }

    /// Three values.
    fn vec3(&self, list: &Located<Vec<Ex>>) -> Result<Vector3<S>, BuildError> {
        let mut v = zero3();
        for (k, ex) in list.value.iter().enumerate().take(3) {
            v[k] = self.eval(ex)?;
        }
        Ok(v)
    }

    /// A whole number in `range`.
    fn count(&self, ex: &Ex, range: std::ops::RangeInclusive<usize>) -> Result<usize, BuildError> {
        let v = self.fixed(ex, "a count")?;
        let (low, high) = (*range.start(), *range.end());
        if v.fract() == 0.0 && v >= low as f64 && v <= high as f64 {
            Ok(v as usize)
        } else {
            Err(invalid(
                &ex.at,
                format!(
                    "`{}` = {} must be a whole number from {low} to {high}",
                    ex.text,
                    number_text(v)
                ),
            ))
        }
    }

    /// The points of `p` (m): the base points, each mirror doubling the list (the mirrored
    /// copies follow the originals, so `mirror = ["x", "y"]` gives (+,+), (−,+), (+,−), (−,−)).
    /// At most [`pendkit_limits::WIRES_PER_SET`] of them, counted before any is made (a
    /// file's sets are counted when it is read; a description made in code is counted here).
    pub fn points(&self, p: &Points) -> Result<Vec<Vector3<S>>, BuildError> {
        pendkit_limits::WIRES_PER_SET
            .check(crate::damping::point_count(p))
            .map_err(|e| invalid(&p.at, e.to_string()))?;
        let mut out = p
            .base
            .iter()
            .map(|b| self.vec3(b))
            .collect::<Result<Vec<_>, _>>()?;
        for &axis in &p.mirror {
            let copies: Vec<Vector3<S>> = out
                .iter()
                .map(|v| {
                    let mut m = *v;
                    m[axis] = -m[axis];
                    m
                })
                .collect();
            out.extend(copies);
        }
        Ok(out)
    }

    /// How a wire leaves the points of `p`.
    fn end_direction(&self, p: &Points) -> Result<EndDirection<S>, BuildError> {
        if let Some(h) = &p.hinged {
            // a switch: 0 or 1, nothing else silently read as "on"
            match self.fixed(h, "a switch")? {
                0.0 => {}
                1.0 => return Ok(EndDirection::Hinged),
                other => {
                    return Err(invalid(
                        &h.at,
                        format!(
                            "`hinged` = {}: must be 0 (clamped) or 1 (hinged)",
                            number_text(other)
                        ),
                    ));
                }
            }
        }
        match &p.direction {
            Some(d) => Ok(EndDirection::Explicit(self.vec3(d)?)),
            None => Ok(EndDirection::Auto),
        }
    }
}

/// A number as expression text that reads back to the same `f64`.
fn num(x: f64) -> String {
    format!("({x})")
}

/// [`num`] of a model number, which must have no derivative (the text would lose it);
/// `at` and `what` name it in the error.
fn num_of<S: BuildScalar>(ctx: &Ctx<S>, x: S, at: &At, what: &str) -> Result<String, BuildError> {
    ctx.lose(
        x,
        at,
        &format!("{what} is written into a pose's expression"),
    )?;
    Ok(num(x.re()))
}

/// The zero vector of the build's scalar.
fn zero3<S: Real>() -> Vector3<S> {
    Vector3::from_element(S::from(0.0))
}

/// One wire of a set, planned: ends (m, body coordinates), geometry at the nominal pose.
struct PlannedWire<S: Real> {
    name: String,
    /// Blade tip carrying the upper end, if the stage has blades.
    tip: Option<usize>,
    /// Upper end in the tip's (or upper body's) coordinates.
    upper: Vector3<S>,
    /// Lower end in the hung body's coordinates.
    lower: Vector3<S>,
    /// Lab components of (lower end − upper end) across, at the nominal geometry (m).
    across: (S, S),
    /// Vertical extent at the nominal geometry (m).
    vertical: S,
    /// Lab positions of the ends at the nominal geometry (m).
    nominal: [Vector3<S>; 2],
}

/// A wire set, planned.
struct PlannedSet<'s, S: Real> {
    set: &'s WireSet,
    /// The stage's scope ([`StageFile::scope`]): written before the wires' names.
    scope: &'s str,
    wires: Vec<PlannedWire<S>>,
    ends: [EndDirection<S>; 2],
    length: S,
    section: WireSection<S>,
    beads: usize,
    /// A tapered fibre's profile (`profile`): each wire is one effective wire of it, or
    /// with beads, each segment the slice of it that it spans.
    profile: Option<FibreProfile<S>>,
}

/// A blade set, planned.
struct PlannedBlades<'s, S: Real> {
    set: &'s BladeSet,
    /// The stage's scope ([`StageFile::scope`]): written before the names the tips make.
    scope: &'s str,
    fields: BladeFields,
    tag: String,
    names: Vec<String>,
    tips: Vec<Vector3<S>>,
    form: BladeForm,
    tip_mass: S,
}

/// A stage, planned before any of its parts is built.
struct PlannedStage<'s, S: Real> {
    stage: &'s StageFile,
    upper: usize,
    lower: usize,
    blades: Option<PlannedBlades<'s, S>>,
    sets: Vec<PlannedSet<'s, S>>,
}

impl<S: Real> PlannedStage<'_, S> {
    fn wire_count(&self) -> usize {
        self.sets.iter().map(|s| s.wires.len()).sum()
    }

    /// Mass (kg) of the blade tips this stage's blades add to the upper body.
    fn tips_mass(&self) -> S {
        self.blades
            .as_ref()
            .map_or(S::from(0.0), |b| b.tip_mass * b.names.len() as f64)
    }

    /// Mass (kg) of this stage's violin beads.
    fn beads_mass(&self) -> S {
        self.sets
            .iter()
            .map(|s| {
                beads_mass(&s.section, s.profile.as_ref(), s.length, s.beads) * s.wires.len() as f64
            })
            .sum()
    }
}

/// The built system of `spec` at the parameter values of `ctx`.
pub fn build<S: BuildScalar>(spec: &Spec, ctx: &Ctx<S>) -> Result<System<S>, BuildError> {
    check_material_domains(spec, ctx.params)?;
    Interpreter::new(spec, ctx)?.run()
}

/// Every constant of every material the file defines, checked against its domain in
/// [`MATERIAL_FIELDS`] whether or not a part (or the command at hand) reads it: a negative
/// heat capacity is refused by `modes` as by `noise`. The values are looked at without
/// recording a read, so that an override nothing uses is still refused as unread.
fn check_material_domains(spec: &Spec, params: &Resolved) -> Result<(), BuildError> {
    for material in &spec.materials {
        for (name, ex) in material.fields() {
            let (Some(ex), Some(field)) = (ex, schema::find(MATERIAL_FIELDS, name)) else {
                continue;
            };
            // an expression that does not evaluate is reported where a part reads it
            let Ok(value) = ex.expr.eval(&|s| params.peek(s)) else {
                continue;
            };
            field
                .check(value)
                .map_err(|message| invalid(&ex.at, format!("{message} (`{}`)", ex.text)))?;
        }
    }
    Ok(())
}

/// In a scene, every included suspension's own gravity must be the scene's: one planet
/// (see [`crate::scene`]). Relative 1e-12, so that `9.81` written two ways agrees.
fn check_scene_gravity<S: BuildScalar>(spec: &Spec, ctx: &Ctx<S>, g: S) -> Result<(), BuildError> {
    for (prefix, gravity) in &spec.gravity_checks {
        let (own, at) = match gravity {
            Some(ex) => (ctx.eval(ex)?.re(), &ex.at),
            None => (9.81, &prefix.at),
        };
        if (own - g.re()).abs() > 1e-12 * g.re().abs() {
            return Err(invalid(
                at,
                format!(
                    "the suspension included as '{}' has gravity {} m/s^2, the scene {} m/s^2: a scene has one gravity; set the scene's `gravity`",
                    prefix.value,
                    number_text(own),
                    number_text(g.re())
                ),
            ));
        }
    }
    Ok(())
}

struct Interpreter<'s, 'c, S: BuildScalar> {
    spec: &'s Spec,
    ctx: &'c Ctx<'c, S>,
    b: SystemBuilder<S>,
    g: S,
    /// Start values of the coordinates defined so far (for nominal poses).
    starts: HashMap<String, f64>,
    /// Per body (spec order): id, nominal position (m), mass (kg).
    bodies: Vec<(BodyId, Vector3<S>, S)>,
    /// Index of each body's stage in `spec.stages`.
    stage_of: HashMap<&'s str, usize>,
    /// Index of each body in `spec.bodies`.
    index: HashMap<&'s str, usize>,
    plans: Vec<Option<PlannedStage<'s, S>>>,
}

impl<'s, 'c, S: BuildScalar> Interpreter<'s, 'c, S> {
    fn new(spec: &'s Spec, ctx: &'c Ctx<'c, S>) -> Result<Self, BuildError> {
        let g = match &spec.gravity {
            Some(ex) => ctx.eval(ex)?,
            None => S::from(9.81),
        };
        check_scene_gravity(spec, ctx, g)?;
        let index: HashMap<&str, usize> = spec
            .bodies
            .iter()
            .enumerate()
            .map(|(i, b)| (b.name.as_str(), i))
            .collect();
        let mut stage_of = HashMap::new();
        for (k, stage) in spec.stages.iter().enumerate() {
            let lower = *index.get(stage.body.as_str()).ok_or_else(|| {
                invalid(
                    &stage.at,
                    format!("no body called '{}' to hang", stage.body),
                )
            })?;
            let upper = *index.get(stage.from.value.as_str()).ok_or_else(|| {
                invalid(
                    &stage.from.at,
                    format!(
                        "unknown body '{}' (bodies: {})",
                        stage.from.value,
                        known_bodies(spec)
                    ),
                )
            })?;
            if upper >= lower {
                return Err(invalid(
                    &stage.from.at,
                    format!(
                        "'{}' hangs from '{}', which is not written above it: write the bodies from the top down",
                        stage.body, stage.from.value
                    ),
                ));
            }
            stage_of.insert(stage.body.as_str(), k);
        }
        Ok(Interpreter {
            spec,
            ctx,
            b: SystemBuilder::new(g),
            g,
            starts: HashMap::new(),
            bodies: Vec::with_capacity(spec.bodies.len()),
            stage_of,
            index,
            plans: Vec::new(),
        })
    }

    fn run(mut self) -> Result<System<S>, BuildError> {
        let ctx = self.ctx;
        for p in &self.spec.parameters {
            // only a switch's value is looked up here: a look-up counts as a read, and an
            // override of a parameter nothing reads is refused
            if p.allowed.is_some() {
                ctx.lose_directions(
                    ctx.moving(&p.name),
                    &p.at,
                    &format!("{} is a switch (its values are listed)", p.name),
                )?;
            }
            if let Some(allowed) = &p.allowed
                && let Ok(value) = ctx.params.get(&p.name)
                && !allowed.value.contains(&value)
            {
                let list: Vec<String> = allowed.value.iter().map(|&v| number_text(v)).collect();
                return Err(invalid(
                    &p.at,
                    format!(
                        "{} = {} must be one of {}",
                        p.name,
                        number_text(value),
                        list.join(", ")
                    ),
                ));
            }
        }
        for c in &self.spec.coordinates {
            // a search start, not a model number: its real part
            let start = c.start.as_ref().map(|s| ctx.eval(s)).transpose()?;
            let start = start.map_or(0.0, |s| s.re());
            let b = &mut self.b;
            match c.kind {
                CoordKind::Variable => b.variable(&c.name, start),
                CoordKind::Float => b.float(&c.name, start),
                CoordKind::Parameter => b.parameter(&c.name, start),
            }
            .map_err(placed(&c.at))?;
            if c.pinned {
                b.pin(&c.name).map_err(placed(&c.at))?;
            }
            self.starts.insert(c.name.clone(), start);
        }
        self.plans = (0..self.spec.stages.len()).map(|_| None).collect();
        for body in &self.spec.bodies {
            self.body(body)?;
        }
        for scheme in &self.spec.name_schemes {
            let pairs: Vec<(&str, &str)> = scheme
                .bodies
                .iter()
                .map(|(body, alias)| (body.value.as_str(), alias.as_str()))
                .collect();
            self.b
                .name_scheme(
                    &scheme.scheme,
                    scheme.dofs.each_ref().map(String::as_str),
                    &pairs,
                )
                .map_err(placed(&scheme.at))?;
        }
        // parts, stage by stage in the file's order: blades, then the wires from them
        let plans = std::mem::take(&mut self.plans);
        let weights = self.hung_weights(&plans);
        for plan in plans.iter().flatten() {
            self.parts(plan, weights[plan.lower])?;
        }
        for stage in &self.spec.stages {
            if let Some(springs) = &stage.springs {
                self.springs(stage, springs)?;
            }
        }
        for instance in &self.spec.instances {
            self.instance(instance)?;
        }
        self.extras()?;
        let system = self.b.build()?;
        // the file's damping must be for tags its parts carry
        let tags = system.tags();
        if let Some(d) = self.spec.damping.iter().find(|d| !tags.contains(&d.tag)) {
            return Err(invalid(
                &d.at,
                format!(
                    "no part carries tag '{}' (tags: {})",
                    d.tag,
                    tags.iter().cloned().collect::<Vec<_>>().join(", ")
                ),
            ));
        }
        Ok(system)
    }

    /// Adds body `body` with its coordinates, planning its stage first (its height comes
    /// from the stage's wires).
    fn body(&mut self, body: &'s BodyFile) -> Result<(), BuildError> {
        let ctx = self.ctx;
        let stage = self.stage_of.get(body.name.as_str()).copied();
        let mut nominal = zero3();
        let mut parent = None;
        let mut linked = None;
        if let Some(k) = stage {
            let stage = &self.spec.stages[k];
            let upper = self.index[stage.from.value.as_str()];
            let (upper_id, upper_at, _) = self.bodies[upper];
            nominal = upper_at;
            if let Some(link) = &stage.link {
                if body.coordinates.is_some() || body.pose.is_some() {
                    return Err(invalid(
                        &link.at,
                        format!(
                            "'{}' rides on '{}' by this link: it can have no coordinates or pose of its own",
                            body.name, stage.from.value
                        ),
                    ));
                }
                let offset = ctx.vec3(&link.offset)?;
                let angles = match &link.angles {
                    Some(a) => ctx.vec3(a)?,
                    None => zero3(),
                };
                nominal = upper_at + offset;
                linked = Some((upper_id, offset, angles));
            } else if stage.wire_sets().next().is_some() {
                let plan = self.plan(k, upper, upper_at)?;
                self.plans[k] = Some(plan);
                if body.coordinates.is_none() {
                    return Err(invalid(
                        &body.at,
                        "a body hung by wires needs `coordinates` (its pose starts at the height the wires give)",
                    ));
                }
                if let Some(p) = &body.position {
                    return Err(invalid(
                        &p.at,
                        "the height of a body hung by wires comes from the wires and break-offs; remove `position`",
                    ));
                }
                nominal.z = self.hung_height(k, upper_at)?;
            }
        }
        if let Some(p) = &body.position {
            nominal = ctx.vec3(p)?;
        }
        if let (Some(pose), None) = (&body.pose, &body.position) {
            nominal = self.pose_translation(pose)?;
            if let Some(p) = &body.parent {
                let parent_index = self.body_index(p)?;
                nominal += self.bodies[parent_index].1;
            }
        }
        let mut spec = BodySpec::new(&body.name);
        if let Some((upper, offset, angles)) = linked {
            let at = &body.at;
            let what = "the link's offset or angles";
            spec = spec.on(upper).pose([
                &num_of(ctx, offset.x, at, what)?,
                &num_of(ctx, offset.y, at, what)?,
                &num_of(ctx, offset.z, at, what)?,
                &num_of(ctx, angles.x, at, what)?,
                &num_of(ctx, angles.y, at, what)?,
                &num_of(ctx, angles.z, at, what)?,
            ]);
        } else if let Some(suffix) = &body.coordinates {
            spec = spec.pose(
                self.body_coordinates(body, &suffix.value, &suffix.at, nominal)?
                    .each_ref()
                    .map(String::as_str),
            );
        } else if let Some(pose) = &body.pose {
            let texts = self.pose_texts(pose)?;
            spec = spec.pose(texts.each_ref().map(String::as_str));
            if let Some(p) = &body.parent {
                let parent_index = self.body_index(p)?;
                parent = Some(self.bodies[parent_index].0);
            }
        } else {
            return Err(invalid(
                &body.at,
                "needs `coordinates = \"<suffix>\"` (its pose is then x<suffix> ... roll<suffix>), a `pose`, or a stage with a rigid `link`",
            ));
        }
        if let Some(p) = parent {
            spec = spec.on(p);
        }
        let (spec, mass) = mass_properties(ctx, body, spec)?;
        let id = self.b.body(spec).map_err(placed(&body.at))?;
        self.bodies.push((id, nominal, mass));
        Ok(())
    }

    fn body_index(&self, name: &Located<String>) -> Result<usize, BuildError> {
        self.index
            .get(name.value.as_str())
            .copied()
            .filter(|&i| i < self.bodies.len())
            .ok_or_else(|| {
                invalid(
                    &name.at,
                    format!(
                        "unknown body '{}' (a parent must be written above; bodies: {})",
                        name.value,
                        known_bodies(self.spec)
                    ),
                )
            })
    }

    /// Defines a body's pose coordinates `<axis><suffix>` (the `dof` ones, or all six),
    /// starting at the nominal pose, and returns the six pose entries.
    fn body_coordinates(
        &mut self,
        body: &BodyFile,
        suffix: &str,
        at: &At,
        nominal: Vector3<S>,
    ) -> Result<[String; 6], BuildError> {
        let dof: Vec<usize> = body
            .dof
            .as_ref()
            .map_or_else(|| (0..6).collect(), |d| d.value.clone());
        let mut pose: [String; 6] = std::array::from_fn(|_| "0".to_string());
        for (k, entry) in pose.iter_mut().enumerate() {
            let nominal_k = if k < 3 { nominal[k] } else { S::from(0.0) };
            // a degree of freedom starts there (a search start: its real part); a fixed
            // axis is there (a number in the pose's text)
            let start = nominal_k.re();
            if dof.contains(&k) {
                let name = format!("{}{}{suffix}", body.scope, AXES[k]);
                if body.driven {
                    // a driven coordinate's value is where it starts: a number
                    self.ctx.lose(
                        nominal_k,
                        at,
                        "the position of a driven body (its coordinates' values) moves with it",
                    )?;
                    self.b.parameter(&name, start)
                } else {
                    self.b.variable(&name, start)
                }
                .map_err(placed(at))?;
                self.starts.insert(name.clone(), start);
                *entry = name;
            } else if start != 0.0 || nominal_k.moves() {
                *entry = num_of(
                    self.ctx,
                    nominal_k,
                    at,
                    "the nominal position of an axis that is not a degree of freedom",
                )?;
            }
        }
        Ok(pose)
    }

    /// Pose texts with the parameters replaced by their values (the builder knows only the
    /// coordinates).
    fn pose_texts(&self, pose: &Located<Vec<Ex>>) -> Result<[String; 6], BuildError> {
        let mut out: [String; 6] = std::array::from_fn(|_| "0".to_string());
        for (entry, ex) in out.iter_mut().zip(&pose.value) {
            *entry = self.substitute_parameters(ex, false)?.to_string();
        }
        Ok(out)
    }

    /// `ex` with every symbol that is not a coordinate (or, with `eq`, `<coordinate>.eq`)
    /// replaced by its parameter value; an unknown symbol is an error.
    fn substitute_parameters(&self, ex: &Ex, eq: bool) -> Result<Expr, BuildError> {
        let is_coordinate = |s: &str| {
            let base = if eq {
                s.strip_suffix(".eq").unwrap_or(s)
            } else {
                s
            };
            self.b.find_coordinate(base).is_some()
        };
        for s in ex.expr.symbols() {
            if !is_coordinate(&s) {
                self.ctx.lose_directions(
                    self.ctx.moving(&s),
                    &ex.at,
                    &format!("'{s}' is written into the expression `{}`", ex.text),
                )?;
            }
            if !is_coordinate(&s) && self.ctx.params.get(&s).is_err() {
                return Err(invalid(
                    &ex.at,
                    format!(
                        "`{}`: '{s}' is neither a coordinate defined so far nor a parameter",
                        ex.text
                    ),
                ));
            }
        }
        self.ctx.record(&ex.expr, &ex.at.path);
        Ok(ex.expr.substitute(&|s| {
            if is_coordinate(s) {
                None
            } else {
                self.ctx.params.get(s).ok().map(Expr::Num)
            }
        }))
    }

    /// Translation (m) of an explicit pose at the coordinates' start values.
    fn pose_translation(&self, pose: &Located<Vec<Ex>>) -> Result<Vector3<S>, BuildError> {
        let mut v = zero3();
        for (k, ex) in pose.value.iter().take(3).enumerate() {
            v[k] = ex
                .expr
                .eval(&|s| {
                    self.starts
                        .get(s)
                        .map(|&x| S::from(x))
                        .or_else(|| self.ctx.values.value(s))
                })
                .map_err(|e| invalid(&ex.at, format!("`{}`: {e}", ex.text)))?;
        }
        Ok(v)
    }

    /// Plans stage `k` (hanging a body from body `upper`, whose nominal position is
    /// `upper_at`): blade tips, each wire's ends and nominal geometry, sections.
    fn plan(
        &self,
        k: usize,
        upper: usize,
        upper_at: Vector3<S>,
    ) -> Result<PlannedStage<'s, S>, BuildError> {
        let ctx = self.ctx;
        let stage = &self.spec.stages[k];
        let blades = match &stage.blades {
            None => None,
            Some(set) => Some(self.plan_blades(stage, set)?),
        };
        let mut sets = Vec::new();
        for set in stage.wire_sets() {
            let uppers = ctx.points(&set.upper)?;
            let lowers = ctx.points(&set.lower)?;
            let names = set
                .names
                .expand(lowers.len(), &set.at)
                .map_err(|e| invalid(&set.at, e.message))?;
            let tips = blades.as_ref().map(|b| &b.tips);
            let per_tip = uppers.len();
            check_lower_count(set, tips, per_tip, lowers.len())?;
            let names_first = names.first().cloned();
            let length = wire_length(ctx, set, &names)?;
            let mut wires = Vec::with_capacity(lowers.len());
            for (w, (lower, name)) in lowers.iter().zip(names).enumerate() {
                let (tip, point) = match tips {
                    Some(_) => (Some(w / per_tip), uppers[w % per_tip]),
                    None => (None, uppers[w]),
                };
                let on_upper = match (tip, tips) {
                    (Some(t), Some(tips)) => tips[t] + point,
                    _ => point,
                };
                let up = upper_at + on_upper;
                // the hung body sits below the one above (x and y), at a height to be found
                let (dx, dy) = (upper_at.x + lower.x - up.x, upper_at.y + lower.y - up.y);
                let across2 = dx * dx + dy * dy;
                if (length * length).re() <= across2.re() {
                    return Err(invalid(
                        &set.length.at,
                        format!(
                            "wire '{name}': length {} m does not reach across {} m",
                            number_text(length.re()),
                            number_text(across2.re().sqrt())
                        ),
                    ));
                }
                let vertical = (length * length - dx * dx - dy * dy).sqrt();
                wires.push(PlannedWire {
                    name,
                    tip,
                    upper: point,
                    lower: *lower,
                    across: (dx, dy),
                    vertical,
                    nominal: [up, zero3()],
                });
            }
            let ends = [
                ctx.end_direction(&set.upper)?,
                ctx.end_direction(&set.lower)?,
            ];
            let beads = match &set.beads {
                Some(ex) => ctx.count(ex, 0..=MAX_BEADS)?,
                None => 0,
            };
            let section = self.section(set, names_first.as_deref())?;
            let profile = self.profile(set, &section, length)?;
            // read here so that a bad value is reported by the build (the damping reads them)
            for ex in [&set.temperature, &set.dilution].into_iter().flatten() {
                ctx.positive(ex, "")?;
            }
            sets.push(PlannedSet {
                set,
                scope: &stage.scope,
                wires,
                ends,
                length,
                section,
                beads,
                profile,
            });
        }
        Ok(PlannedStage {
            stage,
            upper,
            lower: self.index[stage.body.as_str()],
            blades,
            sets,
        })
    }

    /// The height (m) of stage `k`'s hung body: below each wire's upper end by its vertical
    /// extent and the lower end's height on the body; every wire must agree.
    fn hung_height(&mut self, k: usize, plan_xy: Vector3<S>) -> Result<S, BuildError> {
        let Some(plan) = self.plans[k].as_mut() else {
            return Ok(S::from(0.0));
        };
        let mut height: Option<(S, String)> = None;
        for set in &mut plan.sets {
            for w in &mut set.wires {
                let z = w.nominal[0].z - w.vertical - w.lower.z;
                match &height {
                    None => height = Some((z, w.name.clone())),
                    Some((z0, first))
                        if (z.re() - z0.re()).abs() > 1e-9 * z0.re().abs().max(1.0) =>
                    {
                        return Err(invalid(
                            &set.set.at,
                            format!(
                                "wire '{}' puts '{}' at z = {} m but wire '{first}' at {} m: the wires of a stage must agree on its height",
                                w.name,
                                plan.stage.body,
                                number_text(z.re()),
                                number_text(z0.re())
                            ),
                        ));
                    }
                    Some(_) => {}
                }
            }
        }
        let z = height.map_or(S::from(0.0), |(z, _)| z);
        // the hung body sits under the one above it, level
        let below = Vector3::new(plan_xy.x, plan_xy.y, z);
        for set in &mut plan.sets {
            for w in &mut set.wires {
                w.nominal[1] = below + w.lower;
            }
        }
        Ok(z)
    }

    fn plan_blades(
        &self,
        stage: &'s StageFile,
        set: &'s BladeSet,
    ) -> Result<PlannedBlades<'s, S>, BuildError> {
        let ctx = self.ctx;
        let fields = set.fields.or(&self.spec.blade_defaults);
        let tag = blade_tag(stage, &fields.tag);
        let tips = ctx.points(&set.tips)?;
        let names = set
            .names
            .expand(tips.len(), &set.at)
            .map_err(|e| invalid(&set.at, e.message))?;
        let form = fields
            .form
            .as_ref()
            .map_or(BladeForm::XtraLite, |f| f.value);
        let tip_mass = match form {
            BladeForm::Lite | BladeForm::Full => {
                let m = fields.tip_mass.as_ref().ok_or_else(|| {
                    invalid(&set.at, "the lite and full forms need `tip_mass` (kg)")
                })?;
                ctx.eval(m)?
            }
            BladeForm::XtraLite | BladeForm::Lateral => S::from(0.0),
        };
        // read here so that a bad value is reported by the build (the damping reads them)
        for ex in [&fields.thickness, &fields.temperature]
            .into_iter()
            .flatten()
        {
            ctx.positive(ex, "")?;
        }
        Ok(PlannedBlades {
            set,
            scope: &stage.scope,
            fields,
            tag,
            names,
            tips,
            form,
            tip_mass,
        })
    }

    /// The tapered profile of a wire set that gives one (`profile`, with `radius` the
    /// middle's), of the set's elastic constants and density.
    fn profile(
        &self,
        set: &WireSet,
        section: &WireSection<S>,
        length: S,
    ) -> Result<Option<FibreProfile<S>>, BuildError> {
        let (Some(p), Some(radius)) = (&set.profile, &set.radius) else {
            return Ok(None);
        };
        let ctx = self.ctx;
        let neck_length = ctx.positive(&p.neck_length, "m")?;
        let neck_radius = ctx.positive(&p.neck_radius, "m")?;
        let middle = ctx.positive(radius, "m")?;
        let density = section.linear_density / section.area;
        let profile = FibreProfile::tapered(
            length,
            (neck_length, neck_radius),
            middle,
            (section.youngs_modulus, section.shear_modulus, density),
        );
        profile
            .check("the profile")
            .map_err(|e| invalid(&p.at, e.to_string()))?;
        Ok(Some(profile))
    }

    /// The section of a wire set from its radius (or section) and material.
    fn section(&self, set: &WireSet, first: Option<&str>) -> Result<WireSection<S>, BuildError> {
        let ctx = self.ctx;
        let material = match &set.material {
            Some(m) => Some(
                find_material(self.spec, &m.value, &m.at).map_err(|e| invalid(&m.at, e.message))?,
            ),
            None => None,
        };
        let user = set.at.path.as_str();
        let of_material =
            |pick: fn(&MaterialSpec) -> &Option<Ex>| -> Result<Option<S>, BuildError> {
                material
                    .and_then(|m| pick(m).as_ref())
                    .map(|ex| ctx.eval_for(ex, Some(user)))
                    .transpose()
            };
        let e = match &set.youngs_modulus {
            Some(ex) => ctx.eval(ex)?,
            None => of_material(|m| &m.youngs_modulus)?.ok_or_else(|| {
                invalid(
                    &set.at,
                    "needs `youngs_modulus` (Pa), here or in its material",
                )
            })?,
        };
        let g = match (&set.shear_modulus, material) {
            (Some(ex), _) => ctx.eval(ex)?,
            (None, Some(m)) => match (&m.shear_modulus, &m.poisson_ratio) {
                (Some(g), _) => ctx.eval_for(g, Some(user))?,
                (None, Some(nu)) => {
                    let nu_value = ctx.eval_for(nu, Some(user))?;
                    pendkit_model::shear_modulus("poisson_ratio", e, nu_value).map_err(|err| {
                        match err {
                            BuildError::Invalid { message, .. } => invalid(&nu.at, message),
                            other => placed(&nu.at)(other),
                        }
                    })?
                }
                (None, None) => {
                    return Err(invalid(
                        &m.at,
                        "needs `shear_modulus` (Pa) or `poisson_ratio` for the wires made of it",
                    ));
                }
            },
            (None, None) => {
                return Err(invalid(
                    &set.at,
                    "needs `shear_modulus` (Pa) or a material with one",
                ));
            }
        };
        let rho = of_material(|m| &m.density)?.unwrap_or(S::from(0.0));
        // the material's remaining constants are read here too, so that a typo in any of
        // them is reported by the build (the loss physics reads them later)
        for pick in [
            (|m: &MaterialSpec| &m.loss_angle) as fn(&MaterialSpec) -> &Option<Ex>,
            |m| &m.specific_heat,
            |m| &m.conductivity,
            |m| &m.thermal_expansion,
            |m| &m.dlne_dt,
            |m| &m.dissipation_depth,
        ] {
            of_material(pick)?;
        }
        if let Some(r) = &set.radius {
            let radius = ctx.eval(r)?;
            // zero passes on to the wire's stiffness check, which names the wire too
            if radius.re() < 0.0 {
                let wire = first.map_or(String::new(), |n| format!("wire '{n}': "));
                return Err(invalid(
                    &r.at,
                    format!(
                        "{wire}`{}` = {} m: a radius must be positive",
                        r.text,
                        number_text(radius.re())
                    ),
                ));
            }
            Ok(WireSection::round(radius, e, g, rho))
        } else if let Some(s) = &set.section {
            let area = ctx.eval(&s.area)?;
            let axis = match &s.principal_axis {
                Some(a) => ctx.vec3(a)?,
                None => Vector3::new(S::from(1.0), S::from(0.0), S::from(0.0)),
            };
            Ok(WireSection {
                youngs_modulus: e,
                shear_modulus: g,
                area,
                moment_1: ctx.eval(&s.moments[0])?,
                moment_2: ctx.eval(&s.moments[1])?,
                principal_axis: axis,
                torsion_constant: ctx.eval(&s.torsion_constant)?,
                polar_moment: ctx.eval(&s.polar_moment)?,
                linear_density: rho * area,
            })
        } else {
            Err(invalid(&set.at, "needs `radius` (m) or a `section`"))
        }
    }

    /// Weight (N) hung from each body's stage wires, by body: the body, the blade tips and
    /// beads of the stages hung from it, and the same of every body below it. Summed once
    /// from the bottom up (each body is written below the one it hangs from), so that a
    /// chain of n stages costs O(n), not a walk of each stage's subtree.
    fn hung_weights(&self, plans: &[Option<PlannedStage<S>>]) -> Vec<S> {
        let mut total: Vec<S> = self.bodies.iter().map(|b| b.2).collect();
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); total.len()];
        for p in plans.iter().flatten() {
            if let Some(t) = total.get_mut(p.upper) {
                *t += p.tips_mass() + p.beads_mass();
            }
            if let Some(c) = children.get_mut(p.upper) {
                c.push(p.lower);
            }
        }
        for b in (0..total.len()).rev() {
            for &c in &children[b] {
                // a stage hangs its body below the one it hangs from (checked at the plan)
                if c > b {
                    let below = total[c];
                    total[b] += below;
                }
            }
        }
        total.into_iter().map(|w| w * self.g).collect()
    }

    /// Builds a planned stage's blades and wires.
    fn parts(&mut self, plan: &PlannedStage<'s, S>, weight: S) -> Result<(), BuildError> {
        // each wire carries an equal share of the weight vertically
        let share = weight / plan.wire_count() as f64;
        let upper = self.bodies[plan.upper].0;
        let lower = self.bodies[plan.lower].0;
        let mut tips = Vec::new();
        if let Some(blades) = &plan.blades {
            for (t, name) in blades.names.iter().enumerate() {
                // the wires' pull on this tip at the nominal geometry (parent axes; level)
                let mut pull = zero3();
                for set in &plan.sets {
                    for w in set.wires.iter().filter(|w| w.tip == Some(t)) {
                        pull += Vector3::new(
                            share * w.across.0 / w.vertical,
                            share * w.across.1 / w.vertical,
                            -share,
                        );
                    }
                }
                let parent_at = self.bodies[plan.upper].1;
                tips.push(self.blade(blades, t, name, upper, parent_at, pull)?);
            }
        }
        for set in &plan.sets {
            let tags = wire_tags(&set.set.tags.value);
            for w in &set.wires {
                let upper_end = match w.tip {
                    // a point on the tip, moved with the tip's derivative (see `blade`)
                    Some(t) => {
                        let (tip, moved) = tips[t];
                        (tip, w.upper + moved)
                    }
                    None => (upper, w.upper),
                };
                let tension = if w.vertical.re() == set.length.re() {
                    share
                } else {
                    share * set.length / w.vertical
                };
                self.wire(set, w, upper_end, (lower, w.lower), tension, &tags)?;
            }
        }
        Ok(())
    }

    /// Adds blade tip `t` of `blades` (T020205 §6.3–§6.4) on body `parent` and returns the
    /// tip body, with the derivative of the tip's position that the points on it carry. Its
    /// spring's preload balances the wires' pull and the tip's weight, so that the tip is in
    /// equilibrium at the nominal geometry.
    ///
    /// The tip's position on its parent is a constant of the tip's pose, written into its
    /// text as a number: the number is its value, and its derivative (which text cannot
    /// carry) moves every point on the tip instead (the spring's end, the wires' ends, the
    /// lite tip's centre of mass). The tip's axes are its parent's (its pose turns nothing),
    /// so moving the tip's origin by δ and moving every point on it by δ in its own axes are
    /// the same. The shift's value is exactly 0: an `f64` build is unchanged.
    fn blade(
        &mut self,
        blades: &PlannedBlades<S>,
        t: usize,
        name: &str,
        parent: BodyId,
        parent_at: Vector3<S>,
        pull: Vector3<S>,
    ) -> Result<(BodyId, Vector3<S>), BuildError> {
        let ctx = self.ctx;
        let f = &blades.fields;
        let at = &blades.set.at;
        let need = |ex: &Option<Ex>, what: &str| -> Result<S, BuildError> {
            match ex {
                Some(ex) => ctx.eval(ex),
                None => Err(invalid(at, format!("this blade form needs `{what}`"))),
            }
        };
        let kc = match &f.stiffness {
            Some(ex) => ctx.positive(ex, "N/m")?,
            None => return Err(invalid(at, "needs `stiffness` (N/m, vertical, per blade)")),
        };
        let tip_at = blades.tips[t];
        let value = |v: S| num(v.re());
        let scope = blades.scope;
        let (z, x) = (format!("{scope}zb{name}"), format!("{scope}xb{name}"));
        let tip_name = format!("{scope}blade{name}");
        let zero = S::from(0.0);
        let mut stiffness = Vector6::new(zero, zero, kc, zero, zero, zero);
        let mut tip_weight = zero;
        // the derivative of the tip's position, carried by the points on the tip (zero for
        // the full form, whose tip is placed by its own coordinates)
        let moved = match blades.form {
            BladeForm::Full => zero3(),
            _ => tip_at.map(|v| v - S::from(v.re())),
        };
        let b = &mut self.b;
        let tip = match blades.form {
            BladeForm::XtraLite | BladeForm::Lateral | BladeForm::Lite => {
                let x_expr = if blades.form == BladeForm::Lateral {
                    b.float(&x, 0.0).map_err(placed(at))?;
                    stiffness[0] = lateral_stiffness(ctx, f, kc, at)?;
                    format!("{} + {x}", value(tip_at.x))
                } else {
                    value(tip_at.x)
                };
                let mut spec = BodySpec::new(&tip_name)
                    .on(parent)
                    .pose([
                        &x_expr,
                        &value(tip_at.y),
                        &format!("{} + {z}", value(tip_at.z)),
                        "0",
                        "0",
                        "0",
                    ])
                    .centre_of_mass(moved);
                if blades.form == BladeForm::Lite {
                    b.variable(&z, 0.0).map_err(placed(at))?;
                    spec = spec.mass(blades.tip_mass);
                    tip_weight = blades.tip_mass * self.g;
                } else {
                    b.float(&z, 0.0).map_err(placed(at))?;
                }
                b.body(spec).map_err(placed(at))?
            }
            BladeForm::Full => {
                let lab = parent_at + tip_at;
                let names = AXES.map(|n| format!("{scope}{n}b{name}"));
                for (k, n) in names.iter().enumerate() {
                    // search starts: real parts
                    b.variable(n, if k < 3 { lab[k].re() } else { 0.0 })
                        .map_err(placed(at))?;
                }
                let m = blades.tip_mass;
                let i = need(&f.tip_inertia, "tip_inertia")?;
                tip_weight = m * self.g;
                let kt = need(&f.transverse_stiffness, "transverse_stiffness")?;
                let kr = need(&f.rotational_stiffness, "rotational_stiffness")?;
                stiffness = Vector6::new(kt, kt, kc, kr, kr, kr);
                self.b
                    .body(
                        BodySpec::new(&tip_name)
                            .pose(names.each_ref().map(String::as_str))
                            .mass(m)
                            .inertia(Matrix3::from_diagonal_element(i)),
                    )
                    .map_err(placed(at))?
            }
        };
        // the tip frame's origin is the tip itself in every form
        let ends = [
            SpringEnd {
                body: parent,
                point: tip_at,
                angles: [zero; 3],
            },
            SpringEnd {
                body: tip,
                point: moved,
                angles: [zero; 3],
            },
        ];
        self.b
            .spring(
                &tip_name,
                ends,
                Matrix6::from_diagonal(&stiffness),
                Vector6::new(pull.x, pull.y, pull.z - tip_weight, zero, zero, zero),
                &blades.tag,
            )
            .map_err(placed(at))?;
        Ok((tip, moved))
    }

    /// Adds one wire of a set, the shared beaded fibre ([`add_beaded_fibre`]): without beads
    /// one wire (of the profile, if the set has one); with beads its segments joined at the
    /// beads as the set says, each the slice of the profile it spans and carrying the
    /// tension of the lowest plus the weight of the beads below it.
    fn wire(
        &mut self,
        set: &PlannedSet<S>,
        w: &PlannedWire<S>,
        upper: (BodyId, Vector3<S>),
        lower: (BodyId, Vector3<S>),
        tension: S,
        tags: &WireTags,
    ) -> Result<(), BuildError> {
        let end = |(body, point): (BodyId, Vector3<S>), direction: &EndDirection<S>| WireEnd {
            body,
            point,
            direction: direction.clone(),
        };
        add_beaded_fibre(
            &mut self.b,
            &BeadedFibre {
                name: &w.name,
                scope: set.scope,
                upper: end(upper, &set.ends[0]),
                lower: end(lower, &set.ends[1]),
                nominal: w.nominal,
                section: &set.section,
                length: set.length,
                tension,
                g: self.g,
                beads: set.beads,
                joints: set.set.bead_joints,
                profile: set.profile.as_ref(),
                continuum: set.set.continuum,
            },
            tags,
        )
        .map_err(placed(&set.set.at))
    }

    fn springs(&mut self, stage: &StageFile, set: &SpringSet) -> Result<(), BuildError> {
        let ctx = self.ctx;
        let upper = self.bodies[self.index[stage.from.value.as_str()]].0;
        let lower = self.bodies[self.index[stage.body.as_str()]].0;
        let zero = S::from(0.0);
        let ends = |p: &Option<Points>| -> Result<(Vec<Vector3<S>>, [S; 3]), BuildError> {
            match p {
                None => Ok((vec![zero3()], [zero; 3])),
                Some(p) => {
                    let angles = match &p.angles {
                        Some(a) => ctx.vec3(a)?.into(),
                        None => [zero; 3],
                    };
                    Ok((ctx.points(p)?, angles))
                }
            }
        };
        let (ups, up_angles) = ends(&set.upper)?;
        let (lows, low_angles) = ends(&set.lower)?;
        let count = ups.len().max(lows.len());
        let pick = |list: &[Vector3<S>], k: usize| if list.len() == 1 { list[0] } else { list[k] };
        if (ups.len() != 1 && ups.len() != count) || (lows.len() != 1 && lows.len() != count) {
            return Err(invalid(
                &set.at,
                format!(
                    "{} upper and {} lower ends: give as many of each (or one, shared)",
                    ups.len(),
                    lows.len()
                ),
            ));
        }
        let names = set
            .names
            .expand(count, &set.at)
            .map_err(|e| invalid(&set.at, e.message))?;
        let mut k = Matrix6::from_element(zero);
        if set.diagonal {
            for (i, ex) in set.stiffness[0].iter().enumerate() {
                k[(i, i)] = ctx.eval(ex)?;
            }
        } else {
            for (i, row) in set.stiffness.iter().enumerate() {
                for (j, ex) in row.iter().enumerate() {
                    k[(i, j)] = ctx.eval(ex)?;
                }
            }
        }
        let mut preload = Vector6::from_element(zero);
        if let Some(p) = &set.preload {
            for (i, ex) in p.value.iter().enumerate() {
                preload[i] = ctx.eval(ex)?;
            }
        }
        for (s, name) in names.iter().enumerate() {
            let name = format!("{}{name}", stage.scope);
            let spring_ends = [
                SpringEnd {
                    body: upper,
                    point: pick(&ups, s),
                    angles: up_angles,
                },
                SpringEnd {
                    body: lower,
                    point: pick(&lows, s),
                    angles: low_angles,
                },
            ];
            self.b
                .spring(&name, spring_ends, k, preload, &set.tag.value)
                .map_err(placed(&set.at))?;
        }
        Ok(())
    }

    /// One `[[element]]`: its bodies found, points and values evaluated (through the
    /// parameters, so overrides and sensitivities see them), checked against its kind's
    /// schema (the one check every instance meets, placed here on the line at fault;
    /// defaults filled), then added as a plug-in element instance.
    fn instance(&mut self, file: &'s InstanceFile) -> Result<(), BuildError> {
        let ctx = self.ctx;
        let kind = pendkit_energy::find_kind(&file.kind.value);
        let Some(schema) = kind.and_then(|k| k.instance_schema()) else {
            let why = if kind.is_some() {
                "owns no instances (it acts on every wire of a stage; `[elements]` moves it)"
            } else {
                "is not registered"
            };
            return Err(invalid(
                &file.kind.at,
                format!(
                    "element kind '{}' {why}; kinds with instances: {}",
                    file.kind.value,
                    pendkit_energy::kinds_with_instances()
                ),
            ));
        };
        let who = format!("{} '{}'", file.kind.value, file.name);
        let mut bodies = Vec::with_capacity(file.between.value.len());
        for name in &file.between.value {
            let body = self
                .index
                .get(name.as_str())
                .and_then(|&i| self.bodies.get(i))
                .ok_or_else(|| {
                    let known = known_bodies(self.spec);
                    let message = format!("{who}: unknown body '{name}' (bodies: {known})");
                    invalid(&file.between.at, message)
                })?;
            bodies.push(body.0);
        }
        let points = match &file.points {
            Some(p) => p
                .value
                .iter()
                .map(|q| ctx.vec3(q))
                .collect::<Result<_, _>>()?,
            None => Vec::new(),
        };
        let mut values = std::collections::BTreeMap::new();
        for (name, ex) in &file.values {
            values.insert(name.value.clone(), ctx.eval(ex)?);
        }
        let mut element = PluginElement {
            kind: file.kind.value.clone(),
            name: file.name.clone(),
            bodies,
            points,
            values,
            tag: file
                .tag
                .as_ref()
                .map_or_else(|| file.name.clone(), |t| t.value.clone()),
        };
        schema.check(&element).map_err(|m| {
            let value = |name: &str| file.values.iter().find(|(n, _)| n.value == name);
            let (at, message) = match &m.part {
                Part::Bodies => (&file.between.at, m.message),
                Part::Points => (file.points.as_ref().map_or(&file.at, |p| &p.at), m.message),
                Part::Values => (&file.values_at, m.message),
                // a value out of its domain shows the expression that gave it
                Part::Value(name) => match value(name) {
                    Some((n, _)) if schema.field(name).is_none() => (&n.at, m.message),
                    Some((_, ex)) => (&ex.at, format!("`{}`: {}", ex.text, m.message)),
                    None => (&file.values_at, m.message),
                },
            };
            invalid(at, format!("{who}: {message}"))
        })?;
        schema.fill_defaults(&mut element);
        self.b.plugin_element(element).map_err(placed(&file.at))
    }

    /// Element stages, named signals, extra terms, constraints and pins.
    fn extras(&mut self) -> Result<(), BuildError> {
        let ctx = self.ctx;
        for choice in &self.spec.elements {
            let Some(kind) = pendkit_energy::find_kind(&choice.kind) else {
                let known: Vec<&str> = pendkit_energy::registry()
                    .iter()
                    .map(|k| k.kind())
                    .collect();
                return Err(invalid(
                    &choice.at,
                    format!(
                        "unknown element kind '{}' (registered: {})",
                        choice.kind,
                        known.join(", ")
                    ),
                ));
            };
            if kind.stage() == Stage::S0A {
                return Err(invalid(
                    &choice.at,
                    format!(
                        "'{}' is a core kind of stage 0A (the equilibrium needs it): it cannot be moved or switched off",
                        choice.kind
                    ),
                ));
            }
            if let Some(stage) = choice.stage {
                self.b.element_stage(&choice.kind, stage);
            }
        }
        for (list, output) in [(&self.spec.inputs, false), (&self.spec.outputs, true)] {
            for s in list {
                let signal = self.signal(&s.name, &s.text)?;
                self.b
                    .named_signal(signal, output)
                    .map_err(placed(&s.text.at))?;
            }
        }
        for t in &self.spec.extra_terms {
            let energy = self.substitute_parameters(&t.energy, t.after_equilibrium)?;
            let phase = if t.after_equilibrium {
                ExtraPhase::AfterEquilibrium
            } else {
                ExtraPhase::BeforeEquilibrium
            };
            self.b
                .extra_term(&t.name, &energy.to_string(), &t.tag, phase)
                .map_err(placed(&t.at))?;
        }
        for (name, stiffness) in &self.spec.constraints {
            let k = ctx.fixed(stiffness, "a constraint stiffness (kept in f64)")?;
            self.b
                .constraint_stiffness(&name.value, k)
                .map_err(placed(&name.at))?;
        }
        for pin in &self.spec.pins {
            self.b.pin(&pin.value).map_err(placed(&pin.at))?;
        }
        Ok(())
    }

    /// A named signal from its text.
    fn signal(&self, name: &str, text: &Located<String>) -> Result<NamedSignal, BuildError> {
        let at = &text.at;
        let (force, body_text) = match text.value.trim().strip_prefix("force:") {
            Some(rest) => (true, rest.trim()),
            None => (false, text.value.trim()),
        };
        // signals are kept in f64: a parameter they read must not carry a derivative
        let moved = RefCell::new(Vec::<(String, u64)>::new());
        let value = |s: &str| {
            let directions = self.ctx.moving(s);
            if directions != 0 {
                moved.borrow_mut().push((s.to_string(), directions));
            }
            self.ctx.params.get(s).ok()
        };
        let terms = if let Some(point) = point_form(body_text, &value) {
            let (body, point, direction) = point.map_err(|m| invalid(at, m))?;
            let body_id = self
                .index
                .get(body.as_str())
                .map(|&i| self.bodies[i].0)
                // or a body the file's stages make, such as a blade tip (`blade1l`)
                .or_else(|| self.b.body_id(&body))
                .ok_or_else(|| {
                    invalid(
                        at,
                        format!(
                            "unknown body '{body}' (bodies: {}, and the blade tips)",
                            known_bodies(self.spec)
                        ),
                    )
                })?;
            if direction.norm() == 0.0 {
                return Err(invalid(at, "the direction is a zero vector"));
            }
            vec![(
                1.0,
                SignalTerm::Point {
                    body: body_id,
                    point,
                    direction: direction.normalize(),
                },
            )]
        } else {
            let expr = pendkit_expr::parse(body_text).map_err(|e| invalid(at, e.to_string()))?;
            self.ctx.record(&expr, &at.path);
            let is_coordinate = |s: &str| self.b.find_coordinate(s).is_some();
            linear_form(&expr, &is_coordinate, &value)
                .map_err(|m| invalid(at, format!("`{body_text}` {m}")))?
                .into_iter()
                .filter_map(|(c, k)| {
                    self.b
                        .find_coordinate(&c)
                        .map(|(id, _)| (k, SignalTerm::Coordinate(id)))
                })
                .collect()
        };
        for (s, directions) in moved.take() {
            self.ctx.lose_directions(
                directions,
                at,
                &format!("'{s}' is read by signal '{name}', which is kept in f64"),
            )?;
        }
        Ok(NamedSignal {
            name: name.to_string(),
            force,
            terms,
        })
    }
}

/// Tags `<prefix>_stretch`, `<prefix>_bending`, `<prefix>_torsion`.
fn wire_tags(prefix: &str) -> WireTags {
    WireTags {
        stretch: format!("{prefix}_stretch"),
        bending: format!("{prefix}_bending"),
        torsion: format!("{prefix}_torsion"),
    }
}

fn known_bodies(spec: &Spec) -> String {
    spec.bodies
        .iter()
        .map(|b| b.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The lateral blade form's sideways stiffness (N/m): `lateral_stiffness`, or
/// `lateral_ratio` times the vertical stiffness `kc`.
fn lateral_stiffness<S: BuildScalar>(
    ctx: &Ctx<S>,
    f: &BladeFields,
    kc: S,
    at: &At,
) -> Result<S, BuildError> {
    Ok(match (&f.lateral_stiffness, &f.lateral_ratio) {
        (Some(k), _) => ctx.eval(k)?,
        (None, Some(r)) => ctx.eval(r)? * kc,
        (None, None) => {
            return Err(invalid(
                at,
                "the lateral form needs `lateral_stiffness` (N/m) or `lateral_ratio`",
            ));
        }
    })
}

/// `spec` with what `body` says besides where it is: its mass, inertia and centre of mass,
/// the shape it is drawn as and its mode family. Returns the spec and the mass.
fn mass_properties<S: BuildScalar>(
    ctx: &Ctx<S>,
    body: &BodyFile,
    mut spec: BodySpec<S>,
) -> Result<(BodySpec<S>, S), BuildError> {
    let mass = match &body.mass {
        Some(m) => ctx.eval(m)?,
        None => S::from(0.0),
    };
    spec = spec.mass(mass);
    let inertia = match &body.inertia {
        None => None,
        Some(Inertia::Diagonal(d)) => {
            let v = ctx.vec3(d)?;
            let zero = S::from(0.0);
            Some((
                Matrix3::new(v.x, zero, zero, zero, v.y, zero, zero, zero, v.z),
                &d.at,
            ))
        }
        Some(Inertia::Tensor(at, rows)) => {
            let mut m = Matrix3::from_element(S::from(0.0));
            for (i, row) in rows.iter().enumerate() {
                for (j, ex) in row.iter().enumerate() {
                    m[(i, j)] = ctx.eval(ex)?;
                }
            }
            Some((m, at))
        }
    };
    if let Some((m, at)) = inertia {
        // checked here as well as by the builder, so that the error is at the field
        pendkit_model::check_inertia(&format!("body '{}'", body.name), &m.map(|v| v.re()))
            .map_err(|e| invalid(at, e.to_string()))?;
        spec = spec.inertia(m);
    }
    if let Some(c) = &body.centre_of_mass {
        spec = spec.centre_of_mass(ctx.vec3(c)?);
    }
    if let Some(shape) = &body.shape {
        spec = spec.shape(evaluate_shape(ctx, shape)?);
    }
    if let Some(family) = &body.mode_family {
        spec = spec.mode_family(&family.value);
    }
    Ok((spec, mass))
}

/// Checks that wire set `set` has a lower end for each of its `per_tip` upper ends on each
/// blade tip (or, without blades, for each upper end): `lowers` of them.
fn check_lower_count<S: Real>(
    set: &WireSet,
    tips: Option<&Vec<Vector3<S>>>,
    per_tip: usize,
    lowers: usize,
) -> Result<(), BuildError> {
    match tips {
        Some(tips) if tips.len() * per_tip != lowers => {
            return Err(invalid(
                &set.lower.at,
                format!(
                    "{} lower ends for {} blade tips carrying {per_tip} wire(s) each",
                    lowers,
                    tips.len()
                ),
            ));
        }
        None if per_tip != lowers => {
            return Err(invalid(
                &set.lower.at,
                format!("{} lower ends for {per_tip} upper ends", lowers),
            ));
        }
        _ => {}
    }
    Ok(())
}

/// The unstretched length (m) of the wires of `set` (named `names`), which must be
/// positive.
fn wire_length<S: BuildScalar>(
    ctx: &Ctx<S>,
    set: &WireSet,
    names: &[String],
) -> Result<S, BuildError> {
    let length = ctx.eval(&set.length)?;
    if length.re() <= 0.0 {
        // named after the set's first wire, and said plainly when it is zero
        let first = names
            .first()
            .map_or(String::new(), |n| format!("wire '{n}': "));
        let zero = if length.re() == 0.0 {
            " (a zero-length wire)"
        } else {
            ""
        };
        return Err(invalid(
            &set.length.at,
            format!(
                "{first}`{}` = {} m must be positive{zero}",
                set.length.text,
                number_text(length.re())
            ),
        ));
    }
    Ok(length)
}

/// Evaluates and checks a shape.
pub fn evaluate_shape<S: BuildScalar>(
    ctx: &Ctx<S>,
    shape: &ShapeFile,
) -> Result<Shape, BuildError> {
    // a drawing's shape, not a model number: real parts
    match shape {
        ShapeFile::Box { half_sizes } => {
            let mut half_sizes_m = Vector3::zeros();
            for (k, ex) in half_sizes.value.iter().enumerate().take(3) {
                half_sizes_m[k] = ctx.positive(ex, "m")?.re();
            }
            Ok(Shape::Box {
                half_sizes: half_sizes_m,
            })
        }
        ShapeFile::Cylinder {
            radius,
            half_length,
            axis,
        } => Ok(Shape::Cylinder {
            radius: ctx.positive(radius, "m")?.re(),
            half_length: ctx.positive(half_length, "m")?.re(),
            axis: *axis,
        }),
    }
}

/// The parameters the nominal tension expression of material damping reads, for `params`:
/// every symbol of every damping field, by tag.
pub fn damping_reads(
    damping: &std::collections::BTreeMap<String, pendkit_model::DampingSpec>,
) -> Vec<(String, BTreeSet<String>)> {
    damping
        .iter()
        .map(|(tag, d)| {
            let mut symbols = BTreeSet::new();
            let texts = d.fields().map(|(_, text)| text);
            for text in texts {
                if let Ok(e) = pendkit_expr::parse(text) {
                    symbols.extend(e.symbols());
                }
            }
            symbols.remove("f");
            (tag.clone(), symbols)
        })
        .collect()
}
