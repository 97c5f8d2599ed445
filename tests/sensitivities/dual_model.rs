//! The model numbers generic over the scalar (steps 1 and 2 of docs/exact-sensitivities.md):
//! a model built by `SystemBuilder<Dual64>` carries the exact derivatives of every number
//! the builder derives (a wire's stiffness and unstretched length, a round section's
//! constants) with respect to the seeded input, checked against closed forms; its real part
//! is the `f64` model; `System::map_scalars` visits every generic field (checked against a
//! field list written out here, not the visitor's own); and every bundled model built from
//! its suspension file with one parameter seeded (`pendkit_model::build_tangent`) agrees
//! with differences of its `f64` builds (as stored, and as the energies see them: points
//! in the lab), or says why it has no exact derivative.

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use num_dual::Dual64;
use pendkit_model::{BodySpec, SystemBuilder};
use pendkit_rotations::Constant;
use pendkit_system::{
    EndDirection, PluginElement, Real, SpringEnd, System, Wire, WireEnd, WireSection, WireTags,
};

const G: f64 = 9.81;

fn tags() -> WireTags {
    WireTags {
        stretch: "s".into(),
        bending: "b".into(),
        torsion: "t".into(),
    }
}

/// A point mass `m` (kg) on one round steel wire of length `l` (m) and radius `r` (m),
/// carrying the mass's weight, with a spring and a plug-in element so that every kind of
/// model number is present. Every number is of type `S`, built from the three inputs.
fn pendulum<S: Real>(m: S, l: S, r: S) -> System<S> {
    let c = |x: f64| S::from(x);
    let mut b = SystemBuilder::<S>::new(c(G));
    b.support_parameters().unwrap();
    let support = b.body(BodySpec::new("support").pose_suffix("00")).unwrap();
    for (n, v) in [("x1", 0.0), ("y1", 0.0), ("z1", -1.0)] {
        b.variable(n, v).unwrap();
    }
    let bob = b
        .body(
            BodySpec::new("bob")
                .pose(["x1", "y1", "z1", "0", "0", "0"])
                .mass(m)
                .inertia_diag(m * 0.1, m * 0.2, m * 0.3)
                .centre_of_mass(Vector3::new(c(0.0), c(0.0), r)),
        )
        .unwrap();
    let end = |body, direction| WireEnd {
        body,
        point: Vector3::new(c(0.0), r, c(0.0)),
        direction,
    };
    let section = WireSection::round(r, c(200e9), c(80e9), c(7800.0));
    b.wire(Wire::from_tension(
        "wire",
        [
            end(
                support,
                EndDirection::Explicit(Vector3::new(c(0.0), c(0.0), -l)),
            ),
            end(bob, EndDirection::Hinged),
        ],
        section,
        l,
        m * G,
        tags(),
    ))
    .unwrap();
    let spring_end = |body| SpringEnd {
        body,
        point: Vector3::new(r, c(0.0), c(0.0)),
        angles: [c(0.0), r, c(0.0)],
    };
    b.spring(
        "spring",
        [spring_end(support), spring_end(bob)],
        Matrix6::from_diagonal(&Vector6::from_element(m * 10.0)),
        Vector6::from_element(l),
        "k",
    )
    .unwrap();
    b.plugin_element(PluginElement {
        kind: "none".into(),
        name: "extra".into(),
        bodies: vec![bob],
        points: vec![Vector3::new(l, l, l)],
        values: [("a".to_string(), m), ("b".to_string(), l)].into(),
        tag: "e".into(),
    })
    .unwrap();
    b.build().unwrap()
}

const M: f64 = 10.0;
const L: f64 = 1.0;
const R: f64 = 0.5e-3;

