//! Expressions with symbols bound to constants or numbered variables, for fast repeated
//! evaluation.

use std::collections::BTreeSet;
use std::convert::Infallible;

use num_dual::DualNum;

use crate::{BinOp, Expr, ExprError, Func};

/// What a symbol stands for when compiling: a fixed number or the variable with this index.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Slot {
    /// A constant value, folded into the compiled expression.
    Const(f64),
    /// The variable `vars[i]` passed to [`Compiled::eval`].
    Var(usize),
}

/// An expression whose symbols are resolved to constants or variable indices, with constant
/// subtrees folded to numbers. Evaluation does not allocate.
#[derive(Debug, Clone, PartialEq)]
pub struct Compiled {
    node: Node,
    /// How many variables an evaluation must pass: one more than the highest variable
    /// index (0 for a constant), checked once per call so that the tree walk reads
    /// variables without checks of its own.
    arity: usize,
}

#[derive(Debug, Clone, PartialEq)]
enum Node {
    Const(f64),
    Var(usize),
    Neg(Box<Node>),
    Binary(BinOp, Box<Node>, Box<Node>),
    /// Argument counts are checked when compiling.
    Call(Func, Vec<Node>),
}

impl Expr {
    /// Compiles the expression, asking `slot` what each free symbol stands for.
    ///
    /// `pi` is always π. A symbol for which `slot` returns `None` gives
    /// [`ExprError::UnknownSymbol`]; a call with a wrong argument count gives
    /// [`ExprError::WrongArity`].
    pub fn compile(&self, slot: &dyn Fn(&str) -> Option<Slot>) -> Result<Compiled, ExprError> {
        Ok(Compiled::from_node(compile_node(self, slot)?))
    }
}

fn compile_node(expr: &Expr, slot: &dyn Fn(&str) -> Option<Slot>) -> Result<Node, ExprError> {
    // Children are compiled first and are already folded, so a node is constant when all
    // its children are; constants fold here without building the node.
    Ok(match expr {
        Expr::Num(x) => Node::Const(*x),
        Expr::Sym(name) if name == "pi" => Node::Const(std::f64::consts::PI),
        Expr::Sym(name) => match slot(name) {
            Some(Slot::Const(x)) => Node::Const(x),
            Some(Slot::Var(i)) => Node::Var(i),
            None => return Err(ExprError::UnknownSymbol { name: name.clone() }),
        },
        Expr::Neg(e) => match compile_node(e, slot)? {
            Node::Const(x) => Node::Const(-x),
            e => Node::Neg(Box::new(e)),
        },
        Expr::Binary(op, l, r) => match (compile_node(l, slot)?, compile_node(r, slot)?) {
            (Node::Const(a), r @ Node::Const(_)) => Node::Const(binary(*op, a, &r, &[])),
            (l, r) => Node::Binary(*op, Box::new(l), Box::new(r)),
        },
        Expr::Call(func, args) => {
            if !func.accepts(args.len()) {
                return Err(ExprError::WrongArity {
                    func: *func,
                    got: args.len(),
                });
            }
            let args = args.iter().map(|a| compile_node(a, slot));
            let node = Node::Call(*func, args.collect::<Result<_, _>>()?);
            match &node {
                Node::Call(_, args) if args.iter().all(Node::is_const) => {
                    // a call of constants reads no variable
                    Node::Const(node.eval::<f64>(&[]))
                }
                _ => node,
            }
        }
    })
}

/// A buffer of `len` values from `spare` (or a new one).
fn borrow(spare: &mut Vec<Vec<f64>>, len: usize) -> Vec<f64> {
    let mut buffer = spare.pop().unwrap_or_default();
    buffer.resize(len, 0.0);
    buffer
}

/// `l op r`, with `r` still a node: a constant exponent allows negative bases, e.g. (-2)^3.
fn binary<D: DualNum<Primitive = f64> + Copy>(op: BinOp, l: D, r: &Node, vars: &[D]) -> D {
    match (op, r) {
        // a square as one product: the correctly rounded x², where pow is within an ulp
        // of it at several times the cost (thermoelastic peaks square ωτ at every frequency)
        (BinOp::Pow, Node::Const(exponent)) if *exponent == 2.0 => l * l,
        (BinOp::Pow, Node::Const(exponent)) => l.powf(*exponent),
        _ => op.apply(l, r.eval(vars)),
    }
}

impl Node {
    fn is_const(&self) -> bool {
        matches!(self, Node::Const(_))
    }

    fn eval<D: DualNum<Primitive = f64> + Copy>(&self, vars: &[D]) -> D {
        match self {
            Node::Const(x) => D::from(*x),
            // in range: `Compiled::eval` checked the length against the arity
            Node::Var(i) => vars[*i],
            Node::Neg(e) => -e.eval(vars),
            Node::Binary(op, l, r) => binary(*op, l.eval(vars), r, vars),
            Node::Call(func, args) => func
                .apply(args, |a| Ok::<D, Infallible>(a.eval(vars)))
                .ok()
                .flatten()
                .unwrap_or(D::from(f64::NAN)),
        }
    }

