//! Arithmetic expressions over named symbols: parsed once, then evaluated over `f64` or
//! num-dual dual numbers (directly, or after compiling them to a fast variable-slot form).
//!
//! We do not use an existing expression crate because none of them evaluates generically over
//! num-dual's `DualNum` types, which pendkit needs to differentiate through parameter
//! expressions.
//!
//! ```
//! use pendkit_expr::parse;
//! let e = parse("2*sin(x)^2").unwrap();
//! let v: f64 = e.eval(&|name| (name == "x").then_some(0.5)).unwrap();
//! assert!((v - 2.0 * 0.5f64.sin().powi(2)).abs() < 1e-15);
//! ```

mod compile;
mod number;
mod parse;

use std::collections::BTreeSet;
use std::fmt;
use std::str::FromStr;

use num_dual::DualNum;

pub use compile::{Compiled, Slot};
pub use number::{NumberError, number_literal, number_text};
pub use parse::{is_symbol_name, parse};

/// A binary operator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BinOp {
    /// `a + b`
    Add,
    /// `a - b`
    Sub,
    /// `a * b`
    Mul,
    /// `a / b`
    Div,
    /// `a ^ b` (right-associative; binds tighter than unary minus)
    Pow,
}

impl BinOp {
    fn symbol(self) -> &'static str {
        match self {
            BinOp::Add => " + ",
            BinOp::Sub => " - ",
            BinOp::Mul => "*",
            BinOp::Div => "/",
            BinOp::Pow => "^",
        }
    }

    /// Applies the operator. A power with a variable exponent uses `exp(b ln a)`, so its base
    /// must be positive; constant exponents are handled by the callers with `powf`.
    fn apply<D: DualNum<Primitive = f64> + Copy>(self, a: D, b: D) -> D {
        match self {
            BinOp::Add => a + b,
            BinOp::Sub => a - b,
            BinOp::Mul => a * b,
            BinOp::Div => a / b,
            BinOp::Pow => a.powd(b),
        }
    }
}

/// A built-in function.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Func {
    /// Square root.
    Sqrt,
    /// Sine (radians).
    Sin,
    /// Cosine (radians).
    Cos,
    /// Tangent (radians).
    Tan,
    /// Inverse sine.
    Asin,
    /// Inverse cosine.
    Acos,
    /// Inverse tangent.
    Atan,
    /// Two-argument inverse tangent `atan2(y, x)`.
    Atan2,
    /// Exponential.
    Exp,
    /// Natural logarithm.
    Log,
    /// Absolute value.
    Abs,
    /// Minimum of two or more arguments.
    Min,
    /// Maximum of two or more arguments.
    Max,
}

impl Func {
    const ALL: [Func; 13] = [
        Func::Sqrt,
        Func::Sin,
        Func::Cos,
        Func::Tan,
        Func::Asin,
        Func::Acos,
        Func::Atan,
        Func::Atan2,
        Func::Exp,
        Func::Log,
        Func::Abs,
        Func::Min,
        Func::Max,
    ];

    /// The name used in expressions, e.g. `"sqrt"`.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sqrt => "sqrt",
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Asin => "asin",
            Func::Acos => "acos",
            Func::Atan => "atan",
            Func::Atan2 => "atan2",
            Func::Exp => "exp",
            Func::Log => "log",
            Func::Abs => "abs",
            Func::Min => "min",
            Func::Max => "max",
        }
    }

    /// Looks a function up by its name.
    pub fn from_name(name: &str) -> Option<Func> {
        Func::ALL.into_iter().find(|f| f.name() == name)
    }

    /// Whether `n` arguments are acceptable.
    pub fn accepts(self, n: usize) -> bool {
        match self {
            Func::Min | Func::Max => n >= 2,
            Func::Atan2 => n == 2,
            _ => n == 1,
        }
    }

    /// The accepted number of arguments, in words (`"1"`, `"2"`, `"at least 2"`).
    pub fn arity_text(self) -> &'static str {
        match self {
            Func::Min | Func::Max => "at least 2",
            Func::Atan2 => "2",
            _ => "1",
        }
    }

    /// Applies the function to arguments produced by `arg`. Returns `Ok(None)` on a wrong
    /// argument count. Shared by [`Expr::eval`] and [`Compiled::eval`] so both agree exactly.
    fn apply<T, D, E>(
        self,
        args: &[T],
        mut arg: impl FnMut(&T) -> Result<D, E>,
    ) -> Result<Option<D>, E>
    where
        D: DualNum<Primitive = f64> + Copy,
    {
        if !self.accepts(args.len()) {
            return Ok(None);
        }
        let Some((first, rest)) = args.split_first() else {
            return Ok(None);
        };
        let x = arg(first)?;
        let value = match self {
            Func::Sqrt => x.sqrt(),
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Asin => x.asin(),
            Func::Acos => x.acos(),
            Func::Atan => x.atan(),
            Func::Exp => x.exp(),
            Func::Log => x.ln(),
            Func::Abs => x.abs(),
            Func::Atan2 => match rest {
                [r] => x.atan2(arg(r)?),
                _ => return Ok(None),
            },
            Func::Min | Func::Max => {
                let mut best = x;
                for r in rest {
                    let y = arg(r)?;
                    let better = if self == Func::Min {
                        y < best
                    } else {
                        y > best
                    };
                    if better {
                        best = y;
                    }
                }
                best
            }
        };
        Ok(Some(value))
    }
}

