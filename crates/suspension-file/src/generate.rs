//! Suspension files written by a program: `chain`, any number of identical rigid bodies one
//! below the other, each on four vertical steel wires (`pendkit chain-file N`;
//! the bundled `chain` rewrites itself for its parameter `n_stages`).

use std::fmt::Write as _;

/// Largest number of chain stages: 1200 variables, where the dense eigen-solves already take
/// seconds (their cost grows as the cube of the size).
pub const MAX_CHAIN_STAGES: usize = 200;

/// The text of an `n`-stage chain: the rigid-body model's 40 kg body, `n` times, each on four
/// vertical 0.6 m steel wires (the double pendulum's) at (±a, ±b), `d_top` above its centre of
/// mass to the body above and `d_bottom` below it to the body below. Exactly symmetric (every
/// wire vertical, bodies level and centred on the z axis), so the stiffness splits into the
/// x–pitch, y–roll, z and yaw blocks with exact zeros between them.
pub fn chain(n: usize) -> String {
    let mut out = format!(
        r#"# {n}-stage chain, written by `pendkit chain-file {n}`: a suspension
# whose size is a parameter of its generator, for scaling benchmarks (6 variables and
# 4 wires per stage). Edit freely; docs/suspension-files.md describes every field.
name = "chain"
summary = "{n} 40 kg bodies in a vertical chain, each on 4 vertical steel wires"
gravity = "g"

[parameters]
g = {{ value = 9.81, unit = "m/s^2", description = "gravitational acceleration" }}
m = {{ value = 40, unit = "kg", description = "mass of each body (the rigid-body model's)" }}
Ix = {{ value = 0.57, unit = "kg m^2", description = "moment of inertia about x (roll)" }}
Iy = {{ value = 0.42, unit = "kg m^2", description = "moment of inertia about y (pitch)" }}
Iz = {{ value = 0.42, unit = "kg m^2", description = "moment of inertia about z (yaw)" }}
l_wire = {{ value = 0.6, unit = "m", description = "wire length between attachment points (the small models')" }}
a_wire = {{ value = 0.005, unit = "m", description = "half x-separation of the wires (the rigid-body model's fibres)" }}
b_wire = {{ value = 0.17, unit = "m", description = "half y-separation of the wires (the body's radius)" }}
d_top = {{ value = 0.010, unit = "m", description = "height of the wires from above over a body's centre of mass (the rigid-body model's break-off: low, stable pitch modes)" }}
d_bottom = {{ value = 0.010, unit = "m", description = "depth of the wires to the body below under a body's centre of mass" }}
# The double pendulum's steel wires. A wire of stage k carries (N - k + 1) m g / 4: 0.5 GPa
# at the top of a 4-stage chain, a third of a music wire's breaking stress. Long chains
# overload their top wires (12.5 GPa at 100 stages); the model stays linear-elastic, which is
# what a scaling benchmark needs, but it is then no design.
r_wire = {{ value = 0.5e-3, unit = "m", description = "wire radius (music wire)" }}
E_wire = {{ value = 212e9, unit = "Pa", description = "Young's modulus of steel" }}
nu_wire = {{ value = 0.29, unit = "-", description = "Poisson's ratio of steel" }}
rho_wire = {{ value = 7800, unit = "kg/m^3", description = "density of steel" }}
phi_wire = {{ value = 1e-7, unit = "rad", description = "loss angle of the wires (as the small models' fibres, so that the models compare)" }}

[materials.steel]
youngs_modulus = "E_wire"
poisson_ratio = "nu_wire"
density = "rho_wire"
loss_angle = "phi_wire"

[bodies.support]
coordinates = "00"
driven = true
"#
    );
    for k in 1..=n {
        let _ = write!(
            out,
            r#"
[bodies.mass{k}]
coordinates = "{k}"
mass = "m"
inertia = ["Ix", "Iy", "Iz"]
"#
        );
    }
    for k in 1..=n {
        let (from, upper_z) = if k == 1 {
            ("support".to_string(), "0")
        } else {
            (format!("mass{}", k - 1), "\"-d_bottom\"")
        };
        let _ = write!(
            out,
            r#"
[stages.mass{k}]
from = "{from}"
[stages.mass{k}.wires]
name = "wire{k}_"
upper = {{ at = ["a_wire", "b_wire", {upper_z}], mirror = ["y", "x"] }}
lower = {{ at = ["a_wire", "b_wire", "d_top"], mirror = ["y", "x"] }}
length = "l_wire"
radius = "r_wire"
material = "steel"
tags = "wire"
"#
        );
    }
    out
}
