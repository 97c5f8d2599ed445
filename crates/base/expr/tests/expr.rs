//! The expression language: parsing, precedence, functions against std, exact derivatives
//! by dual numbers, and error messages.

use std::collections::BTreeSet;
use std::f64::consts::PI;

use num_dual::{Dual2_64, Dual64, first_derivative, second_derivative};
use pendkit_expr::{BinOp, Expr, ExprError, Func, Slot, is_symbol_name, parse};
use proptest::prelude::*;

/// Evaluates `src` over f64 with a = 2, b = 3, x = 0.3.
fn val(src: &str) -> f64 {
    let lookup = |s: &str| match s {
        "a" => Some(2.0),
        "b" => Some(3.0),
        "x" => Some(0.3),
        "damping.fibre_2" => Some(10.0),
        _ => None,
    };
    parse(src)
        .unwrap_or_else(|e| panic!("{src}: {e}"))
        .eval(&lookup)
        .unwrap()
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + a.abs().max(b.abs()))
}

#[test]
fn precedence_and_associativity() {
    let table = [
        ("1 + 2*3", 7.0),
        ("(1 + 2)*3", 9.0),
        ("2*3^2", 18.0),
        ("-2^2", -4.0),
        ("(-2)^2", 4.0),
        ("(-2)^3", -8.0),
        ("2^3^2", 512.0),
        ("(2^3)^2", 64.0),
        ("2^-1", 0.5),
        ("-a^2", -4.0),
        ("8/4/2", 1.0),
        ("8 - 4 - 2", 2.0),
        ("8 - 4 + 2", 6.0),
        ("2*-3", -6.0),
        ("1 - -1", 2.0),
        ("--3", 3.0),
        ("+3 - +1", 2.0),
        ("-a*b", -6.0),
        ("a/b*b", 2.0),
        (".5 + 1e-3 + 2.5E2 + 1.", 251.501),
        ("1e+2", 100.0),
        ("damping.fibre_2 / 5", 2.0),
        ("  a\t*\n( b +1 ) ", 8.0),
        ("2*pi", 2.0 * PI),
        ("a^b", 8.0),
    ];
    for (src, want) in table {
        assert!(close(val(src), want), "{src} = {} (want {want})", val(src));
    }
}

#[test]
fn functions_match_std() {
    let x: f64 = 0.3;
    let table = [
        ("sqrt(x)", x.sqrt()),
        ("sin(x)", x.sin()),
        ("cos(x)", x.cos()),
        ("tan(x)", x.tan()),
        ("asin(x)", x.asin()),
        ("acos(x)", x.acos()),
        ("atan(x)", x.atan()),
        ("exp(x)", x.exp()),
        ("log(x)", x.ln()),
        ("abs(-x)", x),
        ("abs(x)", x),
        ("atan2(x, -1)", x.atan2(-1.0)),
        ("min(a, b)", 2.0),
        ("min(b, x, a)", x),
        ("max(a, b)", 3.0),
        ("max(x, b, a)", 3.0),
    ];
    for (src, want) in table {
        assert_eq!(val(src), want, "{src}");
    }
}

/// d/dx of every function, through num-dual, against a central difference.
#[test]
fn derivatives_of_every_function() {
    for src in [
        "sqrt(x)",
        "sin(x)",
        "cos(x)",
        "tan(x)",
        "asin(x)",
        "acos(x)",
        "atan(x)",
        "atan2(x, 0.7)",
        "atan2(0.7, x)",
        "exp(x)",
        "log(x)",
        "abs(x)",
        "abs(-x)",
        "min(x, 0.5)",
        "max(x, 0.1)",
        "x^2.5",
        "2^x",
        "x^x",
        "(-x)^3",
    ] {
        let e = parse(src).unwrap();
        let f = |x: f64| e.eval(&|_| Some(x)).unwrap();
        let (v, d) = first_derivative(|x: Dual64| e.eval(&|_| Some(x)), 0.3).unwrap();
        let h = 1e-6;
        let fd = (f(0.3 + h) - f(0.3 - h)) / (2.0 * h);
        assert!(close(v, f(0.3)), "{src}");
        assert!((d - fd).abs() < 1e-7, "{src}: {d} vs {fd}");
    }
}