impl fmt::Display for Func {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A parsed expression.
///
/// The symbol `pi` always denotes π; every other [`Expr::Sym`] is a free symbol.
/// `Display` prints a form that [`parse`] reads back to an equal tree.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    /// A number literal.
    Num(f64),
    /// A named symbol (or the constant `pi`).
    Sym(String),
    /// Unary minus.
    Neg(Box<Expr>),
    /// A binary operation.
    Binary(BinOp, Box<Expr>, Box<Expr>),
    /// A function call.
    Call(Func, Vec<Expr>),
}

/// Errors from parsing, compiling or evaluating expressions.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExprError {
    /// Malformed input text; `column` counts characters from 1.
    #[error("{message} at column {column} in {input:?}")]
    Syntax {
        /// What is wrong, e.g. `expected ')'`.
        message: String,
        /// 1-based character column.
        column: usize,
        /// The whole input text.
        input: String,
    },
    /// A call to a function that does not exist.
    #[error("unknown function '{name}' at column {column} in {input:?}")]
    UnknownFunction {
        /// The function name as written.
        name: String,
        /// 1-based character column.
        column: usize,
        /// The whole input text.
        input: String,
    },
    /// A call with the wrong number of arguments.
    #[error("wrong number of arguments to '{func}' (expected {}, got {got})", func.arity_text())]
    WrongArity {
        /// The function called.
        func: Func,
        /// The number of arguments given.
        got: usize,
    },
    /// A symbol with no value.
    #[error("unknown symbol '{name}'")]
    UnknownSymbol {
        /// The symbol name.
        name: String,
    },
    /// A compiled expression given fewer values than it reads.
    #[error("{function}: {argument} has {given} entries, the expression needs {expected}")]
    Length {
        /// The function called, e.g. `Compiled::eval`.
        function: &'static str,
        /// The argument that is too short.
        argument: &'static str,
        /// The length it needs.
        expected: usize,
        /// The length it has.
        given: usize,
    },
}

impl FromStr for Expr {
    type Err = ExprError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        parse(s)
    }
}

impl Expr {
    /// Whether this is the constant `pi`.
    fn is_pi(&self) -> bool {
        matches!(self, Expr::Sym(s) if s == "pi")
    }

    /// The free symbols used (excluding `pi` and function names), sorted.
    pub fn symbols(&self) -> BTreeSet<String> {
        let mut out = BTreeSet::new();
        self.collect_symbols(&mut out);
        out
    }

    fn collect_symbols(&self, out: &mut BTreeSet<String>) {
        match self {
            Expr::Num(_) => {}
            Expr::Sym(s) => {
                if !self.is_pi() && !out.contains(s) {
                    out.insert(s.clone());
                }
            }
            Expr::Neg(e) => e.collect_symbols(out),
            Expr::Binary(_, l, r) => {
                l.collect_symbols(out);
                r.collect_symbols(out);
            }
            Expr::Call(_, args) => args.iter().for_each(|a| a.collect_symbols(out)),
        }
    }

    /// Whether the expression has no free symbols.
    fn is_constant(&self) -> bool {
        match self {
            Expr::Num(_) => true,
            Expr::Sym(_) => self.is_pi(),
            Expr::Neg(e) => e.is_constant(),
            Expr::Binary(_, l, r) => l.is_constant() && r.is_constant(),
            Expr::Call(_, args) => args.iter().all(Expr::is_constant),
        }
    }

