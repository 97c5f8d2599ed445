//! The model builder: a named, validated library API that turns coordinates, bodies, wires,
//! springs and extra terms into a [`System`], and the [`Model`] trait through which bundled
//! and downstream models offer default parameters and a build function.
//!
//! Every quantity is in SI units: lengths in m, angles in rad, masses in kg, inertias in
//! kg m^2, stiffnesses in N/m (or N m/rad), forces in N, moduli in Pa. The builder is
//! generic over the scalar of the model numbers (`SystemBuilder<S = f64>`): built with
//! dual numbers, every number it derives carries its exact derivative (the checks read the
//! real parts and say the same as for `f64`).

pub mod beads;
mod damping;
mod fibre;
pub mod losses;
pub mod schema;

use std::collections::{BTreeMap, HashMap, HashSet};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use num_dual::Dual64;
use pendkit_expr::{ExprError, Slot, number_text};
use pendkit_geometry::{FrameMap, PoseMap};
use pendkit_params::{ChunkDual, ParamError, ParamSet, Resolved, Tangent};
use pendkit_system::Real;
use pendkit_system::{
    Body, BodyId, CoordId, CoordKind, Coordinate, EarlyWireTerms, EndDirection, ExtraPhase,
    ExtraTerm, NamedSignal, PluginElement, SignalTerm, Spring, SpringEnd, Stage, System, Wire,
};

pub use damping::{DampingSpec, ParsedDamping};
pub use fibre::{FibreProfile, fibre_inverse_radius};
pub use pendkit_system::Shape;

/// Errors in a model definition; each names the item and what is wrong with it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BuildError {
    /// Two items of one kind with the same name.
    #[error("duplicate {what} name '{name}'")]
    Duplicate {
        /// "coordinate", "body", "wire", ...
        what: &'static str,
        /// The repeated name.
        name: String,
    },
    /// A name that does not refer to anything defined.
    #[error("{context}: unknown {what} '{name}'")]
    Unknown {
        /// Where the name was used.
        context: String,
        /// "coordinate", "body", ...
        what: &'static str,
        /// The name.
        name: String,
    },
    /// An expression that does not parse or compile.
    #[error("{context}: {message}")]
    Expression {
        /// Where the expression was used.
        context: String,
        /// The parser's message.
        message: String,
    },
    /// A physically impossible value.
    #[error("{item}: {message}")]
    Invalid {
        /// The item, e.g. `body 'mass1'`.
        item: String,
        /// What is wrong, with the value and its unit.
        message: String,
    },
    /// A parameter problem while building from a parameter set.
    #[error(transparent)]
    Parameter(#[from] ParamError),
}

/// A body to add: name, pose expressions, mass properties.
#[derive(Clone, Debug)]
pub struct BodySpec<S: Real = f64> {
    name: String,
    parent: Option<BodyId>,
    pose: [String; 6],
    mass: S,
    inertia: Matrix3<S>,
    centre_of_mass: Vector3<S>,
    shape: Option<Shape>,
    mode_family: Option<String>,
}

/// LIGO's names of the six pose entries (x, y, z, yaw, pitch, roll): length L, transverse
/// T, vertical V, yaw Y, pitch P, roll R; for [`SystemBuilder::name_scheme`].
pub const LIGO_DOF_NAMES: [&str; 6] = ["L", "T", "V", "Y", "P", "R"];

impl<S: Real> BodySpec<S> {
    /// A massless body fixed at the lab origin; set its pose and mass properties next.
    pub fn new(name: impl Into<String>) -> Self {
        BodySpec {
            name: name.into(),
            parent: None,
            pose: std::array::from_fn(|_| "0".to_string()),
            mass: S::from(0.0),
            inertia: Matrix3::from_element(S::from(0.0)),
            centre_of_mass: Vector3::from_element(S::from(0.0)),
            shape: None,
            mode_family: None,
        }
    }

    /// The shape the body is drawn as in figures (it does not enter the physics). Without
    /// one, a body with mass and inertia is drawn as the uniform box of the same mass and
    /// principal moments ([`Shape::equivalent_box`]).
    pub fn shape(mut self, shape: Shape) -> Self {
        self.shape = Some(shape);
        self
    }

    /// Modes dominated by this body's coordinates belong to `family` (e.g. `violin` for a
    /// fibre's beads) rather than to their degree of freedom.
    pub fn mode_family(mut self, family: impl Into<String>) -> Self {
        self.mode_family = Some(family.into());
        self
    }

    /// Pose (x, y, z in m; yaw, pitch, roll in rad) as expressions of coordinate names.
    pub fn pose(mut self, pose: [&str; 6]) -> Self {
        self.pose = pose.map(str::to_string);
        self
    }

    /// The six pose coordinates `x<s> y<s> z<s> yaw<s> pitch<s> roll<s>`.
    pub fn pose_suffix(mut self, suffix: &str) -> Self {
        self.pose = ["x", "y", "z", "yaw", "pitch", "roll"].map(|n| format!("{n}{suffix}"));
        self
    }

    /// Pose relative to another body's frame instead of the lab.
    pub fn on(mut self, parent: BodyId) -> Self {
        self.parent = Some(parent);
        self
    }

    /// Mass (kg).
    pub fn mass(mut self, mass: S) -> Self {
        self.mass = mass;
        self
    }

    /// Full inertia tensor about the centre of mass in body axes (kg m^2).
    pub fn inertia(mut self, inertia: Matrix3<S>) -> Self {
        self.inertia = inertia;
        self
    }

    /// Principal moments about the body x, y, z axes (kg m^2).
    pub fn inertia_diag(self, ix: S, iy: S, iz: S) -> Self {
        let zero = S::from(0.0);
        self.inertia(Matrix3::new(ix, zero, zero, zero, iy, zero, zero, zero, iz))
    }

    /// Centre of mass in body coordinates (m), if it is not the body origin.
    pub fn centre_of_mass(mut self, com: Vector3<S>) -> Self {
        self.centre_of_mass = com;
        self
    }
}

/// Builds a [`System`] from named parts, checking each as it is added.
#[derive(Debug)]
pub struct SystemBuilder<S: Real = f64> {
    system: System<S>,
    /// Names already used, so that lookups and duplicate checks do not scan the lists
    /// (a 100-stage chain has 600 coordinates and 400 wires).
    coord_ids: HashMap<String, CoordId>,
    body_ids: HashMap<String, BodyId>,
    wire_names: HashSet<String>,
    spring_names: HashSet<String>,
}

/// `item` is formatted only for the error.
fn check_finite(
    item: impl std::fmt::Display,
    what: &str,
    value: f64,
    unit: &str,
) -> Result<(), BuildError> {
    if value.is_finite() {
        Ok(())
    } else {
        Err(BuildError::Invalid {
            item: item.to_string(),
            message: format!(
                "{what} is not a finite number ({}{}{unit})",
                number_text(value),
                if unit.is_empty() { "" } else { " " }
            ),
        })
    }
}

impl<S: Real> Default for SystemBuilder<S> {
    fn default() -> Self {
        SystemBuilder {
            system: System::default(),
            coord_ids: HashMap::new(),
            body_ids: HashMap::new(),
            wire_names: HashSet::new(),
            spring_names: HashSet::new(),
        }
    }
}