    /// Evaluates at every point at once into `out` (one value per point), with variable i
    /// at point k taking `columns[i][k]`: the same operations in the same order as
    /// [`Node::eval`] at each point, one tree walk for all points. `spare` lends buffers
    /// for the right-hand operands and arguments.
    fn eval_points(&self, columns: &[&[f64]], out: &mut [f64], spare: &mut Vec<Vec<f64>>) {
        match self {
            Node::Const(x) => out.fill(*x),
            // in range: `Compiled::eval_points` checked the columns against the arity and
            // the number of points
            Node::Var(i) => out.copy_from_slice(&columns[*i][..out.len()]),
            Node::Neg(e) => {
                e.eval_points(columns, out, spare);
                out.iter_mut().for_each(|y| *y = -*y);
            }
            Node::Binary(BinOp::Pow, l, r) if r.is_const() => {
                l.eval_points(columns, out, spare);
                for y in out.iter_mut() {
                    *y = binary(BinOp::Pow, *y, r, &[]);
                }
            }
            Node::Binary(op, l, r) => {
                l.eval_points(columns, out, spare);
                let mut right = borrow(spare, out.len());
                r.eval_points(columns, &mut right, spare);
                for (y, &b) in out.iter_mut().zip(&right) {
                    *y = op.apply(*y, b);
                }
                spare.push(right);
            }
            Node::Call(func, args) => {
                let mut values: Vec<Vec<f64>> = Vec::with_capacity(args.len());
                for a in args {
                    let mut v = borrow(spare, out.len());
                    a.eval_points(columns, &mut v, spare);
                    values.push(v);
                }
                let which: Vec<usize> = (0..args.len()).collect();
                for (k, y) in out.iter_mut().enumerate() {
                    *y = func
                        .apply(&which, |&a| Ok::<f64, Infallible>(values[a][k]))
                        .ok()
                        .flatten()
                        .unwrap_or(f64::NAN);
                }
                spare.extend(values);
            }
        }
    }

    fn visit_vars(&self, f: &mut dyn FnMut(usize)) {
        match self {
            Node::Const(_) => {}
            Node::Var(i) => f(*i),
            Node::Neg(e) => e.visit_vars(f),
            Node::Binary(_, l, r) => {
                l.visit_vars(f);
                r.visit_vars(f);
            }
            Node::Call(_, args) => args.iter().for_each(|a| a.visit_vars(f)),
        }
    }

    fn remap(&self, map: &dyn Fn(usize) -> usize) -> Node {
        match self {
            Node::Const(x) => Node::Const(*x),
            Node::Var(i) => Node::Var(map(*i)),
            Node::Neg(e) => Node::Neg(Box::new(e.remap(map))),
            Node::Binary(op, l, r) => {
                Node::Binary(*op, Box::new(l.remap(map)), Box::new(r.remap(map)))
            }
            Node::Call(func, args) => {
                Node::Call(*func, args.iter().map(|a| a.remap(map)).collect())
            }
        }
    }
}

impl Compiled {
    fn from_node(node: Node) -> Self {
        let mut arity = 0;
        node.visit_vars(&mut |i| arity = arity.max(i + 1));
        Compiled { node, arity }
    }

    /// How many variables [`Compiled::eval`] must be given: one more than the highest
    /// variable index the expression reads (0 when it reads none).
    pub fn arity(&self) -> usize {
        self.arity
    }

    /// Evaluates with variable `i` taking the value `vars[i]`.
    ///
    /// `vars` must hold at least [`Compiled::arity`] values (more are ignored); fewer give
    /// [`ExprError::Length`].
    pub fn eval<D: DualNum<Primitive = f64> + Copy>(&self, vars: &[D]) -> Result<D, ExprError> {
        self.check_length("Compiled::eval", "vars", vars.len())?;
        Ok(self.node.eval(vars))
    }

    /// Evaluates at many points with one walk of the expression tree: variable `i` takes
    /// `columns[i][k]` at point k and `out[k]` receives the value there, the same number
    /// [`Compiled::eval`] gives (the same operations in the same order), for curves over a
    /// grid such as damping multipliers over a frequency sweep. Fewer than
    /// [`Compiled::arity`] columns, or a column the expression reads shorter than `out`,
    /// give [`ExprError::Length`].
    pub fn eval_points(&self, columns: &[&[f64]], out: &mut [f64]) -> Result<(), ExprError> {
        self.check_length("Compiled::eval_points", "columns", columns.len())?;
        if let Some(short) = columns[..self.arity].iter().find(|c| c.len() < out.len()) {
            return Err(ExprError::Length {
                function: "Compiled::eval_points",
                argument: "a column of `columns` (one value per point of `out`)",
                expected: out.len(),
                given: short.len(),
            });
        }
        self.node.eval_points(columns, out, &mut Vec::new());
        Ok(())
    }

    fn check_length(
        &self,
        function: &'static str,
        argument: &'static str,
        given: usize,
    ) -> Result<(), ExprError> {
        if given < self.arity {
            return Err(ExprError::Length {
                function,
                argument,
                expected: self.arity,
                given,
            });
        }
        Ok(())
    }

    /// The value, if the expression does not depend on any variable.
    pub fn as_const(&self) -> Option<f64> {
        match self.node {
            Node::Const(x) => Some(x),
            _ => None,
        }
    }

    /// The variable index, if the expression is exactly one variable with no arithmetic.
    pub fn as_var(&self) -> Option<usize> {
        match self.node {
            Node::Var(i) => Some(i),
            _ => None,
        }
    }

    /// The indices of the variables the expression depends on.
    pub fn vars(&self) -> BTreeSet<usize> {
        let mut out = BTreeSet::new();
        self.node.visit_vars(&mut |i| {
            out.insert(i);
        });
        out
    }

    /// Renumbers the variables: variable `i` becomes variable `map(i)`.
    pub fn remap(&self, map: &dyn Fn(usize) -> usize) -> Compiled {
        Compiled::from_node(self.node.remap(map))
    }
}
