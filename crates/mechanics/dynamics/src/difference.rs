//! Derivatives of a stage's matrices with respect to a model parameter by the fourth-order
//! central difference over stepped stage models (the sensitivities' difference route,
//! docs/exact-sensitivities.md): the stencil, the difference of anything given at its
//! points, and dE(f)/dp of the dynamic matrix E(f) = L + Σ_tag ε_tag(f) P_tag − ω² M from
//! the stage models at the points, kept as the changes of its frequency-independent parts
//! on one pattern and multiplied into vectors there ([`StageModel::sum_parts`],
//! [`StageModel::multiply`]), never formed densely.
//!
//! Each part is differenced once per parameter, not at every frequency: where a tag's
//! multiplier is the same at every point, d(ε P)/dp = ε dP/dp; where it moves (a loss angle)
//! the difference is taken of ε P point by point, so that a loss angle's derivative does
//! not carry the rounding of the other tags' parts. The stepped models' patterns differ
//! where the parameter moves an entry to or from an exact zero; the parts are then
//! differenced on the pattern that holds the others' ([`CommonPattern`]), or, where none
//! does, point by point.

use std::borrow::Cow;

use faer::c64;
use nalgebra::DVector;
use pendkit_system::Damping;

use crate::pattern::CommonPattern;
use crate::stage::TWO_PI;
use crate::{DynamicsError, StageModel};

/// Offsets (in steps h) of the points of the fourth-order central difference, in the order
/// [`difference`] and [`difference_of`] take them, with their weights (× 1/h):
/// X'(p₀) ≈ [8(X(p₀+h) − X(p₀−h)) − (X(p₀+2h) − X(p₀−2h))] / 12h, whose truncation error
/// is h⁴ X⁽⁵⁾/30.
pub const STENCIL: [(f64, f64); 4] = [
    (-2.0, 1.0 / 12.0),
    (-1.0, -8.0 / 12.0),
    (1.0, 8.0 / 12.0),
    (2.0, -1.0 / 12.0),
];

/// The fourth-order central difference [8(X₊₁ − X₋₁) − (X₊₂ − X₋₂)] / 12h of `x` read at
/// each of the stencil's `points` (one per [`STENCIL`] entry, in its order), step `h`.
/// Written as differences of pairs, so that a quantity the same at every point gives
/// exactly 0.
pub fn difference<P, T>(points: &[P; 4], h: f64, x: impl Fn(&P) -> T) -> T
where
    T: std::ops::Mul<f64, Output = T> + std::ops::Add<T, Output = T>,
{
    let inner = x(&points[2]) + x(&points[1]) * -1.0;
    let outer = x(&points[3]) + x(&points[0]) * -1.0;
    inner * (8.0 / (12.0 * h)) + outer * (-1.0 / (12.0 * h))
}

/// [`difference`] of vectors or matrices given one per stencil point (the same difference
/// written as ((v₊₁ − v₋₁)·8 − (v₊₂ − v₋₂)) / 12h: its own rounding, exactly 0 where the
/// points agree).
pub fn difference_of<M>(v: [&M; 4], h: f64) -> M
where
    for<'a> &'a M: std::ops::Sub<&'a M, Output = M>,
    M: std::ops::Mul<f64, Output = M>
        + std::ops::Sub<M, Output = M>
        + std::ops::Div<f64, Output = M>,
{
    ((v[2] - v[1]) * 8.0 - (v[3] - v[0])) / (12.0 * h)
}

/// Adds the term m V to a list of parts for [`StageModel::sum_parts`], merged with the last
/// one where that has the same values (a tag's real and imaginary multipliers: one pass).
fn push_part<'a>(parts: &mut Vec<(c64, &'a [f64])>, m: c64, values: &'a [f64]) {
    match parts.last_mut() {
        Some((last, v)) if std::ptr::eq(*v, values) => *last += m,
        _ => parts.push((m, values)),
    }
}

