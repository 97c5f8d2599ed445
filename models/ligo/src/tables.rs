//! The public parameter tables (in `models/ligo/params/`, kept as published): the aLIGO quad's 2005 set
//! and the materials' loss and thermal constants, read into parameter definitions.

use pendkit_params::{ParamError, ParamSet};

/// `params/quad2005.csv`: the aLIGO quad, 2005 design (LIGO quad parameter file 'quadopt'
/// v14, May 2005).
pub const QUAD2005: &str = include_str!("../params/quad2005.csv");

/// `params/materials.csv`: fused silica, C70 steel wire, maraging-steel blades.
pub const MATERIALS: &str = include_str!("../params/materials.csv");

/// Rows of quad2005.csv that were derived from the others and rounded: kept out of the
/// parameter set (the model computes them exactly) and used by the tests as cross-checks.
pub const QUAD_DERIVED: [&str; 11] = [
    "tln", "tl1", "tl2", "tl3", "kcn", "kc1", "kc2", "kwn", "kw1", "kw2", "kw3",
];

/// (name, value) rows of a `name,value,...` table, skipping comments and the header.
pub fn rows(table: &str) -> impl Iterator<Item = (&str, &str)> {
    table
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .filter_map(|l| {
            let mut fields = l.split(',');
            Some((fields.next()?.trim(), fields.next()?.trim()))
        })
}

/// Defines every non-derived row of quad2005.csv, with the unit of its `unit` column (`-`,
/// a count or a pure number, becomes no unit).
pub fn define_quad(set: &mut ParamSet) -> Result<(), ParamError> {
    for (name, value) in rows(QUAD2005) {
        if !QUAD_DERIVED.contains(&name) {
            set.define(name, value)?;
        }
    }
    for (name, unit) in units(QUAD2005) {
        if set.contains(name) {
            set.set_unit(name, if unit == "-" { "" } else { unit })?;
        }
    }
    Ok(())
}

/// (name, unit) rows of a `name,value,unit,...` table.
fn units(table: &str) -> impl Iterator<Item = (&str, &str)> {
    table
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .filter_map(|l| {
            let mut fields = l.split(',');
            let name = fields.next()?.trim();
            Some((name, fields.nth(1)?.trim()))
        })
}

/// Units of the materials table's columns (its header spells them `rho_kg_m3`, ...).
const MATERIAL_UNITS: [(&str, &str); 7] = [
    ("rho", "kg/m^3"),
    ("C", "J/(kg K)"),
    ("K", "W/(m K)"),
    ("alpha", "1/K"),
    ("dlnE_dT", "1/K"),
    ("phi", "rad"),
    ("Y", "Pa"),
];

/// Short prefix of each material's parameters.
const MATERIAL_PREFIX: [(&str, &str); 3] = [
    ("fused_silica", "silica"),
    ("c70_steel_wire", "steel"),
    ("maraging_steel_blade", "maraging"),
];

/// Defines `<m>_rho, <m>_C, <m>_K, <m>_alpha, <m>_dlnE_dT, <m>_phi, <m>_Y` for the
/// materials (m = silica, steel, maraging), in SI units as in the table's header.
pub fn define_materials(set: &mut ParamSet) -> Result<(), ParamError> {
    let columns = ["rho", "C", "K", "alpha", "dlnE_dT", "phi", "Y"];
    for line in MATERIALS.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let Some((_, prefix)) = MATERIAL_PREFIX.iter().find(|(name, _)| *name == fields[0]) else {
            continue;
        };
        for (column, value) in columns.iter().zip(&fields[1..]) {
            let name = format!("{prefix}_{column}");
            set.define(&name, value)?;
            if let Some((_, unit)) = MATERIAL_UNITS.iter().find(|(c, _)| c == column) {
                set.set_unit(&name, unit)?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn all_rows_become_parameters() {
        let mut set = ParamSet::new();
        define_quad(&mut set).unwrap();
        define_materials(&mut set).unwrap();
        let r = set.resolve().unwrap();
        assert_eq!(r.get("m3").unwrap(), 39.6);
        assert_eq!(r.get("l1").unwrap(), 0.3085);
        assert_eq!(r.get("silica_phi").unwrap(), 4.1e-10);
        assert_eq!(r.get("maraging_Y").unwrap(), 1.87e11);
        assert!(r.get("tln").is_err());
        // units from the tables' unit column and header
        assert_eq!(set.unit("m3"), Some("kg"));
        assert_eq!(set.unit("I3x"), Some("kg m^2"));
        assert_eq!(set.unit("nwn"), Some(""));
        assert_eq!(set.unit("silica_Y"), Some("Pa"));
    }
}
