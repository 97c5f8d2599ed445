"""Fits the quad's UIM mass `m1` and UIM wire length `l1` to the measured modes of
`measured.csv` (beside this file), as `pendkit fit quad --modes measured.csv --free m1,l1`.

`measured.csv` is example data, not a measurement: the 24 modes of the quad with m1 and l1
set to `TRUTH` (2 % and 1 % above the model's 22.011 kg and 0.3085 m), each frequency moved
by a deterministic stand-in for noise of standard deviation `SIGMA` of itself (σ u_k, with
u_k = 2√3 (frac(0.618034 k) - ½): mean 0, variance 1 over the modes), labelled as
`pendkit modes` labels them (the dominant coordinate, the next two as the shape). The fit
lands within its stated uncertainties of `TRUTH`.

    python examples/python/fit_measured.py            # the fit
    python examples/python/fit_measured.py --write    # writes measured.csv again
"""

import argparse
import math
from pathlib import Path
from typing import Any, Dict, List, Tuple

import numpy as np

import pendkit

HERE = Path(__file__).resolve().parent
MEASURED = HERE / "measured.csv"
#: The values the example data are made with: m1 (kg) and l1 (m).
TRUTH: Dict[str, float] = {"m1": 22.451, "l1": 0.3116}
#: The measurements' relative standard uncertainty.
SIGMA = 2e-4


def measured_rows() -> List[Tuple[str, float, float, str]]:
    """(label, hz, sigma_hz, shape) of each mode of the quad at `TRUTH`, moved by the
    stand-in noise."""
    modes = pendkit.Model("quad", set=TRUTH).run().modes()
    rows = []
    for k, (hz, shares) in enumerate(zip(modes.frequencies, modes.energy_fractions), 1):
        top = [modes.coordinates[i] for i in np.argsort(-shares)[:3]]
        u = 2 * math.sqrt(3) * ((0.618034 * k) % 1 - 0.5)
        sigma = SIGMA * float(hz)
        rows.append((top[0], float(hz) + sigma * u, sigma, "+".join(top[1:])))
    return rows


def write(path: Path) -> None:
    """`measured.csv`: a header saying what it is, then label,hz,sigma_hz,shape."""
    lines = [
        "# Example data, not a measurement: the modes of pendkit's quad with",
        f"# m1 = {TRUTH['m1']} kg and l1 = {TRUTH['l1']} m, each frequency moved by a",
        f"# deterministic stand-in for noise of {SIGMA:g} of itself (examples/python/",
        "# fit_measured.py writes it and says how).",
        "label,hz,sigma_hz,shape",
    ]
    lines += [f"{label},{hz:.7f},{sigma:.2g},{shape}"
              for label, hz, sigma, shape in measured_rows()]
    path.write_text("\n".join(lines) + "\n")


def fit() -> Dict[str, Any]:
    """The fit of m1 and l1 to `measured.csv` from the model's own values."""
    return pendkit.Model("quad").fit(MEASURED, ["m1", "l1"], jacobian="exact")


def main() -> None:
    parser = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    parser.add_argument("--write", action="store_true", help="write measured.csv again")
    args = parser.parse_args()
    if args.write:
        write(MEASURED)
        print(f"wrote {MEASURED}")
        return
    result = fit()
    print("parameter,start,fitted,uncertainty,truth")
    for p in result["parameters"]:
        print(f"{p['name']},{p['start']:.6g},{p['value']:.6g},{p['uncertainty']:.2g},"
              f"{TRUTH[p['name']]:.6g}")
    print(f"chi_squared/dof = {result['reduced_chi_squared']:.3g} over {result['dof']} "
          "degrees of freedom")


if __name__ == "__main__":
    main()
