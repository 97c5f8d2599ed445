//! Frames of rigid bodies as functions of the model's coordinates: where a body-fixed point
//! is, how a body is turned, how one frame sits relative to another, and the velocity
//! Jacobians that build the mass matrix and linearised sensors.
//!
//! A body's pose is six expressions of the coordinates (x, y, z in m; yaw, pitch, roll in
//! rad) relative to a parent frame (the lab for a free body), so constrained bodies and
//! bodies that ride on other bodies (blade tips) are both expressed the same way.

use std::collections::BTreeSet;

use nalgebra::{Matrix3, Matrix3xX, Vector3};
use num_dual::Dual64;
use pendkit_expr::Compiled;
use pendkit_rotations::{Real, c, rotation, vee};

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

    /// Lab position (m) of a point given in frame coordinates (m): X + R p.
    pub fn point(&self, p: &Vector3<f64>) -> Vector3<D> {
        self.origin + self.direction(p)
    }

    /// Lab components of a vector given in frame coordinates: R v.
    pub fn direction(&self, v: &Vector3<f64>) -> Vector3<D> {
        self.rotation * v.map(c::<D>)
    }

    /// The frame `local` (given relative to `self`) expressed in the lab.
    pub fn compose(&self, local: &Frame<D>) -> Frame<D> {
        Frame {
            origin: self.origin + self.rotation * local.origin,
            rotation: self.rotation * local.rotation,
        }
    }

    /// `other` seen from `self`: the pose that composes with `self` to give `other`.
    pub fn relative(&self, other: &Frame<D>) -> Frame<D> {
        let rt = self.rotation.transpose();
        Frame {
            origin: rt * (other.origin - self.origin),
            rotation: rt * other.rotation,
        }
    }

    /// The same frame turned by fixed attachment angles (yaw, pitch, roll in rad) about its
    /// own axes.
    pub fn turned(&self, angles: &[f64; 3]) -> Frame<D> {
        let r = rotation(c::<D>(angles[0]), c(angles[1]), c(angles[2]));
        Frame {
            origin: self.origin,
            rotation: self.rotation * r,
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

impl PoseMap {
    fn eval<D: Real>(&self, x: &[D]) -> Frame<D> {
        Frame::from_pose(std::array::from_fn(|i| self.entries[i].eval(x)))
    }
}

/// How to compute a body's frame from the coordinates: a chain of poses from the lab down
/// to the body (a free body has a chain of one).
#[derive(Clone, Debug)]
pub struct FrameMap {
    chain: Vec<PoseMap>,
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
    /// A frame posed directly in the lab.
    pub fn root(pose: PoseMap) -> Self {
        FrameMap { chain: vec![pose] }
    }

    /// A frame posed relative to `self` (a body riding on another body).
    pub fn child(&self, pose: PoseMap) -> Self {
        let mut chain = self.chain.clone();
        chain.push(pose);
        FrameMap { chain }
    }

    /// Evaluates the frame at coordinates `x` (any scalar: values or dual numbers).
    pub fn eval<D: Real>(&self, x: &[D]) -> Frame<D> {
        let mut frames = self.chain.iter().map(|p| p.eval(x));
        let first = frames.next().unwrap_or_else(Frame::identity);
        frames.fold(first, |parent, local| parent.compose(&local))
    }

    /// Indices of the coordinates this frame depends on.
    pub fn vars(&self) -> BTreeSet<usize> {
        self.chain
            .iter()
            .flat_map(|p| p.entries.iter().flat_map(|e| e.vars()))
            .collect()
    }

    /// The same map with coordinates renumbered (global index -> a term's local index).
    pub fn remap(&self, map: &dyn Fn(usize) -> usize) -> FrameMap {
        FrameMap {
            chain: self
                .chain
                .iter()
                .map(|p| PoseMap {
                    entries: std::array::from_fn(|i| p.entries[i].remap(map)),
                })
                .collect(),
        }
    }

    /// Jacobians of the body-fixed point `p` (m, frame coordinates) and of the frame's
    /// angular velocity, at coordinates `x`, one forward-mode derivative per coordinate the
    /// frame depends on.
    pub fn jacobian(&self, x: &[f64], p: &Vector3<f64>) -> PointJacobian {
        let n = x.len();
        let mut jac = PointJacobian {
            position: Matrix3xX::zeros(n),
            omega_body: Matrix3xX::zeros(n),
            omega_space: Matrix3xX::zeros(n),
        };
        let mut xd: Vec<Dual64> = x.iter().map(|&v| Dual64::from(v)).collect();
        for j in self.vars() {
            xd[j].eps = 1.0;
            let f = self.eval(&xd);
            xd[j].eps = 0.0;
            let r = f.rotation.map(|e| e.re);
            let dr = f.rotation.map(|e| e.eps);
            let dpos = f.point(p).map(|e| e.eps);
            jac.position.set_column(j, &dpos);
            // ω̂_B = Rᵀ ∂R/∂x_j and ω̂_S = ∂R/∂x_j Rᵀ per unit rate of coordinate j.
            jac.omega_body.set_column(j, &vee(&(r.transpose() * dr)));
            jac.omega_space.set_column(j, &vee(&(dr * r.transpose())));
        }
        jac
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
        for k in 0..3 {
            assert!((jac.omega_body.column(3 + k) - omega_b.column(k)).norm() < 1e-14);
        }
    }
}