/// One frequency-independent part of E(f) (the lossless part, a damping tag's P_tag, or the
/// mass) at the stencil's points: its values on each point's pattern (the common pattern's
/// where there is one) and how it moves with the parameter.
pub struct PartChange<'a> {
    /// Per point: the model whose pattern the values are on, and the values there.
    at: Vec<(&'a StageModel, Cow<'a, [f64]>)>,
    change: Change,
}

/// How a [`PartChange`] moves with the parameter.
enum Change {
    /// The same at every point: an exact 0.
    Zero,
    /// The difference of its values on the points' common pattern.
    OnPattern(Vec<f64>),
    /// No point's pattern holds every other's: the difference is taken of the products,
    /// point by point.
    ByPoint,
}

impl<'a> PartChange<'a> {
    /// The part whose values on each model's pattern `values` gives, differenced on the
    /// models' common pattern where they have one (the usual case: then a part the
    /// parameter does not move costs one comparison).
    fn new(
        models: &[&'a StageModel; 4],
        h: f64,
        common: Option<&CommonPattern>,
        values: impl Fn(&'a StageModel) -> &'a [f64],
    ) -> Self {
        let on_base = common.and_then(|common| {
            let base = models[common.base()];
            models
                .iter()
                .enumerate()
                .map(|(k, &m)| Some((base, common.on_base(k, values(m))?)))
                .collect::<Option<Vec<_>>>()
        });
        let Some(at) = on_base else {
            let at = models
                .iter()
                .map(|&m| (m, Cow::Borrowed(values(m))))
                .collect();
            return PartChange {
                at,
                change: Change::ByPoint,
            };
        };
        let change = if at.iter().all(|(_, v)| *v == at[0].1) {
            Change::Zero
        } else {
            let on_pattern: Vec<DVector<f64>> = at
                .iter()
                .map(|(_, v)| DVector::from_column_slice(v))
                .collect();
            let d = difference_of(
                [
                    &on_pattern[0],
                    &on_pattern[1],
                    &on_pattern[2],
                    &on_pattern[3],
                ],
                h,
            );
            Change::OnPattern(d.as_slice().to_vec())
        };
        PartChange { at, change }
    }

    /// Lists this part's d(ε P)/dp for one real (`unit` 1) or imaginary (`unit` i) part of
    /// its multiplier, given that part of ε at each point: ε dP where ε is the same at every
    /// point (nothing where the part does not move either: an exact 0), else Σ_k (weight_k /
    /// h) ε_k P_k over the stencil's points. Terms on the common pattern go to `shared` (one
    /// product for all of them), the others to `own` with their point's model.
    fn collect<'s>(
        &'s self,
        (eps, unit): (&[f64; 4], c64),
        h: f64,
        shared: &mut Vec<(c64, &'s [f64])>,
        own: &mut Vec<(&'s StageModel, c64, &'s [f64])>,
    ) {
        if eps.iter().all(|&e| e == eps[0]) {
            let e = eps[0];
            match &self.change {
                Change::Zero => return,
                _ if e == 0.0 => return,
                Change::OnPattern(d) => {
                    push_part(shared, unit * e, d);
                    return;
                }
                Change::ByPoint => {}
            }
        }
        let same_pattern = !matches!(self.change, Change::ByPoint);
        for ((model, values), (&e, &(_, weight))) in self.at.iter().zip(eps.iter().zip(&STENCIL)) {
            let m = unit * (weight / h * e);
            if same_pattern {
                push_part(shared, m, values);
            } else {
                own.push((model, m, values));
            }
        }
    }

    /// φ(dP/dp) for a linear form φ of values on a model's pattern (z̄ᵀ V z for the noise,
    /// `pendkit_noise::dissipation_form`), step `h`: exactly 0 where the part does not
    /// move, φ of its difference on the common pattern, or, where the points' patterns
    /// differ, Σ_k (weight_k / h) φ(P_k) over the stencil's points.
    pub fn linear<E>(
        &self,
        h: f64,
        form: impl Fn(&StageModel, &[f64]) -> Result<f64, E>,
    ) -> Result<f64, E> {
        Ok(match &self.change {
            Change::Zero => 0.0,
            Change::OnPattern(d) => form(self.at[0].0, d)?,
            Change::ByPoint => {
                let mut sum = 0.0;
                for ((model, values), &(_, weight)) in self.at.iter().zip(&STENCIL) {
                    sum += weight / h * form(model, values)?;
                }
                sum
            }
        })
    }
}

/// dE(f)/dp of one parameter from the stage models at the stencil's points, E(f) = L +
/// Σ_tag ε_tag(f) P_tag − ω² M (L the lossless part, P_tag each damping tag's tension-off
/// part, M the mass), as the parts' changes on one pattern: the parts are differenced once
/// per parameter, and dE(f) w is put together per frequency ([`StageDerivative::at`]).
pub struct StageDerivative<'a> {
    /// The lossless part.
    lossless: PartChange<'a>,
    /// The mass on the pattern.
    mass: PartChange<'a>,
    /// Per damping tag (the stage's order): its name and its part.
    tags: Vec<(&'a str, PartChange<'a>)>,
    /// Each point's damping (its tags' multipliers).
    damping: [&'a Damping; 4],
    /// The step of the difference.
    h: f64,
    /// The model whose pattern the parts' changes are on.
    base: &'a StageModel,
}

impl<'a> StageDerivative<'a> {
    /// The derivative from the stage model and damping at each of the stencil's points
    /// (one per [`STENCIL`] entry, in its order), step `h` (the parameter's unit). `None`
    /// when the points' models do not have the same damping tags (a parameter that
    /// changes which tags dissipate has no derivative).
    pub fn new(points: [(&'a StageModel, &'a Damping); 4], h: f64) -> Option<Self> {
        fn tags(m: &StageModel) -> Vec<&str> {
            m.by_tag.iter().map(|(t, _)| t.as_str()).collect()
        }
        let models = points.map(|(m, _)| m);
        let names = tags(models[0]);
        if models.iter().any(|&m| tags(m) != names) {
            return None;
        }
        let patterns = models.map(|m| &m.pattern);
        let common = CommonPattern::of(&patterns);
        let common = common.as_ref();
        let parts = names
            .iter()
            .enumerate()
            .map(|(t, &name)| {
                let part = PartChange::new(&models, h, common, move |m| &m.by_tag[t].1);
                (name, part)
            })
            .collect();
        Some(StageDerivative {
            lossless: PartChange::new(&models, h, common, |m| &m.lossless),
            mass: PartChange::new(&models, h, common, |m| &m.mass_on_pattern),
            tags: parts,
            damping: points.map(|(_, d)| d),
            h,
            base: models[common.map_or(0, CommonPattern::base)],
        })
    }

    /// dE(f_hz)/dp: the parts on the common pattern summed there once (they then multiply
    /// any number of vectors alike), any part whose points' patterns differ kept point by
    /// point. `values` is a buffer to reuse (the last frequency's, from
    /// [`ChangeAt::into_buffer`]).
    pub fn at(&self, f_hz: f64, mut values: Vec<c64>) -> Result<ChangeAt<'_>, DynamicsError> {
        let (one, i) = (c64::new(1.0, 0.0), c64::new(0.0, 1.0));
        let mut shared = Vec::with_capacity(2 * self.tags.len() + 2);
        let mut own = Vec::new();
        // the lossless part's multiplier is 1 at every point
        self.lossless
            .collect((&[1.0; 4], one), self.h, &mut shared, &mut own);
        for (tag, part) in &self.tags {
            // one multiplier per stencil point
            let (mut real, mut imag) = ([0.0; STENCIL.len()], [0.0; STENCIL.len()]);
            for ((r, m), damping) in real.iter_mut().zip(&mut imag).zip(&self.damping) {
                (*r, *m) = damping.at(tag, f_hz);
            }
            part.collect((&real, one), self.h, &mut shared, &mut own);
            part.collect((&imag, i), self.h, &mut shared, &mut own);
        }
        let w2 = (TWO_PI * f_hz).powi(2);
        self.mass
            .collect((&[-w2; 4], one), self.h, &mut shared, &mut own);
        let model = self.base;
        values.resize(model.pattern.len(), c64::new(0.0, 0.0));
        model.sum_parts(&shared, &mut values)?;
        Ok(ChangeAt { model, values, own })
    }

    /// The part of the tag named `tag` (its P_tag's change, for a per-tag form); `None`
    /// when the points have no such tag.
    pub fn tag(&self, tag: &str) -> Option<&PartChange<'a>> {
        self.tags
            .iter()
            .find(|(name, _)| *name == tag)
            .map(|(_, part)| part)
    }
}

