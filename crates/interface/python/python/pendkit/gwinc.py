"""A drop-in for pygwinc's suspension thermal noise, computed by pendkit's 3-D quad.

pygwinc (0.6) computes the suspension thermal noise of one test mass with
``gwinc.noise.suspensionthermal.suspension_thermal(f, sus, sustf)``: a 1-D chain of
longitudinal and vertical stages, with the vertical noise coupled to the beam line by the
angle ``theta`` between local verticals at the two ends of an arm. :func:`suspension_thermal`
here has the same inputs and output, so a pygwinc budget can use pendkit's model of the
quad instead (``examples/python/gwinc_budget.py`` shows a whole aLIGO budget with it).
"""

from functools import lru_cache
from typing import Any, Optional, Sequence, Tuple

import numpy as np

from ._pendkit import Model

#: The bundled pendkit model used unless ``model=`` says otherwise: the aLIGO test-mass
#: quad as built (pygwinc 0.6.2's numbers, tapered fibres, surface and blade losses).
DEFAULT_MODEL = "quad-aligo"
#: The test-mass coordinates of the bundled quads: longitudinal (along the beam) and
#: vertical displacement of the test mass (LIGO names L3_L and L3_V).
LONGITUDINAL, VERTICAL = "x3", "z3"


@lru_cache(maxsize=16)
def _stage(model: str, sets: Tuple[str, ...], stage: str):
    # runs of the same model and overrides are shared between calls (a budget calls once
    # per frequency array, and sweeps over temperature reuse nothing else)
    return Model(model, set=list(sets)).run(stage)


def _get(struct: Any, *path: str) -> Optional[Any]:
    """``struct.a.b`` for ``path = ("a", "b")``, or None where a field is missing (gwinc
    structs are attribute objects)."""
    for name in path:
        if struct is None:
            return None
        try:
            struct = getattr(struct, name)
        except AttributeError:
            try:
                struct = struct[name]
            except (KeyError, TypeError, IndexError):
                return None
    return struct


def suspension_thermal(
    f: np.ndarray,
    sus: Any = None,
    sustf: Any = None,
    *,
    model: str = DEFAULT_MODEL,
    set: Optional[Sequence[str]] = None,
    stage: str = "2",
) -> np.ndarray:
    """Suspension thermal noise of one suspension: the displacement PSD of the test mass
    along the beam line (m²/Hz) at the frequencies ``f`` (Hz), as pygwinc 0.6's
    ``gwinc.noise.suspensionthermal.suspension_thermal(f, sus, sustf)``.

    Computed by pendkit's 3-D quad (the bundled model ``model``, default ``"quad-aligo"``, at
    ``stage``, default 2: every wire and fibre with stretch, bending and torsion losses and
    dissipation dilution), not from pygwinc's 1-D chain: **the suspension's parameters come
    from pendkit's model, not from** ``sus``, except these, mapped where present:

    - ``sus.Temp`` (K) sets pendkit's ``temperature`` parameter;
    - ``sustf.VHCoupling.theta`` (rad; else ``sus.VHCoupling.theta``, else 0) couples the
      vertical noise to the beam line as pygwinc does: PSD = S_L + θ² S_V, with S_L and S_V
      pendkit's thermal noise of the test mass's longitudinal and vertical displacement
      (``x3``, ``z3``; their correlation, which pygwinc also ignores, left out).

    ``set`` adds pendkit parameter overrides ("NAME=EXPR" strings, e.g. ``["m3=50"]``) after
    those. ``sus`` and ``sustf`` may be None (then nothing is mapped).
    """
    freqs = np.asarray(f, dtype=float)
    sets = []
    temperature = _get(sus, "Temp")
    if temperature is not None:
        sets.append(f"temperature={float(temperature)!r}")
    sets.extend(set or [])
    theta = _get(sustf, "VHCoupling", "theta")
    if theta is None:
        theta = _get(sus, "VHCoupling", "theta")
    theta = 0.0 if theta is None else float(theta)
    result = _stage(model, tuple(sets), stage)
    psd = result.noise(LONGITUDINAL, freqs.ravel()).psd
    if theta != 0.0:
        psd = psd + theta**2 * result.noise(VERTICAL, freqs.ravel()).psd
    return psd.reshape(freqs.shape)
