//! Library entry points given sizes, indices, names and frequencies they cannot use return
//! errors (never a panic, never NaN with success), and points on float-posed bodies carry
//! the floats' motion (issue 11).

use nalgebra::{DMatrix, DVector};
use pendkit::dynamics::{DynamicsError, Input, Output, normal_modes};
use pendkit::{Case, StageResult, run_stage};
use pendkit_system::Stage;

fn quad() -> StageResult {
    let (system, _) = Case::model("quad").unwrap().build().unwrap();
    run_stage(system, Stage::S2).unwrap()
}

#[test]
fn mis_sized_inputs_to_public_functions_are_errors_not_panics_or_nan() {
    let r = quad();
    let d = &r.system.damping;
    let (nx, _, ns) = r.model.sizes;
    let good_in = Input::Displacement(DVector::from_element(ns, 1.0));
    let good_out = Output::Displacement(DVector::from_element(nx, 1.0));
    let short_in = Input::Displacement(DVector::zeros(ns + 1));
    let short_out = Output::Displacement(DVector::zeros(1));
    assert!(matches!(
        r.model.transfer(d, &short_in, &good_out, &[1.0]),
        Err(DynamicsError::Length { .. })
    ));
    assert!(matches!(
        r.model.transfer(d, &good_in, &short_out, &[1.0]),
        Err(DynamicsError::Length { .. })
    ));
    assert!(r.model.transfer(d, &good_in, &good_out, &[1.0]).is_ok());
    let nan_in = Input::Displacement(DVector::from_element(ns, f64::NAN));
    assert!(r.model.transfer(d, &nan_in, &good_out, &[1.0]).is_err());
    // frequencies outside the documented limits
    for f in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e-320, 1e300] {
        assert!(
            r.model.transfer(d, &good_in, &good_out, &[f]).is_err(),
            "{f}"
        );
    }
    // thermal noise: output of the wrong length, temperature not positive
    let v = DVector::zeros(3);
    assert!(pendkit::noise::thermal_noise(&r.model, d, &v, 290.0, &[1.0]).is_err());
    let v = DVector::from_element(nx, 1.0);
    assert!(pendkit::noise::thermal_noise(&r.model, d, &v, -1.0, &[1.0]).is_err());
    assert!(pendkit::noise::thermal_noise(&r.model, d, &v, 290.0, &[1.0]).is_ok());
    // modes of matrices that do not fit, or hold NaN
    let names: Vec<String> = vec!["a".into(), "b".into()];
    let k = DMatrix::identity(2, 2);
    assert!(normal_modes(&k, &DMatrix::identity(3, 3), &names).is_err());
    assert!(normal_modes(&k, &DMatrix::identity(2, 2), &names[..1]).is_err());
    let mut bad = k.clone();
    bad[(0, 1)] = f64::NAN;
    assert!(normal_modes(&bad, &DMatrix::identity(2, 2), &names).is_err());
    // modes below a frequency that is not one
    assert!(r.model.modes_below(d, f64::NAN).is_err());
    // values on the pattern, and the blocks an input and output couple, of the wrong size
    assert!(matches!(
        r.model.dense(&[1.0; 3]),
        Err(DynamicsError::Length { .. })
    ));
    assert!(r.model.dense(&r.model.lossless).is_ok());
    assert!(matches!(
        pendkit::dynamics::coupled_unknowns(&r.model, &short_in, &good_out),
        Err(DynamicsError::Length { .. })
    ));
    assert!(pendkit::dynamics::coupled_unknowns(&r.model, &good_in, &good_out).is_ok());
    // a damping tag's multiplier past the model's tags
    let mut sweep = pendkit::dynamics::Sweep::new(
        &r.model,
        d,
        &good_in,
        &good_out,
        pendkit::dynamics::Solver::Restricted,
    )
    .unwrap();
    sweep.at(1.0).unwrap();
    assert!(sweep.multiplier(r.model.by_tag.len()).is_none());
    assert!(sweep.multiplier(0).is_some());
    // the float elimination of a matrix of the wrong size
    let k = r.model.real_stiffness(d);
    let small = k.view((0, 0), (3, 3)).into_owned();
    assert!(pendkit::dynamics::eliminate_floats(&small, &r.assembled.layout, &r.system).is_err());
    // names that are not the model's
    assert!(r.input("nope").is_err() && r.output("nope").is_err());
    assert!(r.output("testmass@0,0/1,0,0").is_err());
    assert!(r.output("testmass@0,0,0/0,0,0").is_err());
}

