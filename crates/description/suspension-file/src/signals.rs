//! Named inputs and outputs: `0.999*x3 + theta*z3` (a linear expression of coordinates with
//! coefficients from the parameters), `<body>@x,y,z/dx,dy,dz` (a point along a direction), or
//! either after `force:`.

use nalgebra::Vector3;
use pendkit_expr::{BinOp, Expr};

/// Coefficients of a linear expression of some symbols ("coordinates"), the other symbols
/// taking their values: `(coordinate, coefficient)` in the order first met.
pub fn linear_form(
    expr: &Expr,
    is_coordinate: &dyn Fn(&str) -> bool,
    value: &dyn Fn(&str) -> Option<f64>,
) -> Result<Vec<(String, f64)>, String> {
    let (constant, terms) = linear(expr, is_coordinate, value)?;
    if constant != 0.0 {
        return Err(format!(
            "has a constant term ({constant}); a signal is a combination of coordinates only"
        ));
    }
    if terms.is_empty() {
        return Err("names no coordinate".into());
    }
    Ok(terms)
}

type Form = (f64, Vec<(String, f64)>);

fn mentions(expr: &Expr, is_coordinate: &dyn Fn(&str) -> bool) -> bool {
    expr.symbols().iter().any(|s| is_coordinate(s))
}

fn linear(
    expr: &Expr,
    is_coordinate: &dyn Fn(&str) -> bool,
    value: &dyn Fn(&str) -> Option<f64>,
) -> Result<Form, String> {
    if !mentions(expr, is_coordinate) {
        let v = expr.eval(value).map_err(|e| e.to_string())?;
        return Ok((v, Vec::new()));
    }
    let scale = |(c, t): Form, k: f64| -> Form {
        (c * k, t.into_iter().map(|(n, a)| (n, a * k)).collect())
    };
    let not_linear = || format!("'{expr}' is not linear in the coordinates");
    match expr {
        Expr::Sym(s) => Ok((0.0, vec![(s.clone(), 1.0)])),
        Expr::Neg(e) => Ok(scale(linear(e, is_coordinate, value)?, -1.0)),
        Expr::Binary(op, l, r) => {
            let (a, b) = (
                linear(l, is_coordinate, value)?,
                linear(r, is_coordinate, value)?,
            );
            match op {
                BinOp::Add | BinOp::Sub => {
                    let sign = if *op == BinOp::Add { 1.0 } else { -1.0 };
                    let (mut c, mut terms) = a;
                    c += sign * b.0;
                    for (name, k) in b.1 {
                        match terms.iter_mut().find(|(n, _)| *n == name) {
                            Some((_, existing)) => *existing += sign * k,
                            None => terms.push((name, sign * k)),
                        }
                    }
                    Ok((c, terms))
                }
                BinOp::Mul if a.1.is_empty() => Ok(scale(b, a.0)),
                BinOp::Mul if b.1.is_empty() => Ok(scale(a, b.0)),
                BinOp::Div if b.1.is_empty() => Ok(scale(a, 1.0 / b.0)),
                _ => Err(not_linear()),
            }
        }
        _ => Err(not_linear()),
    }
}

/// A point on a body along a direction: the body's name, the point (m, body coordinates)
/// and the direction (lab axes).
pub type PointSignal = (String, Vector3<f64>, Vector3<f64>);

/// A point signal `<body>@x,y,z/dx,dy,dz`: body name, point (m, body coordinates) and
/// direction (lab axes), the numbers as expressions of the parameters (without `/`, which
/// separates the point from the direction). `None` if the text is not of that form (no `@`).
pub fn point_form(
    text: &str,
    value: &dyn Fn(&str) -> Option<f64>,
) -> Option<Result<PointSignal, String>> {
    let (body, rest) = text.split_once('@')?;
    Some((|| {
        let bad = || "expected <body>@x,y,z/dx,dy,dz".to_string();
        let (point, direction) = rest.split_once('/').ok_or_else(bad)?;
        let three = |t: &str| -> Result<Vector3<f64>, String> {
            let parts = split_top_level(t);
            if parts.len() != 3 {
                return Err(bad());
            }
            let mut v = Vector3::zeros();
            for (k, p) in parts.iter().enumerate() {
                let e = pendkit_expr::parse(p).map_err(|e| e.to_string())?;
                v[k] = e.eval(value).map_err(|e| e.to_string())?;
            }
            Ok(v)
        };
        Ok((body.trim().to_string(), three(point)?, three(direction)?))
    })())
}

/// `text` split at the commas outside parentheses.
pub(crate) fn split_top_level(text: &str) -> Vec<&str> {
    let (mut depth, mut start, mut parts) = (0i32, 0, Vec::new());
    for (i, c) in text.char_indices() {
        match c {
            '(' => depth += 1,
            ')' => depth -= 1,
            ',' if depth == 0 => {
                parts.push(&text[start..i]);
                start = i + 1;
            }
            _ => {}
        }
    }
    parts.push(&text[start..]);
    parts
}

#[cfg(test)]
mod tests {
    use super::*;

    fn form(text: &str) -> Result<Vec<(String, f64)>, String> {
        let e = pendkit_expr::parse(text).unwrap();
        linear_form(&e, &|s| s.starts_with('x') || s.starts_with('z'), &|s| {
            (s == "theta").then_some(0.25)
        })
    }

    #[test]
    fn linear_combinations_and_their_errors() {
        assert_eq!(
            form("0.5*x3 + theta*z3 - (x3 - 2*z3)/4").unwrap(),
            vec![("x3".to_string(), 0.25), ("z3".to_string(), 0.75)]
        );
        assert!(form("x3*z3").unwrap_err().contains("not linear"));
        assert!(form("x3 + 1").unwrap_err().contains("constant term"));
        assert!(form("sin(x3)").unwrap_err().contains("not linear"));
        assert!(form("theta").unwrap_err().contains("constant term"));
        assert!(form("x3 + nosuch").is_err());
    }

    #[test]
    fn points_with_expressions() {
        let v = |s: &str| (s == "h").then_some(0.1);
        let (body, p, d) = point_form("top@ h, max(h, 0.2), -h*0.5 / 1,0,0", &v)
            .unwrap()
            .unwrap();
        assert_eq!(body, "top");
        assert_eq!(p, Vector3::new(0.1, 0.2, -0.05));
        assert_eq!(d, Vector3::x());
        assert!(point_form("x3", &v).is_none());
        assert!(point_form("top@1,2/1,0,0", &v).unwrap().is_err());
    }
}
