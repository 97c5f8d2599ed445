//! Fibres carrying violin-mode beads: the one construction of a beaded fibre, which the
//! suspension files build (uniform wires and tapered fibres alike).
//!
//! A fibre with N beads is N + 1 straight segments (tensioned beams, the wire elements)
//! with a point mass at each joint: the lumped-mass discretisation of the continuum, whose
//! violin modes converge to the continuum's, as 1/N² once the segments are much shorter
//! than the bending length √(EI/T). Each segment carries the weight of the beads below it,
//! so the limit is a fibre carrying its own weight, which continuum fibres leave out (a few
//! 1e-6 higher: docs/performance.md, "Violin modes"). The beads' translations are variables
//! (they carry the lumped mass); how the segments join at a bead is [`BeadJoints`]:
//!
//! - [`BeadJoints::Clamped`] (the default): each bead has a massless joint body at the
//!   bead's position whose orientation is three floats (yaw, pitch, roll; `yaw<name>b<k>`
//!   ...), and both segments are clamped to it. The slope is continuous across the bead and
//!   the bending moment is carried through it, so the chain is a beam discretisation whose
//!   bending energy converges to the continuum's. The joint floats carry no inertia (a
//!   slice's rotary inertia changes the modes by O(h²), the order of the mass lumping's
//!   error, and as variables the angles would be free modes at 0 Hz before bending joins)
//!   and are eliminated exactly by the stage model. The joint's yaw joins the segments'
//!   twist in series, so the fibre's torsion stiffness is the whole fibre's, not its end
//!   segments' (as with hinged beads, whose orientation is fixed).
//!
//!   Stages: before 1B nothing turns a joint's pitch and roll. In 0A and 0B no term touches
//!   the joint angles at all and the assembly leaves them out of the stage (exact: they
//!   carry no energy). In 1A the torsion holds the yaw and, on a vertical fibre, touches
//!   pitch and roll with exact zeros, so they are left out too. On a slanted fibre the
//!   twist axis is not vertical: torsion holds the joint's rotation about the fibre and
//!   nothing holds the others (the kink the beads' weight puts at a joint holds one of
//!   them with ε² of the twist's stiffness), and the assembly holds those at zero in 1A
//!   (crates/mechanics/assembly/src/redundant.rs): before bending, a joint turns about its fibre.
//! - [`BeadJoints::Hinged`]: the segments are hinged at the beads (no moment carried, the
//!   loaded string of the 2005 violin model): too soft once a segment is shorter than a
//!   few bending lengths (kept for the loaded-string reference values).
//!
//! The joint floats are pinned at zero in the equilibrium search: every clamp is "auto"
//! (straight at the reference), so zero is where the joints sit.

use nalgebra::Vector3;
use pendkit_system::{EndDirection, Real, Wire, WireEnd, WireSection, WireTags};

use crate::{BodySpec, BuildError, FibreProfile, SystemBuilder};

/// How the segments of a beaded fibre join at the beads.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum BeadJoints {
    /// Slope continuous, bending moment carried (converges to the continuum).
    #[default]
    Clamped,
    /// Free to pivot, no bending moment (the loaded string).
    Hinged,
}

impl BeadJoints {
    /// The joint kind called `name` (`clamped` or `hinged`), if it is one.
    pub fn from_name(name: &str) -> Option<BeadJoints> {
        match name {
            "clamped" => Some(BeadJoints::Clamped),
            "hinged" => Some(BeadJoints::Hinged),
            _ => None,
        }
    }
}

