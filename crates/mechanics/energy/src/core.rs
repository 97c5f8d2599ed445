//! The core element kinds of stage 0A: gravity, springs and wire stretch (docs/physics.md §1).
//!
//! Each has a fast derivative path shaped like its physics: gravity and wire stretch in
//! closed form from the attachment points' jets, springs by the chain rule through the
//! deflection Δ, whose derivatives come from the two frames' jets.

use std::sync::Arc;

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};
use num_dual::Dual64;
use pendkit_geometry::{Frame, FrameMap};
use pendkit_rotations::{
    ANGLE_ENTRIES, Constant, Lift, Real, angle_derivatives, angles, any_moves, c, rotation,
};

use crate::{
    Attached, BodyId, Derivatives, Element, EnergyError, GRAVITY_TAG, JetPoint, LocalFrames,
    OffForm, Potential, Reference, SharedBodies, SpringEnd, Stage, System, TangentPotential,
    TangentTerm, TensionOff, Term, Wire, add_curvature, add_jacobian, term_label,
};

/// Gravitational energy m g z of one body's centre of mass (constants `f64`, or `Dual64`
/// for the parameter derivatives).
#[derive(Clone, Debug)]
pub struct GravityEnergy<C = f64> {
    frame: FrameMap,
    centre_of_mass: Vector3<C>,
    /// m g (N).
    weight: C,
}

impl<C: Constant> GravityEnergy<C> {
    /// m g z (J) with the body at `frame`: the one energy body of both constant types.
    fn energy_on<D: Lift<C>>(&self, frame: &Frame<D>) -> D {
        frame.point(&self.centre_of_mass)[2].times(self.weight)
    }
}

impl TangentPotential for GravityEnergy<Dual64> {
    fn energy_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D {
        self.energy_on(frames[0])
    }
    fn moves(&self) -> bool {
        self.weight.moves() || any_moves(&self.centre_of_mass)
    }
}

impl Potential for GravityEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        self.energy_on(&self.frame.eval(x))
    }

    /// Gravity stores energy without deforming anything: it is lossless.
    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Vanishes
    }

    /// m g times the height of the centre of mass: linear in the point, so its gradient and
    /// Hessian are the weight times the point's first and second derivatives.
    fn fast_derivatives(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        let [frame] = at.frames else {
            return false;
        };
        // a frame whose local indices do not match its jet: the reference path answers
        if frame
            .check_jet("GravityEnergy::fast_derivatives", false)
            .is_err()
        {
            return false;
        }
        let (jet, a, n) = (frame.jet, &self.centre_of_mass, out.n);
        out.values[0] = jet.point(a)[2] * self.weight;
        for (&li, dp) in frame.local.iter().zip(jet.d_points(a)) {
            out.gradients[li] += dp[2] * self.weight;
        }
        if out.hessian {
            // on an error (buffers that do not fit the frame) the reference path answers
            if add_curvature(
                frame,
                Attached::Point(a),
                &Vector3::new(0.0, 0.0, self.weight),
                out.on,
                n,
            )
            .is_err()
            {
                return false;
            }
        }
        out.off_form = OffForm::Zero;
        true
    }
}

struct Gravity;

impl Element for Gravity {
    fn kind(&self) -> &'static str {
        "gravity"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "m g z of every massive body (lossless)"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        gravity_energies(reference, &new_frames(reference.system))
            .map(|term| {
                let (label, local, energy) = term?;
                Ok(Term::on_frames(
                    label,
                    "gravity",
                    GRAVITY_TAG,
                    local,
                    energy,
                ))
            })
            .collect()
    }
    fn tangent_terms(
        &self,
        reference: &Reference<Dual64>,
        shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        gravity_energies(reference, &shared_frames(reference.system, shared))
            .map(|term| {
                let (label, local, energy) = term?;
                Ok(TangentTerm::on_frames(
                    label,
                    "gravity",
                    GRAVITY_TAG,
                    local,
                    energy,
                ))
            })
            .collect::<Result<_, _>>()
            .map(Some)
    }
}

/// Where a kind's build takes the local frames of a set of bodies from.
type FramesOf<'a> = dyn Fn(&[BodyId]) -> Result<Arc<LocalFrames>, EnergyError> + 'a;

