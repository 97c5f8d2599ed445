//! Normal modes solved block by block, and the modes below a frequency by shift-invert
//! Lanczos, against a whole-matrix solve with an independent library (nalgebra).
//!
//! The reference reduces the whole pencil with K_eff's Cholesky factor and solves for
//! 1/ω² (the method the code used before it split the problem into blocks). Both are exact
//! up to rounding: a mode's ω² carries an absolute error of about ε ω²_max/ω²_min · ω²
//! relative to the lowest mode of its problem (the reduced matrix has eigenvalues
//! 1/ω² with errors ε/ω²_min), which is below 1e-12 for the suspension modes and grows to
//! ~1e-8 for the stiffest bead and blade modes. The tolerance per mode is therefore
//! 1e-9 (issue 9's target for the mode frequencies) plus 100 ε ω²/ω²_min: a wrong block, a
//! missing coupling or a wrong normalisation gives errors of order one.

use nalgebra::DMatrix;
use pendkit::StageResult;
use pendkit_dynamics::{EntryRounding, Mode, StiffnessRounding, TermRounding, eliminate_floats};
use pendkit_system::Stage;
use pendkit_tests::{TWO_PI, run};

/// ω² ascending and M-normalised vectors (columns) of the whole pencil (K, M), by
/// nalgebra: K = L Lᵀ, C = L⁻¹ M L⁻ᵀ, μ = 1/ω².
fn whole_matrix_modes(k: &DMatrix<f64>, m: &DMatrix<f64>) -> Vec<(f64, Vec<f64>)> {
    let l = k.clone().cholesky().expect("K_eff positive definite").l();
    let x = l.solve_lower_triangular(m).unwrap();
    let c = l.solve_lower_triangular(&x.transpose()).unwrap();
    let c = (&c + c.transpose()) * 0.5;
    let eig = c.symmetric_eigen();
    let mut modes: Vec<(f64, Vec<f64>)> = (0..k.nrows())
        .map(|j| {
            let w = eig.eigenvectors.column(j).into_owned();
            let u = l.tr_solve_lower_triangular(&w).unwrap();
            let norm = u.dot(&(m * &u)).sqrt();
            (
                1.0 / eig.eigenvalues[j],
                (u / norm).iter().copied().collect(),
            )
        })
        .collect();
    modes.sort_by(|a, b| a.0.total_cmp(&b.0));
    modes
}

fn k_eff(r: &StageResult) -> DMatrix<f64> {
    eliminate_floats(
        &r.model.real_stiffness(&r.system.damping),
        &r.assembled.layout,
        &r.system,
    )
    .unwrap()
    .k_eff
}

/// Tolerance on ω² of a mode (see the file comment).
fn tolerance(w2: f64, lowest: f64) -> f64 {
    1e-9 + 100.0 * f64::EPSILON * w2 / lowest
}

/// Asserts that `modes` are `reference` (ω², vector): the frequencies, and the vectors and
/// energy fractions of the modes whose vectors are determined: an eigenvector turns by
/// about (error of its ω²) / (relative gap to its nearest neighbour), so where that
/// sensitivity is below 1e-6 the vectors must agree within it (|v_refᵀ M v| = 1 to its
/// square, the fractions to twice it); the near-degenerate violin multiplets, whose vectors
/// no double-precision method determines, are compared by frequency only.
#[track_caller]
fn assert_same_modes(what: &str, modes: &[Mode], reference: &[(f64, Vec<f64>)], m: &DMatrix<f64>) {
    assert_eq!(modes.len(), reference.len(), "{what}: number of modes");
    let lowest = reference[0].0;
    for (k, (mode, (w2, v))) in modes.iter().zip(reference).enumerate() {
        let tol = tolerance(*w2, lowest);
        assert!(
            (mode.omega_squared - w2).abs() <= tol * w2,
            "{what}: mode {k} ω² {} vs {w2} (relative {:.2e} > {tol:.1e})",
            mode.omega_squared,
            ((mode.omega_squared - w2) / w2).abs()
        );
        assert!((mode.hz - w2.sqrt() / TWO_PI).abs() <= tol * mode.hz);
        let gap = [k.wrapping_sub(1), k + 1]
            .iter()
            .filter_map(|&j| reference.get(j))
            .map(|(o, _)| ((o - w2) / w2).abs())
            .fold(f64::INFINITY, f64::min);
        let sensitivity = tol / gap;
        if sensitivity < 1e-6 {
            let vm = nalgebra::DVector::from_column_slice(&mode.vector);
            let vr = nalgebra::DVector::from_column_slice(v);
            let overlap = vr.dot(&(m * &vm)).abs();
            assert!(
                (overlap - 1.0).abs() <= 1e-12 + sensitivity * sensitivity,
                "{what}: mode {k} overlap {overlap}"
            );
            let mv = m * &vr;
            for (i, f) in mode.energy_fractions.iter().enumerate() {
                assert!(
                    (f - vr[i] * mv[i]).abs() <= 1e-12 + 2.0 * sensitivity,
                    "{what}: mode {k} fraction {i}: {f} vs {}",
                    vr[i] * mv[i]
                );
            }
        }
    }
}

