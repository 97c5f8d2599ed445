//! The `chain` model (N identical 40 kg bodies, each on four vertical steel wires from the
//! one above) against references computed here: its nominal geometry, the closed forms of
//! one stage (docs/reference-values.md §2, §3, §4), the bounce modes of a fixed–free chain of
//! equal masses and springs, the longitudinal modes of a hanging chain of point masses,
//! and the exact separation of its four blocks.
//!
//! Tolerances: the references are exact second-order expansions of the same potential, so
//! what separates them from pendkit is floating-point rounding in assembly and the
//! eigen-solve (about 1e-13 relative) and the equilibrium residual (below 1e-11 of the
//! largest tension); 1e-10 relative leaves margin above both. A wrong stiffness, mass or
//! tension would be off by far more (a missing wire by 25 %, a tension off by one stage by
//! 1/N).

use nalgebra::{DMatrix, SymmetricEigen};
use pendkit::run_stage;
use pendkit_system::Stage;
use pendkit_tests::{TWO_PI, assert_rel, block, run, two_dof_frequencies};

const REL: f64 = 1e-10;
const G: f64 = 9.81;
/// The chain's defaults (models/basic/src/chain.rs), written out as the reference's inputs.
const M: f64 = 40.0;
const L: f64 = 0.6;
const A_WIRE: f64 = 0.005;
const B_WIRE: f64 = 0.17;
const D_TOP: f64 = 0.010;
const D_BOTTOM: f64 = 0.010;
const INERTIA: [f64; 3] = [0.57, 0.42, 0.42];

/// Axial stiffness of one default steel wire, k = E A / l (N/m): E = 212 GPa, r = 0.5 mm.
fn k_wire() -> f64 {
    212e9 * std::f64::consts::PI * 0.5e-3f64.powi(2) / L
}

fn sets(n: usize, extra: &[&str]) -> Vec<String> {
    let mut s = vec![format!("n_stages={n}")];
    s.extend(extra.iter().map(|e| e.to_string()));
    s
}

fn run_chain(n: usize, extra: &[&str], stage: Stage) -> pendkit::StageResult {
    let s = sets(n, extra);
    run(
        "chain",
        &s.iter().map(String::as_str).collect::<Vec<_>>(),
        stage,
    )
}

/// Frequencies (Hz) of the modes labelled by a coordinate starting with `prefix` (and not
/// another coordinate that shares the prefix: `y` excludes `yaw`), ascending.
fn block_modes(r: &pendkit::StageResult, prefix: &str) -> Vec<f64> {
    r.modes
        .modes
        .iter()
        .filter(|m| m.label.starts_with(prefix) && !(prefix == "y" && m.label.starts_with("yaw")))
        .map(|m| m.hz)
        .collect()
}

#[test]
fn equilibrium_is_the_nominal_geometry() {
    // Nominal geometry from the parameters: body k's centre at
    // z_k = -k (d_top + l + d_bottom) + d_bottom, level and on the z axis. The equilibrium
    // must land there to a micrometre (the unstretched lengths come from the static
    // tensions), whatever the number of stages.
    for n in [1, 4, 30] {
        let r = run_chain(n, &[], Stage::S0A);
        let eq = &r.assembled.equilibrium.coords;
        for k in 1..=n {
            let z = -(k as f64) * (D_TOP + L + D_BOTTOM) + D_BOTTOM;
            for (c, nominal) in ["x", "y", "z", "yaw", "pitch", "roll"]
                .into_iter()
                .zip([0.0, 0.0, z, 0.0, 0.0, 0.0])
            {
                let name = format!("{c}{k}");
                let i = r.system.coord(&name).expect("coordinate");
                assert!(
                    (eq[i] - nominal).abs() < 1e-6,
                    "n = {n}: {name} at {}, nominal {nominal}",
                    eq[i]
                );
            }
        }
    }
}

