//! The numeric description of a suspension: coordinates, bodies, wires, springs and extra
//! terms, with every quantity in SI units. Built by `pendkit-model`; read by the energy terms.

use std::collections::BTreeMap;

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use num_dual::Dual64;
use pendkit_expr::Expr;
use pendkit_geometry::FrameMap;
use pendkit_rotations::Real;

use crate::{Damping, IndexError, Stage};

/// Index of a coordinate in [`System::coords`].
pub type CoordId = usize;
/// Index of a body in [`System::bodies`].
pub type BodyId = usize;

/// The three classes of coordinates of the source document (§3.1.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum CoordKind {
    /// Carries inertia through a body; a normal-mode coordinate (x).
    Variable,
    /// A massless junction between elastic elements, eliminated by Schur complement (q).
    Float,
    /// Externally driven (the support): fixed for modes, an input for transfer functions (s).
    Parameter,
}

/// One coordinate of the model (a length in m or an angle in rad).
#[derive(Clone, Debug)]
pub struct Coordinate {
    /// Name, e.g. `x1`, `pitch3`, `x00`.
    pub name: String,
    /// Variable, float or parameter.
    pub kind: CoordKind,
    /// Start of the equilibrium search for variables and floats; nominal value for
    /// parameters (m or rad).
    pub start: f64,
    /// Held at `start` during the equilibrium search (the source's `nonoptcoords`).
    pub pinned: bool,
}

/// A rigid body (or a massless frame such as the support).
#[derive(Clone, Debug)]
pub struct Body<S: Real = f64> {
    /// Name, e.g. `support`, `mass1`.
    pub name: String,
    /// How the body's frame follows the coordinates.
    pub frame: FrameMap,
    /// Mass (kg).
    pub mass: S,
    /// Inertia tensor about the centre of mass in body axes (kg m^2); products allowed.
    pub inertia: Matrix3<S>,
    /// Centre of mass in body coordinates (m); the origin unless the body says otherwise.
    pub centre_of_mass: Vector3<S>,
    /// The shape the body is drawn as (figures only: the physics uses mass and inertia).
    pub shape: Option<Shape>,
    /// For each pose entry (x, y, z, yaw, pitch, roll), the coordinate it is exactly equal
    /// to, if any: the body's own degrees of freedom, which give a coordinate its unit (m
    /// or rad) and its degree-of-freedom family.
    pub pose_coords: [Option<CoordId>; 6],
    /// A family that modes dominated by this body's coordinates belong to, instead of their
    /// degree of freedom (e.g. `violin` for the beads of a fibre).
    pub mode_family: Option<String>,
}

/// The drawing shape of a body, in body coordinates centred on the body origin (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    /// A box with these half-sizes along body x, y, z (m).
    Box {
        /// Half-sizes (m).
        half_sizes: Vector3<f64>,
    },
    /// A cylinder of `radius` (m) and half-length `half_length` (m) along body axis `axis`
    /// (0 = x, 1 = y, 2 = z).
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Half of the length (m).
        half_length: f64,
        /// The body axis the cylinder lies along (0, 1 or 2).
        axis: usize,
    },
}

impl Shape {
    /// The uniform box with this mass (kg) and principal moments (kg m²): half-sizes
    /// a_i = sqrt(3 (I_j + I_k − I_i) / (2 m)), from I_x = m (b² + c²) / 3 and its
    /// permutations. `None` for a massless body or one without rotational inertia (a point
    /// mass); a moment that no box can have (I_j + I_k < I_i) gives a zero half-size.
    pub fn equivalent_box(mass: f64, principal_moments: [f64; 3]) -> Option<Shape> {
        let [ix, iy, iz] = principal_moments;
        // written so that a NaN mass or moment also gives `None`
        if ![mass, ix, iy, iz].into_iter().all(|v| v > 0.0) {
            return None;
        }
        let half = |i: f64, j: f64, k: f64| (1.5 * (j + k - i) / mass).max(0.0).sqrt();
        Some(Shape::Box {
            half_sizes: Vector3::new(half(ix, iy, iz), half(iy, iz, ix), half(iz, ix, iy)),
        })
    }
}

/// How a wire leaves the body at one end.
#[derive(Clone, Debug, PartialEq)]
pub enum EndDirection<S: Real = f64> {
    /// Clamped along the direction that makes the wire straight at equilibrium.
    Auto,
    /// Clamped along this vector in body coordinates, pointing into the wire.
    Explicit(Vector3<S>),
    /// Free to pivot: no bending moment at this end.
    Hinged,
}

