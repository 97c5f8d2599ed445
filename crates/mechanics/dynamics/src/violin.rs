//! Violin modes: the roots of the frequency-dependent problem E(f) = P(f) − ω²M +
//! Σ frequency terms near each violin harmonic of the terms (docs/continuum-fibres.md,
//! "Violin modes").
//!
//! The damping multipliers are functions of real frequency only, so the roots are found in
//! real f with the loss set aside (multipliers ε′ + 0i), and the loss enters afterwards to
//! first order: Im f = zᵀ Im E z / (−zᵀ ∂E/∂f z) at the root, z its null vector.
//!
//! The lossless E(f) is real and symmetric, and its parts are infinite at the terms' held
//! resonances (a fibre vibrating with its ends still). Roots are counted by the
//! Wittrick–Williams rule: the number of modes below f is the number of held resonances
//! below f plus the number of negative eigenvalues of E(f) (of its Schur complement onto
//! the variables: the floats' count is subtracted). Each harmonic's band is split at the
//! held resonances it contains: the count's jump across a resonance is the number of modes
//! sitting at it (fibres moving with every body still: the quad's four fibres in two planes
//! give eight resonances at each harmonic, of which the test mass and penultimate mass see
//! only a few combinations), and between resonances each root is bracketed by the count and
//! refined by the Illinois method on the eigenvalue that crosses zero.

use faer::c64;
use nalgebra::DMatrix;
use pendkit_system::Damping;

use crate::DynamicsError;
use crate::stage::{HeldResonance, StageModel, TWO_PI};

/// The largest number of violin harmonics asked for at once: each costs a few hundred
/// evaluations of the model, and beyond a few tens the fibres' axial and torsional
/// resonances are as dense as the transverse ones, so that "harmonic n" means little.
pub const MAX_VIOLIN_HARMONICS: usize = 50;

/// Half-width (relative) of the interval around a held resonance whose count jump is
/// taken as modes sitting at it: a root nearer than this is reported at the resonance,
/// with this as its accuracy.
const AT_RESONANCE: f64 = 1e-12;

/// One root of the frequency-dependent problem near a violin harmonic.
#[derive(Clone, Debug, PartialEq)]
pub struct ViolinRoot {
    /// Labels of the frequency terms of the set whose harmonic this is (alike terms: the
    /// same harmonics).
    pub terms: Vec<String>,
    /// The harmonic (1 for the fundamental).
    pub harmonic: usize,
    /// Frequency (Hz): the root of the lossless problem.
    pub frequency_hz: f64,
    /// Quality factor f/(2 Im f), Im f to first order in the loss; infinite without loss.
    pub q: f64,
    /// Bound on the frequency's error (Hz): the final bracket, the rounding of E at the
    /// root through the slope of its crossing eigenvalue, and the second-order effect of
    /// the loss the real-frequency search leaves out.
    pub accuracy_hz: f64,
    /// The motion of the held resonance the root sits at, when every body is still there
    /// (the fibres' end forces cancel on the bodies): "transverse", "axial", "torsion".
    pub held: Option<&'static str>,
}

/// The lossless problem and its loss, over the variables and floats.
struct Problem<'a> {
    model: &'a StageModel,
    damping: &'a Damping,
    /// Variables and floats.
    size: usize,
    nx: usize,
    mass: DMatrix<f64>,
    /// The first frequency (Hz) at which E was not finite (a damping multiplier that is
    /// NaN there, a frequency exactly at a held resonance): the search then reports it
    /// instead of its roots, and the eigensolver never sees a NaN.
    not_finite: std::cell::Cell<Option<f64>>,
}

/// The count at one frequency: negative eigenvalues of E over the variables and floats,
/// and of its float block (their difference is the variables' Schur complement's).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Count {
    all: usize,
    floats: usize,
}

impl Count {
    fn value(self) -> i64 {
        self.all as i64 - self.floats as i64
    }
}