impl<S: Real> SystemBuilder<S> {
    /// An empty model with gravitational acceleration `g` (m/s^2) along -z.
    pub fn new(g: S) -> Self {
        let mut b = SystemBuilder::default();
        b.system.gravity = g;
        b
    }

    fn coordinate(
        &mut self,
        name: &str,
        kind: CoordKind,
        start: f64,
    ) -> Result<CoordId, BuildError> {
        if self.coord_ids.contains_key(name) {
            return Err(BuildError::Duplicate {
                what: "coordinate",
                name: name.to_string(),
            });
        }
        check_coordinate_name(name)?;
        // counted as they come, so that a model past the limit stops growing at it
        pendkit_limits::COORDINATES
            .check(self.system.coords.len() + 1)
            .map_err(|e| BuildError::Invalid {
                item: format!("coordinate '{name}'"),
                message: e.to_string(),
            })?;
        check_finite(
            format_args!("coordinate '{name}'"),
            "start value",
            start,
            "",
        )?;
        self.coord_ids
            .insert(name.to_string(), self.system.coords.len());
        self.system.coords.push(Coordinate {
            name: name.to_string(),
            kind,
            start,
            pinned: false,
        });
        Ok(self.system.coords.len() - 1)
    }

    /// A variable (carries inertia) starting the equilibrium search at `start` (m or rad).
    pub fn variable(&mut self, name: &str, start: f64) -> Result<CoordId, BuildError> {
        self.coordinate(name, CoordKind::Variable, start)
    }

    /// A float (massless junction) starting at `start` (m or rad).
    pub fn float(&mut self, name: &str, start: f64) -> Result<CoordId, BuildError> {
        self.coordinate(name, CoordKind::Float, start)
    }

    /// A parameter (externally driven, e.g. the support) at its nominal value (m or rad).
    pub fn parameter(&mut self, name: &str, nominal: f64) -> Result<CoordId, BuildError> {
        self.coordinate(name, CoordKind::Parameter, nominal)
    }

    /// The six support parameters `x00 ... roll00` at zero.
    pub fn support_parameters(&mut self) -> Result<(), BuildError> {
        for n in ["x00", "y00", "z00", "yaw00", "pitch00", "roll00"] {
            self.parameter(n, 0.0)?;
        }
        Ok(())
    }

    fn coord_id(&self, context: &str, name: &str) -> Result<CoordId, BuildError> {
        self.coord_ids
            .get(name)
            .copied()
            .ok_or_else(|| BuildError::Unknown {
                context: context.to_string(),
                what: "coordinate",
                name: name.to_string(),
            })
    }

    /// The index and class of the coordinate called `name`, if it is defined.
    pub fn find_coordinate(&self, name: &str) -> Option<(CoordId, CoordKind)> {
        let id = *self.coord_ids.get(name)?;
        Some((id, self.system.coords[id].kind))
    }

    /// Holds a variable or float at its start value during the equilibrium search.
    pub fn pin(&mut self, name: &str) -> Result<(), BuildError> {
        let i = self.coord_id("pin", name)?;
        self.system.coords[i].pinned = true;
        Ok(())
    }

    /// A stiffness (N/m or N m/rad) tying a coordinate to its equilibrium, for debugging.
    pub fn constraint_stiffness(&mut self, name: &str, k: f64) -> Result<(), BuildError> {
        let i = self.coord_id("constraint stiffness", name)?;
        check_finite(
            format_args!("constraint on '{name}'"),
            "stiffness",
            k,
            "N/m",
        )?;
        self.system.constraint_stiffness.insert(i, k);
        Ok(())
    }

    /// Whether plug-in wire terms join the equilibrium search.
    pub fn early_wire_terms(&mut self, mode: EarlyWireTerms) {
        self.system.early_wire_terms = mode;
    }

    /// Index of a body by name.
    pub fn body_id(&self, name: &str) -> Option<BodyId> {
        self.body_ids.get(name).copied()
    }

    /// Adds a body, checking its pose expressions and mass properties.
    pub fn body(&mut self, spec: BodySpec<S>) -> Result<BodyId, BuildError> {
        check_body_name(&spec.name)?;
        let item = format!("body '{}'", spec.name);
        if self.body_ids.contains_key(&spec.name) {
            return Err(BuildError::Duplicate {
                what: "body",
                name: spec.name,
            });
        }
        pendkit_limits::BODIES
            .check(self.system.bodies.len() + 1)
            .map_err(|e| BuildError::Invalid {
                item: item.clone(),
                message: e.to_string(),
            })?;
        // every check reads the real part: the derivatives follow the same model
        let mass = spec.mass.re();
        check_finite(&item, "mass", mass, "kg")?;
        if mass < 0.0 {
            return Err(BuildError::Invalid {
                item,
                message: format!("negative mass ({} kg)", number_text(mass)),
            });
        }
        let inertia = spec.inertia.map(|v| v.re());
        check_inertia(&item, &inertia)?;
        if let Some(shape) = &spec.shape {
            check_shape(&item, shape)?;
        }
        let shape = spec.shape.or_else(|| {
            let moments = inertia.symmetric_eigenvalues();
            Shape::equivalent_box(mass, [moments[0], moments[1], moments[2]])
        });
        let pose_coords = spec
            .pose
            .each_ref()
            .map(|text| self.coord_ids.get(text.trim()).copied());
        let labels = ["x", "y", "z", "yaw", "pitch", "roll"];
        let mut entries = Vec::with_capacity(6);
        for (text, label) in spec.pose.iter().zip(labels) {
            // formatted only for an error: a build adds hundreds of pose entries
            let context = || format!("{item} pose {label}");
            let expr = pendkit_expr::parse(text).map_err(|e| BuildError::Expression {
                context: context(),
                message: e.to_string(),
            })?;
            let slot = |s: &str| self.coord_ids.get(s).copied().map(Slot::Var);
            entries.push(expr.compile(&slot).map_err(|e| match e {
                ExprError::UnknownSymbol { name } => BuildError::Unknown {
                    context: context(),
                    what: "coordinate",
                    name,
                },
                e => BuildError::Expression {
                    context: context(),
                    message: e.to_string(),
                },
            })?);
        }
        let pose = PoseMap {
            entries: entries.try_into().map_err(|_| BuildError::Invalid {
                item: item.clone(),
                message: "pose needs six entries".into(),
            })?,
        };
        let frame = match spec.parent {
            None => FrameMap::root(pose),
            Some(p) => self
                .system
                .bodies
                .get(p)
                .ok_or_else(|| BuildError::Invalid {
                    item: item.clone(),
                    message: format!("parent body index {p} does not exist"),
                })?
                .frame
                .child(pose),
        };
        self.body_ids
            .insert(spec.name.clone(), self.system.bodies.len());
        self.system.bodies.push(Body {
            name: spec.name,
            frame,
            mass: spec.mass,
            inertia: spec.inertia,
            centre_of_mass: spec.centre_of_mass,
            shape,
            pose_coords,
            mode_family: spec.mode_family,
        });
        Ok(self.system.bodies.len() - 1)
    }

    fn check_end_body(&self, item: &str, body: BodyId) -> Result<(), BuildError> {
        if body < self.system.bodies.len() {
            Ok(())
        } else {
            Err(BuildError::Invalid {
                item: item.to_string(),
                message: format!("body index {body} does not exist"),
            })
        }
    }

