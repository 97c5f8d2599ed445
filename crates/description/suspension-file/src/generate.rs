//! Suspension files written by a program: `chain`, any number of identical rigid bodies one
//! below the other, each on four vertical steel wires (`pendkit chain-file N`;
//! the bundled `chain` rewrites itself for its parameter `n_stages`). Written with
//! [`Writer`], so a generated file comes with its tree and is read without a parser.

use crate::source::FileError;
use crate::writer::{Item, Writer, Written};

/// Largest number of stages of the bundled `chain`'s parameter `n_stages`: 1200 variables,
/// where the dense eigen-solves of every mode already take seconds (their cost grows as the
/// cube of the size).
pub const MAX_CHAIN_STAGES: usize = 200;

/// Largest number of stages [`chain`] writes (`pendkit chain-file N`): 60 000 variables,
/// the scaling benchmarks' largest chain, whose equilibrium and lowest modes take the
/// sparse paths (a run needs the coordinate, wire and body limits raised).
pub const MAX_GENERATED_STAGES: usize = 10_000;

/// The chain's parameters: name, value as written, unit, description.
const CHAIN_PARAMETERS: [(&str, &str, &str, &str); 15] = [
    ("g", "9.81", "m/s^2", "gravitational acceleration"),
    (
        "m",
        "40",
        "kg",
        "mass of each body (the rigid-body model's)",
    ),
    ("Ix", "0.57", "kg m^2", "moment of inertia about x (roll)"),
    ("Iy", "0.42", "kg m^2", "moment of inertia about y (pitch)"),
    ("Iz", "0.42", "kg m^2", "moment of inertia about z (yaw)"),
    (
        "l_wire",
        "0.6",
        "m",
        "wire length between attachment points (the small models')",
    ),
    (
        "a_wire",
        "0.005",
        "m",
        "half x-separation of the wires (the rigid-body model's fibres)",
    ),
    (
        "b_wire",
        "0.17",
        "m",
        "half y-separation of the wires (the body's radius)",
    ),
    (
        "d_top",
        "0.010",
        "m",
        "height of the wires from above over a body's centre of mass (the rigid-body model's break-off: low, stable pitch modes)",
    ),
    (
        "d_bottom",
        "0.010",
        "m",
        "depth of the wires to the body below under a body's centre of mass",
    ),
    ("r_wire", "0.5e-3", "m", "wire radius (music wire)"),
    ("E_wire", "212e9", "Pa", "Young's modulus of steel"),
    ("nu_wire", "0.29", "-", "Poisson's ratio of steel"),
    ("rho_wire", "7800", "kg/m^3", "density of steel"),
    (
        "phi_wire",
        "1e-7",
        "rad",
        "loss angle of the wires (as the small models' fibres, so that the models compare)",
    ),
];

/// Why the chain's wires are what they are (written above `r_wire`).
const WIRE_NOTE: &str =
    "The double pendulum's steel wires. A wire of stage k carries (N - k + 1) m g / 4: 0.5 GPa
at the top of a 4-stage chain, a third of a music wire's breaking stress. Long chains
overload their top wires (12.5 GPa at 100 stages); the model stays linear-elastic, which is
what a scaling benchmark needs, but it is then no design.";

fn strs(items: &[&str]) -> Item {
    Item::Array(items.iter().map(|s| Item::str(*s)).collect())
}

