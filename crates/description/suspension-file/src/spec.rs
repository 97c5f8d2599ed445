//! The typed description a suspension file gives, read from its (merged) node tree. Every
//! field keeps its place; nothing here evaluates an expression (that is the build's job, with
//! the parameters' values).

use pendkit_limits::WIRES_PER_SET;
use pendkit_model::beads::BeadJoints;
use pendkit_model::schema::{self, DAMPING_FIELDS, Domain, Field};
use pendkit_system::{CoordKind, Stage};

use crate::read::{Ex, Fields, expr_array};
use crate::source::{At, FileError, Located, join};
use crate::tree::{Node, Value};

/// A whole suspension as the file describes it.
#[derive(Clone, Debug, Default)]
pub struct Spec {
    /// `name`, if the file gives one (else the file's stem).
    pub name: Option<Located<String>>,
    /// `summary`: one line saying what the suspension is.
    pub summary: Option<Located<String>>,
    /// `gravity` (m/s²); 9.81 when absent.
    pub gravity: Option<Ex>,
    /// In a scene ([`crate::scene`]): the gravity of each included suspension but the one
    /// whose gravity is the scene's (`None`: it writes none, 9.81 m/s²), with the prefix it
    /// is included under (placed at the include); the build checks that each equals the
    /// scene's.
    pub gravity_checks: Vec<(Located<String>, Option<Ex>)>,
    /// `[parameters]`, in the file's order.
    pub parameters: Vec<ParameterSpec>,
    /// `[materials.<name>]`.
    pub materials: Vec<MaterialSpec>,
    /// `[defaults.blade]`: fields every blade set takes unless it gives its own.
    pub blade_defaults: BladeFields,
    /// `[coordinates.<name>]`: coordinates declared one by one (escape hatch).
    pub coordinates: Vec<CoordinateSpec>,
    /// `[bodies.<name>]`, in the file's order.
    pub bodies: Vec<BodyFile>,
    /// `[stages.<body>]`: how each hung body hangs.
    pub stages: Vec<StageFile>,
    /// `[damping.<tag>]`.
    pub damping: Vec<DampingFile>,
    /// `[elements]`: element kinds moved to another stage or switched off.
    pub elements: Vec<ElementChoice>,
    /// `[[element]]`: instances of element kinds that own instances (a point spring).
    pub instances: Vec<InstanceFile>,
    /// `[inputs]`.
    pub inputs: Vec<SignalFile>,
    /// `[outputs]`.
    pub outputs: Vec<SignalFile>,
    /// `[extra_terms.<name>]`: potential terms written as expressions (escape hatch).
    pub extra_terms: Vec<ExtraFile>,
    /// `[constraints]`: stiffness tying a coordinate to its equilibrium (escape hatch).
    pub constraints: Vec<(Located<String>, Ex)>,
    /// `pin`: coordinates held at their start during the equilibrium search.
    pub pins: Vec<Located<String>>,
    /// `[names.<scheme>]`: other names for bodies and their coordinates (e.g. LIGO's).
    pub name_schemes: Vec<NameSchemeFile>,
}

/// `[names.<scheme>]`: a naming scheme such as LIGO's (`L3` for the test mass, `L3_P` for
/// its pitch).
#[derive(Clone, Debug)]
pub struct NameSchemeFile {
    /// The scheme's name (`ligo`), chosen on the command line with `--naming`.
    pub scheme: String,
    /// Where it is written.
    pub at: At,
    /// The scheme's names of the six pose entries in pose order (x, y, z, yaw, pitch, roll):
    /// coordinates become `<body alias>_<dof>`. LIGO's `L T V Y P R` when absent.
    pub dofs: [String; 6],
    /// Body name and its name in the scheme, in the file's order.
    pub bodies: Vec<(Located<String>, String)>,
}

/// One parameter: its definition, unit and description.
#[derive(Clone, Debug)]
pub struct ParameterSpec {
    /// Name.
    pub name: String,
    /// Definition (a number or an expression of other parameters).
    pub value: Ex,
    /// Unit as written (free text), empty if not given.
    pub unit: String,
    /// Description, empty if not given.
    pub description: String,
    /// `allowed`: the only values the parameter may take (a switch such as 0 or 1).
    pub allowed: Option<Located<Vec<f64>>>,
    /// `domain`: the values it may physically take (`> 0`, `>= 0`, `in (-1, 0.5)`),
    /// checked for every value it takes, overrides included.
    pub domain: Option<Located<Domain>>,
    /// Where the parameter is defined.
    pub at: At,
}

/// A material: each constant an expression (usually naming a parameter).
#[derive(Clone, Debug)]
pub struct MaterialSpec {
    /// Name.
    pub name: String,
    /// Where it is defined.
    pub at: At,
    /// Young's modulus E (Pa).
    pub youngs_modulus: Option<Ex>,
    /// Shear modulus G (Pa); or from `poisson_ratio` as E / (2 (1 + ν)).
    pub shear_modulus: Option<Ex>,
    /// Poisson's ratio ν.
    pub poisson_ratio: Option<Ex>,
    /// Density ρ (kg/m³).
    pub density: Option<Ex>,
    /// Structural loss angle φ.
    pub loss_angle: Option<Ex>,
    /// Specific heat C (J/(kg K)).
    pub specific_heat: Option<Ex>,
    /// Thermal conductivity K (W/(m K)).
    pub conductivity: Option<Ex>,
    /// Linear thermal expansion α (1/K).
    pub thermal_expansion: Option<Ex>,
    /// Temperature coefficient of Young's modulus, β = d ln E / dT (1/K).
    pub dlne_dt: Option<Ex>,
    /// Surface-loss dissipation depth d_s (m).
    pub dissipation_depth: Option<Ex>,
}

