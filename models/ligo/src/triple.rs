//! A GEO-style triple suspension (T020205 §6.1) with an HSTS-like parameter set (aLIGO HAM
//! small triple scale): support, 2 upper blades, 2 upper wires (one per blade), upper mass
//! (stage 1), 4 lower blades, 4 intermediate wires (one per blade), intermediate mass
//! (stage 2), 4 lower wires (or fibres), optic (stage 3). One wire per blade tip throughout.
//!
//! No public parameter set is at hand: the defaults below are a documented, physically
//! consistent choice, every dimension a parameter and every derived quantity (masses and
//! inertias from body dimensions, blade stiffnesses, static tensions, wire radii from the
//! design stress) a parameter expression that a case can override. Wire lengths are
//! equilibrium lengths between attachment points; each wire's stiffness is Y π r² / l and
//! its unstretched length l − T/k with T the static tension, and each blade's preload holds
//! its tip at the nominal height, so the equilibrium sits on the nominal geometry.

use std::collections::BTreeMap;

use nalgebra::Vector3;
use pendkit_energy::System;
use pendkit_model::beads::BeadJoints;
use pendkit_model::{
    BodySpec, BuildError, DampingSpec, DefaultsCache, LIGO_DOF_NAMES, Model, Shape, SystemBuilder,
};
use pendkit_params::{ParamError, ParamSet, Resolved};

use crate::chain::{self, Blade, Blades, vertical};
use crate::tables;

/// One variant of the triple.
pub struct Triple {
    name: &'static str,
    summary: &'static str,
    blades: Blades,
    /// Default number of violin beads per lower wire (parameter `n_beads`).
    beads: usize,
    /// This variant's parsed defaults, after its first build.
    cache: DefaultsCache,
}

/// The bundled triple variants.
pub static TRIPLES: [Triple; 5] = [
    Triple {
        name: "triple",
        summary: "GEO-style triple, xtra-lite (massless blade tips as floats), HSTS-like parameters",
        blades: Blades::XtraLite,
        beads: 0,
        cache: DefaultsCache::new(),
    },
    Triple {
        name: "triple-lite",
        summary: "GEO-style triple, lite (blade tips with mass, 1 DOF each)",
        blades: Blades::Lite,
        beads: 0,
        cache: DefaultsCache::new(),
    },
    Triple {
        name: "triple-full",
        summary: "GEO-style triple, full (blade tips as 6-DOF bodies on 6x6 springs)",
        blades: Blades::Full,
        beads: 0,
        cache: DefaultsCache::new(),
    },
    Triple {
        name: "triple-lateral",
        summary: "GEO-style triple, xtra-lite with lateral blade compliance",
        blades: Blades::Lateral,
        beads: 0,
        cache: DefaultsCache::new(),
    },
    Triple {
        name: "triple-v5",
        summary: "GEO-style triple, xtra-lite with 5 violin beads per lower wire (n_beads sets any N)",
        blades: Blades::XtraLite,
        beads: 5,
        cache: DefaultsCache::new(),
    },
];

