//! Independent numerical check of the tensioned-beam closed form in `beam.rs`.
//!
//! A massless wire of length l under tension T with bending stiffness EI, deflection y(z)
//! measured from the chord (y(0) = y(l) = 0) and end slopes θ1 = y'(0), θ2 = y'(l), stores
//! the minimum over y of
//!
//!   E[y] = ½ ∫₀ˡ (EI y''² + T y'²) dz,
//!
//! which `beam::coefficients` gives in closed form as
//!
//!   U = (EI/2l)(c11 θ1² + c22 θ2² + 2 c12 θ1 θ2).
//!
//! Here the minimum is found instead with cubic Hermite beam finite elements
//! (nodal unknowns y and y') on a mesh graded towards both ends, where boundary layers of
//! width λ = √(EI/T) = l/u form. A clamped end prescribes its slope; a hinged end leaves it
//! free (natural boundary condition: no end moment). The element matrices are integrated
//! here by Gauss quadrature of the Hermite shape functions and checked against the textbook
//! forms.
//!
//! Checked, for u = 1, 10, 624.76195 (EI = 1, T = u², l = 1) and the REF fibre of
//! docs/reference-values.md §0 (EI = 9.0477868e-5 N m², T = 98.1 N, l = 0.6 m):
//! - total energy and bending part with both ends clamped, for several (θ1, θ2);
//! - the same with one end hinged (the condensed coefficient c11 or c22);
//! - the printed values of docs/reference-values.md §9 (s_ii, s_ij at u = 1 and 10, their bending
//!   parts at u = 10, the REF row), to their printed digits;
//! - that the discrete minimum bounds the closed form from above and converges to it as h⁴
//!   when every element is halved, so the agreement is convergence, not coincidence.
//!
//! Bending part. The closed form's `bending` coefficients are EI ∂U/∂EI at fixed T, l and
//! end slopes. With U(EI) = min_y E[y; EI] and boundary data that do not depend on EI, the
//! envelope theorem gives dU/dEI = ∂E/∂EI at the minimiser y* (E is stationary there, so
//! the change of y* with EI costs nothing to first order): EI ∂U/∂EI = ½ ∫ EI y*''² dz, the
//! bending strain energy of the minimiser. The argument holds as well for the discrete
//! minimum over the finite-element space, so the numerical bending part is ½ qᵀ K_b q at the
//! discrete minimiser q. (It would not hold at a shape that is not the minimiser.)

use nalgebra::{Cholesky, DMatrix, DVector, Dyn, Matrix4, Vector4};
use pendkit_element_bending::beam;

/// Smallest element at each end, as a fraction of λ (or of l if λ > l).
const END_ELEMENTS_PER_LAMBDA: f64 = 50.0;
/// Largest element, as a fraction of l.
const LARGEST_ELEMENT: f64 = 1.0 / 20.0;

/// Relative tolerance on the total energy and on its bending part. On the base mesh the
/// discretisation errors measured are at most 5.2e-10 (total) and 6.5e-10 (bending), and
/// halving every element divides them by about 16 (h⁴ convergence), so they are truncation,
/// not round-off; the tolerance leaves a factor of 3 above that.
const TOLERANCE: f64 = 2e-9;

/// A wire: bending stiffness EI (N m²), tension T (N), length l (m).
#[derive(Clone, Copy, Debug)]
struct Wire {
    ei: f64,
    t: f64,
    l: f64,
}

impl Wire {
    /// EI = 1, l = 1 and T = u², so that the tension parameter is `u`.
    fn unit(u: f64) -> Self {
        Wire {
            ei: 1.0,
            t: u * u,
            l: 1.0,
        }
    }

    /// The REF fibre of docs/reference-values.md §0 (u = 624.76195).
    fn reference_fibre() -> Self {
        Wire {
            ei: 9.0477868e-5,
            t: 98.1,
            l: 0.6,
        }
    }

    /// Tension parameter u = l √(T/EI).
    fn u(&self) -> f64 {
        self.l * (self.t / self.ei).sqrt()
    }

