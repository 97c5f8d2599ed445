//! The one description of the fields a user sets by name: each material constant and each
//! damping field with its unit, its physical domain and what it means. Case files,
//! suspension files, `--set`, the Python package, `params` and the files `fit` writes all
//! read and write these fields through this table, and every build checks the values it
//! holds against their domains, whether or not the command at hand reads them.

pub use pendkit_params::Domain;

/// One settable field: how files and `--set` name it, its SI unit, its domain, its meaning.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Field {
    /// The name files and `--set` use (`specific_heat`, `thermoelastic.tau`).
    pub name: &'static str,
    /// SI unit (`-` for a pure number).
    pub unit: &'static str,
    /// The values it may take.
    pub domain: Domain,
    /// What it is, in a few words.
    pub description: &'static str,
}

impl Field {
    /// `Ok` when `value` lies in the field's domain; otherwise the one-line reason, naming
    /// the field, the value with its unit, and the domain (`specific_heat = -486 J/(kg K)
    /// is outside its domain: must be > 0`).
    pub fn check(&self, value: f64) -> Result<(), String> {
        self.domain
            .check(self.name, self.unit, self.description, value)
    }
}

/// The field called `name` of `fields`.
pub fn find(fields: &'static [Field], name: &str) -> Option<&'static Field> {
    fields.iter().find(|f| f.name == name)
}

/// The names of `fields`, comma separated: what an error about an unknown field lists.
pub fn names(fields: &[Field]) -> String {
    fields.iter().map(|f| f.name).collect::<Vec<_>>().join(", ")
}

/// A material's constants (`[materials.<name>]` in a suspension file).
pub const MATERIAL_FIELDS: &[Field] = &[
    Field {
        name: "youngs_modulus",
        unit: "Pa",
        domain: Domain::Positive,
        description: "Young's modulus",
    },
    Field {
        name: "shear_modulus",
        unit: "Pa",
        domain: Domain::Positive,
        description: "shear modulus",
    },
    Field {
        name: "poisson_ratio",
        unit: "-",
        domain: Domain::Between(-1.0, 0.5),
        description: "Poisson's ratio",
    },
    Field {
        name: "density",
        unit: "kg/m^3",
        domain: Domain::Positive,
        description: "density",
    },
    Field {
        name: "loss_angle",
        unit: "rad",
        domain: Domain::NonNegative,
        description: "structural loss angle",
    },
    Field {
        name: "specific_heat",
        unit: "J/(kg K)",
        domain: Domain::Positive,
        description: "specific heat",
    },
    Field {
        name: "conductivity",
        unit: "W/(m K)",
        domain: Domain::NonNegative,
        description: "thermal conductivity",
    },
    Field {
        name: "thermal_expansion",
        unit: "1/K",
        domain: Domain::Finite,
        description: "linear thermal expansion",
    },
    Field {
        name: "dlnE_dT",
        unit: "1/K",
        domain: Domain::Finite,
        description: "temperature coefficient of Young's modulus d ln E/dT",
    },
    // finite, not >= 0: a material without surface loss has depth 0, and the sensitivities'
    // differences step it both ways (the surface term is linear in it)
    Field {
        name: "dissipation_depth",
        unit: "m",
        domain: Domain::Finite,
        description: "surface-loss dissipation depth",
    },
];

/// The fields of one damping tag (`[damping.<tag>]`, `--set damping.<tag>.<field>=...`).
/// `real` and `imag` may use `f` (Hz); their domain is checked where they are evaluated.
pub const DAMPING_FIELDS: &[Field] = &[
    Field {
        name: "real",
        unit: "-",
        domain: Domain::Finite,
        description: "the real multiplier ε'(f) of the tag's stiffness",
    },
    Field {
        name: "structural",
        unit: "rad",
        domain: Domain::NonNegative,
        description: "a structural (frequency-independent) loss angle",
    },
    Field {
        name: "viscous",
        unit: "rad",
        domain: Domain::NonNegative,
        description: "a viscous loss (its loss angle at 1 Hz)",
    },
    Field {
        name: "imag",
        unit: "rad",
        domain: Domain::Finite,
        description: "any further loss angle ε''(f)",
    },
    Field {
        name: "thermoelastic.delta",
        unit: "-",
        domain: Domain::NonNegative,
        description: "the thermoelastic relaxation strength Δ",
    },
    Field {
        name: "thermoelastic.tau",
        unit: "s",
        domain: Domain::NonNegative,
        description: "the thermoelastic relaxation time τ",
    },
    DAMPING_TEMPERATURE,
];

/// The damping field `temperature`: the tag's own noise temperature.
pub const DAMPING_TEMPERATURE: Field = Field {
    name: "temperature",
    unit: "K",
    domain: Domain::Positive,
    description: "a temperature",
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn domains_refuse_what_the_physics_refuses() {
        let field = |name| find(MATERIAL_FIELDS, name).unwrap();
        assert!(field("density").check(0.0).is_err());
        assert!(field("density").check(2200.0).is_ok());
        assert!(field("loss_angle").check(0.0).is_ok());
        assert!(field("loss_angle").check(-2e-4).is_err());
        assert!(field("poisson_ratio").check(0.5).is_err());
        assert!(field("poisson_ratio").check(-1.0).is_err());
        assert!(field("poisson_ratio").check(0.17).is_ok());
        assert!(field("thermal_expansion").check(-1e-6).is_ok());
        for f in MATERIAL_FIELDS.iter().chain(DAMPING_FIELDS) {
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                assert!(f.check(bad).is_err(), "{} takes {bad}", f.name);
            }
        }
        assert_eq!(
            field("specific_heat").check(-486.0).unwrap_err(),
            "specific_heat = -486 J/(kg K) is outside its domain: specific heat must be > 0"
        );
    }

    #[test]
    fn every_field_name_is_unique() {
        for fields in [MATERIAL_FIELDS, DAMPING_FIELDS] {
            for (i, f) in fields.iter().enumerate() {
                assert!(fields[..i].iter().all(|g| g.name != f.name), "{}", f.name);
            }
        }
    }
}
