//! Element kind `optical-spring`: the angular stiffness that the circulating light of a
//! Fabry–Perot cavity exerts on its two mirrors (Sidles & Sigg, Phys. Lett. A 354 (2006)
//! 167; Hirose et al., Appl. Opt. 49 (2010) 3474).
//!
//! A tilt of either mirror moves the cavity's optical axis, and so the spots where the
//! light presses on both mirrors; the force 2P/c at a spot off the mirror's centre is a
//! torque. For mirrors 1 and 2 (the instance's two bodies) with g-factors
//! g_i = 1 − L/R_i, tilts θ = (θ1, θ2) about one lab axis perpendicular to the cavity give
//! the torques τ = −K θ with
//!
//! ```text
//!     K = (2 P L / c) / (1 − g1 g2) · [ −g2   1 ]
//!                                     [  1  −g1 ]
//! ```
//!
//! the same for pitch (about the lab's y) and yaw (about z), the cavity along the lab's x
//! (either way round, and wherever the two suspensions stand: only the mirrors' rotations
//! enter). Its eigenvalues are the hard and soft stiffnesses
//! k = (P L / c) / (1 − g1 g2) · (−(g1 + g2) ± √((g1 − g2)² + 4)); for a cavity of negative
//! g-factors (aLIGO's arms) the hard one is positive and the soft one negative, which is
//! what destabilises the soft mode as the power grows.
//!
//! Conventions, and what is left out: θ_i is the rotation of mirror i from its orientation
//! at the equilibrium (where the cavity is taken to be aligned; the kind joins at stage 0B,
//! built around the equilibrium), read as the lab components of the rotation's
//! antisymmetric part, exact to the order of the stiffness. R_i > 0 is a mirror concave
//! towards the cavity. The static pressure 2P/c along the axis (which shifts the
//! equilibrium), the couplings of the mirrors' translations to the axis, and the cavity's
//! response time (the spring is the static one, exact well below the cavity pole) are not
//! modelled. The stiffness is lossless: it carries no mechanical loss into the thermal
//! noise.

use pendkit_energy::{Domain, InstanceAt, InstanceKind, InstanceSchema, PartOff, ValueField};
use pendkit_geometry::Frame;
use pendkit_rotations::{Constant, Lift};
use pendkit_system::Stage;

/// The speed of light (m/s, exact).
pub const SPEED_OF_LIGHT: f64 = 299_792_458.0;

/// The optical-spring element kind.
pub struct OpticalSpring;

/// One cavity: the diagonal and off-diagonal entries of K (N m/rad) and the mirrors'
/// orientations at the equilibrium.
#[derive(Clone, Debug)]
pub struct Cavity<C> {
    /// (2PL/c)/(1 − g1 g2) · (−g2, −g1): each mirror's own stiffness.
    own: [C; 2],
    /// (2PL/c)/(1 − g1 g2): the coupling.
    coupling: C,
    /// The mirrors' rotation matrices at the equilibrium, row-major.
    rest: [[C; 9]; 2],
}

/// The g-factors 1 − L/R of the two mirrors of a cavity of length `length` with radii of
/// curvature `roc` (m).
pub fn g_factors<C: Constant>(length: C, roc: [C; 2]) -> [C; 2] {
    roc.map(|r| C::from(1.0) - length / r)
}

/// The hard and soft angular stiffnesses (N m/rad; the eigenvalues of K), for power
/// `power` (W), length `length` (m) and g-factors `g`: the closed form of Sidles & Sigg.
pub fn hard_and_soft(power: f64, length: f64, g: [f64; 2]) -> [f64; 2] {
    let scale = power * length / SPEED_OF_LIGHT / (1.0 - g[0] * g[1]);
    let root = ((g[0] - g[1]).powi(2) + 4.0).sqrt();
    [
        scale * (-(g[0] + g[1]) + root),
        scale * (-(g[0] + g[1]) - root),
    ]
}