/// Local frames made anew (the `f64` terms).
fn new_frames<S: Constant>(
    system: &System<S>,
) -> impl Fn(&[BodyId]) -> Result<Arc<LocalFrames>, EnergyError> + '_ {
    move |bodies| LocalFrames::new(system, bodies).map(Arc::new)
}

/// Local frames shared by every term on the same bodies, and taken from another build of
/// the model where `shared` has them ([`SharedBodies::with_frames`]).
fn shared_frames<'a, S: Constant>(
    system: &'a System<S>,
    shared: &'a SharedBodies,
) -> impl Fn(&[BodyId]) -> Result<Arc<LocalFrames>, EnergyError> + 'a {
    move |bodies| shared.frames(system, bodies)
}

/// The gravity term of every body with mass (or whose mass moves with the parameter) that
/// `reference` keeps ([`Reference::keeps_body`]).
fn gravity_energies<'r, S: Constant>(
    reference: &'r Reference<'_, S>,
    frames_of: &'r FramesOf<'r>,
) -> impl Iterator<Item = Result<(String, Arc<LocalFrames>, GravityEnergy<S>), EnergyError>> + 'r {
    let system = reference.system;
    (0..system.bodies.len())
        .filter(|&b| !system.bodies[b].mass.is_exactly_zero() && reference.keeps_body(b))
        .map(move |b| {
            let body = &system.bodies[b];
            let local = frames_of(&[b])?;
            let energy = GravityEnergy {
                frame: local.frames[0].clone(),
                centre_of_mass: body.centre_of_mass,
                weight: body.mass * system.gravity,
            };
            Ok((term_label("gravity", &body.name), local, energy))
        })
}

/// Energy ½ k (l - l0)² of a wire's straight-line stretch between its attachment points.
#[derive(Clone, Debug)]
pub struct WireStretchEnergy<C = f64> {
    frames: [FrameMap; 2],
    points: [Vector3<C>; 2],
    /// k (N/m).
    stiffness: C,
    /// l0 (m).
    unstretched_length: C,
}

impl<C: Constant> WireStretchEnergy<C> {
    /// Chord length (m) at local coordinates `x`.
    pub fn length<D: Lift<C>>(&self, x: &[D]) -> D {
        self.length_between(&self.frames[0].eval(x), &self.frames[1].eval(x))
    }

    /// Chord length (m) with the end bodies at `f0`, `f1`.
    fn length_between<D: Lift<C>>(&self, f0: &Frame<D>, f1: &Frame<D>) -> D {
        let p0 = f0.point(&self.points[0]);
        let p1 = f1.point(&self.points[1]);
        (p1 - p0).map(|v| v * v).sum().sqrt()
    }

    /// ½ k (l − l0)² (J) with the end bodies at `f0`, `f1`.
    fn energy_on<D: Lift<C>>(&self, f0: &Frame<D>, f1: &Frame<D>) -> D {
        let stretch = self.length_between(f0, f1) - D::lift(self.unstretched_length);
        (stretch * stretch).times(self.stiffness * 0.5)
    }
}

impl TangentPotential for WireStretchEnergy<Dual64> {
    fn energy_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D {
        self.energy_on(frames[0], frames[1])
    }
    fn moves(&self) -> bool {
        self.stiffness.moves()
            || self.unstretched_length.moves()
            || self.points.iter().any(any_moves)
    }
}