/// One end of a wire: a point on a body and how the wire leaves it.
#[derive(Clone, Debug)]
pub struct WireEnd<S: Real = f64> {
    /// The body the end is fixed to.
    pub body: BodyId,
    /// Attachment point in body coordinates (m).
    pub point: Vector3<S>,
    /// Clamp direction or hinge.
    pub direction: EndDirection<S>,
}

/// Elastic properties of a wire's cross-section, used by the plug-in wire elements.
#[derive(Clone, Debug)]
pub struct WireSection<S: Real = f64> {
    /// Young's modulus (Pa).
    pub youngs_modulus: S,
    /// Shear modulus (Pa).
    pub shear_modulus: S,
    /// Cross-sectional area (m^2).
    pub area: S,
    /// Second moment of area about the first principal axis (m^4).
    pub moment_1: S,
    /// Second moment of area about the second principal axis (m^4).
    pub moment_2: S,
    /// Direction of the first principal axis, in the coordinates of the body at end 1.
    pub principal_axis: Vector3<S>,
    /// Torsion constant J_e (m^4).
    pub torsion_constant: S,
    /// Polar moment of area J (m^4).
    pub polar_moment: S,
    /// Linear density (kg/m), for reporting and violin-mode models.
    pub linear_density: S,
}

impl<S: Real> WireSection<S> {
    /// A round wire of radius `r` (m) with Young's modulus `e` and shear modulus `g` (Pa)
    /// and density `rho` (kg/m^3): A = πr², I = πr⁴/4, J = J_e = πr⁴/2. A negative radius
    /// gives negative areas and moments (r² and r⁴ taken with the sign of r), so that the
    /// model builder refuses it instead of reading it as its absolute value.
    pub fn round(r: S, e: S, g: S, rho: S) -> Self {
        let pi = std::f64::consts::PI;
        let square = r * r.abs();
        let fourth = square * square.abs();
        WireSection {
            youngs_modulus: e,
            shear_modulus: g,
            area: square * pi,
            moment_1: fourth * (pi / 4.0),
            moment_2: fourth * (pi / 4.0),
            principal_axis: Vector3::new(S::from(1.0), S::from(0.0), S::from(0.0)),
            torsion_constant: fourth * (pi / 2.0),
            polar_moment: fourth * (pi / 2.0),
            linear_density: rho * pi * square,
        }
    }
}

/// Damping tag names of a wire's three kinds of elasticity.
#[derive(Clone, Debug)]
pub struct WireTags {
    /// Tag of the longitudinal stretch (and of the stage-2 extra stretch).
    pub stretch: String,
    /// Tag of bending.
    pub bending: String,
    /// Tag of torsion.
    pub torsion: String,
}

/// A massless wire between points on two bodies.
#[derive(Clone, Debug)]
pub struct Wire<S: Real = f64> {
    /// Name, e.g. `fibre1`.
    pub name: String,
    /// The two ends (end 0 is usually the upper one).
    pub ends: [WireEnd<S>; 2],
    /// Longitudinal stiffness k (N/m), a constant (E A / l_eq in the bundled models).
    pub stiffness: S,
    /// Unstretched length l0 (m).
    pub unstretched_length: S,
    /// Cross-section properties.
    pub section: WireSection<S>,
    /// The round pieces (length m, radius m) of a fibre whose radius changes along it, from
    /// end 0, when `section` is the effective section of such a profile (a tapered fibre);
    /// empty for a uniform wire. The static terms use `section` alone; a continuum fibre
    /// (`pendkit-element-continuum-fibre`) resolves the profile.
    pub profile: Vec<(S, S)>,
    /// Damping tags.
    pub tags: WireTags,
    /// Whether responses and noise take this wire as a continuum (its exact dynamic
    /// stiffness D(f), `pendkit-element-continuum-fibre`) unless told otherwise: a
    /// suspension file's `continuum = true` on the wire's set. The equilibrium, the modes
    /// and the state space use the static terms either way.
    pub continuum: bool,
}

