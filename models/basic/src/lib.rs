//! The small bundled models whose answers are known in closed form (docs/reference-values.md):
//! `toy` (two springs in series with a float), `pendulum` (point mass on four fibres),
//! `double-pendulum` (two point masses on steel wires) and `rigid-body` (one body on four
//! vertical fibres); and `chain`, any number of such bodies one below the other, for
//! scaling benchmarks. Wires are straight and vertical at equilibrium: their unstretched
//! lengths are derived from the static tensions.

mod chain;

use nalgebra::{Matrix6, Vector3, Vector6};
use pendkit_energy::{BodyId, EndDirection, SpringEnd, Wire, WireEnd, WireSection, WireTags};
use std::collections::BTreeMap;

pub use chain::{Chain, MAX_STAGES};

use pendkit_model::{BodySpec, BuildError, DampingSpec, Model, SystemBuilder};
use pendkit_params::{ParamError, ParamSet, Resolved};

/// Builds a parameter set from (name, expression) pairs.
fn params(defs: &[(&str, &str)]) -> Result<ParamSet, ParamError> {
    let mut set = ParamSet::new();
    for (name, text) in defs {
        set.define(name, text)?;
        if let Some((_, unit)) = UNITS.iter().find(|(n, _)| n == name) {
            set.set_unit(name, unit)?;
        }
    }
    Ok(set)
}

/// Units of the parameters of this crate's models (for reports and exports).
const UNITS: [(&str, &str); 35] = [
    ("g", "m/s^2"),
    ("m", "kg"),
    ("m1", "kg"),
    ("m2", "kg"),
    ("k1", "N/m"),
    ("k2", "N/m"),
    ("I1x", "kg m^2"),
    ("I1y", "kg m^2"),
    ("I1z", "kg m^2"),
    ("Ix", "kg m^2"),
    ("Iy", "kg m^2"),
    ("Iz", "kg m^2"),
    ("a_fibre", "m"),
    ("b_fibre", "m"),
    ("d_fibre", "m"),
    ("a_wire", "m"),
    ("b_wire", "m"),
    ("d_top", "m"),
    ("d_bottom", "m"),
    ("l1", "m"),
    ("l2", "m"),
    ("l_fibre", "m"),
    ("l_wire", "m"),
    ("r_fibre", "m"),
    ("r_wire", "m"),
    ("E_fibre", "Pa"),
    ("E_wire", "Pa"),
    ("nu_fibre", ""),
    ("nu_wire", ""),
    ("rho_fibre", "kg/m^3"),
    ("rho_wire", "kg/m^3"),
    ("phi_fibre", "rad"),
    ("phi_wire", "rad"),
    ("hinged_bottom", ""),
    ("n_stages", ""),
];

/// The material parameters of the REF fused-silica fibre (docs/reference-values.md §0).
const SILICA_FIBRE: [(&str, &str); 7] = [
    ("phi_fibre", "1e-7"),
    ("r_fibre", "0.2e-3"),
    ("E_fibre", "72e9"),
    ("nu_fibre", "0.17"),
    ("rho_fibre", "2200"),
    ("l_fibre", "0.6"),
    ("g", "9.81"),
];

/// The steel wire of the double pendulum and the chain: r = 0.5 mm music wire, E = 212 GPa,
/// ν = 0.29, ρ = 7800 kg/m^3, φ = 1e-7 (as the fibres, so that the models compare).
const STEEL_WIRE: [(&str, &str); 5] = [
    ("r_wire", "0.5e-3"),
    ("E_wire", "212e9"),
    ("nu_wire", "0.29"),
    ("rho_wire", "7800"),
    ("phi_wire", "1e-7"),
];

/// Structural loss `phi` (a parameter name) on the stretch, bending and torsion tags of
/// wires called `kind` (the bundled small models' fibres default to φ = 1e-7 everywhere).
fn wire_damping(kind: &str, phi: &str) -> BTreeMap<String, DampingSpec> {
    ["stretch", "bending", "torsion"]
        .into_iter()
        .map(|t| (format!("{kind}_{t}"), DampingSpec::structural(phi)))
        .collect()
}

