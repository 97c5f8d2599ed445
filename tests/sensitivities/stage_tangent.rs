//! The exact derivatives of a stage's equilibrium, stiffness and mass with respect to one
//! parameter (`pendkit_assembly::stage_tangent`: the model built with the parameter seeded,
//! the equilibrium's motion by the implicit function theorem, the matrices differentiated
//! along it) against fourth-order central differences of the same quantities from the
//! `f64` model rebuilt and re-solved from scratch at p₀ ± h, p₀ ± 2h (`Case::with_sets`):
//! the two share the energies, nothing of the derivative.
//!
//! Step h = 10⁻⁴ |p₀|: truncation h⁴ X⁽⁵⁾/30 ~ 10⁻¹⁶ of X; rounding ~ε|X|/h ~ 10⁻¹² of X,
//! plus the re-solved equilibria's own convergence (Newton stops at rounding-level
//! residuals, ~10⁻¹³ m). Tolerance: 10⁻⁷ of the largest entry of the difference plus 10⁻⁹
//! of the largest entry of X itself per unit relative change of p (the floor rounding
//! allows for a parameter that barely moves X).

use nalgebra::DMatrix;
use pendkit::{Case, Stage};
use pendkit_assembly::{
    Along, AssemblyOptions, Balance, Projection, ROUNDING_MARGIN, assemble_with,
    moves_beyond_rounding, stage_tangent,
};

struct Solved {
    coords: Vec<f64>,
    stiffness: DMatrix<f64>,
    mass: DMatrix<f64>,
}

/// The stage re-solved from scratch with `name = value`: equilibrium, tension-on stiffness
/// over all coordinates (global order) and mass over the variables.
fn solved(case: &Case, stage: Stage, name: &str, value: Option<f64>) -> Solved {
    let case = match value {
        Some(v) => case
            .clone()
            .with_sets(&[format!("{name}={v:e}")])
            .expect("set"),
        None => case.clone(),
    };
    let (system, _) = case.build().expect("build");
    let a = assemble_with(&system, stage, &AssemblyOptions::default(), None).expect("assemble");
    let n = system.coords.len();
    let mut k = DMatrix::zeros(n, n);
    for t in &a.terms {
        let m = t.coords.len();
        for (i, &gi) in t.coords.iter().enumerate() {
            for (j, &gj) in t.coords.iter().enumerate() {
                k[(gi, gj)] += t.on[i * m + j];
            }
        }
    }
    Solved {
        coords: a.equilibrium.coords,
        stiffness: k,
        mass: a.mass.to_dense(),
    }
}

fn difference(values: [&DMatrix<f64>; 4], h: f64) -> DMatrix<f64> {
    let [m2, m1, p1, p2] = values;
    ((p1 - m1) * 8.0 - (p2 - m2)) / (12.0 * h)
}

fn close(what: &str, exact: &DMatrix<f64>, reference: &DMatrix<f64>, nominal: &DMatrix<f64>) {
    let tol = 1e-7 * reference.amax() + 1e-9 * nominal.amax();
    let worst = (exact - reference).amax();
    assert!(
        worst <= tol,
        "{what}: exact vs re-solved differences differ by {worst:e} (tolerance {tol:e}; largest entry {:e})",
        reference.amax()
    );
}