#[test]
fn derived_numbers_carry_their_closed_form_derivatives() {
    // k = E A / l and l0 = l − m g / k with A = π r²: closed-form derivatives
    // (∂k/∂l = −k/l, ∂l0/∂l = 1 − m g/(E A), ∂l0/∂m = −g/k, ∂k/∂r = 2k/r,
    // ∂l0/∂r = 2 m g/(k r)); to 1e-14 relative, the rounding of a few operations
    let e = 200e9;
    let area = std::f64::consts::PI * R * R;
    let k = e * area / L;
    let weight = M * G;
    let close = |got: f64, want: f64, what: &str| {
        assert!(
            (got - want).abs() <= 1e-14 * want.abs(),
            "{what}: {got} vs {want}"
        );
    };
    let by_l = pendulum(Dual64::from(M), Dual64::new(L, 1.0), Dual64::from(R));
    close(by_l.wires[0].stiffness.eps, -k / L, "dk/dl");
    close(
        by_l.wires[0].unstretched_length.eps,
        1.0 - weight / (e * area),
        "dl0/dl",
    );
    let by_m = pendulum(Dual64::new(M, 1.0), Dual64::from(L), Dual64::from(R));
    close(by_m.wires[0].unstretched_length.eps, -G / k, "dl0/dm");
    close(by_m.bodies[1].mass.eps, 1.0, "dm/dm");
    close(by_m.bodies[1].inertia[(2, 2)].eps, 0.3, "dIzz/dm");
    let by_r = pendulum(Dual64::from(M), Dual64::from(L), Dual64::new(R, 1.0));
    let w = &by_r.wires[0];
    close(w.stiffness.eps, 2.0 * k / R, "dk/dr");
    close(w.unstretched_length.eps, 2.0 * weight / (k * R), "dl0/dr");
    close(w.section.area.eps, 2.0 * std::f64::consts::PI * R, "dA/dr");
    close(
        w.section.moment_1.eps,
        std::f64::consts::PI * R.powi(3),
        "dI/dr",
    );
}

#[test]
fn the_real_part_is_the_f64_model_and_a_step_along_the_tangent_is_first_order() {
    let f64_model = pendulum(M, L, R);
    let dual = pendulum(Dual64::from(M), Dual64::new(L, 1.0), Dual64::from(R));
    // the same operations on the real parts: equal bit for bit
    let real: Vec<u64> = dual.value().scalars().iter().map(|x| x.to_bits()).collect();
    let plain: Vec<u64> = f64_model.scalars().iter().map(|x| x.to_bits()).collect();
    assert_eq!(real, plain);
    // moving along the exact tangent by h agrees with the model rebuilt at l + h to O(h²):
    // the most curved number is k = E A / l, whose relative second-order error is
    // (h/l)² = 1e-8 at h = 1e-4 l (l0 and the points are linear in l)
    let h = 1e-4;
    let rebuilt = pendulum(M, L + h, R).scalars();
    let stepped = dual.stepped(h).scalars();
    assert_eq!(rebuilt.len(), stepped.len());
    for (i, (a, b)) in rebuilt.iter().zip(&stepped).enumerate() {
        assert!(
            (a - b).abs() <= 2e-8 * a.abs().max(1.0),
            "scalar {i}: {a} vs {b}"
        );
    }
    assert_eq!(dual.tangent().len(), plain.len());
}