impl InstanceKind for OpticalSpring {
    const KIND: &'static str = "optical-spring";
    const STAGE: Stage = Stage::S0B;
    const SUMMARY: &'static str =
        "radiation-pressure angular stiffness between a cavity's two mirrors (pitch and yaw)";
    const SCHEMA: InstanceSchema = InstanceSchema {
        bodies: 2,
        points: 0,
        values: &[
            ValueField {
                name: "power",
                unit: "W",
                domain: Domain::NonNegative,
                default: None,
                description: "power circulating in the cavity",
            },
            ValueField {
                name: "length",
                unit: "m",
                domain: Domain::Positive,
                default: None,
                description: "cavity length",
            },
            ValueField {
                name: "roc1",
                unit: "m",
                domain: Domain::Finite,
                default: None,
                description: "radius of curvature of the first body's mirror (> 0: concave towards the cavity)",
            },
            ValueField {
                name: "roc2",
                unit: "m",
                domain: Domain::Finite,
                default: None,
                description: "radius of curvature of the second body's mirror",
            },
        ],
    };
    const TENSION_OFF: PartOff = PartOff::Vanishes;

    type Instance<C: Constant> = Cavity<C>;

    fn check(value: &dyn Fn(&str) -> f64) -> Result<(), String> {
        let g = g_factors(value("length"), [value("roc1"), value("roc2")]);
        let product = g[0] * g[1];
        if product > 0.0 && product < 1.0 {
            Ok(())
        } else {
            Err(format!(
                "the cavity is not stable: g1 g2 = {product} (g1 = {}, g2 = {}; g = 1 − length/roc) must lie in (0, 1)",
                g[0], g[1]
            ))
        }
    }

    fn instance<C: Constant>(at: &InstanceAt<'_, C>) -> Cavity<C> {
        let g = g_factors(at.value("length"), [at.value("roc1"), at.value("roc2")]);
        let one = C::from(1.0);
        let coupling =
            at.value("power") * at.value("length") * 2.0 / SPEED_OF_LIGHT / (one - g[0] * g[1]);
        let rest = |k: usize| {
            let r = &at.frame(k).rotation;
            std::array::from_fn(|i| r[(i / 3, i % 3)])
        };
        Cavity {
            own: [-(coupling * g[1]), -(coupling * g[0])],
            coupling,
            rest: [rest(0), rest(1)],
        }
    }

    fn energy<C: Constant, D: Lift<C>>(cavity: &Cavity<C>, frames: &[&Frame<D>]) -> D {
        // each mirror's rotation from its rest, ΔR = R R_restᵀ, and of it the lab
        // components about y (pitch) and z (yaw): the antisymmetric part's, (ΔR_xz − ΔR_zx)/2
        // and (ΔR_yx − ΔR_xy)/2
        let tilt = |k: usize| {
            let (r, rest) = (&frames[k].rotation, &cavity.rest[k]);
            let delta = |i: usize, j: usize| {
                r[(i, 0)].times(rest[3 * j])
                    + r[(i, 1)].times(rest[3 * j + 1])
                    + r[(i, 2)].times(rest[3 * j + 2])
            };
            [
                (delta(0, 2) - delta(2, 0)) * 0.5,
                (delta(1, 0) - delta(0, 1)) * 0.5,
            ]
        };
        let (t1, t2) = (tilt(0), tilt(1));
        // ½ θᵀ K θ about each axis
        (0..2)
            .map(|a| {
                (t1[a] * t1[a]).times(cavity.own[0] * 0.5)
                    + (t2[a] * t2[a]).times(cavity.own[1] * 0.5)
                    + (t1[a] * t2[a]).times(cavity.coupling)
            })
            .fold(D::from(0.0), |sum, e| sum + e)
    }
}

pendkit_energy::register_kind!(OpticalSpring);

#[cfg(test)]
mod tests {
    //! The kind's stiffness against the geometry it stands for, computed here by a second
    //! method: the cavity's axis is the line through the mirrors' centres of curvature
    //! (each mirror a sphere of radius R_i through its vertex), the light presses with 2P/c
    //! along it at the spots where it meets the mirrors, and the torque about each vertex
    //! is differentiated by central differences over the tilts. That fixes the sign of the
    //! coupling, which the eigenvalues alone do not.