/// dE(f)/dp at one frequency ([`StageDerivative::at`]): values on the common pattern, and
/// the terms (model, multiplier, values) of any part whose points' patterns differ.
pub struct ChangeAt<'s> {
    model: &'s StageModel,
    values: Vec<c64>,
    own: Vec<(&'s StageModel, c64, &'s [f64])>,
}

impl ChangeAt<'_> {
    /// Adds dE w to `out`, both over every master row. An error when `w` or `out` has
    /// another length.
    pub fn multiply(&self, w: &[c64], out: &mut [c64]) -> Result<(), DynamicsError> {
        self.model.multiply(&self.values, w, out)?;
        for &(model, m, values) in &self.own {
            let mut term = vec![c64::new(0.0, 0.0); values.len()];
            model.sum_parts(&[(m, values)], &mut term)?;
            model.multiply(&term, w, out)?;
        }
        Ok(())
    }

    /// The buffer of the values, for the next frequency's [`StageDerivative::at`].
    pub fn into_buffer(self) -> Vec<c64> {
        self.values
    }
}

#[cfg(test)]
mod tests {
    //! The stencil against polynomials it differentiates exactly, and dE(f)/dp of one lossy
    //! oscillator (a mass m on a spring k along x to the support s, structural loss φ on tag
    //! "spring") against the closed form: over the master rows (x, s),
    //!
    //!   E(f) = k (1 + iφ) [[1, −1], [−1, 1]] − ω² [[m, 0], [0, 0]],  ω = 2π f,
    //!
    //! so dE/dk = (1 + iφ) [[1, −1], [−1, 1]], dE/dφ = i k [[1, −1], [−1, 1]] and dE/dm =
    //! −ω² [[1, 0], [0, 0]]. The stage models at the stencil's points go through the same
    //! builder, equilibrium and stage matrices as any other (`pendkit_assembly::assemble`,
    //! `StageModel::new`).

