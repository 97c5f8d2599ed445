//! A continuum fibre in a stage model's responses: the frequency term
//! Jᵀ [D(f) − D_s(f)] J that turns the fibre's static stack into its continuum
//! (docs/continuum-fibres.md, "Responses and noise").

use std::sync::{Arc, Mutex};

use nalgebra::{Complex, DMatrix};
use pendkit_assembly::{Assembled, Layout};
use pendkit_dynamics::{FrequencyTerm, Group, HeldResonance};
use pendkit_system::System;

use crate::{C64, ContinuumFibre, FibreError, GROUPS, Local, Moduli};

/// The last one-dimensional stiffnesses computed, with the frequency (Hz) and multipliers
/// they are for: shared by the terms of alike fibres ([`ContinuumFibre::alike`]), which
/// differ only in their lab axes, so that each frequency's chain runs once for all of them.
type Cache = Arc<Mutex<Option<(f64, Moduli, Local)>>>;

/// One fibre's frequency term: over the master rows its end frames depend on, each tag's
/// part Jᵀ [D_tag(f; m_tag) − D_tag(0; 1) − (m_tag − 1) ∂D_tag(0)/∂m_tag] J. The bracket's
/// last two terms are the fibre's static stack as the stage model holds it (its tension-on
/// Hessian with the tag's tension-off part scaled by m_tag), so the term vanishes at f = 0
/// for multipliers of 1 and the static model's low-frequency answers stand.
///
/// D is block diagonal in the fibre's one-dimensional coordinates (axial, two beams,
/// twist: `ContinuumFibre::local_rows`), and so is the bracket, the static stack being D
/// at f = 0: the term's own displacements are those 12 coordinates, its blocks the bracket's
/// 2 × 2, 4 × 4, 4 × 4 and 2 × 2 blocks, and its Jacobian that of the coordinates over the
/// master rows, made once. A frequency point forms 40 values, no 12 × 12 matrix.
#[derive(Debug)]
pub struct ContinuumTerm {
    fibre: ContinuumFibre,
    label: String,
    positions: Vec<usize>,
    tags: Vec<String>,
    /// ∂(one-dimensional coordinates)/∂(master rows): 12 × positions.
    jacobian: DMatrix<f64>,
    groups: Vec<Group>,
    /// The blocks of D(0; 1) and of ∂D(0)/∂m_tag ([`Local::entries`] order).
    at_rest: [C64; Local::LEN],
    slope: [f64; Local::LEN],
    cache: Cache,
}

impl ContinuumTerm {
    /// The term of `fibre` between the end frames whose displacements (d₀, θ₀, d₁, θ₁: the
    /// attachment points' translations and the frames' small rotations, lab axes) are
    /// `jacobian` (12 × n) times those of the master rows `positions`.
    pub fn new(fibre: ContinuumFibre, positions: Vec<usize>, jacobian: DMatrix<f64>) -> Self {
        let at_rest = fibre.local(0.0, &Moduli::LOSSLESS).entries();
        // ∂D/∂m by a complex step: D is analytic in each multiplier, so Im D(1 + ih)/h is
        // the derivative to O(h²), with no cancellation
        let h = 1e-20;
        let bump = Complex::new(1.0, h);
        let stepped = fibre
            .local(
                0.0,
                &Moduli {
                    stretch: bump,
                    bending: bump,
                    torsion: bump,
                },
            )
            .entries();
        let slope = stepped.map(|z| z.im / h);
        let rows = fibre.local_rows();
        let local = DMatrix::from_fn(12, jacobian.ncols(), |r, c| {
            let (offset, v) = rows[r];
            (0..3).map(|a| v[a] * jacobian[(offset + a, c)]).sum()
        });
        let tags = vec![
            fibre.tags.stretch.clone(),
            fibre.tags.bending.clone(),
            fibre.tags.torsion.clone(),
        ];
        ContinuumTerm {
            label: format!("continuum:{}", fibre.name),
            fibre,
            positions,
            tags,
            jacobian: local,
            groups: GROUPS.map(|(rows, part)| Group { rows, part }).to_vec(),
            at_rest,
            slope,
            cache: Cache::default(),
        }
    }

    /// Shares `other`'s stiffness cache if the two fibres are alike
    /// ([`ContinuumFibre::alike`]: the quad's four fibres), and says whether it did: each
    /// frequency's one-dimensional stiffnesses are then computed once for both, and every
    /// number stays what each term computes alone (the same function of the same inputs).
    pub fn share_with(&mut self, other: &ContinuumTerm) -> bool {
        let alike = self.fibre.alike(&other.fibre);
        if alike {
            self.cache = Arc::clone(&other.cache);
        }
        alike
    }

