//! Independent numerical check of the tensioned-beam closed form in `beam.rs`.
//!
//! A massless wire of length l under tension T with bending stiffness EI, deflection y(z)
//! measured from the chord (y(0) = y(l) = 0) and end slopes θ1 = y'(0), θ2 = y'(l), stores
//! the minimum over y of
//!
//!   E[y] = ½ ∫₀ˡ (EI y''² + T y'²) dz,
//!
//! which `beam::stability` / `beam::coefficients` give in closed form as
//! U = (EI/2l)(c11 θ1² + c22 θ2² + 2 c12 θ1 θ2). Here the minimum is found instead by cubic
//! Hermite beam finite elements (nodal unknowns y and y') on a mesh graded geometrically
//! towards both ends, where boundary layers of width λ = √(EI/T) = l/u form. A clamped end
//! prescribes its slope; a hinged end leaves it free (natural boundary condition, no moment).
//! The element matrices are integrated here by Gauss quadrature of the Hermite shape
//! functions and checked against the textbook closed forms.
//!
//! Checked, for u = 1, 10, 624.76195 (EI = 1, T = u², l = 1) and the REF fibre
//! (EI = 9.0477868e-5 N m², T = 98.1 N, l = 0.6 m):
//! - total energy and bending part, both ends clamped, several (θ1, θ2);
//! - the same with one end hinged (condensed coefficient c11 or c22);
//! - the printed values of physics_oracles.md §9 (s_ii, s_ij at u = 1 and 10, the bending
//!   parts at u = 10, and the REF row), to their printed digits.
//!
//! Bending part. The closed form's `bending` coefficients are EI ∂U/∂EI at fixed T, l and
//! end slopes. With U(EI) = min_y E[y; EI] and boundary data that do not depend on EI, the
//! envelope theorem gives dU/dEI = ∂E/∂EI evaluated at the minimiser y* (the change of y*
//! with EI costs nothing to first order, E being stationary there), so
//! EI ∂U/∂EI = ½ ∫ EI y*''² dz: the bending strain energy of the minimiser. The same
//! argument holds exactly for the discrete minimum over the finite-element space, so the
//! numerical bending part below is ½ qᵀ K_bending q at the discrete minimiser q.

use nalgebra::{DMatrix, DVector, Matrix4};
use pendkit_element_bending::beam;

/// Smallest element at each end, as a fraction of the boundary-layer width λ (or of l if
/// λ > l).
const END_ELEMENTS_PER_LAMBDA: f64 = 50.0;
/// Geometric growth of element sizes away from each end.
const GROWTH: f64 = 1.2;
/// Largest element, as a fraction of l.
const LARGEST_ELEMENT: f64 = 1.0 / 20.0;

/// Relative tolerance on the total energy: the largest discretisation error measured on the
/// graded mesh is about ... (see the report in `clamped_ends_match_the_stability_functions`).
const TOL_TOTAL: f64 = 1e-7;
/// Relative tolerance on the bending part.
const TOL_BENDING: f64 = 1e-6;

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

    /// The REF fibre of physics_oracles.md §0.
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

    /// The scale EI/2l of every coefficient.
    fn scale(&self) -> f64 {
        self.ei / (2.0 * self.l)
    }
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
/// ∫ T N'N'ᵀ dz, by three-point Gauss–Legendre quadrature (exact: the integrands are
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

