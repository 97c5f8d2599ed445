//! Continuum fibres: the exact dynamic stiffness D(f) of a tensioned fibre between the
//! attachment frames of its two bodies (docs/continuum-fibres.md).
//!
//! A fibre under static tension T is, for small motion about its straight equilibrium, the
//! Euler–Bernoulli beam under tension in each of its two transverse directions,
//! EI w⁗ − T w″ − μω² w = 0, the axial wave EA u″ + μω² u = 0 and the torsional wave
//! (G J_e + T J/A) φ″ + ρJ ω² φ = 0. Over a piecewise-uniform profile (the tapered silica
//! fibres of `quad-aligo`: thick necks, a thin middle) each piece has a closed-form
//! dynamic stiffness, and chaining them gives the fibre's 12×12 D(f) over the translation
//! and small rotation of both end frames, exact at every frequency: the violin modes are
//! its poles, the dissipation dilution the ratio of its imaginary to its real part.
//!
//! Losses enter as complex moduli: EA, EI and G J_e are multiplied by the damping tags'
//! complex multipliers (stretch, bending and torsion tag of the wire, [`Moduli`]); T and
//! T J/A stay real (tension stiffening is lossless), as in the static model's dilution.
//! At f → 0 with real moduli, D is the Hessian of the wire's static stage-2 terms (stretch,
//! torsion, bending and extra stretch) in the same end-frame coordinates.

mod piece;
mod term;
mod violin;

pub use term::{ContinuumTerm, continuum_terms};

use nalgebra::{Matrix2, Matrix3, Matrix4, SMatrix, Vector3};
use pendkit_energy::{EnergyError, Reference};
use pendkit_system::{System, Wire, WireTags};
pub use piece::C64;

/// Why a continuum fibre cannot be built.
#[derive(Debug, thiserror::Error)]
pub enum FibreError {
    /// The wire cannot be a continuum fibre (named, with the reason).
    #[error("continuum fibre '{wire}': {message}")]
    Invalid {
        /// The wire's name.
        wire: String,
        /// What is wrong.
        message: String,
    },
    /// The wire's geometry could not be evaluated (a body the model lacks).
    #[error(transparent)]
    Energy(#[from] EnergyError),
}

/// The complex multipliers ε′ + iε″ (dimensionless) of a fibre's three elasticities at one
/// frequency: those of its stretch, bending and torsion damping tags.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Moduli {
    /// Multiplies E A (the stretch tag).
    pub stretch: C64,
    /// Multiplies E I (the bending tag).
    pub bending: C64,
    /// Multiplies G J_e (the torsion tag).
    pub torsion: C64,
}

impl Moduli {
    /// All three equal to one: no loss.
    pub const LOSSLESS: Moduli = Moduli {
        stretch: C64::new(1.0, 0.0),
        bending: C64::new(1.0, 0.0),
        torsion: C64::new(1.0, 0.0),
    };
}

/// One uniform piece of a fibre, with its lossless constants.
#[derive(Clone, Debug, PartialEq)]
pub struct Piece {
    /// Length along the stretched fibre (m).
    pub length: f64,
    /// Axial stiffness E A (N).
    pub axial: f64,
    /// Bending stiffnesses E I (N m²) for displacement along the first principal direction
    /// and along the second.
    pub bending: [f64; 2],
    /// Unloaded twist stiffness G J_e (N m²).
    pub twist: f64,
    /// J/A (m²): the tension adds T J/A to the twist stiffness.
    pub twist_per_tension: f64,
    /// Linear density μ (kg/m).
    pub density: f64,
    /// Polar moment of inertia per length ρ J = μ J/A (kg m).
    pub twist_inertia: f64,
}

/// A fibre about its straight equilibrium: its pieces from end 0, static tension and
/// geometry in lab axes.
#[derive(Clone, Debug)]
pub struct ContinuumFibre {
    /// The wire's name.
    pub name: String,
    /// Pieces from end 0 to end 1; their lengths add up to the chord.
    pub pieces: Vec<Piece>,
    /// Static tension T (N), k (l − l₀) at the configuration.
    pub tension: f64,
    /// Lab positions of the two attachment points (m).
    pub ends: [Vector3<f64>; 2],
    /// First principal direction (lab, unit, ⟂ the chord): displacement along it bends
    /// with `bending[0]`.
    pub principal: Vector3<f64>,
    /// Whether each end is hinged (free to turn: no bending moment there).
    pub hinged: [bool; 2],
    /// The wire's damping tags (which multipliers make its [`Moduli`]).
    pub tags: WireTags,
}

/// A 12×12 complex dynamic stiffness over the two end frames' displacements.
pub type Stiffness = SMatrix<C64, 12, 12>;