#[test]
fn map_scalars_visits_every_generic_field() {
    // every generic number of the model set to 0 by the visitor: each field listed here
    // (from the types, not from the visitor) must then be 0; a field the visitor forgot
    // would keep its non-zero value
    let zeroed = pendulum(M, L, R).map_scalars(|_| 0.0);
    let zero3 = |v: &Vector3<f64>| v.iter().all(|&x| x == 0.0);
    assert_eq!(zeroed.gravity, 0.0);
    for b in &zeroed.bodies {
        assert!(b.mass == 0.0 && b.inertia == Matrix3::zeros() && zero3(&b.centre_of_mass));
    }
    for w in &zeroed.wires {
        for e in &w.ends {
            assert!(zero3(&e.point));
            if let EndDirection::Explicit(d) = &e.direction {
                assert!(zero3(d));
            }
        }
        let s = &w.section;
        assert_eq!(w.stiffness, 0.0);
        assert_eq!(w.unstretched_length, 0.0);
        for x in [
            s.youngs_modulus,
            s.shear_modulus,
            s.area,
            s.moment_1,
            s.moment_2,
            s.torsion_constant,
            s.polar_moment,
            s.linear_density,
        ] {
            assert_eq!(x, 0.0);
        }
        assert!(zero3(&s.principal_axis));
    }
    for sp in &zeroed.springs {
        for e in &sp.ends {
            assert!(zero3(&e.point) && e.angles == [0.0; 3]);
        }
        assert!(sp.stiffness == Matrix6::zeros() && sp.preload == Vector6::zeros());
    }
    for p in &zeroed.plugin_elements {
        assert!(p.points.iter().all(zero3) && p.values.values().all(|&x| x == 0.0));
    }
    // and the count of visited numbers is the one the types give: gravity; a body's mass,
    // 9 inertia and 3 centre entries (two bodies); the wire's 2 × 3 end points, 3 for its
    // explicit direction, stiffness, l0, 8 section numbers and a 3-vector; the spring's
    // 2 × (3 + 3) end numbers, 36 + 6; the plug-in element's 3 + 2
    let expected = 1 + 2 * 13 + (6 + 3 + 2 + 8 + 3) + (12 + 42) + 5;
    assert_eq!(pendulum(M, L, R).scalars().len(), expected);
}

#[test]
fn zip_scalars_into_rewrites_the_numbers_map_scalars_visits_in_its_order() {
    // each number of a copy rewritten with its index in the visit: the copy's numbers,
    // listed by map_scalars (checked above to reach every generic field), must then be
    // 0, 1, 2, … — the same numbers in the same order, none left out or visited twice
    let model = pendulum(M, L, R);
    let mut copy = model.map_scalars(|x| x);
    let mut index = 0.0;
    assert!(model.zip_scalars_into(&mut copy, |_, y| {
        *y = index;
        index += 1.0;
    }));
    let visited: Vec<f64> = copy.scalars();
    let count = visited.len();
    assert_eq!(visited, (0..count).map(|k| k as f64).collect::<Vec<_>>());
    // each pair is a number and its own place: the copy rewritten from the model is the model
    assert!(model.zip_scalars_into(&mut copy, |x, y| *y = *x));
    assert_eq!(copy.scalars(), model.scalars());
    // models whose numbers differ in count or kind are refused
    let mut fewer = model.map_scalars(|x| x);
    fewer.springs.clear();
    assert!(!model.zip_scalars_into(&mut fewer, |_, _| {}));
    // the wire's top end has an explicit direction (three numbers); made automatic in the
    // copy, the two no longer have the same numbers
    assert!(matches!(
        model.wires[0].ends[0].direction,
        EndDirection::Explicit(_)
    ));
    let mut other_direction = model.map_scalars(|x| x);
    other_direction.wires[0].ends[0].direction = EndDirection::Auto;
    assert!(!model.zip_scalars_into(&mut other_direction, |_, _| {}));
}

#[test]
fn a_wire_moves_exactly_when_one_of_its_own_numbers_does() {
    // `Wire::moves` lets the kinds leave out a wire's terms for a parameter that moves none
    // of its numbers (`Reference::moving_only`): it must see every generic number of the
    // wire and nothing else. Each number of the model seeded alone, in the visitor's order
    // (gravity, the two bodies' 13 each, then the wire's 22, the count the test above
    // checks), moves the wire exactly when it is one of the wire's.
    let base = pendulum(M, L, R);
    let wire_numbers = (1 + 2 * 13)..(1 + 2 * 13 + 22);
    for k in 0..base.scalars().len() {
        let mut index = 0;
        let seeded = base.map_scalars(|x| {
            let seed = if index == k { 1.0 } else { 0.0 };
            index += 1;
            Dual64::new(x, seed)
        });
        assert_eq!(
            seeded.wires[0].moves(),
            wire_numbers.contains(&k),
            "number {k}"
        );
    }
}

