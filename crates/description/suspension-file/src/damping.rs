//! The damping a suspension file implies: each wire set's and blade set's material gives its
//! tags a default (structural loss on stretch, bending and torsion, and for round wires of a
//! material with thermal constants the thermoelastic peak on bending, with the stress term),
//! and `[damping.<tag>]` tables replace the fields they give.

use std::collections::{BTreeMap, HashMap, HashSet};

use pendkit_model::DampingSpec;
use pendkit_model::fibre_inverse_radius;
use pendkit_model::losses::{LossMaterial, WireLoss, blade_loss};

use crate::read::Ex;
use crate::source::FileError;
use crate::spec::{BladeFields, MaterialSpec, Points, Spec, StageFile, WireSet};

/// Every tag's default damping: material defaults, then the file's own tables merged in.
pub fn damping(spec: &Spec) -> Result<BTreeMap<String, DampingSpec>, FileError> {
    let mut out: BTreeMap<String, DampingSpec> = BTreeMap::new();
    let hanging = Hanging::new(spec);
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
            for (tag, d) in wire_damping(spec, &hanging, stage, set, material)? {
                insert(tag, d, &set.tags.at)?;
            }
        }
        if let Some(blades) = &stage.blades {
            let fields = blades.fields.or(&spec.blade_defaults);
            if let Some(name) = &fields.material {
                let material = find_material(spec, &name.value, &name.at)?;
                if let Some(d) = blade_damping(&fields, material)? {
                    let tag = blade_tag(stage, &fields.tag);
                    insert(tag, d, &blades.at)?;
                }
            }
        }
    }
    for d in &spec.damping {
        let given = out.entry(d.tag.clone()).or_default();
        for (field, ex) in &d.fields {
            given
                .set_field(field.name, &ex.text)
                .map_err(|e| ex.at.error(e))?;
        }
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

/// Number of points a [`Points`] spreads to (each mirror doubling the list), `usize::MAX`
/// when that overflows (a hand-made [`Points`] with 64 mirrors: the build refuses it).
pub fn point_count(p: &Points) -> usize {
    u32::try_from(p.mirror.len())
        .ok()
        .and_then(|k| 1usize.checked_shl(k))
        .and_then(|copies| p.base.len().checked_mul(copies))
        .unwrap_or(usize::MAX)
}

/// The constants of `m` the thermoelastic loss needs (density, specific heat,
/// conductivity, expansion, Young's modulus: `youngs` overrides the material's), as
/// expressions, or `None` if one is missing; β = d ln E/dT is 0 and the dissipation depth
/// 0 when absent.
fn loss_material(m: &MaterialSpec, youngs: Option<&Ex>) -> Option<LossMaterial> {
    let need = |e: &Option<Ex>| e.as_ref().map(Ex::paren);
    let or_zero = |e: &Option<Ex>| e.as_ref().map_or("(0)".to_string(), Ex::paren);
    Some(LossMaterial {
        phi: need(&m.loss_angle)?,
        rho: need(&m.density)?,
        specific_heat: need(&m.specific_heat)?,
        conductivity: need(&m.conductivity)?,
        alpha: need(&m.thermal_expansion)?,
        dlne_dt: or_zero(&m.dlne_dt),
        dissipation_depth: or_zero(&m.dissipation_depth),
        youngs: youngs.or(m.youngs_modulus.as_ref()).map(Ex::paren)?,
    })
}

/// Material damping of a wire set's tags `<p>_stretch`, `<p>_bending`, `<p>_torsion`
/// ([`pendkit_model::losses::WireLoss`]): structural φ on each and, for a round wire of a
/// material with density, specific heat, conductivity and expansion, the thermoelastic
/// peak on bending at the clamp's radius (the neck's for a tapered fibre), with the stress
/// term σ = T/(π r²), T the nominal static tension from the weight of the bodies hung below
/// (blade tips and beads, a fraction of a percent, left out). With `surface_loss`, the
/// material's dissipation depth adds surface loss (weighted over the profile of a tapered
/// fibre); `temperature` sets the tags' noise temperature and the Δ it enters; `dilution`
/// scales the bending loss by (computed dilution)/(given).
fn wire_damping(
    spec: &Spec,
    hanging: &Hanging,
    stage: &StageFile,
    set: &WireSet,
    m: &MaterialSpec,
) -> Result<Vec<(String, DampingSpec)>, FileError> {
    let prefix = &set.tags.value;
    let Some(phi) = &m.loss_angle else {
        return Ok(Vec::new());
    };
    let temperature = set.temperature.as_ref().map(Ex::paren);
    let lossy = loss_material(m, set.youngs_modulus.as_ref());
    let (Some(material), Some(r)) = (lossy, &set.radius) else {
        // no thermoelastic loss: structural φ alone (a profile still shapes the mechanics);
        // surface loss and a given dilution are written for the full loss model only
        if let Some(field) = [
            (set.surface_loss, "surface_loss"),
            (set.dilution.is_some(), "dilution"),
        ]
        .iter()
        .find(|(given, _)| *given)
        {
            return Err(set.at.error(format!(
                "`{}` needs a round wire (`radius`) of a material with density, specific_heat, conductivity, thermal_expansion and youngs_modulus",
                field.1
            )));
        }
        let mut structural = DampingSpec::structural(&phi.text);
        structural.temperature = temperature;
        return Ok(["stretch", "bending", "torsion"]
            .into_iter()
            .map(|part| (format!("{prefix}_{part}"), structural.clone()))
            .collect());
    };
    if set.surface_loss && m.dissipation_depth.is_none() {
        return Err(set.at.error(format!(
            "`surface_loss` needs the material's `dissipation_depth` (m) (material '{}')",
            m.name
        )));
    }
    let r = r.paren();
    let length = set.length.paren();
    let clamp_radius = set
        .profile
        .as_ref()
        .map_or_else(|| r.clone(), |p| p.neck_radius.paren());
    let surface = set.surface_loss.then(|| match &set.profile {
        None => (format!("1/{r}"), format!("1/{r}")),
        Some(p) => {
            let profile = (
                length.as_str(),
                &*p.neck_length.paren(),
                &*p.neck_radius.paren(),
                r.as_str(),
            );
            (
                fibre_inverse_radius(profile, 2),
                fibre_inverse_radius(profile, 4),
            )
        }
    });
    let tension = format!("({})", nominal_tension(spec, hanging, stage, set));
    let youngs = material.youngs.clone();
    // the dilution a wire clamped at both ends has, l/λ, λ = √(Y π r⁴/4 / T)
    let dilution_scale = set.dilution.as_ref().map(|given| {
        format!(
            "({length}/sqrt({youngs}*pi*{clamp_radius}^4/4/{tension}))/{}",
            given.paren()
        )
    });
    let temperature = temperature.unwrap_or_else(|| "temperature".to_string());
    Ok(WireLoss {
        set: prefix,
        material,
        tension: &tension,
        youngs: &youngs,
        clamp_radius: &clamp_radius,
        surface,
        temperature: &temperature,
        dilution_scale,
    }
    .damping())
}

/// The damping of a blade set of material `m`: its structural φ and, with `thickness`, the
/// thermoelastic loss of a plate bent across it ([`pendkit_model::losses::blade_loss`]), at
/// the set's `temperature`; `None` for a material without a loss angle.
fn blade_damping(fields: &BladeFields, m: &MaterialSpec) -> Result<Option<DampingSpec>, FileError> {
    let Some(phi) = &m.loss_angle else {
        return Ok(None);
    };
    let temperature = fields.temperature.as_ref().map(Ex::paren);
    let Some(thickness) = &fields.thickness else {
        let mut d = DampingSpec::structural(&phi.text);
        d.temperature = temperature;
        return Ok(Some(d));
    };
    let material = loss_material(m, None).ok_or_else(|| {
        thickness.at.error(format!(
            "blade thermoelastic loss needs the material's density, specific_heat, conductivity, thermal_expansion and youngs_modulus (material '{}')",
            m.name
        ))
    })?;
    let temperature = temperature.unwrap_or_else(|| "temperature".to_string());
    Ok(Some(blade_loss(
        &material,
        &thickness.paren(),
        &temperature,
    )))
}

/// Which bodies hang from which: each body's children in the order of the stages (one pass
/// over the stages, so that walking a long chain costs O(n) and not O(n²)).
pub struct Hanging<'s> {
    children: HashMap<&'s str, Vec<&'s str>>,
}