#[test]
fn blocked_modes_equal_the_whole_matrix_solve() {
    for (model, sets) in [
        ("pendulum", &[][..]),
        ("double-pendulum", &[]),
        ("rigid-body", &[]),
        ("quad", &[]),
        ("quad-lateral", &[]),
        ("quad-lite", &[]),
        ("quad-v5", &[]),
        ("triple", &[]),
        ("quad", &["n_beads=10"]),
    ] {
        for stage in [Stage::S0A, Stage::S2] {
            let r = run(model, sets, stage);
            let k = k_eff(&r);
            let m = &r.assembled.mass.to_dense();
            let reference = whole_matrix_modes(&k, m);
            let what = format!("{model} {sets:?} {stage}");
            assert_same_modes(&what, &r.modes.modes, &reference, m);
        }
    }
}

#[test]
fn banded_chain_blocks_equal_the_whole_matrix_solve() {
    // A 30-stage chain: blocks x–pitch and y–roll of 60 variables with bandwidth 3, z and
    // yaw of 30 (bandwidth 1), so K_eff's Cholesky factors are narrow and the reduction
    // takes the envelope solves (modes.rs) instead of faer's dense ones; the reference is
    // still the whole 180-variable pencil by nalgebra, with the same tolerance.
    for stage in [Stage::S0A, Stage::S2] {
        let r = run("chain", &["n_stages=30"], stage);
        let k = k_eff(&r);
        let m = &r.assembled.mass.to_dense();
        let reference = whole_matrix_modes(&k, m);
        assert_same_modes(&format!("chain-30 {stage}"), &r.modes.modes, &reference, m);
    }
}

#[test]
fn blocks_follow_the_exact_zeros() {
    // the quad's stage-0A modes come from three blocks of K_eff and M (x–pitch, y–z–roll
    // coupled through the vertical blade tips' left/right pairs, yaw): each mode's vector
    // lies in one of them exactly, not approximately
    let r = run("quad", &[], Stage::S0A);
    let names = &r.modes.coordinates;
    let block = |n: &str| {
        if n.starts_with('x') || n.starts_with("pitch") {
            0
        } else if n.starts_with("yaw") {
            2
        } else {
            1
        }
    };
    let mut counts = [0; 3];
    for m in &r.modes.modes {
        let b = block(&m.label);
        for (n, v) in names.iter().zip(&m.vector) {
            assert!(block(n) == b || *v == 0.0, "{} Hz: {n} = {v}", m.hz);
        }
        counts[b] += 1;
    }
    assert_eq!(counts, [8, 12, 4]);
}

#[test]
fn a_modes_rounding_over_its_block_equals_the_estimate_over_all_variables() {
    // The modes cost each mode's rounding estimate over its block only
    // (`StiffnessRounding::estimate_on`); the reference is the same estimate over all n
    // variables (`estimate`), which visits every row and every term. The zeros outside the
    // block add nothing, so the two must agree bit for bit, for the bound and for the
    // term-by-term figure alike, and with the support being the whole set of variables
    // (several blocks: the Lanczos modes' case) as well as the mode's non-zeros. The quad
    // has floats (the blade tips, whose motion the float map adds), the chain four blocks.
    for (model, sets, stage) in [
        ("quad", &[][..], Stage::S0A),
        ("quad", &[], Stage::S2),
        ("quad-v5", &[], Stage::S2),
        ("chain", &["n_stages=12"], Stage::S2),
    ] {
        let r = run(model, sets, stage);
        let terms = TermRounding::new(&r.model, &r.assembled, &r.system.damping);
        let entries = EntryRounding::new(&k_eff(&r));
        let all: Vec<usize> = (0..r.modes.coordinates.len()).collect();
        for mode in &r.modes.modes {
            let v = &mode.vector;
            let nonzero: Vec<usize> = (0..v.len()).filter(|&i| v[i] != 0.0).collect();
            for keep in [true, false] {
                let keep_bound = |_: f64| keep;
                let rounding: [&dyn StiffnessRounding; 2] = [&terms, &entries];
                for rounding in rounding {
                    let full = rounding.estimate(v, &keep_bound);
                    for support in [&nonzero, &all] {
                        let on = rounding.estimate_on(v, support, &keep_bound);
                        assert_eq!(
                            on.to_bits(),
                            full.to_bits(),
                            "{model} {stage} {} Hz (bound {keep}): {on:e} against {full:e}",
                            mode.hz
                        );
                    }
                }
            }
        }
    }
}