    use super::*;
    use nalgebra::{Matrix6, Vector3, Vector6};
    use pendkit_assembly::{EquilibriumOptions, assemble};
    use pendkit_model::{BodySpec, DampingSpec, SystemBuilder};
    use pendkit_params::ParamSet;
    use pendkit_system::{SpringEnd, Stage};

    #[test]
    fn the_stencil_differentiates_a_quartic_exactly() {
        // f(x) = x⁴ at x₀ = 1, h = 1/2: the fourth-order difference is exact up to degree
        // 4 (its error is h⁴ f⁽⁵⁾/30), and every value of f here is a short binary
        // fraction, so f'(1) = 4 carries only the rounding of the weights 8/12h and 1/12h
        // (8/6 is not a binary fraction): an ulp or two, checked to 1e-15 relative
        let (x0, h) = (1.0, 0.5);
        let points = STENCIL.map(|(k, _)| x0 + k * h);
        assert!((difference(&points, h, |&x: &f64| x.powi(4)) - 4.0).abs() <= 4e-15);
        // as vectors: (x⁴, x³, x² + 7) gives (4, 3, 2), with no rounding at all (the
        // division by 12h = 6 comes last, of the exact integers 24, 18 and 12)
        let vectors = points.map(|x| DVector::from_vec(vec![x.powi(4), x.powi(3), x * x + 7.0]));
        let d = difference_of(vectors.each_ref(), h);
        assert_eq!(d.as_slice(), &[4.0, 3.0, 2.0]);
        // what does not move gives exactly 0, even on a large scale
        assert_eq!(difference(&points, h, |_| 1e300), 0.0);
    }