/// `model` built in `f64` with `parameter` overridden by `value`.
fn f64_model(model: &dyn pendkit_model::Model, parameter: &str, value: f64) -> Option<System> {
    let mut overrides = pendkit_model::Overrides::default();
    overrides
        .parameters
        .push((parameter.to_string(), format!("{value:e}")));
    pendkit_model::build_with(model, &overrides)
        .ok()
        .map(|(system, _)| system)
}

/// What the energies see of a model, whichever way a constant enters it (a number in a
/// point, or in a pose's text: a blade tip's position on its parent is the latter in the
/// `f64` build and moves the points on the tip in the dual one): gravity, every mass,
/// inertia, section and stiffness number, clamp direction and spring angle, and the lab
/// position at the coordinates `at` of every point on a body (centres of mass, wire and
/// spring ends). Written out here, not taken from the model's visitor.
fn seen<S: Constant>(system: &System<S>, at: &[f64]) -> Vec<S> {
    let x: Vec<S> = at.iter().map(|&v| S::from(v)).collect();
    let lab = |body: usize, p: &Vector3<S>| system.bodies[body].frame.eval(&x).point(p);
    let mut out = vec![system.gravity];
    for (index, b) in system.bodies.iter().enumerate() {
        out.push(b.mass);
        out.extend(b.inertia.iter().copied());
        out.extend(lab(index, &b.centre_of_mass).iter().copied());
    }
    for w in &system.wires {
        for end in &w.ends {
            out.extend(lab(end.body, &end.point).iter().copied());
            if let EndDirection::Explicit(d) = &end.direction {
                out.extend(d.iter().copied());
            }
        }
        let c = &w.section;
        out.extend([
            w.stiffness,
            w.unstretched_length,
            c.youngs_modulus,
            c.shear_modulus,
        ]);
        out.extend([
            c.area,
            c.moment_1,
            c.moment_2,
            c.torsion_constant,
            c.polar_moment,
        ]);
        out.push(c.linear_density);
        out.extend(c.principal_axis.iter().copied());
    }
    for spring in &system.springs {
        for end in &spring.ends {
            out.extend(lab(end.body, &end.point).iter().copied());
            out.extend(end.angles);
        }
        out.extend(spring.stiffness.iter().copied());
        out.extend(spring.preload.iter().copied());
    }
    for element in &system.plugin_elements {
        out.extend(element.points.iter().flat_map(|p| p.iter().copied()));
        out.extend(element.values.values().copied());
    }
    out
}

/// Fourth-order one-sided differences of the numbers `ahead` (at p + h, ..., p + 4h, with
/// `base` at p) against the tangent `exact`: f' ≈ (−25 f₀ + 48 f₁ − 36 f₂ + 16 f₃ − 3 f₄)/12h,
/// whose rounding is about seven times the central formula's (the weights' sum 128 against
/// 18), so each to 1e-12 of its size over h.
fn check_against_forward_differences(
    what: &str,
    exact: &[f64],
    ahead: &[Vec<f64>],
    base: &[f64],
    h: f64,
) {
    for (i, d) in exact.iter().enumerate() {
        let f = |k: usize| ahead[k][i];
        let fd =
            (-25.0 * base[i] + 48.0 * f(0) - 36.0 * f(1) + 16.0 * f(2) - 3.0 * f(3)) / (12.0 * h);
        let scale = base[i].abs().max(f(3).abs()) / h;
        assert!(
            (d - fd).abs() <= 1e-12 * scale,
            "{what} (number {i}): {d} vs {fd} (value {})",
            base[i]
        );
    }
}