/// A fibre between two bodies, optionally carrying violin-mode beads.
pub struct BeadedFibre<'a, S: Real = f64> {
    /// Name; segments are `<name>s1 ...`, beads `<name>b1 ...` (coordinates
    /// `x<name>b1 y<name>b1 z<name>b1 ...`), clamped joints `<name>j1 ...` (floats
    /// `yaw<name>b1 pitch<name>b1 roll<name>b1 ...`).
    pub name: &'a str,
    /// Written before every name the fibre makes (wire, segments, beads, joints and their
    /// coordinates): a scene's include prefix (`itm_` gives `itm_xf1b1`), empty otherwise.
    pub scope: &'a str,
    /// The upper end: body, attachment point (m, body coordinates) and direction.
    pub upper: WireEnd<S>,
    /// The lower end.
    pub lower: WireEnd<S>,
    /// Lab positions of the upper and lower attachments at the nominal geometry (m).
    pub nominal: [Vector3<S>; 2],
    /// Cross-section (not used with a `profile`).
    pub section: &'a WireSection<S>,
    /// Length between the attachment points (m).
    pub length: S,
    /// Tension of the lowest segment (N).
    pub tension: S,
    /// Gravitational acceleration (m/s²): each segment carries the weight of the beads
    /// below it.
    pub g: S,
    /// Number of beads (0: one plain fibre).
    pub beads: usize,
    /// How the segments join at the beads.
    pub joints: BeadJoints,
    /// A radius profile along the fibre (tapered fibres): each segment is then the slice of
    /// the profile it spans, and `section` is not used.
    pub profile: Option<&'a FibreProfile<S>>,
    /// Whether responses and noise take the fibre as a continuum
    /// ([`pendkit_system::Wire::continuum`]); only without beads, which carry the same mass.
    pub continuum: bool,
}

/// Largest number of violin beads per fibre: dense linear algebra, and 200 beads on each
/// of four fibres is already ~2400 degrees of freedom.
pub const MAX_BEADS: usize = 200;

/// Adds `f` split into `beads + 1` segments of equal length with point-mass beads between
/// them, each bead carrying one segment's mass μ L / (N + 1) (the lumped-mass rule; with a
/// profile, half of each neighbouring segment's mass). The ends are as `f.upper` and
/// `f.lower` say; the beads join the segments as `f.joints` says; each segment carries the
/// tension of the lowest plus the weight of the beads below it. More than [`MAX_BEADS`]
/// beads is an error.
pub fn add_beaded_fibre<S: Real>(
    b: &mut SystemBuilder<S>,
    f: &BeadedFibre<S>,
    tags: &WireTags,
) -> Result<(), BuildError> {
    if f.continuum && f.beads > 0 {
        return Err(BuildError::Invalid {
            item: format!("fibre '{}{}'", f.scope, f.name),
            message: format!(
                "a continuum fibre has its own violin modes: give it no beads (it has {})",
                f.beads
            ),
        });
    }
    if f.beads > MAX_BEADS {
        return Err(BuildError::Invalid {
            item: format!("fibre '{}{}'", f.scope, f.name),
            message: format!(
                "add_beaded_fibre: beads is {}, at most {MAX_BEADS}",
                f.beads
            ),
        });
    }
    let segment = f.length / (f.beads + 1) as f64;
    let slices: Vec<FibreProfile<S>> = f
        .profile
        .map(|p| {
            (0..=f.beads)
                .map(|k| p.slice(segment * k as f64, segment * (k + 1) as f64))
                .collect()
        })
        .unwrap_or_default();
    let bead_masses: Vec<S> = (0..f.beads)
        .map(|k| match (slices.get(k), slices.get(k + 1)) {
            (Some(upper), Some(lower)) => (upper.mass() + lower.mass()) * 0.5,
            _ => f.section.linear_density * segment,
        })
        .collect();
    let mut above = f.upper.clone();
    for k in 0..=f.beads {
        let below = if k < f.beads {
            bead(b, f, k, bead_masses[k])?
        } else {
            f.lower.clone()
        };
        let name = if f.beads == 0 {
            format!("{}{}", f.scope, f.name)
        } else {
            format!("{}{}s{}", f.scope, f.name, k + 1)
        };
        let ends = [above, below.clone()];
        let carried = f.tension + bead_masses[k..].iter().copied().sum::<S>() * f.g;
        let wire = match slices.get(k) {
            None => Wire::from_tension(
                name,
                ends,
                f.section.clone(),
                segment,
                carried,
                tags.clone(),
            ),
            Some(slice) => {
                let section = match f.joints {
                    // a plain fibre, or a segment clamped at one end only: it bends at that
                    // clamp (the lower one for the last segment), within a bending length
                    _ if f.beads == 0 => slice.section(carried),
                    BeadJoints::Hinged => {
                        let (upper_r, lower_r) = slice.clamp_radii();
                        let r = if k == f.beads { lower_r } else { upper_r };
                        slice.section_bent_at(carried, r)
                    }
                    // clamped at both ends. An end segment bends most at the body's clamp,
                    // within a bending length of it (the moment at a bead, where the fibre
                    // is nearly straight, is far smaller): the clamp's radius. An inner
                    // segment bends along its whole length: its pieces in series. Either
                    // way the segment's constant tends to the local one as N grows.
                    BeadJoints::Clamped => {
                        let (upper_r, lower_r) = slice.clamp_radii();
                        let r = match k {
                            0 => upper_r,
                            _ if k == f.beads => lower_r,
                            _ => slice.series_bending_radius(),
                        };
                        slice.section_bent_at(carried, r)
                    }
                };
                slice.wire_with_section(name, ends, carried, section, tags.clone())
            }
        };
        b.wire(pendkit_system::Wire {
            continuum: f.continuum,
            ..wire
        })?;
        above = below;
    }
    Ok(())
}

