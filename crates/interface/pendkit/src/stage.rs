//! One stage of a case, run: the equilibrium, stiffness, mass and modes of a model at a
//! calculation stage ([`run_stage`], [`run_stage_with`]), and what a [`StageResult`] answers
//! (transfer functions, thermal noise, state space, named points and signals), with the
//! provenance of its numbers and the timing of its phases ([`bench()`]).

use nalgebra::{DVector, Vector3};
use pendkit_dynamics::DynamicsError;
use pendkit_noise::thermal_noise_with;
use pendkit_system::{NamedSignal, SignalTerm};

use pendkit_assembly::{PhaseTimes, PointWeights};
use pendkit_dynamics::{Input, Output, Solver, StageRun};
use pendkit_noise::{NoiseOptions, ThermalNoise};
use pendkit_system::{Stage, System};

use pendkit_params::Resolved;

use crate::{Case, Error, VERSION};

pub use crate::bench::{BenchPhase, BenchReport, MAX_REPEAT, bench};
pub use crate::state_space::NamedStateSpace;
pub use pendkit_dynamics::{DENSE_MODES_LIMIT, MAX_VIOLIN_HARMONICS, ModeSelection, RunOptions};
/// Continuum fibres: a wire's exact dynamic stiffness D(f) (docs/continuum-fibres.md).
pub use pendkit_element_continuum_fibre as continuum;

/// One parameter of a case as resolved for a run.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ParameterValue {
    /// Name.
    pub name: String,
    /// Resolved value, in its unit.
    pub value: f64,
    /// Unit, where the model declares one (empty for a pure number).
    pub unit: Option<String>,
    /// The definition as written: the model's default, or the case's override.
    pub definition: String,
    /// Whether the case (or a `--set`) overrides the model's default.
    pub overridden: bool,
}

/// Where a result comes from: the model, the case and every resolved parameter.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Provenance {
    /// Model name.
    pub model: String,
    /// Case name (the model name, or the case file's stem).
    pub case: String,
    /// The case's description, if it has one.
    pub description: Option<String>,
    /// The numeric parameters in definition order.
    pub parameters: Vec<ParameterValue>,
    /// pendkit's version.
    pub version: String,
}

impl Case {
    /// The provenance of a build of this case that resolved to `resolved`: each parameter
    /// with its value, its unit where the model declares one, and its definition.
    pub fn provenance(&self, resolved: &Resolved) -> Result<Provenance, Error> {
        let defaults = pendkit_model::Defaults::of(&*self.model)?;
        let parameters = resolved
            .iter()
            .map(|(name, value)| {
                let overridden = self
                    .overrides
                    .parameters
                    .iter()
                    .rev()
                    .find(|(n, _)| n == name);
                ParameterValue {
                    name: name.to_string(),
                    value,
                    unit: defaults.params.unit(name).map(str::to_string),
                    definition: match overridden {
                        Some((_, text)) => text.clone(),
                        None => defaults
                            .params
                            .get(name)
                            .map(|d| d.source.clone())
                            .unwrap_or_default(),
                    },
                    overridden: overridden.is_some(),
                }
            })
            .collect();
        Ok(Provenance {
            model: self.model.name().to_string(),
            case: self.name.clone(),
            description: self.description.clone(),
            parameters,
            version: VERSION.to_string(),
        })
    }
}

/// The result of running one stage of a model: the dynamics layer's [`StageRun`] (its
/// fields `system`, `assembled`, `model`, `modes` and `stability` read through it), with
/// what the facade adds on top: inputs and outputs by name, transfer functions and noise
/// checked for finite values, the named state space, the modes described.
pub struct StageResult {
    run: StageRun,
    /// For each coordinate, the body whose own pose coordinate it is and the pose entry:
    /// made on first use, once, so that describing every mode of a model is linear in its
    /// size per mode (a search through the bodies per coordinate made it cubic).
    owners: std::sync::OnceLock<Vec<Option<(pendkit_system::BodyId, usize)>>>,
}

impl std::ops::Deref for StageResult {
    type Target = StageRun;

    fn deref(&self) -> &StageRun {
        &self.run
    }
}

impl From<StageRun> for StageResult {
    fn from(run: StageRun) -> StageResult {
        StageResult {
            run,
            owners: std::sync::OnceLock::new(),
        }
    }
}