#[test]
fn analytic_derivatives() {
    let e = parse("sin(x)*x^2").unwrap();
    let x0 = 0.7f64;
    let (v, d, dd) = second_derivative(|x: Dual2_64| e.eval(&|_| Some(x)), x0).unwrap();
    assert!(close(v, x0.sin() * x0 * x0));
    assert!(close(d, x0.cos() * x0 * x0 + 2.0 * x0 * x0.sin()));
    assert!(close(
        dd,
        -x0.sin() * x0 * x0 + 4.0 * x0 * x0.cos() + 2.0 * x0.sin()
    ));

    // The same through a compiled expression with a constant folded in.
    let c = parse("k*sin(x)*x^2")
        .unwrap()
        .compile(&|s| match s {
            "x" => Some(Slot::Var(0)),
            "k" => Some(Slot::Const(3.0)),
            _ => None,
        })
        .unwrap();
    let (cv, cd) = first_derivative(|x: Dual64| c.eval(&[x]).unwrap(), x0);
    assert!(close(cv, 3.0 * v));
    assert!(close(cd, 3.0 * d));
    // Integer power of a negative base keeps a finite derivative.
    let p = parse("x^3")
        .unwrap()
        .compile(&|_| Some(Slot::Var(0)))
        .unwrap();
    let (_, pd) = first_derivative(|x: Dual64| p.eval(&[x]).unwrap(), -2.0);
    assert!(close(pd, 12.0));
}

#[test]
fn display_round_trips_a_list() {
    for src in [
        "a + b*c",
        "(a + b)*c",
        "a - (b - c)",
        "a/(b*c)",
        "a/b/c",
        "-a^2",
        "(-a)^2",
        "a^b^c",
        "(a^b)^c",
        "a^-b",
        "-(a + b)",
        "--a",
        "a*-b",
        "max(a, b, sin(c))",
        "atan2(damping.fibre, x_1)",
        "1e-7*2.5 + 1e20 + 0.001",
        "2*pi",
    ] {
        let e = parse(src).unwrap();
        let shown = e.to_string();
        assert_eq!(parse(&shown).unwrap(), e, "{src} -> {shown}");
    }
    assert_eq!(parse("(a+b)*c").unwrap().to_string(), "(a + b)*c");
    assert_eq!(parse("a - ((b) - c)").unwrap().to_string(), "a - (b - c)");
    assert_eq!(parse("(-a)^2").unwrap().to_string(), "(-a)^2");
    assert_eq!(Expr::Num(-2.0).to_string(), "-2");
    let neg_base = Expr::Binary(
        BinOp::Pow,
        Box::new(Expr::Num(-2.0)),
        Box::new(Expr::Num(2.0)),
    );
    assert_eq!(neg_base.to_string(), "(-2)^2");
    assert_eq!(
        parse(&neg_base.to_string()).unwrap().eval::<f64>(&|_| None),
        Ok(4.0)
    );
}