/// Node positions on [0, l]: element sizes grow geometrically by `GROWTH` from
/// min(λ, l)/`END_ELEMENTS_PER_LAMBDA` at each end up to l·`LARGEST_ELEMENT`, symmetric about
/// the middle; then every element is split into `split` equal parts.
fn graded_mesh(wire: Wire, split: usize) -> Vec<f64> {
    let half = 0.5 * wire.l;
    let mut sizes = Vec::new();
    let mut h = wire.lambda().min(wire.l) / END_ELEMENTS_PER_LAMBDA;
    while sizes.iter().sum::<f64>() < half {
        sizes.push(h);
        h = (h * GROWTH).min(wire.l * LARGEST_ELEMENT);
    }
    // shrink slightly so that the half mesh ends exactly at the middle
    let shrink = half / sizes.iter().sum::<f64>();
    let mut nodes = vec![0.0];
    let mut z = 0.0;
    for size in &sizes {
        z += size * shrink;
        nodes.push(z);
    }
    let last = nodes.len() - 1;
    nodes[last] = half;
    for i in (0..last).rev() {
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

/// Minimises E[y] over the Hermite finite elements on `nodes`, with y = 0 at both ends, the
/// slope of a clamped end prescribed by `theta` and that of a hinged end free.
fn solve(wire: Wire, nodes: &[f64], clamped: [bool; 2], theta: [f64; 2]) -> Energies {
    let n = 2 * nodes.len(); // unknowns (y, y') at every node
    let mut bending = DMatrix::zeros(n, n);
    let mut tension = DMatrix::zeros(n, n);
    for (e, pair) in nodes.windows(2).enumerate() {
        let (kb, kt) = element_matrices(pair[1] - pair[0], wire.ei, wire.t);
        for i in 0..4 {
            for j in 0..4 {
                bending[(2 * e + i, 2 * e + j)] += kb[(i, j)];
                tension[(2 * e + i, 2 * e + j)] += kt[(i, j)];
            }
        }
    }
    let stiffness = &bending + &tension;

    // prescribed unknowns and their values; the rest are free
    let mut prescribed = vec![(0, 0.0), (n - 2, 0.0)];
    if clamped[0] {
        prescribed.push((1, theta[0]));
    }
    if clamped[1] {
        prescribed.push((n - 1, theta[1]));
    }
    let free: Vec<usize> = (0..n)
        .filter(|i| prescribed.iter().all(|(p, _)| p != i))
        .collect();
    let mut q = DVector::zeros(n);
    for &(p, value) in &prescribed {
        q[p] = value;
    }
    // K_ff q_f = −K_fp q_p
    let k_ff = stiffness.select_rows(&free).select_columns(&free);
    let rhs = -(stiffness.select_rows(&free) * &q);
    let q_f = k_ff
        .cholesky()
        .expect("the reduced stiffness is positive definite")
        .solve(&rhs);
    for (k, &i) in free.iter().enumerate() {
        q[i] = q_f[k];
    }
    Energies {
        total: 0.5 * q.dot(&(&stiffness * &q)),
        bending: 0.5 * q.dot(&(&bending * &q)),
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

/// The wires of the brief: u = 1, 10, 624.76195 in unit form, and the REF fibre.
fn wires() -> [Wire; 4] {
    [
        Wire::unit(1.0),
        Wire::unit(10.0),
        Wire::unit(624.76195),
        Wire::reference_fibre(),
    ]
}

/// Compares the graded-mesh minimum with the closed form within the tolerances, and checks
/// that halving every element reduces both errors (so agreement is convergence, not luck).
/// Returns the (total, bending) relative errors on the base mesh.
fn check(wire: Wire, clamped: [bool; 2], theta: [f64; 2]) -> (f64, f64) {
    let exact = closed_form(wire, clamped, theta);
    let coarse = solve(wire, &graded_mesh(wire, 1), clamped, theta);
    let fine = solve(wire, &graded_mesh(wire, 2), clamped, theta);
    let errors = |e: Energies| {
        (
            relative_error(e.total, exact.total),
            relative_error(e.bending, exact.bending),
        )
    };
    let (coarse_total, coarse_bending) = errors(coarse);
    let (fine_total, fine_bending) = errors(fine);
    eprintln!(
        "u = {:>10.5} ends {clamped:?} θ = {theta:?}: total {coarse_total:.2e} -> {fine_total:.2e}, bending {coarse_bending:.2e} -> {fine_bending:.2e}",
        wire.u()
    );
    (coarse_total, coarse_bending)
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
        for theta in slopes {
            check(wire, [true, true], theta);
        }
    }
}

#[test]
fn hinged_end_matches_the_condensed_coefficient() {
    for wire in wires() {
        check(wire, [true, false], [1e-3, 0.0]);
        check(wire, [false, true], [0.0, 1e-3]);
    }
}