    /// Adds a wire, checking its length, stiffness and section.
    pub fn wire(&mut self, spec: Wire<S>) -> Result<usize, BuildError> {
        let item = format!("wire '{}'", spec.name);
        if self.wire_names.contains(&spec.name) {
            return Err(BuildError::Duplicate {
                what: "wire",
                name: spec.name,
            });
        }
        pendkit_limits::WIRES
            .check(self.system.wires.len() + 1)
            .map_err(|e| BuildError::Invalid {
                item: item.clone(),
                message: e.to_string(),
            })?;
        for end in &spec.ends {
            self.check_end_body(&item, end.body)?;
            if let EndDirection::Explicit(v) = &end.direction
                && (v.map(|x| x.re()).norm().is_nan() || v.map(|x| x.re()).norm() <= 0.0)
            {
                return Err(BuildError::Invalid {
                    item,
                    message: "explicit end direction is a zero vector".into(),
                });
            }
        }
        let (unstretched_length, stiffness) = (spec.unstretched_length.re(), spec.stiffness.re());
        check_finite(&item, "unstretched length", unstretched_length, "m")?;
        if unstretched_length <= 0.0 {
            return Err(BuildError::Invalid {
                item,
                message: if unstretched_length < 0.0 {
                    // l0 = l − T/k below 0: the load stretches the wire by more than its
                    // length, which no wire does (a wrong load, stiffness or length)
                    format!(
                        "unstretched length {} m is negative: its tension would stretch it by more than its length (check the load it carries, its stiffness and its length)",
                        number_text(unstretched_length)
                    )
                } else {
                    "zero-length wire: unstretched length 0 m must be positive".into()
                },
            });
        }
        check_finite(&item, "stiffness", stiffness, "N/m")?;
        if stiffness <= 0.0 {
            return Err(BuildError::Invalid {
                item,
                message: format!(
                    "stiffness {} N/m must be positive (check the wire's radius, Young's modulus and length)",
                    number_text(stiffness)
                ),
            });
        }
        let s = &spec.section;
        for (what, v) in [
            ("Young's modulus", s.youngs_modulus),
            ("shear modulus", s.shear_modulus),
            ("area", s.area),
            ("moment of area 1", s.moment_1),
            ("moment of area 2", s.moment_2),
            ("torsion constant", s.torsion_constant),
            ("polar moment", s.polar_moment),
            ("linear density", s.linear_density),
        ] {
            let v = v.re();
            check_finite(&item, what, v, "")?;
            // a wire needs material and a section; bending and torsion may be absent
            let must_be_positive = matches!(what, "Young's modulus" | "area");
            if v < 0.0 || (must_be_positive && v == 0.0) {
                return Err(BuildError::Invalid {
                    item,
                    message: format!(
                        "{what} is {} ({}): wire sizes (radius, thickness) and material constants must be positive",
                        if v < 0.0 { "negative" } else { "zero" },
                        number_text(v)
                    ),
                });
            }
        }
        self.wire_names.insert(spec.name.clone());
        self.system.wires.push(spec);
        Ok(self.system.wires.len() - 1)
    }

    /// Adds a six-axis spring with stiffness `k` and preload `f` in the spring's axes.
    pub fn spring(
        &mut self,
        name: &str,
        ends: [SpringEnd<S>; 2],
        k: Matrix6<S>,
        f: Vector6<S>,
        tag: &str,
    ) -> Result<usize, BuildError> {
        let item = format!("spring '{name}'");
        if self.spring_names.contains(name) {
            return Err(BuildError::Duplicate {
                what: "spring",
                name: name.to_string(),
            });
        }
        for end in &ends {
            self.check_end_body(&item, end.body)?;
        }
        if k.iter().chain(f.iter()).any(|v| !v.re().is_finite()) {
            return Err(BuildError::Invalid {
                item,
                message: "stiffness or preload is not finite".into(),
            });
        }
        let k_value = k.map(|v| v.re());
        if (k_value - k_value.transpose()).abs().max() > 1e-12 * k_value.abs().max() {
            return Err(BuildError::Invalid {
                item,
                message: "stiffness matrix is not symmetric".into(),
            });
        }
        self.spring_names.insert(name.to_string());
        self.system.springs.push(Spring {
            name: name.to_string(),
            ends,
            stiffness: k,
            preload: f,
            tag: tag.to_string(),
        });
        Ok(self.system.springs.len() - 1)
    }

    /// A user-written potential term (J) as an expression of coordinate names; after the
    /// equilibrium, `<coordinate>.eq` names the equilibrium value.
    pub fn extra_term(
        &mut self,
        name: &str,
        energy: &str,
        tag: &str,
        phase: ExtraPhase,
    ) -> Result<(), BuildError> {
        let context = format!("extra term '{name}'");
        let expr = pendkit_expr::parse(energy).map_err(|e| BuildError::Expression {
            context: context.clone(),
            message: e.to_string(),
        })?;
        for s in expr.symbols() {
            let base = s
                .strip_suffix(".eq")
                .filter(|_| phase == ExtraPhase::AfterEquilibrium);
            if !self.coord_ids.contains_key(base.unwrap_or(&s)) {
                return Err(BuildError::Unknown {
                    context,
                    what: "coordinate",
                    name: s,
                });
            }
        }
        self.system.extra_terms.push(ExtraTerm {
            name: name.to_string(),
            energy: expr,
            tag: tag.to_string(),
            phase,
        });
        Ok(())
    }

    /// An instance of a plug-in element kind (checked against the registry at assembly).
    pub fn plugin_element(&mut self, element: PluginElement<S>) -> Result<(), BuildError> {
        let item = format!("element '{}'", element.name);
        for &b in &element.bodies {
            self.check_end_body(&item, b)?;
        }
        // one point per body, or none for a kind that reads none (its schema says which)
        if !element.points.is_empty() && element.points.len() != element.bodies.len() {
            return Err(BuildError::Invalid {
                item,
                message: "needs one point per body, or none".into(),
            });
        }
        self.system.plugin_elements.push(element);
        Ok(())
    }

    /// Moves the element kind `kind` to `stage`, or switches it off (`None`); whether the
    /// kind is registered is checked at assembly.
    pub fn element_stage(&mut self, kind: &str, stage: Option<Stage>) {
        self.system.element_stages.insert(kind.to_string(), stage);
    }

