#!/usr/bin/env python3
"""Why the clamped-bead models' violin frequencies tend to another limit than the
continuum fibres' (docs/performance.md, "Violin modes"): one fibre held still at both
ends, modelled here independently of pendkit, both ways.

    python3 benches/violin_beads.py [--max-beads 2560]

Needs numpy, scipy and mpmath. Takes about a minute (the 2560-bead chains are dense
eigenproblems, which round to ~1e-8 of a frequency).

- The continuum: (EI w'')'' - (T w')' = mu w_tt, clamped at both ends, over the fibre's
  uniform pieces; the root of the clamped-clamped condition of the product of the pieces'
  exact transfer matrices (cosh, sinh, cos, sin), in 320-digit arithmetic (a silica
  fibre's boundary layer has kappa L ~ 600: e^600 does not fit a double), bisected. Its
  tension is one T (the test mass's share, as pendkit's continuum takes it), or with
  `weight` the fibre's own weight added below each point (the pieces cut in eight, each
  at the tension at its middle: the error is second order in the 2e-5 the weight adds).
- The beads as pendkit builds them (crates/description/model/src/beads.rs): N + 1 equal
  segments, each the exact static tensioned beam (solutions 1, x, e^-kx, e^-k(h-x))
  clamped to massless joints at the beads (their rotations condensed), a point mass at
  each bead (half of each neighbouring segment's mass), each segment carrying the bottom
  tension plus the weight of the beads below it. A tapered segment bends with one
  radius, as `add_beaded_fibre` gives it: an end segment its clamp's, an inner one its
  pieces' series radius (1/r^4 = sum (l_i/l)/r_i^4). `junction="exact"` instead chains
  the segment's pieces exactly; `weight=False` gives every segment the bottom tension.

It prints, for the 2005 quad (uniform fibres) and quad-aligo (tapered), the beads at 40,
80 and 160 (pendkit's own figures: `pendkit modes MODEL --set n_beads=N --below 1100`,
the lowest root of each cluster), their extrapolation (4 f160 - f80)/3, the beads up to
`--max-beads`, and how the difference between that extrapolation and the continuum splits.
"""
import argparse

import mpmath as mp
import numpy as np
from scipy.linalg import eigh

mp.mp.dps = 320

# (name, g m/s^2, test mass kg, profile [(length m, radius m)] from the top, Young Pa,
# density kg/m^3): models/ligo/quad.toml and quad-aligo.toml (fibres vertical, so each
# carries a quarter of the test mass's weight at its bottom)
MODELS = [
    ("quad (2005, uniform)", 9.81, 39.6, [(0.6, 2e-4)], 7e10, 2200.0),
    ("quad-aligo (tapered)", 9.80665, 39.6,
     [(0.045, 400e-6), (0.5, 205e-6), (0.045, 400e-6)], 7.2e10, 2200.0),
]


def transfer(length, ei, tension, mu, omega):
    """Transfer matrix of (w, w', EI w'', EI w''' - T w') over one uniform piece."""
    length, ei, tension, mu, omega = map(mp.mpf, (length, ei, tension, mu, omega))
    s = mp.sqrt(tension ** 2 + 4 * ei * mu * omega ** 2)
    kap, k = mp.sqrt((tension + s) / (2 * ei)), mp.sqrt((s - tension) / (2 * ei))

    def states(x):
        basis = [
            (mp.cosh(kap * x), kap * mp.sinh(kap * x), kap ** 2 * mp.cosh(kap * x),
             kap ** 3 * mp.sinh(kap * x)),
            (mp.sinh(kap * x), kap * mp.cosh(kap * x), kap ** 2 * mp.sinh(kap * x),
             kap ** 3 * mp.cosh(kap * x)),
            (mp.cos(k * x), -k * mp.sin(k * x), -k ** 2 * mp.cos(k * x),
             k ** 3 * mp.sin(k * x)),
            (mp.sin(k * x), k * mp.cos(k * x), -k ** 2 * mp.sin(k * x),
             -k ** 3 * mp.cos(k * x)),
        ]
        m = mp.matrix(4, 4)
        for j, (w, w1, w2, w3) in enumerate(basis):
            m[0, j], m[1, j], m[2, j] = w, w1, ei * w2
            m[3, j] = ei * w3 - tension * w1
        return m

    return states(length) * mp.inverse(states(0))