impl MaterialSpec {
    /// Each constant with its name in [`pendkit_model::schema::MATERIAL_FIELDS`] (the
    /// reader's keys), in that table's order.
    pub fn fields(&self) -> [(&'static str, &Option<Ex>); 10] {
        [
            ("youngs_modulus", &self.youngs_modulus),
            ("shear_modulus", &self.shear_modulus),
            ("poisson_ratio", &self.poisson_ratio),
            ("density", &self.density),
            ("loss_angle", &self.loss_angle),
            ("specific_heat", &self.specific_heat),
            ("conductivity", &self.conductivity),
            ("thermal_expansion", &self.thermal_expansion),
            ("dlnE_dT", &self.dlne_dt),
            ("dissipation_depth", &self.dissipation_depth),
        ]
    }
}

/// A coordinate declared by hand.
#[derive(Clone, Debug)]
pub struct CoordinateSpec {
    /// Name.
    pub name: String,
    /// Variable, float or parameter.
    pub kind: CoordKind,
    /// Start of the equilibrium search (nominal value for a parameter), m or rad.
    pub start: Option<Ex>,
    /// Held at its start during the equilibrium search.
    pub pinned: bool,
    /// Where it is declared.
    pub at: At,
}

/// The six pose entries in order.
pub const AXES: [&str; 6] = ["x", "y", "z", "yaw", "pitch", "roll"];

/// A body.
#[derive(Clone, Debug)]
pub struct BodyFile {
    /// Name.
    pub name: String,
    /// Where it is defined.
    pub at: At,
    /// `coordinates = "<suffix>"`: the pose is the coordinates `x<suffix> ... roll<suffix>`.
    pub coordinates: Option<Located<String>>,
    /// `driven = true`: those coordinates are inputs (parameters), as the support's are.
    pub driven: bool,
    /// `dof`: which of the six are coordinates (indices into [`AXES`]); the others are
    /// held at the nominal pose.
    pub dof: Option<Located<Vec<usize>>>,
    /// `pose`: six expressions of coordinates (and parameters), instead of `coordinates`.
    pub pose: Option<Located<Vec<Ex>>>,
    /// `parent`: the body whose frame `pose` is relative to.
    pub parent: Option<Located<String>>,
    /// `position`: nominal centre (m), for bodies whose height no wire fixes.
    pub position: Option<Located<Vec<Ex>>>,
    /// Mass (kg); 0 when absent.
    pub mass: Option<Ex>,
    /// Inertia about the centre of mass in body axes (kg m²).
    pub inertia: Option<Inertia>,
    /// Centre of mass in body coordinates (m).
    pub centre_of_mass: Option<Located<Vec<Ex>>>,
    /// Drawing shape; the uniform box of the same mass and inertia when absent.
    pub shape: Option<ShapeFile>,
    /// `mode_family`: modes dominated by this body's coordinates belong to this family
    /// (e.g. `violin`) rather than to their degree of freedom.
    pub mode_family: Option<Located<String>>,
    /// The prefix of the scene's `[[include]]` the body came from (empty for a file's own
    /// bodies): its coordinates are `<scope>x<suffix>` ... (see [`crate::scene`]).
    pub scope: String,
}

/// An inertia as written: principal moments or a full tensor.
#[derive(Clone, Debug)]
pub enum Inertia {
    /// `[Ixx, Iyy, Izz]`.
    Diagonal(Located<Vec<Ex>>),
    /// `[[Ixx, Ixy, Ixz], [Iyx, Iyy, Iyz], [Izx, Izy, Izz]]`.
    Tensor(At, Vec<Vec<Ex>>),
}

/// A drawing shape (read and checked; drawn by the plotting tools).
#[derive(Clone, Debug)]
pub enum ShapeFile {
    /// `{ kind = "box", half_sizes = [hx, hy, hz] }` (m).
    Box {
        /// Half sizes along the body axes (m).
        half_sizes: Located<Vec<Ex>>,
    },
    /// `{ kind = "cylinder", radius, half_length, axis = "x" | "y" | "z" }` (m).
    Cylinder {
        /// Radius (m).
        radius: Ex,
        /// Half length along the axis (m).
        half_length: Ex,
        /// Axis index (0 x, 1 y, 2 z).
        axis: usize,
    },
}

/// How one body hangs: from which body, by which parts.
#[derive(Clone, Debug)]
pub struct StageFile {
    /// The hung (lower) body: the stage's key.
    pub body: String,
    /// Where the stage is defined.
    pub at: At,
    /// `from`: the upper body.
    pub from: Located<String>,
    /// Blade springs on the upper body; the wires hang from their tips.
    pub blades: Option<BladeSet>,
    /// Wires.
    pub wires: Option<WireSet>,
    /// Fibres (wires by another name, usually the last stage's).
    pub fibres: Option<WireSet>,
    /// Six-axis springs between the bodies.
    pub springs: Option<SpringSet>,
    /// A rigid link: the body rides on the upper one.
    pub link: Option<LinkFile>,
    /// The prefix of the scene's `[[include]]` the stage came from (empty for a file's own
    /// stages): the names of its parts, and of what the build makes from them (blade tips,
    /// beads), start with it (see [`crate::scene`]).
    pub scope: String,
}

impl StageFile {
    /// The stage's wire sets (wires, then fibres).
    pub fn wire_sets(&self) -> impl Iterator<Item = &WireSet> {
        self.wires.iter().chain(self.fibres.iter())
    }
}

/// How a set of parts is named.
#[derive(Clone, Debug)]
pub enum Names {
    /// `name = "w1_"`: `w1_1`, `w1_2`, ... (just the prefix when there is one part).
    Prefix(String),
    /// `names = ["w1_l", "w1_r"]`.
    List(Located<Vec<String>>),
}

impl Names {
    /// The names of `count` parts (at most [`WIRES_PER_SET`], checked before any is made).
    pub fn expand(&self, count: usize, at: &At) -> Result<Vec<String>, FileError> {
        WIRES_PER_SET
            .check(count)
            .map_err(|e| at.error(e.to_string()))?;
        match self {
            Names::Prefix(p) if count == 1 => Ok(vec![p.clone()]),
            Names::Prefix(p) => Ok((1..=count).map(|k| format!("{p}{k}")).collect()),
            Names::List(list) if list.value.len() == count => Ok(list.value.clone()),
            Names::List(list) => Err(list
                .at
                .error(format!("{} names for {count} parts", list.value.len()))),
        }
        .and_then(|names| {
            if names.iter().any(|n| n.is_empty()) {
                Err(at.error("empty part name"))
            } else {
                Ok(names)
            }
        })
    }
}

/// Attachment points: one point mirrored, or a list; with how a wire leaves them.
#[derive(Clone, Debug)]
pub struct Points {
    /// Where the points are written.
    pub at: At,
    /// The points (before mirroring), each three expressions (m).
    pub base: Vec<Located<Vec<Ex>>>,
    /// Axes to mirror across, in order (each doubles the list: the copies follow).
    pub mirror: Vec<usize>,
    /// `hinged`: non-zero means the wire pivots freely here (an expression, so a parameter
    /// can choose).
    pub hinged: Option<Ex>,
    /// `direction`: explicit clamp direction in body coordinates, pointing into the wire.
    pub direction: Option<Located<Vec<Ex>>>,
    /// `angles` (yaw, pitch, roll, rad): a spring end's axes relative to the body's.
    pub angles: Option<Located<Vec<Ex>>>,
}

/// Blade fields that `[defaults.blade]` may give for every blade set.
#[derive(Clone, Debug, Default)]
pub struct BladeFields {
    /// `form`: how a tip is modelled.
    pub form: Option<Located<BladeForm>>,
    /// Vertical stiffness of one blade at its tip (N/m).
    pub stiffness: Option<Ex>,
    /// Tip mass (kg), `lite` and `full`.
    pub tip_mass: Option<Ex>,
    /// Tip moment of inertia about each axis (kg m²), `full`.
    pub tip_inertia: Option<Ex>,
    /// Stiffness of the tip in x and y (N/m), `full`.
    pub transverse_stiffness: Option<Ex>,
    /// Stiffness of the tip in rotation (N m/rad), `full`.
    pub rotational_stiffness: Option<Ex>,
    /// Lateral (x) stiffness (N/m), `lateral`.
    pub lateral_stiffness: Option<Ex>,
    /// Lateral stiffness as a multiple of the vertical one, `lateral`.
    pub lateral_ratio: Option<Ex>,
    /// Material (its loss angle damps the blades' tag).
    pub material: Option<Located<String>>,
    /// Damping tag.
    pub tag: Option<Located<String>>,
    /// Blade thickness (m): with it, the blades' tag gets the material's thermoelastic
    /// loss of a plate bent across its thickness.
    pub thickness: Option<Ex>,
    /// Temperature of the blades (K) for their thermal noise; the model's when absent.
    pub temperature: Option<Ex>,
}

impl BladeFields {
    /// Fills the fields this set does not give from `defaults`.
    pub fn or(&self, defaults: &BladeFields) -> BladeFields {
        BladeFields {
            form: self.form.clone().or_else(|| defaults.form.clone()),
            stiffness: self
                .stiffness
                .clone()
                .or_else(|| defaults.stiffness.clone()),
            tip_mass: self.tip_mass.clone().or_else(|| defaults.tip_mass.clone()),
            tip_inertia: self
                .tip_inertia
                .clone()
                .or_else(|| defaults.tip_inertia.clone()),
            transverse_stiffness: self
                .transverse_stiffness
                .clone()
                .or_else(|| defaults.transverse_stiffness.clone()),
            rotational_stiffness: self
                .rotational_stiffness
                .clone()
                .or_else(|| defaults.rotational_stiffness.clone()),
            lateral_stiffness: self
                .lateral_stiffness
                .clone()
                .or_else(|| defaults.lateral_stiffness.clone()),
            lateral_ratio: self
                .lateral_ratio
                .clone()
                .or_else(|| defaults.lateral_ratio.clone()),
            material: self.material.clone().or_else(|| defaults.material.clone()),
            tag: self.tag.clone().or_else(|| defaults.tag.clone()),
            thickness: self
                .thickness
                .clone()
                .or_else(|| defaults.thickness.clone()),
            temperature: self
                .temperature
                .clone()
                .or_else(|| defaults.temperature.clone()),
        }
    }
}

/// How blade tips are modelled (T020205 §6.3–§6.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BladeForm {
    /// Massless tip moving along the mounting body's z axis: a float.
    XtraLite,
    /// Tip with mass moving along the mounting body's z axis: one variable.
    Lite,
    /// Tip as a 6-DOF body with mass on a 6x6 spring.
    Full,
    /// Massless tip with vertical and lateral (x) compliance: two floats.
    Lateral,
}

