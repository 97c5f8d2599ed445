//! Parameter sets: order-independent resolution, cycles and undefined names in errors,
//! scale and increment overrides, suggestions for unknown names.

use pendkit_expr::{Expr, Slot, parse};
use pendkit_params::{Override, ParamError, ParamSet};

fn set(defs: &[(&str, &str)]) -> ParamSet {
    let mut p = ParamSet::new();
    for (name, text) in defs {
        p.define(name, text).unwrap();
    }
    p
}

fn resolve_err(defs: &[(&str, &str)]) -> String {
    set(defs).resolve().unwrap_err().to_string()
}

/// A small deterministic Fisher-Yates shuffle (xorshift), to avoid a rand dependency.
fn shuffle<T>(items: &mut [T], mut seed: u64) {
    for i in (1..items.len()).rev() {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        items.swap(i, (seed % (i as u64 + 1)) as usize);
    }
}

const SUSPENSION: [(&str, &str); 8] = [
    ("k", "m*g/l"),
    ("m", "m1 + m2"),
    ("m1", "22"),
    ("m2", "m1/2"),
    ("g", "9.81"),
    ("l", "0.6*scale_l"),
    ("scale_l", "1"),
    ("w", "sqrt(k/m)/(2*pi)"),
];

#[test]
fn resolution_is_order_independent() {
    let reference: Vec<(String, f64)> = set(&SUSPENSION)
        .resolve()
        .unwrap()
        .iter()
        .map(|(n, v)| (n.to_string(), v))
        .collect();
    assert_eq!(reference.len(), 8);
    let w = (33.0f64 * 9.81 / 0.6 / 33.0).sqrt() / (2.0 * std::f64::consts::PI);
    assert!((reference[7].1 - w).abs() < 1e-12);
    for seed in 1..50 {
        let mut defs = SUSPENSION;
        shuffle(&mut defs, seed);
        let r = set(&defs).resolve().unwrap();
        // Same values; listing follows the (shuffled) definition order.
        for (name, text) in defs {
            let want = reference.iter().find(|(n, _)| n == name).unwrap().1;
            assert_eq!(r.get(name).unwrap(), want, "{name} = {text}");
        }
        let order: Vec<&str> = r.iter().map(|(n, _)| n).collect();
        assert_eq!(order, defs.map(|(n, _)| n));
        assert_eq!(r.len(), 8);
    }
}

#[test]
fn cycles_name_the_chain() {
    assert_eq!(
        resolve_err(&[("a", "b + 1"), ("b", "2*a")]),
        "parameter cycle: a -> b -> a"
    );
    assert_eq!(
        resolve_err(&[("x", "1"), ("a", "b"), ("b", "c"), ("c", "a*x")]),
        "parameter cycle: a -> b -> c -> a"
    );
    assert_eq!(resolve_err(&[("a", "a + 1")]), "parameter cycle: a -> a");
    // A cycle entered from outside reports only the cycle itself.
    let err = set(&[("top", "b"), ("b", "c"), ("c", "b")])
        .resolve()
        .unwrap_err();
    assert_eq!(
        err,
        ParamError::Cycle {
            chain: vec!["b".into(), "c".into(), "b".into()]
        }
    );
}

#[test]
fn undefined_symbols_name_the_chain() {
    assert_eq!(
        resolve_err(&[("a", "2*b"), ("b", "c + 1")]),
        "undefined symbol 'c' in the definition of 'b' (needed by a -> b)"
    );
    assert_eq!(
        resolve_err(&[("a", "zz")]),
        "undefined symbol 'zz' in the definition of 'a'"
    );
    // Deterministic: the first definition, then its symbols in sorted order.
    assert_eq!(
        resolve_err(&[("p", "y + x"), ("q", "w")]),
        "undefined symbol 'x' in the definition of 'p'"
    );
}

