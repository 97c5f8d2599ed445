//! Building blocks shared by the quad and the triple: blade tips in each variant, wires
//! between bodies, violin-mode beads on fibres, and material damping.

use std::collections::BTreeMap;

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use pendkit_energy::{BodyId, EndDirection, SpringEnd, Wire, WireEnd, WireSection, WireTags};
use pendkit_model::losses::WireLoss;
use pendkit_model::{BodySpec, BuildError, DampingSpec, FibreProfile, Shape, SystemBuilder};
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

/// A vertical fibre between two bodies, optionally carrying violin-mode beads.
pub struct Fibre<'a> {
    /// Name; segments are `<name>s1 ...`, beads `<name>b1 ...` (coordinates
    /// `x<name>b1 y<name>b1 z<name>b1 ...`).
    pub name: &'a str,
    /// Upper body and attachment point (m, body coordinates).
    pub upper: (BodyId, Vector3<f64>),
    /// Lower body and attachment point.
    pub lower: (BodyId, Vector3<f64>),
    /// Lab positions of the upper and lower attachments at the nominal geometry (m).
    pub nominal: [Vector3<f64>; 2],
    /// Cross-section.
    pub section: &'a WireSection,
    /// Length between the attachment points (m).
    pub length: f64,
    /// Tension of the lowest segment (N).
    pub tension: f64,
    /// Number of beads (0: one plain fibre).
    pub beads: usize,
    /// A radius profile along the fibre (tapered fibres): each segment is then the slice of
    /// the profile it spans, and `section` is not used.
    pub profile: Option<&'a FibreProfile>,
}

/// Adds a fibre split into `beads + 1` segments with point-mass beads between them, each
/// bead carrying one segment's mass μ L / (N + 1) (the lumped-mass rule; with a profile,
/// half of each neighbouring segment's mass). The fibre is clamped at both ends and hinged
/// at the beads (a string between them); each segment carries the tension of the lowest
/// plus the weight of the beads below it.
pub fn beaded_fibre(
    b: &mut SystemBuilder,
    f: &Fibre,
    g: f64,
    tags: &WireTags,
) -> Result<(), BuildError> {
    let segment = f.length / (f.beads + 1) as f64;
    let slices: Vec<FibreProfile> = f
        .profile
        .map(|p| {
            (0..=f.beads)
                .map(|k| p.slice(k as f64 * segment, (k + 1) as f64 * segment))
                .collect()
        })
        .unwrap_or_default();
    let bead_masses: Vec<f64> = (0..f.beads)
        .map(|k| match (slices.get(k), slices.get(k + 1)) {
            (Some(upper), Some(lower)) => 0.5 * (upper.mass() + lower.mass()),
            _ => f.section.linear_density * segment,
        })
        .collect();
    let mut above = (f.upper.0, f.upper.1, EndDirection::Auto);
    for k in 0..=f.beads {
        let below = if k < f.beads {
            let names = ["x", "y", "z"].map(|c| format!("{c}{}b{}", f.name, k + 1));
            let at = f.nominal[0]
                + (f.nominal[1] - f.nominal[0]) * ((k + 1) as f64 / (f.beads + 1) as f64);
            for (name, value) in names.iter().zip(at.iter()) {
                b.variable(name, *value)?;
            }
            let bead = b.body(
                BodySpec::new(format!("{}b{}", f.name, k + 1))
                    .pose([&names[0], &names[1], &names[2], "0", "0", "0"])
                    .mass(bead_masses[k])
                    .mode_family("violin"),
            )?;
            (bead, Vector3::zeros(), EndDirection::Hinged)
        } else {
            (f.lower.0, f.lower.1, EndDirection::Auto)
        };
        let end = |(body, point, direction): &(BodyId, Vector3<f64>, EndDirection)| WireEnd {
            body: *body,
            point: *point,
            direction: direction.clone(),
        };
        let name = if f.beads == 0 {
            f.name.to_string()
        } else {
            format!("{}s{}", f.name, k + 1)
        };
        let ends = [end(&above), end(&below)];
        match slices.get(k) {
            None => {
                let carried =
                    f.tension + (f.beads - k) as f64 * (f.section.linear_density * segment) * g;
                b.wire(Wire::from_tension(
                    name,
                    ends,
                    f.section.clone(),
                    segment,
                    carried,
                    tags.clone(),
                ))?
            }
            Some(slice) => {
                let carried = f.tension + bead_masses[k..].iter().sum::<f64>() * g;
                // the segment bends at its clamped end: the lower one for the last segment
                let (upper_r, lower_r) = slice.clamp_radii();
                let r = if k == f.beads && k > 0 {
                    lower_r
                } else {
                    upper_r
                };
                let section = slice.section_bent_at(carried, r);
                b.wire(slice.wire_with_section(name, ends, carried, section, tags.clone()))?
            }
        };
        above = below;
    }
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
    beads: usize,
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
        beaded_fibre(
            b,
            &Fibre {
                name: &format!("f{}", k + 1),
                upper: (upper, upper_point),
                lower: (lower, lower_point),
                nominal: [
                    Vector3::z() * heights[0] + upper_point,
                    Vector3::z() * heights[1] + lower_point,
                ],
                section,
                length: l3,
                tension,
                beads,
                profile,
            },
            p.get("g")?,
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

/// Mass (kg) of the beads of one fibre: N/(N + 1) of a uniform fibre's mass, or with a
/// `profile`, the whole mass less half of the two end segments' (which the end bodies
/// carry, as in [`beaded_fibre`]).
pub fn beads_mass(
    section: &WireSection,
    profile: Option<&FibreProfile>,
    length: f64,
    beads: usize,
) -> f64 {
    if beads == 0 {
        return 0.0;
    }
    match profile {
        None => section.linear_density * length * beads as f64 / (beads + 1) as f64,
        Some(p) => {
            let segment = length / (beads + 1) as f64;
            let ends = p.slice(0.0, segment).mass() + p.slice(length - segment, length).mass();
            p.mass() - 0.5 * ends
        }
    }
}

/// Damping of a wire set from its material: structural φ on stretch, bending and torsion,
/// plus the thermoelastic peak on bending (docs/reference-values.md §7, with the stress term):
/// Δ = (Y T/ρC)(α − σβ/Y)², τ = ρ C d² / (2.16 · 2π · κ), σ = tension / area; no surface
/// loss (the 2005 models' convention). `material` prefixes the material parameters
/// (`<m>_phi`, `<m>_rho`, ...); `tension` and `radius`, `youngs` name the wire set's
/// parameters. See [`pendkit_model::losses`] for the general form.
pub fn wire_damping(
    set: &str,
    material: &str,
    tension: &str,
    radius: &str,
    youngs: &str,
) -> Vec<(String, DampingSpec)> {
    WireLoss {
        set,
        material,
        tension,
        youngs,
        clamp_radius: radius,
        surface: None,
        temperature: "temperature",
        dilution_scale: None,
    }
    .damping()
}

/// Collects damping entries into the map a model returns.
pub fn damping_map(
    entries: impl IntoIterator<Item = (String, DampingSpec)>,
) -> BTreeMap<String, DampingSpec> {
    entries.into_iter().collect()
}