#[test]
fn point_on_a_blade_tip_carries_the_tip_float_motion() {
    // Maxwell–Betti reciprocity: the displacement of coordinate z2 per unit vertical force
    // at a blade tip equals the tip's vertical displacement per unit generalised force on
    // z2. The tip is posed by a massless float, so the second one holds only if the output
    // point carries the float's motion (dropping it gives the UIM's own motion there, a
    // different number). Tolerance: rounding of two solves of the same matrices.
    let r = quad();
    let tip = "blade1l@0,0,0/0,0,1";
    let freqs = [0.01, 1.0, 10.0];
    let push_tip = r.transfer(&format!("force:{tip}"), "z2", &freqs).unwrap();
    let read_tip = r.transfer("force:z2", tip, &freqs).unwrap();
    for ((a, b), f) in push_tip.iter().zip(&read_tip).zip(freqs) {
        assert!((a - b).norm() <= 1e-9 * a.norm(), "{f} Hz: {a} vs {b}");
        assert!(a.norm() > 0.0);
    }
    // and the tip moves relative to the UIM: its own compliance exceeds the UIM point's
    let tip_self = r.transfer(&format!("force:{tip}"), tip, &[0.01]).unwrap()[0];
    let uim = "uim@0,0,0/0,0,1";
    let uim_self = r.transfer(&format!("force:{uim}"), uim, &[0.01]).unwrap()[0];
    assert!(tip_self.re > uim_self.re, "{tip_self} vs {uim_self}");
}

/// A stage-2 run of a bundled suspension file with `extra` appended to its text (named
/// signals, extra terms), written as `<tag>.toml` in the test's scratch folder (suspension
/// files are cached by path: one tag per text).
fn file_with(file: &str, extra: &str, tag: &str) -> StageResult {
    // bundled files extend others by their bundled names, so the copy works from anywhere
    let source = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(file);
    let text = std::fs::read_to_string(&source).unwrap() + extra;
    let path = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{tag}.toml"));
    std::fs::write(&path, text).unwrap();
    let (system, _) = Case::from_file(&path).unwrap().build().unwrap();
    run_stage(system, Stage::S2).unwrap()
}

/// Lab position (m) of `point` (body coordinates) on body `body` at the run's equilibrium.
fn position(r: &StageResult, body: &str, point: [f64; 3]) -> nalgebra::Vector3<f64> {
    let b = r.system.body(body).unwrap();
    r.system.bodies[b]
        .frame
        .eval(&r.assembled.equilibrium.coords)
        .point(&nalgebra::Vector3::from(point))
}

#[test]
fn named_output_on_a_blade_tip_carries_the_tip_float_motion() {
    // Independent reference: the static compliance of the blade tip's height to a vertical
    // force on the PUM (generalised force on z2), by central finite differences of two full
    // equilibria with an extra potential ∓F·z2 (the tip floats re-solved by Newton each
    // time). The model's answer: the transfer function force:z2 → the named output `tip`
    // at 1e-4 Hz, where inertia changes the response by (2π f)² m / k ≈ 1e-8 and the loss
    // angles (≤ 1e-3) change the real part by φ² ≈ 1e-6; the difference's own error is the
    // O(F²) curvature (F = 0.05 N moves things by ~1e-5 m on metre-scale geometry) and the
    // equilibrium's rounding. Tolerance 1e-4 relative covers these with margin, and is
    // far below the difference a dropped float makes (the UIM point's own motion); measured
    // agreement 4e-8.
    let outputs = "\n[outputs]\ntip = \"blade2l@0,0,0/0,0,1\"\n";
    let r = file_with("../models/ligo/quad.toml", outputs, "quad-tip");
    let h = r.transfer("force:z2", "tip", &[1e-4]).unwrap()[0];
    let free_form = r
        .transfer("force:z2", "blade2l@0,0,0/0,0,1", &[1e-4])
        .unwrap()[0];
    assert!(
        (h - free_form).norm() <= 1e-12 * h.norm(),
        "{h} vs {free_form}"
    );
    let force = 0.05;
    let pushed = |f: f64| {
        let extra = format!(
            "{outputs}\n[extra_terms.push]\nenergy = \"{}*z2\"\ntag = \"push\"\nphase = \"before\"\n",
            -f
        );
        let r = file_with(
            "../models/ligo/quad.toml",
            &extra,
            &format!("quad-tip-pushed-{f}"),
        );
        position(&r, "blade2l", [0.0; 3]).z
    };
    let reference = (pushed(force) - pushed(-force)) / (2.0 * force);
    assert!(
        (h.re - reference).abs() <= 1e-4 * reference.abs(),
        "transfer {h} vs finite difference {reference}"
    );
    // dropping the float: the UIM's motion at the tip's mounting point differs by far more
    let uim_point = r.transfer("force:z2", "uim@0,0,0/0,0,1", &[1e-4]).unwrap()[0];
    assert!((uim_point.re - reference).abs() > 1e-2 * reference.abs());
}

