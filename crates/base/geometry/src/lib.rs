//! Frames of rigid bodies as functions of the model's coordinates: where a body-fixed point
//! is, how a body is turned, how one frame sits relative to another, the frames' first and
//! second derivatives (jets) that energy derivatives are built from, and the velocity
//! Jacobians that build the mass matrix and linearised sensors.
//!
//! A body's pose is six expressions of the coordinates (x, y, z in m; yaw, pitch, roll in
//! rad) relative to a parent frame (the lab for a free body), so constrained bodies and
//! bodies that ride on other bodies (blade tips) are both expressed the same way.

mod jet;

use std::collections::BTreeSet;
use std::sync::Arc;

use nalgebra::{Matrix3, Matrix3xX, Vector3};
use num_dual::Dual64;
use pendkit_expr::Compiled;
use pendkit_rotations::{
    Lift, Real, c, mul, mul_const, mul_const_vec, mul_vec, rotation, tr_mul, tr_mul_vec, vee,
};

pub use jet::{FrameJet, JetError, JetOrder};

/// A coordinate vector (or a Jacobian's column count) too short for the frame it is used
/// with: the function, the argument, the length needed and the length given.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{function}: {argument} has {given} entries, the frame needs {expected}")]
pub struct GeometryError {
    /// The function called, e.g. `FrameMap::jet`.
    pub function: &'static str,
    /// The argument that is too short.
    pub argument: &'static str,
    /// The length it needs.
    pub expected: usize,
    /// The length it has.
    pub given: usize,
}

/// A frame in space: origin (m) and rotation from frame axes to lab axes.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame<D> {
    /// Position of the frame origin in lab coordinates (m).
    pub origin: Vector3<D>,
    /// Rotation taking frame-axis components to lab-axis components.
    pub rotation: Matrix3<D>,
}

impl<D: Real> Frame<D> {
    /// The lab frame itself.
    pub fn identity() -> Self {
        Frame {
            origin: Vector3::from_element(c(0.0)),
            rotation: Matrix3::from_fn(|i, j| c(if i == j { 1.0 } else { 0.0 })),
        }
    }

    /// The frame at pose (x, y, z, yaw, pitch, roll) relative to the lab.
    pub fn from_pose(pose: [D; 6]) -> Self {
        Frame {
            origin: Vector3::new(pose[0], pose[1], pose[2]),
            rotation: rotation(pose[3], pose[4], pose[5]),
        }
    }

    /// Lab position (m) of a point given in frame coordinates (m): X + R p. The point is a
    /// model constant: `f64`, or a dual number carrying a parameter derivative ([`Lift`]).
    pub fn point<C: Copy>(&self, p: &Vector3<C>) -> Vector3<D>
    where
        D: Lift<C>,
    {
        // written out rather than as origin + direction: nalgebra's generic sum copies
        // each entry, which for the passes' 208-byte numbers is a call to memmove
        let (o, r) = (&self.origin, &self.rotation);
        let row = |i: usize| {
            o[i] + (r[(i, 0)].times(p[0]) + r[(i, 1)].times(p[1]) + r[(i, 2)].times(p[2]))
        };
        Vector3::new(row(0), row(1), row(2))
    }

    /// Lab components of a vector given in frame coordinates: R v (an `f64` vector is not
    /// lifted to the scalar type).
    pub fn direction<C: Copy>(&self, v: &Vector3<C>) -> Vector3<D>
    where
        D: Lift<C>,
    {
        mul_const_vec(&self.rotation, v)
    }

    /// The frame `local` (given relative to `self`) expressed in the lab.
    pub fn compose(&self, local: &Frame<D>) -> Frame<D> {
        Frame {
            origin: self.origin + mul_vec(&self.rotation, &local.origin),
            rotation: mul(&self.rotation, &local.rotation),
        }
    }

