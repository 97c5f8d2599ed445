//! Building blocks of the Rust `quad-aligo` model (the other bundled models are files):
//! blade tips, wires between bodies, and violin-mode beads on tapered fibres.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use pendkit_energy::{BodyId, EndDirection, SpringEnd, Wire, WireEnd, WireSection, WireTags};
use pendkit_model::beads::{BeadJoints, BeadedFibre, add_beaded_fibre};
use pendkit_model::{BodySpec, BuildError, FibreProfile, Shape, SystemBuilder};
use pendkit_params::Resolved;

/// How blade tips are modelled (T020205 §6.3–§6.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blades {
    /// Massless tip moving along the mounting body's z axis: a float ("xtra-lite").
    XtraLite,
    /// Tip with mass moving along the mounting body's z axis: one variable ("lite").
    Lite,
    /// Tip as a 6-DOF body with mass on a 6x6 spring ("full").
    Full,
    /// Massless tip with vertical and lateral (x) compliance: two floats ("lateral").
    Lateral,
}

impl Blades {
    /// Mass (kg) of one blade tip in this form (parameter `blade_tip_mass`, or 0).
    pub fn tip_mass(self, p: &Resolved) -> Result<f64, BuildError> {
        match self {
            Blades::Lite | Blades::Full => Ok(p.get("blade_tip_mass")?),
            Blades::XtraLite | Blades::Lateral => Ok(0.0),
        }
    }

    /// The blade-tip parameters each form needs, with defaults (documented assumptions:
    /// no public blade data is at hand).
    pub fn parameters(self) -> Vec<(&'static str, &'static str)> {
        match self {
            Blades::XtraLite => vec![],
            // effective tip mass of a ~0.2 kg maraging blade, of order a quarter of it
            Blades::Lite => vec![("blade_tip_mass", "0.05")],
            Blades::Full => vec![
                ("blade_tip_mass", "0.05"),
                // tip inertia m r² with r = 2 cm
                ("blade_tip_inertia", "blade_tip_mass*0.02^2"),
                // stiffness of the non-working directions (N/m, N m/rad)
                ("blade_stiff_translation", "1e6"),
                ("blade_stiff_rotation", "1e3"),
            ],
            // lateral stiffness per blade as a multiple of its vertical stiffness
            Blades::Lateral => vec![("blade_lateral_ratio", "300")],
        }
    }
}

/// One blade: mounted on `parent` with its tip at `tip` (m, parent coordinates), vertical
/// stiffness `kc` (N/m), pulled by its wires with force `pull` at the nominal geometry.
pub struct Blade<'a> {
    /// Suffix of the tip's coordinate names, e.g. `0l`.
    pub name: &'a str,
    /// The body the blade is clamped to.
    pub parent: BodyId,
    /// Lab position of the parent's origin at the nominal geometry (m); the parent is level.
    pub parent_origin: Vector3<f64>,
    /// Tip position in parent coordinates (m).
    pub tip: Vector3<f64>,
    /// Vertical stiffness (N/m).
    pub kc: f64,
    /// Force of the wires on the tip at the nominal geometry (N, parent axes; the parent is
    /// level there).
    pub pull: Vector3<f64>,
    /// Damping tag.
    pub tag: &'a str,
}

fn num(x: f64) -> String {
    // Rust prints f64 without exponent and exactly round-trippable
    format!("({x})")
}

/// Adds a blade in the form `blades` and returns the tip body; wires attach to it at
/// (±s, 0, 0) in its coordinates. The blade's preload balances the wires' pull and the
/// tip's weight, so that the tip is in equilibrium at the nominal geometry (entries for
/// directions a form does not let the tip move in are inert).
pub fn blade(
    b: &mut SystemBuilder,
    blade: &Blade,
    blades: Blades,
    p: &Resolved,
    g: f64,
) -> Result<BodyId, BuildError> {
    let (z, x) = (format!("zb{}", blade.name), format!("xb{}", blade.name));
    let t = &blade.tip;
    let tip_name = format!("blade{}", blade.name);
    let mut stiffness = Vector6::new(0.0, 0.0, blade.kc, 0.0, 0.0, 0.0);
    let mut tip_weight = 0.0;
    let tip = match blades {
        Blades::XtraLite | Blades::Lateral | Blades::Lite => {
            let x_expr = if blades == Blades::Lateral {
                b.float(&x, 0.0)?;
                stiffness[0] = p.get("blade_lateral_ratio")? * blade.kc;
                format!("{} + {x}", num(t.x))
            } else {
                num(t.x)
            };
            let mut spec = BodySpec::new(&tip_name).on(blade.parent).pose([
                &x_expr,
                &num(t.y),
                &format!("{} + {z}", num(t.z)),
                "0",
                "0",
                "0",
            ]);
            if blades == Blades::Lite {
                b.variable(&z, 0.0)?;
                let m = p.get("blade_tip_mass")?;
                spec = spec.mass(m);
                tip_weight = m * g;
            } else {
                b.float(&z, 0.0)?;
            }
            b.body(spec)?
        }
        Blades::Full => {
            let at = blade.parent_origin + t;
            let names =
                ["x", "y", "z", "yaw", "pitch", "roll"].map(|n| format!("{n}b{}", blade.name));
            for (k, n) in names.iter().enumerate() {
                b.variable(n, if k < 3 { at[k] } else { 0.0 })?;
            }
            let m = p.get("blade_tip_mass")?;
            let i = p.get("blade_tip_inertia")?;
            tip_weight = m * g;
            let (kt, kr) = (
                p.get("blade_stiff_translation")?,
                p.get("blade_stiff_rotation")?,
            );
            stiffness = Vector6::new(kt, kt, blade.kc, kr, kr, kr);
            b.body(
                BodySpec::new(&tip_name)
                    .pose(names.each_ref().map(String::as_str))
                    .mass(m)
                    .inertia(Matrix3::identity() * i),
            )?
        }
    };
    // the tip frame's origin is the tip itself in every form
    let ends = [
        SpringEnd {
            body: blade.parent,
            point: *t,
            angles: [0.0; 3],
        },
        SpringEnd {
            body: tip,
            point: Vector3::zeros(),
            angles: [0.0; 3],
        },
    ];
    b.spring(
        &tip_name,
        ends,
        Matrix6::from_diagonal(&stiffness),
        Vector6::new(
            blade.pull.x,
            blade.pull.y,
            blade.pull.z - tip_weight,
            0.0,
            0.0,
            0.0,
        ),
        blade.tag,
    )?;
    Ok(tip)
}