/// The parameters `parameters` of `spec` (with the settings `sets`) at `stage`.
#[expect(
    clippy::too_many_lines,
    reason = "every comparison made for one parameter (two-step projection, rounding bound, the \
              moved equilibrium's balance, projected against full) reads the same solved stage \
              and projection, so a failing parameter is traced in one place"
)]
fn check(spec: &str, sets: &[&str], stage: Stage, parameters: &[&str]) {
    let sets: Vec<String> = sets.iter().map(|s| s.to_string()).collect();
    let case = Case::open(spec)
        .expect("case")
        .with_sets(&sets)
        .expect("sets");
    let nominal = solved(&case, stage, "", None);
    let (system, _) = case.build().expect("build");
    let a = assemble_with(&system, stage, &AssemblyOptions::default(), None).expect("assemble");
    let (_, resolved) = case.build().expect("build");
    let balance = Balance::new(&system, &a.equilibrium.coords)
        .expect("balance")
        .expect("the exact route is open");
    let n = system.coords.len();
    let w = DMatrix::from_fn(n, 3, |i, k| ((i * 7 + k * 3) % 5) as f64 - 2.0);
    let pairs = [(0, 0), (0, 1), (1, 1), (1, 2), (2, 2), (0, 2)];
    let projection = Projection::new(
        &system,
        stage,
        &a.equilibrium.coords,
        &balance,
        (&w, &pairs),
        0,
    )
    .expect("projection")
    .expect("the exact route is open");
    // the same projection in two steps, as the sensitivities take it (the motion's
    // coefficients computed beside the parameters' passes and added afterwards)
    let at_rest = Projection::at_rest(
        &system,
        stage,
        &a.equilibrium.coords,
        &balance,
        (&w, &pairs),
    )
    .expect("projection at rest");
    let motion = at_rest
        .motion(&system, &balance, 0)
        .expect("motion")
        .expect("the exact route is open");
    for &name in parameters {
        let p0 = resolved.get(name).expect("parameter");
        let h = 1e-4 * p0.abs();
        let dual = pendkit_model::build_tangent(&*case.model, &case.overrides, name)
            .unwrap_or_else(|e| panic!("{spec} {name}: no exact build: {e}"));
        let tangent = |along| {
            stage_tangent(
                &dual,
                stage,
                &a.equilibrium.coords,
                &a.layout,
                &balance,
                along,
            )
            .expect("stage tangent")
            .unwrap_or_else(|| panic!("{spec} {name}: the exact route is closed"))
        };
        let t = tangent(Along::Full);
        let at: Vec<Solved> = [-2.0, -1.0, 1.0, 2.0]
            .iter()
            .map(|k| solved(&case, stage, name, Some(p0 + k * h)))
            .collect();
        let vector = |s: &Solved| DMatrix::from_column_slice(s.coords.len(), 1, &s.coords);
        let q: Vec<DMatrix<f64>> = at.iter().map(vector).collect();
        let dq = difference([&q[0], &q[1], &q[2], &q[3]], h);
        let exact_dq = DMatrix::from_column_slice(t.equilibrium.len(), 1, &t.equilibrium);
        let what = |x: &str| format!("{spec} stage {stage} d{x}/d{name}");
        let dq_floor = DMatrix::from_element(1, 1, 1e-3 / p0.abs());
        close(&what("q*"), &exact_dq, &dq, &dq_floor);
        // an entry within its rounding bound is 0 for the re-solved differences too (to
        // their own noise, the tolerance above): the bound leaves out no coordinate the
        // equilibrium moves along
        let moved: Vec<bool> = t
            .equilibrium
            .iter()
            .zip(&t.equilibrium_rounding)
            .map(|(&d, &r)| moves_beyond_rounding(d, r))
            .collect();
        let still = DMatrix::from_fn(n, 1, |i, _| if moved[i] { 0.0 } else { dq[i] });
        close(
            &what("q* (entries within rounding)"),
            &DMatrix::zeros(n, 1),
            &still,
            &dq_floor,
        );
        let k: Vec<&DMatrix<f64>> = at.iter().map(|s| &s.stiffness).collect();
        let dk = difference([k[0], k[1], k[2], k[3]], h);
        close(
            &what("K"),
            &t.stiffness,
            &dk,
            &(&nominal.stiffness / p0.abs()),
        );
        let m: Vec<&DMatrix<f64>> = at.iter().map(|s| &s.mass).collect();
        let dm = difference([m[0], m[1], m[2], m[3]], h);
        close(&what("M"), &t.mass, &dm, &(&nominal.mass / p0.abs()));
        // the implicit function theorem's own check: the moved equilibrium is balanced,
        // a relative change of p unbalancing the forces by no more than their rounding
        // (1e-12 of their size: ε times the few terms on a coordinate, with a margin)
        let imbalance = t.residual * p0.abs();
        assert!(
            imbalance <= 1e-12 * t.forces,
            "{spec} {name}: residual {:e} N per unit, forces {:e} N",
            t.residual,
            t.forces
        );
        // the projected route (the terms whose constants move at the fixed equilibrium,
        // plus the equilibrium's motion through coefficients computed once per stage by
        // one pass per free coordinate) against the full matrix (every term rebuilt around
        // the moving equilibrium, one evaluation per entry) projected on the same
        // directions: the same derivative by two evaluations and two orders of the chain
        // rule, equal to rounding (10⁻¹⁰ of the projection's largest entry)
        let projected = tangent(Along::Projected(&projection));
        // the two steps give the same numbers as one, to the last bit: the same sums in
        // the same order
        let mut two_steps = tangent(Along::Projected(&at_rest));
        at_rest
            .add_motion(
                &motion,
                &mut two_steps.stiffness,
                &two_steps.equilibrium,
                &two_steps.equilibrium_rounding,
            )
            .expect("the projection's own motion");
        let bits = |m: &DMatrix<f64>| m.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(
            bits(&two_steps.stiffness),
            bits(&projected.stiffness),
            "{spec} {name}: the projection at rest plus its motion"
        );
        let full = w.transpose() * &t.stiffness * &w;
        let worst = (&projected.stiffness - &full).amax();
        assert!(
            worst <= 1e-10 * full.amax(),
            "{spec} {name}: directional vs full dK differ by {worst:e} of {:e}",
            full.amax()
        );
        // the motion along only the coordinates this parameter moves beyond rounding: what
        // it leaves out is δqᵢ times its coefficients for entries within ROUNDING_MARGIN of
        // their rounding bound (≲ 10⁻¹³ of the whole), so the same to 10⁻¹⁰ of the largest
        // entry, as the full matrix above
        let along = at_rest
            .motion_along(&system, &balance, 0, &moved)
            .expect("motion along")
            .expect("the exact route is open");
        let mut skipped = tangent(Along::Projected(&at_rest));
        at_rest
            .add_motion(
                &along,
                &mut skipped.stiffness,
                &skipped.equilibrium,
                &skipped.equilibrium_rounding,
            )
            .expect("the motion along the coordinates it moves");
        let worst = (&skipped.stiffness - &projected.stiffness).amax();
        assert!(
            worst <= 1e-10 * full.amax(),
            "{spec} {name}: the motion along {} of {n} coordinates differs by {worst:e} of {:e}",
            moved.iter().filter(|&&m| m).count(),
            full.amax()
        );
    }
}