    /// A mass `m` (kg) on a spring `k` (N/m) along x to the support s, loss angle `phi` on
    /// tag `tag`: its stage model and damping.
    fn oscillator(m: f64, k: f64, phi: f64, tag: &str) -> (StageModel, Damping) {
        let mut b = SystemBuilder::new(9.81);
        b.parameter("s", 0.0).unwrap();
        b.variable("x", 0.0).unwrap();
        let ground = b
            .body(BodySpec::new("ground").pose(["s", "0", "0", "0", "0", "0"]))
            .unwrap();
        let mass = b
            .body(
                BodySpec::new("mass")
                    .pose(["x", "0", "0", "0", "0", "0"])
                    .mass(m),
            )
            .unwrap();
        let end = |body| SpringEnd {
            body,
            point: Vector3::zeros(),
            angles: [0.0; 3],
        };
        let stiffness = Matrix6::from_diagonal(&Vector6::new(k, 0.0, 0.0, 0.0, 0.0, 0.0));
        b.spring(
            "k",
            [end(ground), end(mass)],
            stiffness,
            Vector6::zeros(),
            tag,
        )
        .unwrap();
        let system = b.build().unwrap();
        let assembled = assemble(&system, Stage::S0B, &EquilibriumOptions::default()).unwrap();
        let model = StageModel::new(&system, &assembled);
        let mut damping = Damping::default();
        let spec = DampingSpec::structural(&format!("{phi:e}"));
        damping.set(
            tag,
            spec.resolve(tag, &ParamSet::new().resolve().unwrap())
                .unwrap(),
        );
        (model, damping)
    }

    /// The stage models at the stencil's points p₀ + k h of a parameter that `at` turns
    /// into (m, k, φ).
    fn stencil(p0: f64, h: f64, at: impl Fn(f64) -> (f64, f64, f64)) -> [(StageModel, Damping); 4] {
        STENCIL.map(|(k, _)| {
            let (m, stiffness, phi) = at(p0 + k * h);
            oscillator(m, stiffness, phi, "spring")
        })
    }

    /// dE(f)/dp w over the master rows (x, s) for w = (1, 0).
    fn change_along_x(points: &[(StageModel, Damping); 4], h: f64, f_hz: f64) -> Vec<c64> {
        let derivative = StageDerivative::new(points.each_ref().map(|(m, d)| (m, d)), h)
            .expect("the same tags at every point");
        let change = derivative.at(f_hz, Vec::new()).unwrap();
        let w = [c64::new(1.0, 0.0), c64::new(0.0, 0.0)];
        let mut out = vec![c64::new(0.0, 0.0); 2];
        change.multiply(&w, &mut out).unwrap();
        out
    }

    fn close(got: c64, expected: c64, tolerance: f64) -> bool {
        (got - expected).norm() <= tolerance * expected.norm()
    }

    #[test]
    fn the_stiffness_moves_the_tag_part_by_its_multiplier() {
        // k = 4 ± 1/4, ± 1/2 N/m: P_tag is linear in k, so the difference is exact and
        // dE/dk w = (1 + iφ)(1, −1) to the rounding of the assembly and of the
        // products (a few ulps; 1e-14 relative leaves room for no more)
        let phi = 1e-3;
        let points = stencil(4.0, 0.25, |k| (1.0, k, phi));
        let expected = c64::new(1.0, phi);
        for f in [0.1, 1.0, 10.0] {
            let out = change_along_x(&points, 0.25, f);
            assert!(close(out[0], expected, 1e-14), "{f} Hz: {}", out[0]);
            assert!(close(out[1], -expected, 1e-14), "{f} Hz: {}", out[1]);
        }
    }

