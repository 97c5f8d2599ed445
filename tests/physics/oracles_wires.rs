//! The plug-in wire elements against closed forms (docs/reference-values.md
//! §1, §2, §4, §6, §9): flexure, exact dissipation dilution (never the naive ×2), pitch with
//! bending, yaw with twist and flexure, isolated torsion, and wire terms joining the
//! equilibrium early.
//!
//! References are computed in the tests from the oracle file's closed forms, with the beam
//! functions written here in their textbook cosh/sinh form (independent of the element
//! crate's overflow-free rewriting). Tolerances: frequencies 1e-9 relative (exact
//! second-order expansions of the same energy; rounding and the equilibrium residual are
//! far smaller); loss angles 1e-6 relative (the reference's EI ∂K/∂EI is taken by a central
//! difference with step 1e-4, error ~1e-8). Printed oracle digits to half a unit of the
//! last digit.

use pendkit::StageResult;
use pendkit_assembly::{EquilibriumOptions, solve_equilibrium};
use pendkit_system::Stage;
use pendkit_tests::{TWO_PI, assert_printed, assert_rel, hz, labelled, run, two_dof_frequencies};

const G: f64 = 9.81;
const E: f64 = 72e9;
const R: f64 = 0.2e-3;
const L: f64 = 0.6;

fn ei() -> f64 {
    E * std::f64::consts::PI * R.powi(4) / 4.0
}

/// s_ii, s_ij in Chen & Lui's cosh/sinh form (fine for u < 700).
fn stability(u: f64) -> (f64, f64) {
    let den = 2.0 - 2.0 * u.cosh() + u * u.sinh();
    (
        (u * u * u.cosh() - u * u.sinh()) / den,
        (u * u.sinh() - u * u) / den,
    )
}

/// Lateral stiffness (N/m) of one fibre with tension t: hinged bottom (one bending point)
/// K1 = T/(l − λ tanh(l/λ)), clamped non-rotating bottom K2 = T/(l − 2λ tanh(l/2λ)).
fn lateral(t: f64, ei: f64, clamped_bottom: bool) -> f64 {
    let lambda = (ei / t).sqrt();
    if clamped_bottom {
        t / (L - 2.0 * lambda * (L / (2.0 * lambda)).tanh())
    } else {
        t / (L - lambda * (L / lambda).tanh())
    }
}

/// Loss angle of x1 from the stage's complex K_eff at 1 Hz.
fn loss_angle(r: &StageResult, name: &str) -> f64 {
    let k = r.model.reduced(&r.system.damping, 1.0).unwrap().k_eff;
    let i = r.model.variables.iter().position(|v| v == name).unwrap();
    k[(i, i)].im / k[(i, i)].re
}

#[test]
fn pendulum_flexure_and_exact_dilution() {
    let phi = 1e-7;
    let t = 40.0 * G / 4.0;
    for (sets, clamped, printed_f, printed_loss, naive) in [
        (&[][..], false, 0.6440608, 8.015878e-11, 1.600610e-10),
        (
            &["hinged_bottom=0"][..],
            true,
            0.6445777,
            1.605750e-10,
            3.201219e-10,
        ),
    ] {
        let r = run("pendulum", sets, Stage::S2);
        let k = 4.0 * lateral(t, ei(), clamped);
        assert_rel(hz(&r, "x1", 0), (k / 40.0).sqrt() / TWO_PI, 1e-9);
        assert_printed(hz(&r, "x1", 0), printed_f, 7);
        // φ_pend = φ_w EI ∂K/∂EI / K: only the bending strain energy is lossy
        let h = 1e-4;
        let dk = (lateral(t, ei() * (1.0 + h), clamped) - lateral(t, ei() * (1.0 - h), clamped))
            / (2.0 * h);
        let exact = phi * 4.0 * dk / k;
        let loss = loss_angle(&r, "x1");
        assert_rel(loss, exact, 1e-6);
        assert_printed(loss, printed_loss, 7);
        // the factor-of-2 trap: "stiffness with bending minus without" would give this
        assert!((loss / naive - 0.5).abs() < 0.01, "{loss} vs naive {naive}");
    }
}

