//! Parameter tangents (`ParamSet::resolve_tangent`) against closed-form derivatives and
//! against fourth-order differences of `resolve` with the seed overridden by a number (the
//! meaning the tangent promises).

use pendkit_params::ParamSet;

fn set() -> ParamSet {
    let mut p = ParamSet::new();
    p.define("k", "m*g/l").unwrap(); // defined before what it reads
    p.define_value("m", 2.0).unwrap();
    p.define_value("g", 9.81).unwrap();
    p.define_value("l", 0.5).unwrap();
    p.define("w", "sqrt(k/m)").unwrap();
    p.define("odd", "exp(l)*sin(m) + l^3").unwrap();
    p
}

#[test]
fn closed_forms() {
    // k = m g / l: ∂k/∂m = g/l, ∂k/∂l = −m g/l²; w = √(k/m) = √(g/l) does not depend on m;
    // to 1e-15 relative (a few roundings)
    let p = set();
    let by_m = p.resolve_tangent("m").unwrap();
    assert_eq!(by_m.seed(), "m");
    assert_eq!(by_m.get("m").unwrap().eps, 1.0);
    assert_eq!(by_m.get("g").unwrap().eps, 0.0);
    let dk = by_m.get("k").unwrap().eps;
    assert!((dk - 9.81 / 0.5).abs() <= 1e-15 * dk.abs(), "{dk}");
    assert!(
        by_m.get("w").unwrap().eps.abs() <= 1e-15,
        "dw/dm must vanish"
    );
    let by_l = p.resolve_tangent("l").unwrap();
    let dk = by_l.get("k").unwrap().eps;
    let want = -2.0 * 9.81 / 0.25;
    assert!((dk - want).abs() <= 1e-15 * want.abs(), "{dk}");
    // seeding a derived parameter: its definition is replaced, what it reads is unmoved
    let by_k = p.resolve_tangent("k").unwrap();
    assert_eq!(by_k.get("m").unwrap().eps, 0.0);
    let k: f64 = 2.0 * 9.81 / 0.5;
    let dw = by_k.get("w").unwrap().eps;
    let want = 0.5 / (k * 2.0).sqrt();
    assert!((dw - want).abs() <= 1e-15 * want, "{dw} vs {want}");
}

#[test]
fn against_differences_of_overridden_resolutions() {
    // the fourth-order central difference with h = 1e-3 of the seed's value: truncation
    // h⁴ f⁽⁵⁾/30, which for a 1/p dependence is 4e-12 of f/p (the largest here, k = m g/l
    // in l: 3e-10 of 78), and rounding ~1e-16/h ~ 1e-13; asserted to 1e-10 of f/p
    let p = set();
    for seed in ["m", "l", "g", "k"] {
        let tangent = p.resolve_tangent(seed).unwrap();
        let resolved = p.resolve().unwrap();
        let p0 = resolved.get(seed).unwrap();
        let h = 1e-3 * p0.abs();
        let at = |x: f64| {
            let mut q = p.clone();
            q.apply_text(seed, &format!("{x:e}")).unwrap();
            q.resolve().unwrap()
        };
        let points: Vec<_> = [-2.0, -1.0, 1.0, 2.0]
            .iter()
            .map(|k| at(p0 + k * h))
            .collect();
        for (name, value) in tangent.iter() {
            let v = |i: usize| points[i].get(name).unwrap();
            let fd = (8.0 * (v(2) - v(1)) - (v(3) - v(0))) / (12.0 * h);
            let scale = value.re.abs().max(1.0) / p0.abs();
            assert!(
                (value.eps - fd).abs() <= 1e-10 * scale,
                "d{name}/d{seed}: {} vs {fd}",
                value.eps
            );
            // the real part is the resolved value
            assert!((value.re - resolved.get(name).unwrap()).abs() <= 1e-15 * value.re.abs());
        }
    }
}

#[test]
fn an_unknown_seed_is_an_error() {
    let e = set().resolve_tangent("nope").unwrap_err().to_string();
    assert!(e.contains("nope"), "{e}");
}

#[test]
fn several_seeds_at_once_follow_each_other_as_one_seed_does() {
    // resolve_tangents seeds m, k and l together. In m's direction k follows m through its
    // definition (∂k/∂m = g/l), although k is a seed too: only in its own direction is k's
    // definition replaced (∂m = 0, ∂w = ½/√(k m) there). The closed forms of `closed_forms`,
    // to 1e-15 relative; and every direction equals the one-seed tangent of the same seed
    // bit for bit (the same operations on the same numbers, direction by direction).
    let p = set();
    let seeds = ["m", "k", "l"];
    let chunk = p.resolve_tangents(&seeds).unwrap();
    assert_eq!(
        chunk.seeds().iter().map(|s| &**s).collect::<Vec<_>>(),
        seeds
    );
    let along = |name: &str, k: usize| {
        let k = pendkit_params::Direction::new(k).unwrap();
        pendkit_params::chunk_direction(&chunk.get(name).unwrap(), k)
    };
    let (m, g, l) = (2.0, 9.81, 0.5);
    let close = |x: f64, want: f64| (x - want).abs() <= 1e-15 * want.abs();
    assert!(close(along("k", 0).eps, g / l), "{}", along("k", 0).eps);
    assert_eq!(along("m", 1).eps, 0.0);
    assert_eq!(along("k", 1).eps, 1.0);
    let k = m * g / l;
    assert!(close(along("w", 1).eps, 0.5 / (k * m).sqrt()));
    assert!(close(along("k", 2).eps, -m * g / (l * l)));
    for (d, seed) in seeds.iter().enumerate() {
        let one = p.resolve_tangent(seed).unwrap();
        for (name, value) in one.iter() {
            let x = along(name, d);
            assert_eq!((x.re, x.eps), (value.re, value.eps), "{name} along {seed}");
        }
    }
    // directions past the seeds carry nothing
    assert!(chunk.iter().all(|(_, v)| along_v(&v, 3).eps == 0.0));
    // and past the chunk there is no direction: an error, not an index out of bounds
    let e = pendkit_params::Direction::new(pendkit_params::TANGENT_CHUNK).unwrap_err();
    assert_eq!(
        e.to_string(),
        "derivative seeds: direction 16 is out of range: a chunk has 16 (0 to 15)"
    );
    assert!(pendkit_params::Direction::new(usize::MAX).is_err());
}

/// `x` along direction `k` (below the chunk).
fn along_v(x: &pendkit_params::ChunkDual, k: usize) -> num_dual::Dual64 {
    pendkit_params::chunk_direction(x, pendkit_params::Direction::new(k).unwrap())
}

#[test]
fn bad_seed_lists_are_errors() {
    let p = set();
    let twice = p
        .resolve_tangents(&["m", "l", "m"])
        .unwrap_err()
        .to_string();
    assert!(twice.contains("'m' is seeded twice"), "{twice}");
    let many: Vec<&str> = std::iter::repeat_n("m", pendkit_params::TANGENT_CHUNK + 1).collect();
    let e = p.resolve_tangents(&many).unwrap_err().to_string();
    assert!(e.contains("at most"), "{e}");
    let e = p.resolve_tangents(&["m", "nope"]).unwrap_err().to_string();
    assert!(e.contains("nope"), "{e}");
}