/// The one-dimensional stiffness matrices of a fibre at one frequency.
#[derive(Clone, Copy, Debug)]
struct Local {
    axial: Matrix2<C64>,
    planes: [Matrix4<C64>; 2],
    torsion: Matrix2<C64>,
}

impl ContinuumFibre {
    /// Wire `wire` of `system` at coordinates `coords` (the equilibrium): its ends where the
    /// bodies put them. Errors: an index out of range, a slack or zero-length wire, a wire
    /// clamped other than straight, non-finite constants.
    pub fn at(system: &System, coords: &[f64], wire: usize) -> Result<Self, FibreError> {
        let w = system.wires.get(wire).ok_or_else(|| FibreError::Invalid {
            wire: format!("#{wire}"),
            message: format!("no such wire (the model has {})", system.wires.len()),
        })?;
        let reference = Reference::new(system, coords);
        let ends = reference.wire_points(w)?;
        let bad = |message: String| FibreError::Invalid {
            wire: w.name.clone(),
            message,
        };
        let chord = ends[1] - ends[0];
        let length = chord.norm();
        if !(length.is_finite() && length > 0.0) {
            return Err(bad(format!("its chord has length {length} m")));
        }
        let axis = chord / length;
        let directions = reference.wire_end_directions(w)?;
        let mut hinged = [false; 2];
        for (k, d) in directions.iter().enumerate() {
            let frame = reference.frame(w.ends[k].body)?;
            match d {
                None => hinged[k] = true,
                Some(d) => {
                    // the beam is linearised about a straight wire: a clamp must point along it
                    let lab = frame.rotation * d;
                    let into = if k == 0 { axis } else { -axis };
                    let off = lab.normalize().cross(&into).norm();
                    if off.is_nan() || off > 1e-9 {
                        return Err(bad(format!(
                            "end {k} is clamped {off:e} rad off the chord; a continuum fibre \
                             needs a wire that is straight at equilibrium"
                        )));
                    }
                }
            }
        }
        let rotation0 = reference.frame(w.ends[0].body)?.rotation;
        let tension = reference.wire_tension(w)?;
        Self::new(w, ends, &rotation0, hinged, tension)
    }

    /// The fibre of `wire` with its attachment points at `ends` (lab, m), end 0's body
    /// turned by `rotation0` (body to lab), hinged ends `hinged` and static tension
    /// `tension` (N, positive).
    pub fn new(
        wire: &Wire,
        ends: [Vector3<f64>; 2],
        rotation0: &Matrix3<f64>,
        hinged: [bool; 2],
        tension: f64,
    ) -> Result<Self, FibreError> {
        let bad = |message: String| FibreError::Invalid {
            wire: wire.name.clone(),
            message,
        };
        if !(tension.is_finite() && tension > 0.0) {
            return Err(bad(format!(
                "its static tension is {tension} N; a continuum fibre needs a taut wire"
            )));
        }
        let chord = ends[1] - ends[0];
        let length = chord.norm();
        let axis = chord / length;
        let p = rotation0 * wire.section.principal_axis;
        let p = p - axis * axis.dot(&p);
        if p.norm().is_nan() || p.norm() <= 1e-9 {
            return Err(bad("its principal axis is parallel to the wire".into()));
        }
        let pieces = pieces(wire, length);
        let finite = pieces.iter().all(|q| {
            let v = [q.length, q.axial, q.bending[0], q.bending[1], q.twist];
            v.iter().all(|x| x.is_finite() && *x > 0.0)
                && [q.twist_per_tension, q.density, q.twist_inertia]
                    .iter()
                    .all(|x| x.is_finite() && *x >= 0.0)
        });
        if !finite {
            return Err(bad(
                "its lengths, moduli, moments and density must be finite and positive".into(),
            ));
        }
        Ok(ContinuumFibre {
            name: wire.name.clone(),
            pieces,
            tension,
            ends,
            principal: p.normalize(),
            hinged,
            tags: wire.tags.clone(),
        })
    }

    /// Chord length (m).
    pub fn length(&self) -> f64 {
        (self.ends[1] - self.ends[0]).norm()
    }

