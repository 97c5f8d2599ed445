//! `quad-aligo`: the aLIGO quadruple test-mass suspension as built, on the topology and
//! geometry of the 2005 design (T020205 §6.2, `params/quad2005.csv` and its README): support, 2 structure blades, 2 top wires, top mass
//! (stage 0), 2 blades, 4 wires, UIM (1), 2 blades, 4 wires, PUM (2), 4 silica fibres, test
//! mass (3). Wire lengths are equilibrium lengths between attachment points; each wire's
//! stiffness is Y π r² / l and its unstretched length l − T/k with T the static tension,
//! and each blade's preload holds its tip at the nominal height, so the equilibrium sits on
//! the nominal geometry.

use std::collections::BTreeMap;

use nalgebra::Vector3;
use pendkit_energy::System;
use pendkit_model::beads::BeadJoints;
use pendkit_model::losses::{LossMaterial, WireLoss, blade_loss};
use pendkit_model::{
    BodySpec, BuildError, DampingSpec, DefaultsCache, FibreProfile, LIGO_DOF_NAMES, Model,
    SystemBuilder,
};
use pendkit_params::{ParamError, ParamSet, Resolved};

use crate::chain::{self, Blade, Blades, vertical};
use crate::tables;

/// The aLIGO quad as built, as pygwinc 0.6.2's aLIGO `ifo.yaml` `Suspension` gives it:
/// masses, stage lengths, wire radii, blade vertical stiffnesses and thicknesses, tapered
/// fibres, materials and temperature, with surface loss, blade thermoelastic loss, per-set
/// temperatures and optional given dilution factors; the geometry pygwinc does not carry
/// (attachment points, break-offs, inertias) stays the 2005 set's. Xtra-lite blades.
pub struct Quad {
    name: &'static str,
    summary: &'static str,
    blades: Blades,
    /// This variant's parsed defaults, after its first build.
    cache: DefaultsCache,
}

/// The Rust quads: `quad-aligo` (the 2005 quad and its variants are files, models/ligo/).
pub static QUADS: [Quad; 1] = [Quad {
    name: "quad-aligo",
    summary: "aLIGO quad as built (pygwinc 0.6.2 aLIGO numbers): tapered fibres, surface and blade thermoelastic loss, output tm_beam",
    blades: Blades::XtraLite,
    cache: DefaultsCache::new(),
}];

/// pygwinc 0.6.2's aLIGO `Suspension` numbers (ifo.yaml), as overrides of the 2005 set
/// and new parameters: (name, value, unit, what).
const AS_BUILT: &[(&str, &str, &str, &str)] = &[
    (
        "g",
        "9.80665",
        "m/s^2",
        "standard gravity (pygwinc's scipy.constants.g)",
    ),
    ("mn", "22.1", "kg", "top mass"),
    ("m1", "21.8", "kg", "UIM"),
    ("m2", "39.6", "kg", "PUM"),
    ("m3", "39.6", "kg", "test mass"),
    ("rn", "520e-6", "m", "top wire radius"),
    ("r1", "350e-6", "m", "UIM wire radius"),
    ("r2", "310e-6", "m", "PUM wire radius"),
    (
        "r3",
        "205e-6",
        "m",
        "fibre radius in the middle (Fiber.Radius)",
    ),
    (
        "r3_neck",
        "400e-6",
        "m",
        "fibre radius at the necks (Fiber.EndRadius)",
    ),
    (
        "l3_neck",
        "45e-3",
        "m",
        "length of each neck (Fiber.EndLength)",
    ),
    ("l3", "0.59", "m", "fibre length (the TM stage's Length)"),
    ("Yn", "steel_Y", "Pa", "C70 steel"),
    ("Y1", "steel_Y", "Pa", "C70 steel"),
    ("Y2", "steel_Y", "Pa", "C70 steel"),
    ("Y3", "silica_Y", "Pa", "fused silica"),
    // the blades' vertical stiffness per stage (both blades), as the uncoupled frequency
    // the 2005 set's build reads: kc per blade = ½ (2π f)² m = K/2
    (
        "kv_n",
        "3400",
        "N/m",
        "vertical stiffness of the top blades (both)",
    ),
    (
        "kv_1",
        "3900",
        "N/m",
        "vertical stiffness of the UIM blades (both)",
    ),
    (
        "kv_2",
        "5200",
        "N/m",
        "vertical stiffness of the PUM blades (both)",
    ),
    (
        "ufcn",
        "sqrt(kv_n/mn)/(2*pi)",
        "Hz",
        "top blade frequency from kv_n",
    ),
    (
        "ufc1",
        "sqrt(kv_1/m1)/(2*pi)",
        "Hz",
        "UIM blade frequency from kv_1",
    ),
    (
        "ufc2",
        "sqrt(kv_2/m2)/(2*pi)",
        "Hz",
        "PUM blade frequency from kv_2",
    ),
    ("blade_n_thickness", "4300e-6", "m", "top blade thickness"),
    ("blade_1_thickness", "4600e-6", "m", "UIM blade thickness"),
    ("blade_2_thickness", "4200e-6", "m", "PUM blade thickness"),
    // the vertical-to-beam coupling angle pygwinc derives: arm length / Earth radius
    ("arm_length", "3995", "m", "interferometer arm length"),
    (
        "earth_radius",
        "6.3781e6",
        "m",
        "Earth radius (pygwinc const.R_earth)",
    ),
    (
        "vh_theta",
        "arm_length/earth_radius",
        "rad",
        "vertical-to-beam coupling angle",
    ),
    (
        "temperature",
        "290",
        "K",
        "temperature of every element unless its own is set",
    ),
];

