//! Potential-energy terms: one generic energy body per term, wrapped so that a list of
//! terms of different kinds can be differentiated over each term's own coordinates.

use std::sync::Arc;

use num_dual::HyperDual64;
use pendkit_rotations::Real;

/// The energy of one term as a function of its own (local) coordinate vector, written once
/// for every scalar type.
pub trait Potential: Send + Sync + 'static {
    /// Potential energy (J) at local coordinates `x` (m or rad).
    fn energy<D: Real>(&self, x: &[D]) -> D;

    /// The term with static tensions and preloads switched off (stage 0B, DESIGN.md §4),
    /// given the equilibrium local coordinates. The default keeps the term as it is: all of
    /// its stiffness comes from first-order deformation and so carries its loss.
    fn tension_off(&self, _x_eq: &[f64]) -> TensionOff<Self>
    where
        Self: Sized,
    {
        TensionOff::Unchanged
    }
}

/// What a term becomes when static tensions are switched off.
#[derive(Clone, Debug)]
pub enum TensionOff<P> {
    /// Nothing depends on tension: the whole stiffness is lossy (bending, springs without
    /// preload, user terms).
    Unchanged,
    /// The term is pure work against a static load: the whole stiffness is lossless
    /// (gravity, wire extra stretch).
    Vanishes,
    /// A different term (a wire with l0 set to its equilibrium length, a spring without
    /// preload).
    Replaced(P),
}

/// Object-safe view of a [`Potential`]: the two scalar types the assembly uses (values and
/// hyper-dual second derivatives), so the set behind the trait object stays short.
trait DynPotential: Send + Sync {
    fn value(&self, x: &[f64]) -> f64;
    fn value_hd(&self, x: &[HyperDual64]) -> HyperDual64;
    fn tension_off(&self, x_eq: &[f64]) -> TensionOff<Arc<dyn DynPotential>>;
}

impl<P: Potential> DynPotential for P {
    fn value(&self, x: &[f64]) -> f64 {
        self.energy(x)
    }
    fn value_hd(&self, x: &[HyperDual64]) -> HyperDual64 {
        self.energy(x)
    }
    fn tension_off(&self, x_eq: &[f64]) -> TensionOff<Arc<dyn DynPotential>> {
        match Potential::tension_off(self, x_eq) {
            TensionOff::Unchanged => TensionOff::Unchanged,
            TensionOff::Vanishes => TensionOff::Vanishes,
            TensionOff::Replaced(p) => TensionOff::Replaced(Arc::new(p)),
        }
    }
}

/// Value, gradient and Hessian of one term over its own coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalDerivatives {
    /// Energy (J).
    pub value: f64,
    /// Gradient, one entry per local coordinate (N or N m).
    pub gradient: Vec<f64>,
    /// Hessian, row-major n × n (N/m, N, N m/rad).
    pub hessian: Vec<f64>,
}

/// One potential-energy term: an energy body, the global coordinates it reads, a damping
/// tag and a name for reports.
#[derive(Clone)]
pub struct Term {
    /// Human-readable name, e.g. `wire-stretch fibre1`.
    pub label: String,
    /// Kind of element that produced it, e.g. `wire-stretch`.
    pub kind: &'static str,
    /// Damping tag (DESIGN.md §4).
    pub tag: String,
    /// Global coordinate indices, in the order of the body's local vector.
    pub coords: Vec<usize>,
    body: Arc<dyn DynPotential>,
}

impl std::fmt::Debug for Term {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Term")
            .field("label", &self.label)
            .field("kind", &self.kind)
            .field("tag", &self.tag)
            .field("coords", &self.coords)
            .finish()
    }
}

impl Term {
    /// Wraps an energy body that reads the global coordinates `coords` (in order).
    pub fn new<P: Potential>(
        label: impl Into<String>,
        kind: &'static str,
        tag: impl Into<String>,
        coords: Vec<usize>,
        body: P,
    ) -> Self {
        Term {
            label: label.into(),
            kind,
            tag: tag.into(),
            coords,
            body: Arc::new(body),
        }
    }

    /// This term's coordinates picked out of a full coordinate vector.
    pub fn local(&self, x_global: &[f64]) -> Vec<f64> {
        self.coords.iter().map(|&i| x_global[i]).collect()
    }

    /// Energy (J) at the full coordinate vector `x_global`.
    pub fn energy(&self, x_global: &[f64]) -> f64 {
        self.body.value(&self.local(x_global))
    }

    /// Value, gradient and Hessian over the term's own coordinates, at the full coordinate
    /// vector `x_global`, by one hyper-dual evaluation per entry of the upper triangle.
    pub fn derivatives(&self, x_global: &[f64]) -> LocalDerivatives {
        let n = self.coords.len();
        let mut x: Vec<HyperDual64> = self
            .coords
            .iter()
            .map(|&i| HyperDual64::from_re(x_global[i]))
            .collect();
        let mut out = LocalDerivatives {
            value: self.body.value(&self.local(x_global)),
            gradient: vec![0.0; n],
            hessian: vec![0.0; n * n],
        };
        for i in 0..n {
            x[i].eps1 = 1.0;
            for j in i..n {
                x[j].eps2 = 1.0;
                let r = self.body.value_hd(&x);
                x[j].eps2 = 0.0;
                if j == i {
                    out.gradient[i] = r.eps1;
                }
                out.hessian[i * n + j] = r.eps1eps2;
                out.hessian[j * n + i] = r.eps1eps2;
            }
            x[i].eps1 = 0.0;
        }
        out
    }

    /// The term with static tensions switched off, at the equilibrium `x_eq_global`.
    pub fn tension_off(&self, x_eq_global: &[f64]) -> TensionOff<Term> {
        match self.body.tension_off(&self.local(x_eq_global)) {
            TensionOff::Unchanged => TensionOff::Unchanged,
            TensionOff::Vanishes => TensionOff::Vanishes,
            TensionOff::Replaced(body) => TensionOff::Replaced(Term {
                label: self.label.clone(),
                kind: self.kind,
                tag: self.tag.clone(),
                coords: self.coords.clone(),
                body,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E = a x² y + sin(x) y³, with a known gradient and Hessian.
    struct Cubic {
        a: f64,
    }

    impl Potential for Cubic {
        fn energy<D: Real>(&self, x: &[D]) -> D {
            x[0] * x[0] * x[1] * self.a + x[0].sin() * x[1].powi(3)
        }
    }

    #[test]
    fn derivatives_match_closed_form() {
        let t = Term::new("cubic", "test", "none", vec![2, 0], Cubic { a: 1.5 });
        // local (x, y) = (global[2], global[0])
        let (x, y) = (0.3, -0.7);
        let d = t.derivatives(&[y, 99.0, x]);
        let a = 1.5;
        let g = [
            2.0 * a * x * y + x.cos() * y.powi(3),
            a * x * x + 3.0 * x.sin() * y * y,
        ];
        let h = [
            2.0 * a * y - x.sin() * y.powi(3),
            2.0 * a * x + 3.0 * x.cos() * y * y,
            2.0 * a * x + 3.0 * x.cos() * y * y,
            6.0 * x.sin() * y,
        ];
        assert!((d.value - (a * x * x * y + x.sin() * y.powi(3))).abs() < 1e-15);
        for (got, want) in d.gradient.iter().zip(g).chain(d.hessian.iter().zip(h)) {
            assert!((got - want).abs() < 1e-14);
        }
    }
}