    /// The one-dimensional stiffnesses at angular frequency `omega` (rad/s).
    fn local(&self, omega: f64, moduli: &Moduli) -> Local {
        let t = self.tension;
        let axial =
            piece::join_wave(&piece::chain(self.pieces.iter().map(|q| {
                piece::wave_piece(moduli.stretch * q.axial, q.density, omega, q.length)
            })));
        let torsion = piece::join_wave(&piece::chain(self.pieces.iter().map(|q| {
            let c = moduli.torsion * q.twist + t * q.twist_per_tension;
            piece::wave_piece(c, q.twist_inertia, omega, q.length)
        })));
        let plane = |a: usize| {
            let d = piece::chain(self.pieces.iter().map(|q| {
                piece::beam_piece(moduli.bending * q.bending[a], t, q.density, omega, q.length)
            }));
            self.release_hinges(piece::join(&d))
        };
        let first = plane(0);
        // a round section bends alike in both planes: the same numbers, computed once
        let round = self.pieces.iter().all(|q| q.bending[0] == q.bending[1]);
        let second = if round { first } else { plane(1) };
        Local {
            axial,
            planes: [first, second],
            torsion,
        }
    }

    /// A transverse matrix over (w₀, w₀′, w₁, w₁′) with the slope of each hinged end
    /// condensed out (no moment there) and its row and column left zero.
    fn release_hinges(&self, mut d: Matrix4<C64>) -> Matrix4<C64> {
        for (end, slope) in [(1, 3), (0, 1)] {
            if self.hinged[end] {
                d = piece::condense(&d, slope);
            }
        }
        d
    }

    /// The first `n` transverse resonances (Hz) of the lossless fibre with both ends held
    /// (in the first principal direction): the poles of D, found as the zeros of
    /// 1/D(w₀, w₁) (the cross stiffness), bracketed on a grid of 1/64 of the ideal string's
    /// fundamental √(T/μ̄)/2L from half of it up, and bisected to the last bit. A zero of
    /// the cross stiffness (a pole of its inverse, where it also changes sign) is told
    /// apart by the size of 1/D at the bisection's end.
    pub fn held_resonances(&self, n: usize) -> Vec<f64> {
        let mut found = Vec::with_capacity(n);
        if n == 0 {
            return found;
        }
        // at most 64 steps per expected mode and a few hundred more: a fibre has a mode
        // within each ~string interval
        self.scan_held(
            0.5 * self.string_fundamental(),
            64 * (n + 4),
            &|_| Moduli::LOSSLESS,
            &mut |motion, f| {
                if motion == 0 {
                    found.push(f);
                }
                found.len() < n
            },
        );
        found
    }

    /// The dynamic stiffness D(f) (12×12, complex) at frequency `frequency` (Hz) with the
    /// elasticities' complex multipliers `moduli`, over (translation of end 0's attachment
    /// point (m), small rotation of end 0's frame (rad), the same for end 1), lab axes:
    /// the generalised forces the ends exert on the fibre are D times those displacements.
    /// Entries are infinite at a resonance of the fibre with both ends held.
    pub fn dynamic_stiffness(&self, frequency: f64, moduli: &Moduli) -> Stiffness {
        let [a, b, c] = self.dynamic_stiffness_by_tag(frequency, moduli);
        a + b + c
    }

    /// [`ContinuumFibre::dynamic_stiffness`] in its three parts, each depending on one
    /// multiplier only: stretch (the axial wave), bending (both transverse beams) and
    /// torsion (the twist wave). Their sum is D; the imaginary part of each is the
    /// dissipation of that damping tag.
    pub fn dynamic_stiffness_by_tag(&self, frequency: f64, moduli: &Moduli) -> [Stiffness; 3] {
        let omega = 2.0 * std::f64::consts::PI * frequency;
        self.in_lab(&self.local(omega, moduli))
    }

    /// Whether `other` has the same one-dimensional stiffnesses at every frequency: the
    /// same pieces, tension and hinges (a mirror image or a turned copy of this fibre), so
    /// that the two differ only in their lab axes.
    pub fn alike(&self, other: &ContinuumFibre) -> bool {
        self.pieces == other.pieces && self.tension == other.tension && self.hinged == other.hinged
    }

    /// The fibre's one-dimensional coordinates ([`GROUPS`] order: u₀, u₁; w₀, w₀′, w₁, w₁′
    /// along the first principal direction, the same along the second; φ₀, φ₁) as rows over
    /// its 12 end-frame displacements (d₀, θ₀, d₁, θ₁, lab axes), each as (offset of its
    /// 3-block, direction): u = t·d, w_a = e_a·d, w_a′ = (t × e_a)·θ (e₂ and −e₁), φ = t·θ.
    pub(crate) fn local_rows(&self) -> [(usize, Vector3<f64>); 12] {
        let t = (self.ends[1] - self.ends[0]).normalize();
        let (e1, e2) = (self.principal, t.cross(&self.principal));
        [
            (0, t),
            (6, t),
            (0, e1),
            (3, e2),
            (6, e1),
            (9, e2),
            (0, e2),
            (3, -e1),
            (6, e2),
            (9, -e1),
            (3, t),
            (9, t),
        ]
    }