    /// Adds a named input (`output = false`) or output, checking that its terms fit: a
    /// displacement input combines parameters and points the support alone moves, a force
    /// input variables, floats and points, a displacement output variables, floats and
    /// points, a force output (on the support) parameters.
    pub fn named_signal(&mut self, signal: NamedSignal, output: bool) -> Result<(), BuildError> {
        let what = if output { "output" } else { "input" };
        let item = format!("{what} '{}'", signal.name);
        let list = if output {
            &self.system.outputs
        } else {
            &self.system.inputs
        };
        if list.iter().any(|s| s.name == signal.name) {
            return Err(BuildError::Duplicate {
                what,
                name: signal.name,
            });
        }
        if signal
            .terms
            .iter()
            .all(|(coefficient, _)| *coefficient == 0.0)
        {
            return Err(BuildError::Invalid {
                item,
                message: "combines nothing (no term, or every coefficient zero)".into(),
            });
        }
        // parameters are driven (displacement inputs, support forces), variables respond
        let wanted = if output == signal.force {
            CoordKind::Parameter
        } else {
            CoordKind::Variable
        };
        for (coefficient, term) in &signal.terms {
            check_finite(&item, "coefficient", *coefficient, "")?;
            match term {
                SignalTerm::Coordinate(c) => {
                    let coordinate =
                        self.system
                            .coords
                            .get(*c)
                            .ok_or_else(|| BuildError::Invalid {
                                item: item.clone(),
                                message: format!("coordinate index {c} does not exist"),
                            })?;
                    // a float (such as a blade tip's height) responds as a variable does
                    let responds = |k: CoordKind| k == CoordKind::Variable || k == CoordKind::Float;
                    let fits = coordinate.kind == wanted
                        || (wanted == CoordKind::Variable && responds(coordinate.kind));
                    if !fits {
                        return Err(BuildError::Invalid {
                            item,
                            message: format!(
                                "'{}' is a {:?}; this {what} combines {}s",
                                coordinate.name,
                                coordinate.kind,
                                format!("{wanted:?}").to_lowercase()
                            ),
                        });
                    }
                }
                SignalTerm::Point {
                    body, direction, ..
                } => {
                    self.check_end_body(&item, *body)?;
                    // a driven point must be one the support alone moves: checked at the
                    // equilibrium, where its motion is known
                    if output && signal.force {
                        return Err(BuildError::Invalid {
                            item,
                            message: "a point on a body cannot carry the support force".into(),
                        });
                    }
                    if !(direction.norm() > 0.0 && direction.norm().is_finite()) {
                        return Err(BuildError::Invalid {
                            item,
                            message: "direction is a zero or non-finite vector".into(),
                        });
                    }
                }
            }
        }
        if output {
            self.system.outputs.push(signal);
        } else {
            self.system.inputs.push(signal);
        }
        Ok(())
    }

    /// Declares names of the scheme `scheme` (e.g. `ligo`): each `(body, alias)` pair names
    /// a body, and each of its own pose coordinates becomes `<alias>_<dof>` with `dof` taken
    /// from `dof_names` in pose order (x, y, z, yaw, pitch, roll); e.g. [`LIGO_DOF_NAMES`]
    /// gives the test mass's pitch `L3_P`. Declaring a scheme again adds to it.
    pub fn name_scheme(
        &mut self,
        scheme: &str,
        dof_names: [&str; 6],
        bodies: &[(&str, &str)],
    ) -> Result<(), BuildError> {
        let mut names = self.system.name_schemes.remove(scheme).unwrap_or_default();
        for &(body, alias) in bodies {
            // an alias is addressed as the body is (`L3@x,y,z/dx,dy,dz`)
            check_body_name(alias)?;
            let id = self
                .body_ids
                .get(body)
                .copied()
                .ok_or_else(|| BuildError::Unknown {
                    context: format!("name scheme '{scheme}'"),
                    what: "body",
                    name: body.to_string(),
                })?;
            names.bodies.insert(body.to_string(), alias.to_string());
            for (coord, dof) in self.system.bodies[id].pose_coords.iter().zip(dof_names) {
                if let Some(c) = coord {
                    let name = self.system.coords[*c].name.clone();
                    names.coords.insert(name, format!("{alias}_{dof}"));
                }
            }
        }
        let mut seen = HashSet::new();
        for alias in names.coords.values().chain(names.bodies.values()) {
            if !seen.insert(alias.as_str()) {
                return Err(BuildError::Duplicate {
                    what: "name-scheme",
                    name: alias.clone(),
                });
            }
        }
        self.system.name_schemes.insert(scheme.to_string(), names);
        Ok(())
    }

    /// The finished model.
    pub fn build(self) -> Result<System<S>, BuildError> {
        check_finite("model", "gravity", self.system.gravity.re(), "m/s^2")?;
        // an empty file, or one whose bodies are all driven, has nothing to compute
        if !self
            .system
            .coords
            .iter()
            .any(|c| c.kind == CoordKind::Variable)
        {
            return Err(BuildError::Invalid {
                item: "model".into(),
                message: "no variables (no body with mass moves): nothing to compute".into(),
            });
        }
        check_inertia_ratios(&self.system.bodies)?;
        Ok(self.system)
    }
}

/// Largest ratio of the heaviest to the lightest body mass, and of the largest to the
/// smallest principal moment of inertia, that a model may have.
///
/// The mass matrix of the modes holds every mass and moment side by side, and a symmetric
/// eigensolver resolves its eigenvalues to about ε·(largest/smallest) relative (ε = 2.2e-16,
/// the spacing of doubles at 1): at a ratio of 1e12 that is 2e-4, already coarse; past
/// 1/ε ≈ 4.5e15 the light body's modes carry no correct digit and a verdict such as
/// "neutral" or "stable" read from them would be noise. Massless bodies (frames, blade
/// tips posed by floats) and point masses (no rotational inertia) take no part.
pub const MAX_INERTIA_RATIO: f64 = 1e12;

/// Refuses bodies whose masses (or principal moments of inertia) span more than
/// [`MAX_INERTIA_RATIO`], naming the lightest and the heaviest body and the ratio.
fn check_inertia_ratios<S: Real>(bodies: &[Body<S>]) -> Result<(), BuildError> {
    // (value, body) of the smallest and largest positive entry
    type Extremes<'a> = Option<((f64, &'a str), (f64, &'a str))>;
    fn widen<'a>(range: &mut Extremes<'a>, value: f64, body: &'a str) {
        if value > 0.0 {
            let (low, high) = range.get_or_insert(((value, body), (value, body)));
            if value < low.0 {
                *low = (value, body);
            }
            if value > high.0 {
                *high = (value, body);
            }
        }
    }
    let (mut masses, mut moments): (Extremes, Extremes) = (None, None);
    for body in bodies {
        widen(&mut masses, body.mass.re(), &body.name);
        let inertia = body.inertia.map(|v| v.re());
        if inertia.abs().max() > 0.0 {
            for m in inertia.symmetric_eigenvalues().iter() {
                widen(&mut moments, *m, &body.name);
            }
        }
    }
    for (range, what, unit) in [
        (masses, "mass", "kg"),
        (moments, "principal moment of inertia", "kg m^2"),
    ] {
        let Some(((low, light), (high, heavy))) = range else {
            continue;
        };
        let ratio = high / low;
        if ratio > MAX_INERTIA_RATIO {
            return Err(BuildError::Invalid {
                item: format!("body '{light}'"),
                message: format!(
                    "{what} {low:.3e} {unit} is {ratio:.1e} times smaller than the \
                     {high:.3e} {unit} of body '{heavy}': beyond the ratio \
                     {MAX_INERTIA_RATIO:.0e} that double precision resolves in the modes \
                     (relative errors of about 2.2e-16 x ratio)"
                ),
            });
        }
    }
    Ok(())
}