    /// `other` seen from `self`: the pose that composes with `self` to give `other`.
    pub fn relative(&self, other: &Frame<D>) -> Frame<D> {
        Frame {
            origin: tr_mul_vec(&self.rotation, &(other.origin - self.origin)),
            rotation: tr_mul(&self.rotation, &other.rotation),
        }
    }

    /// The same frame turned about its own axes by a fixed attachment rotation (a model
    /// constant, e.g. R(yaw, pitch, roll) of an attachment's angles, worked out once where
    /// the term is built).
    pub fn turned<C: Copy>(&self, turn: &Matrix3<C>) -> Frame<D>
    where
        D: Lift<C>,
    {
        Frame {
            origin: self.origin,
            rotation: mul_const(&self.rotation, turn),
        }
    }
}

/// The six pose entries of a frame relative to its parent, each a compiled expression of
/// the coordinate vector.
#[derive(Clone, Debug)]
pub struct PoseMap {
    /// x, y, z (m), yaw, pitch, roll (rad) as expressions of the coordinates.
    pub entries: [Compiled; 6],
}

/// How to compute a body's frame from the coordinates: a chain of poses from the lab down
/// to the body (a free body has a chain of one).
///
/// The poses are compiled once and shared by every copy (cloning is cheap); a copy
/// renumbered for a term's local coordinate vector ([`FrameMap::remap`]) differs only in
/// where it reads each of its coordinates.
#[derive(Clone, Debug)]
pub struct FrameMap {
    shape: Arc<jet::Shape>,
    /// Where in the coordinate vector each of the frame's coordinates is read, in the order
    /// of `shape.vars` (the global indices themselves, or a term's local indices).
    index: Arc<[usize]>,
    /// One more than the highest entry of `index`: the shortest coordinate vector the frame
    /// can be evaluated at, checked once per evaluation so that reads need no checks.
    needs: usize,
}

/// Velocity Jacobians of a body-fixed point, with respect to every coordinate (columns).
#[derive(Clone, Debug)]
pub struct PointJacobian {
    /// ∂(lab position)/∂coordinate (m per coordinate unit).
    pub position: Matrix3xX<f64>,
    /// Body-axis angular velocity per unit coordinate rate (rad per coordinate unit).
    pub omega_body: Matrix3xX<f64>,
    /// Lab-axis angular velocity per unit coordinate rate (rad per coordinate unit).
    pub omega_space: Matrix3xX<f64>,
}

impl FrameMap {
    fn from_chain(chain: Vec<PoseMap>) -> Self {
        let shape = jet::Shape::new(chain);
        FrameMap::with_index(Arc::new(shape.vars.clone()), Arc::new(shape))
    }

    fn with_index(index: Arc<Vec<usize>>, shape: Arc<jet::Shape>) -> Self {
        FrameMap {
            // saturating: an index of usize::MAX (e.g. remapped to it) needs more than any
            // vector holds, where wrapping would make it need nothing
            needs: index.iter().max().map_or(0, |&i| i.saturating_add(1)),
            index: index.as_slice().into(),
            shape,
        }
    }

    /// The shortest coordinate vector the frame can be evaluated at: one more than the
    /// highest index it reads (0 for a frame fixed in the lab).
    pub fn needs(&self) -> usize {
        self.needs
    }

    /// `given` (the length of argument `x` of `function`) covers every coordinate read.
    fn check_length(&self, function: &'static str, given: usize) -> Result<(), GeometryError> {
        if given < self.needs {
            return Err(GeometryError {
                function,
                argument: "x (coordinates)",
                expected: self.needs,
                given,
            });
        }
        Ok(())
    }

    /// A frame posed directly in the lab.
    pub fn root(pose: PoseMap) -> Self {
        FrameMap::from_chain(vec![pose])
    }

    /// A frame posed relative to `self` (a body riding on another body); `pose` reads the
    /// same coordinate vector as `self`.
    pub fn child(&self, pose: PoseMap) -> Self {
        let mut chain = self.poses();
        chain.push(pose);
        FrameMap::from_chain(chain)
    }

