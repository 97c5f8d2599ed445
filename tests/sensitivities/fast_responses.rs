//! The fast response paths against the straightforward dense reference.
//!
//! The fast paths (fixed-pattern assembly with the frequency-independent tags folded once,
//! restriction to the blocks the input and output couple to, the small dense LU and the
//! sparse LU, the per-tag noise forms) change only the order of floating-point operations,
//! never the mathematics: the blocks left out are decoupled by exact zeros. Their results
//! must therefore equal the reference (P(f) summed densely over the whole master matrix
//! and one dense LU over every unknown, per frequency: `Solver::DenseReference`) to
//! rounding, amplified at most by the conditioning of E(f). The frequencies are chosen off
//! the resonances (at least 2 % away on these models), where that amplification is below
//! 1e3, so 1e-12 relative is the tolerance: a bug (a missing tag, a wrong sign, a dropped
//! coupling) gives errors of order one.

use faer::c64;
use nalgebra::{DMatrix, DVector};
use pendkit::StageResult;
use pendkit_dynamics::{Input, Output, Solver, Sweep};
use pendkit_noise::{NoiseOptions, thermal_noise_with};
use pendkit_system::Stage;
use pendkit_tests::run;

/// Frequencies (Hz) off every resonance of the models below.
const FREQS: [f64; 5] = [0.13, 0.77, 2.9, 11.0, 47.0];

/// (model, overrides, output variable of the lowest mass, a point on the lowest body with
/// a vertical component in its direction)
const MODELS: [(&str, &[&str], &str, Option<&str>); 8] = [
    ("pendulum", &[], "x1", None),
    ("double-pendulum", &[], "x2", None),
    (
        "rigid-body",
        &[],
        "x1",
        Some("mass1@0.1,0.17,0.01/1,0.2,0.5"),
    ),
    ("quad", &[], "x3", Some("testmass@0.1,0.17,0.01/1,0.2,0.5")),
    (
        "quad-lateral",
        &[],
        "x3",
        Some("testmass@0.1,0.17,0.01/1,0.2,0.5"),
    ),
    (
        "quad-v5",
        &[],
        "x3",
        Some("testmass@0.1,0.17,0.01/1,0.2,0.5"),
    ),
    ("triple", &[], "x3", Some("optic@0.1,0.12,0.01/1,0.2,0.5")),
    // a bead count that puts the whole system above the dense limit: the sparse LU
    ("quad", &["n_beads=12"], "x3", None),
];

fn stage2(model: &str, sets: &[&str]) -> StageResult {
    run(model, sets, Stage::S2)
}

/// The (input, output) pairs checked on a model: support displacement and force inputs,
/// displacement, point and support-force outputs.
fn pairs(output: &str, point: Option<&str>) -> Vec<(String, String)> {
    let mut p = vec![
        ("x00".to_string(), output.to_string()),
        (format!("force:{output}"), output.to_string()),
        ("x00".to_string(), "force:x00".to_string()),
        (format!("force:{output}"), "force:x00".to_string()),
        ("z00".to_string(), output.replace('x', "z")),
    ];
    if let Some(point) = point {
        p.push(("x00".to_string(), point.to_string()));
        p.push((format!("force:{point}"), output.to_string()));
    }
    p
}