    /// The one-dimensional stiffnesses `local` turned into the three tags' 12 × 12 parts
    /// over the lab displacements of the end frames: Σ_g R_gᵀ V_g R_g with R the rows of
    /// [`ContinuumFibre::local_rows`].
    fn in_lab(&self, local: &Local) -> [Stiffness; 3] {
        let rows = self.local_rows();
        let values = local.entries();
        let mut parts = [Stiffness::zeros(); 3];
        let mut offset = 0;
        for (range, part) in GROUPS {
            let (r0, s) = (range.start, range.len());
            for i in 0..s {
                for k in 0..s {
                    let z = values[offset + i * s + k];
                    if z == C64::new(0.0, 0.0) {
                        continue;
                    }
                    let ((oi, vi), (ok, vk)) = (rows[r0 + i], rows[r0 + k]);
                    for a in 0..3 {
                        for b in 0..3 {
                            parts[part][(oi + a, ok + b)] += z * (vi[a] * vk[b]);
                        }
                    }
                }
            }
            offset += s * s;
        }
        parts
    }
}

/// The groups of a fibre's one-dimensional coordinates ([`ContinuumFibre::local_rows`]),
/// each with the tag its block belongs to (0 stretch, 1 bending, 2 torsion): the axial wave,
/// the beam along each principal direction, the twist wave.
pub(crate) const GROUPS: [(std::ops::Range<usize>, usize); 4] =
    [(0..2, 0), (2..6, 1), (6..10, 1), (10..12, 2)];

impl Local {
    /// Number of values of the blocks: 2 × 2 + 4 × 4 + 4 × 4 + 2 × 2.
    pub(crate) const LEN: usize = 40;

    /// The blocks, row-major, one after the other in [`GROUPS`] order.
    pub(crate) fn entries(&self) -> [C64; Self::LEN] {
        let mut out = [C64::new(0.0, 0.0); Self::LEN];
        let (axial, rest) = out.split_at_mut(4);
        let (planes, torsion) = rest.split_at_mut(32);
        for (k, v) in axial.iter_mut().enumerate() {
            *v = self.axial[(k / 2, k % 2)];
        }
        for (k, v) in planes.iter_mut().enumerate() {
            *v = self.planes[k / 16][((k % 16) / 4, k % 4)];
        }
        for (k, v) in torsion.iter_mut().enumerate() {
            *v = self.torsion[(k / 2, k % 2)];
        }
        out
    }

    /// The tag of value `e` of [`Local::entries`] (0 stretch, 1 bending, 2 torsion).
    pub(crate) fn tag(e: usize) -> usize {
        match e {
            0..4 => 0,
            4..36 => 1,
            _ => 2,
        }
    }
}

/// The pieces of `wire` stretched to the chord `length` (m): one piece of its section for a
/// uniform wire, its round pieces for a profile, their lengths scaled to the chord. EA is
/// set so that the pieces in series have the wire's axial stiffness k (the static model's
/// k = E A / l_eq), and μ so that the mean is the section's linear density.
fn pieces(wire: &Wire, length: f64) -> Vec<Piece> {
    let s = &wire.section;
    let (e, g) = (s.youngs_modulus, s.shear_modulus);
    if wire.profile.is_empty() {
        let j_over_a = s.polar_moment / s.area;
        return vec![Piece {
            length,
            axial: wire.stiffness * length,
            bending: [e * s.moment_1, e * s.moment_2],
            twist: g * s.torsion_constant,
            twist_per_tension: j_over_a,
            density: s.linear_density,
            twist_inertia: s.linear_density * j_over_a,
        }];
    }
    let pi = std::f64::consts::PI;
    let nominal: f64 = wire.profile.iter().map(|p| p.0).sum();
    let scale = length / nominal;
    let volume: f64 = wire.profile.iter().map(|&(l, r)| pi * r * r * l).sum();
    let rho = s.linear_density * nominal / volume;
    // E A_i c in series gives k: c = k Σ l_i/(E A_i)
    let compliance: f64 = wire
        .profile
        .iter()
        .map(|&(l, r)| l * scale / (e * pi * r * r))
        .sum();
    let c = wire.stiffness * compliance;
    wire.profile
        .iter()
        .map(|&(l, r)| {
            let (area, i) = (pi * r * r, pi * r.powi(4) / 4.0);
            Piece {
                length: l * scale,
                axial: e * area * c,
                bending: [e * i, e * i],
                twist: g * 2.0 * i,
                twist_per_tension: r * r / 2.0,
                density: rho * area,
                twist_inertia: rho * area * r * r / 2.0,
            }
        })
        .collect()
}
