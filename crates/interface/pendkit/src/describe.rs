//! What a stage result says about itself in people's terms: the unit of every coordinate,
//! input and output, the degree-of-freedom family of every mode, the names a model declares
//! in other schemes (LIGO's `L3_P`), which body is the support and which the test mass, and
//! the standard transfer functions between them. Everything is read from the model's data
//! (its bodies' own pose coordinates, shapes and declared names), never from its name.
//!
//! Also the table of a case's parameters with their units, domains and readers
//! ([`parameter_table`], what `pendkit params` prints).

use nalgebra::Vector3;
use pendkit_dynamics::Mode;
use pendkit_system::{BodyId, CoordKind, NameScheme};

use crate::{Error, StageResult};

pub use crate::parameters::{ParameterRow, parameter_table};

/// Degree-of-freedom family of each pose entry (x, y, z, yaw, pitch, roll): longitudinal L,
/// transverse T, vertical V, yaw Y, pitch P, roll R (the axes of the conventions, with
/// LIGO's letters).
pub const DOF_FAMILIES: [&str; 6] = ["L", "T", "V", "Y", "P", "R"];

/// Family of a mode whose energy is mostly in coordinates that are no body's own degree of
/// freedom.
pub const OTHER_FAMILY: &str = "other";

/// The unit of a pose entry: m for the translations, rad for the rotations.
fn pose_unit(entry: usize) -> &'static str {
    if entry < 3 { "m" } else { "rad" }
}

/// `a/b` for units, bracketing a compound denominator: `m/N`, `rad/(N m)`.
pub fn unit_ratio(numerator: &str, denominator: &str) -> String {
    if denominator.contains(' ') {
        format!("{numerator}/({denominator})")
    } else {
        format!("{numerator}/{denominator}")
    }
}

/// A unit as an identifier-safe suffix for CSV headers: `m/N` → `m_per_N`, `rad/(N m)` →
/// `rad_per_N_m`, `m/√Hz` → `m_per_rthz`, `kg m^2` → `kg_m2`.
pub fn unit_slug(unit: &str) -> String {
    let text = unit
        .replace("√Hz", "rthz")
        .replace('^', "")
        .replace('/', " per ")
        .replace(['(', ')'], " ");
    text.split_whitespace().collect::<Vec<_>>().join("_")
}

impl StageResult {
    /// The names of scheme `scheme` (e.g. `ligo`) that the model declares, or an error
    /// listing the schemes it has.
    pub fn name_scheme(&self, scheme: &str) -> Result<&NameScheme, Error> {
        self.system.name_schemes.get(scheme).ok_or_else(|| {
            let known: Vec<&str> = self
                .system
                .name_schemes
                .keys()
                .map(String::as_str)
                .collect();
            Error::Name {
                name: scheme.to_string(),
                message: if known.is_empty() {
                    "this model declares no other names (no naming scheme)".to_string()
                } else {
                    format!(
                        "not a naming scheme of this model (it has: {})",
                        known.join(" ")
                    )
                },
            }
        })
    }

    /// A coordinate name of any scheme the model declares, as the model's own name
    /// (`L3_P` → `pitch3`); also inside `force:<name>` and before `@` in a point. Names
    /// that are already the model's are returned as they are.
    pub(crate) fn unalias(&self, name: &str) -> String {
        let native = |n: &str| -> Option<String> {
            if self.system.coord(n).is_some() || self.system.body(n).is_some() {
                return None;
            }
            self.system.name_schemes.values().find_map(|s| {
                s.coord_called(n)
                    .or_else(|| s.body_called(n))
                    .map(str::to_string)
            })
        };
        if let Some(rest) = name.strip_prefix("force:") {
            return format!("force:{}", self.unalias(rest));
        }
        if let Some((body, rest)) = name.split_once('@') {
            return match native(body) {
                Some(b) => format!("{b}@{rest}"),
                None => name.to_string(),
            };
        }
        native(name).unwrap_or_else(|| name.to_string())
    }