#[test]
fn pendulum_thermal_noise_at_10_hz() {
    // S_x = (4 k_B T/ω) |Im 1/(K(1 + iφ_p) − mω²)|, 290 K, one bending point per fibre:
    // ASD 2.326369e-20 m/√Hz at 10 Hz (oracle decisions).
    let r = run("pendulum", &[], Stage::S2);
    let t = 40.0 * G / 4.0;
    let k = 4.0 * lateral(t, ei(), false);
    let h = 1e-4;
    let kb = 4.0 * (lateral(t, ei() * (1.0 + h), false) - lateral(t, ei() * (1.0 - h), false))
        / (2.0 * h);
    let w = TWO_PI * 10.0;
    let (re, im) = (k - 40.0 * w * w, 1e-7 * kb);
    let s = 4.0 * 1.380649e-23 * 290.0 / w * im / (re * re + im * im);
    let i = r.model.variables.iter().position(|v| v == "x1").unwrap();
    let mut v = nalgebra::DVector::zeros(r.model.variables.len());
    v[i] = 1.0;
    let noise = pendkit_noise::thermal_noise(
        &r.model,
        &r.system.damping,
        &v,
        r.system.temperature,
        &[10.0],
    )
    .unwrap();
    assert_rel(noise.total[0], s, 1e-6);
    assert_printed(noise.total[0].sqrt(), 2.326369e-20, 7);
    // all of it is bending loss; the breakdown names the four fibres' bending terms
    let tags = noise.by_tag();
    let bending = tags.iter().find(|(t, _)| t == "fibre_bending").unwrap().1[0];
    assert_rel(bending, noise.total[0], 1e-9);
}

/// §2 with bending: both ends clamped; angles from the chord θ1 = −ψ, θ2 = θ − ψ,
/// ψ = (x − dθ)/l, energy N (EI/2l)[s_ii(θ1² + θ2²) + 2 s_ij θ1 θ2] added to the geometric
/// x–pitch stiffness.
fn x_pitch_with_bending(d: f64, s: f64) -> [f64; 2] {
    let (m, ip, n) = (40.0, 0.42, 4.0);
    let t = m * G / n;
    let kw = E * std::f64::consts::PI * R * R / L;
    let mut k = [
        [m * G / L, -m * G * d / L],
        [
            -m * G * d / L,
            m * G * d + m * G * d * d / L + kw * n * s * s,
        ],
    ];
    let (sii, sij) = stability(L * (t / ei()).sqrt());
    let a = [-1.0 / L, d / L]; // θ1 per (x, θ)
    let b = [-1.0 / L, 1.0 + d / L]; // θ2 per (x, θ)
    for i in 0..2 {
        for j in 0..2 {
            k[i][j] += n * ei() / L
                * (sii * (a[i] * a[j] + b[i] * b[j]) + sij * (a[i] * b[j] + b[i] * a[j]));
        }
    }
    two_dof_frequencies(k, (m, ip))
}

#[test]
fn rigid_body_pitch_with_bending() {
    let rows: [(&[&str], f64, f64, [f64; 2]); 5] = [
        (&[], 0.010, 0.005, [0.5758059, 0.6625800]),
        (&["a_fibre=0"], 0.010, 0.0, [0.5020496, 0.6538847]),
        (
            &["d_fibre=0.002", "a_fibre=0"],
            0.002,
            0.0,
            [0.2645543, 0.6449011],
        ),
        (&["d_fibre=0.002"], 0.002, 0.005, [0.4009813, 0.6450163]),
        (
            &["d_fibre=0", "a_fibre=0"],
            0.0,
            0.0,
            [0.1507503, 0.6446076],
        ),
    ];
    for (sets, d, s, printed) in rows {
        let r = run("rigid-body", sets, Stage::S2);
        let pair = labelled(&r, &["x1", "pitch1"]);
        let expected = x_pitch_with_bending(d, s);
        for k in 0..2 {
            assert_rel(pair[k], expected[k], 1e-9);
            assert_printed(pair[k], printed[k], 7);
        }
    }
}

#[test]
fn yaw_with_twist_and_flexure() {
    // §4: K = (T/l_eff) Σr² + N (G J_e + T J/A)/l; l_eff = l at stage 1A (twist only),
    // l − 2λ tanh(l/2λ) at stage 2 (both ends clamped; the bottom clamp does not tilt).
    let (n, t) = (4.0, 40.0 * G / 4.0);
    let sum_r2 = 4.0 * (0.005f64.powi(2) + 0.17f64.powi(2));
    let gj = E / (2.0 * 1.17) * std::f64::consts::PI * R.powi(4) / 2.0;
    let twist = n * (gj + t * R * R / 2.0) / L;
    let lambda = (ei() / t).sqrt();
    let l_eff = L - 2.0 * lambda * (L / (2.0 * lambda)).tanh();
    for (stage, k, printed) in [
        (Stage::S1A, t / L * sum_r2 + twist, 1.068137),
        (Stage::S2, t / l_eff * sum_r2 + twist, 1.069851),
    ] {
        let r = run("rigid-body", &[], stage);
        assert_rel(hz(&r, "yaw1", 0), (k / 0.42).sqrt() / TWO_PI, 1e-9);
        assert_printed(hz(&r, "yaw1", 0), printed, 7);
    }
}