#[test]
fn pendulum_every_stage_hinged_and_clamped() {
    // the fibre length, the mass, the fibres' separation, radius and modulus, gravity; at
    // stage 2 the beam (bending and extra stretch) with the fibres hinged at the mass
    // (one bending point) and clamped (two)
    let parameters = ["l_fibre", "m1", "a_fibre", "r_fibre", "E_fibre", "g"];
    for stage in [Stage::S0A, Stage::S1A, Stage::S1B, Stage::S2] {
        check("pendulum", &[], stage, &parameters);
    }
    check("pendulum", &["hinged_bottom=0"], Stage::S2, &parameters);
}

#[test]
fn quad_at_stage_2() {
    // a wire length, a mass, a Young's modulus, a wire radius, an inertia, a height, two
    // wire separations and two blade tips' positions (numbers in the tips' poses, whose
    // derivatives move the points on the tips)
    let quad = ["l1", "m1", "Y1", "r1", "I1x", "d0", "su", "ln", "nn0", "d1"];
    check("quad", &[], Stage::S2, &quad);
}

#[test]
fn triple_at_stage_2() {
    // a wire length, a mass, a height, an inertia, a blade's uncoupled frequency and silica's
    // Young's modulus
    check(
        "triple",
        &[],
        Stage::S2,
        &["l1", "m2", "d0", "I1x", "ufc1", "silica_Y"],
    );
}