/// Shear modulus G = E / (2 (1 + ν)) (Pa) from Young's modulus `youngs_modulus` (Pa) and
/// Poisson's ratio `poisson_ratio`, which must lie in (-1, 0.5) for an isotropic solid (G
/// and the bulk modulus positive); `item` names where it is read, for the error.
pub fn shear_modulus<S: Real>(
    item: &str,
    youngs_modulus: S,
    poisson_ratio: S,
) -> Result<S, BuildError> {
    let nu = poisson_ratio.re();
    if nu > -1.0 && nu < 0.5 {
        Ok(youngs_modulus / ((poisson_ratio + 1.0) * 2.0))
    } else {
        Err(BuildError::Invalid {
            item: item.to_string(),
            message: format!(
                "Poisson's ratio {} must lie in (-1, 0.5) for an isotropic material",
                number_text(nu)
            ),
        })
    }
}

/// A 0-or-1 switch parameter (`hinged_bottom`): anything else is an error naming it, not
/// silently read as "on".
pub fn switch(params: &Resolved, name: &str) -> Result<bool, BuildError> {
    match params.get(name)? {
        0.0 => Ok(false),
        1.0 => Ok(true),
        other => Err(BuildError::Invalid {
            item: format!("parameter '{name}'"),
            message: format!("must be 0 (off) or 1 (on), got {other}"),
        }),
    }
}

/// The value of parameter `name` as a whole number in `range` (a count: stages, beads), or
/// a one-line error naming the parameter, the range and the value.
pub fn whole_number(
    params: &Resolved,
    name: &str,
    range: std::ops::RangeInclusive<usize>,
) -> Result<usize, BuildError> {
    let value = params.get(name)?;
    let (low, high) = (*range.start(), *range.end());
    if value.fract() == 0.0 && value >= low as f64 && value <= high as f64 {
        Ok(value as usize)
    } else {
        Err(BuildError::Invalid {
            item: format!("parameter '{name}'"),
            message: format!(
                "must be a whole number from {low} to {high}, got {}",
                number_text(value)
            ),
        })
    }
}

/// A drawing shape must have finite, non-negative sizes and a cylinder axis 0, 1 or 2.
fn check_shape(item: &str, shape: &Shape) -> Result<(), BuildError> {
    let (sizes, axis_ok) = match shape {
        Shape::Box { half_sizes } => (vec![half_sizes.x, half_sizes.y, half_sizes.z], true),
        Shape::Cylinder {
            radius,
            half_length,
            axis,
        } => (vec![*radius, *half_length], *axis < 3),
    };
    if sizes.iter().any(|v| !(v.is_finite() && *v >= 0.0)) || !axis_ok {
        return Err(BuildError::Invalid {
            item: item.to_string(),
            message: format!(
                "drawing shape needs finite sizes >= 0 m and a cylinder axis 0, 1 or 2 ({shape:?})"
            ),
        });
    }
    Ok(())
}

/// Inertia must be symmetric and either zero (a point mass) or positive definite.
/// Relative tolerance of the triangle inequality of principal moments of inertia
/// ([`check_inertia`]): the largest may exceed the sum of the other two by this fraction of
/// itself. A thin plate has I₃ = I₁ + I₂ exactly, and moments written with six significant
/// digits (C's `%g`, a spreadsheet's default) can break that equality by up to 1.5e-6 of
/// I₃; 1e-5 keeps them, while the mistakes the check is for (a moment mistyped or swapped,
/// m r² written for every axis of a disc) break it by percents.
pub const INERTIA_TRIANGLE_TOLERANCE: f64 = 1e-5;

/// Checks an inertia tensor (kg m², about the centre of mass) of the body `item` names:
/// finite, symmetric, positive definite (or zero: a point mass), and its principal moments
/// satisfying the triangle inequality I_a ≤ I_b + I_c for every order (within
/// [`INERTIA_TRIANGLE_TOLERANCE`]), which every rigid body's do: I_a + I_b − I_c = 2 ∫ ρ c²
/// dV ≥ 0, c the coordinate along the third axis. One line naming the body, the moments and
/// their unit otherwise.
pub fn check_inertia(item: &str, inertia: &Matrix3<f64>) -> Result<(), BuildError> {
    if inertia.iter().any(|v| !v.is_finite()) {
        return Err(BuildError::Invalid {
            item: item.to_string(),
            message: "inertia is not finite".into(),
        });
    }
    let scale = inertia.abs().max();
    if scale == 0.0 {
        return Ok(());
    }
    if (inertia - inertia.transpose()).abs().max() > 1e-12 * scale {
        return Err(BuildError::Invalid {
            item: item.to_string(),
            message: "inertia tensor is not symmetric".into(),
        });
    }
    // a diagonal tensor (how files write most bodies) is its own principal moments: no
    // eigen-solve in a build that the sensitivities repeat for every parameter
    let off_diagonal = inertia[(0, 1)] != 0.0 || inertia[(0, 2)] != 0.0 || inertia[(1, 2)] != 0.0;
    let moments = if off_diagonal {
        inertia.symmetric_eigenvalues()
    } else {
        inertia.diagonal()
    };
    if moments.iter().any(|&m| m <= 0.0) {
        return Err(BuildError::Invalid {
            item: item.to_string(),
            message: format!(
                "inertia tensor is not positive definite (principal moments {:.6e}, {:.6e}, {:.6e} kg m^2)",
                moments[0], moments[1], moments[2]
            ),
        });
    }
    let mut m = [moments[0], moments[1], moments[2]];
    m.sort_by(f64::total_cmp);
    if m[2] - (m[0] + m[1]) > INERTIA_TRIANGLE_TOLERANCE * m[2] {
        return Err(BuildError::Invalid {
            item: item.to_string(),
            message: format!(
                "principal moments of inertia {}, {}, {} kg m^2 break the triangle inequality: {} > {} + {} (no rigid body has one moment larger than the other two together; a thin plate has them equal)",
                number_text(m[0]),
                number_text(m[1]),
                number_text(m[2]),
                number_text(m[2]),
                number_text(m[0]),
                number_text(m[1])
            ),
        });
    }
    Ok(())
}

/// A body's name (or a naming scheme's alias of one) must be one a point signal,
/// `<body>@x,y,z/dx,dy,dz`, can address: not empty, without `@` (which ends the body's
/// name), `:` (the `force:` prefix, and `--tf IN:OUT`), surrounding spaces (a file's
/// signals are trimmed) or control characters (errors are one line).
pub fn check_body_name(name: &str) -> Result<(), BuildError> {
    let why = if name.is_empty() {
        "a body needs a name"
    } else if name.contains('@') {
        "'@' ends a body's name in a point signal (<body>@x,y,z/dx,dy,dz), so no signal could address it"
    } else if name.contains(':') {
        "':' separates `force:` and `--tf IN:OUT` from the name, so no signal could address it"
    } else if name.trim() != name {
        "spaces around it are trimmed from a point signal's body, so no signal could address it"
    } else if name.chars().any(char::is_control) {
        "it holds a control character"
    } else {
        return Ok(());
    };
    Err(BuildError::Invalid {
        item: format!("body name {name:?}"),
        message: why.into(),
    })
}

/// A coordinate's name must be one an expression can hold (a signal `0.5*x3 + z3`, an
/// extra term, a pose): a letter or `_`, then letters, digits, `_` or `.`, and neither `pi`
/// nor a function's name ([`pendkit_expr::is_symbol_name`]).
pub fn check_coordinate_name(name: &str) -> Result<(), BuildError> {
    if pendkit_expr::is_symbol_name(name) {
        return Ok(());
    }
    Err(BuildError::Invalid {
        item: format!("coordinate name {name:?}"),
        message: "signals and expressions write coordinates by name, so it must start with a letter or '_' and hold only letters, digits, '_' and '.' (and be neither pi nor a function's name)".into(),
    })
}