#[test]
fn one_stage_is_the_rigid_body_closed_form() {
    // A single stage is the rigid-body model on steel wires; its six stage-0A modes in
    // closed form, with T = m g / 4 per wire and k_w = E A / l:
    // - x–pitch (§2, attachment d_top above the centre of mass, x-separations ±a):
    //   K_xx = mg/l, K_xθ = −mg d/l, K_θθ = mg d + mg d²/l + 4 k_w a², with I_y;
    // - y–roll: the same with b for a and I_x (the sign of K_yφ does not change the roots);
    // - bounce (§3): 4 k_w / m;
    // - yaw (§4): (T/l) Σ r² = (mg/4l) 4 (a² + b²), with I_z.
    let r = run_chain(1, &[], Stage::S0A);
    let (mg, d, kw) = (M * G, D_TOP, k_wire());
    let pair = |s: f64, inertia: f64| {
        let (kxx, kxt, ktt) = (
            mg / L,
            -mg * d / L,
            mg * d + mg * d * d / L + 4.0 * kw * s * s,
        );
        two_dof_frequencies([[kxx, kxt], [kxt, ktt]], (M, inertia))
    };
    let x_pitch = pair(A_WIRE, INERTIA[1]);
    let y_roll = pair(B_WIRE, INERTIA[0]);
    let bounce = (4.0 * kw / M).sqrt() / TWO_PI;
    let yaw = (mg / L * (A_WIRE * A_WIRE + B_WIRE * B_WIRE) / INERTIA[2]).sqrt() / TWO_PI;
    let mut expected = vec![x_pitch[0], x_pitch[1], y_roll[0], y_roll[1], bounce, yaw];
    expected.sort_by(f64::total_cmp);
    let found: Vec<f64> = r.modes.modes.iter().map(|m| m.hz).collect();
    assert_eq!(found.len(), 6);
    for (f, e) in found.iter().zip(&expected) {
        assert_rel(*f, *e, REL);
    }
}

#[test]
fn one_stage_matches_the_rigid_body_model_at_every_stage() {
    // With the rigid-body model's fibres (silica, r = 0.2 mm, E = 72 GPa, ν = 0.17,
    // ρ = 2200) a one-stage chain is that model, built by the other code path: every mode
    // at every stage, bending and torsion included, agrees to rounding.
    let fibres = [
        "r_wire=0.2e-3",
        "E_wire=72e9",
        "nu_wire=0.17",
        "rho_wire=2200",
    ];
    for stage in Stage::ALL {
        let chain = run_chain(1, &fibres, stage);
        let rigid = run("rigid-body", &[], stage);
        assert_eq!(chain.modes.modes.len(), rigid.modes.modes.len());
        for (c, r) in chain.modes.modes.iter().zip(&rigid.modes.modes) {
            assert_rel(c.hz, r.hz, 1e-12);
        }
    }
}

/// ω_j² = (K/m) 4 sin²((2j − 1) π / (2 (2N + 1))), j = 1..N: the modes of N equal masses m
/// on N equal springs K, the first fixed to the support and the last mass free.
///
/// Derivation: the equations of motion are m ü_n = K (u_{n−1} − 2 u_n + u_{n+1}) with
/// u_0 = 0 (support) and u_{N+1} = u_N (no spring below the last mass). u_n = sin(n θ)
/// satisfies the first boundary; the second needs sin((N + 1) θ) = sin(N θ), i.e.
/// (2N + 1) θ / 2 = (2j − 1) π / 2, θ = (2j − 1) π / (2N + 1); then ω² = (K/m)(2 − 2 cos θ)
/// = (K/m) 4 sin²(θ/2).
fn fixed_free_chain_hz(n: usize, k: f64, m: f64) -> Vec<f64> {
    (1..=n)
        .map(|j| {
            let theta = (2 * j - 1) as f64 * std::f64::consts::PI / (2 * n + 1) as f64;
            (k / m * 4.0 * (theta / 2.0).sin().powi(2)).sqrt() / TWO_PI
        })
        .collect()
}

#[test]
fn bounce_modes_are_those_of_a_fixed_free_chain_of_masses_and_springs() {
    // Vertically each stage is a spring K = 4 k_w (four wires of axial stiffness
    // k_w = E A / l; the tension only stiffens sideways motion, and gravity is linear in z),
    // so the z modes are the fixed–free chain's, for any number of stages.
    for n in [1, 2, 4, 10, 100] {
        let r = run_chain(n, &[], Stage::S0A);
        let found = block_modes(&r, "z");
        let expected = fixed_free_chain_hz(n, 4.0 * k_wire(), M);
        assert_eq!(found.len(), n, "n = {n}");
        for (f, e) in found.iter().zip(&expected) {
            assert_rel(*f, *e, REL);
        }
    }
}