/// Fourth-order central differences of the numbers `at` (at p − 2h, p − h, p + h, p + 2h)
/// against the tangent `exact`, each to 1e-13 of its size over h (see the test below).
fn check_against_differences(what: &str, exact: &[f64], at: &[Vec<f64>], base: &[f64], h: f64) {
    for (i, d) in exact.iter().enumerate() {
        let fd = (8.0 * (at[2][i] - at[1][i]) - (at[3][i] - at[0][i])) / (12.0 * h);
        let scale = base[i].abs().max(at[3][i].abs()) / h;
        assert!(
            (d - fd).abs() <= 1e-13 * scale,
            "{what} (number {i}): {d} vs {fd} (value {})",
            base[i]
        );
    }
}

#[test]
fn every_bundled_model_differentiates_its_build_exactly() {
    // For every bundled model and every parameter: the dual-number build (one parameter
    // seeded) either says why it has no exact derivative, or its tangent agrees with the
    // fourth-order central difference of f64 builds at p ± h, p ± 2h (h = 1e-3 |p|, 1e-6
    // at p = 0). The difference's truncation h⁴x⁽⁵⁾/30 is ~4e-12 of x/p for a 1/p
    // dependence (the steepest the builds have: k = E A / l, T/k) and its rounding
    // ~2e-16·x/h = 2e-13·x/p, both relative to the size of the number x itself, not of its
    // derivative (l0 = l − T/k is a difference of large terms): asserted to 1e-10 of x/p
    // (1e-13 of x/h). The real parts equal the f64 build to a few roundings: the same
    // operations on the same values, except that num-dual divides by multiplying with the
    // reciprocal (one rounding more).
    //
    // The numbers are compared twice: as the model stores them (every generic field, in the
    // visitor's order), and as the energies see them (`seen`: points in the lab). The first
    // only where no pose's text moves with the parameter: a blade tip's position is a number
    // in the tip's pose in the f64 build, and a shift of the points on the tip in the dual
    // one — the same lab positions, different stored numbers.
    let mut checked = 0;
    let mut moved_poses = 0;
    let mut refused = Vec::new();
    for model in pendkit::catalogue::models() {
        let model = &*model;
        let defaults = pendkit_model::Defaults::of(model).unwrap();
        let (_, resolved) = pendkit_model::parameters_with(&defaults, &Default::default()).unwrap();
        let names: Vec<(String, f64)> = resolved.iter().map(|(n, v)| (n.to_string(), v)).collect();
        let nominal = pendkit_model::build_with(model, &Default::default())
            .unwrap()
            .0;
        let base = nominal.scalars();
        let start = nominal.start();
        let base_seen = seen(&nominal, &start);
        for (name, p0) in names {
            let dual = match pendkit_model::build_tangent(model, &Default::default(), &name) {
                Ok(d) => d,
                Err(e) => {
                    let e = e.to_string();
                    assert!(
                        e.contains("no exact derivative"),
                        "{} {name}: {e}",
                        model.name()
                    );
                    refused.push(format!("{} {name}: {e}", model.name()));
                    continue;
                }
            };
            for (i, (r, x)) in dual.value().scalars().iter().zip(&base).enumerate() {
                assert!(
                    (r - x).abs() <= 4.0 * f64::EPSILON * x.abs(),
                    "{} {name}: real part of number {i}: {r} vs {x}",
                    model.name()
                );
            }
            let h = if p0 == 0.0 { 1e-6 } else { 1e-3 * p0.abs() };
            let at: Vec<Option<System>> = [-2.0, -1.0, 1.0, 2.0]
                .iter()
                .map(|k| f64_model(model, &name, p0 + k * h))
                .collect();
            let tangent = dual.tangent();
            // a parameter on the low edge of its domain (arm-cavity's power, 0 W): the
            // f64 build refuses p − h, so the difference is the one-sided one
            let forward: Option<Vec<System>> = (at[0].is_none() && at[3].is_some())
                .then(|| {
                    (1..=4)
                        .map(|k| f64_model(model, &name, p0 + k as f64 * h))
                        .collect()
                })
                .flatten();
            if let Some(ahead) = forward {
                let ahead: Vec<Vec<f64>> = ahead.iter().map(|s| seen(s, &start)).collect();
                let exact: Vec<f64> = seen(&dual, &start).iter().map(|v| v.eps).collect();
                let what = format!("{} d/d{name}, one-sided, as seen", model.name());
                check_against_forward_differences(&what, &exact, &ahead, &base_seen, h);
                checked += 1;
                continue;
            }
            let Some(at) = at.into_iter().collect::<Option<Vec<_>>>() else {
                // the f64 model refuses a value near p0: a count or a switch, which the
                // dual build must have refused too, unless only what the build adds to the
                // mechanics reads it (`wire_terms_early`): then nothing moves
                assert!(
                    tangent.iter().all(|&d| d == 0.0),
                    "{} {name}: f64 builds refuse p ± h, the dual build did not",
                    model.name()
                );
                continue;
            };
            let what = format!("{} d/d{name}", model.name());
            let frames_at = |s: &System| -> Vec<Vector3<f64>> {
                s.bodies
                    .iter()
                    .map(|b| b.frame.eval(&start).origin)
                    .collect()
            };
            if frames_at(&at[0]) == frames_at(&at[3]) {
                let stored: Vec<Vec<f64>> = at.iter().map(System::scalars).collect();
                check_against_differences(&what, &tangent, &stored, &base, h);
            } else {
                moved_poses += 1;
            }
            let exact: Vec<f64> = seen(&dual, &start).iter().map(|v| v.eps).collect();
            let lab: Vec<Vec<f64>> = at.iter().map(|s| seen(s, &start)).collect();
            check_against_differences(&format!("{what}, as seen"), &exact, &lab, &base_seen, h);
            checked += 1;
        }
    }
    eprintln!(
        "{checked} parameters differentiated exactly ({moved_poses} moving a pose); refused: {refused:?}"
    );
    // the blade tips' positions of the quads' and triples' xtra-lite, lateral and lite forms
    assert!(moved_poses >= 20, "{moved_poses}");
    // 1014 (model, parameter) pairs at the time of writing: most of the bundled parameters
    // (a collapse of this count would mean the dual build refuses what it should not)
    assert!(checked > 900, "{checked}");
}