/// Default parameters (SI units) with the reason for each value. Names follow
/// `params/quad2005.csv` for the quad's lower three stages, which are the triple's stages
/// 1, 2, 3: `d0`/`d1` above/below the upper mass, `d2`/`d3` intermediate, `d4` optic;
/// `n0`/`n1` the upper wires' half y-separations at the top/bottom, `n2`/`n3` the
/// intermediate wires', `n4`/`n5` the lower wires'.
const PARAMETERS: &[(&str, &str)] = &[
    ("g", "9.81"),
    // --- optic (stage 3): an HSTS-size fused-silica optic, 150 mm diameter × 75 mm thick,
    // axis along x; mass and inertias of the cylinder (≈ 2.92 kg)
    ("tr", "0.075"),
    ("tx", "0.075"),
    ("m3", "silica_rho*pi*tr^2*tx"),
    ("I3x", "m3*tr^2/2"),
    ("I3y", "m3*(tr^2/4 + tx^2/12)"),
    ("I3z", "I3y"),
    // --- intermediate mass (stage 2): a cylinder of the optic's size and of about its
    // mass (GEO-style triples match the masses; HSTS masses are all about 3 kg)
    ("ir", "0.075"),
    ("ix", "0.075"),
    ("m2", "2.9"),
    ("I2x", "m2*ir^2/2"),
    ("I2y", "m2*(ir^2/4 + ix^2/12)"),
    ("I2z", "I2y"),
    // --- upper mass (stage 1): a block ux × uy × uz (x × y × z) of about 3 kg, wide in y to
    // carry the four lower blades
    ("ux", "0.10"),
    ("uy", "0.20"),
    ("uz", "0.05"),
    ("m1", "2.9"),
    ("I1x", "m1*(uy^2 + uz^2)/12"),
    ("I1y", "m1*(ux^2 + uz^2)/12"),
    ("I1z", "m1*(ux^2 + uy^2)/12"),
    // --- wire lengths (equilibrium lengths between attachment points): chosen for
    // longitudinal pendulum modes between ~0.5 and ~2.5 Hz and the optic ~0.9 m below the
    // suspension point
    ("l1", "0.40"),
    ("l2", "0.25"),
    ("l3", "0.25"),
    // --- break-offs: 1 mm from each centre-of-mass plane, as in quad2005 (small positive
    // values keep the pitch modes stable and low)
    ("d0", "0.001"),
    ("d1", "0.001"),
    ("d2", "0.001"),
    ("d3", "0.001"),
    ("d4", "0.001"),
    // --- half y-separations: upper blade tips on the structure (n0) slightly wider than the
    // upper-mass clamps (n1), for roll/transverse stiffness; lower blade tips (n2) inside the
    // upper mass (uy/2 = 0.1 m); intermediate clamps 5 mm outside its barrel (n3); lower
    // wires vertical, 1 mm outside the optic's barrel at both ends (a break-off prism)
    ("n0", "0.10"),
    ("n1", "0.08"),
    ("n2", "0.09"),
    ("n3", "ir + 0.005"),
    ("n4", "n5"),
    ("n5", "tr + 0.001"),
    // --- half x-separations (the upper wires lie in the y–z plane through the centres of
    // mass, as the quad's top wires): intermediate wires from blades in two pairs 20 mm
    // apart; lower wires 10 mm apart, whose stretch stiffness sets the differential pitch
    // mode of the intermediate mass and the optic (~3 Hz)
    ("si", "0.01"),
    ("sl", "0.005"),
    // --- blades: uncoupled vertical frequencies of a few Hz (the quad's are 1.8–2.5 Hz);
    // per-blade stiffness kc = (2π ufc)² m_hung / (blades in the set), m_hung the mass hung
    // directly from the set (m1 for the 2 upper blades, m2 for the 4 lower ones)
    ("ufc1", "2.5"),
    ("ufc2", "2.5"),
    ("kc1", "(2*pi*ufc1)^2*m1/2"),
    ("kc2", "(2*pi*ufc2)^2*m2/4"),
    // --- static tension (N) per wire at the nominal geometry (without blade tips and beads)
    ("T1", "(m1 + m2 + m3)*g/2*l1/sqrt(l1^2 - (n0 - n1)^2)"),
    ("T2", "(m2 + m3)*g/4*l2/sqrt(l2^2 - (n2 - n3)^2)"),
    ("T3", "m3*g/4*l3/sqrt(l3^2 - (n4 - n5)^2)"),
    // --- wire radii: design stress a third of the tensile strength of C70 (music) steel
    // wire, assumed 2 GPa for 0.1–0.3 mm wire: r = sqrt(T / (π σ)); gives diameters of
    // about 0.29, 0.17 and 0.12 mm
    ("steel_strength", "2e9"),
    ("wire_stress", "steel_strength/3"),
    ("r1", "sqrt(T1/(pi*wire_stress))"),
    ("r2", "sqrt(T2/(pi*wire_stress))"),
    ("r3", "sqrt(T3/(pi*wire_stress))"),
    // --- materials: steel wires (C70, table), maraging blades (damping); the lower wires
    // are steel as in HSTS unless fibre_silica = 1 chooses fused-silica fibres ("lower_*"
    // blends the two materials' constants, exact for 0 and 1)
    ("fibre_silica", "0"),
    ("Y1", "steel_Y"),
    ("Y2", "steel_Y"),
    ("Y3", "lower_Y"),
    // Poisson's ratios (not in the tables): silica as docs/reference-values.md §0, steel typical
    ("nu_steel", "0.29"),
    ("nu_silica", "0.17"),
    (
        "nu3",
        "(1 - fibre_silica)*nu_steel + fibre_silica*nu_silica",
    ),
];