#[test]
#[expect(
    clippy::too_many_lines,
    reason = "a list of refused inputs, each a wrong-sized call and the check on its one-line \
              message, all on the same two solved models; read top to bottom as the list it is"
)]
fn wrong_sizes_are_errors_naming_what_and_where() {
    // inputs of the wrong size (another model's layout or balance, short vectors, a pair
    // naming a direction that does not exist) give one-line errors, never a panic
    let pendulum = Case::open("pendulum").expect("case");
    let quad = Case::open("quad").expect("case");
    let solved = |case: &Case| {
        let (system, _) = case.build().expect("build");
        let a =
            assemble_with(&system, Stage::S2, &AssemblyOptions::default(), None).expect("assemble");
        let balance = Balance::new(&system, &a.equilibrium.coords)
            .expect("balance")
            .expect("open");
        (system, a, balance)
    };
    let (_, pa, pb) = solved(&pendulum);
    let (qs, qa, qb) = solved(&quad);
    let dual = pendkit_model::build_tangent(&*quad.model, &quad.overrides, "m1").expect("dual");
    let q = &qa.equilibrium.coords;
    let err = |r: Result<Option<pendkit_assembly::StageTangent>, _>| match r {
        Err(e) => pendkit_assembly::AssemblyError::to_string(&e),
        Ok(_) => panic!("must fail"),
    };
    let e = err(stage_tangent(
        &dual,
        Stage::S2,
        &q[1..],
        &qa.layout,
        &qb,
        Along::Full,
    ));
    assert!(
        e.contains("stage_tangent") && e.contains("equilibrium"),
        "{e}"
    );
    let e = err(stage_tangent(
        &dual,
        Stage::S2,
        q,
        &pa.layout,
        &qb,
        Along::Full,
    ));
    assert!(e.contains("stage_tangent") && e.contains("layout"), "{e}");
    let e = err(stage_tangent(
        &dual,
        Stage::S2,
        q,
        &qa.layout,
        &pb,
        Along::Full,
    ));
    assert!(e.contains("balance") && !e.contains('\n'), "{e}");
    let n = qs.coords.len();
    let project = |vectors: &DMatrix<f64>, pairs: &[(usize, usize)], balance: &Balance| {
        match Projection::new(&qs, Stage::S2, q, balance, (vectors, pairs), 1) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("must fail"),
        }
    };
    let w = DMatrix::zeros(n, 2);
    let e = project(&w, &[(0, 2)], &qb);
    assert!(e.contains("Projection::new") && e.contains("pairs"), "{e}");
    let e = project(&DMatrix::zeros(n - 1, 2), &[(0, 0)], &qb);
    assert!(
        e.contains("Projection::new") && e.contains("vectors"),
        "{e}"
    );
    let e = project(&w, &[(0, 0)], &pb);
    assert!(e.contains("balance") && !e.contains('\n'), "{e}");
    // a projection of another stage (or model) is refused by stage_tangent
    let other_stage = Projection::new(&qs, Stage::S1A, q, &qb, (&w, &[(0, 0)]), 1)
        .expect("projection")
        .expect("open");
    let e = err(stage_tangent(
        &dual,
        Stage::S2,
        q,
        &qa.layout,
        &qb,
        Along::Projected(&other_stage),
    ));
    assert!(e.contains("projection") && !e.contains('\n'), "{e}");
    // a motion belongs to the projection it was computed for, and its inputs must fit it
    let at_rest =
        |stage| Projection::at_rest(&qs, stage, q, &qb, (&w, &[(0, 0), (0, 1)])).expect("at rest");
    let (one, other) = (at_rest(Stage::S2), at_rest(Stage::S2));
    let motion = one.motion(&qs, &qb, 1).expect("motion").expect("open");
    let zeros = vec![0.0; n];
    let add_with =
        |projection: &Projection,
         motion: &pendkit_assembly::Motion,
         stiffness: &mut DMatrix<f64>,
         delta: &[f64],
         rounding: &[f64]| match projection.add_motion(motion, stiffness, delta, rounding) {
            Err(e) => e.to_string(),
            Ok(()) => panic!("must fail"),
        };
    let add = |projection: &Projection, stiffness: &mut DMatrix<f64>, delta: &[f64]| {
        add_with(projection, &motion, stiffness, delta, &zeros)
    };
    let e = add(&other, &mut DMatrix::zeros(2, 2), &zeros);
    assert!(e.contains("another projection") && !e.contains('\n'), "{e}");
    let e = add(&one, &mut DMatrix::zeros(2, 2), &vec![0.0; n - 1]);
    assert!(
        e.contains("Projection::add_motion") && e.contains("delta"),
        "{e}"
    );
    let e = add_with(
        &one,
        &motion,
        &mut DMatrix::zeros(2, 2),
        &zeros,
        &zeros[1..],
    );
    assert!(
        e.contains("Projection::add_motion") && e.contains("rounding"),
        "{e}"
    );
    let e = add(&one, &mut DMatrix::zeros(3, 2), &zeros);
    assert!(e.contains("stiffness (rows)"), "{e}");
    assert!(
        one.add_motion(&motion, &mut DMatrix::zeros(2, 2), &zeros, &zeros)
            .is_ok()
    );
    // a motion that left out a coordinate refuses a δq that moves along it beyond its
    // rounding bound, naming it, and takes one that moves within it
    let z0 = qs.coords.iter().position(|c| c.name == "z0").expect("z0");
    let mut moved = vec![true; n];
    moved[z0] = false;
    let without_z0 = one
        .motion_along(&qs, &qb, 1, &moved)
        .expect("motion along")
        .expect("open");
    let refused_without_z0 = |delta: &[f64], rounding: &[f64]| {
        add_with(
            &one,
            &without_z0,
            &mut DMatrix::zeros(2, 2),
            delta,
            rounding,
        )
    };
    let mut delta = zeros.clone();
    delta[z0] = 1e-3;
    let mut rounding = zeros.clone();
    let e = refused_without_z0(&delta, &rounding);
    assert!(
        e.contains("'z0'") && e.contains("left out") && !e.contains('\n'),
        "{e}"
    );
    rounding[z0] = 1e-3 / ROUNDING_MARGIN;
    assert!(
        one.add_motion(&without_z0, &mut DMatrix::zeros(2, 2), &delta, &rounding)
            .is_ok()
    );
    delta[z0] = f64::NAN;
    let e = refused_without_z0(&delta, &rounding);
    assert!(e.contains("'z0'"), "{e}");
    match one.motion_along(&qs, &qb, 1, &moved[1..]) {
        Err(e) => assert!(e.to_string().contains("moved"), "{e}"),
        Ok(_) => panic!("must fail"),
    }
    match other.with_motion(motion) {
        Err(e) => assert!(e.to_string().contains("another projection"), "{e}"),
        Ok(_) => panic!("must fail"),
    }
    assert!(Balance::new(&qs, &q[1..]).is_err());
    // a NaN anywhere in the inputs is a one-line error naming the argument and the entry,
    // never NaN derivatives
    let mut nan_q = q.clone();
    nan_q[3] = f64::NAN;
    let e = err(stage_tangent(
        &dual,
        Stage::S2,
        &nan_q,
        &qa.layout,
        &qb,
        Along::Full,
    ));
    assert!(e.contains("equilibrium entry 3 is not finite"), "{e}");
    let e = match Balance::new(&qs, &nan_q) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("must fail"),
    };
    assert!(
        e.contains("Balance::new") && e.contains("not finite"),
        "{e}"
    );
    let mut nan_w = DMatrix::zeros(n, 2);
    nan_w[(1, 1)] = f64::INFINITY;
    let e = project(&nan_w, &[(0, 1)], &qb);
    assert!(e.contains("vectors") && e.contains("not finite"), "{e}");
}

/// The equilibrium of `system` at stage 2, as dual numbers with no derivative.
fn stage_2_at_rest(system: &pendkit_system::System) -> Vec<num_dual::Dual64> {
    let a = assemble_with(system, Stage::S2, &AssemblyOptions::default(), None)
        .unwrap_or_else(|e| panic!("assemble: {e}"));
    a.equilibrium
        .coords
        .iter()
        .map(|&v| num_dual::Dual64::from_re(v))
        .collect()
}

/// Every term of every kind up to stage 2, built around `reference`.
fn tangent_terms_to_stage_2(
    reference: &pendkit_energy::Reference<num_dual::Dual64>,
) -> Vec<pendkit_energy::TangentTerm> {
    let shared = pendkit_energy::SharedBodies::new();
    let mut terms = Vec::new();
    for kind in pendkit_energy::registry() {
        if reference
            .system
            .element_stage(kind.kind(), kind.stage())
            .is_some_and(|s| s <= Stage::S2)
        {
            terms.extend(
                kind.tangent_terms(reference, &shared)
                    .expect("terms")
                    .expect("every bundled kind has tangent terms"),
            );
        }
    }
    terms
}

