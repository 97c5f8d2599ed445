//! Frame jets: a body's frame (origin and rotation) at one configuration together with its
//! first and second derivatives with respect to the coordinates the frame depends on.
//!
//! A jet is computed once per body and evaluation point and shared by every energy term
//! that touches the body: the derivatives of attachment points (p = X + R a) and of
//! body-fixed directions (d = R v) follow from it by a few f64 products, and a term's
//! Hessian by the chain rule. Pose entries that are a single coordinate or a constant (the
//! usual case) cost nothing to differentiate; other entries are differentiated by
//! hyper-dual evaluation over their own few coordinates. The rotation's derivatives come
//! from the closed-form angle derivatives of R(yaw, pitch, roll), and a chain of poses (a
//! blade tip riding on its parent) is composed by the product rule.

use nalgebra::{Matrix3, Vector3};
use num_dual::HyperDual64;
use pendkit_expr::Compiled;
use pendkit_rotations::{Real, rotation_derivatives};

use crate::{Frame, PoseMap};

/// How many derivatives a jet carries.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JetOrder {
    /// Value and first derivatives (gradients, Jacobians).
    First,
    /// Value, first and second derivatives (Hessians).
    Second,
}

/// How one pose entry depends on the frame's coordinates.
#[derive(Clone, Debug)]
enum Entry {
    /// A number.
    Const(f64),
    /// Exactly one coordinate: its position in the frame's coordinate list.
    Var { at: usize },
    /// Any other expression, renumbered to its own coordinates 0..m, with their positions
    /// in the frame's coordinate list.
    General { expr: Compiled, at: Vec<usize> },
}

/// Most coordinates a general pose entry is evaluated with on the stack.
const INLINE: usize = 8;

/// One pose of a chain: how each entry depends on the coordinates, and which of the
/// frame's coordinates move it at all.
#[derive(Clone, Debug)]
pub(crate) struct PoseShape {
    entries: [Entry; 6],
    moves: Vec<bool>,
    /// Every entry is a constant or a single coordinate: the entries have no second
    /// derivatives (the usual case), so the jet skips them.
    linear: bool,
}

/// A frame map's poses as the evaluation and derivative code reads them, worked out once
/// when the map is built.
#[derive(Clone, Debug)]
pub(crate) struct Shape {
    /// The poses as given (coordinates by global index).
    pub(crate) chain: Vec<PoseMap>,
    /// The coordinates the frame depends on (global indices), ascending.
    pub(crate) vars: Vec<usize>,
    pub(crate) poses: Vec<PoseShape>,
}

impl PoseShape {
    /// The six pose entries at `x`, reading the frame's coordinate `i` at `x[index[i]]`;
    /// the caller has checked that `x` covers every index.
    pub(crate) fn eval<D: Real>(&self, x: &[D], index: &[usize]) -> [D; 6] {
        let read = |at: usize| x[index[at]];
        std::array::from_fn(|m| match &self.entries[m] {
            Entry::Const(v) => D::from(*v),
            Entry::Var { at } => read(*at),
            Entry::General { expr, at } if at.len() <= INLINE => {
                let mut own = [D::from(0.0); INLINE];
                for (o, &a) in own.iter_mut().zip(at) {
                    *o = read(a);
                }
                // the entry was renumbered to its own coordinates 0..at.len(), so the
                // length always fits
                expr.eval(&own[..at.len()]).unwrap_or(D::from(f64::NAN))
            }
            Entry::General { expr, at } => {
                let own: Vec<D> = at.iter().map(|&a| read(a)).collect();
                expr.eval(&own).unwrap_or(D::from(f64::NAN))
            }
        })
    }
}

impl Shape {
    pub(crate) fn new(chain: Vec<PoseMap>) -> Self {
        let vars: Vec<usize> = chain
            .iter()
            .flat_map(|p| p.entries.iter().flat_map(|e| e.vars()))
            .collect::<std::collections::BTreeSet<_>>()
            .into_iter()
            .collect();
        // every variable of every entry is in `vars` by construction
        let at = |g: usize| vars.binary_search(&g).unwrap_or(0);
        let poses = chain
            .iter()
            .map(|pose| {
                let entries = std::array::from_fn(|m| {
                    let e = &pose.entries[m];
                    if let Some(v) = e.as_const() {
                        Entry::Const(v)
                    } else if let Some(g) = e.as_var() {
                        Entry::Var { at: at(g) }
                    } else {
                        let index: Vec<usize> = e.vars().into_iter().collect();
                        let own = |g: usize| index.binary_search(&g).unwrap_or(0);
                        Entry::General {
                            expr: e.remap(&own),
                            at: index.iter().map(|&g| at(g)).collect(),
                        }
                    }
                });
                let mut moves = vec![false; vars.len()];
                for e in pose.entries.iter() {
                    for g in e.vars() {
                        moves[at(g)] = true;
                    }
                }
                let linear = entries.iter().all(|e| !matches!(e, Entry::General { .. }));
                PoseShape {
                    entries,
                    moves,
                    linear,
                }
            })
            .collect();
        Shape { chain, vars, poses }
    }
}

