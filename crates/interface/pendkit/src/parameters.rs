//! What `pendkit params` lists: every parameter of a case with its value, unit, description
//! and the parts of the model that read it.

use pendkit_model::{Defaults, ParameterInfo, parameters_with};

use crate::{Case, Error};

/// One parameter of a case.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ParameterRow {
    /// Name.
    pub name: String,
    /// Value at the case's settings, in `unit`.
    pub value: f64,
    /// Unit (empty for a pure number or when the model declares none).
    pub unit: String,
    /// The values it may take (`> 0`, `>= 0`, `in (-1, 0.5)`), empty when the model
    /// declares none.
    pub domain: String,
    /// The definition: a number or an expression of other parameters.
    pub definition: String,
    /// What it is (empty when the model says nothing).
    pub description: String,
    /// The parts of the model that read it (`bodies.top.mass`, `stages.uim.wires.length`,
    /// `damping.fibre_bending`), in the order first read.
    pub read_by: Vec<String>,
}

/// Every parameter of `case`, in definition order: value with the case's overrides, unit,
/// definition, and what the model says about it ([`pendkit_model::Model::parameter_info`]).
/// The bundled models are suspension files, which say all of it.
pub fn parameter_table(case: &Case) -> Result<Vec<ParameterRow>, Error> {
    // the case is built as every command builds it, so that the values `params` lists are
    // ones every other command accepts (a damping field outside its domain is refused here
    // too, though the table shows no damping)
    case.build()?;
    let defaults = Defaults::of(&*case.model)?;
    let (params, resolved) = parameters_with(&defaults, &case.overrides)?;
    let info = case.model.parameter_info(&resolved)?;
    let about = |name: &str| -> Option<&ParameterInfo> { info.iter().find(|i| i.name == name) };
    Ok(resolved
        .iter()
        .map(|(name, value)| {
            let known = about(name);
            ParameterRow {
                name: name.to_string(),
                value,
                unit: params
                    .unit(name)
                    .map(str::to_string)
                    .or_else(|| known.map(|i| i.unit.clone()))
                    .unwrap_or_default(),
                domain: params
                    .domain(name)
                    .map(|d| d.describe())
                    .unwrap_or_default(),
                definition: params
                    .get(name)
                    .map(|d| d.source.clone())
                    .unwrap_or_default(),
                description: known.map(|i| i.description.clone()).unwrap_or_default(),
                read_by: known.map(|i| i.read_by.clone()).unwrap_or_default(),
            }
        })
        .collect())
}