    /// The fibre.
    pub fn fibre(&self) -> &ContinuumFibre {
        &self.fibre
    }
}

impl FrequencyTerm for ContinuumTerm {
    fn label(&self) -> &str {
        &self.label
    }

    fn positions(&self) -> &[usize] {
        &self.positions
    }

    fn jacobian(&self) -> &DMatrix<f64> {
        &self.jacobian
    }

    fn tags(&self) -> &[String] {
        &self.tags
    }

    fn groups(&self) -> &[Group] {
        &self.groups
    }

    fn held_resonances(
        &self,
        lo_hz: f64,
        hi_hz: f64,
        multipliers: &dyn Fn(f64) -> Vec<C64>,
    ) -> Vec<HeldResonance> {
        self.fibre
            .held_in(lo_hz, hi_hz, &|f| moduli_of(&multipliers(f)))
    }

    fn harmonics(&self, n: usize) -> Vec<f64> {
        self.fibre.held_resonances(n)
    }

    fn parts(&self, f_hz: f64, multipliers: &[C64], values: &mut [C64]) {
        let m = |t: usize| multipliers.get(t).copied().unwrap_or(C64::new(1.0, 0.0));
        let moduli = moduli_of(multipliers);
        let local = {
            // a poisoned lock only means another thread panicked mid-update: the entry is
            // checked against its key before use either way
            let mut cache = self
                .cache
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            match *cache {
                Some((f, m, local)) if f == f_hz && m == moduli => local,
                _ => {
                    let local = self.fibre.local(2.0 * std::f64::consts::PI * f_hz, &moduli);
                    *cache = Some((f_hz, moduli, local));
                    local
                }
            }
        };
        let d = local.entries();
        let one = C64::new(1.0, 0.0);
        let excess = [m(0) - one, m(1) - one, m(2) - one];
        for (e, v) in values.iter_mut().enumerate().take(Local::LEN) {
            *v = d[e] - self.at_rest[e] - excess[Local::tag(e)] * self.slope[e];
        }
    }
}

/// The fibre's [`Moduli`] from its tags' multipliers (stretch, bending, torsion order; one
/// for a multiplier not given).
fn moduli_of(multipliers: &[C64]) -> Moduli {
    let m = |t: usize| multipliers.get(t).copied().unwrap_or(C64::new(1.0, 0.0));
    Moduli {
        stretch: m(0),
        bending: m(1),
        torsion: m(2),
    }
}

/// The continuum terms of the wires `wires` (indices) of `system` at the equilibrium of
/// `assembled`: each fibre at its equilibrium ([`ContinuumFibre::at`]) with the Jacobian of
/// its end frames' displacements (attachment point, lab-axis rotation) over the master
/// rows. Alike fibres share one stiffness cache ([`ContinuumTerm::share_with`]). Errors
/// name the wire.
pub fn continuum_terms(
    system: &System,
    assembled: &Assembled,
    wires: &[usize],
) -> Result<Vec<Arc<dyn FrequencyTerm>>, FibreError> {
    let x = &assembled.equilibrium.coords;
    let layout: &Layout = &assembled.layout;
    let mut built: Vec<ContinuumTerm> = Vec::with_capacity(wires.len());
    for &w in wires {
        let fibre = ContinuumFibre::at(system, x, w)?;
        let wire = &system.wires[w];
        let mut rows = Vec::with_capacity(4);
        for end in &wire.ends {
            let jac = system.bodies[end.body]
                .frame
                .try_jacobian(x, &end.point)
                .map_err(|e| FibreError::Invalid {
                    wire: wire.name.clone(),
                    message: e.to_string(),
                })?;
            rows.push(jac.position);
            rows.push(jac.omega_space);
        }
        // the master rows any of the 12 depends on
        let positions: Vec<usize> = (0..x.len())
            .filter(|&g| {
                layout.position[g] != Layout::NO_ROW
                    && rows.iter().any(|r| r.column(g).iter().any(|&v| v != 0.0))
            })
            .map(|g| layout.position[g])
            .collect();
        let globals: Vec<usize> = (0..x.len())
            .filter(|&g| {
                layout.position[g] != Layout::NO_ROW && positions.contains(&layout.position[g])
            })
            .collect();
        let jacobian = DMatrix::from_fn(12, globals.len(), |r, c| rows[r / 3][(r % 3, globals[c])]);
        let mut term = ContinuumTerm::new(fibre, positions, jacobian);
        for other in &built {
            if term.share_with(other) {
                break;
            }
        }
        built.push(term);
    }
    Ok(built
        .into_iter()
        .map(|t| Arc::new(t) as Arc<dyn FrequencyTerm>)
        .collect())
}