/// First-order bound on how much two backward-stable computations of one response can
/// differ. Each adds the parts of E(f) (and of the input's and output's couplings to the
/// support) in its own order, which perturbs an entry by at most γ_k (k = the number of
/// parts) times the sum of the magnitudes of its parts, A = |lossless| + Σ_tag |m_tag(f)|
/// |P_tag| + ω² |M|; and each factorises with its own pivots: an LU with partial pivoting
/// solves (E + δE) x̂ = b with |δE| ≤ γ_3n Pᵀ|L||U| (Higham, Accuracy and Stability of
/// Numerical Algorithms, thm. 9.4), γ_m = mε/(1 − mε). To first order the output
/// y = õᵀ E⁻¹ b moves by λᵀ δE x (plus the perturbations of the couplings to the support),
/// with x = E⁻¹ b the response and λ = E⁻¹ õ the adjoint (E is symmetric), so the bound is
/// γ_k (|λ|ᵀ A_uu |x| + |λ|ᵀ A_us |s| + |o_s|ᵀ A_su |x| + |o_s|ᵀ A_ss |s|) plus
/// γ_3n |λ|ᵀ Pᵀ|L||U| |x|. It is ~1e-15 of |y| for most pairs here and reaches ~1e-10 of
/// |y| for the vertical chains far above their resonances, where the answer is a small
/// difference of stiff terms. Without the γ factors (ε alone) the observed differences
/// already stayed below it on every pair checked.
fn rounding_bound(r: &StageResult, input: &Input, output: &Output, f: f64) -> f64 {
    use faer::prelude::Solve;
    let m = &r.model;
    let (nx, nq, ns) = m.sizes;
    let n = nx + nq;
    let dim = n + ns;
    let gamma = |k: usize| k as f64 * f64::EPSILON / (1.0 - k as f64 * f64::EPSILON);
    let w2 = (2.0 * std::f64::consts::PI * f).powi(2);
    let mut abs = DMatrix::<f64>::zeros(dim, dim);
    let mut add = |values: &[f64], weight: f64| {
        for (v, position) in values.iter().zip(m.pattern.positions()) {
            abs[position] += weight * v.abs();
        }
    };
    add(&m.lossless, 1.0);
    for (tag, values) in &m.by_tag {
        let (re, im) = r.system.damping.at(tag, f);
        add(values, re.hypot(im));
    }
    add(&m.mass_on_pattern, w2);
    let parts = m.by_tag.len() + 2;
    let (re, im) = m.master(&r.system.damping, f);
    let p = |i: usize, j: usize| c64::new(re[(i, j)], im[(i, j)]);
    let e = faer::Mat::<c64>::from_fn(n, n, |i, j| {
        let mass = if i < nx && j < nx {
            m.mass[(i, j)]
        } else {
            0.0
        };
        p(i, j) - c64::new(w2 * mass, 0.0)
    });
    let zero = DVector::zeros(ns);
    let (force, s) = match input {
        Input::Force(force) => (Some(force), &zero),
        Input::Displacement(s) => (None, s),
    };
    let b = faer::Mat::<c64>::from_fn(n, 1, |i, _| {
        let f_i = force.map_or(0.0, |force| if i < nx { force[i] } else { 0.0 });
        c64::new(f_i, 0.0) - (0..ns).map(|k| p(i, n + k) * s[k]).sum::<c64>()
    });
    let (o_s, o_u) = match output {
        Output::Displacement(o) => (
            DVector::zeros(ns),
            faer::Mat::<c64>::from_fn(n, 1, |i, _| c64::new(if i < nx { o[i] } else { 0.0 }, 0.0)),
        ),
        Output::SupportForce(o) => (
            o.clone(),
            faer::Mat::<c64>::from_fn(n, 1, |j, _| {
                -(0..ns).map(|k| p(n + k, j) * o[k]).sum::<c64>()
            }),
        ),
    };
    let lu = e.partial_piv_lu();
    let x = lu.solve(&b);
    let lambda = lu.solve(&o_u);
    let left = |i: usize| {
        if i < n {
            lambda[(i, 0)].norm()
        } else {
            o_s[i - n].abs()
        }
    };
    let right = |j: usize| {
        if j < n {
            x[(j, 0)].norm()
        } else {
            s[j - n].abs()
        }
    };
    let mut assembly = 0.0;
    for i in 0..dim {
        for j in 0..dim {
            assembly += left(i) * abs[(i, j)] * right(j);
        }
    }
    let (l, u, perm) = (lu.L(), lu.U(), lu.P());
    let (row_of, _) = perm.arrays();
    let mut factorisation = 0.0;
    for i in 0..n {
        // row i of P E is row row_of[i] of E
        for j in 0..n {
            let lu_ij: f64 = (0..n).map(|k| l[(i, k)].norm() * u[(k, j)].norm()).sum();
            factorisation += left(row_of[i]) * lu_ij * right(j);
        }
    }
    gamma(parts) * assembly + gamma(3 * n) * factorisation
}

#[test]
fn transfer_functions_equal_the_dense_reference() {
    for (model, sets, output, point) in MODELS {
        let r = stage2(model, sets);
        for (input, out) in pairs(output, point) {
            let reference = r
                .transfer_with(&input, &out, &FREQS, Solver::DenseReference)
                .unwrap();
            let (i, o) = (r.input(&input).unwrap(), r.output(&out).unwrap());
            for solver in [Solver::Restricted, Solver::Full] {
                let got = r.transfer_with(&input, &out, &FREQS, solver).unwrap();
                for ((g, w), f) in got.iter().zip(&reference).zip(FREQS) {
                    let what = format!("{model} {sets:?} {out}/{input} at {f} Hz, {solver:?}");
                    let bound = rounding_bound(&r, &i, &o, f);
                    assert!(
                        (g - w).norm() <= 1e-12 * w.norm() + bound,
                        "{what}: {g} vs reference {w} (relative {:.2e}, bound {:.2e})",
                        (g - w).norm() / w.norm(),
                        bound / w.norm()
                    );
                }
            }
        }
    }
}