/// Longitudinal modes (Hz) of N point masses m hanging one below the other on massless
/// strings of length l: the string above mass k carries the N − k + 1 masses from it down,
/// tension T_k = (N − k + 1) m g, and resists sideways motion of its ends with T_k / l.
/// K is tridiagonal, M = m I; solved here as a symmetric eigenproblem.
fn hanging_chain_hz(n: usize, m: f64, l: f64) -> Vec<f64> {
    let spring = |k: usize| (n - k + 1) as f64 * m * G / l; // string above mass k (1-based)
    let mut k = DMatrix::zeros(n, n);
    for i in 0..n {
        k[(i, i)] = spring(i + 1) + if i + 1 < n { spring(i + 2) } else { 0.0 };
        if i + 1 < n {
            k[(i, i + 1)] = -spring(i + 2);
            k[(i + 1, i)] = -spring(i + 2);
        }
    }
    let mut w2: Vec<f64> = SymmetricEigen::new(k / m)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    w2.sort_by(f64::total_cmp);
    w2.into_iter().map(|w2| w2.sqrt() / TWO_PI).collect()
}

#[test]
fn longitudinal_modes_with_centred_attachments_are_a_hanging_chain() {
    // With every wire attached at its bodies' centre-of-mass height (d_top = d_bottom = 0)
    // x decouples from pitch exactly: moving a body along x tilts its wires and changes
    // their tension only at second order, and pitching it moves the attachments (±a, ±b, 0)
    // only vertically, along wires that are vertical. The x modes are then those of point
    // masses on strings of length l_wire.
    let centred = ["d_top=0", "d_bottom=0"];
    // N = 2 against the double-pendulum closed form (docs/reference-values.md §2) with equal
    // masses and lengths: ω² = (g/l)(2 ∓ √2).
    let r = run_chain(2, &centred, Stage::S0A);
    let found = block_modes(&r, "x");
    let closed = [2.0 - 2f64.sqrt(), 2.0 + 2f64.sqrt()].map(|c| (c * G / L).sqrt() / TWO_PI);
    assert_eq!(found.len(), 2);
    for (f, e) in found.iter().zip(&closed) {
        assert_rel(*f, *e, REL);
    }
    // and longer chains against the tridiagonal eigenproblem (whose N = 2 case is the
    // closed form above: checked here too, so the two references agree)
    for (f, e) in hanging_chain_hz(2, M, L).iter().zip(&closed) {
        assert_rel(*f, *e, 1e-12);
    }
    for n in [4, 10] {
        let r = run_chain(n, &centred, Stage::S0A);
        let found = block_modes(&r, "x");
        let expected = hanging_chain_hz(n, M, L);
        assert_eq!(found.len(), n, "n = {n}");
        for (f, e) in found.iter().zip(&expected) {
            assert_rel(*f, *e, REL);
        }
    }
}

#[test]
fn blocks_are_separated_by_exact_zeros() {
    // The geometry is exactly symmetric (every wire vertical at (±a, ±b), bodies level and
    // centred), so the stiffness and mass have exact zeros between the x–pitch, y–roll, z
    // and yaw blocks, at every stage: a solver that splits the problem along the sparsity
    // pattern relies on it. Rounding cannot be allowed here: the contributions of the
    // mirrored wires must cancel exactly.
    for stage in [Stage::S0A, Stage::S2] {
        let r = run_chain(4, &[], stage);
        let k = pendkit::dynamics::eliminate_floats(
            &r.model.real_stiffness(&r.system.damping),
            &r.assembled.layout,
            &r.system,
        )
        .expect("no floats to eliminate")
        .k_eff;
        let names = &r.model.variables;
        let mut coupled = 0;
        for i in 0..names.len() {
            for j in 0..names.len() {
                if block(&names[i]) == block(&names[j]) {
                    coupled += usize::from(k[(i, j)] != 0.0);
                } else {
                    assert_eq!(k[(i, j)], 0.0, "K[{}, {}]", names[i], names[j]);
                    assert_eq!(r.assembled.mass[(i, j)], 0.0);
                }
            }
        }
        // and the blocks are not trivially empty: each body couples to its neighbours
        assert!(coupled > names.len(), "{coupled} non-zero entries");
    }
}

#[test]
fn stage_count_is_validated() {
    for (value, shown) in [("0", "0"), ("2.5", "2.5"), ("201", "201"), ("-3", "-3")] {
        let case = pendkit::Case::model("chain")
            .and_then(|c| c.with_sets(&[format!("n_stages={value}")]))
            .expect("case");
        let e = case.build().expect_err("must fail").to_string();
        assert_eq!(
            e,
            format!("parameter 'n_stages': must be a whole number from 1 to 200, got {shown}")
        );
    }
}