#[test]
fn named_points_on_the_support_carry_the_support_motion() {
    // A point on the support moves exactly as the support does: as a named output with
    // the support's own x00 as input, 1 at every frequency (exact: the parameters' part
    // passes straight through); as a named input, the pendulum mass follows it as a
    // pendulum does, x1/x00 = ω0²/(ω0² − ω²) → 1 at 0.01 Hz (f0 ≈ 0.64 Hz: 1 + 2.4e-4).
    let signals = "\n[outputs]\nframe = \"support@0,0,0/1,0,0\"\n\
                   [inputs]\ndrive = \"support@0,0,0/1,0,0\"\n";
    let r = file_with(
        "../models/basic/pendulum.toml",
        signals,
        "pendulum-support-points",
    );
    for f in [0.1, 1.0, 10.0] {
        let h = r.transfer("x00", "frame", &[f]).unwrap()[0];
        assert_eq!((h.re, h.im), (1.0, 0.0), "{f} Hz");
    }
    let h = r.transfer("drive", "x1", &[0.01]).unwrap()[0];
    assert!((h.re - 1.0).abs() < 1e-3, "{h}");
    // and the same as the free-form point
    let free = r.transfer("support@0,0,0/1,0,0", "x1", &[0.01]).unwrap()[0];
    assert!((h - free).norm() <= 1e-12, "{h} vs {free}");
}

#[test]
fn terms_given_a_short_coordinate_vector_are_errors_not_panics() {
    // every public Term entry that reads the full coordinate vector checks its length
    // once; the quad's first wire-stretch term reads coordinates far past index 3
    use pendkit_energy::{EnergyError, Reference, find_kind};
    let (system, _) = Case::model("quad").unwrap().build().unwrap();
    let x = system.start();
    let terms = find_kind("wire-stretch")
        .unwrap()
        .terms(&Reference::new(&system, &x))
        .unwrap();
    let term = &terms[0];
    let short = &x[..3];
    assert!(term.needs() > 3 && term.needs() <= x.len());
    let is_length = |e: EnergyError| matches!(e, EnergyError::Length { given: 3, .. });
    assert!(is_length(term.local(short).unwrap_err()));
    assert!(is_length(term.energy(short).unwrap_err()));
    assert!(is_length(term.derivatives(short).unwrap_err()));
    assert!(is_length(term.reference_derivatives(short).unwrap_err()));
    assert!(is_length(term.hessians(short, true).unwrap_err()));
    assert!(is_length(term.tension_off(short).err().unwrap()));
    // the full vector works
    assert!(term.energy(&x).unwrap().is_finite());
    assert_eq!(term.local(&x).unwrap().len(), term.coords.len());
}

