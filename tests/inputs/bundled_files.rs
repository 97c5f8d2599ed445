//! The bundled models, which are suspension files (models/), against the independent
//! references the Rust tables they replaced were written from. The physics of each model
//! (equilibria, modes, transfer functions) is pinned by its own tests: tests/quad.rs and
//! tests/triple.rs (every variant: nominal equilibrium, blocks, limits, convergence of the
//! variants, violin modes), tests/chain.rs (closed forms), tests/oracles_*.rs (toy, pendulum,
//! double pendulum, rigid body). What those do not pin is checked here:
//!
//! - the quad's numbers are the published 2005 table, `models/ligo/params/quad2005.csv`, row
//!   for row with its units, and the materials are `models/ligo/params/materials.csv`;
//! - the quad's and the triple's default damping is the loss formula of LIGO's noise budget
//!   (structural φ, and on bending the thermoelastic peak with the stress term), evaluated
//!   here from the tables' numbers;
//! - `chain` with `n_stages = N` is the file `pendkit chain-file N` writes.

use pendkit::{Case, Stage, run_stage};
use pendkit_model::{Defaults, Model, Overrides, parameters_with};

const PI: f64 = std::f64::consts::PI;

fn model(name: &str) -> std::sync::Arc<dyn Model> {
    pendkit::catalogue::find_model(name).unwrap()
}

/// The rows (name, value, unit) of a `name,value,unit,...` table, skipping comments.
fn rows(table: &str) -> Vec<(String, f64, String)> {
    table
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').map(str::trim).collect();
            (f[0].to_string(), f[1].parse().unwrap(), f[2].to_string())
        })
        .collect()
}