/// One violin mode of a model with continuum fibres ([`StageResult::violin_modes`]).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ViolinMode {
    /// The wires of the fibre set whose harmonic this is (alike fibres: the same
    /// harmonics).
    pub wires: Vec<String>,
    /// The harmonic (1 for the fundamental): the mode lies in the band around it.
    pub harmonic: usize,
    /// Frequency (Hz).
    pub frequency_hz: f64,
    /// Quality factor (dimensionless) f/(2 Im f), Im f to first order in the loss;
    /// infinite without loss (null in JSON).
    pub q: f64,
    /// Bound on the frequency's numerical error (Hz).
    pub accuracy_hz: f64,
    /// When every body is still in this mode (the fibres' end forces cancel on them): the
    /// motion of the fibres' held resonance it sits at ("transverse", "axial", "torsion").
    pub held: Option<String>,
}

/// How the wires' own motion enters responses and noise. A stage result starts as the
/// model says ([`Fibres::AsModelled`]: the wires its file marks `continuum = true`, none in
/// the bundled models); [`StageResult::with_fibres`] chooses otherwise.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum Fibres {
    /// The static model: massless wires (and violin beads where the model has them).
    Static,
    /// The wires the model marks as continua ([`pendkit_system::Wire::continuum`]); the
    /// static model when it marks none.
    #[default]
    AsModelled,
    /// The lowest wires (those ending on the body whose wire ends lie lowest: a quad's
    /// fibres, a triple's lower wires) and any the model marks, as continua: their exact
    /// dynamic stiffness D(f) in `tf` and `noise` (docs/continuum-fibres.md). The modes
    /// and the state space keep the static model.
    Continuum,
    /// The named wires as continua.
    ContinuumNamed(Vec<String>),
}

impl StageResult {
    /// This result with `fibres` in place of the wires it took as continua before: for a
    /// continuum, the wires' frequency terms join the stage model, so that transfer
    /// functions and noise see their violin modes and exact dilution. Refused: violin beads
    /// together with continuum fibres (the beads carry the same mass), a name that is no
    /// wire, a wire that is not taut and straight.
    pub fn with_fibres(mut self, fibres: &Fibres) -> Result<StageResult, Error> {
        self.run.model.frequency_terms.clear();
        let system = &self.run.system;
        let marked = || (0..system.wires.len()).filter(|&w| system.wires[w].continuum);
        let wires: Vec<usize> = match fibres {
            Fibres::Static => return Ok(self),
            Fibres::AsModelled => {
                let wires: Vec<usize> = marked().collect();
                if wires.is_empty() {
                    return Ok(self);
                }
                wires
            }
            Fibres::Continuum => {
                // the wires that end on the body whose wire ends lie lowest (a quad's test
                // mass): a body hanging nothing from itself is not enough, since blade tips
                // (their own bodies) carry the next wires down
                let reference =
                    pendkit_energy::Reference::new(system, &self.run.assembled.equilibrium.coords);
                let low = |w: &pendkit_system::Wire| {
                    reference.wire_points(w).map_or(f64::INFINITY, |p| p[1][2])
                };
                let lowest = system
                    .wires
                    .iter()
                    .min_by(|a, b| low(a).total_cmp(&low(b)))
                    .map(|w| w.ends[1].body);
                (0..system.wires.len())
                    .filter(|&w| Some(system.wires[w].ends[1].body) == lowest)
                    .chain(marked())
                    .collect::<std::collections::BTreeSet<usize>>()
                    .into_iter()
                    .collect()
            }
            Fibres::ContinuumNamed(names) => names
                .iter()
                .map(|n| {
                    system
                        .wires
                        .iter()
                        .position(|w| &w.name == n)
                        .ok_or_else(|| Error::Name {
                            name: n.clone(),
                            message: "no wire of the model has this name".into(),
                        })
                })
                // a name given twice is one wire, whose term counts once
                .collect::<Result<std::collections::BTreeSet<usize>, _>>()?
                .into_iter()
                .collect(),
        };
        if let Some(b) = system
            .bodies
            .iter()
            .find(|b| b.mode_family.as_deref() == Some("violin"))
        {
            return Err(Error::Name {
                name: b.name.clone(),
                message: "continuum fibres replace violin beads: build the model without \
                          beads (n_beads=0)"
                    .into(),
            });
        }
        let terms =
            pendkit_element_continuum_fibre::continuum_terms(system, &self.run.assembled, &wires)
                .map_err(|e| Error::Name {
                name: "continuum fibres".into(),
                message: e.to_string(),
            })?;
        let mut result = self;
        result.run.model.frequency_terms.extend(terms);
        Ok(result)
    }