/// Four fibres on the axis carrying 4 kg, yaw inertia 0.04 kg m^2: a disc (its other two
/// moments 0.025 kg m^2, so that it is a body: each moment at most the other two
/// together; the yaw mode does not depend on them).
const AXIAL_FOUR: [&str; 6] = [
    "a_fibre=0",
    "b_fibre=0",
    "m1=4",
    "I1x=0.025",
    "I1y=0.025",
    "I1z=0.04",
];

#[test]
fn isolated_torsion() {
    // §4: one REF fibre on the axis carrying 1 kg (T = 9.81 N), I = 0.01 kg m²:
    // K = G J/l + T (J/A)/l = 1.2921285e-4 N m/rad, f = 0.01809143 Hz. Four such fibres
    // on the axis carrying 4 kg with I = 0.04 kg m² have the same frequency.
    let r = run("rigid-body", &AXIAL_FOUR, Stage::S1A);
    let gj = E / (2.0 * 1.17) * std::f64::consts::PI * R.powi(4) / 2.0;
    let k = gj / L + 9.81 * R * R / 2.0 / L;
    assert_printed(k, 1.2921285e-4, 8);
    assert_rel(hz(&r, "yaw1", 0), (k / 0.01).sqrt() / TWO_PI, 1e-9);
    assert_printed(hz(&r, "yaw1", 0), 0.01809143, 7);
    // and stage 0A has no torsion at all: the yaw mode is neutral
    let r0 = run("rigid-body", &AXIAL_FOUR, Stage::S0A);
    assert_eq!(hz(&r0, "yaw1", 0), 0.0);
}

#[test]
fn each_stage_adds_its_own_terms() {
    // pendulum x: torsion (1A) cannot move a point mass; bending (1B) and extra stretch (2)
    // both stiffen it, and 1B + 2 together give the exact flexure stiffness.
    let f: Vec<f64> = [Stage::S0B, Stage::S1A, Stage::S1B, Stage::S2]
        .map(|s| hz(&run("pendulum", &[], s), "x1", 0))
        .to_vec();
    assert_eq!(f[0], f[1]);
    assert!(f[2] > f[1] && f[3] > f[2]);
}

#[test]
fn wire_terms_early_rescue_a_model_unstable_without_them() {
    // Break-off 4.5 mm below the centre of mass: the pitch stiffness m g d + k_w Σs² is
    // negative without the fibres' bending and positive with it (§2: bending adds about
    // N sqrt(T EI) = 0.377 N m). A small static torque (a user pre-equilibrium term,
    // −τ·pitch1 with τ = 1e-3 N m) breaks the symmetry: the stage-0A potential then has no
    // minimum near the nominal start, while with the wire terms in the equilibrium (clamps
    // aligned at the nominal start, as in the source) the body settles at a small tilt.
    let tau = 1e-3;
    let build = |early: &str| {
        let sets = vec![
            "d_fibre=-0.0045".to_string(),
            format!("wire_terms_early={early}"),
        ];
        let (mut system, _) = pendkit::Case::model("rigid-body")
            .unwrap()
            .with_sets(&sets)
            .unwrap()
            .build()
            .unwrap();
        system.extra_terms.push(pendkit_system::ExtraTerm {
            name: "torque".into(),
            energy: format!("-{tau}*pitch1").parse().unwrap(),
            tag: "torque".into(),
            phase: pendkit_system::ExtraPhase::BeforeEquilibrium,
        });
        system
    };
    let system = build("0");
    let i = system.coord("pitch1").unwrap();
    match solve_equilibrium(&system, &EquilibriumOptions::default()) {
        Err(e) => assert!(
            e.to_string().contains("pitch1") || e.to_string().contains("converge"),
            "{e}"
        ),
        // it may find a far-away minimum, but not one near the upright start
        Ok(eq) => assert!(eq.coords[i].abs() > 0.1, "{:?}", eq.coords),
    }
    for early in ["1", "2"] {
        let r = pendkit::run_stage(build(early), Stage::S2).unwrap();
        let pitch = r.assembled.equilibrium.coords[i];
        // tilt ≈ τ / K_pitch with K_pitch of order 0.1 N m/rad: a few 10 mrad at most
        assert!(pitch > 0.0 && pitch < 0.05, "early={early}: pitch {pitch}");
        r.modes.check_stable().unwrap();
    }
}

