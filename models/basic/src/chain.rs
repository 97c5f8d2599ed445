//! `chain`: `n_stages` identical rigid bodies one below the other, each hung by four vertical
//! steel wires from the one above (the first from the support). A suspension whose size is
//! a parameter, for scaling benchmarks: 6 variables and 4 wires per stage.
//!
//! The geometry is exactly symmetric (every wire vertical, attached at (±a, ±b) on both of
//! its bodies, bodies level and centred on the z axis), so the stiffness splits into the
//! blocks x–pitch, y–roll, z and yaw with exact zeros between them.

use std::collections::BTreeMap;

use pendkit_energy::{EndDirection, System};
use pendkit_model::{BodySpec, BuildError, DampingSpec, Model, SystemBuilder, whole_number};
use pendkit_params::{ParamError, ParamSet, Resolved};

use crate::{
    FourWires, STEEL_WIRE, four_wires, params, round_section, support, wire_damping, wire_tags,
};

/// Largest `n_stages`: 1200 variables, where the dense eigen-solves already take seconds
/// (their cost grows as the cube of the size).
pub const MAX_STAGES: usize = 200;

/// The chain model (see the module documentation).
pub struct Chain;

impl Model for Chain {
    pendkit_model::defaults_cache_per_impl!();

    fn name(&self) -> &'static str {
        "chain"
    }

    fn summary(&self) -> &'static str {
        "n_stages (default 4) 40 kg bodies in a vertical chain, each on 4 vertical steel wires"
    }

    fn parameters(&self) -> Result<ParamSet, ParamError> {
        let mut defs = vec![
            ("g", "9.81"),
            // number of bodies: a whole number from 1 to MAX_STAGES (200)
            ("n_stages", "4"),
            // each body is the rigid-body model's: 40 kg with its inertias about x, y, z (kg m²)
            ("m", "40"),
            ("Ix", "0.57"),
            ("Iy", "0.42"),
            ("Iz", "0.42"),
            // wires of the small models' length, between attachment points (m)
            ("l_wire", "0.6"),
            // attachments at (±a, ±b) as the rigid-body model's fibres: 5 mm either side of
            // the centre along x, 0.17 m (the body's radius) along y
            ("a_wire", "0.005"),
            ("b_wire", "0.17"),
            // the wires from above attach d_top above each body's centre of mass, those to
            // the body below d_bottom beneath it: 10 mm each, the rigid-body model's break-off,
            // which keeps the pitch modes low and stable
            ("d_top", "0.010"),
            ("d_bottom", "0.010"),
        ];
        // The double pendulum's steel wires (r = 0.5 mm). A wire of stage k carries
        // (n_stages − k + 1) m g / 4: 0.5 GPa at the top of the default 4-stage chain, about a
        // third of a music wire's breaking stress. Long chains overload their top wires
        // (12.5 GPa, strain 6 %, at 100 stages); the model stays linear-elastic, which is
        // what a scaling benchmark needs, but it is then no design.
        defs.extend(STEEL_WIRE);
        params(&defs)
    }

    fn damping(&self) -> BTreeMap<String, DampingSpec> {
        wire_damping("wire", "phi_wire")
    }

    fn build(&self, p: &Resolved) -> Result<System, BuildError> {
        let stages = whole_number(p, "n_stages", 1..=MAX_STAGES)?;
        let (g, m, l) = (p.get("g")?, p.get("m")?, p.get("l_wire")?);
        let (d_top, d_bottom) = (p.get("d_top")?, p.get("d_bottom")?);
        let section = round_section(p, "wire")?;
        let tags = wire_tags("wire");
        let spread = (p.get("a_wire")?, p.get("b_wire")?);
        let inertia = (p.get("Ix")?, p.get("Iy")?, p.get("Iz")?);
        // centre-to-centre height of one stage (m)
        let pitch = d_bottom + l + d_top;

        let mut b = SystemBuilder::new(g);
        let support = support(&mut b)?;
        // the body above and the height of its attachment points (m, its coordinates)
        let mut above = (support, 0.0);
        for k in 1..=stages {
            // body k's centre: its top attachments hang l below the attachments above it
            let z = d_bottom - k as f64 * pitch;
            for (c, start) in ["x", "y", "z", "yaw", "pitch", "roll"]
                .into_iter()
                .zip([0.0, 0.0, z, 0.0, 0.0, 0.0])
            {
                b.variable(&format!("{c}{k}"), start)?;
            }
            let body = b.body(
                BodySpec::new(format!("mass{k}"))
                    .pose_suffix(&k.to_string())
                    .mass(m)
                    .inertia_diag(inertia.0, inertia.1, inertia.2),
            )?;
            let wires = FourWires {
                name: &format!("wire{k}_"),
                bodies: (above.0, body),
                spread,
                heights: (above.1, d_top),
                length: l,
                section: &section,
                tags: &tags,
                bottom: EndDirection::Auto,
            };
            // each stage's wires carry the bodies from this one down
            four_wires(&mut b, &wires, (stages - k + 1) as f64 * m * g)?;
            above = (body, -d_bottom);
        }
        b.build()
    }
}