#[test]
fn assembly_of_a_hand_built_system_with_out_of_range_ids_is_an_error() {
    // A System's fields are public, so a hand-built one can name bodies and coordinates
    // that do not exist: every assembly entry refuses it before indexing anything.
    use pendkit_assembly::{AssemblyError, Layout, assemble_at, mass_matrix, solve_equilibrium};
    use pendkit_energy::EnergyError;
    let (system, _) = Case::model("pendulum").unwrap().build().unwrap();
    let good = solve_equilibrium(&system, &Default::default()).unwrap();
    let is_index = |e: AssemblyError| matches!(e, AssemblyError::Energy(EnergyError::Index { .. }));
    // a wire end on a body past the end of the list
    let mut bad = system.clone();
    bad.wires[0].ends[1].body = bad.bodies.len();
    assert!(is_index(
        solve_equilibrium(&bad, &Default::default()).unwrap_err()
    ));
    assert!(is_index(
        assemble_at(&bad, Stage::S2, good.clone()).unwrap_err()
    ));
    // a body posed by coordinates the system does not have
    let mut bad = system.clone();
    bad.coords.truncate(1);
    assert!(is_index(
        solve_equilibrium(&bad, &Default::default()).unwrap_err()
    ));
    // an output reading a coordinate that does not exist
    let mut bad = system.clone();
    bad.outputs.push(pendkit_system::NamedSignal {
        name: "ghost".into(),
        force: false,
        terms: vec![(1.0, pendkit_system::SignalTerm::Coordinate(99))],
    });
    assert!(is_index(
        solve_equilibrium(&bad, &Default::default()).unwrap_err()
    ));
    // an equilibrium, and a mass-matrix point, of the wrong length
    let mut short = good.clone();
    short.coords.pop();
    assert!(matches!(
        assemble_at(&system, Stage::S2, short).unwrap_err(),
        AssemblyError::Length { .. }
    ));
    let layout = Layout::new(&system);
    assert!(matches!(
        mass_matrix(&system, &layout, &good.coords[1..]).unwrap_err(),
        AssemblyError::Length { .. }
    ));
    // a layout of another system
    let other = Layout::new(&Case::model("quad").unwrap().build().unwrap().0);
    assert!(mass_matrix(&system, &other, &good.coords).is_err());
    // and the real thing still works
    assert!(mass_matrix(&system, &layout, &good.coords).is_ok());
    assert!(assemble_at(&system, Stage::S2, good).is_ok());
}

#[test]
fn mass_and_inertia_ratios_past_what_doubles_resolve_are_refused_naming_the_body() {
    // MAX_INERTIA_RATIO is 1e12: the quad's heaviest masses are 39.6 kg and its largest
    // principal moment 0.4558 kg m^2 (quad.toml), so m3 = 1e-20 kg and I3x = 1e-30 kg m^2
    // are far past it, m3 = 1e-9 kg (ratio 4e10) is within it.
    let refused = |set: &str| {
        let e = Case::model("quad")
            .unwrap()
            .with_sets(&[set.to_string()])
            .and_then(|c| c.build())
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    };
    for (set, body) in [
        ("m3=1e-300", "testmass"),
        ("m3=1e-20", "testmass"),
        ("I3x=1e-30", "testmass"),
    ] {
        let e = refused(set);
        assert!(e.contains(body) && e.contains("1e12"), "{set}: {e}");
    }
    assert!(refused("m3=1e-20").contains("mass"));
    assert!(refused("I3x=1e-30").contains("moment of inertia"));
    let within = Case::model("quad")
        .unwrap()
        .with_sets(&["m3=1e-9".to_string()])
        .and_then(|c| c.build());
    assert!(within.is_ok());
}

#[test]
fn wires_stiffer_than_1e12_times_their_pendulum_stiffness_are_refused() {
    // k l / T = l0 / (l − l0) at the equilibrium: for the double pendulum's steel wires
    // (T ≈ 785 N and 392 N, E A = 2.12e11 × π (5e-4)² N) about 2e5 nominal, so E × 1e12 is
    // past the limit and E × 1e4 well within it
    use pendkit::dynamics::DynamicsError;
    let run = |set: &str| {
        let (system, _) = Case::model("double-pendulum")
            .unwrap()
            .with_sets(&[set.to_string()])
            .unwrap()
            .build()
            .unwrap();
        run_stage(system, Stage::S2)
    };
    match run("E_wire=scale(1e12)") {
        Err(pendkit::Error::Dynamics(DynamicsError::StiffWire { wire, ratio, .. })) => {
            assert!(wire.starts_with("wire"), "{wire}");
            assert!(ratio > 1e12 && ratio < 1e16, "{ratio}");
        }
        other => panic!("{:?}", other.map(|_| ())),
    }
    assert!(run("E_wire=scale(1e4)").is_ok());
}

/// The jet (to `order`) of the quad's test mass's frame (the last body with six own
/// coordinates) at the equilibrium.
fn test_mass_jet(
    r: &StageResult,
    order: pendkit::geometry::JetOrder,
) -> pendkit::geometry::FrameJet {
    let tm = r.test_mass().unwrap();
    let mut jet = pendkit::geometry::FrameJet::new();
    r.system.bodies[tm]
        .frame
        .jet(&r.assembled.equilibrium.coords, order, &mut jet)
        .unwrap();
    jet
}