    /// Boundary-layer width λ = √(EI/T).
    fn lambda(&self) -> f64 {
        (self.ei / self.t).sqrt()
    }

    /// The factor EI/2l in front of every coefficient.
    fn scale(&self) -> f64 {
        self.ei / (2.0 * self.l)
    }
}

/// The wires of the test: u = 1, 10, 624.76195 in unit form, and the REF fibre.
fn wires() -> [Wire; 4] {
    [
        Wire::unit(1.0),
        Wire::unit(10.0),
        Wire::unit(624.76195),
        Wire::reference_fibre(),
    ]
}

/// Total energy and its bending-strain part (J).
#[derive(Clone, Copy, Debug)]
struct Energies {
    total: f64,
    bending: f64,
}

/// Slopes and curvatures of the four cubic Hermite shape functions of an element of length
/// `h` at ξ = (z − z_a)/h ∈ [0, 1], for the unknowns (y_a, y'_a, y_b, y'_b):
/// N = [1 − 3ξ² + 2ξ³, h(ξ − 2ξ² + ξ³), 3ξ² − 2ξ³, h(−ξ² + ξ³)].
fn hermite_derivatives(xi: f64, h: f64) -> ([f64; 4], [f64; 4]) {
    let slope = [
        (-6.0 * xi + 6.0 * xi * xi) / h,
        1.0 - 4.0 * xi + 3.0 * xi * xi,
        (6.0 * xi - 6.0 * xi * xi) / h,
        -2.0 * xi + 3.0 * xi * xi,
    ];
    let curvature = [
        (-6.0 + 12.0 * xi) / (h * h),
        (-4.0 + 6.0 * xi) / h,
        (6.0 - 12.0 * xi) / (h * h),
        (-2.0 + 6.0 * xi) / h,
    ];
    (slope, curvature)
}

/// Element bending stiffness ∫ EI N''N''ᵀ dz and geometric (tension) stiffness
/// ∫ T N'N'ᵀ dz, by three-point Gauss–Legendre quadrature (exact here: the integrands are
/// polynomials of degree ≤ 4).
fn element_matrices(h: f64, ei: f64, t: f64) -> (Matrix4<f64>, Matrix4<f64>) {
    let a = 0.5 * (3.0f64 / 5.0).sqrt();
    let gauss = [
        (0.5 - a, 5.0 / 18.0),
        (0.5, 8.0 / 18.0),
        (0.5 + a, 5.0 / 18.0),
    ];
    let mut bending = Matrix4::zeros();
    let mut tension = Matrix4::zeros();
    for (xi, w) in gauss {
        let (slope, curvature) = hermite_derivatives(xi, h);
        for i in 0..4 {
            for j in 0..4 {
                bending[(i, j)] += w * h * ei * curvature[i] * curvature[j];
                tension[(i, j)] += w * h * t * slope[i] * slope[j];
            }
        }
    }
    (bending, tension)
}

/// Node positions on [0, l], symmetric about the middle. From each end the element size
/// grows as h(z) = h₀ e^(2z/5λ), h₀ = min(λ, l)/`END_ELEMENTS_PER_LAMBDA`, up to
/// l·`LARGEST_ELEMENT`. (An element's energy error is about h⁵ y''''², and y'''' decays as
/// e^(−z/λ) into the wire; this growth minimises the summed error for a given number of
/// elements.) Then every element is split into `split` equal parts.
fn graded_mesh(wire: Wire, split: usize) -> Vec<f64> {
    let half = 0.5 * wire.l;
    let lambda = wire.lambda();
    let smallest = lambda.min(wire.l) / END_ELEMENTS_PER_LAMBDA;
    let mut sizes = Vec::new();
    let mut z = 0.0;
    while z < half {
        let h = (smallest * (0.4 * z / lambda).exp()).min(wire.l * LARGEST_ELEMENT);
        sizes.push(h);
        z += h;
    }
    // shrink slightly so that the half mesh ends exactly at the middle, then mirror it
    let shrink = half / z;
    let mut nodes = vec![0.0];
    for size in &sizes {
        nodes.push(nodes[nodes.len() - 1] + size * shrink);
    }
    let middle = nodes.len() - 1;
    nodes[middle] = half;
    for i in (0..middle).rev() {
        nodes.push(wire.l - nodes[i]);
    }
    let mut refined = vec![0.0];
    for pair in nodes.windows(2) {
        for k in 1..=split {
            refined.push(pair[0] + (pair[1] - pair[0]) * k as f64 / split as f64);
        }
    }
    refined
}