    /// The poses reading the coordinate vector this map reads.
    fn poses(&self) -> Vec<PoseMap> {
        let renumbered = self.index.as_ref() != self.shape.vars.as_slice();
        let at = |g: usize| {
            self.shape
                .vars
                .binary_search(&g)
                .map_or(g, |i| self.index[i])
        };
        self.shape
            .chain
            .iter()
            .map(|p| {
                if renumbered {
                    PoseMap {
                        entries: std::array::from_fn(|i| p.entries[i].remap(&at)),
                    }
                } else {
                    p.clone()
                }
            })
            .collect()
    }

    /// Evaluates the frame at coordinates `x` (any scalar: values or dual numbers). `x`
    /// must hold at least [`FrameMap::needs`] values; a shorter one gives a frame of NaN,
    /// which energy bodies (whose coordinate vectors are sized when the term is built)
    /// never see. [`FrameMap::try_eval`] says so as an error.
    pub fn eval<D: Real>(&self, x: &[D]) -> Frame<D> {
        self.try_eval(x).unwrap_or_else(|_| Frame {
            origin: Vector3::from_element(c(f64::NAN)),
            rotation: Matrix3::from_element(c(f64::NAN)),
        })
    }

    /// [`FrameMap::eval`], with a coordinate vector shorter than [`FrameMap::needs`] an
    /// error naming both lengths.
    pub fn try_eval<D: Real>(&self, x: &[D]) -> Result<Frame<D>, GeometryError> {
        self.check_length("FrameMap::eval", x.len())?;
        let mut frames = self
            .shape
            .poses
            .iter()
            .map(|p| Frame::from_pose(p.eval(x, &self.index)));
        let first = frames.next().unwrap_or_else(Frame::identity);
        Ok(frames.fold(first, |parent, local| parent.compose(&local)))
    }

    /// Indices of the coordinates this frame depends on.
    pub fn vars(&self) -> BTreeSet<usize> {
        self.index.iter().copied().collect()
    }

    /// Indices of the coordinates this frame depends on, in the order of the derivatives in
    /// [`FrameJet`] (ascending, for the global map and for order-keeping renumberings).
    pub fn var_list(&self) -> &[usize] {
        &self.index
    }

    /// The same map with coordinates renumbered (global index -> a term's local index).
    pub fn remap(&self, map: &dyn Fn(usize) -> usize) -> FrameMap {
        FrameMap::with_index(
            Arc::new(self.index.iter().map(|&i| map(i)).collect()),
            self.shape.clone(),
        )
    }

    /// Jacobians of the body-fixed point `p` (m, frame coordinates) and of the frame's
    /// angular velocity, at coordinates `x`, from the frame's first-order jet: one column
    /// per entry of `x`. An `x` shorter than [`FrameMap::needs`] gives columns of NaN;
    /// [`FrameMap::try_jacobian`] says so as an error.
    pub fn jacobian(&self, x: &[f64], p: &Vector3<f64>) -> PointJacobian {
        self.try_jacobian(x, p)
            .unwrap_or_else(|_| PointJacobian::filled(x.len(), f64::NAN))
    }

    /// [`FrameMap::jacobian`], with a coordinate vector shorter than [`FrameMap::needs`]
    /// an error naming both lengths.
    pub fn try_jacobian(
        &self,
        x: &[f64],
        p: &Vector3<f64>,
    ) -> Result<PointJacobian, GeometryError> {
        let mut jet = FrameJet::new();
        self.jet(x, JetOrder::First, &mut jet)?;
        jet.jacobian(x.len(), p)
    }