#[test]
fn frame_jet_derivatives_past_the_jets_coordinates_are_errors_naming_function_and_index() {
    let r = quad();
    let jet = test_mass_jet(&r, pendkit::geometry::JetOrder::Second);
    let k = jet.vars().len();
    assert!(k >= 6, "the test mass moves in six coordinates at least");
    let a = nalgebra::Vector3::new(0.0, 0.17, 0.0);
    // the last coordinate works, one past it is an error naming function, argument, index
    assert!(jet.d_point(k - 1, &a).is_ok());
    let message = |e: pendkit::geometry::JetError| e.to_string();
    assert_eq!(
        message(jet.d_point(k, &a).unwrap_err()),
        format!("FrameJet::d_point: i = {k} is out of range, the jet has {k} coordinates")
    );
    assert!(message(jet.d_rotation(k).unwrap_err()).starts_with("FrameJet::d_rotation: i = "));
    assert!(message(jet.dd_point(k, 0, &a).unwrap_err()).starts_with("FrameJet::dd_point: i = "));
    // j = k would alias the pair (i + 1, 0) of the k × k storage: refused
    assert!(message(jet.dd_rotation(0, k).unwrap_err()).starts_with("FrameJet::dd_rotation: j = "));
    assert!(message(jet.velocity(k, &a).unwrap_err()).starts_with("FrameJet::velocity: i = "));
    assert!(
        message(jet.hyper_dual(Some(0), Some(usize::MAX)).unwrap_err())
            .starts_with("FrameJet::hyper_dual: e2 = ")
    );
    // the loop forms have one entry per coordinate, the same numbers as the indexed ones
    assert_eq!(jet.d_points(&a).len(), k);
    assert_eq!(jet.d_points(&a).last(), jet.d_point(k - 1, &a).ok());
    assert_eq!(jet.velocities(&a).last(), jet.velocity(k - 1, &a).ok());
}

#[test]
fn fast_path_helpers_given_a_frame_whose_local_indices_do_not_match_its_jet_are_errors() {
    use pendkit_energy::{Attached, FrameAt, add_curvature, add_jacobian};
    let r = quad();
    let jet = test_mass_jet(&r, pendkit::geometry::JetOrder::Second);
    let k = jet.vars().len();
    let a = nalgebra::Vector3::new(0.0, 0.17, 0.0);
    // one local index too many: the last would read a jet coordinate that does not exist
    let long: Vec<usize> = (0..=k).collect();
    let frame = FrameAt {
        jet: &jet,
        local: &long,
    };
    let mut columns = vec![nalgebra::Vector3::zeros(); k + 1];
    let e = add_jacobian(&frame, Attached::Point(&a), 1.0, &mut columns).unwrap_err();
    assert!(
        e.to_string().starts_with("add_jacobian: frame.local"),
        "{e}"
    );
    assert!(
        columns.iter().all(|c| *c == nalgebra::Vector3::zeros()),
        "nothing added"
    );
    let n = k + 1;
    let mut h = vec![0.0; n * n];
    let w = nalgebra::Vector3::new(0.0, 0.0, 1.0);
    let e = add_curvature(&frame, Attached::Direction(&a), &w, &mut h, n).unwrap_err();
    assert!(
        e.to_string().starts_with("add_curvature: frame.local"),
        "{e}"
    );
    assert!(h.iter().all(|&v| v == 0.0), "nothing added");
    // the matching frame works; a first-order jet has no curvature to add
    let local: Vec<usize> = (0..k).collect();
    let frame = FrameAt {
        jet: &jet,
        local: &local,
    };
    assert!(add_jacobian(&frame, Attached::Point(&a), 1.0, &mut columns).is_ok());
    let first = test_mass_jet(&r, pendkit::geometry::JetOrder::First);
    let frame = FrameAt {
        jet: &first,
        local: &local,
    };
    let e = add_curvature(&frame, Attached::Point(&a), &w, &mut h, n).unwrap_err();
    assert!(e.to_string().contains("no second derivatives"), "{e}");
}