fn arb_expr() -> impl Strategy<Value = Expr> {
    let leaf = prop_oneof![
        prop_oneof![
            Just(0.0),
            Just(1.0),
            Just(2.5),
            Just(1e-7),
            Just(3e21),
            Just(0.1 + 0.2)
        ]
        .prop_map(Expr::Num),
        (0.0..1e6f64).prop_map(Expr::Num),
        prop_oneof![
            Just("a"),
            Just("b"),
            Just("pi"),
            Just("damping.fibre"),
            Just("x_1")
        ]
        .prop_map(|s| Expr::Sym(s.to_string())),
    ];
    leaf.prop_recursive(5, 48, 3, |inner| {
        let op = prop_oneof![
            Just(BinOp::Add),
            Just(BinOp::Sub),
            Just(BinOp::Mul),
            Just(BinOp::Div),
            Just(BinOp::Pow),
        ];
        prop_oneof![
            inner.clone().prop_map(|e| Expr::Neg(Box::new(e))),
            (op, inner.clone(), inner.clone()).prop_map(|(op, l, r)| Expr::Binary(
                op,
                Box::new(l),
                Box::new(r)
            )),
            inner.clone().prop_map(|e| Expr::Call(Func::Sqrt, vec![e])),
            (inner.clone(), inner.clone()).prop_map(|(a, b)| Expr::Call(Func::Atan2, vec![a, b])),
            prop::collection::vec(inner, 2..4).prop_map(|v| Expr::Call(Func::Max, v)),
        ]
    })
}

proptest! {
    #[test]
    fn display_round_trips(e in arb_expr()) {
        let shown = e.to_string();
        prop_assert_eq!(parse(&shown).unwrap(), e, "{}", shown);
    }

    #[test]
    fn parse_never_panics(s in "[-+*/^(),.a-z0-9 eE]{0,40}") {
        let _ = parse(&s);
    }
}

fn err(src: &str) -> String {
    parse(src).unwrap_err().to_string()
}