def continuum_root(pieces, guess):
    """The clamped-clamped root (Hz) near `guess` of pieces [(l, EI, T, mu)]."""
    def condition(f):
        p = mp.eye(4)
        for piece in pieces:
            p = transfer(*piece, 2 * mp.pi * mp.mpf(f)) * p
        # w(0) = w'(0) = 0: w(L) = w'(L) = 0 asks the 2 x 2 block to be singular
        return p[0, 2] * p[1, 3] - p[0, 3] * p[1, 2]

    a, b = guess * 0.995, guess * 1.005
    fa = condition(a)
    assert fa * condition(b) < 0, f"no root within 0.5 % of {guess}"
    for _ in range(64):
        m = (a + b) / 2
        if condition(m) * fa < 0:
            b = m
        else:
            a, fa = m, condition(m)
    return (a + b) / 2


def cut(profile, a, b):
    """The pieces (l, r) of `profile` between a and b (m from the top)."""
    out, start = [], 0.0
    for length, r in profile:
        lo, hi = max(a, start), min(b, start + length)
        if hi > lo:
            out.append((hi - lo, r))
        start += length
    return out


def continuum(model, weight, guesses):
    """The first clamped-clamped roots (Hz) of the continuum, with or without the fibre's
    own weight in the tension."""
    _, g, mass, profile, young, rho = model
    total = sum(length for length, _ in profile)
    pieces, start = [], 0.0
    for length, r in profile:
        parts = 8 if weight else 1
        for j in range(parts):
            mid = start + length * (j + 0.5) / parts
            below = sum(rho * np.pi * q * q * l for l, q in cut(profile, mid, total))
            tension = mass * g / 4 + (g * below if weight else 0.0)
            pieces.append((length / parts, young * np.pi * r ** 4 / 4, tension,
                           rho * np.pi * r * r))
        start += length
    return np.array([float(continuum_root(pieces, f)) for f in guesses])


def segment(length, ei, tension):
    """Static stiffness of a uniform tensioned beam over (w0, w0', w1, w1')."""
    k = np.sqrt(tension / ei)

    def at(x):
        a, b = np.exp(-k * x), np.exp(-k * (length - x))
        return (np.array([1, x, a, b]), np.array([0, 1, -k * a, k * b]),
                np.array([0, 0, k * k * a, k * k * b]),
                np.array([0, 0, -k ** 3 * a, k ** 3 * b]))

    w0, s0, c0, v0 = at(0.0)
    w1, s1, c1, v1 = at(length)
    values = np.array([w0, s0, w1, s1])
    forces = np.array([ei * v0 - tension * s0, -ei * c0, -ei * v1 + tension * s1, ei * c1])
    stiffness = forces @ np.linalg.inv(values)
    return (stiffness + stiffness.T) / 2


def condense(blocks):
    """Stiffness over the two ends of segments chained end to end (joints condensed)."""
    n = 2 * (len(blocks) + 1)
    k = np.zeros((n, n))
    for j, b in enumerate(blocks):
        k[2 * j:2 * j + 4, 2 * j:2 * j + 4] += b
    ends, inner = [0, 1, n - 2, n - 1], list(range(2, n - 2))
    if not inner:
        return k
    return k[np.ix_(ends, ends)] - k[np.ix_(ends, inner)] @ np.linalg.solve(
        k[np.ix_(inner, inner)], k[np.ix_(inner, ends)])