#[test]
fn non_finite_values_are_errors() {
    assert_eq!(
        resolve_err(&[("x", "sqrt(-1)")]),
        "parameter 'x' = sqrt(-1) is not a finite number"
    );
    assert_eq!(
        resolve_err(&[("y", "1/z"), ("z", "0")]),
        "parameter 'y' = 1/z is not a finite number"
    );
}

#[test]
fn scale_and_increment() {
    let mut p = set(&[
        ("m", "2"),
        ("l", "a + b"),
        ("a", "1"),
        ("b", "3"),
        ("n", "5"),
    ]);
    p.apply_text("m", "scale(1.5)").unwrap();
    p.apply_text("l", " scale ( 2 ) ").unwrap();
    assert_eq!(p.get("l").unwrap().source, "(a + b)*2");
    p.apply_text("l", "scale(a + 2)").unwrap(); // scaling composes
    assert_eq!(p.get("l").unwrap().source, "(a + b)*2*(a + 2)");
    p.apply_text("n", "increment(-1)").unwrap();
    p.apply_text("n", "increment(b)").unwrap();
    p.apply_text("b", "4").unwrap();
    assert_eq!(p.get("b").unwrap().source, "4");
    let r = p.resolve().unwrap();
    assert_eq!(r.get("m").unwrap(), 3.0);
    assert_eq!(r.get("l").unwrap(), 30.0);
    assert_eq!(r.get("n").unwrap(), 8.0);

    // The enum form does the same.
    let mut q = set(&[("m", "2")]);
    q.apply("m", Override::Scale(parse("3").unwrap())).unwrap();
    q.apply("m", Override::Increment(parse("1").unwrap()))
        .unwrap();
    assert_eq!(q.resolve().unwrap().get("m").unwrap(), 7.0);
    q.apply("m", Override::Expr(Expr::Num(0.5))).unwrap();
    assert_eq!(q.resolve().unwrap().get("m").unwrap(), 0.5);

    assert_eq!(
        Override::parse("scale(2)"),
        Ok(Override::Scale(Expr::Num(2.0)))
    );
    assert_eq!(
        Override::parse("increment(2)"),
        Ok(Override::Increment(Expr::Num(2.0)))
    );
    assert_eq!(Override::parse("2"), Ok(Override::Expr(Expr::Num(2.0))));
    assert!(Override::parse("scale(a) + scale(b)").is_err());
}

#[test]
fn unknown_names_get_suggestions() {
    let mut p = set(&[("m1", "1"), ("m3", "2"), ("stiffness", "3")]);
    let e = p.apply_text("m31", "scale(2)").unwrap_err();
    assert_eq!(
        e.to_string(),
        "unknown parameter 'm31' (did you mean 'm3'?)"
    );
    let e = p
        .apply("stifness", Override::Expr(Expr::Num(1.0)))
        .unwrap_err();
    assert_eq!(
        e.to_string(),
        "unknown parameter 'stifness' (did you mean 'stiffness'?)"
    );
    let e = p.apply_text("length", "1").unwrap_err();
    assert_eq!(e.to_string(), "unknown parameter 'length'");
    let r = p.resolve().unwrap();
    assert_eq!(
        r.get("m2").unwrap_err().to_string(),
        "unknown parameter 'm2' (did you mean 'm1'?)"
    );
}

#[test]
fn definition_errors() {
    let mut p = set(&[("m1", "1")]);
    assert_eq!(
        p.define("m1", "2").unwrap_err().to_string(),
        "duplicate parameter 'm1'"
    );
    assert_eq!(
        p.define_value("m1", 2.0).unwrap_err().to_string(),
        "duplicate parameter 'm1'"
    );
    for bad in ["pi", "sin", "2x", "a b", "", "a+b"] {
        assert_eq!(
            p.define(bad, "1"),
            Err(ParamError::InvalidName { name: bad.into() }),
            "{bad}"
        );
    }
    assert_eq!(
        p.define("x", "sin(a").unwrap_err().to_string(),
        r#"parameter 'x': expected ')' at column 6 in "sin(a""#
    );
    assert!(!p.contains("x"));
    assert_eq!(
        p.apply_text("m1", "scale(").unwrap_err().to_string(),
        r#"parameter 'm1': unknown function 'scale' at column 1 in "scale(""#
    );
    p.define("damping.fibre", "1e-3").unwrap();
    assert_eq!(p.names().collect::<Vec<_>>(), ["m1", "damping.fibre"]);
    assert_eq!(p.len(), 2);
}