#[test]
fn without_tension_the_fibres_are_cantilevers() {
    // g = 0: no tension, u = 0, and the beam energy reduces to textbook beam bending: a
    // fibre clamped at the top and pinned at the mass resists with 3 EI/l³ (cantilever tip
    // force), clamped to the non-rotating point mass with 12 EI/l³ (guided beam). This
    // takes the stage-2 pipeline through the u → 0 series of the beam functions.
    for (sets, k_per_fibre) in [
        (&["g=0"][..], 3.0 * ei() / L.powi(3)),
        (&["g=0", "hinged_bottom=0"][..], 12.0 * ei() / L.powi(3)),
    ] {
        let r = run("pendulum", sets, Stage::S2);
        assert_rel(
            hz(&r, "x1", 0),
            (4.0 * k_per_fibre / 40.0).sqrt() / TWO_PI,
            1e-9,
        );
    }
}

/// A 40 kg point mass on one fibre of length L clamped at the top (direction `top`) and
/// hinged at the mass, with the given section, at stage 2.
fn one_fibre(
    section: pendkit_system::WireSection,
    top: pendkit_system::EndDirection,
    early: bool,
) -> pendkit::StageResult {
    use nalgebra::Vector3;
    use pendkit_model::{BodySpec, SystemBuilder};
    use pendkit_system::{EarlyWireTerms, EndDirection, Wire, WireEnd, WireTags};
    let mut b = SystemBuilder::new(G);
    b.support_parameters().unwrap();
    let support = b.body(BodySpec::new("support").pose_suffix("00")).unwrap();
    for (n, v) in [("x1", 0.0), ("y1", 0.0), ("z1", -L)] {
        b.variable(n, v).unwrap();
    }
    let bob = b
        .body(
            BodySpec::new("bob")
                .pose(["x1", "y1", "z1", "0", "0", "0"])
                .mass(40.0),
        )
        .unwrap();
    let tags = WireTags {
        stretch: "s".into(),
        bending: "b".into(),
        torsion: "t".into(),
    };
    let ends = [
        WireEnd {
            body: support,
            point: Vector3::zeros(),
            direction: top,
        },
        WireEnd {
            body: bob,
            point: Vector3::zeros(),
            direction: EndDirection::Hinged,
        },
    ];
    b.wire(Wire::from_tension(
        "fibre",
        ends,
        section,
        L,
        40.0 * G,
        tags,
    ))
    .unwrap();
    if early {
        b.early_wire_terms(EarlyWireTerms::Yes);
    }
    pendkit::run_stage(b.build().unwrap(), Stage::S2).unwrap()
}

fn silica() -> pendkit_system::WireSection {
    pendkit_system::WireSection::round(R, E, E / 2.34, 2200.0)
}

#[test]
fn oblong_section_bends_with_each_principal_moment() {
    // A ribbon-like section: EI along the principal axis (x) is 4× the round wire's, across
    // it (y) ¼ of it. Each direction follows the one-bending-point stiffness of its own EI.
    let mut section = silica();
    section.moment_1 *= 4.0;
    section.moment_2 /= 4.0;
    section.principal_axis = nalgebra::Vector3::x();
    let r = one_fibre(section, pendkit_system::EndDirection::Auto, false);
    let t = 40.0 * G;
    for (label, ei) in [("x1", 4.0 * ei()), ("y1", ei() / 4.0)] {
        assert_rel(
            hz(&r, label, 0),
            (lateral(t, ei, false) / 40.0).sqrt() / TWO_PI,
            1e-9,
        );
    }
}

#[test]
fn explicit_clamp_direction() {
    use pendkit_system::EndDirection;
    let t = 40.0 * G;
    // the natural direction given explicitly is the auto clamp: identical results
    let auto = one_fibre(silica(), EndDirection::Auto, false);
    let explicit = one_fibre(
        silica(),
        EndDirection::Explicit(nalgebra::Vector3::new(0.0, 0.0, -1.0)),
        false,
    );
    assert_eq!(hz(&auto, "x1", 0), hz(&explicit, "x1", 0));
    // a clamp tilted by α towards +x, with the wire terms in the equilibrium, pushes the
    // mass sideways until the pendulum's restoring force balances the clamp's bending
    // moment: minimising ½ (T/l) x² + ½ K_b l² (α − x/l)² gives x = α l K_b / (T/l + K_b),
    // with K_b = K₁ − T/l the bending stiffness (one bending point). The formula is the
    // small-angle limit: at α = 1e-4 rad we measured 6.7e-9 relative (geometric terms of
    // order x/l ~ 1e-7 and the equilibrium's step tolerance), so 1e-7 is asserted.
    let alpha = 1e-4f64;
    let tilted = one_fibre(
        silica(),
        EndDirection::Explicit(nalgebra::Vector3::new(alpha.sin(), 0.0, -alpha.cos())),
        true,
    );
    let x = tilted.assembled.equilibrium.coords[tilted.system.coord("x1").unwrap()];
    let kb = lateral(t, ei(), false) - t / L;
    let expected = alpha * L * kb / (t / L + kb);
    assert_rel(x, expected, 1e-7);
}
