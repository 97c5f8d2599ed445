//! What an instance of an element kind needs: its value fields (name, SI unit, domain,
//! default, meaning) and how many bodies and points it connects. A kind that owns instances
//! declares one ([`Element::instance_schema`](crate::Element::instance_schema)); every
//! instance is checked against it before any term is built ([`check_plugin_elements`]), so a
//! kind reads its values without checking them again.

use pendkit_expr::number_text;
pub use pendkit_params::Domain;
use pendkit_rotations::Real;

use crate::{EnergyError, PluginElement, System, find_kind, registry};

/// One value an instance gives (`values = { k = "k_magnet" }` in a suspension file).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValueField {
    /// The name instances use (`k`).
    pub name: &'static str,
    /// SI unit (`N/m`; `-` for a pure number).
    pub unit: &'static str,
    /// The values it may physically take.
    pub domain: Domain,
    /// The value taken when an instance gives none; `None`: the field is required.
    pub default: Option<f64>,
    /// What it is, in one line.
    pub description: &'static str,
}

impl ValueField {
    /// `Ok` when `value` lies in the field's domain; otherwise the reason, naming the field,
    /// the value with its unit and the domain (`k = NaN N/m is not a finite number`).
    pub fn check(&self, value: f64) -> Result<(), String> {
        self.domain
            .check(self.name, self.unit, self.description, value)
    }

    /// The field in short: `k (N/m, finite, required)`.
    pub fn short(&self) -> String {
        let need = self.default.map_or("required".to_string(), |d| {
            format!("default {}", number_text(d))
        });
        format!(
            "{} ({}, {}, {need})",
            self.name,
            self.unit,
            self.domain.describe()
        )
    }

    /// The field as one line of a listing: `k (N/m, finite, required): stiffness`.
    pub fn describe(&self) -> String {
        format!("{}: {}", self.short(), self.description)
    }
}

/// What an instance of a kind needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceSchema {
    /// How many bodies an instance connects (`between` in a suspension file).
    pub bodies: usize,
    /// How many points (m, each in its body's coordinates) an instance gives: one per body
    /// ([`PluginElement`] carries one point per body), or none for a kind that reads none.
    pub points: usize,
    /// The values, in the order a listing shows them.
    pub values: &'static [ValueField],
}

/// What is wrong with an instance against its kind's schema ([`InstanceSchema::check`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Misfit {
    /// The part of the instance that is wrong.
    pub part: Part,
    /// What is wrong, and what the kind accepts, in one line.
    pub message: String,
}

impl std::fmt::Display for Misfit {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.message)
    }
}

/// A part of an instance (where a suspension file places a [`Misfit`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Part {
    /// The bodies it connects (how many).
    Bodies,
    /// Its points (how many).
    Points,
    /// The values as a whole (a required one missing).
    Values,
    /// The value called so (unknown to the kind, or outside its field's domain).
    Value(String),
}

impl InstanceSchema {
    /// The value field called `name`.
    pub fn field(&self, name: &str) -> Option<&'static ValueField> {
        self.values.iter().find(|f| f.name == name)
    }

    /// What the kind accepts, in one line: `2 bodies, 2 points, values k (N/m, finite,
    /// required)`.
    pub fn accepts(&self) -> String {
        let values = if self.values.is_empty() {
            "no values".to_string()
        } else {
            let list: Vec<String> = self.values.iter().map(ValueField::short).collect();
            format!("values {}", list.join(", "))
        };
        format!("{} bodies, {} points, {values}", self.bodies, self.points)
    }

    /// The first thing wrong with `element` against this schema: the number of bodies or
    /// points, a value the kind does not know, a required value missing, a value outside its
    /// field's domain. Values with a default may be missing (the kind reads the default,
    /// [`InstanceSchema::value`]); the message lists what the kind accepts, and the misfit
    /// says which part of the instance is wrong, so that a suspension file can place it.
    pub fn check<S: Real>(&self, element: &PluginElement<S>) -> Result<(), Misfit> {
        let misfit = |part: Part, what: String| Misfit {
            part,
            message: format!("{what} (it takes {})", self.accepts()),
        };
        if element.bodies.len() != self.bodies {
            return Err(misfit(
                Part::Bodies,
                format!("needs {} bodies, got {}", self.bodies, element.bodies.len()),
            ));
        }
        if element.points.len() != self.points {
            return Err(misfit(
                Part::Points,
                format!("needs {} points, got {}", self.points, element.points.len()),
            ));
        }
        if let Some(name) = element.values.keys().find(|n| self.field(n).is_none()) {
            return Err(misfit(
                Part::Value(name.clone()),
                format!("unknown value '{name}'"),
            ));
        }
        for field in self.values {
            match element.values.get(field.name) {
                Some(v) => field
                    .check(v.re())
                    .map_err(|e| misfit(Part::Value(field.name.to_string()), e))?,
                None if field.default.is_none() => {
                    return Err(misfit(
                        Part::Values,
                        format!(
                            "needs the value '{}' ({}, {})",
                            field.name, field.unit, field.description
                        ),
                    ));
                }
                None => {}
            }
        }
        Ok(())
    }

    /// The value `name` of `element`, or the field's default when the instance gives none
    /// (after [`InstanceSchema::check`], every field has one or the other). A name the
    /// schema does not have, or a required value missing, reads as NaN (a kind asks only for
    /// its own fields, of checked instances).
    pub fn value<S: Real>(&self, element: &PluginElement<S>, name: &str) -> S {
        element.values.get(name).copied().unwrap_or_else(|| {
            S::from(self.field(name).and_then(|f| f.default).unwrap_or(f64::NAN))
        })
    }

    /// `element` with every missing value that has a default set to it (what a suspension
    /// file's instance holds once built).
    pub fn fill_defaults<S: Real>(&self, element: &mut PluginElement<S>) {
        for field in self.values {
            if let Some(d) = field.default {
                element
                    .values
                    .entry(field.name.to_string())
                    .or_insert_with(|| S::from(d));
            }
        }
    }
}