impl<'s> Hanging<'s> {
    /// The hierarchy of `spec`'s stages.
    pub fn new(spec: &'s Spec) -> Self {
        let mut children: HashMap<&str, Vec<&str>> = HashMap::new();
        for stage in &spec.stages {
            children
                .entry(stage.from.value.as_str())
                .or_default()
                .push(&stage.body);
        }
        Hanging { children }
    }

    /// The bodies hung from `body`, itself first, depth first in the order of the stages.
    pub fn subtree(&self, body: &'s str) -> Vec<&'s str> {
        let mut out = Vec::new();
        let mut seen = HashSet::new();
        let mut visit = vec![body];
        while let Some(b) = visit.pop() {
            if !seen.insert(b) {
                continue; // a cycle, reported by the build
            }
            out.push(b);
            // children pushed in reverse so that the first stage is visited first
            if let Some(below) = self.children.get(b) {
                visit.extend(below.iter().rev());
            }
        }
        out
    }
}

/// The static tension of one wire of `set` at the nominal geometry, as an expression of the
/// parameters: (Σ masses hung) g / (wires in the stage) · l / vertical extent.
fn nominal_tension(spec: &Spec, hanging: &Hanging, stage: &StageFile, set: &WireSet) -> String {
    let bodies: HashMap<&str, _> = spec.bodies.iter().map(|b| (b.name.as_str(), b)).collect();
    let masses: Vec<String> = hanging
        .subtree(&stage.body)
        .into_iter()
        .filter_map(|b| bodies.get(b))
        .filter_map(|b| b.mass.as_ref().map(Ex::paren))
        .collect();
    let wires = stage
        .wire_sets()
        .fold(0usize, |n, s| n.saturating_add(point_count(&s.lower)));
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
