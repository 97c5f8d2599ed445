//! Frequency responses with dissipation dilution (DESIGN.md §4–§5): the complex master
//! matrix P(f), force and support-displacement transfer functions, forces on the support,
//! and the state-space form (thermal noise builds on it in `pendkit-noise`).
//!
//! The per-term matrices are assembled once; damping enters only through the multipliers
//! passed to each call, so trying other damping never re-assembles anything.

use faer::prelude::Solve;
use faer::{Mat, c64};
use nalgebra::{DMatrix, DVector};
use pendkit_assembly::{Assembled, OffHessian};
use pendkit_energy::{Damping, System};

use crate::DynamicsError;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// One term's tension-off Hessian, kept for the noise breakdown.
#[derive(Clone, Debug)]
pub struct TermLoss {
    /// Term name.
    pub label: String,
    /// Damping tag.
    pub tag: String,
    /// Master-matrix rows of the term's coordinates.
    pub positions: Vec<usize>,
    /// Tension-off Hessian over those coordinates (row-major).
    pub off: Vec<f64>,
}

/// The frequency-independent matrices of one stage: P(f) = lossless + Σ_tag m_tag(f) P_tag.
#[derive(Clone, Debug)]
pub struct StageModel {
    /// Numbers of variables, floats and parameters (master-matrix order x, q, s).
    pub sizes: (usize, usize, usize),
    /// Variable names.
    pub variables: Vec<String>,
    /// Parameter names.
    pub parameters: Vec<String>,
    /// Σ(P_on − P_off): stiffness from static loads through changing geometry (lossless).
    pub lossless: DMatrix<f64>,
    /// Σ P_off per damping tag.
    pub by_tag: Vec<(String, DMatrix<f64>)>,
    /// Per-term tension-off Hessians (for the noise breakdown).
    pub terms: Vec<TermLoss>,
    /// Mass matrix over the variables.
    pub mass: DMatrix<f64>,
}

/// A displacement or force input.
#[derive(Clone, Debug, PartialEq)]
pub enum Input {
    /// Displacement of the parameters (m or rad per unit input), one entry per parameter.
    Displacement(DVector<f64>),
    /// Generalised force on the variables (N or N m per unit input), one per variable.
    Force(DVector<f64>),
}

/// A displacement or support-force output.
#[derive(Clone, Debug, PartialEq)]
pub enum Output {
    /// A linear combination of the variables (m or rad).
    Displacement(DVector<f64>),
    /// A linear combination of the generalised forces on the parameters (N or N m).
    SupportForce(DVector<f64>),
}

/// Complex master matrix at one frequency, as real and imaginary parts.
struct Complex {
    re: DMatrix<f64>,
    im: DMatrix<f64>,
}

/// Real state-space matrices with names (DESIGN.md §5), damping as viscous at `f_d`.
#[derive(Clone, Debug)]
pub struct StateSpace {
    /// State matrix (2n × 2n).
    pub a: DMatrix<f64>,
    /// Input matrix (2n × (n_s + n)).
    pub b: DMatrix<f64>,
    /// Output matrix ((n + n_s) × 2n).
    pub c: DMatrix<f64>,
    /// Feedthrough ((n + n_s) × (n_s + n)).
    pub d: DMatrix<f64>,
    /// State names: the variables, then their rates (`<name>_dot`).
    pub states: Vec<String>,
    /// Input names: support displacements, then `force:<variable>`.
    pub inputs: Vec<String>,
    /// Output names: the variables, then `force:<parameter>` (forces on the support).
    pub outputs: Vec<String>,
    /// Frequency (Hz) at which frequency-dependent damping was represented as viscous.
    pub damping_frequency: f64,
}

impl StageModel {
    /// Collects the stage's matrices from an assembly.
    pub fn new(system: &System, assembled: &Assembled) -> Self {
        let (lossless, tags) = assembled.dilution_parts();
        let layout = &assembled.layout;
        let names = |ids: &[usize]| ids.iter().map(|&i| system.coords[i].name.clone()).collect();
        let terms = assembled
            .terms
            .iter()
            .filter_map(|t| {
                let off = match &t.off {
                    OffHessian::Zero => return None,
                    OffHessian::Same => t.on.clone(),
                    OffHessian::Matrix(m) => m.clone(),
                };
                Some(TermLoss {
                    label: t.label.clone(),
                    tag: t.tag.clone(),
                    positions: t.coords.iter().map(|&g| layout.position[g]).collect(),
                    off,
                })
            })
            .collect();
        StageModel {
            sizes: layout.sizes(),
            variables: names(&layout.variables),
            parameters: names(&layout.parameters),
            lossless,
            by_tag: tags.into_iter().collect(),
            terms,
            mass: assembled.mass.clone(),
        }
    }