#[test]
fn thermal_noise_equals_the_dense_reference_in_total_per_tag_and_per_term() {
    // The per-tag and per-term shares are compared to the total: a share is a quadratic
    // form of the same response, so its rounding is relative to the total it adds up to.
    for (model, sets, output, point) in MODELS {
        let r = stage2(model, sets);
        for out in std::iter::once(output).chain(point) {
            let Output::Displacement(v) = r.output(out).unwrap() else {
                panic!("{out} is a displacement output");
            };
            let noise = |solver, per_term| {
                let options = NoiseOptions { solver, per_term };
                let t = r.system.temperature;
                thermal_noise_with(&r.model, &r.system.damping, &v, t, &FREQS, &options).unwrap()
            };
            let reference = noise(Solver::DenseReference, true);
            for solver in [Solver::Restricted, Solver::Full] {
                let fast = noise(solver, true);
                for (k, f) in FREQS.iter().enumerate() {
                    let what = format!("{model} {sets:?} noise of {out} at {f} Hz, {solver:?}");
                    let total = reference.total[k];
                    assert!(
                        (fast.total[k] - total).abs() <= 1e-12 * total,
                        "{what}: total {} vs {total}",
                        fast.total[k]
                    );
                    assert_eq!(fast.tags.len(), reference.tags.len());
                    for ((tag, a), (_, b)) in fast.tags.iter().zip(&reference.tags) {
                        assert!(
                            (a[k] - b[k]).abs() <= 1e-12 * total,
                            "{what}: tag {tag} {} vs {}",
                            a[k],
                            b[k]
                        );
                    }
                    for ((term, _, a), (_, _, b)) in fast.by_term.iter().zip(&reference.by_term) {
                        assert!(
                            (a[k] - b[k]).abs() <= 1e-12 * total,
                            "{what}: term {term} {} vs {}",
                            a[k],
                            b[k]
                        );
                    }
                    // and the per-tag shares add up to the total (fluctuation–dissipation)
                    let sum: f64 = fast.tags.iter().map(|(_, s)| s[k]).sum();
                    assert!((sum - total).abs() <= 1e-9 * total, "{what}: Σ tags {sum}");
                }
            }
            // without asking, there is no per-term breakdown (it costs a form per term)
            assert!(noise(Solver::Restricted, false).by_term.is_empty());
        }
    }
}

/// Names of the unknowns a restricted sweep solves.
fn solved(r: &StageResult, input: &str, output: &str) -> Vec<String> {
    let (i, o) = (r.input(input).unwrap(), r.output(output).unwrap());
    let sweep = Sweep::new(&r.model, &r.system.damping, &i, &o, Solver::Restricted).unwrap();
    let names: Vec<&String> = r.model.variables.iter().chain(&r.model.floats).collect();
    let mut s: Vec<String> = sweep.unknowns().iter().map(|&u| names[u].clone()).collect();
    s.sort();
    s
}

fn sorted(names: &[&str]) -> Vec<String> {
    let mut s: Vec<String> = names.iter().map(|n| n.to_string()).collect();
    s.sort();
    s
}

#[test]
fn the_restriction_is_the_coupled_blocks_of_the_suspension() {
    // The quad is symmetric about its x–z and y–z planes, so its longitudinal motion (x and
    // pitch of the four masses) is exactly decoupled from the rest: the 8 unknowns of that
    // block, whatever drives it longitudinally.
    let quad = stage2("quad", &[]);
    let x_pitch = sorted(&[
        "x0", "x1", "x2", "x3", "pitch0", "pitch1", "pitch2", "pitch3",
    ]);
    for input in ["x00", "force:x3", "pitch00"] {
        assert_eq!(solved(&quad, input, "x3"), x_pitch, "{input}");
    }
    // a vertical input reaches the y–z–roll block with the vertical blade tips, not x3:
    // nothing to solve, and the transfer function is exactly zero
    assert!(solved(&quad, "z00", "x3").is_empty());
    let zero = quad.transfer("z00", "x3", &[1.0]).unwrap();
    assert_eq!(zero[0], c64::new(0.0, 0.0));
    // an output with a vertical part (here its thermal noise: the same point as input and
    // output) adds the block holding z: y, z and roll of every mass with the six vertical
    // blade-tip floats, coupled through the tips' left/right pairs
    let point = "testmass@0,0,0/1,0,1";
    let with_vertical = solved(&quad, &format!("force:{point}"), point);
    assert_eq!(with_vertical.len(), 8 + 12 + 6);
    // driven longitudinally only, the vertical block is never excited: 8 again
    assert_eq!(solved(&quad, "x00", point), x_pitch);
    for name in ["z3", "y3", "roll3", "zb0l", "zb2r", "x3", "pitch0"] {
        assert!(with_vertical.iter().any(|n| n == name), "{name}");
    }
    assert!(!with_vertical.iter().any(|n| n.starts_with("yaw")));
    // quad-lateral: the lateral blade-tip floats xb* couple the x–pitch block to yaw in
    // these coordinates (each tip's lateral stiffness is driven by x and, with opposite
    // signs left and right, by yaw), so the block is x, pitch, yaw and the six xb floats
    let lateral = stage2("quad-lateral", &[]);
    let mut expected: Vec<String> = x_pitch.clone();
    for k in 0..4 {
        expected.push(format!("yaw{k}"));
    }
    for tip in ["0l", "0r", "1l", "1r", "2l", "2r"] {
        expected.push(format!("xb{tip}"));
    }
    expected.sort();
    assert_eq!(solved(&lateral, "x00", "x3"), expected);
}

