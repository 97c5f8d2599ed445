//! `quad-aligo`'s own physics switches, each against an exact relation: per-element
//! temperatures (the fluctuation–dissipation theorem term by term), given dilution
//! factors (the bending loss rescaled by computed/given), the `tm_beam` output
//! (x3 + θ z3), and one-line errors for impossible fibres. The comparison with pygwinc is
//! in `pygwinc_quad_aligo.rs`.

use pendkit::Case;
use pendkit::noise::ThermalNoise;
use pendkit_system::Stage;
use pendkit_tests::run;

const FREQS: [f64; 4] = [10.0, 20.0, 50.0, 100.0];

fn noise(sets: &[&str], output: &str) -> ThermalNoise {
    run("quad-aligo", sets, Stage::S2)
        .noise(output, &FREQS)
        .expect("noise")
}

fn share<'a>(n: &'a ThermalNoise, tag: &str) -> &'a [f64] {
    &n.by_tag()
        .iter()
        .find(|(t, _)| t == tag)
        .unwrap_or_else(|| panic!("no tag {tag}"))
        .1
}

#[test]
fn an_element_at_its_own_temperature_scales_its_share_alone() {
    // S = Σ_terms 4 k_B T_term ε''_term z̄ᵀ P_term z / ω: halving the noise temperature of
    // the fibres' bending terms halves their share (the loss and the dynamics do not
    // change), leaves every other share as it was, and the total is the sum of the shares
    let base = noise(&[], "tm_beam");
    let cold = noise(&["damping.fibre_bending.temperature=145"], "tm_beam");
    for (k, f) in FREQS.iter().enumerate() {
        for (tag, psd) in base.by_tag() {
            let expected = if tag == "fibre_bending" {
                0.5 * psd[k]
            } else {
                psd[k]
            };
            let got = share(&cold, tag)[k];
            assert!(
                (got - expected).abs() <= 1e-12 * base.psd()[k],
                "{f} Hz {tag}: {got} vs {expected}"
            );
        }
        let sum: f64 = cold.by_tag().iter().map(|(_, p)| p[k]).sum();
        assert!((cold.psd()[k] / sum - 1.0).abs() < 1e-12);
        if *f >= 20.0 {
            // above the 9.7 Hz bounce mode the fibres' bending dominates
            assert!(cold.psd()[k] < 0.8 * base.psd()[k], "{f} Hz");
        }
    }
    // the fibres' temperature parameter also enters their thermoelastic Δ ∝ T: the
    // stretch and torsion shares (no thermoelastic part) halve exactly, bending by more
    let cold_fibres = noise(&["temp_fibre=145"], "tm_beam");
    for k in 0..FREQS.len() {
        for tag in ["fibre_stretch", "fibre_torsion"] {
            let (a, b) = (share(&cold_fibres, tag)[k], share(&base, tag)[k]);
            assert!((a - 0.5 * b).abs() <= 1e-9 * b, "{tag}: {a} vs {b}");
        }
        assert!(share(&cold_fibres, "fibre_bending")[k] < 0.5 * share(&base, "fibre_bending")[k]);
    }
}

#[test]
fn a_given_dilution_rescales_the_bending_loss() {
    // the default dilution is l/λ, λ = √(Y π r⁴/4 / T) at the necks, written out here from
    // the numbers of pygwinc's aLIGO ifo.yaml (l = 0.59 m, r = 400 µm, Y = 72 GPa,
    // T = 39.6 kg · 9.80665 m/s² / 4 along a vertical fibre); giving half of it doubles
    // the fibres' bending share of the noise and nothing else
    let tension = 39.6 * 9.80665 / 4.0;
    let lambda = (7.2e10 * std::f64::consts::PI * 400e-6f64.powi(4) / 4.0 / tension).sqrt();
    let computed = 0.59 / lambda;
    let base = noise(&[], "tm_beam");
    let given = noise(&[&format!("dilution_fibre={}", computed / 2.0)], "tm_beam");
    for k in 0..FREQS.len() {
        let (a, b) = (
            share(&given, "fibre_bending")[k],
            share(&base, "fibre_bending")[k],
        );
        assert!((a / b - 2.0).abs() < 1e-9, "{a} vs 2 x {b}");
        let (a, b) = (
            share(&given, "w2_bending")[k],
            share(&base, "w2_bending")[k],
        );
        assert!((a / b - 1.0).abs() < 1e-9);
    }
}