    fn master_at(&self, damping: &Damping, f_hz: f64) -> Complex {
        let mut re = self.lossless.clone();
        let mut im = DMatrix::zeros(re.nrows(), re.ncols());
        for (tag, p) in &self.by_tag {
            let (mr, mi) = damping.at(tag, f_hz);
            re += p * mr;
            if mi != 0.0 {
                im += p * mi;
            }
        }
        Complex { re, im }
    }

    /// Real stiffness at f = 0 (ε' of each tag at DC): the matrix the modes use.
    pub fn real_stiffness(&self, damping: &Damping) -> DMatrix<f64> {
        self.master_at(damping, 0.0).re
    }

    /// Complex master matrix P(f) (layout order x, q, s).
    pub fn master(&self, damping: &Damping, f_hz: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        let c = self.master_at(damping, f_hz);
        (c.re, c.im)
    }

    /// Factorises A(f) = P_{xq,xq}(f) − ω² diag(M, 0) and solves A z = rhs for each column.
    fn solve(&self, p: &Complex, f_hz: f64, rhs: &Mat<c64>) -> Mat<c64> {
        let (nx, nq, _) = self.sizes;
        let n = nx + nq;
        let w2 = (TWO_PI * f_hz).powi(2);
        let a = Mat::<c64>::from_fn(n, n, |i, j| {
            let m = if i < nx && j < nx {
                self.mass[(i, j)]
            } else {
                0.0
            };
            c64::new(p.re[(i, j)] - w2 * m, p.im[(i, j)])
        });
        a.partial_piv_lu().solve(rhs)
    }

    /// Transfer function from `input` to `output` at each frequency (Hz): output per unit
    /// input, complex (m/m, m/N, N/m, N/N ...). Sign conventions of DESIGN.md §5: a
    /// pendulum's displacement transfer function tends to +1 at DC.
    pub fn transfer(
        &self,
        damping: &Damping,
        input: &Input,
        output: &Output,
        freqs: &[f64],
    ) -> Vec<c64> {
        let (nx, nq, ns) = self.sizes;
        let n = nx + nq;
        freqs
            .iter()
            .map(|&f| {
                let p = self.master_at(damping, f);
                let pc = |i: usize, j: usize| c64::new(p.re[(i, j)], p.im[(i, j)]);
                let s_in = match input {
                    Input::Displacement(s) => s.clone(),
                    Input::Force(_) => DVector::zeros(ns),
                };
                // right-hand side: the force the input puts on the variables and floats
                let rhs = Mat::<c64>::from_fn(n, 1, |i, _| match input {
                    Input::Force(force) => c64::new(if i < nx { force[i] } else { 0.0 }, 0.0),
                    Input::Displacement(s) => -(0..ns).map(|k| pc(i, n + k) * s[k]).sum::<c64>(),
                });
                let z = self.solve(&p, f, &rhs);
                match output {
                    Output::Displacement(o) => (0..nx).map(|i| z[(i, 0)] * o[i]).sum(),
                    Output::SupportForce(o) => {
                        // f_s = −∂U/∂s = −(P_{s,xq} z + P_ss s)
                        (0..ns)
                            .map(|k| {
                                let row = n + k;
                                let from_z: c64 = (0..n).map(|j| pc(row, j) * z[(j, 0)]).sum();
                                let from_s: c64 = (0..ns).map(|j| pc(row, n + j) * s_in[j]).sum();
                                -(from_z + from_s) * o[k]
                            })
                            .sum()
                    }
                }
            })
            .collect()
    }

    /// Response z (over the variables, then the floats) to the generalised force `force`
    /// on the variables at `f_hz`, with the support held: A(f) z = [force; 0].
    pub fn respond_to_force(&self, damping: &Damping, force: &DVector<f64>, f_hz: f64) -> Vec<c64> {
        let (nx, nq, _) = self.sizes;
        let rhs = Mat::<c64>::from_fn(nx + nq, 1, |i, _| {
            c64::new(if i < nx { force[i] } else { 0.0 }, 0.0)
        });
        let z = self.solve(&self.master_at(damping, f_hz), f_hz, &rhs);
        (0..nx + nq).map(|i| z[(i, 0)]).collect()
    }