    /// Evaluates the expression, taking symbol values from `lookup`.
    ///
    /// Works for `f64` and any num-dual scalar. A power whose exponent contains symbols is
    /// computed as `exp(b ln a)` and so needs a positive base; constant exponents use `powf`.
    pub fn eval<D>(&self, lookup: &dyn Fn(&str) -> Option<D>) -> Result<D, ExprError>
    where
        D: DualNum<Primitive = f64> + Copy,
    {
        match self {
            Expr::Num(x) => Ok(D::from(*x)),
            Expr::Sym(_) if self.is_pi() => Ok(D::from(std::f64::consts::PI)),
            Expr::Sym(name) => {
                lookup(name).ok_or_else(|| ExprError::UnknownSymbol { name: name.clone() })
            }
            Expr::Neg(e) => Ok(-e.eval(lookup)?),
            Expr::Binary(BinOp::Pow, l, r) if r.is_constant() => {
                let exponent: f64 = r.eval(&|_| None)?;
                Ok(l.eval(lookup)?.powf(exponent))
            }
            Expr::Binary(op, l, r) => Ok(op.apply(l.eval(lookup)?, r.eval(lookup)?)),
            Expr::Call(func, args) => {
                func.apply(args, |a| a.eval(lookup))?
                    .ok_or(ExprError::WrongArity {
                        func: *func,
                        got: args.len(),
                    })
            }
        }
    }

    /// Replaces symbols for which `replace` gives an expression, then folds every constant
    /// subtree (one without free symbols, other than a bare `pi`) into a number.
    pub fn substitute(&self, replace: &dyn Fn(&str) -> Option<Expr>) -> Expr {
        let folded = match self {
            Expr::Num(_) => return self.clone(),
            Expr::Sym(name) => {
                return match replace(name) {
                    Some(e) if !self.is_pi() => e,
                    _ => self.clone(),
                };
            }
            Expr::Neg(e) => Expr::Neg(Box::new(e.substitute(replace))),
            Expr::Binary(op, l, r) => Expr::Binary(
                *op,
                Box::new(l.substitute(replace)),
                Box::new(r.substitute(replace)),
            ),
            Expr::Call(func, args) => {
                Expr::Call(*func, args.iter().map(|a| a.substitute(replace)).collect())
            }
        };
        if folded.is_constant()
            && let Ok(x) = folded.eval::<f64>(&|_| None)
        {
            return Expr::Num(x);
        }
        folded
    }

    /// Binding strength used by `Display`: higher binds tighter.
    fn precedence(&self) -> u8 {
        match self {
            Expr::Binary(BinOp::Add | BinOp::Sub, ..) => 1,
            Expr::Binary(BinOp::Mul | BinOp::Div, ..) => 2,
            Expr::Neg(_) => 3,
            Expr::Num(x) if x.is_sign_negative() && !x.is_nan() => 3,
            Expr::Binary(BinOp::Pow, ..) => 4,
            _ => 5,
        }
    }

    fn fmt_prec(&self, f: &mut fmt::Formatter<'_>, min: u8) -> fmt::Result {
        let parens = self.precedence() < min;
        if parens {
            f.write_str("(")?;
        }
        match self {
            Expr::Num(x) => fmt_number(*x, f)?,
            Expr::Sym(s) => f.write_str(s)?,
            Expr::Neg(e) => {
                f.write_str("-")?;
                e.fmt_prec(f, 3)?;
            }
            Expr::Binary(op, l, r) => {
                // Left-associative operators need parentheses on an equal-precedence right
                // operand; `^` is right-associative and takes a unary operand on the right.
                let (lmin, rmin) = match op {
                    BinOp::Add | BinOp::Sub => (1, 2),
                    BinOp::Mul | BinOp::Div => (2, 3),
                    BinOp::Pow => (5, 3),
                };
                l.fmt_prec(f, lmin)?;
                f.write_str(op.symbol())?;
                r.fmt_prec(f, rmin)?;
            }
            Expr::Call(func, args) => {
                write!(f, "{func}(")?;
                for (i, a) in args.iter().enumerate() {
                    if i > 0 {
                        f.write_str(", ")?;
                    }
                    a.fmt_prec(f, 0)?;
                }
                f.write_str(")")?;
            }
        }
        if parens {
            f.write_str(")")?;
        }
        Ok(())
    }
}

/// Writes a number so that it parses back exactly (non-finite values as `1/0`, `0/0`).
fn fmt_number(x: f64, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    let a = x.abs();
    if x.is_nan() {
        f.write_str("(0/0)")
    } else if x.is_infinite() {
        f.write_str(if x > 0.0 { "(1/0)" } else { "(-1/0)" })
    } else if a != 0.0 && !(1e-5..1e16).contains(&a) {
        write!(f, "{x:e}")
    } else {
        write!(f, "{x}")
    }
}

impl fmt::Display for Expr {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.fmt_prec(f, 0)
    }
}