#[test]
fn state_space_matches_an_independent_float_elimination() {
    // docs/physics.md §3 with K_eff, C_XS,eff, S_eff from a Schur complement done here with
    // nalgebra's complex LU on the dense master matrix (the code under test uses its own
    // elimination, shared with the modes).
    for model in ["quad", "quad-lateral", "triple", "double-pendulum"] {
        let r = stage2(model, &[]);
        let f_d = 1.0;
        let ss = r.model.state_space(&r.system.damping, f_d).unwrap();
        let (nx, nq, ns) = r.model.sizes;
        let (re, im) = r.model.master(&r.system.damping, f_d);
        let p = DMatrix::from_fn(re.nrows(), re.ncols(), |i, j| {
            nalgebra::Complex::new(re[(i, j)], im[(i, j)])
        });
        let kept: Vec<usize> = (0..nx).chain(nx + nq..nx + nq + ns).collect();
        let floats: Vec<usize> = (nx..nx + nq).collect();
        let pick = |rows: &[usize], cols: &[usize]| {
            DMatrix::from_fn(rows.len(), cols.len(), |i, j| p[(rows[i], cols[j])])
        };
        let mut a = pick(&kept, &kept);
        if nq > 0 {
            let q_inv = pick(&floats, &floats).lu().try_inverse().unwrap();
            a -= pick(&kept, &floats) * q_inv * pick(&floats, &kept);
        }
        let m_inv = r.model.mass.to_dense().try_inverse().unwrap();
        let k_eff = a.view((0, 0), (nx, nx)).into_owned();
        let c_eff = a.view((0, nx), (nx, ns)).into_owned();
        let s_eff = a.view((nx, nx), (ns, ns)).into_owned();
        let minus_mk = -(&m_inv * k_eff.map(|z| z.re));
        let damping = -(&m_inv * k_eff.map(|z| z.im)) / (2.0 * std::f64::consts::PI * f_d);
        let minus_mc = -(&m_inv * c_eff.map(|z| z.re));
        let check = |got: DMatrix<f64>, want: DMatrix<f64>, what: &str| {
            let scale = want.amax();
            assert!(
                (&got - &want).amax() <= 1e-12 * scale,
                "{model} {what}: {:.3e} of {scale:.3e}",
                (&got - &want).amax()
            );
        };
        check(ss.a.view((nx, 0), (nx, nx)).into_owned(), minus_mk, "A21");
        check(ss.a.view((nx, nx), (nx, nx)).into_owned(), damping, "A22");
        check(ss.b.view((nx, 0), (nx, ns)).into_owned(), minus_mc, "B21");
        check(
            ss.c.view((nx, 0), (ns, nx)).into_owned(),
            -c_eff.map(|z| z.re).transpose(),
            "C21",
        );
        check(
            ss.d.view((nx, 0), (ns, ns)).into_owned(),
            -s_eff.map(|z| z.re),
            "D21",
        );
    }
}

#[test]
fn a_force_response_is_zero_outside_the_coupled_blocks() {
    // respond_to_force over every unknown: the entries outside the block the force drives
    // are exactly zero (decoupled by exact zeros, not small numbers)
    let r = stage2("quad", &[]);
    let k = r.model.variables.iter().position(|v| v == "x3").unwrap();
    let mut force = DVector::zeros(r.model.variables.len());
    force[k] = 1.0;
    let z = r
        .model
        .respond_to_force(&r.system.damping, &force, 3.0)
        .unwrap();
    for (name, zi) in r.model.variables.iter().chain(&r.model.floats).zip(&z) {
        let in_block = name.starts_with('x') || name.starts_with("pitch");
        assert_eq!(*zi == c64::new(0.0, 0.0), !in_block, "{name}: {zi}");
    }
    // the input of a sweep is checked against the model
    let short = Input::Force(DVector::zeros(3));
    let out = Output::Displacement(force);
    let e = Sweep::new(
        &r.model,
        &r.system.damping,
        &short,
        &out,
        Solver::Restricted,
    )
    .err()
    .unwrap();
    assert!(
        e.to_string()
            .contains("force input has 3 entries, expected 24"),
        "{e}"
    );
}