impl Potential for WireStretchEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        self.energy_on(&self.frames[0].eval(x), &self.frames[1].eval(x))
    }

    /// With the tension off the wire is unstretched at its equilibrium length, so only
    /// first-order length changes store energy (docs/physics.md §2).
    fn tension_off(&self, x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Replaced(WireStretchEnergy {
            unstretched_length: self.length(x_eq),
            ..self.clone()
        })
    }

    /// Closed form on the chord c = p1 − p0 (l = |c|, u = c/l, s = l − l0): gradient
    /// k s u and Hessian k [u uᵀ + (s/l)(I − u uᵀ)] with respect to c, carried to the
    /// coordinates by the chain rule with the points' jets. With J the chord's Jacobian and
    /// a = Jᵀu: H = k [(1 − s/l) a aᵀ + (s/l) JᵀJ] + k s Σ_k u_k ∇²c_k. The tension-off
    /// wire, unstretched at this point, has s = 0: H_off = k a aᵀ, from the same pass.
    fn fast_derivatives(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        let [f0, f1] = at.frames else {
            return false;
        };
        let n = out.n;
        let [a0, a1] = &self.points;
        let (p0, p1) = (f0.jet.point(a0), f1.jet.point(a1));
        let chord = p1 - p0;
        let l = chord.norm();
        let u = chord / l;
        let k = self.stiffness;
        let s = l - self.unstretched_length;
        out.values[0] = 0.5 * k * s * s;
        let columns = out.scratch.zero_vectors(n);
        // on an error (buffers that do not fit the frames) the reference path answers
        if add_jacobian(f1, Attached::Point(a1), 1.0, columns).is_err()
            || add_jacobian(f0, Attached::Point(a0), -1.0, columns).is_err()
        {
            return false;
        }
        // the rounding of s = l − l0 is that of lengths of size |p0| + |p1| + l0
        let cancelled = k * (p0.norm() + p1.norm() + self.unstretched_length);
        for (i, col) in columns.iter().enumerate() {
            let a = col.dot(&u);
            out.gradients[i] = k * s * a;
            out.force_scales[i] = cancelled * a.abs();
        }
        if !out.hessian {
            return true;
        }
        let ratio = s / l;
        for i in 0..n {
            let ai = columns[i].dot(&u);
            for j in i..n {
                let aj = columns[j].dot(&u);
                let on = k * ((1.0 - ratio) * ai * aj + ratio * columns[i].dot(&columns[j]));
                let off = k * ai * aj;
                out.on[i * n + j] = on;
                out.on[j * n + i] = on;
                out.off[i * n + j] = off;
                out.off[j * n + i] = off;
            }
        }
        if add_curvature(f1, Attached::Point(a1), &(u * (k * s)), out.on, n).is_err()
            || add_curvature(f0, Attached::Point(a0), &(u * (-k * s)), out.on, n).is_err()
        {
            return false;
        }
        out.off_form = OffForm::Written;
        true
    }
}

struct WireStretch;

impl Element for WireStretch {
    fn kind(&self) -> &'static str {
        "wire-stretch"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "½ k (l - l0)² of each wire's chord length"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        reference
            .system
            .wires
            .iter()
            .map(|wire| {
                let (local, energy) =
                    wire_stretch_energy(reference, wire, &new_frames(reference.system))?;
                let label = term_label("wire-stretch", &wire.name);
                let tag = wire.tags.stretch.clone();
                Ok(Term::on_frames(label, "wire-stretch", tag, local, energy))
            })
            .collect()
    }
    fn tangent_terms(
        &self,
        reference: &Reference<Dual64>,
        shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        let frames_of = shared_frames(reference.system, shared);
        let wires = reference.system.wires.iter();
        let terms = wires.filter(|w| reference.keeps_wire(w)).map(|wire| {
            let (local, energy) = wire_stretch_energy(reference, wire, &frames_of)?;
            let label = term_label("wire-stretch", &wire.name);
            let tag = wire.tags.stretch.clone();
            Ok(TangentTerm::on_frames(
                label,
                "wire-stretch",
                tag,
                local,
                energy,
            ))
        });
        terms.collect::<Result<_, _>>().map(Some)
    }
}

/// The stretch energy of `wire`, which must have a positive length at the reference.
fn wire_stretch_energy<S: Constant>(
    reference: &Reference<S>,
    wire: &Wire<S>,
    frames_of: &FramesOf,
) -> Result<(Arc<LocalFrames>, WireStretchEnergy<S>), EnergyError> {
    let length = reference.wire_length(wire)?.re();
    if length.is_nan() || length <= 0.0 {
        return Err(EnergyError::ZeroLengthWire {
            wire: wire.name.clone(),
        });
    }
    let local = frames_of(&[wire.ends[0].body, wire.ends[1].body])?;
    let energy = WireStretchEnergy {
        frames: [local.frames[0].clone(), local.frames[1].clone()],
        points: [wire.ends[0].point, wire.ends[1].point],
        stiffness: wire.stiffness,
        unstretched_length: wire.unstretched_length,
    };
    Ok((local, energy))
}

/// Energy ½ Δᵀ K Δ + fᵀ Δ of a six-axis spring, Δ = (x, y, z, yaw, pitch, roll) of end 1's
/// attachment frame seen from end 0's.
#[derive(Clone, Debug)]
pub struct SpringEnergy<C: Constant = f64> {
    frames: [FrameMap; 2],
    ends: [SpringEnd<C>; 2],
    /// Each end's attachment rotation R(yaw, pitch, roll) of its fixed angles, worked out
    /// once here rather than per evaluation.
    turns: [Matrix3<C>; 2],
    stiffness: Matrix6<C>,
    preload: Vector6<C>,
}