impl<S: pendkit_rotations::Constant> Wire<S> {
    /// Whether any of the wire's numbers (its ends' points and explicit directions,
    /// stiffness, unstretched length, section) moves with the parameter
    /// ([`pendkit_rotations::Constant::moves`]).
    pub fn moves(&self) -> bool {
        let ends = self.ends.iter().any(|e| {
            e.point.iter().any(|v| v.moves())
                || matches!(&e.direction, EndDirection::Explicit(d) if d.iter().any(|v| v.moves()))
        });
        let s = &self.section;
        let section = [
            s.youngs_modulus,
            s.shear_modulus,
            s.area,
            s.moment_1,
            s.moment_2,
            s.torsion_constant,
            s.polar_moment,
            s.linear_density,
        ];
        let profile = self.profile.iter().any(|(l, r)| l.moves() || r.moves());
        ends || profile
            || self.stiffness.moves()
            || self.unstretched_length.moves()
            || section.iter().chain(&s.principal_axis).any(|v| v.moves())
    }
}

impl<S: Real> Wire<S> {
    /// A wire of equilibrium length `length` (m) carrying static tension `tension` (N):
    /// k = E A / length (the parameter sets' convention) and l0 = length − T / k.
    pub fn from_tension(
        name: impl Into<String>,
        ends: [WireEnd<S>; 2],
        section: WireSection<S>,
        length: S,
        tension: S,
        tags: WireTags,
    ) -> Self {
        let stiffness = section.youngs_modulus * section.area / length;
        // A non-positive length or stiffness is passed through as it is, so that the builder
        // reports a zero-length or zero-stiffness wire rather than an infinite length.
        let unstretched_length = if length.re() > 0.0 && stiffness.re() > 0.0 {
            length - tension / stiffness
        } else {
            length
        };
        Wire {
            name: name.into(),
            ends,
            stiffness,
            unstretched_length,
            section,
            profile: Vec::new(),
            tags,
            continuum: false,
        }
    }
}

/// One end of a spring: a point on a body and the fixed angles that turn the body's axes
/// into the spring's.
#[derive(Clone, Debug)]
pub struct SpringEnd<S: Real = f64> {
    /// The body the end is fixed to.
    pub body: BodyId,
    /// Attachment point in body coordinates (m).
    pub point: Vector3<S>,
    /// Attachment angles (yaw, pitch, roll) relative to the body axes (rad).
    pub angles: [S; 3],
}

/// A zero-length six-axis spring (blade, flexure, debugging constraint).
#[derive(Clone, Debug)]
pub struct Spring<S: Real = f64> {
    /// Name, e.g. `blade1`.
    pub name: String,
    /// The two ends; the relative pose of end 1 seen from end 0 is the spring's deflection.
    pub ends: [SpringEnd<S>; 2],
    /// Stiffness on (x, y, z, yaw, pitch, roll) deflection (N/m, N/rad, N m/m, N m/rad).
    pub stiffness: Matrix6<S>,
    /// Preload force/torque at zero deflection (N, N m), in the spring's axes.
    pub preload: Vector6<S>,
    /// Damping tag.
    pub tag: String,
}

/// When a user-written potential term joins the calculation (the source's
/// `preeqtermlist` / `posteqtermlist`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExtraPhase {
    /// Part of the potential that is minimised.
    BeforeEquilibrium,
    /// Added after the equilibrium is found; may use `<coordinate>.eq` symbols.
    AfterEquilibrium,
}

/// A user-written potential term (J) as an expression of the coordinates.
#[derive(Clone, Debug)]
pub struct ExtraTerm {
    /// Name for reports.
    pub name: String,
    /// Potential energy (J) as an expression of coordinate names (and `<name>.eq`).
    pub energy: Expr,
    /// Damping tag.
    pub tag: String,
    /// Before or after the equilibrium.
    pub phase: ExtraPhase,
}

/// An instance of an element kind that lives in a plug-in crate, described by data only.
#[derive(Clone, Debug)]
pub struct PluginElement<S: Real = f64> {
    /// Registered kind name, e.g. `viscous-spring`.
    pub kind: String,
    /// Instance name for reports.
    pub name: String,
    /// Bodies the element connects.
    pub bodies: Vec<BodyId>,
    /// Points on those bodies (m, body coordinates), one per body.
    pub points: Vec<Vector3<S>>,
    /// Named numbers (SI units documented by the kind).
    pub values: BTreeMap<String, S>,
    /// Damping tag.
    pub tag: String,
}

/// Whether plug-in wire terms join the equilibrium search (the source's `wiretermsearly`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum EarlyWireTerms {
    /// Plug-in terms are added after the equilibrium (the default).
    #[default]
    No,
    /// Plug-in terms join the equilibrium and the stage-0A matrices.
    Yes,
    /// Plug-in terms join the equilibrium only.
    EquilibriumOnly,
}