/// The finite-element problem for one wire, mesh and pair of end conditions, factorised once
/// for all end slopes.
struct Discretisation {
    /// (bending, tension) stiffness of every element.
    elements: Vec<(Matrix4<f64>, Matrix4<f64>)>,
    clamped: [bool; 2],
    /// Unknowns not fixed by the boundary conditions.
    free: Vec<usize>,
    /// Cholesky factor of the stiffness restricted to the free unknowns.
    factor: Cholesky<f64, Dyn>,
}

impl Discretisation {
    /// Assembles and factorises. Unknowns: (y, y') at every node in order. y = 0 at both
    /// ends; the slope of a clamped end is prescribed, that of a hinged end is free.
    fn new(wire: Wire, nodes: &[f64], clamped: [bool; 2]) -> Self {
        let elements: Vec<_> = nodes
            .windows(2)
            .map(|pair| element_matrices(pair[1] - pair[0], wire.ei, wire.t))
            .collect();
        let n = 2 * nodes.len();
        let mut stiffness = DMatrix::zeros(n, n);
        for (e, (bending, tension)) in elements.iter().enumerate() {
            let k = bending + tension;
            for i in 0..4 {
                for j in 0..4 {
                    stiffness[(2 * e + i, 2 * e + j)] += k[(i, j)];
                }
            }
        }
        let fixed =
            |i: usize| i == 0 || i == n - 2 || (i == 1 && clamped[0]) || (i == n - 1 && clamped[1]);
        let free: Vec<usize> = (0..n).filter(|&i| !fixed(i)).collect();
        let factor = stiffness
            .select_rows(&free)
            .select_columns(&free)
            .cholesky()
            .expect("the stiffness of the free unknowns is positive definite");
        Discretisation {
            elements,
            clamped,
            free,
            factor,
        }
    }

    /// Unknowns of element `e`, less the element's mean deflection. Neither element matrix
    /// sees a rigid translation, and removing it avoids cancellation: in a boundary layer y
    /// is of order θλ but changes by only about θh across an element, so products with the
    /// global vector would lose a factor (λ/h)³ of precision.
    fn local(q: &DVector<f64>, e: usize) -> Vector4<f64> {
        let mean = 0.5 * (q[2 * e] + q[2 * e + 2]);
        Vector4::new(
            q[2 * e] - mean,
            q[2 * e + 1],
            q[2 * e + 2] - mean,
            q[2 * e + 3],
        )
    }

    /// The gradient K q of the energy, assembled element by element.
    fn gradient(&self, q: &DVector<f64>) -> DVector<f64> {
        let mut gradient = DVector::zeros(q.len());
        for (e, (bending, tension)) in self.elements.iter().enumerate() {
            let force = (bending + tension) * Self::local(q, e);
            for i in 0..4 {
                gradient[2 * e + i] += force[i];
            }
        }
        gradient
    }