    /// The first `harmonics` violin modes of each set of alike continuum fibres (a quad's
    /// four), as roots of the whole model's frequency-dependent problem with the fibres'
    /// exact D(f) (docs/continuum-fibres.md, "Violin modes"): each harmonic's cluster,
    /// frequency, quality factor and accuracy. Needs continuum fibres
    /// ([`StageResult::with_fibres`]); refused: `harmonics` outside
    /// 1..=[`MAX_VIOLIN_HARMONICS`], a model without them.
    pub fn violin_modes(&self, harmonics: usize) -> Result<Vec<ViolinMode>, Error> {
        if self.run.model.frequency_terms.is_empty() {
            return Err(Error::Name {
                name: "violin modes".into(),
                message: "they need continuum fibres (Fibres::Continuum): this result has \
                          the static wires"
                    .into(),
            });
        }
        let roots = self
            .run
            .model
            .violin_modes(&self.run.system.damping, harmonics)?;
        Ok(roots
            .into_iter()
            .map(|r| ViolinMode {
                wires: r
                    .terms
                    .iter()
                    .map(|t| t.strip_prefix("continuum:").unwrap_or(t).to_string())
                    .collect(),
                harmonic: r.harmonic,
                frequency_hz: r.frequency_hz,
                q: r.q,
                accuracy_hz: r.accuracy_hz,
                held: r.held.map(str::to_string),
            })
            .collect())
    }

    /// The body whose own pose coordinate `coord` is, and the pose entry (0 to 5: x, y, z,
    /// yaw, pitch, roll), from an index made once.
    pub(crate) fn owner(
        &self,
        coord: pendkit_system::CoordId,
    ) -> Option<(pendkit_system::BodyId, usize)> {
        let owners = self.owners.get_or_init(|| {
            let mut owners = vec![None; self.run.system.coords.len()];
            // the first body that has the coordinate, as a search in body order finds it
            for (b, body) in self.run.system.bodies.iter().enumerate().rev() {
                for (k, c) in body.pose_coords.iter().enumerate().rev() {
                    if let Some(slot) = c.and_then(|c| owners.get_mut(c)) {
                        *slot = Some((b, k));
                    }
                }
            }
            owners
        });
        owners.get(coord).copied().flatten()
    }

    /// The dynamics layer's run, for the functions of `pendkit::dynamics` that take one.
    pub fn into_run(self) -> StageRun {
        self.run
    }
}

/// Equilibrium, stiffness, mass and modes of `system` at `stage`. The modes use the real
/// stiffness at f = 0 (each tag's ε'(0); 1 unless a model says otherwise).
pub fn run_stage(system: System, stage: Stage) -> Result<StageResult, Error> {
    run_stage_with(system, stage, &RunOptions::default(), None)
}

/// [`run_stage`] with options, recording the time of each phase into `times` when given
/// (the phases are listed at [`StageRun::new`], which runs them). The wires the model
/// marks as continua are taken as such ([`Fibres::AsModelled`]).
pub fn run_stage_with(
    system: System,
    stage: Stage,
    options: &RunOptions,
    times: Option<&mut PhaseTimes>,
) -> Result<StageResult, Error> {
    let result = StageResult::from(StageRun::new(system, stage, options, times)?);
    if result.run.system.wires.iter().any(|w| w.continuum) {
        result.with_fibres(&Fibres::AsModelled)
    } else {
        Ok(result)
    }
}

impl StageResult {
    /// One line saying what grows, as an error, unless the equilibrium is stable (or
    /// neutral). Every calculation that answers with a linearised model checks this first.
    pub fn check_stable(&self) -> Result<(), Error> {
        Ok(self.run.check_stable()?)
    }

    /// The check every command answering with a linearised model makes before it answers
    /// (see [`StageRun::require_stable`]).
    pub fn require_stable(&self, allow_unstable: bool) -> Result<Option<String>, Error> {
        Ok(self.run.require_stable(allow_unstable)?)
    }
}