#[test]
fn a_driven_body_placed_by_a_parameter_has_no_exact_derivative() {
    // a driven body's coordinates are fixed at their values, which are numbers: a
    // parameter that places it cannot be followed by the dual build, which must say so
    // (not drop the derivative); the sensitivities then difference it
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/basic/pendulum.toml"
    ))
    .unwrap()
    .replace(
        "[bodies.support]\ncoordinates = \"00\"\ndriven = true",
        "[bodies.support]\ncoordinates = \"00\"\ndriven = true\nposition = [0, 0, \"h_support\"]",
    )
    .replace(
        "[parameters]\n",
        "[parameters]\nh_support = { value = 0.1, unit = \"m\", description = \"support height\" }\n",
    );
    assert!(text.contains("h_support\"]"), "the edit applies");
    let case = pendkit::Case::from_text(std::path::Path::new("moved-support.toml"), &text)
        .expect("the file builds");
    let e = pendkit_model::build_tangent(&*case.model, &case.overrides, "h_support")
        .expect_err("no exact derivative")
        .to_string();
    assert!(
        e.contains("no exact derivative") && e.contains("driven body"),
        "{e}"
    );
    // the fibre length still has one
    assert!(pendkit_model::build_tangent(&*case.model, &case.overrides, "l_fibre").is_ok());
    let mut request = pendkit::sensitivity::SensitivityRequest::modes(pendkit::Stage::S2);
    request.parameters = Some(vec!["h_support".into(), "l_fibre".into()]);
    let s = pendkit::sensitivity::sensitivities(&case, &request).expect("sensitivities");
    assert_eq!(s.exact, vec![false, true]);
}