/// Tags `<kind>_stretch`, `<kind>_bending`, `<kind>_torsion`.
fn wire_tags(kind: &str) -> WireTags {
    WireTags {
        stretch: format!("{kind}_stretch"),
        bending: format!("{kind}_bending"),
        torsion: format!("{kind}_torsion"),
    }
}

fn round_section(p: &Resolved, prefix: &str) -> Result<WireSection, BuildError> {
    let e = p.get(&format!("E_{prefix}"))?;
    let nu = format!("nu_{prefix}");
    let g = pendkit_model::shear_modulus(&format!("parameter '{nu}'"), e, p.get(&nu)?)?;
    Ok(WireSection::round(
        p.get(&format!("r_{prefix}"))?,
        e,
        g,
        p.get(&format!("rho_{prefix}"))?,
    ))
}

/// The support: a massless body posed by the six parameters `x00 ... roll00`.
fn support(b: &mut SystemBuilder) -> Result<usize, BuildError> {
    b.support_parameters()?;
    b.body(BodySpec::new("support").pose_suffix("00"))
}

/// Four vertical wires of one kind from `upper` to `lower`, at (±a, ±b) in x and y on both,
/// at height `heights.0` (m, in `upper`'s coordinates) on the upper body and `heights.1` on
/// the lower one.
struct FourWires<'a> {
    /// Wires are called `<name>1` ... `<name>4`.
    name: &'a str,
    /// Upper and lower body.
    bodies: (BodyId, BodyId),
    /// Half-separations a in x and b in y (m).
    spread: (f64, f64),
    /// Attachment heights on the upper and on the lower body (m, body coordinates).
    heights: (f64, f64),
    /// Length between the attachment points at equilibrium (m).
    length: f64,
    /// Cross-section.
    section: &'a WireSection,
    /// Damping tags.
    tags: &'a WireTags,
    /// How the lower ends are held (the upper ends are clamped: auto direction).
    bottom: EndDirection,
}

/// Adds the four wires, each carrying a quarter of `weight` (N) at equilibrium.
fn four_wires(b: &mut SystemBuilder, w: &FourWires, weight: f64) -> Result<(), BuildError> {
    let (a, bb) = w.spread;
    for (k, (sx, sy)) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
        .into_iter()
        .enumerate()
    {
        let (x, y) = (sx * a, sy * bb);
        let ends = [
            WireEnd {
                body: w.bodies.0,
                point: Vector3::new(x, y, w.heights.0),
                direction: EndDirection::Auto,
            },
            WireEnd {
                body: w.bodies.1,
                point: Vector3::new(x, y, w.heights.1),
                direction: w.bottom.clone(),
            },
        ];
        b.wire(Wire::from_tension(
            format!("{}{}", w.name, k + 1),
            ends,
            w.section.clone(),
            w.length,
            weight / 4.0,
            w.tags.clone(),
        ))?;
    }
    Ok(())
}

/// The four silica fibres `fibre1` ... `fibre4` of the pendulum and the rigid body, from
/// the support (at z = 0) to `body`, attached at (±a_fibre, ±b_fibre, d) on the body whose
/// centre sits at z = -(l_fibre + d); each carries a quarter of `weight` (N). Their lower
/// ends are hinged when the parameter `hinged_bottom` is 1, clamped when it is 0.
fn four_fibres(
    b: &mut SystemBuilder,
    (support, body): (BodyId, BodyId),
    p: &Resolved,
    d: f64,
    weight: f64,
) -> Result<(), BuildError> {
    let bottom = if pendkit_model::switch(p, "hinged_bottom")? {
        EndDirection::Hinged
    } else {
        EndDirection::Auto
    };
    let fibres = FourWires {
        name: "fibre",
        bodies: (support, body),
        spread: (p.get("a_fibre")?, p.get("b_fibre")?),
        heights: (0.0, d),
        length: p.get("l_fibre")?,
        section: &round_section(p, "fibre")?,
        tags: &wire_tags("fibre"),
        bottom,
    };
    four_wires(b, &fibres, weight)
}