/// The equilibrium of `case` at stage 2 as dual numbers with no derivative, and every term
/// of every kind up to stage 2 of the model built with `name` seeded, built around it.
fn dual_terms_at_rest(
    case: &Case,
    name: &str,
) -> (
    pendkit_system::System<num_dual::Dual64>,
    Vec<num_dual::Dual64>,
    Vec<pendkit_energy::TangentTerm>,
) {
    let (system, _) = case.build().expect("build");
    let at_rest = stage_2_at_rest(&system);
    let dual = pendkit_model::build_tangent(&*case.model, &case.overrides, name)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    let terms = tangent_terms_to_stage_2(&pendkit_energy::Reference::new(&dual, &at_rest));
    (dual, at_rest, terms)
}

#[test]
fn a_gradient_from_frames_shared_by_all_terms_is_the_terms_own() {
    // each parameter's ∂g/∂p reads the bodies' frames the balance evaluated once at the
    // equilibrium of the nominal model (`GradientFrames`), instead of each term evaluating
    // its own, and so do the balance's checks along two directions: sound only if the
    // numbers are the same, bit for bit (the same arithmetic on the same numbers), for
    // every term of every kind at stage 2 of a model built with a parameter seeded, the
    // frames taken from the f64 model without the seed.
    use pendkit_energy::GradientFrames;
    let cases: [(&str, &[&str]); 3] = [
        ("pendulum", &["m1", "l_fibre"]),
        ("quad", &["m3", "l3", "nn0", "Y2"]),
        ("triple", &["m3", "d0"]),
    ];
    let mut compared = 0;
    for (model, parameters) in cases {
        let case = Case::open(model).expect("case");
        let (nominal, _) = case.build().expect("build");
        for &name in parameters {
            let (_, at_rest, terms) = dual_terms_at_rest(&case, name);
            let frames = GradientFrames::new(&nominal, &at_rest).expect("frames");
            assert!(frames.are_at(&at_rest) && !frames.are_at(&at_rest[1..]));
            assert!(frames.have_bodies_of(&nominal));
            // and at the equilibrium moved along a direction (the balance's check of H z)
            let along: Vec<num_dual::Dual64> = at_rest
                .iter()
                .enumerate()
                .map(|(i, v)| num_dual::Dual64::new(v.re, 0.1 + 0.01 * i as f64))
                .collect();
            let frames_along = GradientFrames::new(&nominal, &along).expect("frames");
            assert!(!frames_along.are_at(&at_rest));
            for term in &terms {
                let bits = |d: &pendkit_energy::TangentDerivatives| -> Vec<u64> {
                    std::iter::once(&d.value)
                        .chain(&d.gradient)
                        .flat_map(|v| [v.re.to_bits(), v.eps.to_bits()])
                        .collect()
                };
                for (x, frames) in [(&at_rest, &frames), (&along, &frames_along)] {
                    let own = term.gradient(x).expect("gradient");
                    let shared = term.gradient_from(frames).expect("gradient_from");
                    assert_eq!(
                        bits(&own),
                        bits(&shared),
                        "{model} {name}: '{}'",
                        term.label
                    );
                }
                compared += 1;
            }
        }
    }
    assert!(compared > 100, "{compared} terms compared");

    // frames at too short a configuration, or of a model with fewer bodies, are errors
    let case = Case::open("quad").expect("case");
    let (nominal, _) = case.build().expect("build");
    let (_, at_rest, terms) = dual_terms_at_rest(&case, "m3");
    let e = GradientFrames::new(&nominal, &at_rest[..3])
        .unwrap_err()
        .to_string();
    assert!(e.contains("x") && e.contains("3"), "{e}");
    let pendulum = Case::open("pendulum")
        .expect("case")
        .build()
        .expect("build")
        .0;
    let zeros = vec![num_dual::Dual64::from_re(0.0); pendulum.coords.len()];
    let short = GradientFrames::new(&pendulum, &zeros).expect("frames");
    assert!(!short.have_bodies_of(&nominal));
    let errors: Vec<String> = terms
        .iter()
        .filter_map(|t| t.gradient_from(&short).err())
        .map(|e| e.to_string())
        .collect();
    assert!(
        !errors.is_empty(),
        "no term of the quad refused the pendulum's frames"
    );
    for e in &errors {
        assert!(
            e.contains("x_global") || e.contains("gradient frames"),
            "{e}"
        );
    }
}