    /// [`FrameMap::jacobian`] computed independently of the jets: one forward-mode dual
    /// evaluation of the pose expressions per coordinate the frame depends on (the
    /// reference the jets are checked against).
    pub fn reference_jacobian(
        &self,
        x: &[f64],
        p: &Vector3<f64>,
    ) -> Result<PointJacobian, GeometryError> {
        self.check_length("FrameMap::reference_jacobian", x.len())?;
        let mut jac = PointJacobian::filled(x.len(), 0.0);
        let mut xd: Vec<Dual64> = x.iter().map(|&v| Dual64::from(v)).collect();
        for &j in self.var_list() {
            xd[j].eps = 1.0;
            let f = self.eval(&xd);
            xd[j].eps = 0.0;
            let r = f.rotation.map(|e| e.re);
            let dr = f.rotation.map(|e| e.eps);
            jac.position.set_column(j, &f.point(p).map(|e| e.eps));
            // ω̂_B = Rᵀ ∂R/∂x_j and ω̂_S = ∂R/∂x_j Rᵀ per unit rate of coordinate j.
            jac.omega_body.set_column(j, &vee(&(r.transpose() * dr)));
            jac.omega_space.set_column(j, &vee(&(dr * r.transpose())));
        }
        Ok(jac)
    }
}

impl PointJacobian {
    /// `n` columns of `value`.
    fn filled(n: usize, value: f64) -> Self {
        PointJacobian {
            position: Matrix3xX::from_element(n, value),
            omega_body: Matrix3xX::from_element(n, value),
            omega_space: Matrix3xX::from_element(n, value),
        }
    }
}

impl FrameJet {
    /// Velocity of the body-fixed point `a` (m, frame coordinates) and angular velocity of
    /// the frame per unit rate of coordinate `vars()[i]`: (∂p/∂q_i, ω_B, ω_S), with
    /// ω̂_B = Rᵀ ∂R/∂q_i and ω̂_S = ∂R/∂q_i Rᵀ. An `i` past [`FrameJet::vars`] is an error.
    pub fn velocity(&self, i: usize, a: &Vector3<f64>) -> Result<[Vector3<f64>; 3], JetError> {
        let dp = self
            .d_point(i, a)
            .map_err(|e| e.renamed("FrameJet::velocity"))?;
        Ok(self.velocity_of(dp, self.d_rotations()[i]))
    }