impl<C: Constant> SpringEnergy<C> {
    /// Deflection Δ (m, rad) at local coordinates `x`.
    pub fn deflection<D: Lift<C>>(&self, x: &[D]) -> Vector6<D> {
        self.deflection_between(&self.frames[0].eval(x), &self.frames[1].eval(x))
    }

    /// Deflection Δ (m, rad) with the end bodies at `f0`, `f1`.
    fn deflection_between<D: Lift<C>>(&self, f0: &Frame<D>, f1: &Frame<D>) -> Vector6<D> {
        let attach = |k: usize| -> Frame<D> {
            let body = if k == 0 { f0 } else { f1 };
            let at_point = Frame {
                origin: body.point(&self.ends[k].point),
                rotation: body.rotation,
            };
            at_point.turned(&self.turns[k])
        };
        let rel = attach(0).relative(&attach(1));
        let [yaw, pitch, roll] = angles(&rel.rotation);
        Vector6::new(
            rel.origin[0],
            rel.origin[1],
            rel.origin[2],
            yaw,
            pitch,
            roll,
        )
    }

    /// ½ Δᵀ K Δ + fᵀ Δ for a deflection Δ.
    fn energy_of<D: Lift<C>>(&self, d: &Vector6<D>) -> D {
        let mut e = c::<D>(0.0);
        for i in 0..6 {
            e += d[i].times(self.preload[i]);
            for j in 0..6 {
                if !self.stiffness[(i, j)].is_exactly_zero() {
                    e += (d[i] * d[j]).times(self.stiffness[(i, j)] * 0.5);
                }
            }
        }
        e
    }
}

impl TangentPotential for SpringEnergy<Dual64> {
    fn energy_on_frames<D: Lift<Dual64>>(&self, frames: &[&Frame<D>]) -> D {
        self.energy_of(&self.deflection_between(frames[0], frames[1]))
    }
    fn moves(&self) -> bool {
        any_moves(&self.stiffness)
            || any_moves(&self.preload)
            || self
                .ends
                .iter()
                .any(|e| any_moves(&e.point) || any_moves(&e.angles))
    }
}