/// One term of a [`NamedSignal`]: a coordinate, or a point on a body along a lab direction.
#[derive(Clone, Debug, PartialEq)]
pub enum SignalTerm {
    /// A coordinate (m or rad).
    Coordinate(CoordId),
    /// A point on a body (m, body coordinates) and a lab direction (unit vector): the
    /// point's displacement along it, or a force there along it, through the linearised
    /// geometry at the equilibrium.
    Point {
        /// The body.
        body: BodyId,
        /// The point (m, body coordinates).
        point: Vector3<f64>,
        /// The direction (lab axes, normalised).
        direction: Vector3<f64>,
    },
}

/// A named input or output of a model: a linear combination of coordinates and points (an
/// interferometer's beam spot, a sensor, an actuator), e.g. `0.999 x3 + 0.045 z3`.
#[derive(Clone, Debug, PartialEq)]
pub struct NamedSignal {
    /// The name used on the command line (`--input`, `--output`).
    pub name: String,
    /// A force (on variables or points for an input; on the support parameters for an
    /// output) rather than a displacement.
    pub force: bool,
    /// Coefficient (dimensionless) and term.
    pub terms: Vec<(f64, SignalTerm)>,
}

/// A complete numeric model.
#[derive(Clone, Debug)]
pub struct System<S: Real = f64> {
    /// All coordinates: variables, floats and parameters.
    pub coords: Vec<Coordinate>,
    /// All bodies, massive or not.
    pub bodies: Vec<Body<S>>,
    /// All wires.
    pub wires: Vec<Wire<S>>,
    /// All springs.
    pub springs: Vec<Spring<S>>,
    /// User-written extra potential terms.
    pub extra_terms: Vec<ExtraTerm>,
    /// Instances of plug-in element kinds.
    pub plugin_elements: Vec<PluginElement<S>>,
    /// Gravitational acceleration g (m/s^2), acting along -z.
    pub gravity: S,
    /// Per-coordinate stiffness to the equilibrium (N/m or N m/rad), for debugging; zero
    /// entries add nothing.
    pub constraint_stiffness: BTreeMap<CoordId, f64>,
    /// Whether plug-in wire terms join the equilibrium.
    pub early_wire_terms: EarlyWireTerms,
    /// Complex multipliers of the damping tags.
    pub damping: Damping,
    /// Temperature for thermal noise (K).
    pub temperature: f64,
    /// Element kinds moved to another stage (`Some`) or switched off (`None`); a kind not
    /// listed joins at its own stage (`pendkit_energy::Element::stage`).
    pub element_stages: BTreeMap<String, Option<Stage>>,
    /// Named inputs (displacements of parameters, forces on variables or points).
    pub inputs: Vec<NamedSignal>,
    /// Named outputs (displacements of variables or points, forces on the support).
    pub outputs: Vec<NamedSignal>,
    /// Other names for the model's bodies and coordinates, by scheme (e.g. `ligo`).
    pub name_schemes: BTreeMap<String, NameScheme>,
}

/// Another set of names for some of a model's bodies and coordinates, declared by the model
/// (e.g. LIGO's: the test mass `L3`, its pitch `L3_P`). Names not in the scheme stay as
/// they are.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NameScheme {
    /// Body name to its name in the scheme.
    pub bodies: BTreeMap<String, String>,
    /// Coordinate name to its name in the scheme.
    pub coords: BTreeMap<String, String>,
}

impl NameScheme {
    /// The scheme's name of coordinate `name`, or `name` itself.
    pub fn coord<'a>(&'a self, name: &'a str) -> &'a str {
        self.coords.get(name).map_or(name, String::as_str)
    }

    /// The scheme's name of body `name`, or `name` itself.
    pub fn body<'a>(&'a self, name: &'a str) -> &'a str {
        self.bodies.get(name).map_or(name, String::as_str)
    }

    /// The coordinate that the scheme calls `alias`, if any.
    pub fn coord_called(&self, alias: &str) -> Option<&str> {
        self.coords
            .iter()
            .find(|(_, a)| *a == alias)
            .map(|(name, _)| name.as_str())
    }

    /// The body that the scheme calls `alias`, if any.
    pub fn body_called(&self, alias: &str) -> Option<&str> {
        self.bodies
            .iter()
            .find(|(_, a)| *a == alias)
            .map(|(name, _)| name.as_str())
    }
}