/// Origin and rotation with derivatives over k coordinates (second derivatives stored as
/// full symmetric k × k arrays).
#[derive(Clone, Debug)]
struct Derivs {
    origin: Vector3<f64>,
    rotation: Matrix3<f64>,
    d_origin: Vec<Vector3<f64>>,
    d_rotation: Vec<Matrix3<f64>>,
    dd_origin: Vec<Vector3<f64>>,
    dd_rotation: Vec<Matrix3<f64>>,
}

impl Default for Derivs {
    fn default() -> Self {
        Derivs {
            origin: Vector3::zeros(),
            rotation: Matrix3::identity(),
            d_origin: Vec::new(),
            d_rotation: Vec::new(),
            dd_origin: Vec::new(),
            dd_rotation: Vec::new(),
        }
    }
}

impl Derivs {
    /// Zeroes the derivatives for `k` coordinates (reusing the buffers).
    fn reset(&mut self, k: usize, second: bool) {
        let kk = if second { k * k } else { 0 };
        for (v, n) in [(&mut self.d_origin, k), (&mut self.dd_origin, kk)] {
            v.clear();
            v.resize(n, Vector3::zeros());
        }
        for (v, n) in [(&mut self.d_rotation, k), (&mut self.dd_rotation, kk)] {
            v.clear();
            v.resize(n, Matrix3::zeros());
        }
    }
}

/// A frame and its derivatives with respect to the coordinates it depends on, at one
/// configuration (see the module documentation). Reusable: computing into an existing jet
/// does not allocate once its buffers have grown.
#[derive(Clone, Debug, Default)]
pub struct FrameJet {
    vars: Vec<usize>,
    second: bool,
    main: Derivs,
    // scratch: one pose of a chain, and the composition of the chain so far
    pose: Derivs,
    composed: Derivs,
    entries: EntryScratch,
    /// Which coordinates the poses composed so far depend on.
    moved: Vec<bool>,
}

/// Value, gradient (k) and Hessian (k × k) of each of the six entries of one pose.
#[derive(Clone, Debug, Default)]
struct EntryScratch {
    values: [f64; 6],
    grads: Vec<f64>,
    hessians: Vec<f64>,
    hyper: Vec<HyperDual64>,
}

impl FrameJet {
    /// An empty jet, to be filled by [`crate::FrameMap::jet`].
    pub fn new() -> Self {
        FrameJet::default()
    }

    /// The coordinates the derivatives are taken with respect to (indices into the vector
    /// the jet was evaluated at), ascending; derivative `i` is with respect to `vars()[i]`.
    pub fn vars(&self) -> &[usize] {
        &self.vars
    }

    /// Whether second derivatives are present.
    pub fn has_second(&self) -> bool {
        self.second
    }

    /// Origin (m, lab coordinates).
    pub fn origin(&self) -> &Vector3<f64> {
        &self.main.origin
    }

    /// Rotation from frame axes to lab axes.
    pub fn rotation(&self) -> &Matrix3<f64> {
        &self.main.rotation
    }

    /// `i` checked against the jet's coordinates, for `function`'s argument `argument`.
    fn first_index(
        &self,
        function: &'static str,
        argument: &'static str,
        i: usize,
    ) -> Result<usize, JetError> {
        let len = self.main.d_rotation.len();
        if i >= len {
            return Err(JetError::Index {
                function,
                argument,
                index: i,
                len,
            });
        }
        Ok(i)
    }