#[test]
fn pattern_lookups_past_the_pattern_are_none_not_panics() {
    let r = quad();
    let p = &r.model.pattern;
    let (dim, len) = (p.dim(), p.len());
    assert!(p.get_position(len - 1).is_some());
    assert_eq!(p.get_position(len), None);
    assert_eq!(p.slot(dim, 0), None);
    assert_eq!(p.slot(0, dim), None);
    assert_eq!(p.slot(usize::MAX, 0), None);
    // every stored position is in range and finds its own slot again
    assert_eq!(p.positions().len(), len);
    for (s, (i, j)) in p.positions().enumerate() {
        assert_eq!(p.slot(i, j), Some(s));
    }
}

#[test]
fn eliminating_floats_from_a_master_matrix_of_the_wrong_size_is_an_error() {
    let r = quad();
    let n = r.model.pattern.dim();
    let e = pendkit::dynamics::eliminate_floats(
        &DMatrix::zeros(n, n - 1),
        &r.assembled.layout,
        &r.system,
    )
    .unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "eliminate_floats: p (master matrix, per side) has {} entries, expected {n}",
            n - 1
        )
    );
}

#[test]
fn tradeoff_comparisons_of_answers_that_do_not_fit_are_errors_naming_the_argument() {
    use pendkit::tradeoff::{Answer, compare, match_modes};
    let answer = |coordinates: usize, mass: usize, points: usize| Answer {
        coordinates: (0..coordinates).map(|i| format!("x{i}")).collect(),
        modes: Vec::new(),
        violin: Vec::new(),
        mass: DMatrix::identity(mass, mass),
        noise_asd: vec![1.0; points],
        transfer: None,
    };
    // a mass matrix smaller than the coordinates it is indexed by
    let e = match_modes(&answer(3, 2, 4), &answer(3, 3, 4), 10.0).unwrap_err();
    assert_eq!(
        e,
        "match_modes: reference.mass is 2 x 2, its 3 coordinates need 3 x 3"
    );
    // curves over different numbers of points: not compared by their common part
    let e = compare(&answer(3, 3, 4), &answer(3, 3, 5), 10.0).unwrap_err();
    assert_eq!(
        e,
        "compare: variant.noise_asd has 5 points, the reference's has 4"
    );
    // matching answers compare, with zero error against themselves
    let errors = compare(&answer(3, 3, 4), &answer(3, 3, 4), 10.0).unwrap();
    assert_eq!((errors.modes, errors.noise), (0.0, 0.0));
}

#[test]
fn a_beaded_fibre_with_more_beads_than_the_limit_is_an_error_not_an_overflow() {
    use pendkit::model::beads::{BeadJoints, BeadedFibre, MAX_BEADS, add_beaded_fibre, beads_mass};
    use pendkit_system::{EndDirection, WireEnd, WireSection, WireTags};
    let section: WireSection = WireSection::round(1e-4, 2e11, 8e10, 7800.0);
    let end = |body| WireEnd {
        body,
        point: nalgebra::Vector3::zeros(),
        direction: EndDirection::Auto,
    };
    let mut b = pendkit::model::SystemBuilder::new(9.81);
    let support = b.body(pendkit::model::BodySpec::new("support")).unwrap();
    let fibre = |beads| BeadedFibre {
        name: "f",
        scope: "",
        upper: end(support),
        lower: end(support),
        nominal: [
            nalgebra::Vector3::zeros(),
            nalgebra::Vector3::new(0.0, 0.0, -1.0),
        ],
        section: &section,
        length: 1.0,
        tension: 10.0,
        g: 9.81,
        beads,
        joints: BeadJoints::Clamped,
        profile: None,
        continuum: false,
    };
    let tags = WireTags {
        stretch: "stretch".into(),
        bending: "bending".into(),
        torsion: "torsion".into(),
    };
    for beads in [MAX_BEADS + 1, usize::MAX] {
        let e = add_beaded_fibre(&mut b, &fibre(beads), &tags).unwrap_err();
        assert_eq!(
            e.to_string(),
            format!("fibre 'f': add_beaded_fibre: beads is {beads}, at most {MAX_BEADS}")
        );
    }
    // the beads' mass for any count, without overflow: N/(N + 1) of the fibre's mass
    let whole = section.linear_density * 1.0;
    assert!((beads_mass(&section, None, 1.0, usize::MAX) - whole).abs() <= 1e-15 * whole);
    assert_eq!(beads_mass(&section, None, 1.0, 1), 0.5 * whole);
}