#[test]
fn modes_below_a_frequency_by_shift_invert_equal_the_dense_solve() {
    // 10 beads per fibre (144 variables) below 100 Hz: the 24 suspension modes; below
    // 1100 Hz also the first two violin harmonics, each eight modes within 1e-5 of one
    // another (four fibres, two directions), which a single-vector Lanczos would miss.
    let r = run("quad", &["n_beads=10"], Stage::S2);
    let m = &r.assembled.mass.to_dense();
    let reference = whole_matrix_modes(&k_eff(&r), m);
    for hz in [0.5, 100.0, 1100.0] {
        let below = r.model.modes_below(&r.system.damping, hz).unwrap();
        let expected: Vec<(f64, Vec<f64>)> = reference
            .iter()
            .filter(|(w2, _)| w2.sqrt() / TWO_PI < hz)
            .cloned()
            .collect();
        assert!(!expected.is_empty());
        assert_same_modes(&format!("below {hz} Hz"), &below.modes, &expected, m);
        assert_eq!(below.coordinates, r.model.variables);
    }
    // the quad without beads, through the floats (blade tips) of the joint factorisation
    let quad = run("quad", &[], Stage::S2);
    let reference = whole_matrix_modes(&k_eff(&quad), &quad.assembled.mass.to_dense());
    let below = quad.model.modes_below(&quad.system.damping, 2.0).unwrap();
    let expected: Vec<_> = reference
        .into_iter()
        .filter(|(w2, _)| w2.sqrt() / TWO_PI < 2.0)
        .collect();
    assert_same_modes(
        "quad below 2 Hz",
        &below.modes,
        &expected,
        &quad.assembled.mass.to_dense(),
    );
    // a bound that is not a frequency is refused
    let e = quad
        .model
        .modes_below(&quad.system.damping, -1.0)
        .unwrap_err();
    assert!(e.to_string().contains("must be positive"), "{e}");
}

#[test]
fn nearly_degenerate_violin_modes_keep_their_own_frequencies() {
    // quad-aligo with 20 beads per fibre: each violin harmonic is eight modes (four fibres,
    // two directions) within 2e-5 of one another, and the pair at 490.9411 Hz is split by
    // 2.4e-9 relative. The reference for each mode is the Rayleigh quotient of its own
    // vector, vᵀKv / vᵀMv, formed here with nalgebra from the dense K_eff and M: for an
    // eigenvector accurate to δ it is the eigenvalue to O(δ²), so a mode reported at a
    // neighbour's frequency (faer's eigensolver once merged such pairs at an absolute
    // tolerance, 5e-9 off here, while stating 1e-11) shows as a difference far beyond
    // the mode's stated error. Tolerance: the stated ω² error plus the rounding of the
    // quotient itself, 4ε (|v|ᵀ|K||v| + ω²|v|ᵀ|M||v|) / vᵀMv.
    let r = run("quad-aligo", &["n_beads=20"], Stage::S2);
    let k = k_eff(&r);
    let m = r.assembled.mass.to_dense();
    let violins: Vec<&Mode> = r
        .modes
        .modes
        .iter()
        .filter(|mode| mode.hz > 400.0 && mode.hz < 1100.0)
        .collect();
    assert_eq!(violins.len(), 16, "two harmonics of eight modes");
    for mode in violins {
        let v = nalgebra::DVector::from_column_slice(&mode.vector);
        let a = v.abs();
        let norm = v.dot(&(&m * &v));
        let quotient = v.dot(&(&k * &v)) / norm;
        let rounding =
            4.0 * f64::EPSILON * (a.dot(&(k.abs() * &a)) + quotient * a.dot(&(m.abs() * &a)))
                / norm;
        let difference = (mode.omega_squared - quotient).abs();
        assert!(
            difference <= mode.omega_squared_error + rounding,
            "{} Hz ({}): ω² {} against its vector's quotient {quotient}: {difference:e} > \
             stated {:e} + rounding {rounding:e}",
            mode.hz,
            mode.label,
            mode.omega_squared,
            mode.omega_squared_error
        );
    }
    // and the split pair is two frequencies, as shift-invert (a second method) finds them
    let below = r.model.modes_below(&r.system.damping, 1100.0).unwrap();
    let pair = |modes: &[Mode]| {
        let mut hz: Vec<f64> = modes
            .iter()
            .map(|m| m.hz)
            .filter(|&f| (f - 490.9411).abs() < 1e-4)
            .collect();
        hz.sort_by(f64::total_cmp);
        hz
    };
    let (dense, sliced) = (pair(&r.modes.modes), pair(&below.modes));
    assert_eq!(dense.len(), 2);
    assert_eq!(sliced.len(), 2);
    for (d, s) in dense.iter().zip(&sliced) {
        assert!((d - s).abs() <= 1e-12 * s, "{dense:?} against {sliced:?}");
    }
    assert!(dense[1] - dense[0] > 1e-9 * dense[0], "{dense:?}");
}
