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
        Ok(Compiled {
            node: compile_node(self, slot)?,
        })
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
                    Node::Const(node.eval::<f64>(&[]))
                }
                _ => node,
            }
        }
    })
}

/// `l op r`, with `r` still a node: a constant exponent allows negative bases, e.g. (-2)^3.
fn binary<D: DualNum<Primitive = f64> + Copy>(op: BinOp, l: D, r: &Node, vars: &[D]) -> D {
    match (op, r) {
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
            Node::Var(i) => vars.get(*i).copied().unwrap_or(D::from(f64::NAN)),
            Node::Neg(e) => -e.eval(vars),
            Node::Binary(op, l, r) => binary(*op, l.eval(vars), r, vars),
            Node::Call(func, args) => func
                .apply(args, |a| Ok::<D, Infallible>(a.eval(vars)))
                .ok()
                .flatten()
                .unwrap_or(D::from(f64::NAN)),
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
    /// Evaluates with variable `i` taking the value `vars[i]`.
    ///
    /// Every variable index used must be `< vars.len()`; an out-of-range index evaluates to
    /// NaN rather than panicking.
    pub fn eval<D: DualNum<Primitive = f64> + Copy>(&self, vars: &[D]) -> D {
        self.node.eval(vars)
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
        Compiled {
            node: self.node.remap(map),
        }
    }
}
