"""The element kinds shipped in the repository are linked into the Python package.

examples/two-mirrors.toml couples two spring-held rigid mirrors by the optical spring
(elements/optical-spring). Reference: the closed form of the rigid-mirror limit, each
angular pair's modes ω² = (k + λ)/I with λ the cavity's hard and soft stiffnesses
(P L / c)/(1 − g1 g2) · (−(g1 + g2) ± √((g1 − g2)² + 4)) (Sidles & Sigg 2006), evaluated
here. Tolerance 1e-9 relative: the model is exactly this linear system.
"""

import math

import pendkit

from conftest import REPO

TWO_MIRRORS = str(REPO / "examples" / "two-mirrors.toml")


def closed_form_hz(power):
    length, r1, r2, c = 3994.5, 1934.0, 2245.0, 299_792_458.0
    g1, g2 = 1 - length / r1, 1 - length / r2
    scale = power * length / c / (1 - g1 * g2)
    root = math.sqrt((g1 - g2) ** 2 + 4)
    hard, soft = scale * (-(g1 + g2) + root), scale * (-(g1 + g2) - root)
    hz = lambda k, inertia: math.sqrt(k / inertia) / (2 * math.pi)
    # pitch (k 1000 N m/rad, I 0.4 kg m²) and yaw (800, 0.5); translations and roll twice
    angular = [
        hz(1000 + hard, 0.4),
        hz(1000 + soft, 0.4),
        hz(800 + hard, 0.5),
        hz(800 + soft, 0.5),
    ]
    others = [hz(2000, 40), hz(3000, 40), hz(5000, 40), hz(700, 0.3)] * 2
    return sorted(angular + others)


def test_the_optical_spring_reaches_python():
    modes = pendkit.Model(TWO_MIRRORS, set={"power": 1e6}).run().modes()
    got, expected = sorted(modes.frequencies), closed_form_hz(1e6)
    assert len(got) == len(expected)
    for f, want in zip(got, expected):
        assert abs(f - want) <= 1e-9 * want, (f, want)
