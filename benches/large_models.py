#!/usr/bin/env python3
"""Writes the large suspension files of issue 38 (docs/performance.md, "Large models"):

    python3 benches/large_models.py chain N > chain-N.toml    # N light bodies in a chain
    python3 benches/large_models.py springs N > springs-N.toml  # N one-DOF bodies, each on its own spring

The chain is `pendkit chain-file`'s (four vertical steel wires per stage) with 10 g bodies,
so that a chain of 10 000 stages keeps its top wires elastic (0.3 GPa); the springs are N
bodies of 1 kg moving along z only, each on a spring of its own from the ground, with
stiffnesses spread so that no two modes coincide. Both need the size limits raised
(PENDKIT_MAX_COORDINATES, PENDKIT_MAX_WIRES, PENDKIT_MAX_BODIES; docs/cli.md).
"""
import sys


def chain(n):
    out = [f"""# {n}-stage chain of light bodies (benches/large_models.py)
name = "chain-light"
summary = "{n} 10 g bodies in a vertical chain, each on 4 vertical steel wires"
gravity = "g"

[parameters]
g = {{ value = 9.81, unit = "m/s^2", description = "gravitational acceleration" }}
m = {{ value = 0.01, unit = "kg", description = "mass of each body" }}
Ix = {{ value = 1.425e-4, unit = "kg m^2", description = "moment of inertia about x (the chain's, scaled with the mass)" }}
Iy = {{ value = 1.05e-4, unit = "kg m^2", description = "moment of inertia about y" }}
Iz = {{ value = 1.05e-4, unit = "kg m^2", description = "moment of inertia about z" }}
l_wire = {{ value = 0.6, unit = "m", description = "wire length" }}
a_wire = {{ value = 0.005, unit = "m", description = "half x-separation of the wires" }}
b_wire = {{ value = 0.17, unit = "m", description = "half y-separation of the wires" }}
d_top = {{ value = 0.010, unit = "m", description = "height of the wires from above over a body's centre of mass" }}
d_bottom = {{ value = 0.010, unit = "m", description = "depth of the wires to the body below" }}
r_wire = {{ value = 0.5e-3, unit = "m", description = "wire radius" }}
E_wire = {{ value = 212e9, unit = "Pa", description = "Young's modulus of steel" }}
nu_wire = {{ value = 0.29, unit = "-", description = "Poisson's ratio of steel" }}
rho_wire = {{ value = 7800, unit = "kg/m^3", description = "density of steel" }}
phi_wire = {{ value = 1e-7, unit = "rad", description = "loss angle of the wires" }}

[materials.steel]
youngs_modulus = "E_wire"
poisson_ratio = "nu_wire"
density = "rho_wire"
loss_angle = "phi_wire"

[bodies.support]
coordinates = "00"
driven = true
"""]
    for k in range(1, n + 1):
        out.append(f"""
[bodies.mass{k}]
coordinates = "{k}"
mass = "m"
inertia = ["Ix", "Iy", "Iz"]
""")
    for k in range(1, n + 1):
        upper_z = "0" if k == 1 else '"-d_bottom"'
        out.append(f"""
[stages.mass{k}]
from = "{'support' if k == 1 else f'mass{k - 1}'}"
[stages.mass{k}.wires]
name = "wire{k}_"
upper = {{ at = ["a_wire", "b_wire", {upper_z}], mirror = ["y", "x"] }}
lower = {{ at = ["a_wire", "b_wire", "d_top"], mirror = ["y", "x"] }}
length = "l_wire"
radius = "r_wire"
material = "steel"
tags = "wire"
""")
    return "".join(out)


def springs(n):
    out = [f"""# {n} one-DOF bodies, each on its own spring (benches/large_models.py)
name = "springs"
summary = "{n} 1 kg bodies moving along z, each on a spring from the ground"
gravity = 0

[parameters]
m = {{ value = 1, unit = "kg", description = "mass of each body" }}
k = {{ value = 1000, unit = "N/m", description = "stiffness of the first spring; body i's is k (1 + i/N)" }}

[bodies.ground]
coordinates = "g"
driven = true
"""]
    for i in range(1, n + 1):
        out.append(f"""
[bodies.b{i}]
coordinates = "{i}"
dof = "z"
mass = "m"

[stages.b{i}]
from = "ground"
springs = {{ name = "k{i}", stiffness = [0, 0, "k*(1 + {i}/{n})", 0, 0, 0], tag = "spring" }}
""")
    return "".join(out)


if __name__ == "__main__":
    kind, n = sys.argv[1], int(sys.argv[2])
    sys.stdout.write({"chain": chain, "springs": springs}[kind](n))