    /// [`FrameJet::velocity`] for every coordinate, in the order of [`FrameJet::vars`]:
    /// the loop form, with nothing to check.
    pub fn velocities<'s>(
        &'s self,
        a: &'s Vector3<f64>,
    ) -> impl ExactSizeIterator<Item = [Vector3<f64>; 3]> + 's {
        self.d_points(a)
            .zip(self.d_rotations())
            .map(|(dp, dr)| self.velocity_of(dp, *dr))
    }

    /// (∂p/∂q_i, ω_B, ω_S) from ∂p/∂q_i and ∂R/∂q_i.
    fn velocity_of(&self, dp: Vector3<f64>, dr: Matrix3<f64>) -> [Vector3<f64>; 3] {
        let r = self.rotation();
        [dp, vee(&(r.transpose() * dr)), vee(&(dr * r.transpose()))]
    }

    /// The velocity Jacobians of the body-fixed point `a` over all `n` coordinates of the
    /// vector the jet was evaluated at (zero columns for coordinates the frame ignores);
    /// an `n` that leaves out a coordinate of the jet is an error.
    pub fn jacobian(&self, n: usize, a: &Vector3<f64>) -> Result<PointJacobian, GeometryError> {
        let needs = self.vars().iter().max().map_or(0, |&g| g.saturating_add(1));
        if n < needs {
            return Err(GeometryError {
                function: "FrameJet::jacobian",
                argument: "n (columns)",
                expected: needs,
                given: n,
            });
        }
        let mut jac = PointJacobian::filled(n, 0.0);
        for (&g, [dp, wb, ws]) in self.vars().iter().zip(self.velocities(a)) {
            jac.position.set_column(g, &dp);
            jac.omega_body.set_column(g, &wb);
            jac.omega_space.set_column(g, &ws);
        }
        Ok(jac)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use pendkit_expr::{Slot, parse};

    /// Compiles six pose expressions over the named coordinates.
    fn pose(names: &[&str], texts: [&str; 6]) -> PoseMap {
        let slot = |s: &str| names.iter().position(|n| *n == s).map(Slot::Var);
        PoseMap {
            entries: texts.map(|t| parse(t).unwrap().compile(&slot).unwrap()),
        }
    }

    #[test]
    fn point_on_turned_body() {
        // body at (1, 2, 3) yawed by 90°: its x axis points along lab y.
        let names = ["x", "yaw"];
        let map = FrameMap::root(pose(&names, ["x", "2", "3", "yaw", "0", "0"]));
        let f = map.eval(&[1.0, std::f64::consts::FRAC_PI_2]);
        let p = f.point(&Vector3::new(0.5, 0.0, 0.0));
        assert!((p - Vector3::new(1.0, 2.5, 3.0)).norm() < 1e-15);
    }

    #[test]
    fn child_frame_rides_on_parent() {
        // a tip 0.2 m along the parent's y axis, sliding along the parent's z by q.
        let names = ["yaw", "q"];
        let parent = FrameMap::root(pose(&names, ["0", "0", "0", "yaw", "0", "0"]));
        let tip = parent.child(pose(&names, ["0", "0.2", "q", "0", "0", "0"]));
        let f = tip.eval(&[std::f64::consts::FRAC_PI_2, 0.01]);
        assert!((f.origin - Vector3::new(-0.2, 0.0, 0.01)).norm() < 1e-15);
        assert_eq!(tip.vars(), [0, 1].into_iter().collect());
    }

    #[test]
    fn relative_inverts_compose() {
        let names = ["a", "b", "c"];
        let a = FrameMap::root(pose(&names, ["a", "b", "c", "a", "b", "c"]));
        let b = FrameMap::root(pose(&names, ["c", "a", "b", "b", "c", "a"]));
        let x = [0.3, -0.2, 0.7];
        let (fa, fb) = (a.eval(&x), b.eval(&x));
        let back = fa.compose(&fa.relative(&fb));
        assert!((back.origin - fb.origin).norm() < 1e-14);
        assert!((back.rotation - fb.rotation).norm() < 1e-14);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let names = ["x", "y", "z", "yaw", "pitch", "roll"];
        let map = FrameMap::root(pose(&names, ["x", "y", "z", "yaw", "pitch", "roll"]));
        let x = [0.1, 0.2, -0.3, 0.4, -0.5, 0.6];
        let p = Vector3::new(0.01, -0.17, 0.02);
        let jac = map.jacobian(&x, &p);
        let h = 1e-6;
        for j in 0..6 {
            let mut xp = x;
            let mut xm = x;
            xp[j] += h;
            xm[j] -= h;
            let fd = (map.eval(&xp).point(&p) - map.eval(&xm).point(&p)) / (2.0 * h);
            assert!((fd - jac.position.column(j)).norm() < 1e-9, "column {j}");
        }
        // the rotational columns reproduce the analytic rate matrices
        let omega_b = pendkit_rotations::body_rate_matrix(x[3], x[4], x[5]);
        let omega_s = pendkit_rotations::space_rate_matrix(x[3], x[4], x[5]);
        for k in 0..3 {
            assert!((jac.omega_body.column(3 + k) - omega_b.column(k)).norm() < 1e-14);
            assert!((jac.omega_space.column(3 + k) - omega_s.column(k)).norm() < 1e-14);
        }
        // and the jet route agrees with the dual-number one
        let dual = map.reference_jacobian(&x, &p).unwrap();
        assert!((dual.position - &jac.position).norm() < 1e-15);
        assert!((dual.omega_body - &jac.omega_body).norm() < 1e-15);
        assert!((dual.omega_space - &jac.omega_space).norm() < 1e-15);
    }
}