    /// The slot of the pair (`i`, `j`) among the second derivatives, both checked against
    /// the jet's coordinates (a `j` past the end would otherwise alias another pair's
    /// slot), and the second derivatives checked present.
    fn pair_index(&self, function: &'static str, i: usize, j: usize) -> Result<usize, JetError> {
        let k = self.main.d_rotation.len();
        self.first_index(function, "i", i)?;
        self.first_index(function, "j", j)?;
        let ij = i * k + j;
        if ij >= self.main.dd_rotation.len() {
            return Err(JetError::NoSecond { function });
        }
        Ok(ij)
    }

    /// ∂R/∂q_i (per unit of coordinate `vars()[i]`); `i` past [`FrameJet::vars`] is an
    /// error.
    pub fn d_rotation(&self, i: usize) -> Result<&Matrix3<f64>, JetError> {
        let i = self.first_index("FrameJet::d_rotation", "i", i)?;
        Ok(&self.main.d_rotation[i])
    }

    /// ∂R/∂q_i for every coordinate, in the order of [`FrameJet::vars`]: the loop form of
    /// [`FrameJet::d_rotation`], with nothing to check.
    pub fn d_rotations(&self) -> &[Matrix3<f64>] {
        &self.main.d_rotation
    }

    /// ∂²R/∂q_i∂q_j; `i` or `j` past [`FrameJet::vars`], or a jet computed with
    /// [`JetOrder::First`], is an error.
    pub fn dd_rotation(&self, i: usize, j: usize) -> Result<&Matrix3<f64>, JetError> {
        let ij = self.pair_index("FrameJet::dd_rotation", i, j)?;
        Ok(&self.main.dd_rotation[ij])
    }

    /// Lab position (m) of the body-fixed point `a` (m, frame coordinates): X + R a.
    pub fn point(&self, a: &Vector3<f64>) -> Vector3<f64> {
        self.main.origin + self.main.rotation * a
    }

    /// ∂(X + R a)/∂q_i (m per unit of coordinate `vars()[i]`); `i` past
    /// [`FrameJet::vars`] is an error.
    pub fn d_point(&self, i: usize, a: &Vector3<f64>) -> Result<Vector3<f64>, JetError> {
        let i = self.first_index("FrameJet::d_point", "i", i)?;
        Ok(self.main.d_origin[i] + self.main.d_rotation[i] * a)
    }

    /// ∂(X + R a)/∂q_i for every coordinate, in the order of [`FrameJet::vars`] (m per
    /// unit of coordinate): the loop form of [`FrameJet::d_point`], with nothing to check.
    pub fn d_points<'s>(
        &'s self,
        a: &'s Vector3<f64>,
    ) -> impl ExactSizeIterator<Item = Vector3<f64>> + 's {
        self.main
            .d_origin
            .iter()
            .zip(&self.main.d_rotation)
            .map(move |(dx, dr)| dx + dr * a)
    }

    /// ∂²(X + R a)/∂q_i∂q_j (m per unit of both coordinates); `i` or `j` past
    /// [`FrameJet::vars`], or a jet computed with [`JetOrder::First`], is an error.
    pub fn dd_point(&self, i: usize, j: usize, a: &Vector3<f64>) -> Result<Vector3<f64>, JetError> {
        let ij = self.pair_index("FrameJet::dd_point", i, j)?;
        Ok(self.main.dd_origin[ij] + self.main.dd_rotation[ij] * a)
    }

    /// The frame as hyper-dual numbers whose first infinitesimal is a unit change of
    /// coordinate `e1` and whose second is a unit change of `e2` (positions in `vars()`,
    /// `None` for a coordinate the frame does not depend on). This is exactly what
    /// evaluating the frame's pose expressions over those hyper-dual coordinates gives,
    /// without evaluating them. A position past [`FrameJet::vars`] is an error, and so is
    /// giving both to a jet computed with [`JetOrder::First`].
    pub fn hyper_dual(
        &self,
        e1: Option<usize>,
        e2: Option<usize>,
    ) -> Result<Frame<HyperDual64>, JetError> {
        const FUNCTION: &str = "FrameJet::hyper_dual";
        let d = &self.main;
        let e1 = e1
            .map(|i| self.first_index(FUNCTION, "e1", i))
            .transpose()?;
        let e2 = e2
            .map(|j| self.first_index(FUNCTION, "e2", j))
            .transpose()?;
        let e12 = match (e1, e2) {
            (Some(i), Some(j)) => Some(self.pair_index(FUNCTION, i, j)?),
            _ => None,
        };
        // every index below was checked above
        let pick = |e: Option<usize>, f: &dyn Fn(usize) -> f64| e.map_or(0.0, f);
        Ok(Frame {
            origin: Vector3::from_fn(|r, _| {
                HyperDual64::new(
                    d.origin[r],
                    pick(e1, &|i| d.d_origin[i][r]),
                    pick(e2, &|i| d.d_origin[i][r]),
                    pick(e12, &|ij| d.dd_origin[ij][r]),
                )
            }),
            rotation: Matrix3::from_fn(|r, c| {
                HyperDual64::new(
                    d.rotation[(r, c)],
                    pick(e1, &|i| d.d_rotation[i][(r, c)]),
                    pick(e2, &|i| d.d_rotation[i][(r, c)]),
                    pick(e12, &|ij| d.dd_rotation[ij][(r, c)]),
                )
            }),
        })
    }
}