#[test]
fn error_messages() {
    assert_eq!(err("sin(a"), r#"expected ')' at column 6 in "sin(a""#);
    assert_eq!(err("(a + b"), r#"expected ')' at column 7 in "(a + b""#);
    assert_eq!(
        err("sinn(x)"),
        r#"unknown function 'sinn' at column 1 in "sinn(x)""#
    );
    assert_eq!(
        err("sqrt(a, b)"),
        "wrong number of arguments to 'sqrt' (expected 1, got 2)"
    );
    assert_eq!(
        err("max(a)"),
        "wrong number of arguments to 'max' (expected at least 2, got 1)"
    );
    assert_eq!(err(""), r#"expected an expression at column 1 in """#);
    assert_eq!(err("   "), r#"expected an expression at column 4 in "   ""#);
    assert_eq!(err("a +"), r#"expected an expression at column 4 in "a +""#);
    assert_eq!(err("a b"), r#"unexpected 'b' at column 3 in "a b""#);
    assert_eq!(err("a)"), r#"unexpected ')' at column 2 in "a)""#);
    assert_eq!(err("2x"), r#"unexpected 'x' at column 2 in "2x""#);
    assert_eq!(
        err("a # b"),
        r#"unexpected character '#' at column 3 in "a # b""#
    );
    assert_eq!(
        err("é + #"),
        r#"unexpected character 'é' at column 1 in "é + #""#
    );
    // columns count characters, whatever their bytes: a non-breaking and an em space are
    // whitespace
    assert!(
        err("a\u{a0}+\u{2003}b #").starts_with("unexpected character '#' at column 7 in "),
        "{}",
        err("a\u{a0}+\u{2003}b #")
    );
    assert_eq!(
        err("1e999"),
        r#"number '1e999' is too large (overflows to infinity; the largest is 1.8e308) at column 1 in "1e999""#
    );
    // a nonzero literal that would read as 0 (or a subnormal) is named, not read as 0
    assert!(
        err("2*1e-400").starts_with("number '1e-400' is too small"),
        "{}",
        err("2*1e-400")
    );
    assert!(err("2*1e-400").ends_with(r#"at column 3 in "2*1e-400""#));
    assert_eq!(
        err("sin + 1"),
        r#"expected '(' after function 'sin' at column 5 in "sin + 1""#
    );
    assert_eq!(err("*a"), r#"unexpected '*' at column 1 in "*a""#);
    // Quotes and newlines are escaped so messages stay on one line.
    assert_eq!(err("a\n)"), r#"unexpected ')' at column 3 in "a\n)""#);

    let e = parse("a + q")
        .unwrap()
        .eval::<f64>(&|s| (s == "a").then_some(1.0));
    assert_eq!(e, Err(ExprError::UnknownSymbol { name: "q".into() }));
    assert_eq!(e.unwrap_err().to_string(), "unknown symbol 'q'");
}

#[test]
fn deep_input_is_an_error_not_a_crash() {
    let nested = format!("{}1{}", "(".repeat(100_000), ")".repeat(100_000));
    assert!(err(&nested).starts_with("expression nested too deeply"));
    let long = vec!["a"; 100_000].join("+");
    assert!(err(&long).starts_with("expression nested too deeply"));
    let minus = "-".repeat(100_000) + "a";
    assert!(err(&minus).starts_with("expression nested too deeply"));
    // Moderately long sums are fine.
    assert_eq!(val(&vec!["a"; 300].join(" + ")), 600.0);
}

#[test]
fn symbols_are_free_names_only() {
    let e = parse("a*pi + sin(damping.fibre) - max(a, b, 2) + atan2(pi, c)").unwrap();
    let want: BTreeSet<String> = ["a", "b", "c", "damping.fibre"].map(String::from).into();
    assert_eq!(e.symbols(), want);
    assert!(parse("2*pi + sqrt(3)").unwrap().symbols().is_empty());
}

#[test]
fn compile_folds_constants() {
    let none = |_: &str| None;
    assert_eq!(
        parse("2*pi").unwrap().compile(&none).unwrap().as_const(),
        Some(2.0 * PI)
    );
    assert_eq!(
        parse("sqrt(4) + max(1, 3)")
            .unwrap()
            .compile(&none)
            .unwrap()
            .as_const(),
        Some(5.0)
    );
    let slots = |s: &str| match s {
        "x" => Some(Slot::Var(0)),
        "y" => Some(Slot::Var(3)),
        "a" => Some(Slot::Const(2.0)),
        _ => None,
    };
    let c = parse("a*0 + x").unwrap().compile(&slots).unwrap();
    assert_eq!(c.as_const(), None);
    assert_eq!(c.as_var(), None);
    assert_eq!(c.eval(&[5.0]), Ok(5.0));
    let x = parse("x").unwrap().compile(&slots).unwrap();
    assert_eq!(x.as_var(), Some(0));
    assert_eq!(x.as_const(), None);
    assert_eq!(
        parse("a^3").unwrap().compile(&slots).unwrap().as_const(),
        Some(8.0)
    );
    assert_eq!(parse("-x").unwrap().compile(&slots).unwrap().as_var(), None);

    let c = parse("a*x + y^2").unwrap().compile(&slots).unwrap();
    assert_eq!(c.vars(), BTreeSet::from([0, 3]));
    assert_eq!(c.arity(), 4);
    assert_eq!(c.eval(&[1.0, 0.0, 0.0, 3.0]), Ok(11.0));
    // Too few values is an error naming the function and both lengths, not a panic or NaN.
    assert_eq!(
        c.eval(&[1.0f64]),
        Err(ExprError::Length {
            function: "Compiled::eval",
            argument: "vars",
            expected: 4,
            given: 1
        })
    );
    let r = c.remap(&|i| if i == 3 { 1 } else { 0 });
    assert_eq!(r.vars(), BTreeSet::from([0, 1]));
    assert_eq!(r.eval(&[1.0, 3.0]), Ok(11.0));

    let e = parse("a + q").unwrap().compile(&slots);
    assert_eq!(e, Err(ExprError::UnknownSymbol { name: "q".into() }));
    let bad = Expr::Call(Func::Sin, vec![]);
    assert!(matches!(
        bad.compile(&slots),
        Err(ExprError::WrongArity { got: 0, .. })
    ));
    assert!(bad.eval::<f64>(&|_| None).is_err());
}

#[test]
fn compiled_matches_direct_evaluation() {
    let src = "a*sin(x)^2 - max(x, 0.2, y)/exp(a) + atan2(y, x) + x^y";
    let e = parse(src).unwrap();
    let direct: f64 = e
        .eval(&|s| match s {
            "a" => Some(2.0),
            "x" => Some(0.3),
            "y" => Some(1.7),
            _ => None,
        })
        .unwrap();
    let c = e
        .compile(&|s| match s {
            "a" => Some(Slot::Const(2.0)),
            "x" => Some(Slot::Var(1)),
            "y" => Some(Slot::Var(0)),
            _ => None,
        })
        .unwrap();
    assert_eq!(c.eval(&[1.7, 0.3]), Ok(direct));
    let dual = c
        .eval(&[Dual64::from(1.7), Dual64::from(0.3).derivative()])
        .unwrap();
    assert_eq!(dual.re, direct);
}

#[test]
fn substitute_replaces_and_folds() {
    let e = parse("2*a*f + b^2 + pi").unwrap();
    let s = e.substitute(&|name| match name {
        "a" => Some(Expr::Num(1.5)),
        "b" => Some(Expr::Num(-2.0)),
        _ => None,
    });
    assert_eq!(s.to_string(), "3*f + 4 + pi");
    assert_eq!(s.symbols(), BTreeSet::from(["f".to_string()]));
    let s = parse("a*f")
        .unwrap()
        .substitute(&|n| (n == "a").then(|| Expr::Num(-2.0)));
    assert_eq!(s.to_string(), "-2*f");
    assert_eq!(s.eval::<f64>(&|_| Some(3.0)), Ok(-6.0));
}

proptest! {
    /// Evaluating over many points at once gives exactly the numbers of one evaluation per
    /// point (same operations, same order), for random expressions over two variables.
    #[test]
    fn points_match_one_evaluation_per_point(e in arb_expr()) {
        let slots = |s: &str| match s {
            "a" => Some(Slot::Var(0)),
            "b" => Some(Slot::Var(1)),
            "damping.fibre" => Some(Slot::Const(1e-7)),
            "x_1" => Some(Slot::Const(-2.5)),
            _ => None,
        };
        let c = e.compile(&slots).unwrap();
        let a = [0.1, 1.0, 7.5, 1e3, 0.0, -3.0];
        let b = [2.0, 0.5, -1.0, 1e-9, 4.0, 3.0];
        let mut out = [0.0; 6];
        c.eval_points(&[&a, &b], &mut out).unwrap();
        for k in 0..a.len() {
            let one = c.eval(&[a[k], b[k]]).unwrap();
            prop_assert!(out[k] == one || (out[k].is_nan() && one.is_nan()), "{} at {}: {} vs {}", e, k, out[k], one);
        }
        // a missing column is an error, as a missing variable is; so is a short column
        if !c.vars().is_empty() {
            let mut short = [0.0; 6];
            prop_assert!(c.eval_points(&[], &mut short).is_err());
            prop_assert!(c.eval::<f64>(&[]).is_err());
            prop_assert!(c.eval_points(&[&a[..2], &b[..2]], &mut short).is_err());
        }
    }
}

/// `is_symbol_name` is a shortcut for "parses as exactly this one symbol, and is not `pi`":
/// the second method here is the parser itself.
#[test]
fn a_symbol_name_is_what_parses_back_as_that_symbol() {
    let by_parsing = |name: &str| matches!(parse(name), Ok(Expr::Sym(s)) if s == name && s != "pi");
    for name in [
        "m1", "_x", "a.b", "a..", "stage1.m", "e", "nan", "inf", "pi", "pix", "sqrt", "sqrtx",
        "atan2", "min", "max", "1e3", "1a", ".5", "", " a", "a ", "a b", "a-b", "a(b)", "é", "aé",
        "A_9", "_", "x.", "x^2",
    ] {
        assert_eq!(is_symbol_name(name), by_parsing(name), "{name:?}");
    }
}