impl<S: Real> System<S> {
    /// Every index the system holds is in range: each body's frame reads only coordinates
    /// of [`System::coords`], and every wire, spring, plug-in element, constraint and
    /// named signal refers to an existing body or coordinate. The model builder guarantees
    /// this; the assembly checks it once at each entry for systems put together by hand, so
    /// that what follows indexes without checks.
    pub fn check_indices(&self) -> Result<(), IndexError> {
        let (n_coords, n_bodies) = (self.coords.len(), self.bodies.len());
        let out_of_range = |item: String, what: &'static str, index: usize, len: usize| {
            Err(IndexError {
                item,
                what,
                index,
                len,
            })
        };
        for body in &self.bodies {
            if body.frame.needs() > n_coords {
                return out_of_range(
                    format!("body '{}' (its pose)", body.name),
                    "coordinate",
                    body.frame.needs() - 1,
                    n_coords,
                );
            }
        }
        // (what, its name, a body it refers to); the item's label is written only for an
        // error (this runs at every entry of the assembly, once per parameter and more)
        let bodies = self
            .wires
            .iter()
            .flat_map(|w| w.ends.iter().map(move |e| ("wire", &w.name, e.body)))
            .chain(
                self.springs
                    .iter()
                    .flat_map(|s| s.ends.iter().map(move |e| ("spring", &s.name, e.body))),
            )
            .chain(
                self.plugin_elements
                    .iter()
                    .flat_map(|p| p.bodies.iter().map(move |&b| ("element", &p.name, b))),
            );
        for (what, name, b) in bodies {
            if b >= n_bodies {
                return out_of_range(format!("{what} '{name}'"), "body", b, n_bodies);
            }
        }
        if let Some((&c, _)) = self.constraint_stiffness.range(n_coords..).next() {
            return out_of_range("constraint".into(), "coordinate", c, n_coords);
        }
        for signal in self.inputs.iter().chain(&self.outputs) {
            for (_, term) in &signal.terms {
                let (what, index, len) = match term {
                    SignalTerm::Coordinate(c) => ("coordinate", *c, n_coords),
                    SignalTerm::Point { body, .. } => ("body", *body, n_bodies),
                };
                if index >= len {
                    return out_of_range(format!("signal '{}'", signal.name), what, index, len);
                }
            }
        }
        Ok(())
    }

    /// Index of the coordinate called `name`.
    pub fn coord(&self, name: &str) -> Option<CoordId> {
        self.coords.iter().position(|c| c.name == name)
    }

    /// Index of the body called `name`.
    pub fn body(&self, name: &str) -> Option<BodyId> {
        self.bodies.iter().position(|b| b.name == name)
    }

    /// Start (or nominal) values of all coordinates.
    pub fn start(&self) -> Vec<f64> {
        self.coords.iter().map(|c| c.start).collect()
    }

    /// Every damping tag the model's terms can carry.
    pub fn tags(&self) -> std::collections::BTreeSet<String> {
        let mut tags: std::collections::BTreeSet<String> = self
            .wires
            .iter()
            .flat_map(|w| [&w.tags.stretch, &w.tags.bending, &w.tags.torsion])
            .chain(self.springs.iter().map(|s| &s.tag))
            .chain(self.extra_terms.iter().map(|t| &t.tag))
            .chain(self.plugin_elements.iter().map(|e| &e.tag))
            .cloned()
            .collect();
        tags.insert(crate::GRAVITY_TAG.to_string());
        tags.insert(crate::CONSTRAINT_TAG.to_string());
        tags
    }

    /// The stage at which the terms of the element kind called `kind` join this model, or
    /// `None` if it is switched off; `own` is the kind's own stage, used unless the model
    /// moved it.
    pub fn element_stage(&self, kind: &str, own: Stage) -> Option<Stage> {
        match self.element_stages.get(kind) {
            Some(choice) => *choice,
            None => Some(own),
        }
    }

    /// Indices of the coordinates of one kind, in definition order.
    pub fn coords_of(&self, kind: CoordKind) -> Vec<CoordId> {
        (0..self.coords.len())
            .filter(|&i| self.coords[i].kind == kind)
            .collect()
    }
}