impl SpringEnergy {
    /// The fast path: Δ = (A0ᵀ(o1 − o0), angles(A0ᵀ A1)) with A_k = R_k R_att,k and o_k the
    /// attachment points; its first derivatives over the local coordinates from the two
    /// frames' jets by the product rule, its second derivatives pair by pair, and
    /// H = ∇Δᵀ K ∇Δ + Σ_m (K Δ + f)_m ∇²Δ_m; the tension-off spring (no preload) differs only
    /// in the weights K Δ of the curvature sum, so it comes from the same pass.
    #[expect(
        clippy::too_many_lines,
        reason = "one fused pass on the hot path: the first derivatives (dA, dd, dr, dM, ∇Δ, K∇Δ) \
                  live in slices split from `out.scratch` that the gradient and the pair-by-pair \
                  Hessian loops read in place; pieces would pass a dozen borrowed slices between them"
    )]
    fn jets(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        let [f0, f1] = at.frames else {
            return false;
        };
        let n = out.n;
        let turn = &self.turns;
        let frames = [f0, f1];
        // frames whose local indices do not match their jets: the reference path answers
        if frames
            .iter()
            .any(|f| f.check_jet("SpringEnergy::jets", out.hessian).is_err())
        {
            return false;
        }
        // attachment frames at the point
        let attach = |k: usize| frames[k].jet.rotation() * turn[k];
        let (a0, a1) = (attach(0), attach(1));
        let o: [Vector3<f64>; 2] =
            std::array::from_fn(|k| frames[k].jet.point(&self.ends[k].point));
        let d = o[1] - o[0];
        let r = a0.transpose() * d;
        let m = a0.transpose() * a1;
        let angle = angle_derivatives(&m);
        let (ga, ha) = (&angle.gradient, &angle.hessian);
        let [yaw, pitch, roll] = angles(&m);
        let delta = Vector6::new(r[0], r[1], r[2], yaw, pitch, roll);
        out.values[0] = self.energy_of(&delta);
        // first derivatives over the local coordinates: of A0, A1 (matrices), of d, and
        // from them of r and M, then of Δ
        let scratch = &mut *out.scratch;
        scratch.matrices.clear();
        scratch.matrices.resize(4 * n, Matrix3::zeros());
        scratch.vectors.clear();
        scratch.vectors.resize(2 * n, Vector3::zeros());
        let (da, dm) = scratch.matrices.split_at_mut(2 * n);
        let (dd, dr) = scratch.vectors.split_at_mut(n);
        for k in 0..2 {
            let f = frames[k];
            let sign = if k == 0 { -1.0 } else { 1.0 };
            let derivatives = f
                .jet
                .d_rotations()
                .iter()
                .zip(f.jet.d_points(&self.ends[k].point));
            for (&l, (dr, dp)) in f.local.iter().zip(derivatives) {
                da[k * n + l] = dr * turn[k];
                dd[l] += dp * sign;
            }
        }
        for l in 0..n {
            dr[l] = da[l].transpose() * d + a0.transpose() * dd[l];
            dm[l] = da[l].transpose() * a1 + a0.transpose() * da[n + l];
        }
        // ∇Δ (6 × n): rows 0..3 from r, rows 3..6 through the angles; and K ∇Δ (6 × n),
        // for the quadratic part of every Hessian entry
        scratch.numbers.clear();
        scratch.numbers.resize(12 * n, 0.0);
        let (grad_delta, k_grad) = scratch.numbers.split_at_mut(6 * n);
        for l in 0..n {
            for q in 0..3 {
                grad_delta[q * n + l] = dr[l][q];
                grad_delta[(3 + q) * n + l] =
                    (0..5).map(|e| ga[q][e] * dm[l][ANGLE_ENTRIES[e]]).sum();
            }
        }
        for p in 0..6 {
            for l in 0..n {
                k_grad[p * n + l] = (0..6)
                    .map(|q| self.stiffness[(p, q)] * grad_delta[q * n + l])
                    .sum();
            }
        }
        // the five entries of a matrix that the angles read
        let read = |m: &Matrix3<f64>| ANGLE_ENTRIES.map(|e| m[e]);
        let weights_on = self.stiffness * delta + self.preload;
        let weights_off = self.stiffness * delta;
        // rounding scale: Δ's translations are differences of points of size |o0| + |o1|
        let size = o[0].norm() + o[1].norm();
        for l in 0..n {
            let mut g = 0.0;
            let mut scale = 0.0;
            for q in 0..6 {
                let dq = grad_delta[q * n + l];
                g += weights_on[q] * dq;
                let spread = if q < 3 { size } else { 1.0 };
                let load: f64 = self.preload[q].abs()
                    + (0..6)
                        .map(|p| self.stiffness[(q, p)].abs() * (delta[p].abs() + spread))
                        .sum::<f64>();
                scale += dq.abs() * load;
            }
            out.gradients[l] = g;
            out.force_scales[l] = scale;
        }
        if !out.hessian {
            return true;
        }
        for a in 0..n {
            let at_a = [f0.position(a), f1.position(a)];
            for b in a..n {
                let at_b = [f0.position(b), f1.position(b)];
                // second derivatives of r = A0ᵀ d and M = A0ᵀ A1 at (a, b), product rule
                let mut ddr = Vector3::zeros();
                let mut ddm = Matrix3::zeros();
                // positions among `local`, which was checked against the jets above
                if let (Some(i), Some(j)) = (at_a[0], at_b[0]) {
                    let (Ok(dd_r0), Ok(dd_o0)) = (
                        f0.jet.dd_rotation(i, j),
                        f0.jet.dd_point(i, j, &self.ends[0].point),
                    ) else {
                        return false;
                    };
                    let dda0 = dd_r0 * turn[0];
                    ddr += dda0.transpose() * d - a0.transpose() * dd_o0;
                    ddm += dda0.transpose() * a1;
                }
                if let (Some(i), Some(j)) = (at_a[1], at_b[1]) {
                    let (Ok(dd_r1), Ok(dd_o1)) = (
                        f1.jet.dd_rotation(i, j),
                        f1.jet.dd_point(i, j, &self.ends[1].point),
                    ) else {
                        return false;
                    };
                    ddr += a0.transpose() * dd_o1;
                    ddm += a0.transpose() * (dd_r1 * turn[1]);
                }
                if at_a[0].is_some() {
                    ddr += da[a].transpose() * dd[b];
                    if at_b[1].is_some() {
                        ddm += da[a].transpose() * da[n + b];
                    }
                }
                if at_b[0].is_some() {
                    ddr += da[b].transpose() * dd[a];
                    if at_a[1].is_some() {
                        ddm += da[b].transpose() * da[n + a];
                    }
                }
                let mut dd_delta = [0.0; 6];
                let (ma, mb) = (read(&dm[a]), read(&dm[b]));
                for q in 0..3 {
                    dd_delta[q] = ddr[q];
                    let mut v = 0.0;
                    for e in 0..5 {
                        v += ga[q][e] * ddm[ANGLE_ENTRIES[e]];
                        let row: f64 = (0..5).map(|f| ha[q][e][f] * mb[f]).sum();
                        v += ma[e] * row;
                    }
                    dd_delta[3 + q] = v;
                }
                // ∇Δ_aᵀ K ∇Δ_b
                let quadratic: f64 = (0..6)
                    .map(|p| grad_delta[p * n + a] * k_grad[p * n + b])
                    .sum();
                let on = quadratic + (0..6).map(|q| weights_on[q] * dd_delta[q]).sum::<f64>();
                let off = quadratic + (0..6).map(|q| weights_off[q] * dd_delta[q]).sum::<f64>();
                out.on[a * n + b] = on;
                out.on[b * n + a] = on;
                out.off[a * n + b] = off;
                out.off[b * n + a] = off;
            }
        }
        out.off_form = OffForm::Written;
        true
    }
}