impl BladeForm {
    /// The names the file uses.
    pub const NAMES: [(&'static str, BladeForm); 4] = [
        ("xtra-lite", BladeForm::XtraLite),
        ("lite", BladeForm::Lite),
        ("full", BladeForm::Full),
        ("lateral", BladeForm::Lateral),
    ];
}

/// A set of blades on the stage's upper body.
#[derive(Clone, Debug)]
pub struct BladeSet {
    /// Where the set is defined.
    pub at: At,
    /// Tip names: coordinates `zb<name>` (and `xb<name>`, ...), bodies `blade<name>`.
    pub names: Names,
    /// Tip positions on the upper body (m).
    pub tips: Points,
    /// The rest.
    pub fields: BladeFields,
}

/// A set of wires (or fibres) from the upper body (or its blade tips) to the lower body.
#[derive(Clone, Debug)]
pub struct WireSet {
    /// `wires` or `fibres`.
    pub slot: &'static str,
    /// Where the set is defined.
    pub at: At,
    /// Wire names.
    pub names: Names,
    /// Upper ends: on the upper body, or on each blade tip when the stage has blades.
    pub upper: Points,
    /// Lower ends on the hung body.
    pub lower: Points,
    /// Length between the attachment points at equilibrium (m).
    pub length: Ex,
    /// Radius of a round section (m).
    pub radius: Option<Ex>,
    /// A general section instead of `radius`.
    pub section: Option<SectionFile>,
    /// Material name.
    pub material: Option<Located<String>>,
    /// Young's modulus (Pa), overriding the material's.
    pub youngs_modulus: Option<Ex>,
    /// Shear modulus (Pa), overriding the material's.
    pub shear_modulus: Option<Ex>,
    /// Violin-mode beads per wire (a whole number 0–200).
    pub beads: Option<Ex>,
    /// How the beads join the segments (`bead_joints = "clamped"`, the default, or
    /// `"hinged"`).
    pub bead_joints: BeadJoints,
    /// Damping tag prefix: tags `<p>_stretch`, `<p>_bending`, `<p>_torsion`.
    pub tags: Located<String>,
    /// A tapered fibre: thicker necks of their own length at both ends (`radius` is the
    /// middle's).
    pub profile: Option<ProfileFile>,
    /// Surface loss from the material's dissipation depth (`surface_loss = true`).
    pub surface_loss: bool,
    /// Temperature of the set (K) for its thermal noise; the model's when absent.
    pub temperature: Option<Ex>,
    /// A given (measured) dilution factor of the set's bending: the bending loss is scaled
    /// by (computed dilution)/(this).
    pub dilution: Option<Ex>,
    /// Responses and noise take the set's wires as continua (`continuum = true`;
    /// docs/continuum-fibres.md), unless the command says otherwise.
    pub continuum: bool,
}

/// A tapered fibre's profile: a neck of `neck_length` and `neck_radius` at each end, the
/// set's `radius` in between (m).
#[derive(Clone, Debug)]
pub struct ProfileFile {
    /// Where it is written.
    pub at: At,
    /// Length of each neck (m).
    pub neck_length: Ex,
    /// Radius of the necks (m).
    pub neck_radius: Ex,
}

/// A general wire section.
#[derive(Clone, Debug)]
pub struct SectionFile {
    /// Where it is written.
    pub at: At,
    /// Area (m²).
    pub area: Ex,
    /// Second moments about the two principal axes (m⁴).
    pub moments: [Ex; 2],
    /// Torsion constant J_e (m⁴).
    pub torsion_constant: Ex,
    /// Polar moment J (m⁴).
    pub polar_moment: Ex,
    /// First principal axis in the upper body's coordinates.
    pub principal_axis: Option<Located<Vec<Ex>>>,
}

/// A set of six-axis springs between the stage's bodies.
#[derive(Clone, Debug)]
pub struct SpringSet {
    /// Where the set is defined.
    pub at: At,
    /// Spring names.
    pub names: Names,
    /// Ends on the upper body (its origin when absent).
    pub upper: Option<Points>,
    /// Ends on the lower body (its origin when absent).
    pub lower: Option<Points>,
    /// Stiffness: six diagonal entries or a 6x6 matrix (N/m, N/rad, N m/m, N m/rad).
    pub stiffness: Vec<Vec<Ex>>,
    /// Whether `stiffness` is the diagonal.
    pub diagonal: bool,
    /// Preload (N, N m) in the spring's axes.
    pub preload: Option<Located<Vec<Ex>>>,
    /// Damping tag.
    pub tag: Located<String>,
}

/// A rigid link: the hung body rides on the upper body at a fixed offset.
#[derive(Clone, Debug)]
pub struct LinkFile {
    /// Where it is written.
    pub at: At,
    /// Offset of the hung body's origin in the upper body's coordinates (m).
    pub offset: Located<Vec<Ex>>,
    /// Fixed angles (yaw, pitch, roll, rad).
    pub angles: Option<Located<Vec<Ex>>>,
}

/// A `[damping.<tag>]` table: the damping fields of [`pendkit_model::schema::DAMPING_FIELDS`]
/// that it gives, in the table's order.
#[derive(Clone, Debug)]
pub struct DampingFile {
    /// The tag.
    pub tag: String,
    /// Where it is written.
    pub at: At,
    /// Each field given and its expression.
    pub fields: Vec<(&'static Field, Ex)>,
}

/// An element kind moved or switched off.
#[derive(Clone, Debug)]
pub struct ElementChoice {
    /// The kind's registered name.
    pub kind: String,
    /// `Some(stage)` to move it, `None` to switch it off; `true` in the file means its own
    /// stage (nothing to record).
    pub stage: Option<Option<Stage>>,
    /// Where it is written.
    pub at: At,
}

/// One `[[element]]`: an instance of a registered element kind.
#[derive(Clone, Debug)]
pub struct InstanceFile {
    /// `kind`: the registered kind's name.
    pub kind: Located<String>,
    /// `name`: the instance's name (term labels, reports).
    pub name: String,
    /// `between`: the bodies it connects, in the kind's order.
    pub between: Located<Vec<String>>,
    /// `points`: one point (m, three expressions in that body's coordinates) per body.
    pub points: Option<Located<Vec<Located<Vec<Ex>>>>>,
    /// `values`: each value's name (with its place) and expression, in the file's order.
    pub values: Vec<(Located<String>, Ex)>,
    /// Where `values` is written (the instance's place when absent).
    pub values_at: At,
    /// `tag`: damping tag (the instance's name when absent).
    pub tag: Option<Located<String>>,
    /// Where the instance is written.
    pub at: At,
}

/// A named input or output: a linear expression of coordinates, a point
/// `<body>@x,y,z/dx,dy,dz`, or either after `force:`.
#[derive(Clone, Debug)]
pub struct SignalFile {
    /// Name.
    pub name: String,
    /// The definition as written.
    pub text: Located<String>,
}

/// A potential term written as an expression.
#[derive(Clone, Debug)]
pub struct ExtraFile {
    /// Name.
    pub name: String,
    /// Energy (J), an expression of coordinates and parameters.
    pub energy: Ex,
    /// Damping tag.
    pub tag: String,
    /// Part of the minimised potential, or added after the equilibrium.
    pub after_equilibrium: bool,
    /// Where it is written.
    pub at: At,
}

/// Reads the description from a merged file tree.
pub fn read(root: &Node, at: At) -> Result<Spec, FileError> {
    let mut f = Fields::of(root, at)?;
    let mut spec = Spec {
        name: f.string("name")?,
        summary: f.string("summary")?,
        gravity: f.expr("gravity")?,
        ..Spec::default()
    };
    // `extends` is resolved by the loader before the tree is read
    f.node("extends");
    for (name, node, at) in f.named("parameters")? {
        spec.parameters.push(parameter(name, node, at)?);
    }
    for (name, node, at) in f.named("materials")? {
        spec.materials.push(material(name, node, at)?);
    }
    if let Some(mut defaults) = f.table("defaults")? {
        if let Some(mut blade) = defaults.table("blade")? {
            spec.blade_defaults = blade_fields(&mut blade)?;
            blade.finish()?;
        }
        defaults.finish()?;
    }
    for (name, node, at) in f.named("coordinates")? {
        spec.coordinates.push(coordinate(name, node, at)?);
    }
    for (name, node, at) in f.named("bodies")? {
        spec.bodies.push(body(name, node, at)?);
    }
    for (name, node, at) in f.named("stages")? {
        spec.stages.push(stage(name, node, at)?);
    }
    for (tag, node, at) in f.named("damping")? {
        spec.damping.push(damping(tag, node, at)?);
    }
    for (kind, node, at) in f.named("elements")? {
        spec.elements.push(element(kind, node, at)?);
    }
    if let Some((node, at)) = f.node("element") {
        spec.instances = instances(node, at)?;
    }
    for (key, list) in [("inputs", &mut spec.inputs), ("outputs", &mut spec.outputs)] {
        for (name, node, at) in f.named(key)? {
            let Value::Str(text) = &node.value else {
                return Err(at.error(format!(
                    "expected a string (a linear expression of coordinates, <body>@x,y,z/dx,dy,dz, or either after force:), got {}",
                    node.value.type_name()
                )));
            };
            list.push(SignalFile {
                name,
                text: Located {
                    value: text.clone(),
                    at,
                },
            });
        }
    }
    for (name, node, at) in f.named("extra_terms")? {
        spec.extra_terms.push(extra(name, node, at)?);
    }
    for (name, node, at) in f.named("constraints")? {
        let stiffness = Ex::read(node, at.clone())?;
        spec.constraints
            .push((Located { value: name, at }, stiffness));
    }
    for (scheme, node, at) in f.named("names")? {
        spec.name_schemes.push(name_scheme(scheme, node, at)?);
    }
    if let Some(pins) = f.strings("pin")? {
        spec.pins = pins
            .value
            .into_iter()
            .map(|value| Located {
                value,
                at: pins.at.clone(),
            })
            .collect();
    }
    f.finish()?;
    Ok(spec)
}

fn name_scheme(scheme: String, node: &Node, at: At) -> Result<NameSchemeFile, FileError> {
    let mut f = Fields::of(node, at.clone())?;
    let dofs = match f.strings("dofs")? {
        None => pendkit_model::LIGO_DOF_NAMES.map(String::from),
        Some(list) => <[String; 6]>::try_from(list.value).map_err(|given| {
            list.at.error(format!(
                "expected 6 names (x, y, z, yaw, pitch, roll), got {}",
                given.len()
            ))
        })?,
    };
    let mut bodies = Vec::new();
    for (body, alias, body_at) in f.named("bodies")? {
        let Value::Str(alias) = &alias.value else {
            return Err(body_at.error(format!(
                "expected the body's name in the scheme (a string), got {}",
                alias.value.type_name()
            )));
        };
        // an alias is addressed as a body is (`M3@x,y,z/dx,dy,dz`)
        pendkit_model::check_body_name(alias).map_err(|e| body_at.error(e.to_string()))?;
        bodies.push((
            Located {
                value: body,
                at: body_at,
            },
            alias.clone(),
        ));
    }
    f.finish()?;
    Ok(NameSchemeFile {
        scheme,
        at,
        dofs,
        bodies,
    })
}

fn parameter(name: String, node: &Node, at: At) -> Result<ParameterSpec, FileError> {
    if let Value::Table(_) = node.value {
        let mut f = Fields::of(node, at.clone())?;
        let value = f.required_expr("value", "a number or an expression")?;
        let text = |s: Option<Located<String>>| s.map(|l| l.value).unwrap_or_default();
        let unit = text(f.string("unit")?);
        let description = text(f.string("description")?);
        let allowed = match f.node("allowed") {
            None => None,
            Some((node, allowed_at)) => {
                let items = match &node.value {
                    Value::Array(items) if !items.is_empty() => items,
                    _ => return Err(allowed_at.error("expected an array of numbers")),
                };
                let value = items
                    .iter()
                    .map(|n| match &n.value {
                        Value::Num(t) => pendkit_expr::number_literal(t)
                            .map_err(|e| allowed_at.error(e.to_string())),
                        _ => Err(allowed_at.error("expected an array of numbers")),
                    })
                    .collect::<Result<Vec<f64>, _>>()?;
                Some(Located {
                    value,
                    at: allowed_at,
                })
            }
        };
        let domain = match f.string("domain")? {
            None => None,
            Some(text) => Some(Located {
                value: text.value.parse::<Domain>().map_err(|e| text.at.error(e))?,
                at: text.at,
            }),
        };
        f.finish()?;
        Ok(ParameterSpec {
            name,
            value,
            unit,
            description,
            allowed,
            domain,
            at,
        })
    } else {
        Ok(ParameterSpec {
            name,
            value: Ex::read(node, at.clone())?,
            unit: String::new(),
            description: String::new(),
            allowed: None,
            domain: None,
            at,
        })
    }
}

fn material(name: String, node: &Node, at: At) -> Result<MaterialSpec, FileError> {
    let mut f = Fields::of(node, at.clone())?;
    let m = MaterialSpec {
        name,
        at,
        youngs_modulus: f.expr("youngs_modulus")?,
        shear_modulus: f.expr("shear_modulus")?,
        poisson_ratio: f.expr("poisson_ratio")?,
        density: f.expr("density")?,
        loss_angle: f.expr("loss_angle")?,
        specific_heat: f.expr("specific_heat")?,
        conductivity: f.expr("conductivity")?,
        thermal_expansion: f.expr("thermal_expansion")?,
        dlne_dt: f.expr("dlnE_dT")?,
        dissipation_depth: f.expr("dissipation_depth")?,
    };
    if let (Some(_), Some(nu)) = (&m.shear_modulus, &m.poisson_ratio) {
        return Err(nu.at.error("give shear_modulus or poisson_ratio, not both"));
    }
    f.finish()?;
    Ok(m)
}

fn coordinate(name: String, node: &Node, at: At) -> Result<CoordinateSpec, FileError> {
    pendkit_model::check_coordinate_name(&name).map_err(|e| at.error(e.to_string()))?;
    let kind_of = |text: &str, at: &At| match text {
        "variable" => Ok(CoordKind::Variable),
        "float" => Ok(CoordKind::Float),
        "parameter" => Ok(CoordKind::Parameter),
        other => Err(at.error(format!(
            "unknown coordinate kind '{other}' (variable, float or parameter)"
        ))),
    };
    match &node.value {
        Value::Str(kind) => Ok(CoordinateSpec {
            name,
            kind: kind_of(kind, &at)?,
            start: None,
            pinned: false,
            at,
        }),
        _ => {
            let mut f = Fields::of(node, at.clone())?;
            let kind = f
                .string("kind")?
                .ok_or_else(|| at.error("needs `kind` (variable, float or parameter)"))?;
            let c = CoordinateSpec {
                name,
                kind: kind_of(&kind.value, &kind.at)?,
                start: f.expr("start")?,
                pinned: f.bool("pinned")?.is_some_and(|b| b.value),
                at,
            };
            f.finish()?;
            Ok(c)
        }
    }
}

fn vector3(f: &mut Fields, key: &'static str) -> Result<Option<Located<Vec<Ex>>>, FileError> {
    f.exprs(key, Some(3))
}

fn body(name: String, node: &Node, at: At) -> Result<BodyFile, FileError> {
    // a body a signal cannot address is refused where it is written
    pendkit_model::check_body_name(&name).map_err(|e| at.error(e.to_string()))?;
    let mut f = Fields::of(node, at.clone())?;
    let dof = body_dof(&mut f)?;
    let inertia = match f.node("inertia") {
        None => None,
        Some((node, at)) => Some(match &node.value {
            Value::Array(rows) if rows.iter().all(|r| matches!(r.value, Value::Array(_))) => {
                if rows.len() != 3 {
                    return Err(at.error(format!("expected 3 rows, got {}", rows.len())));
                }
                let rows = rows
                    .iter()
                    .enumerate()
                    .map(|(i, r)| {
                        let row_at = At {
                            origin: r.origin.clone(),
                            path: format!("{}[{i}]", at.path),
                        };
                        expr_array(r, row_at, Some(3)).map(|l| l.value)
                    })
                    .collect::<Result<_, _>>()?;
                Inertia::Tensor(at, rows)
            }
            _ => Inertia::Diagonal(expr_array(node, at, Some(3))?),
        }),
    };
    let shape = body_shape(&mut f)?;
    let b = BodyFile {
        name,
        at: at.clone(),
        coordinates: f.string("coordinates")?,
        driven: f.bool("driven")?.is_some_and(|b| b.value),
        dof,
        pose: f.exprs("pose", Some(6))?,
        parent: f.string("parent")?,
        position: vector3(&mut f, "position")?,
        mass: f.expr("mass")?,
        inertia,
        centre_of_mass: vector3(&mut f, "centre_of_mass")?,
        shape,
        mode_family: f.string("mode_family")?,
        scope: String::new(),
    };
    f.planned("temperature", "a temperature per body")?;
    f.finish()?;
    // a body with neither rides on another by a rigid link (checked by the build)
    if let (Some(c), Some(_)) = (&b.coordinates, &b.pose) {
        return Err(c.at.error("give `coordinates` or `pose`, not both"));
    }
    if let (Some(p), None) = (&b.parent, &b.pose) {
        return Err(p.at.error("`parent` goes with `pose`"));
    }
    if let (Some(d), None) = (&b.dof, &b.coordinates) {
        return Err(d.at.error("`dof` goes with `coordinates`"));
    }
    // the suffix makes the coordinates' names (`x<suffix>` ... `roll<suffix>`)
    if let Some(c) = &b.coordinates {
        pendkit_model::check_coordinate_name(&format!("x{}", c.value)).map_err(|_| {
            c.at.error(format!(
                "'{}' does not make usable coordinate names (x{0} ... roll{0}): a suffix holds only letters, digits, '_' and '.'",
                c.value
            ))
        })?;
    }
    Ok(b)
}

/// A body's `dof`: the axes (indices into [`AXES`]) its coordinates move along, ascending.
fn body_dof(f: &mut Fields) -> Result<Option<Located<Vec<usize>>>, FileError> {
    Ok(match f.strings("dof")? {
        None => None,
        Some(list) => {
            // "xyz" is short for ["x", "y", "z"]
            let names: Vec<String> = if list.value.len() == 1 && list.value[0] == "xyz" {
                vec!["x".into(), "y".into(), "z".into()]
            } else {
                list.value.clone()
            };
            let mut axes = Vec::new();
            for n in &names {
                let k = AXES.iter().position(|a| a == n).ok_or_else(|| {
                    list.at.error(format!(
                        "unknown degree of freedom '{n}' (x, y, z, yaw, pitch, roll)"
                    ))
                })?;
                if axes.contains(&k) {
                    return Err(list.at.error(format!("'{n}' given twice")));
                }
                axes.push(k);
            }
            axes.sort_unstable();
            Some(Located {
                value: axes,
                at: list.at,
            })
        }
    })
}

/// A body's `shape` table: a box or a cylinder, as it is drawn.
fn body_shape(f: &mut Fields) -> Result<Option<ShapeFile>, FileError> {
    Ok(match f.table("shape")? {
        None => None,
        Some(mut s) => {
            let kind = s
                .string("kind")?
                .ok_or_else(|| s.at.error("needs `kind` (box or cylinder)"))?;
            let shape = match kind.value.as_str() {
                "box" => ShapeFile::Box {
                    half_sizes: s
                        .exprs("half_sizes", Some(3))?
                        .ok_or_else(|| s.at.error("a box needs `half_sizes` = [hx, hy, hz] (m)"))?,
                },
                "cylinder" => {
                    let radius = s.required_expr("radius", "m")?;
                    let half_length = s.required_expr("half_length", "m")?;
                    let axis = match s.string("axis")? {
                        None => 2,
                        Some(a) => ["x", "y", "z"]
                            .iter()
                            .position(|n| *n == a.value)
                            .ok_or_else(|| a.at.error("axis must be x, y or z"))?,
                    };
                    ShapeFile::Cylinder {
                        radius,
                        half_length,
                        axis,
                    }
                }
                other => {
                    return Err(kind
                        .at
                        .error(format!("unknown shape '{other}' (box or cylinder)")));
                }
            };
            s.finish()?;
            Some(shape)
        }
    })
}

fn points(node: &Node, at: At) -> Result<Points, FileError> {
    let mut f = Fields::of(node, at.clone())?;
    let mut base = Vec::new();
    if let Some(one) = f.exprs("at", Some(3))? {
        base.push(one);
    }
    if let Some((list, list_at)) = f.node("points") {
        if !base.is_empty() {
            return Err(list_at.error("give `at` or `points`, not both"));
        }
        let Value::Array(items) = &list.value else {
            return Err(list_at.error("expected an array of [x, y, z] points"));
        };
        // counted before any point is read
        WIRES_PER_SET
            .check(items.len())
            .map_err(|e| list_at.error(e.to_string()))?;
        for (i, item) in items.iter().enumerate() {
            let item_at = At {
                origin: item.origin.clone(),
                path: format!("{}[{i}]", list_at.path),
            };
            base.push(expr_array(item, item_at, Some(3))?);
        }
    }
    if base.is_empty() {
        return Err(at.error("needs `at = [x, y, z]` or `points = [[x, y, z], ...]` (m)"));
    }
    let mirror = match f.strings("mirror")? {
        None => Vec::new(),
        Some(list) => mirror_axes(&list, base.len())?,
    };
    let p = Points {
        at,
        base,
        mirror,
        hinged: f.expr("hinged")?,
        direction: vector3(&mut f, "direction")?,
        angles: vector3(&mut f, "angles")?,
    };
    f.finish()?;
    Ok(p)
}

/// The axes of a `mirror` list (0 x, 1 y, 2 z), each given once, for `base` points: the
/// points they make counted before any is made.
fn mirror_axes(list: &Located<Vec<String>>, base: usize) -> Result<Vec<usize>, FileError> {
    // "xy" is short for ["x", "y"]
    let letters: Vec<String> = if list.value.len() == 1 && list.value[0].chars().count() > 1 {
        list.value[0].chars().map(String::from).collect()
    } else {
        list.value.clone()
    };
    let mut axes: Vec<usize> = Vec::with_capacity(3);
    for a in &letters {
        let axis = ["x", "y", "z"].iter().position(|n| n == a).ok_or_else(|| {
            list.at
                .error(format!("cannot mirror across '{a}' (x, y or z)"))
        })?;
        // a second mirror across an axis copies every point onto one already there: wires
        // (or springs) that coincide pair by pair, never what a file means
        if axes.contains(&axis) {
            return Err(list.at.error(format!(
                "'{a}' is given twice: mirroring across an axis again puts every point on one already there (mirror across each axis once)"
            )));
        }
        axes.push(axis);
    }
    // each mirror doubles the list
    let count = base.checked_mul(1 << axes.len());
    WIRES_PER_SET
        .check_counted(count)
        .map_err(|e| list.at.error(e.to_string()))?;
    Ok(axes)
}

fn names(f: &mut Fields, default: String) -> Result<Names, FileError> {
    let name = f.string("name")?;
    let list = f.strings("names")?;
    match (name, list) {
        (Some(n), Some(_)) => Err(n.at.error("give `name` or `names`, not both")),
        (Some(n), None) => Ok(Names::Prefix(n.value)),
        (None, Some(l)) => Ok(Names::List(l)),
        (None, None) => Ok(Names::Prefix(default)),
    }
}

fn blade_fields(f: &mut Fields) -> Result<BladeFields, FileError> {
    let form = match f.string("form")? {
        None => None,
        Some(s) => {
            let form = BladeForm::NAMES
                .iter()
                .find(|(n, _)| *n == s.value)
                .map(|(_, form)| *form)
                .ok_or_else(|| {
                    s.at.error(format!(
                        "unknown blade form '{}' (xtra-lite, lite, full or lateral)",
                        s.value
                    ))
                })?;
            Some(Located {
                value: form,
                at: s.at,
            })
        }
    };
    let fields = BladeFields {
        form,
        stiffness: f.expr("stiffness")?,
        tip_mass: f.expr("tip_mass")?,
        tip_inertia: f.expr("tip_inertia")?,
        transverse_stiffness: f.expr("transverse_stiffness")?,
        rotational_stiffness: f.expr("rotational_stiffness")?,
        lateral_stiffness: f.expr("lateral_stiffness")?,
        lateral_ratio: f.expr("lateral_ratio")?,
        material: f.string("material")?,
        tag: f.string("tag")?,
        thickness: f.expr("thickness")?,
        temperature: f.expr("temperature")?,
    };
    if let (Some(s), Some(_)) = (&fields.lateral_stiffness, &fields.lateral_ratio) {
        return Err(s
            .at
            .error("give lateral_stiffness or lateral_ratio, not both"));
    }
    Ok(fields)
}

fn stage(body: String, node: &Node, at: At) -> Result<StageFile, FileError> {
    let mut f = Fields::of(node, at.clone())?;
    let from = f
        .string("from")?
        .ok_or_else(|| at.error("needs `from`: the body this one hangs from"))?;
    let blades = match f.node("blades") {
        None => None,
        Some((node, at)) => {
            let mut b = Fields::of(node, at.clone())?;
            let names = names(&mut b, format!("{body}_"))?;
            let tips = match b.node("tips") {
                Some((n, tips_at)) => points(n, tips_at)?,
                None => return Err(at.error("needs `tips` (the tip positions on the upper body)")),
            };
            let fields = blade_fields(&mut b)?;
            b.finish()?;
            Some(BladeSet {
                at,
                names,
                tips,
                fields,
            })
        }
    };
    let mut sets = Vec::new();
    for slot in ["wires", "fibres"] {
        sets.push(match f.node(slot) {
            None => None,
            Some((node, at)) => Some(wire_set(slot, &body, node, at)?),
        });
    }
    let fibres = sets.pop().flatten();
    let wires = sets.pop().flatten();
    let springs = match f.node("springs") {
        None => None,
        Some((node, at)) => Some(spring_set(&body, node, at)?),
    };
    let link = match f.table("link")? {
        None => None,
        Some(mut l) => {
            let link = LinkFile {
                at: l.at.clone(),
                offset: vector3(&mut l, "offset")?
                    .ok_or_else(|| l.at.error("needs `offset = [x, y, z]` (m)"))?,
                angles: vector3(&mut l, "angles")?,
            };
            l.finish()?;
            Some(link)
        }
    };
    if let Some((_, at)) = f.node("dilution") {
        return Err(at.error(
            "a given dilution factor belongs to the stage's wires or fibres: `[stages.<body>.wires] dilution = ...`",
        ));
    }
    f.finish()?;
    if let Some(l) = &link
        && (blades.is_some() || wires.is_some() || fibres.is_some() || springs.is_some())
    {
        return Err(l.at.error(
            "a rigid link fixes the body to the one above: the stage can have no other parts",
        ));
    }
    if let Some(b) = &blades
        && wires.is_none()
        && fibres.is_none()
    {
        return Err(b.at.error("blades need wires hanging from their tips"));
    }
    Ok(StageFile {
        body,
        at,
        from,
        blades,
        wires,
        fibres,
        springs,
        link,
        scope: String::new(),
    })
}

fn wire_set(slot: &'static str, body: &str, node: &Node, at: At) -> Result<WireSet, FileError> {
    let mut f = Fields::of(node, at.clone())?;
    let singular = &slot[..slot.len() - 1];
    let names = names(&mut f, format!("{body}_{singular}"))?;
    let mut ends = Vec::new();
    for key in ["upper", "lower"] {
        ends.push(match f.node(key) {
            Some((n, end_at)) => points(n, end_at)?,
            None => return Err(at.error(format!("needs `{key}` attachment points"))),
        });
    }
    let lower = ends.pop().ok_or_else(|| at.error("needs `lower`"))?;
    let upper = ends.pop().ok_or_else(|| at.error("needs `upper`"))?;
    let section = match f.table("section")? {
        None => None,
        Some(mut s) => {
            let section = SectionFile {
                at: s.at.clone(),
                area: s.required_expr("area", "m^2")?,
                moments: [
                    s.required_expr("moment_1", "m^4")?,
                    s.required_expr("moment_2", "m^4")?,
                ],
                torsion_constant: s.required_expr("torsion_constant", "m^4")?,
                polar_moment: s.required_expr("polar_moment", "m^4")?,
                principal_axis: vector3(&mut s, "principal_axis")?,
            };
            s.finish()?;
            Some(section)
        }
    };
    let mut w = WireSet {
        slot,
        names,
        upper,
        lower,
        length: f.required_expr("length", "m, between the attachment points at equilibrium")?,
        radius: f.expr("radius")?,
        section,
        material: f.string("material")?,
        youngs_modulus: f.expr("youngs_modulus")?,
        shear_modulus: f.expr("shear_modulus")?,
        beads: f.expr("beads")?,
        bead_joints: BeadJoints::default(),
        tags: f.string("tags")?.unwrap_or_else(|| Located {
            value: format!("{body}_{slot}"),
            at: at.clone(),
        }),
        at: at.clone(),
        profile: match f.table("profile")? {
            None => None,
            Some(mut p) => {
                let profile = ProfileFile {
                    at: p.at.clone(),
                    neck_length: p.required_expr("neck_length", "m, the length of each neck")?,
                    neck_radius: p.required_expr("neck_radius", "m, the radius of the necks")?,
                };
                p.finish()?;
                Some(profile)
            }
        },
        surface_loss: f.bool("surface_loss")?.is_some_and(|b| b.value),
        temperature: f.expr("temperature")?,
        dilution: f.expr("dilution")?,
        continuum: f.bool("continuum")?.is_some_and(|b| b.value),
    };
    match (&w.radius, &w.section) {
        (Some(r), Some(_)) => return Err(r.at.error("give `radius` or `section`, not both")),
        (None, None) => return Err(at.error("needs `radius` (m) or a `section`")),
        _ => {}
    }
    if let (Some(p), None) = (&w.profile, &w.radius) {
        return Err(p
            .at
            .error("a profile needs `radius` (m, the middle's), not a `section`"));
    }
    if let (true, None) = (w.surface_loss, &w.radius) {
        return Err(at.error("surface loss needs a round section (`radius`)"));
    }
    if let Some((node, joints_at)) = f.node("bead_joints") {
        w.bead_joints = match &node.value {
            Value::Str(s) => BeadJoints::from_name(s),
            _ => None,
        }
        .ok_or_else(|| joints_at.error("expected \"clamped\" or \"hinged\""))?;
    }
    f.finish()?;
    Ok(w)
}

fn spring_set(body: &str, node: &Node, at: At) -> Result<SpringSet, FileError> {
    let mut f = Fields::of(node, at.clone())?;
    let names = names(&mut f, format!("{body}_spring"))?;
    let upper = f.node("upper").map(|(n, a)| points(n, a)).transpose()?;
    let lower = f.node("lower").map(|(n, a)| points(n, a)).transpose()?;
    let (stiffness, diagonal) = match f.node("stiffness") {
        None => return Err(at.error("needs `stiffness`: 6 diagonal entries or a 6x6 matrix")),
        Some((node, k_at)) => match &node.value {
            Value::Array(rows) if rows.iter().all(|r| matches!(r.value, Value::Array(_))) => {
                if rows.len() != 6 {
                    return Err(k_at.error(format!("expected 6 rows, got {}", rows.len())));
                }
                let rows = rows
                    .iter()
                    .enumerate()
                    .map(|(i, r)| {
                        let row_at = At {
                            origin: r.origin.clone(),
                            path: format!("{}[{i}]", k_at.path),
                        };
                        expr_array(r, row_at, Some(6)).map(|l| l.value)
                    })
                    .collect::<Result<_, _>>()?;
                (rows, false)
            }
            _ => (vec![expr_array(node, k_at, Some(6))?.value], true),
        },
    };
    let s = SpringSet {
        names,
        upper,
        lower,
        stiffness,
        diagonal,
        preload: f.exprs("preload", Some(6))?,
        tag: f.string("tag")?.unwrap_or_else(|| Located {
            value: format!("{body}_springs"),
            at: at.clone(),
        }),
        at,
    };
    f.finish()?;
    Ok(s)
}

fn damping(tag: String, node: &Node, at: At) -> Result<DampingFile, FileError> {
    let mut f = Fields::of(node, at.clone())?;
    let mut fields = Vec::new();
    for field in DAMPING_FIELDS {
        // `thermoelastic.delta` and `.tau`: read below, from one pair or one table
        if !field.name.contains('.')
            && let Some(ex) = f.expr(field.name)?
        {
            fields.push((field, ex));
        }
    }
    if let Some((node, te_at)) = f.node("thermoelastic") {
        let halves: Vec<Option<Ex>> = match &node.value {
            // `thermoelastic = [delta, tau]`
            Value::Array(_) => expr_array(node, te_at, Some(2))?
                .value
                .into_iter()
                .map(Some)
                .collect(),
            // `thermoelastic = { delta = ..., tau = ... }`, or the dotted keys
            // `thermoelastic.delta = ...` (the same table): what `fit --out` writes
            _ => {
                let mut pair = Fields::of(node, te_at)?;
                let halves = vec![pair.expr("delta")?, pair.expr("tau")?];
                pair.finish()?;
                halves
            }
        };
        for (name, ex) in ["thermoelastic.delta", "thermoelastic.tau"]
            .into_iter()
            .zip(halves)
        {
            if let (Some(field), Some(ex)) = (schema::find(DAMPING_FIELDS, name), ex) {
                fields.push((field, ex));
            }
        }
    }
    f.finish()?;
    Ok(DampingFile { tag, at, fields })
}

fn element(kind: String, node: &Node, at: At) -> Result<ElementChoice, FileError> {
    let stage = match &node.value {
        Value::Bool(true) => None,
        Value::Bool(false) => Some(None),
        Value::Str(s) => Some(Some(
            s.parse::<Stage>().map_err(|e| at.error(e.to_string()))?,
        )),
        other => {
            return Err(at.error(format!(
                "expected a stage (\"0a\" ... \"2\"), true (its own stage) or false (off), got {}",
                other.type_name()
            )));
        }
    };
    Ok(ElementChoice { kind, stage, at })
}

fn extra(name: String, node: &Node, at: At) -> Result<ExtraFile, FileError> {
    let mut f = Fields::of(node, at.clone())?;
    let energy = f.required_expr("energy", "J, an expression of coordinates and parameters")?;
    let tag = f
        .string("tag")?
        .map(|t| t.value)
        .unwrap_or_else(|| join("extra", &name).replace('.', "_"));
    let after_equilibrium = match f.string("phase")? {
        None => false,
        Some(p) => match p.value.as_str() {
            "before" => false,
            "after" => true,
            other => {
                return Err(p.at.error(format!(
                    "unknown phase '{other}' (before or after the equilibrium)"
                )));
            }
        },
    };
    f.finish()?;
    Ok(ExtraFile {
        name,
        energy,
        tag,
        after_equilibrium,
        at,
    })
}

/// `[[element]]`: the array of instance tables.
fn instances(node: &Node, at: At) -> Result<Vec<InstanceFile>, FileError> {
    let Value::Array(items) = &node.value else {
        return Err(at.error(format!(
            "expected an array of tables ([[element]]), got {}",
            node.value.type_name()
        )));
    };
    items
        .iter()
        .enumerate()
        .map(|(i, item)| instance(item, &at, i))
        .collect()
}

/// The `[[element]]` table `item`, the `i`-th of the array at `array`.
fn instance(item: &Node, array: &At, i: usize) -> Result<InstanceFile, FileError> {
    // every field of an instance is placed under its name (element.coil.values.k), which
    // the reader sees before it has read the table; one without a name keeps its index
    let name = match &item.value {
        Value::Table(t) => t.get("name").and_then(|n| match &n.value {
            Value::Str(s) if !s.is_empty() => Some(s.clone()),
            _ => None,
        }),
        _ => None,
    };
    let at = At {
        origin: item.origin.clone(),
        path: name.map_or_else(
            || format!("{}[{i}]", array.path),
            |n| format!("{}.{n}", array.path),
        ),
    };
    let mut f = Fields::of(item, at.clone())?;
    let kind = f.string("kind")?.ok_or_else(|| {
        at.error("needs `kind` (a registered element kind; `pendkit elements` lists them)")
    })?;
    let name = f
        .string("name")?
        .ok_or_else(|| at.error("needs `name` (the instance's name)"))?;
    if name.value.is_empty() {
        return Err(name.at.error("empty instance name"));
    }
    let between = f
        .strings("between")?
        .ok_or_else(|| at.error("needs `between` (the bodies it connects)"))?;
    let points = f
        .node("points")
        .map(|(n, a)| instance_points(n, a))
        .transpose()?;
    let (values, values_at) = match f.node("values") {
        None => (Vec::new(), at.clone()),
        Some((node, values_at)) => (instance_values(node, &values_at)?, values_at),
    };
    let tag = f.string("tag")?;
    f.finish()?;
    Ok(InstanceFile {
        kind,
        name: name.value,
        between,
        points,
        values,
        values_at,
        tag,
        at,
    })
}

/// An instance's `points`: an array of points, each three expressions (m).
fn instance_points(node: &Node, at: At) -> Result<Located<Vec<Located<Vec<Ex>>>>, FileError> {
    let Value::Array(items) = &node.value else {
        return Err(at.error(format!(
            "expected an array of points [[x, y, z], ...], got {}",
            node.value.type_name()
        )));
    };
    let value = items
        .iter()
        .enumerate()
        .map(|(k, p)| {
            let p_at = At {
                origin: p.origin.clone(),
                path: format!("{}[{k}]", at.path),
            };
            expr_array(p, p_at, Some(3))
        })
        .collect::<Result<_, _>>()?;
    Ok(Located { value, at })
}

/// An instance's `values`: a table of expressions, each name with its place.
fn instance_values(node: &Node, at: &At) -> Result<Vec<(Located<String>, Ex)>, FileError> {
    let Value::Table(table) = &node.value else {
        return Err(at.error(format!(
            "expected a table of values {{ name = expression, ... }}, got {}",
            node.value.type_name()
        )));
    };
    table
        .entries
        .iter()
        .map(|(key, key_origin, n)| {
            let v_at = at.child(key_origin.clone(), key);
            let name = Located {
                value: key.clone(),
                at: v_at.clone(),
            };
            Ok((name, Ex::read(n, v_at)?))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use pendkit_model::schema::MATERIAL_FIELDS;

    use super::*;

    /// A material's constants are named as the schema names them, in its order: the
    /// domain check of every constant (build.rs) finds each one's field.
    #[test]
    fn material_constants_are_the_schemas_fields() {
        let origin = crate::source::Origin {
            source: crate::source::Source::new("m.toml", None, ""),
            span: 0..0,
        };
        let at = At {
            origin,
            path: "materials.m".into(),
        };
        let m = MaterialSpec {
            name: "m".into(),
            at,
            youngs_modulus: None,
            shear_modulus: None,
            poisson_ratio: None,
            density: None,
            loss_angle: None,
            specific_heat: None,
            conductivity: None,
            thermal_expansion: None,
            dlne_dt: None,
            dissipation_depth: None,
        };
        let names: Vec<&str> = m.fields().iter().map(|(name, _)| *name).collect();
        let schema: Vec<&str> = MATERIAL_FIELDS.iter().map(|f| f.name).collect();
        assert_eq!(names, schema);
    }
}