fn table(file: &str) -> String {
    std::fs::read_to_string(format!(
        "{}/../models/ligo/params/{file}",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// Rows of quad2005.csv derived from the others and printed rounded (tests/quad.rs checks
/// them against the exact values), and the wire counts and damping switch the file's
/// structure stands for.
const DERIVED_OR_STRUCTURE: [&str; 16] = [
    "tln", "tl1", "tl2", "tl3", "kcn", "kc1", "kc2", "kwn", "kw1", "kw2", "kw3", "nwn", "nw1",
    "nw2", "nw3", "bd",
];

/// Every other row of the published table is a parameter of every quad of 2005 with the
/// same value (parsed from the same decimal: exact) and unit.
#[test]
fn the_quads_are_the_published_2005_table() {
    let published = rows(&table("quad2005.csv"));
    assert!(published.len() > 60, "{} rows", published.len());
    for name in ["quad", "quad-lite", "quad-full", "quad-lateral", "quad-v5"] {
        let (params, values) =
            parameters_with(&Defaults::of(&*model(name)).unwrap(), &Overrides::default()).unwrap();
        for (row, value, unit) in published
            .iter()
            .filter(|(n, _, _)| !DERIVED_OR_STRUCTURE.contains(&n.as_str()))
        {
            let got = values
                .get(row)
                .unwrap_or_else(|e| panic!("{name}: {row}: {e}"));
            assert_eq!(got, *value, "{name}: {row}");
            // a pure number's unit `-` reads as no unit
            let unit = if unit == "-" { "" } else { unit.as_str() };
            assert_eq!(
                params.unit(row).unwrap_or(""),
                unit,
                "{name}: unit of {row}"
            );
        }
    }
}

/// The materials table's columns are the parameters `<m>_<column>` (an empty dissipation
/// depth, no surface loss known, is 0), exactly.
#[test]
fn the_materials_are_the_published_table() {
    let text = table("materials.csv");
    let (_, values) = parameters_with(
        &Defaults::of(&*model("quad")).unwrap(),
        &Overrides::default(),
    )
    .unwrap();
    let columns = ["rho", "C", "K", "alpha", "dlnE_dT", "phi", "Y", "dissdepth"];
    let mut checked = 0;
    for line in text.lines().filter(|l| !l.starts_with('#')).skip(1) {
        let f: Vec<&str> = line.split(',').map(str::trim).collect();
        let prefix = match f[0] {
            "fused_silica" => "silica",
            "c70_steel_wire" => "steel",
            "maraging_steel_blade" => "maraging",
            _ => continue,
        };
        for (column, text) in columns.iter().zip(&f[1..]) {
            let expected = if text.is_empty() {
                0.0
            } else {
                text.parse().unwrap()
            };
            let name = format!("{prefix}_{column}");
            assert_eq!(values.get(&name).unwrap(), expected, "{name}");
            checked += 1;
        }
    }
    assert_eq!(checked, 24);
}

/// The loss angle of a wire set's bending at `f` Hz: structural φ plus the thermoelastic
/// peak (Cagnoli & Willems, PRB 65, 174111 (2002), with the stress term; docs/reference-values.md §7)
/// Δ ωτ/(1 + ω²τ²), Δ = (E T/ρC)(α − σβ/E)², τ = ρ C (2r)²/(2.16 · 2π K), σ = tension/πr².
/// `m` = (φ, ρ, C, K, α, β) of the material.
fn bending_loss(f: f64, m: [f64; 6], e: f64, r: f64, tension: f64) -> f64 {
    let [phi, rho, c, k, alpha, beta] = m;
    let sigma = tension / (PI * r * r);
    let delta = e * 290.0 / (rho * c) * (alpha - sigma * beta / e).powi(2);
    let tau = rho * c * (2.0 * r).powi(2) / (2.16 * 2.0 * PI * k);
    let wt = 2.0 * PI * f * tau;
    phi + delta * wt / (1.0 + wt * wt)
}

/// The quad's damping from quad2005.csv and materials.csv: each wire set's bending with its
/// own tension (the weight below shared by its wires, along the wire), stretch and torsion
/// structural, the blades the maraging φ. Tolerance 1e-12: the same formula, evaluated in
/// another order.
#[test]
fn the_quads_damping_is_the_noise_budget_formula() {
    let case = Case::model("quad").unwrap();
    let (system, _) = case.build().unwrap();
    let silica = [4.1e-10, 2200.0, 772.0, 1.38, 3.9e-7, 1.52e-4];
    let steel = [2e-4, 7800.0, 486.0, 49.0, 12e-6, -2.5e-4];
    let g = 9.81;
    let (mn, m1, m2, m3) = (22.11, 22.011, 39.6, 39.6);
    let slope = |l: f64, dy: f64| l / (l * l - dy * dy).sqrt();
    // (tag, material, Young's modulus, radius, tension): quad2005.csv's rows; the wire sets'
    // spans differ in y by nn0 - nn1, n0 - n1, n2 - n3, n4 - n5
    let sets = [
        (
            "wn",
            steel,
            220e9,
            0.00054,
            (mn + m1 + m2 + m3) * g / 2.0 * slope(0.445, 0.25 - 0.09),
        ),
        (
            "w1",
            steel,
            220e9,
            0.00035,
            (m1 + m2 + m3) * g / 4.0 * slope(0.3085, 0.2 - 0.06),
        ),
        (
            "w2",
            steel,
            220e9,
            0.00031,
            (m2 + m3) * g / 4.0 * slope(0.341, 0.14 - 0.1762),
        ),
        (
            "fibre",
            silica,
            70e9,
            0.0002,
            m3 * g / 4.0 * slope(0.6, 0.1712 - 0.1712),
        ),
    ];
    for f in [0.3, 10.0, 300.0] {
        for (set, material, e, r, tension) in sets {
            let expected = bending_loss(f, material, e, r, tension);
            let (re, im) = system.damping.at(&format!("{set}_bending"), f);
            assert_eq!(re, 1.0, "{set}");
            assert!(
                (im - expected).abs() <= 1e-12 * expected,
                "{set}_bending at {f} Hz: {im} vs {expected}"
            );
            for part in ["stretch", "torsion"] {
                let (_, im) = system.damping.at(&format!("{set}_{part}"), f);
                assert!(
                    (im - material[0]).abs() <= 1e-15 * material[0],
                    "{set}_{part}"
                );
            }
        }
        for blade in ["blade_n", "blade_1", "blade_2"] {
            assert_eq!(system.damping.at(blade, f).1, 1e-4, "{blade}");
        }
    }
}

/// `chain` with `n_stages = N` builds the model of the text `pendkit chain-file N` writes:
/// the same coordinates and, at stage 2, the same mode frequencies (the same file read
/// twice: exactly).
#[test]
fn the_chain_is_its_generators_file() {
    for n in [1, 3, 6] {
        let case = Case::model("chain")
            .unwrap()
            .with_sets(&[format!("n_stages={n}")])
            .unwrap();
        let (bundled, _) = case.build().unwrap();
        let dir =
            std::env::temp_dir().join(format!("pendkit-bundled-chain-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(format!("chain-{n}.toml"));
        std::fs::write(
            &path,
            &pendkit::suspension::generate::chain(n).unwrap().source.text,
        )
        .unwrap();
        let (written, _) = Case::open(path.to_str().unwrap()).unwrap().build().unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        // six coordinates per body and six of the support (driven)
        assert_eq!(bundled.coords.len(), 6 * (n + 1));
        let names = |s: &pendkit::system::System| {
            s.coords.iter().map(|c| c.name.clone()).collect::<Vec<_>>()
        };
        assert_eq!(names(&bundled), names(&written));
        let a = run_stage(bundled, Stage::S2).unwrap();
        let b = run_stage(written, Stage::S2).unwrap();
        let hz = |r: &pendkit::StageResult| r.modes.modes.iter().map(|m| m.hz).collect::<Vec<_>>();
        assert_eq!(hz(&a), hz(&b), "{n} stages");
    }
}