    /// Unit of the coordinate called `name`: `m` or `rad` when it is a body's own pose
    /// coordinate (translation or rotation), `None` otherwise.
    pub fn coordinate_unit(&self, name: &str) -> Option<&'static str> {
        let c = self.system.coord(&self.unalias(name))?;
        self.owner(c).map(|(_, k)| pose_unit(k))
    }

    /// Unit of an input (see [`StageResult::input`]): a support displacement in m or rad,
    /// a force on a translation or at a point in N, a torque on a rotation in N m.
    pub fn input_unit(&self, input: &str) -> Option<String> {
        if let Some(signal) = self.system.inputs.iter().find(|s| s.name == input) {
            return self.signal_unit(signal);
        }
        let input = self.unalias(input);
        match input.strip_prefix("force:") {
            Some(target) if target.contains('@') => Some("N".into()),
            Some(target) => self
                .coordinate_unit(target)
                .map(|u| if u == "m" { "N" } else { "N m" }.to_string()),
            None => self.coordinate_unit(&input).map(str::to_string),
        }
    }

    /// Unit of an output (see [`StageResult::output`]): a displacement in m or rad, a point's
    /// displacement in m, a force (N) or torque (N m) on the support.
    pub fn output_unit(&self, output: &str) -> Option<String> {
        if let Some(signal) = self.system.outputs.iter().find(|s| s.name == output) {
            return self.signal_unit(signal);
        }
        let output = self.unalias(output);
        if output.contains('@') {
            return Some("m".into());
        }
        match output.strip_prefix("force:") {
            Some(target) => self
                .coordinate_unit(target)
                .map(|u| if u == "m" { "N" } else { "N m" }.to_string()),
            None => self.coordinate_unit(&output).map(str::to_string),
        }
    }

    /// Unit of a model's named input or output: its terms' common unit (a point's
    /// displacement m, a force there N; a coordinate's m or rad, a force on it N or N m),
    /// `None` when they differ.
    fn signal_unit(&self, signal: &pendkit_system::NamedSignal) -> Option<String> {
        let mut units = signal.terms.iter().map(|(_, term)| match term {
            pendkit_system::SignalTerm::Point { .. } => {
                Some(if signal.force { "N" } else { "m" }.to_string())
            }
            pendkit_system::SignalTerm::Coordinate(c) => {
                let unit = self.coordinate_unit(&self.system.coords.get(*c)?.name)?;
                Some(match (signal.force, unit) {
                    (false, u) => u.to_string(),
                    (true, "m") => "N".to_string(),
                    (true, _) => "N m".to_string(),
                })
            }
        });
        let first = units.next()??;
        units
            .all(|u| u.as_deref() == Some(first.as_str()))
            .then_some(first)
    }

    /// Unit of the transfer function from `input` to `output`, e.g. `m/m`, `rad/(N m)`.
    pub fn transfer_unit(&self, input: &str, output: &str) -> Option<String> {
        Some(unit_ratio(
            &self.output_unit(output)?,
            &self.input_unit(input)?,
        ))
    }

    /// The family a mode belongs to: the family with the largest share of its kinetic
    /// energy, where each variable counts for its body's declared mode family (e.g.
    /// `violin` for beads) or else its degree of freedom ([`DOF_FAMILIES`]), and variables
    /// that are no body's own coordinate for [`OTHER_FAMILY`].
    pub fn mode_family(&self, mode: &Mode) -> String {
        // the families borrowed from the system (a command asks this of every mode): only
        // the winner is copied
        let mut shares: Vec<(&str, f64)> = Vec::new();
        for (k, &g) in self.assembled.layout.variables.iter().enumerate() {
            let share = mode.energy_fractions.get(k).copied().unwrap_or(0.0);
            // a variable without kinetic energy in the mode adds nothing to any family
            // (and no family that would win: the largest share is positive)
            if share == 0.0 && !shares.is_empty() {
                continue;
            }
            let family = match self.owner(g) {
                Some((b, entry)) => self.system.bodies[b]
                    .mode_family
                    .as_deref()
                    .unwrap_or(DOF_FAMILIES[entry]),
                None => OTHER_FAMILY,
            };
            match shares.iter_mut().find(|(f, _)| *f == family) {
                Some((_, total)) => *total += share,
                None => shares.push((family, share)),
            }
        }
        shares
            .into_iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .map_or(OTHER_FAMILY, |(f, _)| f)
            .to_string()
    }

    /// Follows the modes of `reference` (a run of the same model at other parameter
    /// values) into this result by the overlap of their shapes: for each of the reference's
    /// modes, in its order, the index into `self.modes.modes` of the mode that continues it
    /// and their overlap (1 for the same shape, 0 for shapes sharing no kinetic energy; see
    /// [`crate::fit::pair_modes_by_overlap`]), or `None` when this result has fewer modes.
    /// Modes keep their identity where they cross in frequency, which sorting by frequency
    /// does not. A reference over other coordinates is an error naming both counts.
    pub fn match_modes(&self, reference: &StageResult) -> Result<Vec<Option<(usize, f64)>>, Error> {
        if reference.modes.coordinates != self.modes.coordinates {
            return Err(Error::Argument {
                function: "StageResult::match_modes",
                argument: "reference",
                expected: format!(
                    "a run over the same {} coordinates",
                    self.modes.coordinates.len()
                ),
                given: format!("{} coordinates", reference.modes.coordinates.len()),
            });
        }
        let pairs = crate::fit::pair_modes_by_overlap(
            &crate::fit::all_shapes(reference),
            &reference.assembled.mass.to_dense(),
            &crate::fit::all_shapes(self),
            &self.assembled.mass.to_dense(),
        )?;
        let mut continued = vec![None; reference.modes.modes.len()];
        for (new, pair) in pairs.into_iter().enumerate() {
            if let Some((old, overlap)) = pair {
                continued[old] = Some((new, overlap));
            }
        }
        Ok(continued)
    }

    /// Lab position (m) of body `b`'s centre of mass at the equilibrium; `None` for an
    /// index past the model's bodies.
    pub fn body_centre(&self, b: BodyId) -> Option<Vector3<f64>> {
        let body = self.system.bodies.get(b)?;
        let frame = body
            .frame
            .try_eval(&self.assembled.equilibrium.coords)
            .ok()?;
        Some(frame.point(&body.centre_of_mass))
    }

    /// The support: the body with the most pose coordinates that are parameters (the
    /// externally driven frame), if any.
    pub fn support(&self) -> Option<BodyId> {
        let driven = |b: &pendkit_system::Body| {
            b.pose_coords
                .iter()
                .flatten()
                .filter(|&&c| self.system.coords[c].kind == CoordKind::Parameter)
                .count()
        };
        (0..self.system.bodies.len())
            .filter(|&b| driven(&self.system.bodies[b]) > 0)
            .max_by_key(|&b| driven(&self.system.bodies[b]))
    }

    /// The test mass: the lowest (at equilibrium) of the bodies with mass that have the
    /// most own degrees of freedom as variables; a rigid body with six beats a bead with
    /// three hanging below it.
    pub fn test_mass(&self) -> Option<BodyId> {
        let own = |b: &pendkit_system::Body| {
            b.pose_coords
                .iter()
                .flatten()
                .filter(|&&c| self.system.coords[c].kind == CoordKind::Variable)
                .count()
        };
        let most = self
            .system
            .bodies
            .iter()
            .filter(|b| b.mass > 0.0)
            .map(own)
            .max()?;
        (0..self.system.bodies.len())
            .filter(|&b| {
                let body = &self.system.bodies[b];
                body.mass > 0.0 && own(body) == most && most > 0
            })
            .filter_map(|b| Some((b, self.body_centre(b)?.z)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(b, _)| b)
    }

    /// The standard transfer functions, as (input, output) names: from the support's
    /// displacement to the test mass's in each degree of freedom both have (L, T, V, R, P,
    /// Y in that order), then from a force (or torque) on the test mass to its displacement
    /// in each of its degrees of freedom.
    pub fn standard_transfer_functions(&self) -> Vec<(String, String)> {
        let Some(tm) = self.test_mass() else {
            return Vec::new();
        };
        // L, T, V, R, P, Y in pose-entry order
        const ORDER: [usize; 6] = [0, 1, 2, 5, 4, 3];
        let coord = |b: BodyId, k: usize| {
            self.system.bodies[b].pose_coords[k].map(|c| self.system.coords[c].name.clone())
        };
        let mut pairs = Vec::new();
        if let Some(support) = self.support() {
            for k in ORDER {
                if let (Some(s), Some(t)) = (coord(support, k), coord(tm, k)) {
                    pairs.push((s, t));
                }
            }
        }
        for k in ORDER {
            if let Some(t) = coord(tm, k) {
                pairs.push((format!("force:{t}"), t));
            }
        }
        pairs
    }

    /// Whether the equilibrium is stable: an error naming the growing mode if not. The
    /// verdict is the run's [`StageResult::stability`] (floats and upside-down bodies
    /// included); this is [`StageResult::check_stable`] under its older name.
    pub fn stability(&self) -> Result<(), Error> {
        self.check_stable()
    }
}