#[test]
fn terms_built_on_another_builds_local_frames_are_the_same_terms() {
    // each parameter's model builds its terms on the local frames of the balance's build
    // (`SharedBodies::with_frames`) instead of making them again: sound only if the terms
    // are the same (labels, coordinates, gradient bit for bit) and take the frames given.
    use pendkit_energy::{Reference, SharedBodies};
    let case = Case::open("quad").expect("case");
    let (nominal, _) = case.build().expect("build");
    let lifted = nominal.map_scalars(num_dual::Dual64::from_re);
    let at_rest = stage_2_at_rest(&nominal);
    let first = tangent_terms_to_stage_2(&Reference::new(&lifted, &at_rest));
    let given: Vec<_> = first.iter().map(|t| t.local_frames().clone()).collect();
    for name in ["m3", "l1", "nn0"] {
        let dual = pendkit_model::build_tangent(&*case.model, &case.overrides, name)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let reference = Reference::new(&dual, &at_rest);
        let fresh = tangent_terms_to_stage_2(&reference);
        let shared = SharedBodies::with_frames(given.iter().cloned());
        let mut seeded = Vec::new();
        for kind in pendkit_energy::registry() {
            if dual
                .element_stage(kind.kind(), kind.stage())
                .is_some_and(|s| s <= Stage::S2)
            {
                seeded.extend(kind.tangent_terms(&reference, &shared).unwrap().unwrap());
            }
        }
        assert_eq!(fresh.len(), seeded.len(), "{name}");
        let mut taken = 0;
        for (a, b) in fresh.iter().zip(&seeded) {
            assert_eq!((&a.label, &a.coords), (&b.label, &b.coords), "{name}");
            let bits = |t: &pendkit_energy::TangentTerm| -> Vec<u64> {
                let d = t.gradient(&at_rest).expect("gradient");
                std::iter::once(&d.value)
                    .chain(&d.gradient)
                    .flat_map(|v| [v.re.to_bits(), v.eps.to_bits()])
                    .collect()
            };
            assert_eq!(bits(a), bits(b), "{name}: '{}'", a.label);
            if given
                .iter()
                .any(|g| std::sync::Arc::ptr_eq(g, b.local_frames()))
            {
                taken += 1;
            }
        }
        // not vacuous: the seeded build took the frames given rather than making its own
        assert_eq!(
            taken,
            seeded.len(),
            "{name}: {taken} of {} took them",
            seeded.len()
        );
    }
}

#[test]
fn terms_that_do_not_move_have_no_derivative_at_fixed_coordinates() {
    // the projected route evaluates, at the fixed equilibrium, only the terms that say
    // their constants move with the parameter (`TangentTerm::moves`): sound only if every
    // other term has no derivative there, every dual part of its value, gradient and
    // Hessian exactly 0 (no tolerance: the dual parts of constants that do not move are
    // exact zeros, and so is all arithmetic on them). Every term of every kind at stage 2,
    // built around the equilibrium, for parameters that each move a few terms (a mass, a
    // wire's length, radius and modulus, a blade tip's position, a blade's frequency).
    use pendkit_rotations::Constant;
    let cases: [(&str, &[&str]); 3] = [
        ("pendulum", &["m1", "l_fibre", "r_fibre", "E_fibre"]),
        (
            "quad",
            &["m3", "mn", "l3", "r1", "Y2", "nn0", "d1", "I2y", "ufc1"],
        ),
        ("triple", &["m3", "l2", "ufc1", "d0"]),
    ];
    let (mut skipped, mut kept) = (0, 0);
    for (model, parameters) in cases {
        let case = Case::open(model).expect("case");
        for &name in parameters {
            let (_, at_rest, terms) = dual_terms_at_rest(&case, name);
            for term in &terms {
                if term.moves() {
                    kept += 1;
                    continue;
                }
                skipped += 1;
                let d = term.derivatives(&at_rest).expect("derivatives");
                let moving = std::iter::once(&d.value)
                    .chain(&d.gradient)
                    .chain(&d.hessian)
                    .any(|v| v.moves());
                assert!(
                    !moving,
                    "{model} {name}: '{}' says its constants do not move, yet has a derivative",
                    term.label
                );
            }
        }
    }
    // not vacuous: most terms are skipped for each of these parameters, and some kept
    assert!(skipped > kept && kept > 0, "skipped {skipped}, kept {kept}");
}

#[test]
fn a_sum_evaluates_a_shared_body_once_and_equals_the_terms_one_by_one() {
    // TangentSum evaluates a wire's beam once for its bending and extra-stretch terms; the
    // sum must equal the two terms evaluated separately (to rounding: the same arithmetic,
    // summed in another order), and a term listed twice must count twice (a part the body
    // does not have is an error: pendkit-energy's own unit test)
    use pendkit_energy::{TangentSum, tangent_frames};
    let (dual, at_rest, terms) = dual_terms_at_rest(&Case::open("quad").expect("case"), "m3");
    let n = dual.coords.len();
    let u: Vec<f64> = (0..n).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
    let v: Vec<f64> = (0..n).map(|i| ((i * 3) % 4) as f64 - 1.5).collect();
    let along = tangent_frames(&dual, &at_rest, &u, &u).expect("frames");
    let across = tangent_frames(&dual, &at_rest, &u, &v).expect("frames");
    let one_by_one_along: f64 = terms
        .iter()
        .map(|t| t.second_along_frames(&along).expect("term").eps)
        .sum();
    let one_by_one_across: f64 = terms
        .iter()
        .map(|t| t.second_along_frames(&across).expect("term").eps)
        .sum();
    let sum = TangentSum::new(&terms);
    // the 14 beams' two parts each fold into one evaluation
    assert_eq!(sum.len(), terms.len() - 14);
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1e-300);
    let summed = sum.second_along_frames(&along).expect("sum").eps;
    assert!(
        close(summed, one_by_one_along),
        "{summed} vs {one_by_one_along}"
    );
    let summed = sum.second_along_frames(&across).expect("sum").eps;
    assert!(
        close(summed, one_by_one_across),
        "{summed} vs {one_by_one_across}"
    );
    let twice = TangentSum::new(terms.iter().chain(&terms));
    let summed = twice.second_along_frames(&along).expect("sum").eps;
    assert!(
        close(summed, 2.0 * one_by_one_along),
        "{summed} vs 2 × {one_by_one_along}"
    );
}