impl Problem<'_> {
    /// E(f) with real multipliers ε′, over the variables and floats.
    fn real(&self, f: f64) -> DMatrix<f64> {
        let damping = self.damping;
        let (re, _) = self
            .model
            .master_with(f, &|tag, f| (damping.at(tag, f).0, 0.0));
        let mut e = re.view((0, 0), (self.size, self.size)).into_owned();
        let w2 = (TWO_PI * f).powi(2);
        let mut block = e.view_mut((0, 0), (self.nx, self.nx));
        block -= &self.mass * w2;
        if e.iter().all(|v| v.is_finite()) {
            e
        } else {
            if self.not_finite.get().is_none() {
                self.not_finite.set(Some(f));
            }
            DMatrix::zeros(self.size, self.size)
        }
    }

    /// Im E(f) with the model's multipliers, over the variables and floats.
    fn imag(&self, f: f64) -> DMatrix<f64> {
        let (_, im) = self.model.master(self.damping, f);
        let im = im.view((0, 0), (self.size, self.size)).into_owned();
        if im.iter().all(|v| v.is_finite()) {
            im
        } else {
            if self.not_finite.get().is_none() {
                self.not_finite.set(Some(f));
            }
            DMatrix::zeros(self.size, self.size)
        }
    }

    fn count(&self, f: f64) -> Count {
        let e = self.real(f);
        let negative = |m: DMatrix<f64>| {
            m.symmetric_eigenvalues()
                .iter()
                .filter(|&&v| v < 0.0)
                .count()
        };
        let nq = self.size - self.nx;
        let floats = if nq == 0 {
            0
        } else {
            negative(e.view((self.nx, self.nx), (nq, nq)).into_owned())
        };
        Count {
            all: negative(e),
            floats,
        }
    }

    /// The `k`-th smallest eigenvalue of E(f) over the variables and floats.
    fn eigenvalue(&self, f: f64, k: usize) -> f64 {
        let mut v: Vec<f64> = self
            .real(f)
            .symmetric_eigenvalues()
            .iter()
            .copied()
            .collect();
        v.sort_by(f64::total_cmp);
        v.get(k).copied().unwrap_or(f64::NAN)
    }
}

/// A root found between held resonances, before its loss.
struct Bracketed {
    frequency: f64,
    /// Width of the final bracket (Hz).
    width: f64,
    /// Index of the eigenvalue that crosses zero there.
    index: Option<usize>,
}

impl StageModel {
    /// The roots of E(f) near the first `harmonics` violin harmonics of every set of alike
    /// frequency terms (docs/continuum-fibres.md, "Violin modes"), grouped by set and
    /// harmonic, each with its quality factor and accuracy. The frequency axis is cut
    /// midway between consecutive harmonics (all sets together), from half the lowest
    /// first harmonic up to midway between each set's last harmonic and the next; every
    /// mode of the model in a harmonic's band is listed with it. Errors: `harmonics` out of
    /// 1..=[`MAX_VIOLIN_HARMONICS`], no term with harmonics, a damping multiplier that is
    /// not finite.
    pub fn violin_modes(
        &self,
        damping: &Damping,
        harmonics: usize,
    ) -> Result<Vec<ViolinRoot>, DynamicsError> {
        if harmonics == 0 || harmonics > MAX_VIOLIN_HARMONICS {
            return Err(DynamicsError::Violin(format!(
                "the number of harmonics must be 1 to {MAX_VIOLIN_HARMONICS} (got {harmonics})"
            )));
        }
        // sets of alike terms: the same harmonics to the last bit
        let mut sets: Vec<(Vec<usize>, Vec<f64>)> = Vec::new();
        for (t, term) in self.frequency_terms.iter().enumerate() {
            let h = term.harmonics(harmonics + 1);
            if h.len() < harmonics + 1 {
                continue;
            }
            match sets.iter_mut().find(|(_, g)| *g == h) {
                Some((members, _)) => members.push(t),
                None => sets.push((vec![t], h)),
            }
        }
        if sets.is_empty() {
            return Err(DynamicsError::Violin(
                "the model has no continuum fibres (no frequency term with violin harmonics)"
                    .into(),
            ));
        }
        let bands = bands(&sets, harmonics);
        let (nx, nq, _) = self.sizes;
        let problem = Problem {
            model: self,
            damping,
            size: nx + nq,
            nx,
            mass: self.mass.to_dense(),
            not_finite: std::cell::Cell::new(None),
        };
        let mut roots = Vec::new();
        for (set, harmonic, lo, hi) in bands {
            crate::validate::check_damping(
                damping,
                self.by_tag.iter().map(|(t, _)| t.as_str()),
                &[lo, hi],
            )?;
            let terms: Vec<String> = sets[set]
                .0
                .iter()
                .map(|&t| self.frequency_terms[t].label().to_string())
                .collect();
            let found = problem.band(lo, hi);
            if let Some(f) = problem.not_finite.get() {
                return Err(DynamicsError::Violin(format!(
                    "the dynamic stiffness is not finite at {} Hz (a damping multiplier \
                     there, or a frequency at a fibre's held resonance)",
                    pendkit_expr::number_text(f)
                )));
            }
            for (frequency_hz, q, accuracy_hz, held) in found {
                roots.push(ViolinRoot {
                    terms: terms.clone(),
                    harmonic,
                    frequency_hz,
                    q,
                    accuracy_hz,
                    held,
                });
            }
        }
        Ok(roots)
    }
}

