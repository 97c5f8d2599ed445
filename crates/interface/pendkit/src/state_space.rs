//! The state space with names in any declared scheme and the unit of every state, input
//! and output, and (behind the `export` feature) written to a file with its provenance.

use pendkit_dynamics::StateSpace;

#[cfg(feature = "export")]
use crate::stage::Provenance;
use crate::{Error, StageResult};

/// A state space with the units of its states, inputs and outputs.
#[derive(Clone, Debug)]
pub struct NamedStateSpace {
    /// The matrices and names (names in the scheme asked for).
    pub state_space: StateSpace,
    /// Unit of each state: `m` or `rad`, then `m/s` or `rad/s` for the rates.
    pub state_units: Vec<String>,
    /// Unit of each input: `m` or `rad` for support displacements, `N` or `N m` for forces.
    pub input_units: Vec<String>,
    /// Unit of each output: `m` or `rad`, then `N` or `N m` for forces on the support.
    pub output_units: Vec<String>,
}

impl StageResult {
    /// The state space (damping represented as viscous at `damping_frequency`, Hz) with
    /// names in `scheme` (e.g. `ligo`: `L3_P`, `L3_P_dot`, `GND_L`, `force:L3_L`) or the
    /// model's own names, and the unit of each state, input and output (empty where a
    /// coordinate is no body's own degree of freedom).
    pub fn named_state_space(
        &self,
        damping_frequency: f64,
        scheme: Option<&str>,
    ) -> Result<NamedStateSpace, Error> {
        let mut ss = self
            .model
            .state_space(&self.system.damping, damping_frequency)?;
        let unit = |name: &str| self.coordinate_unit(name).unwrap_or_default().to_string();
        let state_units = ss
            .states
            .iter()
            .map(|s| match s.strip_suffix("_dot") {
                Some(base) if self.system.coord(s).is_none() => self
                    .coordinate_unit(base)
                    .map_or(String::new(), |u| format!("{u}/s")),
                _ => unit(s),
            })
            .collect();
        let input_units = ss
            .inputs
            .iter()
            .map(|i| self.input_unit(i).unwrap_or_default())
            .collect();
        let output_units = ss
            .outputs
            .iter()
            .map(|o| self.output_unit(o).unwrap_or_default())
            .collect();
        if let Some(scheme) = scheme {
            let names = self.name_scheme(scheme)?;
            let rename = |n: &String| -> String {
                if let Some(base) = n.strip_prefix("force:") {
                    return format!("force:{}", names.coord(base));
                }
                match n.strip_suffix("_dot") {
                    Some(base) if self.system.coord(n).is_none() => {
                        format!("{}_dot", names.coord(base))
                    }
                    _ => names.coord(n).to_string(),
                }
            };
            for list in [&mut ss.states, &mut ss.inputs, &mut ss.outputs] {
                *list = list.iter().map(rename).collect();
            }
        }
        Ok(NamedStateSpace {
            state_space: ss,
            state_units,
            input_units,
            output_units,
        })
    }

    /// Writes the state space to `path` (`.mat`, `.npz` or `.json`, by the extension):
    /// `A B C D`, the names `states inputs outputs` and their units `state_units
    /// input_units output_units`, and the provenance: `model`, `case_name` (`case` is a MATLAB keyword), `stage`,
    /// `naming`, `pendkit_version` (one-item string lists), `damping_frequency_hz` (1 x 1),
    /// and the resolved parameters `parameter_names`, `parameter_values` (n x 1) and
    /// `parameter_units` (empty where the model declares none). The file is written whole
    /// or not at all (a temporary file renamed into place); an existing file is refused
    /// unless `options.overwrite`.
    #[cfg(feature = "export")]
    pub fn write_state_space(
        &self,
        path: &std::path::Path,
        damping_frequency: f64,
        scheme: Option<&str>,
        provenance: &Provenance,
        options: &pendkit_export::WriteOptions,
    ) -> Result<NamedStateSpace, Error> {
        use pendkit_export::{Matrix, Metadata, Names};
        let named = self.named_state_space(damping_frequency, scheme)?;
        let ss = &named.state_space;
        let rows = |m: &nalgebra::DMatrix<f64>| -> Vec<f64> {
            (0..m.nrows())
                .flat_map(|i| (0..m.ncols()).map(move |j| m[(i, j)]))
                .collect()
        };
        let data = [rows(&ss.a), rows(&ss.b), rows(&ss.c), rows(&ss.d)];
        let matrices: Vec<Matrix> = [("A", &ss.a), ("B", &ss.b), ("C", &ss.c), ("D", &ss.d)]
            .iter()
            .zip(&data)
            .map(|((name, m), d)| Matrix {
                name,
                rows: m.nrows(),
                cols: m.ncols(),
                data: d,
            })
            .collect();
        let names = [
            Names {
                name: "states",
                items: &ss.states,
            },
            Names {
                name: "inputs",
                items: &ss.inputs,
            },
            Names {
                name: "outputs",
                items: &ss.outputs,
            },
        ];
        let mut meta = Metadata::new();
        meta.text("state_units", named.state_units.clone())
            .text("input_units", named.input_units.clone())
            .text("output_units", named.output_units.clone());
        provenance.add_to(&mut meta, self.assembled.stage.name(), scheme);
        meta.numbers("damping_frequency_hz", vec![damping_frequency]);
        pendkit_export::write_with_metadata(path, &matrices, &names, &meta, options)
            .map_err(Error::Export)?;
        Ok(named)
    }
}

#[cfg(feature = "export")]
impl Provenance {
    /// Adds `model`, `case_name` (`case` is a MATLAB keyword), `stage`, `naming`, `pendkit_version` and the parameters to an
    /// export's metadata.
    pub fn add_to(&self, meta: &mut pendkit_export::Metadata, stage: &str, scheme: Option<&str>) {
        meta.text("model", vec![self.model.clone()])
            .text("case_name", vec![self.case.clone()])
            .text("stage", vec![stage.to_string()])
            .text("naming", vec![scheme.unwrap_or("model").to_string()])
            .text("pendkit_version", vec![crate::VERSION.to_string()])
            .text(
                "parameter_names",
                self.parameters.iter().map(|p| p.name.clone()).collect(),
            )
            .numbers(
                "parameter_values",
                self.parameters.iter().map(|p| p.value).collect(),
            )
            .text(
                "parameter_units",
                self.parameters
                    .iter()
                    .map(|p| p.unit.clone().unwrap_or_default())
                    .collect(),
            );
    }
}