#[test]
fn a_pass_along_several_modes_at_once_is_the_passes_along_each() {
    // The projection and each parameter's column evaluate the terms along LANES modes at
    // once (`SecondLanes`: the value shared, one lane per direction). Each lane must be the
    // one-direction pass along its own direction (`HyperDual<Dual64>` with u = v, an
    // independent scalar of num-dual's), term by term and summed, to rounding (the same
    // second derivative by other products: 1e-12 of the term's size is a thousand times the
    // rounding seen); the
    // lanes past the directions given are 0, and more directions than lanes is an error.
    // Every kind of the quad and of quad-full (6 × 6 blade springs), with a parameter
    // whose derivative moves terms of each kind (the PUM mass: gravity, wire stretch,
    // bending through the tension, torsion), and the coordinates' own motion.
    use num_dual::Dual64;
    use pendkit_energy::{TangentSum, tangent_frames, tangent_frames_along_lanes};
    use pendkit_rotations::LANES;
    for (model, parameter) in [("quad", "m2"), ("quad-full", "m2"), ("quad", "l3")] {
        let (dual, at_rest, terms) =
            dual_terms_at_rest(&Case::open(model).expect("case"), parameter);
        let n = dual.coords.len();
        // directions with every coordinate moving, different in each lane
        let directions: Vec<Vec<f64>> = (0..LANES + 1)
            .map(|k| {
                (0..n)
                    .map(|i| (((i + 3) * (k + 5)) % 7) as f64 * 0.3 - 0.8)
                    .collect()
            })
            .collect();
        let refs: Vec<&[f64]> = directions.iter().map(|d| d.as_slice()).collect();
        let e = tangent_frames_along_lanes(&dual, &at_rest, &refs).expect_err("too many");
        assert!(e.to_string().contains("directions"), "{e}");
        for count in [LANES, 3] {
            let lanes = tangent_frames_along_lanes(&dual, &at_rest, &refs[..count]).expect("lanes");
            let close = |a: Dual64, b: Dual64, what: &str| {
                for (x, y) in [(a.re, b.re), (a.eps, b.eps)] {
                    assert!(
                        (x - y).abs() <= 1e-12 * y.abs().max(1e-300),
                        "{model} {parameter} {what}: lanes {x} against one direction {y}"
                    );
                }
            };
            let sum = TangentSum::new(&terms);
            let summed = sum.second_along_frames_lanes(&lanes).expect("sum");
            for (k, direction) in refs.iter().enumerate().take(LANES) {
                if k >= count {
                    assert_eq!(
                        summed[k],
                        Dual64::from_re(0.0),
                        "lane {k} past the directions"
                    );
                    continue;
                }
                let along = tangent_frames(&dual, &at_rest, direction, direction).expect("frames");
                for term in &terms {
                    let one = term.second_along_frames(&along).expect("term");
                    let lane = term.second_along_frames_lanes(&lanes).expect("term")[k];
                    close(lane, one, &format!("{} lane {k}", term.label));
                }
                let one = sum.second_along_frames(&along).expect("sum");
                close(summed[k], one, &format!("sum lane {k}"));
            }
        }
        // the coordinates' own motion (the projection's coefficients): a coordinate with a
        // derivative moves every lane's second derivative as it moves the one direction's
        let mut moving = at_rest.clone();
        moving[n / 2].eps = 1.0;
        let lanes = tangent_frames_along_lanes(&dual, &moving, &refs[..LANES]).expect("lanes");
        let summed = TangentSum::new(&terms)
            .second_along_frames_lanes(&lanes)
            .expect("sum");
        for (k, direction) in refs.iter().enumerate().take(LANES) {
            let along = tangent_frames(&dual, &moving, direction, direction).expect("frames");
            let one = TangentSum::new(&terms)
                .second_along_frames(&along)
                .expect("sum");
            assert!(
                (summed[k].eps - one.eps).abs() <= 1e-12 * one.eps.abs().max(1e-300),
                "{model}: coordinate motion, lane {k}: {} against {}",
                summed[k].eps,
                one.eps
            );
        }
    }
}