def beads(model, n, weight=True, junction="pendkit"):
    """The first two frequencies (Hz) of n clamped beads, both ends held."""
    _, g, mass, profile, young, rho = model
    total = sum(length for length, _ in profile)
    h = total / (n + 1)
    slices = [cut(profile, k * h, (k + 1) * h) for k in range(n + 1)]
    slice_mass = [sum(rho * np.pi * r * r * l for l, r in s) for s in slices]
    bead = [(slice_mass[k] + slice_mass[k + 1]) / 2 for k in range(n)]
    size = 2 * (n + 2)
    k_all = np.zeros((size, size))
    for k, s in enumerate(slices):
        tension = mass * g / 4 + (g * sum(bead[k:]) if weight else 0.0)
        if junction == "exact":
            block = condense([segment(l, young * np.pi * r ** 4 / 4, tension) for l, r in s])
        else:
            if k == 0:
                r = s[0][1]
            elif k == n:
                r = s[-1][1]
            else:
                r = (sum(l for l, _ in s) / sum(l / q ** 4 for l, q in s)) ** 0.25
            block = segment(h, young * np.pi * r ** 4 / 4, tension)
        k_all[2 * k:2 * k + 4, 2 * k:2 * k + 4] += block
    k_all = k_all[2:-2, 2:-2]
    w, t = np.arange(0, 2 * n, 2), np.arange(1, 2 * n, 2)
    kww = k_all[np.ix_(w, w)] - k_all[np.ix_(w, t)] @ np.linalg.solve(
        k_all[np.ix_(t, t)], k_all[np.ix_(t, w)])
    ev = eigh(kww, np.diag(bead), eigvals_only=True, subset_by_index=[0, 1])
    return np.sqrt(ev) / (2 * np.pi)


def richardson(fine, coarse):
    return (4 * fine - coarse) / 3


def study(model, max_beads):
    name, g, mass, profile, young, rho = model
    # the 160 beads lie within 1e-3 below the continuum: the roots' first guesses
    plain = continuum(model, False, beads(model, 160) * 1.002)
    heavy = continuum(model, True, plain)
    print(f"\n{name}")
    print(f"  continuum, one tension (pendkit's):  {plain[0]:.7f} {plain[1]:.7f} Hz")
    print(f"  continuum carrying its own weight:   {heavy[0]:.7f} {heavy[1]:.7f} Hz"
          f"  ({heavy[0] / plain[0] - 1:+.2e}, {heavy[1] / plain[1] - 1:+.2e})")
    print("  beads: N, f1, f2 (Hz), and relative to the continuum carrying its weight")
    counts = [n for n in (40, 80, 160, 320, 640, 1280, 2560) if n <= max_beads]
    pk = {}
    for n in counts:
        pk[n] = beads(model, n)
        print(f"  {n:5d} {pk[n][0]:.7f} {pk[n][1]:.7f}  "
              f"{pk[n][0] / heavy[0] - 1:+.2e} {pk[n][1] / heavy[1] - 1:+.2e}", flush=True)
    print("  (f80 - f40)/(f160 - f80):", (pk[80] - pk[40]) / (pk[160] - pk[80]))
    extrapolated = richardson(pk[160], pk[80])
    exact = richardson(*(beads(model, n, junction="exact") for n in (160, 80)))
    weightless = {n: beads(model, n, weight=False) for n in counts[-2:]}
    print(f"  without the weight, {counts[-1]} beads against the one-tension continuum:",
          weightless[counts[-1]] / plain - 1)
    if len(counts) >= 2 and counts[-1] >= 640:
        limit = richardson(pk[counts[-1]], pk[counts[-2]])
        print(f"  ({counts[-1]} and {counts[-2]} beads extrapolated) / weighted continuum - 1:",
              limit / heavy - 1)
    print("  (4 f160 - f80)/3 =", extrapolated, "Hz; continuum / it - 1 =", plain / extrapolated - 1)
    print("  extrapolation - continuum, split (relative, harmonics 1 and 2):")
    print("    the beads carry the fibre's weight:         ", heavy / plain - 1)
    print("    80/160 beads not yet converging as 1/N^2:    ", exact / heavy - 1)
    print("    one bending radius per tapered segment:      ", (extrapolated - exact) / heavy)
    print("    sum:                                          ", extrapolated / plain - 1)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--max-beads", type=int, default=2560,
                        help="largest bead count to follow the beads to (160 or more)")
    args = parser.parse_args()
    for model in MODELS:
        study(model, max(args.max_beads, 160))


if __name__ == "__main__":
    main()