/// Checks every plug-in element instance of `system` before any term is built: its kind is
/// registered, owns instances (declares an [`InstanceSchema`]) and the instance fits it.
/// The first problem names the instance, its kind and what the kind accepts.
pub fn check_plugin_elements<S: Real>(system: &System<S>) -> Result<(), EnergyError> {
    for e in &system.plugin_elements {
        let Some(kind) = find_kind(&e.kind) else {
            return Err(EnergyError::UnknownKind {
                element: e.name.clone(),
                kind: e.kind.clone(),
                known: registry()
                    .iter()
                    .map(|k| k.kind())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        };
        let fail = |message: String| EnergyError::Element {
            kind: kind.kind(),
            element: e.name.clone(),
            message,
        };
        let Some(schema) = kind.instance_schema() else {
            return Err(fail(format!(
                "the kind owns no instances (it acts on every wire of a stage; kinds with instances: {})",
                kinds_with_instances()
            )));
        };
        schema.check(e).map_err(|m| fail(m.message))?;
        kind.check_instance(&|name| schema.value(e, name).re())
            .map_err(fail)?;
    }
    Ok(())
}

/// The registered kinds that own instances, comma separated.
pub fn kinds_with_instances() -> String {
    let names: Vec<&str> = registry()
        .iter()
        .filter(|k| k.instance_schema().is_some())
        .map(|k| k.kind())
        .collect();
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SCHEMA: InstanceSchema = InstanceSchema {
        bodies: 1,
        points: 0,
        values: &[
            ValueField {
                name: "k",
                unit: "N/m",
                domain: Domain::Positive,
                default: None,
                description: "stiffness",
            },
            ValueField {
                name: "q",
                unit: "-",
                domain: Domain::Finite,
                default: Some(2.0),
                description: "quality",
            },
        ],
    };

    fn instance(values: &[(&str, f64)]) -> PluginElement<f64> {
        PluginElement {
            kind: "test".into(),
            name: "one".into(),
            bodies: vec![0],
            points: Vec::new(),
            values: values.iter().map(|&(n, v)| (n.to_string(), v)).collect(),
            tag: "one".into(),
        }
    }

    #[test]
    fn each_misfit_names_its_part_and_what_the_kind_takes() {
        assert_eq!(SCHEMA.check(&instance(&[("k", 1.0)])), Ok(()));
        let part = |values: &[(&str, f64)]| SCHEMA.check(&instance(values)).unwrap_err().part;
        assert_eq!(part(&[]), Part::Values);
        assert_eq!(part(&[("k", 1.0), ("c", 1.0)]), Part::Value("c".into()));
        let out = SCHEMA.check(&instance(&[("k", -1.0)])).unwrap_err();
        assert_eq!(out.part, Part::Value("k".into()));
        assert!(
            out.message.starts_with("k = -1 N/m is outside its domain"),
            "{out}"
        );
        assert!(
            out.message.ends_with(
                "(it takes 1 bodies, 0 points, values k (N/m, > 0, required), \
                 q (-, finite, default 2))"
            ),
            "{out}"
        );
    }

    #[test]
    fn a_missing_value_reads_its_default() {
        let mut e = instance(&[("k", 1.0)]);
        assert_eq!(SCHEMA.value(&e, "q"), 2.0);
        SCHEMA.fill_defaults(&mut e);
        assert_eq!(e.values["q"], 2.0);
    }
}