impl StageResult {
    /// A point on a body and a direction, written `<body>@x,y,z/dx,dy,dz` (m, body
    /// coordinates; direction in lab axes, normalised): how far the point moves along the
    /// direction per unit of every unknown and parameter (the linearised geometry at
    /// equilibrium). The same weights are the generalised force of a unit force there.
    fn point_weights(&self, spec: &str) -> Option<Result<PointWeights, Error>> {
        let (body, rest) = spec.split_once('@')?;
        Some((|| {
            let bad = |why: &str| Error::Name {
                name: spec.to_string(),
                message: format!("expected <body>@x,y,z/dx,dy,dz ({why})"),
            };
            let (point, dir) = rest
                .split_once('/')
                .ok_or_else(|| bad("no '/' before the direction"))?;
            let nums = |t: &str, what: &str| -> Result<Vector3<f64>, Error> {
                let v: Vec<f64> = t
                    .split(',')
                    .map(pendkit_expr::number_literal)
                    .collect::<Result<_, _>>()
                    .map_err(|e| bad(&format!("the {what} is not three numbers: {e}")))?;
                if v.len() == 3 {
                    Ok(Vector3::new(v[0], v[1], v[2]))
                } else {
                    Err(bad(&format!("the {what} must be three finite numbers")))
                }
            };
            let (p, d) = (nums(point, "point")?, nums(dir, "direction")?);
            // scaled by its largest component first: a tiny or huge (finite) direction
            // would otherwise underflow or overflow in its norm
            let largest = d.amax();
            if largest == 0.0 {
                return Err(bad("the direction is zero"));
            }
            let d = d / largest;
            let b = self.system.body(body).ok_or_else(|| Error::Name {
                name: spec.to_string(),
                message: format!(
                    "unknown body '{body}' (bodies: {})",
                    self.system
                        .bodies
                        .iter()
                        .map(|b| b.name.as_str())
                        .collect::<Vec<_>>()
                        .join(" ")
                ),
            })?;
            self.assembled
                .point_weights(&self.system, b, &p, &d)
                .ok_or_else(|| bad("its motion is not finite at the equilibrium"))
        })())
    }

    /// The vector of a model's named input or output (`[inputs]`/`[outputs]` of a
    /// suspension file), laid out as the built-in forms are:
    ///
    /// - a displacement output: over the variables, floats and parameters (a point's whole
    ///   motion, as `<body>@x,y,z/dx,dy,dz`: through the variables, the floats that pose
    ///   its body, and the support);
    /// - a force input: over the variables and floats (a force on a float-posed body such
    ///   as a blade tip reaches the variables through the float elimination);
    /// - a displacement input or a support-force output: over the parameters; a point there
    ///   must be one the support alone moves (driven as `support@x,y,z/dx,dy,dz` is).
    fn named_vector(&self, signal: &NamedSignal, input: bool) -> Result<DVector<f64>, Error> {
        let m = &self.model;
        let (nx, nq, ns) = m.sizes;
        let on_parameters = input != signal.force;
        let n = match (on_parameters, input) {
            (true, _) => ns,
            (false, true) => nx + nq,
            (false, false) => nx + nq + ns,
        };
        let bad = |message: String| Error::Name {
            name: signal.name.clone(),
            message,
        };
        let mut v = DVector::zeros(n);
        for (coefficient, term) in &signal.terms {
            match term {
                SignalTerm::Coordinate(c) => {
                    let coordinate = self
                        .system
                        .coords
                        .get(*c)
                        .map(|c| c.name.as_str())
                        .unwrap_or_default();
                    let position = |names: &[String]| names.iter().position(|n| n == coordinate);
                    let k = if on_parameters {
                        position(&m.parameters)
                    } else {
                        // variables first, then floats, then (outputs) the parameters
                        position(&m.variables)
                            .or_else(|| position(&m.floats).map(|k| nx + k))
                            .or_else(|| position(&m.parameters).map(|k| nx + nq + k))
                            .filter(|&k| k < n)
                    };
                    let k = k.ok_or_else(|| {
                        bad(format!(
                            "combines '{coordinate}', which this stage does not keep as a {}",
                            if on_parameters {
                                "parameter"
                            } else if input {
                                "variable or float"
                            } else {
                                "variable, float or parameter"
                            }
                        ))
                    })?;
                    v[k] += coefficient;
                }
                SignalTerm::Point {
                    body,
                    point,
                    direction,
                } => {
                    let w = self
                        .assembled
                        .point_weights(&self.system, *body, point, direction)
                        .ok_or_else(|| {
                            bad("a point whose motion is not finite at the equilibrium".into())
                        })?;
                    if !on_parameters {
                        v.rows_mut(0, nx + nq).axpy(*coefficient, &w.unknowns, 1.0);
                        if n == nx + nq + ns {
                            v.rows_mut(nx + nq, ns)
                                .axpy(*coefficient, &w.parameters, 1.0);
                        }
                    } else if signal.force {
                        return Err(bad(
                            "a point cannot carry the support force: name the support's coordinates".into(),
                        ));
                    } else {
                        // a driven point: the smallest change of the parameters that moves
                        // it by one unit along the direction, as support@x,y,z/dx,dy,dz
                        let norm2 = w.parameters.norm_squared();
                        if w.unknowns.iter().any(|&x| x != 0.0)
                            || norm2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
                        {
                            return Err(bad(
                                "a displacement input must be a point that only the support moves"
                                    .into(),
                            ));
                        }
                        v.axpy(*coefficient / norm2, &w.parameters, 1.0);
                    }
                }
            }
        }
        Ok(v)
    }