    /// The minimum energy and its bending part for end slopes `theta` (a hinged end's entry
    /// is ignored).
    fn minimise(&self, theta: [f64; 2]) -> Energies {
        let n = 2 * (self.elements.len() + 1);
        let mut q = DVector::zeros(n);
        if self.clamped[0] {
            q[1] = theta[0];
        }
        if self.clamped[1] {
            q[n - 1] = theta[1];
        }
        // Newton steps on the free unknowns. The first one solves the quadratic problem; the
        // second is one step of iterative refinement, with the gradient computed accurately
        // (see `local`): the factorised assembled matrix is only good to about 1e-9 in the
        // solution, which the bending part, first order in that error, would show.
        for _ in 0..2 {
            let step = self
                .factor
                .solve(&-self.gradient(&q).select_rows(&self.free));
            for (k, &i) in self.free.iter().enumerate() {
                q[i] += step[k];
            }
        }
        let mut energies = Energies {
            total: 0.0,
            bending: 0.0,
        };
        for (e, (bending, tension)) in self.elements.iter().enumerate() {
            let local = Self::local(&q, e);
            let bending = 0.5 * local.dot(&(bending * local));
            energies.bending += bending;
            energies.total += bending + 0.5 * local.dot(&(tension * local));
        }
        energies
    }
}

/// The closed form of `beam::coefficients` for the same wire, ends and slopes.
fn closed_form(wire: Wire, clamped: [bool; 2], theta: [f64; 2]) -> Energies {
    let (total, bending) = beam::coefficients(wire.u(), clamped);
    let quadratic = |c: beam::Coefficients<f64>| {
        wire.scale()
            * (c.c11 * theta[0] * theta[0]
                + c.c22 * theta[1] * theta[1]
                + 2.0 * c.c12 * theta[0] * theta[1])
    };
    Energies {
        total: quadratic(total),
        bending: quadratic(bending),
    }
}

fn relative_error(numerical: f64, exact: f64) -> f64 {
    ((numerical - exact) / exact).abs()
}

/// For every slope pair: the base-mesh minimum matches the closed form within `TOLERANCE`;
/// the minima on the base and the halved mesh bound it from above (nested spaces), the
/// error of the total falling by at least 8 (h⁴ convergence gives 16); the bending error
/// falls too.
fn check(wire: Wire, clamped: [bool; 2], slopes: &[[f64; 2]]) {
    let base = Discretisation::new(wire, &graded_mesh(wire, 1), clamped);
    let halved = Discretisation::new(wire, &graded_mesh(wire, 2), clamped);
    for &theta in slopes {
        let exact = closed_form(wire, clamped, theta);
        let (coarse, fine) = (base.minimise(theta), halved.minimise(theta));
        let total = [coarse, fine].map(|e| relative_error(e.total, exact.total));
        let bending = [coarse, fine].map(|e| relative_error(e.bending, exact.bending));
        let case = format!("u = {}, ends {clamped:?}, θ = {theta:?}", wire.u());
        eprintln!(
            "{case}: total error {:.1e} -> {:.1e}, bending error {:.1e} -> {:.1e}",
            total[0], total[1], bending[0], bending[1]
        );
        assert!(total[0] < TOLERANCE && bending[0] < TOLERANCE, "{case}");
        assert!(
            coarse.total > fine.total && fine.total > exact.total,
            "{case}"
        );
        assert!(total[1] < total[0] / 8.0, "{case}");
        assert!(bending[1] < bending[0], "{case}");
    }
}

/// Total and bending coefficients (c11, c22, c12) from three numerical minima, by
/// polarisation: c11 = U(1, 0)/s, c22 = U(0, 1)/s, c12 = [U(1, 1) − U(1, 0) − U(0, 1)]/2s
/// with s = EI/2l.
fn numerical_coefficients(wire: Wire) -> ([f64; 3], [f64; 3]) {
    let problem = Discretisation::new(wire, &graded_mesh(wire, 1), [true, true]);
    let [first, second, both] = [[1.0, 0.0], [0.0, 1.0], [1.0, 1.0]].map(|t| problem.minimise(t));
    let coefficients = |part: fn(&Energies) -> f64| {
        let s = wire.scale();
        [
            part(&first) / s,
            part(&second) / s,
            (part(&both) - part(&first) - part(&second)) / (2.0 * s),
        ]
    };
    (coefficients(|e| e.total), coefficients(|e| e.bending))
}