impl JetError {
    /// The same error reported as coming from `function` (for a public function that
    /// checks through another).
    pub(crate) fn renamed(self, function: &'static str) -> Self {
        match self {
            JetError::Index {
                argument,
                index,
                len,
                ..
            } => JetError::Index {
                function,
                argument,
                index,
                len,
            },
            JetError::NoSecond { .. } => JetError::NoSecond { function },
        }
    }
}

/// An index a [`FrameJet`] does not have: past its coordinates, or a second derivative of
/// a jet computed with [`JetOrder::First`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum JetError {
    /// An index past the jet's coordinates.
    #[error("{function}: {argument} = {index} is out of range, the jet has {len} coordinates")]
    Index {
        /// The function called, e.g. `FrameJet::d_point`.
        function: &'static str,
        /// The argument out of range.
        argument: &'static str,
        /// Its value.
        index: usize,
        /// The number of coordinates of the jet (valid indices are below it).
        len: usize,
    },
    /// A second derivative asked of a first-order jet.
    #[error("{function}: the jet has no second derivatives (it was computed with JetOrder::First)")]
    NoSecond {
        /// The function called.
        function: &'static str,
    },
}

impl crate::FrameMap {
    /// The frame and its derivatives with respect to [`crate::FrameMap::var_list`] at
    /// coordinates `x`, written into `out` (whose buffers are reused). `x` must cover every
    /// coordinate the frame reads ([`crate::FrameMap::needs`]); a shorter one is an error
    /// and leaves `out` as it was.
    pub fn jet(
        &self,
        x: &[f64],
        order: JetOrder,
        out: &mut FrameJet,
    ) -> Result<(), crate::GeometryError> {
        self.check_length("FrameMap::jet", x.len())?;
        let shape = &*self.shape;
        let index = &*self.index;
        let k = shape.vars.len();
        let second = order == JetOrder::Second;
        out.vars.clear();
        out.vars.extend_from_slice(index);
        out.second = second;
        let FrameJet {
            main,
            pose,
            composed,
            entries,
            moved,
            ..
        } = out;
        moved.clear();
        moved.resize(k, false);
        for (p, ps) in shape.poses.iter().enumerate() {
            let target = if p == 0 { &mut *main } else { &mut *pose };
            pose_derivs(ps, x, index, second, entries, target);
            if p > 0 {
                compose(main, pose, moved, &ps.moves, k, second, composed);
                std::mem::swap(main, composed);
            }
            for (m, &now) in moved.iter_mut().zip(&ps.moves) {
                *m |= now;
            }
        }
        if shape.poses.is_empty() {
            main.origin = Vector3::zeros();
            main.rotation = Matrix3::identity();
            main.reset(k, second);
        }
        Ok(())
    }
}