    fn unit(n: usize, k: usize) -> DVector<f64> {
        let mut v = DVector::zeros(n);
        v[k] = 1.0;
        v
    }

    fn names_error(&self, name: &str, what: &str, valid: &[String]) -> Error {
        Error::Name {
            name: name.to_string(),
            message: format!("not {what} (valid: {})", valid.join(" ")),
        }
    }

    /// Parses an input: a named input the model declares, a parameter (support
    /// displacement, e.g. `x00`), a point on a body the support alone moves
    /// (`support@x,y,z/dx,dy,dz`: the smallest change of the parameters, metres and radians
    /// alike, that moves the point by one unit along the direction), `force:<variable>` or
    /// `force:<body>@x,y,z/dx,dy,dz` (a force at a point, also on a body a float poses, such
    /// as a blade tip). Names of a scheme the model declares are accepted too (`GND_L`,
    /// `force:L3_P`).
    pub fn input(&self, name: &str) -> Result<Input, Error> {
        if let Some(signal) = self.system.inputs.iter().find(|s| s.name == name) {
            let v = self.named_vector(signal, true)?;
            return Ok(if signal.force {
                Input::Force(v)
            } else {
                Input::Displacement(v)
            });
        }
        let name = &self.unalias(name);
        let m = &self.model;
        let err = |message: &str| Error::Name {
            name: name.to_string(),
            message: message.to_string(),
        };
        if let Some(target) = name.strip_prefix("force:") {
            if let Some(w) = self.point_weights(target) {
                let w = w?;
                if w.unknowns.iter().all(|&x| x == 0.0) {
                    return Err(err(if w.parameters.iter().any(|&x| x != 0.0) {
                        "a force on a point the support alone moves does nothing (the support is driven): use the point as a displacement input"
                    } else {
                        "the point does not move with any coordinate"
                    }));
                }
                return Ok(Input::Force(w.unknowns));
            }
            return match m.variables.iter().position(|v| v == target) {
                Some(k) => Ok(Input::Force(Self::unit(m.variables.len(), k))),
                None => Err(self.names_error(target, "a variable to push on", &m.variables)),
            };
        }
        if let Some(w) = self.point_weights(name) {
            let w = w?;
            if w.unknowns.iter().any(|&x| x != 0.0) {
                return Err(err(
                    "a displacement input must be a point that only the support moves: push on a moving body with force:<body>@x,y,z/dx,dy,dz",
                ));
            }
            let norm2 = w.parameters.norm_squared();
            if norm2.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return Err(err("the point does not move with any parameter"));
            }
            return Ok(Input::Displacement(w.parameters / norm2));
        }
        match m.parameters.iter().position(|v| v == name) {
            Some(k) => Ok(Input::Displacement(Self::unit(m.parameters.len(), k))),
            None => Err(self.names_error(
                name,
                "a parameter to drive (or <support body>@x,y,z/dx,dy,dz, force:<variable>, force:<body>@x,y,z/dx,dy,dz)",
                &m.parameters,
            )),
        }
    }

    /// Parses an output: a named output the model declares, a variable,
    /// `<body>@x,y,z/dx,dy,dz` (the point's whole motion: through the variables, the floats
    /// that pose its body and the support), or `force:<parameter>` (the force on the
    /// support). Names of a scheme the model declares are accepted too (`L3_L`,
    /// `L3@0,0,0/1,0,0`).
    pub fn output(&self, name: &str) -> Result<Output, Error> {
        if let Some(signal) = self.system.outputs.iter().find(|s| s.name == name) {
            let v = self.named_vector(signal, false)?;
            return Ok(if signal.force {
                Output::SupportForce(v)
            } else {
                Output::Displacement(v)
            });
        }
        let name = &self.unalias(name);
        let m = &self.model;
        if let Some(target) = name.strip_prefix("force:") {
            return match m.parameters.iter().position(|v| v == target) {
                Some(k) => Ok(Output::SupportForce(Self::unit(m.parameters.len(), k))),
                None => Err(self.names_error(target, "a parameter", &m.parameters)),
            };
        }
        if let Some(w) = self.point_weights(name) {
            let w = w?;
            let all: Vec<f64> = w
                .unknowns
                .iter()
                .chain(w.parameters.iter())
                .copied()
                .collect();
            return Ok(Output::Displacement(DVector::from_vec(all)));
        }
        match m.variables.iter().position(|v| v == name) {
            Some(k) => Ok(Output::Displacement(Self::unit(m.variables.len(), k))),
            None => Err(self.names_error(
                name,
                "a variable (or <body>@x,y,z/dx,dy,dz, force:<parameter>)",
                &m.variables,
            )),
        }
    }
}