/// Source §4 toy: mass m on springs k1 (support s to float q) and k2 (float q to mass x).
pub struct Toy;

impl Model for Toy {
    pendkit_model::defaults_cache_per_impl!();

    fn name(&self) -> &'static str {
        "toy"
    }
    fn summary(&self) -> &'static str {
        "mass on two springs in series with a massless junction (T020205 §4)"
    }
    fn parameters(&self) -> Result<ParamSet, ParamError> {
        params(&[("m", "1"), ("k1", "1000"), ("k2", "3000")])
    }
    fn build(&self, p: &Resolved) -> Result<pendkit_energy::System, BuildError> {
        let mut b = SystemBuilder::new(0.0);
        b.variable("x", 0.0)?;
        b.float("q", 0.0)?;
        b.parameter("s", 0.0)?;
        let ground = b.body(BodySpec::new("ground").pose(["s", "0", "0", "0", "0", "0"]))?;
        let junction = b.body(BodySpec::new("junction").pose(["q", "0", "0", "0", "0", "0"]))?;
        let mass = b.body(
            BodySpec::new("mass")
                .pose(["x", "0", "0", "0", "0", "0"])
                .mass(p.get("m")?),
        )?;
        let along_x = |k: f64| Matrix6::from_diagonal(&Vector6::new(k, 0.0, 0.0, 0.0, 0.0, 0.0));
        let end = |body| SpringEnd {
            body,
            point: Vector3::zeros(),
            angles: [0.0; 3],
        };
        b.spring(
            "k1",
            [end(ground), end(junction)],
            along_x(p.get("k1")?),
            Vector6::zeros(),
            "k1",
        )?;
        b.spring(
            "k2",
            [end(junction), end(mass)],
            along_x(p.get("k2")?),
            Vector6::zeros(),
            "k2",
        )?;
        b.build()
    }
}

/// Point mass on four fused-silica fibres, clamped at the support and hinged at the mass.
pub struct Pendulum;

impl Model for Pendulum {
    pendkit_model::defaults_cache_per_impl!();

    fn name(&self) -> &'static str {
        "pendulum"
    }
    fn summary(&self) -> &'static str {
        "40 kg point mass on 4 silica fibres, 0.6 m, clamped at the top, hinged at the mass"
    }
    fn parameters(&self) -> Result<ParamSet, ParamError> {
        let mut defs = vec![
            ("m1", "40"),
            ("a_fibre", "0.005"),
            ("b_fibre", "0.17"),
            // 1: fibres hinged at the mass (one bending point); 0: clamped to the
            // non-rotating point mass (two bending points)
            ("hinged_bottom", "1"),
        ];
        defs.extend(SILICA_FIBRE);
        params(&defs)
    }
    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        wire_damping("fibre", "phi_fibre")
    }
    fn build(&self, p: &Resolved) -> Result<pendkit_energy::System, BuildError> {
        let (g, m, l) = (p.get("g")?, p.get("m1")?, p.get("l_fibre")?);
        let mut b = SystemBuilder::new(g);
        let support = support(&mut b)?;
        b.variable("x1", 0.0)?;
        b.variable("y1", 0.0)?;
        b.variable("z1", -l)?;
        let mass = b.body(
            BodySpec::new("mass1")
                .pose(["x1", "y1", "z1", "0", "0", "0"])
                .mass(m),
        )?;
        four_fibres(&mut b, (support, mass), p, 0.0, m * g)?;
        b.build()
    }
}

/// Two point masses, one above the other, each on one steel wire hinged at both ends.
pub struct DoublePendulum;

impl Model for DoublePendulum {
    pendkit_model::defaults_cache_per_impl!();