/// A model: default parameters and a function that builds a [`System`] from resolved
/// parameter values. Bundled models implement it; so can a downstream tool.
pub trait Model: Send + Sync {
    /// Name used on the command line, e.g. `pendulum`.
    fn name(&self) -> &str;
    /// One line describing the model.
    fn summary(&self) -> &str;
    /// Default parameter definitions.
    fn parameters(&self) -> Result<ParamSet, ParamError>;
    /// Default damping per tag (expressions over the parameters).
    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        BTreeMap::new()
    }
    /// [`Model::damping`] parsed ([`DampingSpec::parse`]); a model that parsed it already
    /// (to check it when it was read, as suspension files do) hands out its copy instead of
    /// parsing it again.
    fn parsed_damping(&self) -> Result<BTreeMap<String, ParsedDamping>, BuildError> {
        self.damping()
            .into_iter()
            .map(|(tag, spec)| Ok((tag.clone(), spec.parse(&tag)?)))
            .collect()
    }
    /// Builds the numeric model from resolved parameters.
    fn build(&self, params: &Resolved) -> Result<System, BuildError>;
    /// Builds the model with dual numbers seeded in the directions of up to
    /// [`pendkit_params::TANGENT_CHUNK`] parameters at once (`tangent`, resolved from the
    /// same set as `params`): every model number with its exact derivatives with respect to
    /// them (docs/exact-sensitivities.md). A derivative the build cannot carry (a number
    /// that becomes a count, a switch or the text of an expression) is listed in
    /// [`ChunkBuild::lost`] rather than failing the build, so the chunk's other parameters
    /// keep theirs. The default says the model offers none; suspension files do.
    fn build_tangents(
        &self,
        params: &Resolved,
        tangent: &Tangent<ChunkDual>,
    ) -> Result<ChunkBuild, BuildError> {
        let _ = (params, tangent);
        Err(BuildError::Invalid {
            item: format!("model '{}'", self.name()),
            message: "offers no exact derivatives of its build".into(),
        })
    }
    /// Where this model keeps its parsed [`Defaults`] from one build to the next, if it
    /// does (a `DefaultsCache` of its own, e.g. in a `static`). A model that returns one
    /// promises that [`Model::parameters`] and [`Model::damping`] always give the same
    /// result. The default, `None`, parses them again at every build.
    fn defaults_cache(&self) -> Option<&DefaultsCache> {
        None
    }
    /// Unit, description and readers of each parameter at the values `params` (what
    /// `pendkit params` lists). The default knows only the names; a model that records which
    /// of its parts read which parameter (suspension files do) says more.
    fn parameter_info(&self, params: &Resolved) -> Result<Vec<ParameterInfo>, BuildError> {
        Ok(params
            .iter()
            .map(|(name, _)| ParameterInfo {
                name: name.to_string(),
                ..ParameterInfo::default()
            })
            .collect())
    }
}

/// What a model says about one of its parameters.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParameterInfo {
    /// The parameter's name.
    pub name: String,
    /// Its unit as the model writes it (`kg`, `m`, `N/m`, `-`), empty if not given.
    pub unit: String,
    /// What it is, empty if not given.
    pub description: String,
    /// The fields of the model that read it (`bodies.top.mass`,
    /// `stages.uim.wires.length`, `damping.fibre_bending`), in the order first read.
    pub read_by: Vec<String>,
}

/// Inside an `impl Model for T`, defines [`Model::defaults_cache`] to return a
/// [`DefaultsCache`] of its own (a `static` in the function, so one per `impl`): for a type
/// with a single instance, such as a unit struct. Types with several instances keep a
/// `DefaultsCache` field instead.
#[macro_export]
macro_rules! defaults_cache_per_impl {
    () => {
        fn defaults_cache(&self) -> Option<&$crate::DefaultsCache> {
            static CACHE: $crate::DefaultsCache = $crate::DefaultsCache::new();
            Some(&CACHE)
        }
    };
}

/// Default temperature for thermal noise (K) when a model does not define `temperature`.
pub const DEFAULT_TEMPERATURE: f64 = 290.0;

/// What a model's builds share, whatever the overrides: its default parameters, parsed
/// (with `temperature` and `wire_terms_early` added when the model does not define them),
/// and its default damping per tag, parsed.
#[derive(Debug)]
pub struct Defaults {
    /// The model's name.
    pub model: String,
    /// Default parameters; cloning them is cheap (see [`ParamSet`]).
    pub params: ParamSet,
    /// Default damping per tag.
    pub damping: BTreeMap<String, ParsedDamping>,
}

impl Defaults {
    /// Parses `model`'s defaults (without looking at its cache).
    pub fn parse(model: &dyn Model) -> Result<Defaults, BuildError> {
        let mut params = model.parameters()?;
        if !params.contains("temperature") {
            params.define_value("temperature", DEFAULT_TEMPERATURE)?;
            params.set_unit("temperature", "K")?;
        }
        if !params.contains("wire_terms_early") {
            params.define_value("wire_terms_early", 0.0)?;
            params.set_unit("wire_terms_early", "")?;
        }
        let damping = model.parsed_damping()?;
        Ok(Defaults {
            model: model.name().to_string(),
            params,
            damping,
        })
    }

    /// `model`'s defaults: from its [`DefaultsCache`] if it has one, else parsed now.
    pub fn of(model: &dyn Model) -> Result<Arc<Defaults>, BuildError> {
        match model.defaults_cache() {
            Some(cache) => cache.get_or_parse(model),
            None => Defaults::parse(model).map(Arc::new),
        }
    }
}

/// A model's parsed [`Defaults`], kept after the first build (parsing the quad's parameter
/// tables and damping expressions is about half the cost of building it). Give each model
/// its own; a cache found holding another model's defaults is bypassed.
#[derive(Debug, Default)]
pub struct DefaultsCache(OnceLock<Result<Arc<Defaults>, BuildError>>);

impl DefaultsCache {
    /// An empty cache (usable in a `static`).
    pub const fn new() -> Self {
        DefaultsCache(OnceLock::new())
    }

    /// The cached defaults of `model`, parsed on first use. A model whose defaults do not
    /// parse gives the same error every time.
    pub fn get_or_parse(&self, model: &dyn Model) -> Result<Arc<Defaults>, BuildError> {
        let cached = self
            .0
            .get_or_init(|| Defaults::parse(model).map(Arc::new))
            .clone();
        match cached {
            Ok(defaults) if defaults.model != model.name() => Defaults::parse(model).map(Arc::new),
            other => other,
        }
    }
}

/// What a case changes in a model: parameter overrides (name, expression text, applied in
/// order) and damping fields per tag.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Overrides {
    /// Parameter overrides: a value, an expression, `scale(x)` or `increment(x)`.
    pub parameters: Vec<(String, String)>,
    /// Damping overrides per tag; the fields given replace the model's.
    pub damping: BTreeMap<String, DampingSpec>,
}