/// Mass (kg) of the beads of one fibre of `length` (m) with `beads` beads, as
/// [`add_beaded_fibre`] places them: N/(N + 1) of a uniform fibre's mass, or with a
/// `profile`, the whole mass less half of the two end segments' (which the end bodies
/// carry). What the wires above the fibre carry besides the bodies.
pub fn beads_mass<S: Real>(
    section: &WireSection<S>,
    profile: Option<&FibreProfile<S>>,
    length: S,
    beads: usize,
) -> S {
    if beads == 0 {
        return S::from(0.0);
    }
    match profile {
        // N + 1 in floating point: no overflow for any count
        None => section.linear_density * length * beads as f64 / (beads as f64 + 1.0),
        Some(p) => {
            let segment = length / (beads as f64 + 1.0);
            let ends =
                p.slice(S::from(0.0), segment).mass() + p.slice(length - segment, length).mass();
            p.mass() - ends * 0.5
        }
    }
}

/// Bead `k` (from 0, top down) of `f` with `mass` (kg): the bead body and, with clamped
/// joints, its joint body; returns the end the segments attach to.
fn bead<S: Real>(
    b: &mut SystemBuilder<S>,
    f: &BeadedFibre<S>,
    k: usize,
    mass: S,
) -> Result<WireEnd<S>, BuildError> {
    let label = format!("{}b{}", f.name, k + 1);
    let names = ["x", "y", "z"].map(|c| format!("{}{c}{label}", f.scope));
    // the beads' start positions (search starts, not model numbers: real parts)
    let [top, bottom] = f.nominal.each_ref().map(|v| v.map(|x| x.re()));
    let at = top + (bottom - top) * ((k + 1) as f64 / (f.beads + 1) as f64);
    for (name, value) in names.iter().zip(at.iter()) {
        b.variable(name, *value)?;
    }
    let bead = b.body(
        BodySpec::new(format!("{}{label}", f.scope))
            .pose([&names[0], &names[1], &names[2], "0", "0", "0"])
            .mass(mass)
            .mode_family("violin"),
    )?;
    let (body, direction) = match f.joints {
        BeadJoints::Hinged => (bead, EndDirection::Hinged),
        BeadJoints::Clamped => {
            let angles = ["yaw", "pitch", "roll"].map(|c| format!("{}{c}{label}", f.scope));
            for angle in &angles {
                b.float(angle, 0.0)?;
                b.pin(angle)?;
            }
            let joint = b.body(
                BodySpec::new(format!("{}{}j{}", f.scope, f.name, k + 1)).pose([
                    &names[0], &names[1], &names[2], &angles[0], &angles[1], &angles[2],
                ]),
            )?;
            (joint, EndDirection::Auto)
        }
    };
    Ok(WireEnd {
        body,
        point: Vector3::from_element(S::from(0.0)),
        direction,
    })
}