/// The material constants blended into `lower_<c>` by `fibre_silica`.
const LOWER_MATERIAL: [&str; 7] = ["rho", "C", "K", "alpha", "dlnE_dT", "phi", "Y"];

impl Model for Triple {
    fn name(&self) -> &'static str {
        self.name
    }

    fn defaults_cache(&self) -> Option<&DefaultsCache> {
        Some(&self.cache)
    }

    fn summary(&self) -> &'static str {
        self.summary
    }

    fn parameters(&self) -> Result<ParamSet, ParamError> {
        let mut set = ParamSet::new();
        tables::define_materials(&mut set)?;
        for &(name, value) in PARAMETERS {
            set.define(name, value)?;
        }
        for c in LOWER_MATERIAL {
            set.define(
                &format!("lower_{c}"),
                &format!("(1 - fibre_silica)*steel_{c} + fibre_silica*silica_{c}"),
            )?;
        }
        set.define("n_beads", &self.beads.to_string())?;
        for (name, value) in self.blades.parameters() {
            set.define(name, value)?;
        }
        if set.contains("blade_tip_mass") {
            // the small triple's blades are far lighter than the quad's (~0.2 kg): take a
            // ~40 g blade and a quarter of it at the tip
            set.apply_text("blade_tip_mass", "0.01")?;
        }
        Ok(set)
    }

    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        let mut d = chain::damping_map(
            [
                ("w1", "steel", "T1", "r1", "Y1"),
                ("w2", "steel", "T2", "r2", "Y2"),
                ("w3", "lower", "T3", "r3", "Y3"),
            ]
            .into_iter()
            .flat_map(|(set, m, t, r, y)| chain::wire_damping(set, m, t, r, y)),
        );
        for blade in ["blade_1", "blade_2"] {
            d.insert(blade.into(), DampingSpec::structural("maraging_phi"));
        }
        d
    }

    fn build(&self, p: &Resolved) -> Result<System, BuildError> {
        let v = |n: &str| p.get(n);
        let g = v("g")?;
        let fibre_silica = v("fibre_silica")?;
        if fibre_silica != 0.0 && fibre_silica != 1.0 {
            return Err(BuildError::Invalid {
                item: "parameter 'fibre_silica'".into(),
                message: format!(
                    "must be 0 (steel wires) or 1 (silica fibres), got {fibre_silica}"
                ),
            });
        }
        let beads = chain::bead_count(p)?;
        let (m1, m2, m3) = (v("m1")?, v("m2")?, v("m3")?);
        let steel = |r: &str, y: &str| chain::round_section(p, r, y, "nu_steel", "steel_rho");
        let (sec_1, sec_2) = (steel("r1", "Y1")?, steel("r2", "Y2")?);
        let sec_3 = chain::round_section(p, "r3", "Y3", "nu3", "lower_rho")?;
        let (l1, l2, l3) = (v("l1")?, v("l2")?, v("l3")?);
        let (n0, n1, n2, n3, n4, n5) = (v("n0")?, v("n1")?, v("n2")?, v("n3")?, v("n4")?, v("n5")?);
        let (d0, d1, d2, d3, d4) = (v("d0")?, v("d1")?, v("d2")?, v("d3")?, v("d4")?);
        let si = v("si")?;
        let m_beads = 4.0 * chain::beads_mass(&sec_3, None, l3, beads);

        // nominal geometry: centre-of-mass heights from the wires' vertical extents
        let (vert_1, vert_2, vert_3) = (
            vertical(l1, n0 - n1),
            vertical(l2, n2 - n3),
            vertical(l3, n4 - n5),
        );
        let z1 = -vert_1 - d0;
        let z2 = z1 - d1 - vert_2 - d2;
        let z3 = z2 - d3 - vert_3 - d4;

        let mut b = SystemBuilder::new(g);
        b.support_parameters()?;
        let support = b.body(BodySpec::new("support").pose_suffix("00"))?;
        let mut bodies = Vec::new();
        for (k, (name, z, m)) in [
            ("upper", z1, m1),
            ("intermediate", z2, m2),
            ("optic", z3, m3),
        ]
        .into_iter()
        .enumerate()
        {
            let stage = (k + 1).to_string();
            for (c, start) in ["x", "y", "z", "yaw", "pitch", "roll"]
                .into_iter()
                .zip([0.0, 0.0, z, 0.0, 0.0, 0.0])
            {
                b.variable(&format!("{c}{stage}"), start)?;
            }
            let inertia = |axis: &str| p.get(&format!("I{stage}{axis}"));
            // drawn as what their inertias are computed from: the upper mass a box of
            // ux x uy x uz, the intermediate mass and the optic cylinders along x
            let shape = match k {
                0 => Shape::Box {
                    half_sizes: Vector3::new(v("ux")?, v("uy")?, v("uz")?) / 2.0,
                },
                1 => chain::cylinder_along_x(v("ir")?, v("ix")?),
                _ => chain::cylinder_along_x(v("tr")?, v("tx")?),
            };
            bodies.push(
                b.body(
                    BodySpec::new(name)
                        .pose_suffix(&stage)
                        .mass(m)
                        .inertia_diag(inertia("x")?, inertia("y")?, inertia("z")?)
                        .shape(shape),
                )?,
            );
        }
        let [upper, intermediate, optic] = [bodies[0], bodies[1], bodies[2]];
        // LIGO's names: M1 (top) to M3 (optic), the support GND
        b.name_scheme(
            "ligo",
            LIGO_DOF_NAMES,
            &[
                ("support", "GND"),
                ("upper", "M1"),
                ("intermediate", "M2"),
                ("optic", "M3"),
            ],
        )?;

        // vertical load (N) on each blade tip: everything hung below it, shared by the
        // blades of its set; the tips of the lite and full forms weigh on the body their
        // blade is mounted on (the 4 lower tips on the upper mass)
        let tip = self.blades.tip_mass(p)?;
        let load_1 = (m1 + m2 + m3 + 4.0 * tip + m_beads) * g / 2.0;
        let load_2 = (m2 + m3 + m_beads) * g / 4.0;

        // upper blades on the structure, tips at (0, ±n0, 0); one wire each to the upper
        // mass at (0, ±n1, d0)
        let tags_1 = chain::tags("w1");
        for (side, sy) in [("l", 1.0), ("r", -1.0)] {
            let blade = Blade {
                name: &format!("1{side}"),
                parent: support,
                parent_origin: Vector3::zeros(),
                tip: Vector3::new(0.0, sy * n0, 0.0),
                kc: v("kc1")?,
                // the wire hangs down and sideways towards its lower end
                pull: Vector3::new(0.0, sy * load_1 * (n1 - n0) / vert_1, -load_1),
                tag: "blade_1",
            };
            let tip = chain::blade(&mut b, &blade, self.blades, p, g)?;
            chain::wire(
                &mut b,
                &format!("w1_{side}"),
                (tip, Vector3::zeros()),
                (upper, Vector3::new(0.0, sy * n1, d0)),
                (&sec_1, l1, load_1 * l1 / vert_1),
                &tags_1,
            )?;
        }

        // lower blades on the upper mass, tips at (±si, ±n2, −d1); one wire each to the
        // intermediate mass at (±si, ±n3, d2)
        let tags_2 = chain::tags("w2");
        for (side, sy) in [("l", 1.0), ("r", -1.0)] {
            for (end, sx) in [("f", 1.0), ("b", -1.0)] {
                let blade = Blade {
                    name: &format!("2{side}{end}"),
                    parent: upper,
                    parent_origin: Vector3::new(0.0, 0.0, z1),
                    tip: Vector3::new(sx * si, sy * n2, -d1),
                    kc: v("kc2")?,
                    pull: Vector3::new(0.0, sy * load_2 * (n3 - n2) / vert_2, -load_2),
                    tag: "blade_2",
                };
                let tip = chain::blade(&mut b, &blade, self.blades, p, g)?;
                chain::wire(
                    &mut b,
                    &format!("w2_{side}{end}"),
                    (tip, Vector3::zeros()),
                    (intermediate, Vector3::new(sx * si, sy * n3, d2)),
                    (&sec_2, l2, load_2 * l2 / vert_2),
                    &tags_2,
                )?;
            }
        }

        // lower wires from the intermediate mass (±sl, ±n4, −d3) to the optic (±sl, ±n5, d4)
        chain::lowest_wires(
            &mut b,
            p,
            (intermediate, optic),
            [z2, z3],
            (&sec_3, None, m3 * g),
            (beads, BeadJoints::Clamped),
            &chain::tags("w3"),
        )?;
        b.build()
    }
}
