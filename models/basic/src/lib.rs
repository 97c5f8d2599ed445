//! The small bundled models whose answers are known in closed form (physics_oracles.md):
//! `toy` (two springs in series with a float), `pendulum` (point mass on four fibres),
//! `double-pendulum` (two point masses on steel wires) and `rigid-body` (one body on four
//! vertical fibres). Wires are straight and vertical at equilibrium: their unstretched
//! lengths are derived from the static tensions.

use nalgebra::{Matrix6, Vector3, Vector6};
use pendkit_energy::{EndDirection, SpringEnd, Wire, WireEnd, WireSection, WireTags};
use std::collections::BTreeMap;

use pendkit_model::{BodySpec, BuildError, DampingSpec, Model, SystemBuilder};
use pendkit_params::{ParamError, ParamSet, Resolved};

/// Builds a parameter set from (name, expression) pairs.
fn params(defs: &[(&str, &str)]) -> Result<ParamSet, ParamError> {
    let mut set = ParamSet::new();
    for (name, text) in defs {
        set.define(name, text)?;
    }
    Ok(set)
}

/// The material parameters of the REF fused-silica fibre (physics_oracles.md §0).
const SILICA_FIBRE: [(&str, &str); 7] = [
    ("phi_fibre", "1e-7"),
    ("r_fibre", "0.2e-3"),
    ("E_fibre", "72e9"),
    ("nu_fibre", "0.17"),
    ("rho_fibre", "2200"),
    ("l_fibre", "0.6"),
    ("g", "9.81"),
];

/// Structural loss `phi` (a parameter name) on the stretch, bending and torsion tags of
/// wires called `kind` (the bundled small models' fibres default to φ = 1e-7 everywhere).
fn wire_damping(kind: &str, phi: &str) -> BTreeMap<String, DampingSpec> {
    ["stretch", "bending", "torsion"]
        .into_iter()
        .map(|t| (format!("{kind}_{t}"), DampingSpec::structural(phi)))
        .collect()
}

fn fibre_tags() -> WireTags {
    WireTags {
        stretch: "fibre_stretch".into(),
        bending: "fibre_bending".into(),
        torsion: "fibre_torsion".into(),
    }
}

fn round_section(p: &Resolved, prefix: &str) -> Result<WireSection, BuildError> {
    let e = p.get(&format!("E_{prefix}"))?;
    let nu = p.get(&format!("nu_{prefix}"))?;
    Ok(WireSection::round(
        p.get(&format!("r_{prefix}"))?,
        e,
        e / (2.0 * (1.0 + nu)),
        p.get(&format!("rho_{prefix}"))?,
    ))
}

/// The support: a massless body posed by the six parameters `x00 ... roll00`.
fn support(b: &mut SystemBuilder) -> Result<usize, BuildError> {
    b.support_parameters()?;
    b.body(BodySpec::new("support").pose_suffix("00"))
}

/// Four vertical fibres from the support (at z = 0) to `body`, attached at (±a, ±b, d) on the
/// body whose centre sits at z = -(l + d); each carries a quarter of `weight` (N). Their
/// lower ends are hinged when the parameter `hinged_bottom` is non-zero, else clamped.
fn four_fibres(
    b: &mut SystemBuilder,
    (support, body): (usize, usize),
    p: &Resolved,
    (a, bb, d): (f64, f64, f64),
    weight: f64,
) -> Result<(), BuildError> {
    let bottom = if p.get("hinged_bottom")? != 0.0 {
        EndDirection::Hinged
    } else {
        EndDirection::Auto
    };
    let section = round_section(p, "fibre")?;
    let length = p.get("l_fibre")?;
    for (k, (sx, sy)) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)]
        .into_iter()
        .enumerate()
    {
        let (x, y) = (sx * a, sy * bb);
        let ends = [
            WireEnd {
                body: support,
                point: Vector3::new(x, y, 0.0),
                direction: EndDirection::Auto,
            },
            WireEnd {
                body,
                point: Vector3::new(x, y, d),
                direction: bottom.clone(),
            },
        ];
        b.wire(Wire::from_tension(
            format!("fibre{}", k + 1),
            ends,
            section.clone(),
            length,
            weight / 4.0,
            fibre_tags(),
        ))?;
    }
    Ok(())
}

/// Source §4 toy: mass m on springs k1 (support s to float q) and k2 (float q to mass x).
pub struct Toy;

impl Model for Toy {
    pendkit_model::defaults_cache_per_impl!();

    fn name(&self) -> &'static str {
        "toy"
    }
    fn summary(&self) -> &'static str {
        "mass on two springs in series with a massless junction (source §4)"
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
        let spread = (p.get("a_fibre")?, p.get("b_fibre")?, 0.0);
        four_fibres(&mut b, (support, mass), p, spread, m * g)?;
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
        params(&[
            ("g", "9.81"),
            ("m1", "40"),
            ("m2", "40"),
            ("l1", "0.6"),
            ("l2", "0.6"),
            ("r_wire", "0.5e-3"),
            ("E_wire", "212e9"),
            ("nu_wire", "0.29"),
            ("rho_wire", "7800"),
            ("phi_wire", "1e-7"),
        ])
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
        let tags = WireTags {
            stretch: "wire_stretch".into(),
            bending: "wire_bending".into(),
            torsion: "wire_torsion".into(),
        };
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
        let spread = (p.get("a_fibre")?, p.get("b_fibre")?, d);
        four_fibres(&mut b, (support, body), p, spread, m * g)?;
        b.build()
    }
}

/// The models of this crate.
pub fn models() -> Vec<&'static dyn Model> {
    vec![&Toy, &Pendulum, &DoublePendulum, &RigidBody]
}
