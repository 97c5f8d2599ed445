#!/usr/bin/env python3
"""Writes the springs model of docs/performance.md, "Large models":

    python3 benches/large_models.py springs N > springs-N.toml

N bodies of 1 kg moving along z only, each on a spring of its own from the ground, with
stiffnesses spread so that no two modes coincide. Past 10 000 bodies it needs
PENDKIT_MAX_BODIES raised (docs/cli.md). The large chain is `pendkit chain-file N` with
light bodies (`--set m=0.01 --set Ix=1.425e-4 --set Iy=1.05e-4 --set Iz=1.05e-4`).
"""
import sys


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
    sys.stdout.write({"springs": springs}[kind](n))