/// Nominal vertical extent (m) of a wire of length `l` whose ends differ by `dy` in y.
pub fn vertical(l: f64, dy: f64) -> f64 {
    (l * l - dy * dy).sqrt()
}

/// A round wire's section from parameters `r<suffix>`, `Y<suffix>` and Poisson's ratio
/// `nu` (a parameter name), with density `rho` (a parameter name).
pub fn round_section(
    p: &Resolved,
    r: &str,
    y: &str,
    nu: &str,
    rho: &str,
) -> Result<WireSection, BuildError> {
    let e = p.get(y)?;
    let g = pendkit_model::shear_modulus(&format!("parameter '{nu}'"), e, p.get(nu)?)?;
    Ok(WireSection::round(p.get(r)?, e, g, p.get(rho)?))
}

/// Tags `<set>_stretch`, `<set>_bending`, `<set>_torsion`.
pub fn tags(set: &str) -> WireTags {
    WireTags {
        stretch: format!("{set}_stretch"),
        bending: format!("{set}_bending"),
        torsion: format!("{set}_torsion"),
    }
}

/// One straight wire, clamped at both ends (auto directions), of nominal length `length`
/// (m) carrying `tension` (N).
pub fn wire(
    b: &mut SystemBuilder,
    name: &str,
    (upper, upper_point): (BodyId, Vector3<f64>),
    (lower, lower_point): (BodyId, Vector3<f64>),
    (section, length, tension): (&WireSection, f64, f64),
    tags: &WireTags,
) -> Result<(), BuildError> {
    let end = |body, point| WireEnd {
        body,
        point,
        direction: EndDirection::Auto,
    };
    b.wire(Wire::from_tension(
        name,
        [end(upper, upper_point), end(lower, lower_point)],
        section.clone(),
        length,
        tension,
        tags.clone(),
    ))?;
    Ok(())
}

/// The number of violin beads per fibre from parameter `n_beads` (a whole number, 0–200:
/// dense linear algebra, and 200 beads per fibre is already ~2400 degrees of freedom).
pub fn bead_count(p: &Resolved) -> Result<usize, BuildError> {
    pendkit_model::whole_number(p, "n_beads", 0..=200)
}

/// The four lowest wires (or fibres), from `upper` at (±sl, ±n4, −d3) to `lower` at
/// (±sl, ±n5, d4) (parameters of those names, m), each of length `l3` and carrying a quarter
/// of `weight` (N) along its slope, with `beads` violin beads each. `heights` are the two
/// bodies' nominal centre heights (m); the bodies are level and centred on the z axis there.
/// With a `profile` (a tapered fibre of length `l3`), each segment follows the profile
/// ([`FibreProfile::slice`]); without beads a fibre is one effective wire of it.
pub fn lowest_wires(
    b: &mut SystemBuilder,
    p: &Resolved,
    (upper, lower): (BodyId, BodyId),
    heights: [f64; 2],
    (section, profile, weight): (&WireSection, Option<&FibreProfile>, f64),
    (beads, joints): (usize, BeadJoints),
    tags: &WireTags,
) -> Result<(), BuildError> {
    let (sl, n4, n5, d3, d4, l3) = (
        p.get("sl")?,
        p.get("n4")?,
        p.get("n5")?,
        p.get("d3")?,
        p.get("d4")?,
        p.get("l3")?,
    );
    let vert = vertical(l3, n4 - n5);
    for (k, (sx, sy)) in [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)]
        .into_iter()
        .enumerate()
    {
        let (upper_point, lower_point) = (
            Vector3::new(sx * sl, sy * n4, -d3),
            Vector3::new(sx * sl, sy * n5, d4),
        );
        let tension = weight / 4.0 * l3 / vert;
        let end = |body, point| WireEnd {
            body,
            point,
            direction: EndDirection::Auto,
        };
        add_beaded_fibre(
            b,
            &BeadedFibre {
                name: &format!("f{}", k + 1),
                upper: end(upper, upper_point),
                lower: end(lower, lower_point),
                nominal: [
                    Vector3::z() * heights[0] + upper_point,
                    Vector3::z() * heights[1] + lower_point,
                ],
                section,
                length: l3,
                tension,
                g: p.get("g")?,
                beads,
                joints,
                profile,
            },
            tags,
        )?;
    }
    Ok(())
}

/// The drawing shape of a cylinder of `radius` and `length` (m) with its axis along body x
/// (an optic or a mass of the same form).
pub fn cylinder_along_x(radius: f64, length: f64) -> Shape {
    Shape::Cylinder {
        radius,
        half_length: length / 2.0,
        axis: 0,
    }
}