/// Derivatives of one pose (relative to its parent) over the frame's k coordinates.
#[expect(
    clippy::too_many_lines,
    reason = "the general-pose path of every frame jet (the linear one is split off): the entries' \
              values, gradients and Hessians fill the `EntryScratch` buffers that the chain rule \
              through the angles then reads in place, so the hot loop borrows the scratch once"
)]
fn pose_derivs(
    shape: &PoseShape,
    x: &[f64],
    index: &[usize],
    second: bool,
    scratch: &mut EntryScratch,
    out: &mut Derivs,
) {
    let k = index.len();
    // in range: `FrameMap::jet` checked `x` against every index
    let read = |at: usize| x[index[at]];
    if shape.linear {
        linear_pose_derivs(shape, &read, k, second, out);
        return;
    }
    let EntryScratch {
        values,
        grads,
        hessians,
        hyper,
    } = scratch;
    let kk = k * k;
    grads.clear();
    grads.resize(6 * k, 0.0);
    // second derivatives of the entries themselves, when any entry has them
    let curved = second && !shape.linear;
    hessians.clear();
    if curved {
        hessians.resize(6 * kk, 0.0);
    }
    // value, gradient and Hessian of each entry
    for (m, entry) in shape.entries.iter().enumerate() {
        let g = &mut grads[m * k..(m + 1) * k];
        match entry {
            Entry::Const(v) => values[m] = *v,
            Entry::Var { at } => {
                values[m] = read(*at);
                g[*at] = 1.0;
            }
            Entry::General { expr, at } => {
                hyper.clear();
                hyper.extend(at.iter().map(|&a| HyperDual64::from_re(read(a))));
                // renumbered to its own coordinates 0..at.len(): the length always fits
                values[m] = expr.eval(hyper.as_slice()).map_or(f64::NAN, |v| v.re);
                for a in 0..at.len() {
                    hyper[a].eps1 = 1.0;
                    let last = if second { at.len() } else { a + 1 };
                    for b in a..last {
                        hyper[b].eps2 = 1.0;
                        let r = expr
                            .eval(hyper.as_slice())
                            .unwrap_or(HyperDual64::from_re(f64::NAN));
                        hyper[b].eps2 = 0.0;
                        if b == a {
                            g[at[a]] = r.eps1;
                        }
                        if second {
                            let h = &mut hessians[m * kk..(m + 1) * kk];
                            h[at[a] * k + at[b]] = r.eps1eps2;
                            h[at[b] * k + at[a]] = r.eps1eps2;
                        }
                    }
                    hyper[a].eps1 = 0.0;
                }
            }
        }
    }
    out.reset(k, second);
    out.origin = Vector3::new(values[0], values[1], values[2]);
    let grad = |m: usize, i: usize| grads[m * k + i];
    for i in 0..k {
        out.d_origin[i] = Vector3::new(grad(0, i), grad(1, i), grad(2, i));
    }
    if curved {
        let hess = |m: usize, ij: usize| hessians[m * kk + ij];
        for ij in 0..kk {
            out.dd_origin[ij] = Vector3::new(hess(0, ij), hess(1, ij), hess(2, ij));
        }
    }
    // rotation: chain rule through the three angles
    let r = rotation_derivatives(values[3], values[4], values[5], second);
    out.rotation = r.value;
    for i in 0..k {
        let mut d = Matrix3::zeros();
        for m in 0..3 {
            let gm = grad(3 + m, i);
            if gm != 0.0 {
                d += r.first[m] * gm;
            }
        }
        out.d_rotation[i] = d;
    }
    if second {
        for i in 0..k {
            for j in i..k {
                let mut d = Matrix3::zeros();
                for m in 0..3 {
                    let gi = grad(3 + m, i);
                    if gi != 0.0 {
                        for n in 0..3 {
                            let gj = grad(3 + n, j);
                            if gj != 0.0 {
                                d += r.second[m][n] * (gi * gj);
                            }
                        }
                    }
                    let h = if curved {
                        hessians[(3 + m) * kk + i * k + j]
                    } else {
                        0.0
                    };
                    if h != 0.0 {
                        d += r.first[m] * h;
                    }
                }
                out.dd_rotation[i * k + j] = d;
                out.dd_rotation[j * k + i] = d;
            }
        }
    }
}

/// [`pose_derivs`] for a pose whose entries are constants or single coordinates (a free
/// body, a blade tip sliding along an axis): each entry's gradient is a unit vector and its
/// Hessian zero, so ∂R/∂q_i is the sum of ∂R/∂θ_m over the angles m read from coordinate i,
/// and ∂²R/∂q_i∂q_j that of ∂²R/∂θ_m∂θ_n.
fn linear_pose_derivs(
    shape: &PoseShape,
    read: &dyn Fn(usize) -> f64,
    k: usize,
    second: bool,
    out: &mut Derivs,
) {
    let at = |m: usize| match shape.entries[m] {
        Entry::Var { at } => Some(at),
        _ => None,
    };
    let value = |m: usize| match &shape.entries[m] {
        Entry::Const(v) => *v,
        Entry::Var { at } => read(*at),
        // not in a linear pose
        Entry::General { .. } => f64::NAN,
    };
    out.reset(k, second);
    out.origin = Vector3::new(value(0), value(1), value(2));
    for m in 0..3 {
        if let Some(i) = at(m) {
            out.d_origin[i][m] += 1.0;
        }
    }
    let r = rotation_derivatives(value(3), value(4), value(5), second);
    out.rotation = r.value;
    for m in 0..3 {
        let Some(i) = at(3 + m) else { continue };
        out.d_rotation[i] += r.first[m];
        if !second {
            continue;
        }
        for n in 0..3 {
            if let Some(j) = at(3 + n) {
                out.dd_rotation[i * k + j] += r.second[m][n];
            }
        }
    }
}

