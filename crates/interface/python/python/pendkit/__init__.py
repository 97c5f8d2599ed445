"""pendkit for Python: multi-stage pendulum suspensions (LIGO quad and triple).

Equilibrium, normal modes, transfer functions, thermal noise and state space of a bundled
model or a case file, computed by pendkit's Rust library (the GIL is released while it
computes) and returned as numpy arrays::

    import numpy as np
    import pendkit

    quad = pendkit.Model("quad", set={"d4": 0.01})
    result = quad.run()                        # stage "2", the complete model
    modes = result.modes()                     # modes.frequencies (Hz), .labels, .shapes
    f = np.logspace(-1, 2, 1000)               # Hz
    h = result.tf("x00", "x3", f)              # complex, m/m
    noise = result.noise("x3", f)              # noise.asd (m/√Hz), noise.asd_by_tag
    ss = result.state_space(["force:x3"], ["x3"]).to_control()
    hz = pendkit.sweep(quad, {"m3": np.linspace(39, 41, 200)})   # (200, 24), Hz

Errors raise :class:`PendkitError` (a ``ValueError``) with the command line's one-line
message; a wrong type raises ``TypeError`` naming the argument. Models, results and
errors pickle, so they go to worker processes and Dask clusters; :func:`sweep` runs a
whole sweep in threads or on a Dask cluster.
:func:`pendkit.gwinc.suspension_thermal` is a drop-in for pygwinc's suspension thermal
noise; :mod:`pendkit.finesse` (import it explicitly: it loads Finesse) makes Finesse 3
suspension components from pendkit models (docs/finesse.md).
"""

from ._pendkit import (
    Model,
    PendkitError,
    Result,
    __version__,
    log_grid,
    models,
)
from ._results import (
    Modes,
    Noise,
    Parameter,
    Sensitivities,
    Stability,
    StateSpace,
    control_name,
)
from ._sweep import sweep

__all__ = [
    "Model",
    "Modes",
    "Noise",
    "Parameter",
    "PendkitError",
    "Result",
    "Sensitivities",
    "Stability",
    "StateSpace",
    "__version__",
    "control_name",
    "log_grid",
    "models",
    "sweep",
]