impl System {
    /// A support and free rigid bodies, each with its own six coordinates (x, y, z, yaw,
    /// pitch, roll, suffixed by the body's index: `x0` … `roll0` are the support's and are
    /// parameters, the others variables), every frame at the lab's root, each `(name, mass
    /// in kg)` with unit inertia (kg m²) and its centre of mass at its origin, g = 9.81 m/s²
    /// and nothing connecting them: the smallest system on which to try an element kind or
    /// a term (add its wires, springs or instances to it).
    pub fn free_bodies(bodies: &[(&str, f64)]) -> Result<System, pendkit_expr::ExprError> {
        const AXES: [&str; 6] = ["x", "y", "z", "yaw", "pitch", "roll"];
        let coords = (0..bodies.len())
            .flat_map(|k| AXES.map(|axis| format!("{axis}{k}")))
            .enumerate()
            .map(|(i, name)| Coordinate {
                name,
                kind: if i < 6 {
                    CoordKind::Parameter
                } else {
                    CoordKind::Variable
                },
                start: 0.0,
                pinned: false,
            })
            .collect();
        let mut built = Vec::with_capacity(bodies.len());
        for (k, &(name, mass)) in bodies.iter().enumerate() {
            // pose entry m is coordinate 6k + m itself
            let [x, y, z, yaw, pitch, roll] = std::array::from_fn(|m| {
                Expr::Sym(AXES[m].into()).compile(&|_| Some(pendkit_expr::Slot::Var(6 * k + m)))
            });
            let entries = [x?, y?, z?, yaw?, pitch?, roll?];
            built.push(Body {
                name: name.into(),
                frame: FrameMap::root(pendkit_geometry::PoseMap { entries }),
                mass,
                inertia: Matrix3::identity(),
                centre_of_mass: Vector3::zeros(),
                shape: None,
                pose_coords: std::array::from_fn(|m| Some(6 * k + m)),
                mode_family: None,
            });
        }
        Ok(System {
            coords,
            bodies: built,
            gravity: 9.81,
            ..System::default()
        })
    }
}

impl<S: Real> Default for System<S> {
    fn default() -> Self {
        System {
            coords: Vec::new(),
            bodies: Vec::new(),
            wires: Vec::new(),
            springs: Vec::new(),
            extra_terms: Vec::new(),
            plugin_elements: Vec::new(),
            gravity: S::from(0.0),
            constraint_stiffness: BTreeMap::new(),
            early_wire_terms: EarlyWireTerms::default(),
            damping: Damping::default(),
            temperature: 0.0,
            element_stages: BTreeMap::new(),
            inputs: Vec::new(),
            outputs: Vec::new(),
            name_schemes: BTreeMap::new(),
        }
    }
}

/// Applies one map to every generic number of a [`System`], in the visiting order of
/// [`System::map_scalars`].
struct Visit<F>(F);

impl<F> Visit<F> {
    fn one<S: Real, T: Real>(&mut self, x: S) -> T
    where
        F: FnMut(S) -> T,
    {
        (self.0)(x)
    }
    fn vector3<S: Real, T: Real>(&mut self, v: &Vector3<S>) -> Vector3<T>
    where
        F: FnMut(S) -> T,
    {
        Vector3::from_iterator(v.iter().map(|&x| (self.0)(x)))
    }
    fn matrix3<S: Real, T: Real>(&mut self, m: &Matrix3<S>) -> Matrix3<T>
    where
        F: FnMut(S) -> T,
    {
        Matrix3::from_iterator(m.iter().map(|&x| (self.0)(x)))
    }
    fn vector6<S: Real, T: Real>(&mut self, v: &Vector6<S>) -> Vector6<T>
    where
        F: FnMut(S) -> T,
    {
        Vector6::from_iterator(v.iter().map(|&x| (self.0)(x)))
    }
    fn matrix6<S: Real, T: Real>(&mut self, m: &Matrix6<S>) -> Matrix6<T>
    where
        F: FnMut(S) -> T,
    {
        Matrix6::from_iterator(m.iter().map(|&x| (self.0)(x)))
    }
}