/// Each (set, harmonic, lower, upper) band: the axis cut midway between consecutive
/// harmonics of all sets, from half the lowest first harmonic, the last of each set up to
/// midway to its next harmonic.
fn bands(sets: &[(Vec<usize>, Vec<f64>)], harmonics: usize) -> Vec<(usize, usize, f64, f64)> {
    let mut points: Vec<(f64, usize, usize)> = sets
        .iter()
        .enumerate()
        .flat_map(|(s, (_, h))| (0..harmonics).map(move |k| (h[k], s, k + 1)))
        .collect();
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut out = Vec::with_capacity(points.len());
    for (i, &(f, s, k)) in points.iter().enumerate() {
        let lo = if i == 0 {
            0.5 * f
        } else {
            0.5 * (points[i - 1].0 + f)
        };
        let own_next = 0.5 * (f + sets[s].1[k]);
        let hi = points
            .get(i + 1)
            .map_or(own_next, |p| own_next.min(0.5 * (f + p.0)));
        out.push((s, k, lo, hi));
    }
    out
}

impl Problem<'_> {
    /// The held resonances of every term in [`lo`, `hi`], sorted.
    fn held(&self, lo: f64, hi: f64) -> Vec<HeldResonance> {
        let mut all: Vec<HeldResonance> = self
            .model
            .frequency_terms
            .iter()
            .flat_map(|t| {
                let tags = t.tags().to_vec();
                let damping = self.damping;
                let multipliers = move |f: f64| -> Vec<c64> {
                    tags.iter()
                        .map(|tag| {
                            let (re, im) = damping.at(tag, f);
                            c64::new(re, im)
                        })
                        .collect()
                };
                t.held_resonances(lo, hi, &multipliers)
            })
            .collect();
        all.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
        all
    }

    /// The roots in (`lo`, `hi`): (frequency, Q, accuracy, held motion), ascending.
    fn band(&self, lo: f64, hi: f64) -> Vec<(f64, f64, f64, Option<&'static str>)> {
        let held = self.held(lo, hi);
        let mut out = Vec::new();
        // groups of resonances within AT_RESONANCE of each other
        let mut groups: Vec<Vec<&HeldResonance>> = Vec::new();
        for r in &held {
            match groups.last_mut() {
                Some(g)
                    if r.frequency_hz - g[0].frequency_hz
                        <= 2.0 * AT_RESONANCE * r.frequency_hz =>
                {
                    g.push(r);
                }
                _ => groups.push(vec![r]),
            }
        }
        let mut start = (lo, self.count(lo));
        for g in &groups {
            let first = g[0].frequency_hz;
            let last = g[g.len() - 1].frequency_hz;
            let below = first * (1.0 - AT_RESONANCE);
            let above = last * (1.0 + AT_RESONANCE);
            let (c_below, c_above) = (self.count(below), self.count(above));
            self.isolate(start, (below, c_below), &held, &mut out);
            let jump = g.len() as i64 + c_above.value() - c_below.value();
            let jump = usize::try_from(jump).unwrap_or(0);
            for r in g.iter().take(jump) {
                let q = quality(r.frequency_hz, r.imag_hz);
                out.push((r.frequency_hz, q, above - below, Some(r.motion)));
            }
            // more roots than resonances in the interval: bodies moving, within
            // AT_RESONANCE of it (not seen in practice; reported without their loss)
            for _ in g.len()..jump {
                out.push((0.5 * (first + last), f64::NAN, above - below, None));
            }
            start = (above, c_above);
        }
        self.isolate(start, (hi, self.count(hi)), &held, &mut out);
        out.sort_by(|a, b| a.0.total_cmp(&b.0));
        out
    }

    /// The roots between two frequencies with no held resonance between them, by bisection
    /// on the count down to single roots, each refined by [`Problem::illinois`], with its
    /// loss.
    fn isolate(
        &self,
        (a, ca): (f64, Count),
        (b, cb): (f64, Count),
        held: &[HeldResonance],
        out: &mut Vec<(f64, f64, f64, Option<&'static str>)>,
    ) {
        let mut found = Vec::new();
        self.bracket((a, ca), (b, cb), &mut found);
        for r in found {
            let (q, extra) = match r.index {
                Some(k) => self.loss(r.frequency, k, held),
                None => (f64::NAN, 0.0),
            };
            out.push((r.frequency, q, r.width + extra, None));
        }
    }

    /// Bisection on the count, then the Illinois method on a single crossing eigenvalue.
    fn bracket(&self, (a, ca): (f64, Count), (b, cb): (f64, Count), out: &mut Vec<Bracketed>) {
        let roots = cb.value() - ca.value();
        if roots <= 0 {
            return;
        }
        if roots == 1 && ca.floats == cb.floats && cb.all == ca.all + 1 {
            out.push(self.illinois(a, b, ca.all));
            return;
        }
        if b - a <= 4.0 * f64::EPSILON * b {
            // coincident roots: each with one of the crossing eigenvalues (in a degenerate
            // pair any basis is a pair of modes)
            for j in 0..roots.unsigned_abs() as usize {
                out.push(Bracketed {
                    frequency: 0.5 * (a + b),
                    width: b - a,
                    index: Some(ca.all + j),
                });
            }
            return;
        }
        let m = 0.5 * (a + b);
        let cm = self.count(m);
        self.bracket((a, ca), (m, cm), out);
        self.bracket((m, cm), (b, cb), out);
    }

    /// The root of the `k`-th eigenvalue in (`a`, `b`), where it goes from non-negative to
    /// negative: regula falsi with the Illinois modification, to a bracket of a few ulps.
    fn illinois(&self, mut a: f64, mut b: f64, k: usize) -> Bracketed {
        let (mut fa, mut fb) = (self.eigenvalue(a, k), self.eigenvalue(b, k));
        let mut side = 0i8;
        for _ in 0..200 {
            if b - a <= 4.0 * f64::EPSILON * b {
                break;
            }
            let mut c = b - fb * (b - a) / (fb - fa);
            if !(c > a && c < b) {
                c = 0.5 * (a + b);
            }
            let fc = self.eigenvalue(c, k);
            if fc == 0.0 {
                (a, b) = (c, c);
                break;
            }
            if fc > 0.0 {
                (a, fa) = (c, fc);
                if side == 1 {
                    fb *= 0.5;
                }
                side = 1;
            } else {
                (b, fb) = (c, fc);
                if side == -1 {
                    fa *= 0.5;
                }
                side = -1;
            }
        }
        Bracketed {
            frequency: 0.5 * (a + b),
            width: 0.5 * (b - a),
            index: Some(k),
        }
    }

    /// The quality factor of the root at `f` whose crossing eigenvalue is the `k`-th, and
    /// the part of its accuracy (Hz) that is not the bracket (see [`Problem::complex_shift`]).
    fn loss(&self, f: f64, k: usize, held: &[HeldResonance]) -> (f64, f64) {
        let e = self.real(f);
        let eigen = e.clone().symmetric_eigen();
        let mut order: Vec<usize> = (0..eigen.eigenvalues.len()).collect();
        order.sort_by(|&i, &j| eigen.eigenvalues[i].total_cmp(&eigen.eigenvalues[j]));
        let Some(&column) = order.get(k) else {
            return (f64::NAN, f64::INFINITY);
        };
        let z = eigen.eigenvectors.column(column).into_owned();
        let (x, slope) = self.complex_shift(f, &z, held);
        // the computed eigenvalue is that of E + δE with ‖δE‖ ≲ n ε ‖E‖ (the entries of E
        // themselves carry a few ε of their own, the continuum's chains included)
        let n = e.nrows() as f64;
        let rounding = n * f64::EPSILON * e.norm() / slope.abs();
        (quality(f, x.im), rounding + x.re.abs())
    }

    /// The complex shift x of the root at `f` (null vector `z` of the lossless E) when the
    /// loss is put in, and the slope ∂λ/∂f of its eigenvalue (per Hz).
    ///
    /// Near the nearest held resonance f_p (whose own loss moves it to f_p + iδ_p), E is
    /// A(f) + R/(f_p − f), A regular: the loss shifts that pole exactly, and enters A to
    /// first order. With r = zᵀRz (R from E on either side of f_p), u = f_p − f,
    /// a′ = zᵀA′z and a_i = zᵀ Im A z, the root of zᵀE z = 0 moves by
    ///
    /// ```text
    /// x = i (a_i u² − r δ_p) / (−r − a′u² − i a′ δ_p u),
    /// ```
    ///
    /// linear in the losses but not in δ_p/u: a root nearer the resonance than its width
    /// (a fibre hanging an almost still body) takes the fibre's own loss, x → iδ_p, where
    /// perturbing at real f would see Im E of the pole's flank instead. Far from it,
    /// x = i a_i/(−λ′), the usual first-order result.
    fn complex_shift(
        &self,
        f: f64,
        z: &nalgebra::DVector<f64>,
        held: &[HeldResonance],
    ) -> (c64, f64) {
        let quad = |m: &DMatrix<f64>| z.dot(&(m * z));
        // the nearest group of resonances and the distance to the next one beyond it
        let mut distances: Vec<(f64, &HeldResonance)> = held
            .iter()
            .map(|r| ((r.frequency_hz - f).abs(), r))
            .collect();
        distances.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (fp, dp, next) = match distances.first() {
            Some(&(_, p)) => {
                let group: Vec<&HeldResonance> = distances
                    .iter()
                    .map(|d| d.1)
                    .filter(|r| {
                        (r.frequency_hz - p.frequency_hz).abs()
                            <= 2.0 * AT_RESONANCE * p.frequency_hz
                    })
                    .collect();
                let beyond = distances
                    .iter()
                    .filter(|d| !group.iter().any(|g| std::ptr::eq(*g, d.1)))
                    .map(|d| d.0)
                    .fold(f, f64::min);
                let mean = |v: &dyn Fn(&HeldResonance) -> f64| {
                    group.iter().map(|r| v(r)).sum::<f64>() / group.len() as f64
                };
                (mean(&|r| r.frequency_hz), mean(&|r| r.imag_hz), beyond)
            }
            None => (f64::INFINITY, 0.0, f),
        };
        // R = lim (f_p − f) E(f) from both sides, 1e-8 f_p away: the regular part's share
        // −Δ²A′ cancels to first order, and E's rounding near the pole is ε f_p/Δ ≈ 1e-8
        let residue = if fp.is_finite() {
            let delta = 1e-8 * fp;
            (self.real(fp - delta) - self.real(fp + delta)) * (0.5 * delta)
        } else {
            DMatrix::zeros(self.size, self.size)
        };
        let r = quad(&residue);
        let u = fp - f;
        let pole = |g: f64| {
            if fp.is_finite() {
                &residue / (fp - g)
            } else {
                residue.clone() * 0.0
            }
        };
        // a′ by a central difference of A = E − R/(f_p − f) over a step well inside the
        // distance to the next resonance
        let h = (1e-4 * f).min(0.25 * next);
        let a_slope = (quad(&(self.real(f + h) - pole(f + h)))
            - quad(&(self.real(f - h) - pole(f - h))))
            / (2.0 * h);
        // the loss of A: Im E less that of the shifted pole, Im R/(u + iδ_p)
        let a_loss = quad(&self.imag(f)) + r * dp / (u * u + dp * dp);
        let slope = if fp.is_finite() {
            a_slope + r / (u * u)
        } else {
            a_slope
        };
        let (num, den) = if fp.is_finite() {
            (
                c64::new(0.0, a_loss * u * u - r * dp),
                c64::new(-r - a_slope * u * u, -a_slope * dp * u),
            )
        } else {
            (c64::new(0.0, a_loss), c64::new(-a_slope, 0.0))
        };
        (num / den, slope)
    }
}

/// f/(2 Im f); infinite without loss.
fn quality(f: f64, imag: f64) -> f64 {
    if imag > 0.0 {
        f / (2.0 * imag)
    } else {
        f64::INFINITY
    }
}