/// The wire sets of the quad: (tag prefix, material, tension, radius at the clamps,
/// Young's modulus, length) parameter names.
const WIRE_SETS: [(&str, &str, &str, &str, &str, &str); 4] = [
    ("wn", "steel", "Tn", "rn", "Yn", "ln"),
    ("w1", "steel", "T1", "r1", "Y1", "l1"),
    ("w2", "steel", "T2", "r2", "Y2", "l2"),
    ("fibre", "silica", "T3", "r3", "Y3", "l3"),
];

/// The blades' damping tags, top to bottom.
const BLADE_TAGS: [&str; 3] = ["blade_n", "blade_1", "blade_2"];

/// [`WIRE_SETS`] as quad-aligo reads them: the fibres bend at their necks.
fn as_built_wire_sets() -> [(
    &'static str,
    &'static str,
    &'static str,
    &'static str,
    &'static str,
    &'static str,
); 4] {
    WIRE_SETS.map(|w| {
        if w.0 == "fibre" {
            (w.0, w.1, w.2, "r3_neck", w.4, w.5)
        } else {
            w
        }
    })
}

/// The dilution factor l/λ (λ = √(Y π r⁴/4 / T), the bending length) as an expression.
fn computed_dilution(length: &str, youngs: &str, radius: &str, tension: &str) -> String {
    format!("{length}/sqrt({youngs}*pi*{radius}^4/4/{tension})")
}

/// quad-aligo's damping: bulk, surface and thermoelastic loss of every wire set (the
/// fibres' surface loss weighted over their profile), blade thermoelastic loss, each at
/// its own temperature parameter, the bending loss scaled to a given dilution if one is set.
fn as_built_damping() -> BTreeMap<String, DampingSpec> {
    let mut d = BTreeMap::new();
    for (set, material, tension, radius, youngs, length) in as_built_wire_sets() {
        let surface = if set == "fibre" {
            let profile = ("l3", "l3_neck", "r3_neck", "r3");
            (
                pendkit_model::fibre_inverse_radius(profile, 2),
                pendkit_model::fibre_inverse_radius(profile, 4),
            )
        } else {
            (format!("1/{radius}"), format!("1/{radius}"))
        };
        let temperature = format!("temp_{set}");
        let loss = WireLoss {
            set,
            material: LossMaterial::parameters(material),
            tension,
            youngs,
            clamp_radius: radius,
            surface: Some(surface),
            temperature: &temperature,
            dilution_scale: Some(format!(
                "({})/dilution_{set}",
                computed_dilution(length, youngs, radius, tension)
            )),
        };
        d.extend(loss.damping());
    }
    for blade in BLADE_TAGS {
        d.insert(
            blade.to_string(),
            blade_loss(
                &LossMaterial::parameters("maraging"),
                &format!("{blade}_thickness"),
                &format!("temp_{blade}"),
            ),
        );
    }
    d
}

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
            ("n_beads", "0".to_string()),
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
        {
            for &(name, value, unit, _) in AS_BUILT {
                if set.contains(name) {
                    set.apply_text(name, value)?;
                } else {
                    set.define(name, value)?;
                }
                set.set_unit(name, unit)?;
            }
            // each wire set and blade at its own temperature, the model's by default
            for set_name in WIRE_SETS.map(|w| w.0).into_iter().chain(BLADE_TAGS) {
                let name = format!("temp_{set_name}");
                set.define(&name, "temperature")?;
                set.set_unit(&name, "K")?;
            }
            // the pendulum dilution factor of each wire set: by default l/λ, what the
            // bending terms give a wire clamped at both ends (so the bending loss is not
            // rescaled); a number imposes a given (measured) dilution
            for (wires, _, tension, radius, youngs, length) in as_built_wire_sets() {
                let name = format!("dilution_{wires}");
                set.define(&name, &computed_dilution(length, youngs, radius, tension))?;
                set.set_unit(&name, "")?;
            }
        }
        Ok(set)
    }

    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        as_built_damping()
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
        // quad-aligo's fibres: necks at both ends, one effective wire each
        let profile = FibreProfile::tapered(
            l3,
            (v("l3_neck")?, v("r3_neck")?),
            v("r3")?,
            (sec_3.youngs_modulus, sec_3.shear_modulus, v("silica_rho")?),
        );
        profile.check("the fibres (l3, l3_neck, r3_neck, r3)")?;
        let profile = Some(profile);
        let m_beads = 4.0 * pendkit_model::beads::beads_mass(&sec_3, profile.as_ref(), l3, beads);

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
            (&sec_3, profile.as_ref(), m3 * g),
            (beads, BeadJoints::Clamped),
            &chain::tags("fibre"),
        )?;
        // the test mass along the beam: x3 + θ z3 (see the README for the sign)
        b.named_output("tm_beam", &[("x3", 1.0), ("z3", v("vh_theta")?)])?;
        b.build()
    }
}
