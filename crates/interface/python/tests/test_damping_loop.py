"""The damping-loop example (examples/python/damping_loop.py): python-control closes
velocity damping on the quad's top mass by signal name. Each check compares with a second
method: the open loop with pendkit's own `tf` (the complex stiffness solved directly, not
the state space); the closed loop with the loop algebra done by hand, in numpy, from the
plant's frequency response (python-control reduces the interconnection to one state space
and evaluates that instead) and, at the damping frequency, from pendkit's `tf` alone."""

import importlib
import sys

import numpy as np
import pytest

import pendkit

from conftest import REPO

control = pytest.importorskip("control")


def load_example():
    folder = str(REPO / "examples" / "python")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module("damping_loop")


example = load_example()
DOFS = example.DOFS
RESULT = pendkit.Model("quad").run()


def frequency_response(A, B, C, D, f):
    """C (sI - A)⁻¹ B + D at s = 2πi f, solved directly (outputs × inputs)."""
    s = 2j * np.pi * f
    return C @ np.linalg.solve(s * np.eye(A.shape[0]) - A, B) + D


def loop_by_hand(G, gains):
    """The closed loop's transfers to L3_L from G (rows L3_L then the six velocities,
    columns GND_L then the six forces): u = -K (v + n) gives
    L3_L/n = -G_Lu (I + K G_vu)⁻¹ K and L3_L/GND_L = G_Lg - G_Lu (I + K G_vu)⁻¹ K G_vg."""
    K = np.diag([gains[d] for d in DOFS])
    G_Lg, G_Lu, G_vg, G_vu = G[0, 0], G[0, 1:], G[1:, 0], G[1:, 1:]
    S_K = np.linalg.solve(np.eye(len(DOFS)) + K @ G_vu, K)
    return G_Lg - G_Lu @ S_K @ G_vg, -G_Lu @ S_K


def test_the_open_loop_through_control_is_pendkits_tf():
    # at s = 2πi f_d the state space with damping viscous at f_d is exactly the quad's
    # response (test_state_space.py): force to L3_L, and force to velocity = 2πi f times
    # the force-to-displacement tf; to 1e-9 of each column's largest entry
    for f_d in [0.5, 1.0, 3.0]:
        h = example.response(example.plant(RESULT, damping_frequency=f_d), [f_d])[:, :, 0]
        for j, d in enumerate(DOFS, start=1):
            force = f"force:M0_{d}"
            expected = np.array(
                [RESULT.tf(force, "L3_L", [f_d])[0]]
                + [2j * np.pi * f_d * RESULT.tf(force, f"M0_{e}", [f_d])[0] for e in DOFS])
            assert np.abs(h[:, j] - expected).max() <= 1e-9 * np.abs(expected).max(), (f_d, d)


def test_the_closed_loop_equals_the_loop_algebra_by_hand():
    quad = example.plant(RESULT)
    damped = example.closed_loop(quad, example.GAINS)
    assert damped.input_labels == ["GND_L"] + [f"noise_{d}" for d in DOFS]
    freqs = pendkit.log_grid(0.1, 30.0, 60)
    h = example.response(damped, freqs)[0]
    for k, f in enumerate(freqs):
        G = frequency_response(quad.A, quad.B, quad.C, quad.D, f)
        ground, noise = loop_by_hand(G, example.GAINS)
        assert abs(h[0, k] - ground) <= 1e-9 * abs(ground), f
        assert np.abs(h[1:, k] - noise).max() <= 1e-9 * np.abs(noise).max(), f
        # the example's noise budget is these six transfers in quadrature
        expected = np.sqrt(np.sum(np.abs(noise) ** 2)) * 2 * np.pi * f * example.SENSOR_NOISE
        got = example.sensor_noise_at_test_mass(damped, [f])[0]
        assert abs(got - expected) <= 1e-9 * expected


def test_the_sensor_noise_transfer_from_pendkits_tf_alone():
    # at the damping frequency the plant is pendkit's tf (above), so the loop algebra on
    # tf's numbers gives the noise transfer with no state space at all
    for f_d in [0.7, 2.0]:
        damped = example.closed_loop(example.plant(RESULT, damping_frequency=f_d),
                                     example.GAINS)
        G = np.zeros((7, 7), dtype=complex)
        for j, d in enumerate(DOFS, start=1):
            force = f"force:M0_{d}"
            G[0, j] = RESULT.tf(force, "L3_L", [f_d])[0]
            for i, e in enumerate(DOFS, start=1):
                G[i, j] = 2j * np.pi * f_d * RESULT.tf(force, f"M0_{e}", [f_d])[0]
        _, noise = loop_by_hand(G, example.GAINS)
        h = example.response(damped, [f_d])[0, 1:, 0]
        assert np.abs(h - noise).max() <= 1e-9 * np.abs(noise).max(), f_d


def test_the_damping_is_stable_and_lowers_the_peaks():
    quad = example.plant(RESULT)
    damped = example.closed_loop(quad, example.GAINS)
    assert np.all(np.linalg.eigvals(damped.A).real < 0)
    # with the gains negated the same loop pumps energy in: the check can fail
    undamped = example.closed_loop(quad, {d: -g for d, g in example.GAINS.items()})
    assert np.any(np.linalg.eigvals(undamped.A).real > 0)
    modes = RESULT.modes()
    coupled = [f for f, family in zip(modes.frequencies, modes.families)
               if family in ("L", "P")]
    peaks = example.peaks(quad, damped, coupled)
    for f, (open_peak, closed_peak) in zip(coupled, peaks):
        assert closed_peak < open_peak, f
    # the highest resonance of the test mass's response to the ground falls a
    # thousandfold and more (Q of 10⁵ to Q of tens)
    assert max(c for _, c in peaks) < 1e-3 * max(o for o, _ in peaks)