    fn name(&self) -> &'static str {
        "double-pendulum"
    }
    fn summary(&self) -> &'static str {
        "40 kg over 40 kg point masses on 0.6 m steel wires, hinged"
    }
    fn parameters(&self) -> Result<ParamSet, ParamError> {
        let mut defs = vec![
            ("g", "9.81"),
            ("m1", "40"),
            ("m2", "40"),
            ("l1", "0.6"),
            ("l2", "0.6"),
        ];
        defs.extend(STEEL_WIRE);
        params(&defs)
    }
    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        wire_damping("wire", "phi_wire")
    }
    fn build(&self, p: &Resolved) -> Result<pendkit_energy::System, BuildError> {
        let g = p.get("g")?;
        let (m1, m2, l1, l2) = (p.get("m1")?, p.get("m2")?, p.get("l1")?, p.get("l2")?);
        let mut b = SystemBuilder::new(g);
        let support = support(&mut b)?;
        for (name, start) in [
            ("x1", 0.0),
            ("y1", 0.0),
            ("z1", -l1),
            ("x2", 0.0),
            ("y2", 0.0),
            ("z2", -l1 - l2),
        ] {
            b.variable(name, start)?;
        }
        let upper = b.body(
            BodySpec::new("mass1")
                .pose(["x1", "y1", "z1", "0", "0", "0"])
                .mass(m1),
        )?;
        let lower = b.body(
            BodySpec::new("mass2")
                .pose(["x2", "y2", "z2", "0", "0", "0"])
                .mass(m2),
        )?;
        let section = round_section(p, "wire")?;
        let tags = wire_tags("wire");
        let hinge = |body| WireEnd {
            body,
            point: Vector3::zeros(),
            direction: EndDirection::Hinged,
        };
        b.wire(Wire::from_tension(
            "wire1",
            [hinge(support), hinge(upper)],
            section.clone(),
            l1,
            (m1 + m2) * g,
            tags.clone(),
        ))?;
        b.wire(Wire::from_tension(
            "wire2",
            [hinge(upper), hinge(lower)],
            section,
            l2,
            m2 * g,
            tags,
        ))?;
        b.build()
    }
}

/// One rigid body on four vertical fibres attached at (±a, ±b, +d) from its centre of mass.
pub struct RigidBody;

impl Model for RigidBody {
    pendkit_model::defaults_cache_per_impl!();

    fn name(&self) -> &'static str {
        "rigid-body"
    }
    fn summary(&self) -> &'static str {
        "40 kg body, inertias (0.57, 0.42, 0.42) kg m^2, on 4 vertical silica fibres"
    }
    fn parameters(&self) -> Result<ParamSet, ParamError> {
        let mut defs = vec![
            ("m1", "40"),
            ("I1x", "0.57"),
            ("I1y", "0.42"),
            ("I1z", "0.42"),
            ("a_fibre", "0.005"),
            ("b_fibre", "0.17"),
            ("d_fibre", "0.010"),
            // 1: the fibres are hinged at the body; 0: clamped (welded) there
            ("hinged_bottom", "0"),
        ];
        defs.extend(SILICA_FIBRE);
        params(&defs)
    }
    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        wire_damping("fibre", "phi_fibre")
    }
    fn build(&self, p: &Resolved) -> Result<pendkit_energy::System, BuildError> {
        let (g, m, l, d) = (
            p.get("g")?,
            p.get("m1")?,
            p.get("l_fibre")?,
            p.get("d_fibre")?,
        );
        let mut b = SystemBuilder::new(g);
        let support = support(&mut b)?;
        for (name, start) in [
            ("x1", 0.0),
            ("y1", 0.0),
            ("z1", -l - d),
            ("yaw1", 0.0),
            ("pitch1", 0.0),
            ("roll1", 0.0),
        ] {
            b.variable(name, start)?;
        }
        let body = b.body(
            BodySpec::new("mass1")
                .pose_suffix("1")
                .mass(m)
                .inertia_diag(p.get("I1x")?, p.get("I1y")?, p.get("I1z")?),
        )?;
        four_fibres(&mut b, (support, body), p, d, m * g)?;
        b.build()
    }
}

/// The models of this crate.
pub fn models() -> Vec<&'static dyn Model> {
    vec![&Toy, &Pendulum, &DoublePendulum, &RigidBody, &Chain]
}