#[test]
fn a_chunk_build_carries_each_parameter_as_its_own_build_does() {
    // The sensitivities build the model once per chunk of parameters
    // (`build_tangent_chunk`, one dual direction per parameter). For every bundled model,
    // with its parameters in chunks in definition order (so that chunks mix parameters the
    // build refuses with ones it carries, and parameters defined in terms of each other):
    // each direction is the one-parameter build's model (`build_tangent`, checked against
    // differences above) bit for bit — the same operations on the same numbers, direction
    // by direction (a zero derivative's sign aside: a direction the chunk carries as zero
    // may come out −0) — and a parameter is refused, with the same reason, exactly when its own
    // build refuses it.
    let mut carried = 0;
    let mut refused = 0;
    for model in pendkit::catalogue::models() {
        let model = &*model;
        let defaults = pendkit_model::Defaults::of(model).unwrap();
        let (_, resolved) = pendkit_model::parameters_with(&defaults, &Default::default()).unwrap();
        let names: Vec<String> = resolved.iter().map(|(n, _)| n.to_string()).collect();
        let mut scratch = pendkit_model::DirectionScratch::default();
        for chunk in names.chunks(pendkit_params::TANGENT_CHUNK) {
            let chunk: Vec<&str> = chunk.iter().map(String::as_str).collect();
            let built = pendkit_model::build_tangent_chunk(model, &Default::default(), &chunk)
                .unwrap_or_else(|e| panic!("{}: {e}", model.name()));
            assert_eq!(built.parameters(), chunk);
            assert!(
                built.direction(chunk.len()).is_err(),
                "a direction past the chunk"
            );
            for (k, name) in chunk.iter().enumerate() {
                let from_chunk = built.direction(k);
                // the same model rewritten in place, in a scratch shared with the chunk's
                // other directions and with the other chunks (which copy it anew)
                let in_scratch = built
                    .direction_in(k, &mut scratch)
                    .map(|system| system.scalars());
                match (&from_chunk, &in_scratch) {
                    (Ok(a), Ok(b)) => {
                        let a = a.scalars();
                        let bits = |v: &[num_dual::Dual64]| {
                            v.iter()
                                .map(|x| (x.re.to_bits(), x.eps.to_bits()))
                                .collect::<Vec<_>>()
                        };
                        assert_eq!(bits(&a), bits(b), "{} {name}: in the scratch", model.name());
                    }
                    (Err(a), Err(b)) => assert_eq!(a, b, "{} {name}", model.name()),
                    _ => panic!(
                        "{} {name}: direction and direction_in disagree",
                        model.name()
                    ),
                }
                let alone = pendkit_model::build_tangent(model, &Default::default(), name);
                match (from_chunk, alone) {
                    (Ok(a), Ok(b)) => {
                        let (a, b) = (a.scalars(), b.scalars());
                        assert_eq!(a.len(), b.len());
                        for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                            assert!(
                                x.re.to_bits() == y.re.to_bits() && x.eps == y.eps,
                                "{} {name}: number {i}: {x:?} in the chunk, {y:?} alone",
                                model.name()
                            );
                        }
                        carried += 1;
                    }
                    (Err(a), Err(b)) => {
                        assert_eq!(a, b, "{} {name}", model.name());
                        refused += 1;
                    }
                    (a, b) => panic!(
                        "{} {name}: the chunk says {:?}, the build alone {:?}",
                        model.name(),
                        a.err(),
                        b.err()
                    ),
                }
            }
        }
    }
    eprintln!("{carried} carried, {refused} refused");
    assert!(carried > 900 && refused > 10, "{carried} {refused}");
}
