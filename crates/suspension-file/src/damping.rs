//! The damping a suspension file implies: each wire set's and blade set's material gives its
//! tags a default (structural loss on stretch, bending and torsion, and for round wires of a
//! material with thermal constants the thermoelastic peak on bending, with the stress term),
//! and `[damping.<tag>]` tables replace the fields they give.

use std::collections::BTreeMap;

use pendkit_model::DampingSpec;

use crate::read::Ex;
use crate::source::FileError;
use crate::spec::{MaterialSpec, Points, Spec, StageFile, WireSet};

/// Every tag's default damping: material defaults, then the file's own tables merged in.
pub fn damping(spec: &Spec) -> Result<BTreeMap<String, DampingSpec>, FileError> {
    let mut out: BTreeMap<String, DampingSpec> = BTreeMap::new();
    let mut insert = |tag: String, d: DampingSpec, at: &crate::source::At| {
        match out.get(&tag) {
            Some(existing) if *existing != d => Err(at.error(format!(
                "tag '{tag}' already gets different damping from another part's material; give this part its own tags"
            ))),
            _ => {
                out.insert(tag, d);
                Ok(())
            }
        }
    };
    for stage in &spec.stages {
        for set in stage.wire_sets() {
            let Some(name) = &set.material else { continue };
            let material = find_material(spec, &name.value, &name.at)?;
            for (tag, d) in wire_damping(spec, stage, set, material) {
                insert(tag, d, &set.tags.at)?;
            }
        }
        if let Some(blades) = &stage.blades {
            let fields = blades.fields.or(&spec.blade_defaults);
            if let Some(name) = &fields.material {
                let material = find_material(spec, &name.value, &name.at)?;
                if let Some(phi) = &material.loss_angle {
                    let tag = blade_tag(stage, &fields.tag);
                    insert(tag, DampingSpec::structural(&phi.text), &blades.at)?;
                }
            }
        }
    }
    for d in &spec.damping {
        let text = |e: &Option<Ex>| e.as_ref().map(|e| e.text.clone());
        let given = DampingSpec {
            real: text(&d.real),
            structural: text(&d.structural),
            viscous: text(&d.viscous),
            imag: text(&d.imag),
            thermoelastic: d
                .thermoelastic
                .as_ref()
                .map(|(delta, tau)| (delta.text.clone(), tau.text.clone())),
        };
        out.entry(d.tag.clone()).or_default().merge(&given);
    }
    Ok(out)
}

/// The tag of a stage's blades.
pub fn blade_tag(stage: &StageFile, tag: &Option<crate::source::Located<String>>) -> String {
    tag.as_ref()
        .map(|t| t.value.clone())
        .unwrap_or_else(|| format!("{}_blades", stage.body))
}

/// The material called `name`.
pub fn find_material<'s>(
    spec: &'s Spec,
    name: &str,
    at: &crate::source::At,
) -> Result<&'s MaterialSpec, FileError> {
    spec.materials
        .iter()
        .find(|m| m.name == name)
        .ok_or_else(|| {
            let known: Vec<&str> = spec.materials.iter().map(|m| m.name.as_str()).collect();
            at.error(format!(
                "unknown material '{name}' (materials: {})",
                if known.is_empty() {
                    "none defined".to_string()
                } else {
                    known.join(", ")
                }
            ))
        })
}

/// Number of points a [`Points`] spreads to.
pub fn point_count(p: &Points) -> usize {
    p.base.len() << p.mirror.len()
}