#[test]
fn a_hundred_stages_reach_stage_2() {
    // 600 variables, 400 wires: the scaling case of the benchmarks runs through stage 2 and
    // stays stable (every mode real and positive).
    let case = pendkit::Case::model("chain")
        .and_then(|c| c.with_sets(&["n_stages=100".into()]))
        .expect("case");
    let (system, _) = case.build().expect("builds");
    let r = run_stage(system, Stage::S2).expect("stage 2 runs");
    assert_eq!(r.modes.modes.len(), 600);
    assert!(r.modes.modes.iter().all(|m| m.hz > 0.0));
}

/// The sparse path (equilibrium Newton steps on the terms' sparsity pattern, modes below a
/// frequency by shift-invert on the sparse factorisation; both chosen above 200
/// coordinates) against the dense one (dense Hessian and Cholesky, every mode by the dense
/// eigen-solve) on a 40-stage chain, 240 variables, started off its equilibrium so that
/// Newton takes steps. Reference: the dense path, an independent factorisation and
/// eigen-solve of the same matrices. Tolerance 1e-9: both paths converge the equilibrium
/// to forces of 1e-11 of the largest tension, i.e. positions to about 1e-12 m, and
/// their modes agree to the eigen-solvers' rounding (about 1e-12 relative at the chain's
/// ratio of largest to smallest ω²); a wrong entry in the sparse Hessian or mass matrix
/// would move both by orders of magnitude more.
#[test]
fn sparse_path_equals_the_dense_one() {
    use pendkit::stage::{ModeSelection, RunOptions, run_stage_with};
    use pendkit_assembly::{AssemblyOptions, EquilibriumOptions};
    let (mut system, _) = pendkit::Case::model("chain")
        .and_then(|c| c.with_sets(&sets(40, &[])))
        .unwrap()
        .build()
        .unwrap();
    // off the equilibrium by up to 1 mm and 1 mrad, a different amount on each coordinate
    for (k, c) in system.coords.iter_mut().enumerate() {
        if c.kind == pendkit_system::CoordKind::Variable {
            c.start += 1e-3 * ((k % 7) as f64 - 3.0) / 3.0;
        }
    }
    let dense = RunOptions {
        assembly: AssemblyOptions {
            equilibrium: EquilibriumOptions {
                dense_limit: usize::MAX,
                ..Default::default()
            },
            ..Default::default()
        },
        modes: ModeSelection::All,
    };
    let below = 3.0;
    let sparse = RunOptions {
        modes: ModeSelection::Below(below),
        ..Default::default()
    };
    let d = run_stage_with(system.clone(), Stage::S2, &dense, None).unwrap();
    let s = run_stage_with(system, Stage::S2, &sparse, None).unwrap();
    assert!(s.modes.coordinates.len() > pendkit::stage::DENSE_MODES_LIMIT);
    assert!(
        s.assembled.equilibrium.iterations > 1,
        "Newton took {} steps",
        s.assembled.equilibrium.iterations
    );
    for (a, b) in d
        .assembled
        .equilibrium
        .coords
        .iter()
        .zip(&s.assembled.equilibrium.coords)
    {
        assert!((a - b).abs() <= 1e-9, "equilibrium {a} vs {b}");
    }
    // the dense eigen-solve of the dense matrices, every mode
    let k_eff = pendkit::dynamics::eliminate_floats(
        &d.model.real_stiffness(&d.system.damping),
        &d.assembled.layout,
        &d.system,
    )
    .unwrap()
    .k_eff;
    let mass = d.assembled.mass.to_dense();
    let dense_modes = pendkit::dynamics::normal_modes(&k_eff, &mass, &d.model.variables).unwrap();
    let all: Vec<f64> = dense_modes.modes.iter().map(|m| m.hz).collect();
    // every mode block by block from the pattern (the stage run's, above 200 variables)
    let by_blocks: Vec<f64> = d.modes.modes.iter().map(|m| m.hz).collect();
    assert_eq!(by_blocks.len(), all.len());
    for (a, b) in all.iter().zip(&by_blocks) {
        assert_rel(*b, *a, 1e-9);
    }
    let reference: Vec<f64> = all.into_iter().filter(|&hz| hz < below).collect();
    let found: Vec<f64> = s.modes.modes.iter().map(|m| m.hz).collect();
    assert!(
        reference.len() >= 20,
        "{} modes below {below} Hz",
        reference.len()
    );
    assert_eq!(found.len(), reference.len());
    for (a, b) in reference.iter().zip(&found) {
        assert_rel(*b, *a, 1e-9);
    }
}