#[test]
fn mode_pairing_and_fit_jacobians_of_mismatched_sizes_are_errors_naming_the_argument() {
    use pendkit::fit::MatchedModes;
    let (i2, i3) = (DMatrix::identity(2, 2), DMatrix::identity(3, 3));
    // two modes over two coordinates against masses and shapes over three
    let e = pendkit::fit::pair_modes_by_overlap(&i2, &i2, &i2, &i3).unwrap_err();
    assert_eq!(
        e.to_string(),
        "pair_modes_by_overlap: new_mass is 3 x 3, expected over old_shapes' 2 coordinates"
    );
    let e = pendkit::fit::pair_modes_by_overlap(&i2, &i3, &i2, &i2).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("pair_modes_by_overlap: old_mass is 3 x 3")
    );
    let e =
        pendkit::fit::pair_modes_by_overlap(&i2, &i2, &DMatrix::identity(3, 2), &i2).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("pair_modes_by_overlap: new_shapes (rows) is 3 x 2")
    );
    // the same shapes pair with themselves, overlap 1 (mass-normalised columns of I)
    let pairs = pendkit::fit::pair_modes_by_overlap(&i2, &i2, &i2, &i2).unwrap();
    assert_eq!(pairs, [Some((0, 1.0)), Some((1, 1.0))]);
    // a Jacobian with one value for two free parameters, or a zero step
    let case = Case::model("toy").unwrap();
    let matched = MatchedModes {
        indices: vec![0],
        hz: vec![1.0],
        labels: vec!["q".into()],
        shapes: DMatrix::zeros(1, 1),
        mass: DMatrix::identity(1, 1),
        overlaps: vec![1.0],
    };
    let free = ["k1".to_string(), "m".to_string()];
    let e =
        pendkit::fit::mode_jacobian(&case, Stage::S2, &free, &[1.0], &matched, 1e-4).unwrap_err();
    assert_eq!(
        e.to_string(),
        "mode_jacobian: values is 1, expected one value per free parameter (2)"
    );
    let e = pendkit::fit::mode_jacobian(&case, Stage::S2, &free[..1], &[1.0], &matched, 0.0)
        .unwrap_err();
    assert!(
        e.to_string()
            .starts_with("mode_jacobian: relative_step is 0")
    );
}

#[test]
fn the_hyper_dual_fallback_refuses_frames_whose_local_indices_do_not_match_their_jets() {
    use pendkit_energy::{
        Derivatives, FrameAt, JetPoint, OffForm, Scratch, hyper_dual_over_frames,
    };
    let r = quad();
    let jet = test_mass_jet(&r, pendkit::geometry::JetOrder::Second);
    let k = jet.vars().len();
    let run = |local: &[usize]| {
        let n = k + 1;
        let (mut values, mut gradients, mut scales) = (vec![0.0; 1], vec![0.0; n], vec![0.0; n]);
        let (mut on, mut off) = (vec![0.0; n * n], vec![0.0; n * n]);
        let mut scratch = Scratch::default();
        let mut out = Derivatives {
            n,
            hessian: true,
            values: &mut values,
            gradients: &mut gradients,
            force_scales: &mut scales,
            on: &mut on,
            off: &mut off,
            off_form: OffForm::Same,
            scratch: &mut scratch,
        };
        let x = vec![0.0; n];
        let frames = [FrameAt { jet: &jet, local }];
        let at = JetPoint {
            x: &x,
            frames: &frames,
        };
        // the height of a body-fixed point: any energy over the frame will do
        let done = hyper_dual_over_frames::<1>(&at, 1, &mut out, |[f], e| {
            e[0] = f.origin[2];
        });
        (done, gradients)
    };
    // one local index per jet coordinate: computed, the gradient is ∂z/∂q of the jet
    let matching: Vec<usize> = (0..k).collect();
    let (done, gradients) = run(&matching);
    assert!(done);
    let a = nalgebra::Vector3::zeros();
    for (g, dp) in gradients.iter().zip(jet.d_points(&a)) {
        assert_eq!(*g, dp[2]);
    }
    // one local index more than the jet has: refused, nothing written
    let long: Vec<usize> = (0..=k).collect();
    let (done, gradients) = run(&long);
    assert!(!done);
    assert!(gradients.iter().all(|&g| g == 0.0));
}