    #[test]
    fn a_loss_angle_moves_only_its_multiplier() {
        // φ = 1e-3 ± 1e-6, ± 2e-6 at k = 4 N/m: dE/dφ w = i k (1, −1); the real part is
        // exactly 0 (ε' = 1 at every point and P_tag the same: nothing to difference), the
        // imaginary one the difference of the φ_k, linear, so exact up to the rounding of
        // the weights (1/12, 8/12) and of φ₀ + k h, amplified by φ₀/h = 1e3: ~1e-13
        // relative, checked to 1e-10
        let k = 4.0;
        let points = stencil(1e-3, 1e-6, |phi| (1.0, k, phi));
        for f in [0.1, 1.0, 10.0] {
            let out = change_along_x(&points, 1e-6, f);
            assert_eq!(out[0].re, 0.0);
            assert_eq!(out[1].re, 0.0);
            assert!(close(out[0], c64::new(0.0, k), 1e-10), "{f} Hz: {}", out[0]);
            assert!(
                close(out[1], c64::new(0.0, -k), 1e-10),
                "{f} Hz: {}",
                out[1]
            );
        }
    }

    #[test]
    fn the_mass_moves_the_inertia_term_only() {
        // m = 2 ± 1/4, ± 1/2 kg: dE/dm w = (−ω², 0) (the support row has no mass), the
        // difference exact (M linear in m), −ω² the one rounded number: 1e-14 relative
        let points = stencil(2.0, 0.25, |m| (m, 4.0, 1e-3));
        for f in [0.1, 1.0, 10.0] {
            let w2 = (2.0 * std::f64::consts::PI * f).powi(2);
            let out = change_along_x(&points, 0.25, f);
            assert!(
                close(out[0], c64::new(-w2, 0.0), 1e-14),
                "{f} Hz: {}",
                out[0]
            );
            assert_eq!(out[1], c64::new(0.0, 0.0));
        }
    }

    #[test]
    fn a_tag_part_gives_its_change_to_a_linear_form() {
        // the form reads the (x, x) entry of the values: dP_tag/dk there is 1 (P_tag = k
        // [[1, −1], [−1, 1]], exact as above); along φ the tag's part does not move: 0
        let form = |model: &StageModel, values: &[f64]| -> Result<f64, DynamicsError> {
            Ok(values[model.pattern.slot(0, 0).expect("(x, x) is stored")])
        };
        let along_k = stencil(4.0, 0.25, |k| (1.0, k, 1e-3));
        let d = StageDerivative::new(along_k.each_ref().map(|(m, d)| (m, d)), 0.25).unwrap();
        let part = d.tag("spring").expect("the oscillator's tag");
        assert!((part.linear(0.25, form).unwrap() - 1.0).abs() <= 1e-14);
        assert!(d.tag("other").is_none());
        let along_phi = stencil(1e-3, 1e-6, |phi| (1.0, 4.0, phi));
        let d = StageDerivative::new(along_phi.each_ref().map(|(m, d)| (m, d)), 1e-6).unwrap();
        assert_eq!(d.tag("spring").unwrap().linear(1e-6, form).unwrap(), 0.0);
    }

    #[test]
    fn points_whose_tags_differ_have_no_derivative() {
        let points: [(StageModel, Damping); 4] = [0, 1, 2, 3].map(|k| {
            let tag = if k < 2 { "spring" } else { "other" };
            oscillator(1.0, 4.0, 1e-3, tag)
        });
        assert!(StageDerivative::new(points.each_ref().map(|(m, d)| (m, d)), 0.25).is_none());
    }
}