#[test]
fn free_symbols_stay_symbolic() {
    let p = set(&[
        ("phi", "phi0*(1 + (f/f0)^2)"),
        ("phi0", "1e-4"),
        ("f0", "2*5"),
        ("loss", "k*phi"),
        ("k", "100"),
        ("plain", "k + 1"),
    ]);
    let r = p.resolve_with_free(&["f"]).unwrap();
    assert_eq!(r.get("k").unwrap(), 100.0);
    assert_eq!(r.get("plain").unwrap(), 101.0);
    assert_eq!(r.len(), 4);
    assert!(r.is_symbolic("loss") && !r.is_symbolic("k"));
    assert_eq!(
        r.get("loss").unwrap_err().to_string(),
        "parameter 'loss' has no numeric value: it depends on f"
    );
    let phi = r.expression("phi").unwrap();
    assert_eq!(phi.to_string(), "0.0001*(1 + (f/10)^2)");
    let loss = r.expression("loss").unwrap();
    assert_eq!(loss.symbols().into_iter().collect::<Vec<_>>(), ["f"]);
    let c = loss
        .compile(&|s| (s == "f").then_some(Slot::Var(0)))
        .unwrap();
    assert!((c.eval(&[20.0f64]).unwrap() - 100.0 * 1e-4 * 5.0).abs() < 1e-15);
    assert_eq!(r.expression("k").unwrap(), Expr::Num(100.0));
    let names: Vec<&str> = r.symbolic().map(|(n, _)| n).collect();
    assert_eq!(names, ["phi", "loss"]);

    // Without `f` free, it is an undefined symbol.
    assert_eq!(
        p.resolve().unwrap_err().to_string(),
        "undefined symbol 'f' in the definition of 'phi'"
    );
}

#[test]
fn resolved_eval() {
    let r = set(&[("a", "2"), ("b", "a^3")]).resolve().unwrap();
    assert_eq!(r.eval_str("a*b + 1").unwrap(), 17.0);
    assert_eq!(r.eval(&parse("b/a").unwrap()).unwrap(), 4.0);
    assert_eq!(
        r.eval_str("a*c").unwrap_err().to_string(),
        "unknown parameter 'c' (did you mean 'a'?)"
    );
    assert!(r.eval_str("a*").is_err());
    assert!(!r.is_empty());
}

#[test]
fn clones_are_independent() {
    // Clones share their entries until one changes (copy on write): an override or a new
    // definition on a clone leaves the original, and its resolution, as they were.
    let base = set(&SUSPENSION);
    let mut copy = base.clone();
    copy.apply_text("m1", "scale(2)").unwrap();
    copy.define("extra", "m1 + 1").unwrap();
    let (original, changed) = (base.resolve().unwrap(), copy.resolve().unwrap());
    assert_eq!(original.get("m1"), Ok(22.0));
    assert_eq!(changed.get("m1"), Ok(44.0));
    // dependents follow the override in the copy only
    assert_eq!(original.get("m2"), Ok(11.0));
    assert_eq!(changed.get("m2"), Ok(22.0));
    assert_eq!(changed.get("extra"), Ok(45.0));
    assert!(!base.contains("extra") && original.get("extra").is_err());
    assert_eq!(base.get("m1").unwrap().source, "22");
    assert_eq!(copy.get("m1").unwrap().source, "22*2");
}
