//! The aLIGO quadruple test-mass suspension (T020205 §6.2), parameters and topology from
//! `params/quad2005.csv` and its README: support, 2 structure blades, 2 top wires, top mass
//! (stage 0), 2 blades, 4 wires, UIM (1), 2 blades, 4 wires, PUM (2), 4 silica fibres, test
//! mass (3). Wire lengths are equilibrium lengths between attachment points; each wire's
//! stiffness is Y π r² / l and its unstretched length l − T/k with T the static tension,
//! and each blade's preload holds its tip at the nominal height, so the equilibrium sits on
//! the nominal geometry.

use std::collections::BTreeMap;

use nalgebra::Vector3;
use pendkit_energy::System;
use pendkit_model::{
    BodySpec, BuildError, DampingSpec, DefaultsCache, LIGO_DOF_NAMES, Model, SystemBuilder,
};
use pendkit_params::{ParamError, ParamSet, Resolved};

use crate::chain::{self, Blade, Blades, vertical};
use crate::tables;

/// One variant of the quad.
pub struct Quad {
    name: &'static str,
    summary: &'static str,
    blades: Blades,
    /// Default number of violin beads per fibre (parameter `n_beads`).
    beads: usize,
    /// This variant's parsed defaults, after its first build.
    cache: DefaultsCache,
}

/// The bundled quad variants.
pub static QUADS: [Quad; 5] = [
    Quad {
        name: "quad",
        summary: "aLIGO quad, xtra-lite (massless blade tips as floats), quad2005 parameters",
        blades: Blades::XtraLite,
        beads: 0,
        cache: DefaultsCache::new(),
    },
    Quad {
        name: "quad-lite",
        summary: "aLIGO quad, lite (blade tips with mass, 1 DOF each)",
        blades: Blades::Lite,
        beads: 0,
        cache: DefaultsCache::new(),
    },
    Quad {
        name: "quad-full",
        summary: "aLIGO quad, full (blade tips as 6-DOF bodies on 6x6 springs)",
        blades: Blades::Full,
        beads: 0,
        cache: DefaultsCache::new(),
    },
    Quad {
        name: "quad-lateral",
        summary: "aLIGO quad, xtra-lite with lateral blade compliance (the source's preferred model)",
        blades: Blades::Lateral,
        beads: 0,
        cache: DefaultsCache::new(),
    },
    Quad {
        name: "quad-v5",
        summary: "aLIGO quad, xtra-lite with 5 violin beads per fibre (n_beads sets any N)",
        blades: Blades::XtraLite,
        beads: 5,
        cache: DefaultsCache::new(),
    },
];