/// Every value finite, or an error naming the first frequency where one is not.
fn check_finite<'a>(
    what: &str,
    freqs: &[f64],
    values: impl IntoIterator<Item = &'a f64>,
    per_frequency: usize,
) -> Result<(), Error> {
    let per = per_frequency.max(1);
    match values.into_iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(k) => Err(Error::NotFinite {
            what: what.to_string(),
            f_hz: freqs.get(k / per).copied().unwrap_or(f64::NAN),
        }),
    }
}

impl StageResult {
    /// Transfer function from the named input to the named output (see
    /// [`StageResult::input`], [`StageResult::output`]) at `freqs` (Hz), with the model's
    /// damping, solved over the blocks they couple to. An equilibrium that is not stable
    /// is refused ([`StageResult::check_stable`]): a growing system has no steady response,
    /// and its frequency response would look like one.
    pub fn transfer(
        &self,
        input: &str,
        output: &str,
        freqs: &[f64],
    ) -> Result<Vec<faer::c64>, Error> {
        self.check_stable()?;
        self.transfer_with(input, output, freqs, Solver::Restricted)
    }

    /// [`StageResult::transfer`] solved as `solver` says (restricted, full, or the dense
    /// reference), without the stability check: for a caller that has made it already, or
    /// that goes on from an unstable equilibrium on purpose
    /// ([`StageResult::require_stable`] with `allow_unstable`; control design needs
    /// unstable plants).
    pub fn transfer_with(
        &self,
        input: &str,
        output: &str,
        freqs: &[f64],
        solver: Solver,
    ) -> Result<Vec<faer::c64>, Error> {
        let (i, o) = (self.input(input)?, self.output(output)?);
        let h = self
            .model
            .transfer_with(&self.system.damping, &i, &o, freqs, solver)?;
        check_finite(
            &format!("transfer function {output}/{input}"),
            freqs,
            h.iter().flat_map(|z| [&z.re, &z.im]),
            2,
        )?;
        Ok(h)
    }

    /// Thermal noise (PSD, m²/Hz or rad²/Hz) of the named displacement output at `freqs`
    /// (Hz), at the model's temperature, with its breakdown by damping tag. An equilibrium
    /// that is not stable is refused, as by [`StageResult::transfer`].
    pub fn noise(&self, output: &str, freqs: &[f64]) -> Result<ThermalNoise, Error> {
        self.check_stable()?;
        self.noise_with(output, freqs, &NoiseOptions::default())
    }

    /// [`StageResult::noise`] solved and broken down as `options` says (per term too, full
    /// or restricted solve), without the stability check (see
    /// [`StageResult::transfer_with`]).
    pub fn noise_with(
        &self,
        output: &str,
        freqs: &[f64],
        options: &NoiseOptions,
    ) -> Result<ThermalNoise, Error> {
        match self.output(output)? {
            Output::Displacement(v) => {
                let noise = thermal_noise_with(
                    &self.model,
                    &self.system.damping,
                    &v,
                    self.system.temperature,
                    freqs,
                    options,
                )
                .map_err(|e| match e {
                    DynamicsError::NoLoss { lossless, .. } => DynamicsError::NoLoss {
                        output: format!("'{output}'"),
                        lossless,
                    },
                    other => other,
                })?;
                let what = format!("thermal noise of {output}");
                check_finite(&what, freqs, &noise.total, 1)?;
                for (_, series) in &noise.tags {
                    check_finite(&what, freqs, series, 1)?;
                }
                Ok(noise)
            }
            Output::SupportForce(_) => Err(Error::Name {
                name: output.to_string(),
                message: "thermal noise needs a displacement output".into(),
            }),
        }
    }
}