#[test]
fn tm_beam_is_x3_plus_theta_z3() {
    // x (x–pitch block) and z (y–z–roll block) do not couple in the symmetric quad, so the
    // PSD at x3 + θ z3 is PSD(x3) + θ² PSD(z3) exactly; θ = 3995 m / 6.3781e6 m
    let theta: f64 = 3995.0 / 6.3781e6;
    let (beam, x, z) = (noise(&[], "tm_beam"), noise(&[], "x3"), noise(&[], "z3"));
    for k in 0..FREQS.len() {
        let expected = x.psd()[k] + theta * theta * z.psd()[k];
        assert!((beam.psd()[k] / expected - 1.0).abs() < 1e-9);
    }
    // the vertical part is a few % of the PSD at 20 Hz (pygwinc's "vert" terms)
    let vertical = theta * theta * z.psd()[1] / beam.psd()[1];
    assert!(vertical > 0.01 && vertical < 0.1, "{vertical}");
}

#[test]
fn impossible_fibres_are_named() {
    for (set, needle) in [
        ("n_beads=0.5", "n_beads"),
        ("l3_neck=0.4", "fibres"),
        // refused by the parameter's declared domain before the fibres read it
        (
            "r3_neck=-1e-4",
            "parameter 'r3_neck' = -0.0001 m: outside its declared domain",
        ),
    ] {
        let case = Case::model("quad-aligo")
            .unwrap()
            .with_sets(&[set.to_string()])
            .unwrap();
        let e = case.build().unwrap_err().to_string();
        assert!(e.contains(needle), "{set}: {e}");
    }
}

#[test]
fn beads_on_tapered_fibres_follow_the_profile() {
    // the first violin mode of a tapered fibre (20 beads per fibre, each segment the slice
    // of the profile it spans) lies between those of uniform strings f = √(T/μ)/(2L): with
    // the mean density of the profile (necks included: the heaviest it can be) and with
    // the middle's density stiffened by the clamps' bending, (1 + 2λ/L) with the neck's λ
    // (the lightest and stiffest); T = 39.6 kg g/4, L = 0.59 m, ρ = 2200 kg/m³
    let pi = std::f64::consts::PI;
    let (t, l) = (39.6 * 9.80665 / 4.0, 0.59);
    let mass = 2200.0 * pi * (0.09 * 400e-6f64.powi(2) + 0.5 * 205e-6f64.powi(2));
    let lambda = (7.2e10 * pi * 400e-6f64.powi(4) / 4.0 / t).sqrt();
    let low = (t / (mass / l)).sqrt() / (2.0 * l);
    let high =
        (t / (2200.0 * pi * 205e-6f64.powi(2))).sqrt() / (2.0 * l) * (1.0 + 2.0 * lambda / l);
    let r = run("quad-aligo", &["n_beads=20"], Stage::S2);
    let violin: Vec<f64> = r
        .modes
        .modes
        .iter()
        .filter(|m| r.mode_family(m) == "violin")
        .map(|m| m.hz)
        .collect();
    let first = violin.first().copied().expect("violin modes");
    assert!(first > low && first < high, "{low} < {first} < {high} Hz");
}

#[test]
fn thermal_noise_converges_as_beads_are_added() {
    // With clamped beads the chain of segments is a beam discretisation: the noise at
    // 100 Hz converges as O(1/N²) once the segments resolve the 45 mm necks (N ≥ 13), so
    // doubling N from 40 to 80 changes it by about a quarter of the change from 20 to 40
    // (asserted below 0.4 of it: O(1/N) would give 0.5), and no more than 2 % in all
    // (hinged beads fell by 12 % from 20 to 80, the defect of issue 12).
    let asd = |n: usize| {
        let set = format!("n_beads={n}");
        run("quad-aligo", &[set.as_str()], Stage::S2)
            .noise("tm_beam", &[100.0])
            .expect("noise")
            .asd()[0]
    };
    let (a20, a40, a80) = (asd(20), asd(40), asd(80));
    assert!(
        (a80 - a40).abs() < 0.4 * (a40 - a20).abs(),
        "{a20:.6e} {a40:.6e} {a80:.6e}"
    );
    assert!((a80 / a20 - 1.0).abs() < 0.02, "{a20:.6e} {a80:.6e}");
}

#[test]
fn continuum_fibres_keep_the_low_frequency_noise_and_add_up_by_tag() {
    // With continuum fibres (docs/continuum-fibres.md) the noise at 0.1 Hz, below every
    // mode (so that no resonance magnifies a change), is the static model's but for the
    // fibres' own mass (about 1 g, 2.5e-5 of the test mass, which the static model leaves
    // out): its effect there is of order (m_f/M)(f/f₁)² ≈ 1e-6 with f₁ = 0.44 Hz, so 1e-5.
    // The correction D(f) − D_s(f) itself vanishes at f = 0 (continuum_fibre.rs, 1e-9). At
    // 100 Hz the fibres' mass lowers the noise (docs/quad-aligo.md: by 3 % in ASD against
    // pygwinc's continuum). The tags' shares add up to the total (the split of Im D by tag
    // is exact: each part depends on one multiplier), to rounding.
    let freqs = [0.1, 20.0, 100.0, 300.0];
    let result = run("quad-aligo", &[], Stage::S2);
    let static_model = result.noise("tm_beam", &freqs).expect("noise");
    let continuum = result
        .with_fibres(&pendkit::stage::Fibres::Continuum)
        .expect("continuum fibres")
        .noise("tm_beam", &freqs)
        .expect("noise");
    let (s, c) = (static_model.psd(), continuum.psd());
    assert!((c[0] / s[0] - 1.0).abs() < 1e-5, "{} vs {}", c[0], s[0]);
    assert!(
        c[2] < 0.97 * s[2] && c[2] > 0.85 * s[2],
        "{} vs {}",
        c[2],
        s[2]
    );
    for (k, f) in freqs.iter().enumerate() {
        let sum: f64 = continuum.psd_by_tag().iter().map(|(_, v)| v[k]).sum();
        assert!(
            (sum / c[k] - 1.0).abs() < 1e-9,
            "{f} Hz: shares {sum} vs {}",
            c[k]
        );
    }
}