impl Overrides {
    /// The text of a case file of `model` (a bundled model's name or a suspension file's
    /// path) with these overrides: every parameter override, then every damping field each
    /// by its name in [`schema::DAMPING_FIELDS`], so that reading the text back gives the
    /// same overrides. `note(name)` is a comment written after a parameter's line.
    pub fn case_file(
        &self,
        model: &str,
        description: &str,
        note: &dyn Fn(&str) -> Option<String>,
    ) -> String {
        // a TOML basic string: the expression texts and names as they are
        let quote = |s: &str| format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""));
        let mut out = format!(
            "model = {}\ndescription = {}\n\n[parameters]\n",
            quote(model),
            quote(description)
        );
        for (name, text) in &self.parameters {
            let note = note(name).map(|n| format!("  # {n}")).unwrap_or_default();
            out += &format!("{} = {}{note}\n", quote(name), quote(text));
        }
        for (tag, spec) in &self.damping {
            out += &format!("\n[damping.{}]\n", quote(tag));
            // `thermoelastic.tau = ...` is a TOML dotted key: both file readers take it as
            // the thermoelastic table
            for (field, value) in spec.fields() {
                out += &format!("{} = {}\n", field.name, quote(value));
            }
        }
        out
    }
}

/// `defaults`' parameters with the overrides applied, and their values.
pub fn parameters_with(
    defaults: &Defaults,
    overrides: &Overrides,
) -> Result<(ParamSet, Resolved), BuildError> {
    let mut params = defaults.params.clone();
    for (name, text) in &overrides.parameters {
        params.apply_text(name, text)?;
    }
    let resolved = params.resolve()?;
    Ok((params, resolved))
}

/// A model built over a chunk of seeds ([`Model::build_tangents`]).
pub struct ChunkBuild {
    /// Every model number with its derivatives, direction k with respect to the k-th seed.
    pub system: System<ChunkDual>,
    /// The derivatives the build could not carry: the directions (bit k: the k-th seed)
    /// lost at one place, and why.
    pub lost: Vec<(u64, BuildError)>,
}

/// `model` with `overrides` built with dual numbers seeded in the direction of `parameter`
/// (see [`Model::build_tangents`]): the dual part of every model number is its exact
/// derivative with respect to `parameter`, moved as an override of it would move it. Only
/// the mechanical model: no damping, temperature or early-terms switch (what
/// [`build_with`] adds).
pub fn build_tangent(
    model: &dyn Model,
    overrides: &Overrides,
    parameter: &str,
) -> Result<System<Dual64>, BuildError> {
    build_tangent_chunk(model, overrides, &[parameter])?.direction(0)
}

/// [`build_tangent`] for up to [`pendkit_params::TANGENT_CHUNK`] parameters with one build
/// (the cost of about two `f64` builds instead of one each). The outer error is a model
/// that does not build at all; [`TangentChunk::direction`] gives each parameter's model,
/// or why it has no exact derivative.
pub fn build_tangent_chunk(
    model: &dyn Model,
    overrides: &Overrides,
    parameters: &[&str],
) -> Result<TangentChunk, BuildError> {
    let defaults = Defaults::of(model)?;
    let (set, resolved) = parameters_with(&defaults, overrides)?;
    let tangent = set.resolve_tangents(parameters)?;
    let build = model.build_tangents(&resolved, &tangent)?;
    // told apart from every other chunk of the process, so that a scratch model is rewritten
    // only by the chunk it was copied from
    static CHUNKS_BUILT: AtomicU64 = AtomicU64::new(0);
    Ok(TangentChunk {
        parameters: parameters.iter().map(|p| p.to_string()).collect(),
        id: CHUNKS_BUILT.fetch_add(1, Ordering::Relaxed),
        build,
    })
}

/// A model built once for a chunk of parameters ([`build_tangent_chunk`]), from which each
/// parameter's model is taken when it is wanted: a copy of the model
/// ([`TangentChunk::direction`]), or its numbers rewritten in a model kept from the chunk's
/// other parameters ([`TangentChunk::direction_in`]).
pub struct TangentChunk {
    parameters: Vec<String>,
    /// This chunk among the chunks built by the process.
    id: u64,
    build: ChunkBuild,
}

/// A parameter's model kept between calls of [`TangentChunk::direction_in`]: taking another
/// parameter of the same chunk rewrites the model's numbers in place, where
/// [`TangentChunk::direction`] copies the whole model (its names, frames, signals and
/// name schemes: about two hundred allocations for the quad).
#[derive(Default)]
pub struct DirectionScratch {
    /// The chunk the model was copied from, and the model.
    kept: Option<(u64, System<Dual64>)>,
}

impl TangentChunk {
    /// The parameters, in direction order.
    pub fn parameters(&self) -> &[String] {
        &self.parameters
    }

    /// The model with the derivatives of its numbers with respect to the `k`-th parameter,
    /// or why it has none: a derivative the build could not carry, one that is not finite,
    /// or `k` past the chunk.
    pub fn direction(&self, k: usize) -> Result<System<Dual64>, BuildError> {
        let mut scratch = DirectionScratch::default();
        self.direction_in(k, &mut scratch)?;
        match scratch.kept {
            Some((_, system)) => Ok(system),
            // direction_in keeps the model whenever it succeeds
            None => Err(BuildError::Invalid {
                item: format!("direction {k}"),
                message: "no model was taken".into(),
            }),
        }
    }

    /// [`TangentChunk::direction`] written into `scratch`: the numbers rewritten in place
    /// when the scratch holds a model of this chunk, else a copy of the model. On an error
    /// the scratch holds a model of the chunk whose numbers are not to be read.
    pub fn direction_in<'s>(
        &self,
        k: usize,
        scratch: &'s mut DirectionScratch,
    ) -> Result<&'s System<Dual64>, BuildError> {
        let Some(parameter) = self.parameters.get(k) else {
            return Err(BuildError::Invalid {
                item: format!("direction {k}"),
                message: format!("the chunk has {} parameters", self.parameters.len()),
            });
        };
        // the chunk has at most TANGENT_CHUNK parameters, so `k` is a direction
        let direction = pendkit_params::Direction::new(k)?;
        let mut lost = self.build.lost.iter();
        if let Some((_, why)) = lost.find(|(directions, _)| directions >> k & 1 == 1) {
            return Err(why.clone());
        }
        let mut finite = true;
        let mut along = |x: &ChunkDual| {
            let x = pendkit_params::chunk_direction(x, direction);
            finite &= x.eps.is_finite();
            x
        };
        // the same chunk's model has the same numbers in the same places
        let rewritten = match &mut scratch.kept {
            Some((id, system)) if *id == self.id => self
                .build
                .system
                .zip_scalars_into(system, |x, y| *y = along(x)),
            _ => false,
        };
        if !rewritten {
            scratch.kept = None;
        }
        let (_, system) = scratch
            .kept
            .get_or_insert_with(|| (self.id, self.build.system.map_scalars(|x| along(&x))));
        // a derivative that overflows or is undefined (a square root at zero) is not exact
        if !finite {
            return Err(BuildError::Invalid {
                item: format!("parameter '{parameter}'"),
                message: "no exact derivative: a model number's derivative is not finite".into(),
            });
        }
        Ok(system)
    }
}