/// The frame `local` riding on `parent`, by the product rule: X = Xp + Rp Xl, R = Rp Rl.
/// `parent_moves` and `local_moves` say which coordinates each depends on, so that
/// products with vanishing derivatives are skipped.
fn compose(
    parent: &Derivs,
    local: &Derivs,
    parent_moves: &[bool],
    local_moves: &[bool],
    k: usize,
    second: bool,
    out: &mut Derivs,
) {
    out.reset(k, second);
    let (xp, rp, xl, rl) = (
        &parent.origin,
        &parent.rotation,
        &local.origin,
        &local.rotation,
    );
    out.origin = xp + rp * xl;
    out.rotation = rp * rl;
    for i in 0..k {
        let (mut dx, mut dr) = (Vector3::zeros(), Matrix3::zeros());
        if parent_moves[i] {
            dx += parent.d_origin[i] + parent.d_rotation[i] * xl;
            dr += parent.d_rotation[i] * rl;
        }
        if local_moves[i] {
            dx += rp * local.d_origin[i];
            dr += rp * local.d_rotation[i];
        }
        out.d_origin[i] = dx;
        out.d_rotation[i] = dr;
    }
    if !second {
        return;
    }
    for i in 0..k {
        for j in i..k {
            let ij = i * k + j;
            let (mut ddx, mut ddr) = (Vector3::zeros(), Matrix3::zeros());
            if parent_moves[i] && parent_moves[j] {
                ddx += parent.dd_origin[ij] + parent.dd_rotation[ij] * xl;
                ddr += parent.dd_rotation[ij] * rl;
            }
            if parent_moves[i] && local_moves[j] {
                ddx += parent.d_rotation[i] * local.d_origin[j];
                ddr += parent.d_rotation[i] * local.d_rotation[j];
            }
            if parent_moves[j] && local_moves[i] {
                ddx += parent.d_rotation[j] * local.d_origin[i];
                ddr += parent.d_rotation[j] * local.d_rotation[i];
            }
            if local_moves[i] && local_moves[j] {
                ddx += rp * local.dd_origin[ij];
                ddr += rp * local.dd_rotation[ij];
            }
            out.dd_origin[ij] = ddx;
            out.dd_origin[j * k + i] = ddx;
            out.dd_rotation[ij] = ddr;
            out.dd_rotation[j * k + i] = ddr;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::FrameMap;
    use pendkit_expr::{Slot, parse};

    fn pose(names: &[&str], texts: [&str; 6]) -> PoseMap {
        let slot = |s: &str| names.iter().position(|n| *n == s).map(Slot::Var);
        PoseMap {
            entries: texts.map(|t| parse(t).unwrap().compile(&slot).unwrap()),
        }
    }

    /// The frame of a chain of poses evaluated directly from their compiled expressions,
    /// independently of the map's own evaluation code.
    fn direct<D: pendkit_rotations::Real>(chain: &[PoseMap], x: &[D]) -> Frame<D> {
        chain
            .iter()
            .map(|p| Frame::from_pose(std::array::from_fn(|i| p.entries[i].eval(x).unwrap())))
            .reduce(|parent, local| parent.compose(&local))
            .unwrap_or_else(Frame::identity)
    }

    /// Every derivative of the jet against hyper-dual evaluation of the pose expressions
    /// (the reference), at `x`; and the map's own evaluation, also after renumbering.
    fn check_against_hyper_duals(map: &FrameMap, x: &[f64]) {
        let chain = &map.shape.chain;
        let f = map.eval(x);
        let d = direct(chain, x);
        assert!((f.origin - d.origin).norm() < 1e-15 && (f.rotation - d.rotation).norm() < 1e-15);
        // renumbered into a longer vector with the coordinates in reverse order at the end
        let n = x.len();
        let shifted = map.remap(&|i| 2 * n - 1 - i);
        let mut y = vec![f64::NAN; 2 * n];
        for i in 0..n {
            y[2 * n - 1 - i] = x[i];
        }
        let g = shifted.eval(&y);
        assert!((g.origin - d.origin).norm() < 1e-15 && (g.rotation - d.rotation).norm() < 1e-15);
        let mut jet = FrameJet::new();
        map.jet(x, JetOrder::Second, &mut jet).unwrap();
        let vars = jet.vars().to_vec();
        let a = Vector3::new(0.03, -0.2, 0.11);
        let scale = 1.0 + jet.point(&a).norm();
        for (i, &gi) in vars.iter().enumerate() {
            for (j, &gj) in vars.iter().enumerate() {
                let mut xd: Vec<HyperDual64> = x.iter().map(|&v| HyperDual64::from_re(v)).collect();
                xd[gi].eps1 = 1.0;
                xd[gj].eps2 = 1.0;
                let f = direct(chain, &xd);
                let p = f.point(&a);
                let r = f.rotation;
                assert!((p.map(|e| e.re) - jet.point(&a)).norm() < 1e-15 * scale);
                assert!((p.map(|e| e.eps1) - jet.d_point(i, &a).unwrap()).norm() < 1e-14 * scale);
                assert_eq!(jet.d_points(&a).nth(i), jet.d_point(i, &a).ok());
                assert!(
                    (p.map(|e| e.eps1eps2) - jet.dd_point(i, j, &a).unwrap()).norm()
                        < 1e-14 * scale
                );
                assert!((r.map(|e| e.eps1) - jet.d_rotation(i).unwrap()).norm() < 1e-14);
                assert!((r.map(|e| e.eps1eps2) - jet.dd_rotation(i, j).unwrap()).norm() < 1e-14);
                // the hyper-dual frame rebuilt from the jet is the same number
                let h = jet.hyper_dual(Some(i), Some(j)).unwrap();
                assert!(
                    (h.origin.map(|e| e.eps1eps2) - f.origin.map(|e| e.eps1eps2)).norm()
                        < 1e-14 * scale
                );
                assert!((h.rotation.map(|e| e.eps1eps2) - r.map(|e| e.eps1eps2)).norm() < 1e-14);
            }
        }
    }

    #[test]
    fn free_body_jet_matches_hyper_duals() {
        let names = ["x", "y", "z", "yaw", "pitch", "roll"];
        let map = FrameMap::root(pose(&names, ["x", "y", "z", "yaw", "pitch", "roll"]));
        check_against_hyper_duals(&map, &[0.1, 0.2, -0.3, 0.4, -0.5, 0.6]);
    }

    #[test]
    fn general_entries_and_chains_match_hyper_duals() {
        // a parent with expressions mixing coordinates, and a child riding on it whose
        // entries are affine and nonlinear in shared and own coordinates
        let names = ["a", "b", "c", "q"];
        let parent = FrameMap::root(pose(
            &names,
            ["a + 0.1", "2*b", "-0.6", "a*b", "sin(c)", "0.2"],
        ));
        let child = parent.child(pose(&names, ["0.3", "q*q", "0.1 + q", "q", "0", "c"]));
        check_against_hyper_duals(&child, &[0.2, -0.3, 0.4, 0.05]);
        check_against_hyper_duals(&parent, &[0.2, -0.3, 0.4, 0.05]);
        // a pose of single coordinates (the fast linear form) that reads one coordinate in
        // several entries, riding on a free body
        let free = FrameMap::root(pose(&names, ["a", "b", "c", "q", "a", "b"]));
        let linear = free.child(pose(&names, ["q", "0.2", "q", "c", "q", "q"]));
        check_against_hyper_duals(&linear, &[0.2, -0.3, 0.4, 0.05]);
    }

    #[test]
    fn first_order_jet_agrees_with_second_order() {
        let names = ["x", "y", "z", "yaw", "pitch", "roll"];
        let map = FrameMap::root(pose(&names, ["x", "y", "z", "yaw", "pitch", "roll"]));
        let x = [0.1, 0.2, -0.3, 0.4, -0.5, 0.6];
        let (mut a, mut b) = (FrameJet::new(), FrameJet::new());
        map.jet(&x, JetOrder::First, &mut a).unwrap();
        map.jet(&x, JetOrder::Second, &mut b).unwrap();
        assert!(!a.has_second() && b.has_second());
        for i in 0..6 {
            assert_eq!(a.d_rotation(i), b.d_rotation(i));
        }
    }
}