impl Potential for SpringEnergy {
    fn energy<D: Real>(&self, x: &[D]) -> D {
        self.energy_of(&self.deflection(x))
    }

    fn fast_derivatives(&self, at: &JetPoint, out: &mut Derivatives) -> bool {
        self.jets(at, out)
    }

    /// Without preload only the spring's own deformation stores energy.
    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self> {
        TensionOff::Replaced(SpringEnergy {
            preload: Vector6::zeros(),
            ..self.clone()
        })
    }
}

struct SpringKind;

impl Element for SpringKind {
    fn kind(&self) -> &'static str {
        "spring"
    }
    fn stage(&self) -> Stage {
        Stage::S0A
    }
    fn summary(&self) -> &'static str {
        "six-axis spring ½ Δᵀ K Δ + fᵀ Δ between two attachment frames"
    }
    fn terms(&self, reference: &Reference) -> Result<Vec<Term>, EnergyError> {
        spring_energies(reference, &new_frames(reference.system))
            .map(|term| {
                let (label, tag, local, energy) = term?;
                Ok(Term::on_frames(label, "spring", tag, local, energy))
            })
            .collect()
    }
    fn tangent_terms(
        &self,
        reference: &Reference<Dual64>,
        shared: &SharedBodies,
    ) -> Result<Option<Vec<TangentTerm>>, EnergyError> {
        spring_energies(reference, &shared_frames(reference.system, shared))
            .map(|term| {
                let (label, tag, local, energy) = term?;
                Ok(TangentTerm::on_frames(label, "spring", tag, local, energy))
            })
            .collect::<Result<_, _>>()
            .map(Some)
    }
}

/// The energy of every spring `reference` keeps ([`Reference::keeps_spring`]), with its
/// label and tag.
fn spring_energies<'r, S: Constant>(
    reference: &'r Reference<'_, S>,
    frames_of: &'r FramesOf<'r>,
) -> impl Iterator<Item = Result<SpringParts<S>, EnergyError>> + 'r {
    let system = reference.system;
    system
        .springs
        .iter()
        .filter(|s| reference.keeps_spring(s))
        .map(move |s| {
            let local = frames_of(&[s.ends[0].body, s.ends[1].body])?;
            let energy = SpringEnergy {
                frames: [local.frames[0].clone(), local.frames[1].clone()],
                ends: s.ends.clone(),
                turns: s.ends.each_ref().map(|e| {
                    let [yaw, pitch, roll] = e.angles;
                    rotation(yaw, pitch, roll)
                }),
                stiffness: s.stiffness,
                preload: s.preload,
            };
            Ok((term_label("spring", &s.name), s.tag.clone(), local, energy))
        })
}

/// A spring's term as [`spring_energies`] makes it: label, tag, frames and energy.
type SpringParts<S> = (String, String, Arc<LocalFrames>, SpringEnergy<S>);