/// Material damping of a wire set's tags `<p>_stretch`, `<p>_bending`, `<p>_torsion`:
/// structural φ on each and, for a round wire of a material with density, specific heat,
/// conductivity and expansion, the thermoelastic peak on bending (physics_oracles.md §7, with
/// the stress term): Δ = (E T/ρC)(α − σβ/E)², τ = ρ C d² / (2.16 · 2π · K), σ = T/(π r²),
/// T the nominal static tension from the weight of the bodies hung below (blade tips and
/// beads, a fraction of a percent, left out).
fn wire_damping(
    spec: &Spec,
    stage: &StageFile,
    set: &WireSet,
    m: &MaterialSpec,
) -> Vec<(String, DampingSpec)> {
    let prefix = &set.tags.value;
    let Some(phi) = &m.loss_angle else {
        return Vec::new();
    };
    let phi = phi.text.clone();
    let mut bending = DampingSpec::structural(&phi);
    let thermal = (
        &m.density,
        &m.specific_heat,
        &m.conductivity,
        &m.thermal_expansion,
    );
    let youngs = set.youngs_modulus.as_ref().or(m.youngs_modulus.as_ref());
    if let ((Some(rho), Some(c), Some(k), Some(alpha)), Some(r), Some(e)) =
        (thermal, &set.radius, youngs)
    {
        let (rho, c, k, alpha, r, e) = (
            rho.paren(),
            c.paren(),
            k.paren(),
            alpha.paren(),
            r.paren(),
            e.paren(),
        );
        let beta = m.dlne_dt.as_ref().map_or("(0)".to_string(), Ex::paren);
        let stress = format!("({})/(pi*{r}^2)", nominal_tension(spec, stage, set));
        let delta = format!("{e}*temperature/({rho}*{c})*({alpha} - {stress}*{beta}/{e})^2");
        let tau = format!("{rho}*{c}*(2*{r})^2/(2.16*2*pi*{k})");
        bending.thermoelastic = Some((delta, tau));
    }
    vec![
        (format!("{prefix}_stretch"), DampingSpec::structural(&phi)),
        (format!("{prefix}_bending"), bending),
        (format!("{prefix}_torsion"), DampingSpec::structural(&phi)),
    ]
}

/// The bodies hung from `body`, itself first, depth first in the order of the stages.
pub fn subtree<'s>(spec: &'s Spec, body: &'s str) -> Vec<&'s str> {
    let mut out = Vec::new();
    let mut visit = vec![body];
    while let Some(b) = visit.pop() {
        if out.contains(&b) {
            continue; // a cycle, reported by the build
        }
        out.push(b);
        // children pushed in reverse so that the first stage is visited first
        for stage in spec.stages.iter().rev().filter(|s| s.from.value == b) {
            visit.push(&stage.body);
        }
    }
    out
}

/// The static tension of one wire of `set` at the nominal geometry, as an expression of the
/// parameters: (Σ masses hung) g / (wires in the stage) · l / vertical extent.
fn nominal_tension(spec: &Spec, stage: &StageFile, set: &WireSet) -> String {
    let masses: Vec<String> = subtree(spec, &stage.body)
        .into_iter()
        .filter_map(|b| spec.bodies.iter().find(|x| x.name == b))
        .filter_map(|b| b.mass.as_ref().map(Ex::paren))
        .collect();
    let wires: usize = stage.wire_sets().map(|s| point_count(&s.lower)).sum();
    let gravity = spec
        .gravity
        .as_ref()
        .map_or("(9.81)".to_string(), Ex::paren);
    let l = set.length.paren();
    // the first wire: the unmirrored points, on the first blade tip if there are blades
    let tip = stage.blades.as_ref().map(|b| &b.tips.base[0].value);
    let upper = &set.upper.base[0].value;
    let lower = &set.lower.base[0].value;
    let offset = |k: usize| {
        let up = match tip {
            Some(t) => format!("({}+{})", t[k].paren(), upper[k].paren()),
            None => upper[k].paren(),
        };
        format!("({up}-{})", lower[k].paren())
    };
    format!(
        "({})*{gravity}/{wires}*{l}/sqrt({l}^2-{}^2-{}^2)",
        if masses.is_empty() {
            "0".to_string()
        } else {
            masses.join("+")
        },
        offset(0),
        offset(1)
    )
}