#[test]
fn a_moving_only_reference_leaves_out_no_term_that_moves() {
    // The projected route builds each parameter's terms around a `Reference::moving_only`,
    // which lets a kind leave out the terms of an element nothing of which moves, and keeps
    // the terms that say their constants move (`TangentTerm::moves`). Sound only if no
    // moving term is left out: for every bundled model and every parameter its dual build
    // carries, every kind's terms up to stage 2, built around the equilibrium both ways,
    // must give the same moving terms (by label, in order) — an exact comparison, nothing
    // numerical. Likewise the projection's builds, around the equilibrium moved along one
    // coordinate with the model's numbers fixed: the same terms that move or are on the
    // coordinate. Not vacuous: the moving-only builds leave out most terms.
    use pendkit_energy::{Reference, TangentTerm};
    let (mut built_all, mut built_moving_only, mut compared) = (0, 0, 0);
    let terms_of = tangent_terms_to_stage_2;
    let labels = |terms: &[TangentTerm], keep: &dyn Fn(&TangentTerm) -> bool| -> Vec<String> {
        terms
            .iter()
            .filter(|t| keep(t))
            .map(|t| t.label.clone())
            .collect()
    };
    for model in pendkit::catalogue::models() {
        let model = &*model;
        let (system, resolved) =
            pendkit_model::build_with(model, &Default::default()).expect("build");
        let at_rest = stage_2_at_rest(&system);
        let lifted = system.map_scalars(num_dual::Dual64::from_re);
        for i in 0..at_rest.len() {
            let mut moved = at_rest.clone();
            moved[i].eps = 1.0;
            let on_it = |t: &TangentTerm| t.moves() || t.coords.contains(&i);
            let all = terms_of(&Reference::new(&lifted, &moved));
            let kept = terms_of(&Reference::moving_only(&lifted, &moved));
            assert_eq!(
                labels(&kept, &on_it),
                labels(&all, &on_it),
                "{} along {}",
                model.name(),
                system.coords[i].name
            );
            built_all += all.len();
            built_moving_only += kept.len();
        }
        let names: Vec<String> = resolved.iter().map(|(n, _)| n.to_string()).collect();
        for chunk in names.chunks(pendkit_params::TANGENT_CHUNK) {
            let chunk: Vec<&str> = chunk.iter().map(String::as_str).collect();
            let Ok(built) = pendkit_model::build_tangent_chunk(model, &Default::default(), &chunk)
            else {
                continue;
            };
            for (k, name) in chunk.iter().enumerate() {
                let Ok(dual) = built.direction(k) else {
                    continue;
                };
                let all = terms_of(&Reference::new(&dual, &at_rest));
                let kept = terms_of(&Reference::moving_only(&dual, &at_rest));
                let moves = |t: &TangentTerm| t.moves();
                assert_eq!(
                    labels(&kept, &moves),
                    labels(&all, &moves),
                    "{} {name}",
                    model.name()
                );
                built_all += all.len();
                built_moving_only += kept.len();
                compared += 1;
            }
        }
    }
    assert!(
        compared > 500 && 2 * built_moving_only < built_all,
        "{compared} parameters: {built_moving_only} terms built moving-only, {built_all} in all"
    );
}

#[test]
fn the_symmetric_quads_lateral_motion_is_rounding() {
    // the quad is symmetric about its longitudinal (x–z) plane and every one of its
    // parameters acts on both sides alike, so by symmetry the equilibrium does not move
    // along y, roll or yaw with any of them (exactly 0; the computed entries are the
    // rounding of wires' lateral forces that cancel). The rounding bound must say so for
    // every parameter, and must not swallow a motion: the vertical entries that do move
    // are many orders beyond it.
    let case = Case::open("quad").expect("case");
    let (system, resolved) = case.build().expect("build");
    let a = assemble_with(&system, Stage::S2, &AssemblyOptions::default(), None).expect("assemble");
    let q = &a.equilibrium.coords;
    let balance = Balance::new(&system, q).expect("balance").expect("open");
    let n = system.coords.len();
    let w = DMatrix::from_element(n, 1, 1.0);
    let projection =
        Projection::at_rest(&system, Stage::S2, q, &balance, (&w, &[(0, 0)])).expect("at rest");
    let lateral = |name: &str| ["y", "roll", "yaw"].iter().any(|p| name.starts_with(p));
    let mut checked = 0;
    let mut moves_far = std::collections::BTreeSet::new();
    for (name, _) in resolved.iter() {
        // a parameter without a dual build (a count, a switch) has no exact route
        let Ok(dual) = pendkit_model::build_tangent(&*case.model, &case.overrides, name) else {
            continue;
        };
        let Some(t) = stage_tangent(
            &dual,
            Stage::S2,
            q,
            &a.layout,
            &balance,
            Along::Projected(&projection),
        )
        .expect("stage tangent") else {
            continue;
        };
        checked += 1;
        for (i, c) in system.coords.iter().enumerate() {
            let (d, r) = (t.equilibrium[i], t.equilibrium_rounding[i]);
            if lateral(&c.name) {
                assert!(
                    !moves_beyond_rounding(d, r),
                    "quad d{}/d{name}: {d:e} beyond its rounding bound {r:e}",
                    c.name
                );
            }
            if d.abs() > 1e8 * r && r > 0.0 {
                moves_far.insert(c.name.clone());
            }
        }
    }
    assert!(
        checked > 60,
        "only {checked} quad parameters took the exact route"
    );
    // some parameter (a length, a height) moves every stage's longitudinal coordinates
    // 10⁸ times their bound at least (measured 10¹²: the bound is ε times the solve's
    // condition)
    for body in 0..4 {
        for axis in ["x", "z", "pitch"] {
            let c = format!("{axis}{body}");
            assert!(
                moves_far.contains(&c),
                "no quad parameter moves {c} beyond 1e8 times its bound"
            );
        }
    }
}