/// `value` rounds to `printed`, which has `decimals` digits after the point, within the
/// discretisation tolerance: the REF fibre's s_ij = 1.00321149997 lies only 3e-11 below a
/// rounding edge of its printed 1.003211.
fn agrees_to_printed_digits(value: f64, printed: f64, decimals: i32) -> bool {
    (value - printed).abs() <= 0.5 * 10f64.powi(-decimals) + TOLERANCE * printed.abs()
}

#[test]
fn element_matrices_match_the_textbook_forms() {
    let (h, ei, t) = (0.37, 2.5, 7.0);
    let (bending, tension) = element_matrices(h, ei, t);
    let h2 = h * h;
    #[rustfmt::skip]
    let textbook_bending = Matrix4::new(
        12.0,    6.0 * h,  -12.0,    6.0 * h,
        6.0 * h, 4.0 * h2, -6.0 * h, 2.0 * h2,
        -12.0,   -6.0 * h, 12.0,     -6.0 * h,
        6.0 * h, 2.0 * h2, -6.0 * h, 4.0 * h2,
    ) * (ei / (h * h2));
    #[rustfmt::skip]
    let textbook_tension = Matrix4::new(
        36.0,    3.0 * h,  -36.0,    3.0 * h,
        3.0 * h, 4.0 * h2, -3.0 * h, -h2,
        -36.0,   -3.0 * h, 36.0,     -3.0 * h,
        3.0 * h, -h2,      -3.0 * h, 4.0 * h2,
    ) * (t / (30.0 * h));
    assert!((bending - textbook_bending).norm() < 1e-13 * textbook_bending.norm());
    assert!((tension - textbook_tension).norm() < 1e-13 * textbook_tension.norm());
}

#[test]
fn clamped_ends_match_the_stability_functions() {
    let slopes = [[1e-3, 0.0], [0.0, 1e-3], [1e-3, 1e-3], [1e-3, -2e-3]];
    for wire in wires() {
        check(wire, [true, true], &slopes);
    }
}

#[test]
fn hinged_end_matches_the_condensed_coefficient() {
    for wire in wires() {
        check(wire, [true, false], &[[1e-3, 0.0]]);
        check(wire, [false, true], &[[0.0, 1e-3]]);
    }
}

#[test]
fn printed_oracle_values_are_reproduced() {
    // docs/reference-values.md §9: s_ii, s_ij at u = 1
    let ([s_ii, s_jj, s_ij], _) = numerical_coefficients(Wire::unit(1.0));
    assert!(agrees_to_printed_digits(s_ii, 4.131623, 6), "{s_ii}");
    assert!(agrees_to_printed_digits(s_jj, 4.131623, 6), "{s_jj}");
    assert!(agrees_to_printed_digits(s_ij, 1.967670, 6), "{s_ij}");

    // u = 10 (EI = 1 N m², T = 100 N, l = 1 m), and the bending parts of (EI/l) s_ii and
    // (EI/l) s_ij
    let ([s_ii, _, s_ij], [b_ii, _, b_ij]) = numerical_coefficients(Wire::unit(10.0));
    assert!(agrees_to_printed_digits(s_ii, 11.24974, 5), "{s_ii}");
    assert!(agrees_to_printed_digits(s_ij, 1.248837, 6), "{s_ij}");
    assert!(agrees_to_printed_digits(b_ii, 6.404669, 6), "{b_ii}");
    assert!(agrees_to_printed_digits(b_ij, 1.399674, 6), "{b_ij}");

    // REF fibre, u = 624.762: s_ii, s_ij and (EI/l) s_ii in N m
    let wire = Wire::reference_fibre();
    let ([s_ii, _, s_ij], _) = numerical_coefficients(wire);
    assert!(agrees_to_printed_digits(s_ii, 625.7652, 4), "{s_ii}");
    assert!(agrees_to_printed_digits(s_ij, 1.003211, 6), "{s_ij}");
    let moment = wire.ei / wire.l * s_ii;
    assert!(agrees_to_printed_digits(moment, 0.09436316, 8), "{moment}");
}