    /// Complex reduced matrices K_eff(f), C_XS,eff(f), S_eff(f) (Schur complement of the
    /// floats done on the complex matrices, per frequency).
    pub fn reduced(&self, damping: &Damping, f_hz: f64) -> ReducedComplex {
        let (nx, nq, ns) = self.sizes;
        let p = self.master_at(damping, f_hz);
        let keep: Vec<usize> = (0..nx).chain(nx + nq..nx + nq + ns).collect();
        let k = keep.len();
        let pc = |i: usize, j: usize| c64::new(p.re[(i, j)], p.im[(i, j)]);
        let mut a = Mat::<c64>::from_fn(k, k, |i, j| pc(keep[i], keep[j]));
        if nq > 0 {
            let q = Mat::<c64>::from_fn(nq, nq, |i, j| pc(nx + i, nx + j));
            let c_qk = Mat::<c64>::from_fn(nq, k, |i, j| pc(nx + i, keep[j]));
            let q_inv_c = q.partial_piv_lu().solve(&c_qk);
            let c_kq = Mat::<c64>::from_fn(k, nq, |i, j| pc(keep[i], nx + j));
            a -= &c_kq * &q_inv_c;
        }
        let block = |r0: usize, c0: usize, nr: usize, nc: usize| {
            Mat::<c64>::from_fn(nr, nc, |i, j| a[(r0 + i, c0 + j)])
        };
        ReducedComplex {
            k_eff: block(0, 0, nx, nx),
            c_xs_eff: block(0, nx, nx, ns),
            s_eff: block(nx, nx, ns, ns),
        }
    }

    /// State-space matrices with damping represented as viscous at `f_d` (Hz, > 0); exact
    /// for viscous damping only.
    pub fn state_space(&self, damping: &Damping, f_d: f64) -> Result<StateSpace, DynamicsError> {
        if f_d.is_nan() || f_d <= 0.0 {
            return Err(DynamicsError::DampingFrequency(f_d));
        }
        let (nx, _, ns) = self.sizes;
        let r = self.reduced(damping, f_d);
        let m_inv = self
            .mass
            .clone()
            .cholesky()
            .ok_or_else(|| DynamicsError::SingularMass {
                variable: self.variables.first().cloned().unwrap_or_default(),
            })?
            .inverse();
        let re = |m: &Mat<c64>| DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)].re);
        let im = |m: &Mat<c64>| DMatrix::from_fn(m.nrows(), m.ncols(), |i, j| m[(i, j)].im);
        let mk_re = -(&m_inv * re(&r.k_eff));
        let mk_im = -(&m_inv * im(&r.k_eff)) / (TWO_PI * f_d);
        let mc_re = -(&m_inv * re(&r.c_xs_eff));
        let mut a = DMatrix::zeros(2 * nx, 2 * nx);
        a.view_mut((0, nx), (nx, nx)).fill_with_identity();
        a.view_mut((nx, 0), (nx, nx)).copy_from(&mk_re);
        a.view_mut((nx, nx), (nx, nx)).copy_from(&mk_im);
        let mut b = DMatrix::zeros(2 * nx, ns + nx);
        b.view_mut((nx, 0), (nx, ns)).copy_from(&mc_re);
        b.view_mut((nx, ns), (nx, nx)).copy_from(&m_inv);
        let mut c = DMatrix::zeros(nx + ns, 2 * nx);
        c.view_mut((0, 0), (nx, nx)).fill_with_identity();
        c.view_mut((nx, 0), (ns, nx))
            .copy_from(&(-re(&r.c_xs_eff).transpose()));
        let mut d = DMatrix::zeros(nx + ns, ns + nx);
        d.view_mut((nx, 0), (ns, ns)).copy_from(&(-re(&r.s_eff)));
        let forces = |names: &[String]| {
            names
                .iter()
                .map(|n| format!("force:{n}"))
                .collect::<Vec<_>>()
        };
        Ok(StateSpace {
            a,
            b,
            c,
            d,
            states: self
                .variables
                .iter()
                .cloned()
                .chain(self.variables.iter().map(|n| format!("{n}_dot")))
                .collect(),
            inputs: self
                .parameters
                .iter()
                .cloned()
                .chain(forces(&self.variables))
                .collect(),
            outputs: self
                .variables
                .iter()
                .cloned()
                .chain(forces(&self.parameters))
                .collect(),
            damping_frequency: f_d,
        })
    }
}

/// Complex K_eff, C_XS,eff and S_eff at one frequency.
#[derive(Clone, Debug)]
pub struct ReducedComplex {
    /// K_eff over the variables.
    pub k_eff: Mat<c64>,
    /// C_XS,eff: variables × parameters.
    pub c_xs_eff: Mat<c64>,
    /// S_eff over the parameters.
    pub s_eff: Mat<c64>,
}