crate::register_element!(Gravity);
crate::register_element!(WireStretch);
crate::register_element!(SpringKind);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{OffHessian, Spring, System};

    /// Two free bodies (12 coordinates) below a support driven by six parameters, each
    /// centre of mass off its body's origin (so that gravity's fast path turns it).
    fn two_bodies() -> System {
        let mut system =
            System::free_bodies(&[("support", 0.0), ("upper", 3.0), ("lower", 5.0)]).unwrap();
        for body in &mut system.bodies {
            body.centre_of_mass = Vector3::new(0.01, -0.02, 0.03);
        }
        system
    }

    /// Largest |fast − reference| relative to the reference's largest entry.
    fn mismatch(fast: &[f64], reference: &[f64]) -> f64 {
        let scale = reference.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let diff = fast
            .iter()
            .zip(reference)
            .fold(0.0f64, |a, (f, r)| a.max((f - r).abs()));
        diff / scale.max(f64::MIN_POSITIVE)
    }

    fn check(term: &Term, x: &[f64]) {
        let (fast, reference) = (
            term.derivatives(x).unwrap(),
            term.reference_derivatives(x).unwrap(),
        );
        assert!(
            (fast.value - reference.value).abs() <= 1e-13 * reference.value.abs().max(1e-3),
            "{}",
            term.label
        );
        assert!(
            mismatch(&fast.gradient, &reference.gradient) < 1e-12,
            "{}",
            term.label
        );
        let (on_fast, off_fast) = term.hessians(x, true).unwrap();
        let (on_ref, off_ref) = term.hessians(x, false).unwrap();
        assert!(
            mismatch(&on_fast, &on_ref) < 1e-12,
            "{}: {:e}",
            term.label,
            mismatch(&on_fast, &on_ref)
        );
        match (off_fast, off_ref) {
            (OffHessian::Matrix(f), OffHessian::Matrix(r)) => {
                assert!(
                    mismatch(&f, &r) < 1e-12,
                    "{} off: {:e}",
                    term.label,
                    mismatch(&f, &r)
                )
            }
            (f, r) => assert_eq!(f, r, "{}", term.label),
        }
    }

    #[test]
    fn core_kinds_fast_paths_match_the_hyper_dual_reference() {
        let mut system = two_bodies();
        system.wires.push(crate::Wire::from_tension(
            "w",
            [
                crate::WireEnd {
                    body: 1,
                    point: Vector3::new(0.1, 0.2, -0.05),
                    direction: crate::EndDirection::Auto,
                },
                crate::WireEnd {
                    body: 2,
                    point: Vector3::new(-0.05, 0.15, 0.04),
                    direction: crate::EndDirection::Auto,
                },
            ],
            crate::WireSection::round(3e-4, 2e11, 8e10, 7800.0),
            0.4,
            50.0,
            crate::WireTags {
                stretch: "s".into(),
                bending: "b".into(),
                torsion: "t".into(),
            },
        ));
        let mut stiffness =
            Matrix6::from_fn(|i, j| if i == j { 1e3 * (i + 1) as f64 } else { 0.0 });
        stiffness[(0, 4)] = 40.0;
        stiffness[(4, 0)] = 40.0;
        system.springs.push(Spring {
            name: "blade".into(),
            ends: [
                SpringEnd {
                    body: 0,
                    point: Vector3::new(0.0, 0.1, -0.1),
                    angles: [0.1, -0.2, 0.05],
                },
                SpringEnd {
                    body: 1,
                    point: Vector3::new(0.02, 0.0, 0.1),
                    angles: [0.0, 0.3, 0.0],
                },
            ],
            stiffness,
            preload: Vector6::new(1.0, -2.0, 30.0, 0.1, 0.2, -0.3),
            tag: "blade".into(),
        });
        // a configuration away from any equilibrium: bodies displaced and turned
        let x: Vec<f64> = (0..18)
            .map(|i| {
                let base = [
                    0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.01, -0.02, -0.3, 0.05, -0.03, 0.02, 0.03, 0.01,
                    -0.75, -0.04, 0.06, 0.1,
                ];
                base[i] + 1e-3 * ((i * 7 % 5) as f64 - 2.0)
            })
            .collect();
        let reference = Reference::new(&system, &x);
        for kind in [&Gravity as &dyn Element, &WireStretch, &SpringKind] {
            for term in kind.terms(&reference).unwrap() {
                check(&term, &x);
            }
        }
    }
}