/// An `n`-stage chain (text and tree): the rigid-body model's 40 kg body, `n` times, each on
/// four vertical 0.6 m steel wires (the double pendulum's) at (±a, ±b), `d_top` above its
/// centre of mass to the body above and `d_bottom` below it to the body below. Exactly
/// symmetric (every wire vertical, bodies level and centred on the z axis), so the stiffness
/// splits into the x–pitch, y–roll, z and yaw blocks with exact zeros between them. `n`
/// from 1 to [`MAX_GENERATED_STAGES`], or an error saying so (before anything is written).
pub fn chain(n: usize) -> Result<Written, FileError> {
    if !(1..=MAX_GENERATED_STAGES).contains(&n) {
        return Err(FileError::file(
            "chain",
            format!("{n} stages: a chain has 1 to {MAX_GENERATED_STAGES}"),
        ));
    }
    let mut w = Writer::new();
    w.comment(&format!(
        "{n}-stage chain, written by `pendkit chain-file {n}`: a suspension
whose size is a parameter of its generator, for scaling benchmarks (6 variables and
4 wires per stage). Edit freely; docs/suspension-files.md describes every field."
    ));
    w.entry("name", Item::str("chain"));
    w.entry(
        "summary",
        Item::str(format!(
            "{n} 40 kg bodies in a vertical chain, each on 4 vertical steel wires"
        )),
    );
    w.entry("gravity", Item::str("g"));
    w.blank();
    w.section(&["parameters"]);
    for (name, value, unit, description) in CHAIN_PARAMETERS {
        if name == "r_wire" {
            w.comment(WIRE_NOTE);
        }
        w.entry(
            name,
            Item::Inline(vec![
                ("value".into(), Item::num(value)),
                ("unit".into(), Item::str(unit)),
                ("description".into(), Item::str(description)),
            ]),
        );
    }
    w.blank();
    w.section(&["materials", "steel"]);
    for (field, parameter) in [
        ("youngs_modulus", "E_wire"),
        ("poisson_ratio", "nu_wire"),
        ("density", "rho_wire"),
        ("loss_angle", "phi_wire"),
    ] {
        w.entry(field, Item::str(parameter));
    }
    w.blank();
    w.section(&["bodies", "support"]);
    w.entry("coordinates", Item::str("00"));
    w.entry("driven", Item::Bool(true));
    for k in 1..=n {
        let body = format!("mass{k}");
        w.blank();
        w.section(&["bodies", &body]);
        w.entry("coordinates", Item::str(k.to_string()));
        w.entry("mass", Item::str("m"));
        w.entry("inertia", strs(&["Ix", "Iy", "Iz"]));
    }
    for k in 1..=n {
        let body = format!("mass{k}");
        // the top wires hang from the support's origin, the others from under the body above
        let (from, upper_z) = if k == 1 {
            ("support".to_string(), Item::num("0"))
        } else {
            (format!("mass{}", k - 1), Item::str("-d_bottom"))
        };
        let end = |z: Item| {
            Item::Inline(vec![
                (
                    "at".into(),
                    Item::Array(vec![Item::str("a_wire"), Item::str("b_wire"), z]),
                ),
                ("mirror".into(), strs(&["y", "x"])),
            ])
        };
        w.blank();
        w.section(&["stages", &body]);
        w.entry("from", Item::str(from));
        w.section(&["stages", &body, "wires"]);
        w.entry("name", Item::str(format!("wire{k}_")));
        w.entry("upper", end(upper_z));
        w.entry("lower", end(Item::str("d_top")));
        w.entry("length", Item::str("l_wire"));
        w.entry("radius", Item::str("r_wire"));
        w.entry("material", Item::str("steel"));
        w.entry("tags", Item::str("wire"));
    }
    Ok(w.finish(&format!("chain-{n}.toml")))
}

#[cfg(all(test, feature = "toml"))]
mod tests {
    use super::*;

    /// A TOML reader reads the generated text as the same suspension: the spec read from the
    /// parsed text builds the same system as the one read from the writer's tree.
    #[test]
    fn the_written_tree_is_what_the_text_says() {
        use pendkit_model::{Overrides, build_with};
        let written = chain(3).unwrap();
        let from_text =
            crate::Suspension::from_text("c.toml", &written.source.text, &crate::NoLibrary)
                .unwrap();
        let from_tree = crate::Suspension::from_tree(
            written.source.clone(),
            written.root.clone(),
            &crate::NoLibrary,
        )
        .unwrap();
        let (a, _) = build_with(&from_text, &Overrides::default()).unwrap();
        let (b, _) = build_with(&from_tree, &Overrides::default()).unwrap();
        assert_eq!(format!("{a:?}"), format!("{b:?}"));
    }
}