impl Model for Quad {
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
        tables::define_quad(&mut set)?;
        tables::define_materials(&mut set)?;
        for (name, value) in [
            // Poisson's ratios (not in the tables): silica as docs/reference-values.md §0, steel typical
            ("nu_steel", "0.29".to_string()),
            ("nu_silica", "0.17".to_string()),
            ("n_beads", self.beads.to_string()),
            // static tensions (N) of each wire set at the nominal geometry, for the
            // thermoelastic stress term
            (
                "Tn",
                "(mn+m1+m2+m3)*g/2*ln/sqrt(ln^2-(nn0-nn1)^2)".to_string(),
            ),
            ("T1", "(m1+m2+m3)*g/4*l1/sqrt(l1^2-(n0-n1)^2)".to_string()),
            ("T2", "(m2+m3)*g/4*l2/sqrt(l2^2-(n2-n3)^2)".to_string()),
            ("T3", "m3*g/4*l3/sqrt(l3^2-(n4-n5)^2)".to_string()),
        ] {
            set.define(name, &value)?;
        }
        for (name, unit) in [
            ("nu_steel", ""),
            ("nu_silica", ""),
            ("n_beads", ""),
            ("Tn", "N"),
            ("T1", "N"),
            ("T2", "N"),
            ("T3", "N"),
        ] {
            set.set_unit(name, unit)?;
        }
        for (name, value) in self.blades.parameters() {
            set.define(name, value)?;
        }
        Ok(set)
    }

    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        let mut d = chain::damping_map(
            [
                ("wn", "steel", "Tn", "rn", "Yn"),
                ("w1", "steel", "T1", "r1", "Y1"),
                ("w2", "steel", "T2", "r2", "Y2"),
                ("fibre", "silica", "T3", "r3", "Y3"),
            ]
            .into_iter()
            .flat_map(|(set, m, t, r, y)| chain::wire_damping(set, m, t, r, y)),
        );
        for blade in ["blade_n", "blade_1", "blade_2"] {
            d.insert(blade.into(), DampingSpec::structural("maraging_phi"));
        }
        d
    }

    fn build(&self, p: &Resolved) -> Result<System, BuildError> {
        let v = |n: &str| p.get(n);
        let g = v("g")?;
        for (name, expected) in [("nwn", 2.0), ("nw1", 4.0), ("nw2", 4.0), ("nw3", 4.0)] {
            if v(name)? != expected {
                return Err(BuildError::Invalid {
                    item: format!("parameter '{name}'"),
                    message: format!("the quad's topology has {expected} wires here"),
                });
            }
        }
        let beads = chain::bead_count(p)?;
        let (mn, m1, m2, m3) = (v("mn")?, v("m1")?, v("m2")?, v("m3")?);
        let steel = |r: &str, y: &str| chain::round_section(p, r, y, "nu_steel", "steel_rho");
        let (sec_n, sec_1, sec_2) = (steel("rn", "Yn")?, steel("r1", "Y1")?, steel("r2", "Y2")?);
        let sec_3 = chain::round_section(p, "r3", "Y3", "nu_silica", "silica_rho")?;
        let l3 = v("l3")?;
        let m_beads = 4.0 * chain::beads_mass(&sec_3, l3, beads);

        // nominal geometry: centre-of-mass heights from the wire lengths (the derived tl*)
        let vert_n = vertical(v("ln")?, v("nn0")? - v("nn1")?);
        let vert_1 = vertical(v("l1")?, v("n0")? - v("n1")?);
        let vert_2 = vertical(v("l2")?, v("n2")? - v("n3")?);
        let vert_3 = vertical(l3, v("n4")? - v("n5")?);
        let z0 = -vert_n - v("dm")?;
        let z1 = z0 - v("dn")? - vert_1 - v("d0")?;
        let z2 = z1 - v("d1")? - vert_2 - v("d2")?;
        let z3 = z2 - v("d3")? - vert_3 - v("d4")?;

        let mut b = SystemBuilder::new(g);
        b.support_parameters()?;
        let support = b.body(BodySpec::new("support").pose_suffix("00"))?;
        let mut bodies = Vec::new();
        for (k, (name, z, m, inertia)) in [
            ("top", z0, mn, ["Inx", "Iny", "Inz"]),
            ("uim", z1, m1, ["I1x", "I1y", "I1z"]),
            ("pum", z2, m2, ["I2x", "I2y", "I2z"]),
            ("testmass", z3, m3, ["I3x", "I3y", "I3z"]),
        ]
        .into_iter()
        .enumerate()
        {
            for (c, start) in ["x", "y", "z", "yaw", "pitch", "roll"]
                .into_iter()
                .zip([0.0, 0.0, z, 0.0, 0.0, 0.0])
            {
                b.variable(&format!("{c}{k}"), start)?;
            }
            let mut spec = BodySpec::new(name)
                .pose_suffix(&k.to_string())
                .mass(m)
                .inertia_diag(v(inertia[0])?, v(inertia[1])?, v(inertia[2])?);
            // the PUM and the test mass are cylinders along x (r = 0.17 m, h = 0.2 m); the
            // top mass and the UIM keep the box of their inertias (the default)
            match k {
                2 => spec = spec.shape(chain::cylinder_along_x(v("ir")?, v("ix")?)),
                3 => spec = spec.shape(chain::cylinder_along_x(v("tr")?, v("tx")?)),
                _ => {}
            }
            bodies.push(b.body(spec)?);
        }
        let [top, uim, pum, tm] = [bodies[0], bodies[1], bodies[2], bodies[3]];
        // LIGO's names: M0 (top), L1 (UIM), L2 (PUM), L3 (test mass), the support GND
        b.name_scheme(
            "ligo",
            LIGO_DOF_NAMES,
            &[
                ("support", "GND"),
                ("top", "M0"),
                ("uim", "L1"),
                ("pum", "L2"),
                ("testmass", "L3"),
            ],
        )?;

        // vertical loads (N) on each blade tip: everything hung below it, shared by 2 blades;
        // the tips of the lite and full forms weigh on the body their blade is mounted on
        let tip = 2.0 * self.blades.tip_mass(p)?;
        let below = |masses: f64| (masses + m_beads) * g / 2.0;
        let kc = |f: &str, m: f64| -> Result<f64, BuildError> {
            Ok(0.5 * (2.0 * std::f64::consts::PI * v(f)?).powi(2) * m)
        };
        // (parent, parent origin z, tip y, tip z, kc, load W, y of the wires' lower ends,
        //  their vertical extent, tag, name prefix)
        let blade_stages = [
            (
                support,
                0.0,
                v("nn0")?,
                0.0,
                kc("ufcn", mn)?,
                below(mn + m1 + m2 + m3 + 2.0 * tip),
                v("nn1")?,
                vert_n,
                "blade_n",
                "0",
            ),
            (
                top,
                z0,
                v("n0")?,
                -v("dn")?,
                kc("ufc1", m1)?,
                below(m1 + m2 + m3 + tip),
                v("n1")?,
                vert_1,
                "blade_1",
                "1",
            ),
            (
                uim,
                z1,
                v("n2")?,
                -v("d1")?,
                kc("ufc2", m2)?,
                below(m2 + m3),
                v("n3")?,
                vert_2,
                "blade_2",
                "2",
            ),
        ];
        let mut tips = Vec::new();
        for (parent, origin_z, y, z, kc, load, y_low, vert, tag, prefix) in blade_stages {
            let mut pair = Vec::new();
            for (side, sign) in [("l", 1.0), ("r", -1.0)] {
                let blade = Blade {
                    name: &format!("{prefix}{side}"),
                    parent,
                    parent_origin: Vector3::new(0.0, 0.0, origin_z),
                    tip: Vector3::new(0.0, sign * y, z),
                    kc,
                    // the wires hang down and sideways towards their lower ends
                    pull: Vector3::new(0.0, sign * load * (y_low - y) / vert, -load),
                    tag,
                };
                pair.push(chain::blade(&mut b, &blade, self.blades, p, g)?);
            }
            tips.push(pair);
        }

        // top wires: one per structure blade tip, to the top mass at (0, ±nn1, dm)
        let (sn, su, si) = (v("sn")?, v("su")?, v("si")?);
        let tags_n = chain::tags("wn");
        for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
            chain::wire(
                &mut b,
                &format!("wn{}", k + 1),
                (tips[0][k], Vector3::new(sn, 0.0, 0.0)),
                (top, Vector3::new(sn, sign * v("nn1")?, v("dm")?)),
                (
                    &sec_n,
                    v("ln")?,
                    below(mn + m1 + m2 + m3 + 2.0 * tip) * v("ln")? / vert_n,
                ),
                &tags_n,
            )?;
        }
        // UIM and PUM wires: two per blade tip at x = ±s
        for (stage, lower, s, n_low, d_low, sec, l, vert, mass, set) in [
            (
                1,
                uim,
                su,
                v("n1")?,
                v("d0")?,
                &sec_1,
                v("l1")?,
                vert_1,
                m1 + m2 + m3 + tip,
                "w1",
            ),
            (
                2,
                pum,
                si,
                v("n3")?,
                v("d2")?,
                &sec_2,
                v("l2")?,
                vert_2,
                m2 + m3,
                "w2",
            ),
        ] {
            let tags = chain::tags(set);
            let tension = below(mass) / 2.0 * l / vert;
            for (k, (side, sx)) in [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0)]
                .into_iter()
                .enumerate()
            {
                let sy = if side == 0 { 1.0 } else { -1.0 };
                chain::wire(
                    &mut b,
                    &format!("{set}_{}", k + 1),
                    (tips[stage][side], Vector3::new(sx * s, 0.0, 0.0)),
                    (lower, Vector3::new(sx * s, sy * n_low, d_low)),
                    (sec, l, tension),
                    &tags,
                )?;
            }
        }
        // fibres from the PUM (±sl, ±n4, −d3) to the test mass (±sl, ±n5, d4)
        chain::lowest_wires(
            &mut b,
            p,
            (pum, tm),
            [z2, z3],
            (&sec_3, m3 * g),
            beads,
            &chain::tags("fibre"),
        )?;
        b.build()
    }
}