#[test]
fn continuum_fibres_solve_alike_on_every_path() {
    // The restricted sparse solve, the full one and the dense reference (which adds the
    // continuum's terms to its dense matrices instead of the sweep's slots) agree, total
    // and per tag, to 1e-9 (the reference's own agreement with the fast path on the
    // static model is of that order: tests/physics/quad.rs).
    use pendkit::{NoiseOptions, Solver};
    let freqs = [0.1, 20.0, 505.0, 1500.0];
    let result = run("quad-aligo", &[], Stage::S2)
        .with_fibres(&pendkit::stage::Fibres::Continuum)
        .expect("continuum fibres");
    let solve = |solver| {
        let options = NoiseOptions {
            solver,
            ..Default::default()
        };
        result
            .noise_with("tm_beam", &freqs, &options)
            .expect("noise")
    };
    let fast = solve(Solver::Restricted);
    for other in [solve(Solver::Full), solve(Solver::DenseReference)] {
        for (a, b) in fast.psd().iter().zip(other.psd()) {
            assert!((a / b - 1.0).abs() < 1e-9, "{a} vs {b}");
        }
        for ((tag, a), (_, b)) in fast.psd_by_tag().iter().zip(other.psd_by_tag()) {
            for (k, (x, y)) in a.iter().zip(b).enumerate() {
                // a share is compared against the total at its frequency
                let scale = fast.psd()[k];
                assert!((x - y).abs() <= 1e-9 * scale, "{tag}: {x} vs {y}");
            }
        }
    }
}

#[test]
fn a_file_marks_its_fibres_as_continua() {
    // `continuum = true` on a wire set makes its wires continua in responses and noise by
    // default: the same numbers, bit for bit, as asking for the continuum explicitly on
    // the bundled model (the same terms of the same wires), and `Fibres::Static` gives the
    // bundled model's static numbers back. With beads the file asks for the fibres' mass
    // twice: refused at build, naming the fibre.
    use std::path::Path;
    let marked = "extends = \"quad-aligo\"\n[stages.testmass.fibres]\ncontinuum = true\n";
    let freqs = [20.0, 493.0];
    let case = Case::from_text(Path::new("marked.toml"), marked).expect("file");
    let (system, _) = case.build().expect("build");
    let from_file = pendkit::run_stage(system, Stage::S2).expect("stage");
    assert_eq!(from_file.model.frequency_terms.len(), 4);
    let by_file = from_file.noise("tm_beam", &freqs).expect("noise");
    let by_flag = run("quad-aligo", &[], Stage::S2)
        .with_fibres(&pendkit::stage::Fibres::Continuum)
        .expect("continuum")
        .noise("tm_beam", &freqs)
        .expect("noise");
    assert_eq!(by_file.psd(), by_flag.psd());
    // the same wires by name, one of them twice: each wire's term counts once
    let named = ["f1", "f2", "f3", "f4", "f2"].map(String::from).to_vec();
    let by_name = run("quad-aligo", &[], Stage::S2)
        .with_fibres(&pendkit::stage::Fibres::ContinuumNamed(named))
        .expect("named")
        .noise("tm_beam", &freqs)
        .expect("noise");
    assert_eq!(by_name.psd(), by_flag.psd());
    let unmarked = from_file
        .with_fibres(&pendkit::stage::Fibres::Static)
        .expect("static")
        .noise("tm_beam", &freqs)
        .expect("noise");
    let bundled = run("quad-aligo", &[], Stage::S2);
    assert_eq!(
        unmarked.psd(),
        bundled.noise("tm_beam", &freqs).expect("noise").psd()
    );
    let beaded = Case::from_text(Path::new("marked.toml"), marked)
        .and_then(|c| c.with_sets(&["n_beads=3".to_string()]))
        .and_then(|c| c.build().map(|_| ()))
        .expect_err("beads on a continuum");
    let message = beaded.to_string();
    assert!(
        message.contains("continuum") && message.contains("beads") && message.contains("f1"),
        "{message}"
    );
}