/// The `f64` model `dual` (a model built with one parameter seeded, [`build_tangent`] or
/// [`TangentChunk::direction`]) moved by `step` (the parameter's unit) along its exact
/// tangent, every mechanical number x + step·dx (to first order, all a central difference
/// sees of it), with what [`build_with`] adds (the damping, the temperature, the "wire
/// terms early" switch) attached at the parameters of `defaults` with `overrides` (those
/// of the stepped value): the model a rebuild at the stepped value gives, to first order,
/// without the build.
pub fn build_stepped(
    dual: &System<Dual64>,
    step: f64,
    defaults: &Defaults,
    overrides: &Overrides,
) -> Result<System, BuildError> {
    let (_, resolved) = parameters_with(defaults, overrides)?;
    attach_to_build(dual.stepped(step), defaults, overrides, &resolved)
}

/// Resolves `model`'s defaults with `overrides` applied, builds the system and attaches
/// its damping multipliers, temperature (parameter `temperature`, K, default 290) and the
/// "wire terms early" switch (parameter `wire_terms_early`: 0 no, 1 yes, 2 equilibrium
/// only; default 0).
pub fn build_with(
    model: &dyn Model,
    overrides: &Overrides,
) -> Result<(System, Resolved), BuildError> {
    build_observed(model, overrides, |_| ()).map(|(system, resolved, ())| (system, resolved))
}

/// [`build_with`], with the parameters the model's own build read (before the damping,
/// the temperature and the "wire terms early" switch were attached: what the mechanics
/// depend on directly; add what their definitions refer to for all they depend on).
pub fn build_with_mechanical_reads(
    model: &dyn Model,
    overrides: &Overrides,
) -> Result<(System, Resolved, Vec<String>), BuildError> {
    build_observed(model, overrides, |resolved| {
        resolved
            .read_names()
            .into_iter()
            .map(String::from)
            .collect()
    })
}

/// [`build_with`], with what `after_model` makes of the parameters right after the model's
/// own build (before the built-in parts are attached): nothing for a plain build, which
/// then allocates nothing for it.
fn build_observed<T>(
    model: &dyn Model,
    overrides: &Overrides,
    after_model: impl FnOnce(&Resolved) -> T,
) -> Result<(System, Resolved, T), BuildError> {
    let defaults = Defaults::of(model)?;
    let (_, resolved) = parameters_with(&defaults, overrides)?;
    // checked before the model's build too, which a refused value then does not cost (the
    // sensitivities' differences step the switch off its allowed values); looked at
    // without recording a read, so that the reads after the build are the model's own
    let unread = |name: &str| resolved.iter().find(|(n, _)| *n == name).map(|(_, v)| v);
    if let (Some(temperature), Some(switch)) = (unread("temperature"), unread(WIRE_TERMS_EARLY)) {
        built_in_settings(temperature, switch)?;
    }
    let system = model.build(&resolved)?;
    let observed = after_model(&resolved);
    let system = attach_to_build(system, &defaults, overrides, &resolved)?;
    Ok((system, resolved, observed))
}

/// The parameter that switches the "wire terms early" mode of [`attach_to_build`] (0 no,
/// 1 yes, 2 equilibrium only): a switch, which moves the equilibrium and the modes.
pub const WIRE_TERMS_EARLY: &str = "wire_terms_early";

/// The symbols (parameters, and `f`) that the real multipliers ε'(f) of the damping read,
/// with the case's `overrides` merged in as [`attach_to_build`] merges them: where no tag
/// gives a real part that reads a parameter, ε' is 1 whatever the parameters. A real part
/// that does not parse reads nothing here (the build reports it).
pub fn damping_real_symbols(
    defaults: &Defaults,
    overrides: &Overrides,
) -> std::collections::BTreeSet<String> {
    let tags = defaults.damping.keys().chain(
        overrides
            .damping
            .keys()
            .filter(|t| !defaults.damping.contains_key(*t)),
    );
    let mut symbols = std::collections::BTreeSet::new();
    for tag in tags {
        let over = overrides.damping.get(tag).and_then(|o| o.real.as_ref());
        let default = defaults
            .damping
            .get(tag)
            .and_then(|d| d.spec().real.as_ref());
        if let Some(Ok(expr)) = over.or(default).map(|text| pendkit_expr::parse(text)) {
            symbols.extend(expr.symbols());
        }
    }
    symbols
}

/// What [`build_with`] adds to the model's mechanical build `system`: the damping
/// multipliers of its tags (the model's defaults with `overrides`), the temperature and
/// the "wire terms early" switch, at the parameter values `resolved`.
pub fn attach_to_build(
    mut system: System,
    defaults: &Defaults,
    overrides: &Overrides,
    resolved: &Resolved,
) -> Result<System, BuildError> {
    if !overrides.damping.is_empty() {
        let used = system.tags();
        if let Some(tag) = overrides.damping.keys().find(|t| !used.contains(*t)) {
            return Err(BuildError::Unknown {
                context: format!(
                    "damping (tags of this model: {})",
                    used.iter().cloned().collect::<Vec<_>>().join(", ")
                ),
                what: "tag",
                name: tag.clone(),
            });
        }
    }
    // the model's tags, then those only a case gives damping; a tag the case overrides is
    // parsed again with its fields merged in
    let case_only = overrides
        .damping
        .keys()
        .filter(|t| !defaults.damping.contains_key(*t));
    for tag in defaults.damping.keys().chain(case_only) {
        let (damping, temperature) = match (defaults.damping.get(tag), overrides.damping.get(tag)) {
            (Some(parsed), None) => (
                parsed.compile(tag, resolved)?,
                parsed.spec().temperature_value(tag, resolved)?,
            ),
            (parsed, over) => {
                let mut spec = parsed.map(|p| p.spec().clone()).unwrap_or_default();
                if let Some(over) = over {
                    spec.merge(over);
                }
                (
                    spec.resolve(tag, resolved)?,
                    spec.temperature_value(tag, resolved)?,
                )
            }
        };
        system.damping.set(tag, damping);
        if let Some(t) = temperature {
            system.damping.set_temperature(tag, t);
        }
    }
    (system.temperature, system.early_wire_terms) = built_in_settings(
        resolved.get("temperature")?,
        resolved.get(WIRE_TERMS_EARLY)?,
    )?;
    Ok(system)
}

/// The temperature (K) and the "wire terms early" switch of the parameters `temperature`
/// and `wire_terms_early`, checked.
fn built_in_settings(
    temperature: f64,
    wire_terms_early: f64,
) -> Result<(f64, EarlyWireTerms), BuildError> {
    if temperature <= 0.0 {
        return Err(BuildError::Invalid {
            item: "parameter 'temperature'".into(),
            message: format!("must be positive (got {} K)", number_text(temperature)),
        });
    }
    let early_wire_terms = match wire_terms_early {
        0.0 => EarlyWireTerms::No,
        1.0 => EarlyWireTerms::Yes,
        2.0 => EarlyWireTerms::EquilibriumOnly,
        other => {
            return Err(BuildError::Invalid {
                item: "parameter 'wire_terms_early'".into(),
                message: format!(
                    "must be 0 (no), 1 (yes) or 2 (equilibrium only), got {}",
                    number_text(other)
                ),
            });
        }
    };
    Ok((temperature, early_wire_terms))
}
