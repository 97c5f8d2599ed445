"""Local damping of the quad's top mass, closed with python-control by signal name.

pendkit exports the quad's state space (damping represented as viscous at 1 Hz) in LIGO's
names: inputs the ground's longitudinal motion `GND_L` (m) and the six forces and torques on
the top mass (`force:M0_L` ... `force:M0_R`, N or N m), outputs the test mass's
longitudinal displacement `L3_L` (m) and the top mass's six velocities (`M0_L_dot` ...,
states read as outputs, m/s or rad/s). python-control names them as identifiers
(`force:M0_L` is `force_M0_L`), so the loop closes by name: for each degree of freedom a
sensor adds its noise to the velocity (`M0_L_dot` + `noise_L` = `M0_L_meas`) and a
controller feeds back `force_M0_L` = -g_L `M0_L_meas`, a velocity damping whose gains
(`GAINS`) bring the modes the top mass moves to Q of a few to a few tens.

The sensor noise is a displacement sensor's, flat at `SENSOR_NOISE` (m/√Hz, and rad/√Hz in
the rotations), read as a velocity: 2πf times it. Its contribution at the test mass adds
the six sensors' in quadrature. The velocities are the state space's, inertial; a sensor on
the suspension's cage would also see the ground's motion, which this example leaves out.

    python examples/python/damping_loop.py

prints the modes' Q without and with the damping, the peaks of the test mass's response to
the ground at its longitudinal and pitch modes, and the sensors' noise at the test mass.
"""

from typing import Any, Dict, List, Tuple

import control
import numpy as np
import numpy.typing as npt

import pendkit

#: The top mass's degrees of freedom, in LIGO's order (M0_L, M0_T, ...).
DOFS = ("L", "T", "V", "Y", "P", "R")
#: Velocity-damping gains: N s/m for L, T, V; N m s/rad for Y, P, R (the top mass is
#: 22 kg, its moments of inertia 0.07 to 0.46 kg m²).
GAINS: Dict[str, float] = {"L": 100.0, "T": 100.0, "V": 100.0, "Y": 2.0, "P": 0.3, "R": 2.0}
#: The displacement sensors' flat noise (m/√Hz; rad/√Hz for Y, P, R).
SENSOR_NOISE = 1e-10


def plant(result: pendkit.Result, damping_frequency: float = 1.0) -> Any:
    """The quad as a python-control StateSpace: `GND_L` and the top mass's six forces in,
    `L3_L` and the top mass's six velocities out."""
    inputs = ["GND_L"] + [f"force:M0_{d}" for d in DOFS]
    outputs = ["L3_L"] + [f"M0_{d}_dot" for d in DOFS]
    return result.to_control(inputs, outputs, naming="ligo",
                             damping_frequency=damping_frequency, name="quad")


def damping(gains: Dict[str, float]) -> List[Any]:
    """Per degree of freedom, a sensor (velocity plus noise) and a velocity-damping
    controller, named so that `control.interconnect` connects them to the plant."""
    blocks = []
    for d in DOFS:
        blocks.append(control.summing_junction(
            inputs=[f"M0_{d}_dot", f"noise_{d}"], output=f"M0_{d}_meas", name=f"sensor_{d}"))
        blocks.append(control.ss([], [], [], [[-gains[d]]], inputs=[f"M0_{d}_meas"],
                                 outputs=[f"force_M0_{d}"], name=f"damp_{d}"))
    return blocks


def closed_loop(quad: Any, gains: Dict[str, float]) -> Any:
    """The damped quad: inputs `GND_L` and the six sensors' noises, output `L3_L`."""
    inputs = ["GND_L"] + [f"noise_{d}" for d in DOFS]
    return control.interconnect([quad, *damping(gains)], inplist=inputs, inputs=inputs,
                                outlist=["L3_L"], outputs=["L3_L"], name="damped")


def response(sys: Any, freqs: npt.ArrayLike) -> npt.NDArray[np.complex128]:
    """Frequency response, outputs × inputs × frequencies, at `freqs` (Hz)."""
    s = 2j * np.pi * np.asarray(freqs, dtype=float)
    return np.asarray(sys(s), dtype=complex).reshape(sys.noutputs, sys.ninputs, len(s))


def modes_q(sys: Any) -> Dict[float, float]:
    """The quality factor of each oscillating pole pair, by its frequency (Hz)."""
    poles = np.linalg.eigvals(sys.A)
    poles = poles[poles.imag > 0]
    return {float(p.imag / (2 * np.pi)): float(abs(p) / (-2 * p.real)) for p in poles}


def peaks(quad: Any, damped: Any, freqs: npt.ArrayLike,
          width: float = 0.01) -> List[Tuple[float, float]]:
    """The largest |L3_L / GND_L| of the open and of the closed loop within ±`width` (a
    fraction) of each of `freqs` (Hz), on a grid that holds both loops' resonances."""
    f = np.asarray(freqs, dtype=float)
    grid = np.unique(np.concatenate([
        np.geomspace(f.min() * (1 - width), f.max() * (1 + width), 4000),
        list(modes_q(quad)), list(modes_q(damped))]))
    h_open = np.abs(response(quad, grid)[0, 0])
    h_closed = np.abs(response(damped, grid)[0, 0])
    out = []
    for centre in f:
        band = (grid >= centre * (1 - width)) & (grid <= centre * (1 + width))
        out.append((float(h_open[band].max()), float(h_closed[band].max())))
    return out


def sensor_noise_at_test_mass(damped: Any, freqs: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The six sensors' noise at the test mass's L3_L (m/√Hz) at `freqs` (Hz): each
    sensor's velocity noise 2πf `SENSOR_NOISE` through its transfer to L3_L, added in
    quadrature."""
    f = np.asarray(freqs, dtype=float)
    h = response(damped, f)[0, 1:, :]  # L3_L from each noise input (s)
    velocity_noise = 2 * np.pi * f * SENSOR_NOISE
    return np.sqrt(np.sum(np.abs(h) ** 2, axis=0)) * velocity_noise


def main() -> None:
    result = pendkit.Model("quad").run()
    quad = plant(result)
    damped = closed_loop(quad, GAINS)
    stable = bool(np.all(np.linalg.eigvals(damped.A).real < 0))
    print(f"closed loop stable: {stable}")

    print("mode_hz,open_loop_q,closed_loop_hz,closed_loop_q")
    open_q, closed_q = modes_q(quad), modes_q(damped)
    for (f_open, q_open), (f_closed, q_closed) in zip(sorted(open_q.items()),
                                                      sorted(closed_q.items())):
        print(f"{f_open:.4f},{q_open:.4g},{f_closed:.4f},{q_closed:.3g}")

    # the test mass's response to the ground: its peaks at the modes it moves in
    print("mode_hz,family,open_loop_peak_m_per_m,closed_loop_peak_m_per_m")
    modes = result.modes(naming="ligo")
    for f, family, (a, b) in zip(modes.frequencies, modes.families,
                                 peaks(quad, damped, modes.frequencies)):
        if family in ("L", "P"):
            print(f"{f:.4f},{family},{a:.4g},{b:.4g}")

    freqs = pendkit.log_grid(0.1, 100.0, 7)
    noise = sensor_noise_at_test_mass(damped, freqs)
    print(f"sensor noise {SENSOR_NOISE:g} m/√Hz (rad/√Hz) at the test mass, L3_L:")
    print("freq_hz,asd_m_per_rthz")
    for f, n in zip(freqs, noise):
        print(f"{f:.4g},{n:.3e}")


if __name__ == "__main__":
    main()