    use super::*;
    use nalgebra::Vector3;
    use pendkit_energy::{Element, KindElement, Reference};
    use pendkit_system::{PluginElement, System};

    const L: f64 = 3994.5;
    const R: [f64; 2] = [1934.0, 2245.0];
    const P: f64 = 1e6;

    /// The pitch torques (N m, about the lab's y through each vertex) with the mirrors
    /// turned by `theta` (rad) about y: mirror 1 at the origin facing +x, mirror 2 at
    /// (L, 0, 0) facing −x.
    fn torques(theta: [f64; 2]) -> [f64; 2] {
        let turn = |t: f64, v: Vector3<f64>| {
            Vector3::new(
                v.x * t.cos() + v.z * t.sin(),
                v.y,
                -v.x * t.sin() + v.z * t.cos(),
            )
        };
        let vertex = [Vector3::zeros(), Vector3::new(L, 0.0, 0.0)];
        let facing = [Vector3::x(), -Vector3::x()];
        let centre: Vec<Vector3<f64>> = (0..2)
            .map(|k| vertex[k] + R[k] * turn(theta[k], facing[k]))
            .collect();
        let axis = (centre[1] - centre[0]).normalize();
        let force = 2.0 * P / SPEED_OF_LIGHT;
        std::array::from_fn(|k| {
            // the spot is where the axis meets the sphere on the vertex's side (the
            // axis crosses each sphere twice); the light pushes the mirror away from the
            // cavity, along the axis
            let [a, b] = [centre[k] + R[k] * axis, centre[k] - R[k] * axis];
            let spot = if (a - vertex[k]).norm() < (b - vertex[k]).norm() {
                a
            } else {
                b
            };
            let push = if axis.dot(&facing[k]) < 0.0 {
                axis
            } else {
                -axis
            };
            (spot - vertex[k]).cross(&(force * push)).y
        })
    }

    #[test]
    fn the_stiffness_is_the_geometric_torques_derivative() {
        let mut system =
            System::free_bodies(&[("support", 0.0), ("m1", 40.0), ("m2", 40.0)]).unwrap();
        let values = [("power", P), ("length", L), ("roc1", R[0]), ("roc2", R[1])];
        system.plugin_elements.push(PluginElement {
            kind: "optical-spring".into(),
            name: "arm".into(),
            bodies: vec![1, 2],
            points: vec![],
            values: values.iter().map(|(k, v)| (k.to_string(), *v)).collect(),
            tag: "radiation".into(),
        });
        let start = vec![0.0; 18];
        let terms = KindElement::<OpticalSpring>::NEW
            .terms(&Reference::new(&system, &start))
            .unwrap();
        let hessian = terms[0].derivatives(&start).unwrap().hessian;
        // local coordinates: m1's six, then m2's; pitch is the fifth of each
        let (n, pitch) = (12, [4, 10]);
        let h = 1e-7;
        for j in 0..2 {
            let mut up = [0.0; 2];
            let mut down = [0.0; 2];
            up[j] = h;
            down[j] = -h;
            let (tu, td) = (torques(up), torques(down));
            for i in 0..2 {
                // τ = −K θ in lab angles; the model's pitch may count the other way round
                // for both mirrors, which leaves the quadratic form as it is
                let geometric = -(tu[i] - td[i]) / (2.0 * h);
                let model = hessian[pitch[i] * n + pitch[j]];
                assert!(
                    (model - geometric).abs() <= 1e-6 * geometric.abs().max(1.0),
                    "K[{i}][{j}]: {model} from the kind, {geometric} from the geometry"
                );
            }
        }
        // and the eigenvalues are the closed form's
        let [hard, soft] = hard_and_soft(P, L, g_factors(L, R));
        let (a, b, c) = (
            hessian[pitch[0] * n + pitch[0]],
            hessian[pitch[1] * n + pitch[1]],
            hessian[pitch[0] * n + pitch[1]],
        );
        let mean = (a + b) / 2.0;
        let half = (((a - b) / 2.0).powi(2) + c * c).sqrt();
        assert!((mean + half - hard).abs() <= 1e-12 * hard.abs());
        assert!((mean - half - soft).abs() <= 1e-12 * hard.abs());
    }
}