/// The model numbers of a [`System`] that are generic over the scalar — the ones a
/// dual-number build differentiates — in one fixed order: gravity; each body's mass,
/// inertia (column-major) and centre of mass; each wire's end points and explicit end
/// directions (end 0, then end 1), stiffness, unstretched length and section (Young's
/// modulus, shear modulus, area, the two moments of area, principal axis, torsion constant,
/// polar moment, linear density); each spring's end points and angles, stiffness
/// (column-major) and preload; each plug-in element's points and values (in name order).
/// Everything else (names, coordinates and their start values, frames, shapes, extra terms,
/// damping, temperature, signals) is copied as it is.
impl<S: Real> System<S> {
    /// The same model with every generic number mapped by `f`, visited in the order above.
    #[expect(
        clippy::too_many_lines,
        reason = "visits every generic number in the one order documented above, which \
                  `zip_scalars_into` must repeat; one body keeps that order checkable line by line"
    )]
    pub fn map_scalars<T: Real>(&self, f: impl FnMut(S) -> T) -> System<T> {
        let mut v = Visit(f);
        let gravity = v.one(self.gravity);
        let bodies = self
            .bodies
            .iter()
            .map(|b| Body {
                name: b.name.clone(),
                frame: b.frame.clone(),
                mass: v.one(b.mass),
                inertia: v.matrix3(&b.inertia),
                centre_of_mass: v.vector3(&b.centre_of_mass),
                shape: b.shape,
                pose_coords: b.pose_coords,
                mode_family: b.mode_family.clone(),
            })
            .collect();
        let wires = self
            .wires
            .iter()
            .map(|w| {
                let ends = w.ends.each_ref().map(|e| WireEnd {
                    body: e.body,
                    point: v.vector3(&e.point),
                    direction: match &e.direction {
                        EndDirection::Auto => EndDirection::Auto,
                        EndDirection::Explicit(d) => EndDirection::Explicit(v.vector3(d)),
                        EndDirection::Hinged => EndDirection::Hinged,
                    },
                });
                let stiffness = v.one(w.stiffness);
                let unstretched_length = v.one(w.unstretched_length);
                let s = &w.section;
                let section = WireSection {
                    youngs_modulus: v.one(s.youngs_modulus),
                    shear_modulus: v.one(s.shear_modulus),
                    area: v.one(s.area),
                    moment_1: v.one(s.moment_1),
                    moment_2: v.one(s.moment_2),
                    principal_axis: v.vector3(&s.principal_axis),
                    torsion_constant: v.one(s.torsion_constant),
                    polar_moment: v.one(s.polar_moment),
                    linear_density: v.one(s.linear_density),
                };
                Wire {
                    name: w.name.clone(),
                    ends,
                    stiffness,
                    unstretched_length,
                    section,
                    profile: w
                        .profile
                        .iter()
                        .map(|&(l, r)| (v.one(l), v.one(r)))
                        .collect(),
                    tags: w.tags.clone(),
                    continuum: w.continuum,
                }
            })
            .collect();
        let springs = self
            .springs
            .iter()
            .map(|sp| {
                let ends = sp.ends.each_ref().map(|e| SpringEnd {
                    body: e.body,
                    point: v.vector3(&e.point),
                    angles: e.angles.map(|a| v.one(a)),
                });
                Spring {
                    name: sp.name.clone(),
                    ends,
                    stiffness: v.matrix6(&sp.stiffness),
                    preload: v.vector6(&sp.preload),
                    tag: sp.tag.clone(),
                }
            })
            .collect();
        let plugin_elements = self
            .plugin_elements
            .iter()
            .map(|p| PluginElement {
                kind: p.kind.clone(),
                name: p.name.clone(),
                bodies: p.bodies.clone(),
                points: p.points.iter().map(|x| v.vector3(x)).collect(),
                values: p
                    .values
                    .iter()
                    .map(|(k, &x)| (k.clone(), v.one(x)))
                    .collect(),
                tag: p.tag.clone(),
            })
            .collect();
        System {
            coords: self.coords.clone(),
            bodies,
            wires,
            springs,
            extra_terms: self.extra_terms.clone(),
            plugin_elements,
            gravity,
            constraint_stiffness: self.constraint_stiffness.clone(),
            early_wire_terms: self.early_wire_terms,
            damping: self.damping.clone(),
            temperature: self.temperature,
            element_stages: self.element_stages.clone(),
            inputs: self.inputs.clone(),
            outputs: self.outputs.clone(),
            name_schemes: self.name_schemes.clone(),
        }
    }

    /// `f(x, y)` for each generic number x of this model and the number y in the same
    /// place of `target`, in the order of [`System::map_scalars`]: for rewriting a model's
    /// numbers without copying the rest of it (names, frames, signals). False, with
    /// `target` partly rewritten, when the two models do not have the same numbers (a count
    /// or an end's kind of direction differs).
    pub fn zip_scalars_into<T: Real>(
        &self,
        target: &mut System<T>,
        mut f: impl FnMut(&S, &mut T),
    ) -> bool {
        // the numbers of two fixed-size vectors or matrices, pairwise
        fn each<'a, 'b, S: 'a, T: 'b>(
            from: impl IntoIterator<Item = &'a S>,
            to: impl IntoIterator<Item = &'b mut T>,
            f: &mut impl FnMut(&S, &mut T),
        ) {
            from.into_iter().zip(to).for_each(|(x, y)| f(x, y));
        }
        let same = self.bodies.len() == target.bodies.len()
            && self.wires.len() == target.wires.len()
            && self.springs.len() == target.springs.len()
            && self.plugin_elements.len() == target.plugin_elements.len();
        if !same {
            return false;
        }
        f(&self.gravity, &mut target.gravity);
        for (a, b) in self.bodies.iter().zip(&mut target.bodies) {
            f(&a.mass, &mut b.mass);
            each(&a.inertia, &mut b.inertia, &mut f);
            each(&a.centre_of_mass, &mut b.centre_of_mass, &mut f);
        }
        for (a, b) in self.wires.iter().zip(&mut target.wires) {
            for (ea, eb) in a.ends.iter().zip(&mut b.ends) {
                each(&ea.point, &mut eb.point, &mut f);
                match (&ea.direction, &mut eb.direction) {
                    (EndDirection::Explicit(da), EndDirection::Explicit(db)) => {
                        each(da, db, &mut f)
                    }
                    (EndDirection::Auto, EndDirection::Auto)
                    | (EndDirection::Hinged, EndDirection::Hinged) => {}
                    _ => return false,
                }
            }
            f(&a.stiffness, &mut b.stiffness);
            f(&a.unstretched_length, &mut b.unstretched_length);
            let (sa, sb) = (&a.section, &mut b.section);
            f(&sa.youngs_modulus, &mut sb.youngs_modulus);
            f(&sa.shear_modulus, &mut sb.shear_modulus);
            f(&sa.area, &mut sb.area);
            f(&sa.moment_1, &mut sb.moment_1);
            f(&sa.moment_2, &mut sb.moment_2);
            each(&sa.principal_axis, &mut sb.principal_axis, &mut f);
            f(&sa.torsion_constant, &mut sb.torsion_constant);
            f(&sa.polar_moment, &mut sb.polar_moment);
            f(&sa.linear_density, &mut sb.linear_density);
            if a.profile.len() != b.profile.len() {
                return false;
            }
            for ((la, ra), (lb, rb)) in a.profile.iter().zip(&mut b.profile) {
                f(la, lb);
                f(ra, rb);
            }
        }
        for (a, b) in self.springs.iter().zip(&mut target.springs) {
            for (ea, eb) in a.ends.iter().zip(&mut b.ends) {
                each(&ea.point, &mut eb.point, &mut f);
                each(&ea.angles, &mut eb.angles, &mut f);
            }
            each(&a.stiffness, &mut b.stiffness, &mut f);
            each(&a.preload, &mut b.preload, &mut f);
        }
        for (a, b) in self.plugin_elements.iter().zip(&mut target.plugin_elements) {
            let same = a.points.len() == b.points.len()
                && a.values.len() == b.values.len()
                && a.values.keys().eq(b.values.keys());
            if !same {
                return false;
            }
            for (pa, pb) in a.points.iter().zip(&mut b.points) {
                each(pa, pb, &mut f);
            }
            each(a.values.values(), b.values.values_mut(), &mut f);
        }
        true
    }

    /// The model's generic numbers, in the order of [`System::map_scalars`].
    pub fn scalars(&self) -> Vec<S> {
        let mut out = Vec::new();
        self.map_scalars(|x| {
            out.push(x);
            x
        });
        out
    }

    /// The `f64` model: the real part of every number.
    pub fn value(&self) -> System<f64> {
        self.map_scalars(|x| x.re())
    }
}

impl System<Dual64> {
    /// The derivative of every generic number with respect to the seeded direction, in the
    /// order of [`System::map_scalars`] (units: the number's unit per unit of the seed).
    pub fn tangent(&self) -> Vec<f64> {
        self.scalars().into_iter().map(|x| x.eps).collect()
    }

    /// The `f64` model moved along the exact tangent: every number x + step·dx (`step` in
    /// the seed's unit).
    pub fn stepped(&self, step: f64) -> System<f64> {
        self.map_scalars(|x| x.re + step * x.eps)
    }
}
