#!/usr/bin/env python3
"""Evaluates the state-space model that `pendkit ss` exported to a .mat file,
H(s) = C (sI - A)^-1 B + D at s = 2 pi i f, and compares it with pendkit's own transfer
functions. The model is held as a scipy.signal.StateSpace; H is evaluated by a direct
complex solve (scipy.linalg) rather than scipy.signal.freqresp, whose conversion to
polynomial form loses about 1e-8 on a 12-state model ("badly conditioned coefficients").

Usage: python3 ss_check.py MODEL.mat EXPECTED.json
EXPECTED.json: {"freqs": [...], "pairs": [{"input": name, "output": name, "re": [...], "im": [...]}],
                "provenance": {"model": ..., "case_name": ..., "stage": ..., "pendkit_version": ...,
                               "parameters": {name: [value, unit]}, "damping_frequency_hz": ...}}
Exit status 0 when every pair agrees to 1e-9 relative (of the largest magnitude of that pair)
and the file's provenance is the expected one.
"""

import json
import sys

try:
    import numpy as np
    import scipy.io
    import scipy.linalg
    import scipy.signal
except ImportError:
    sys.exit("scipy is needed: python3 -m pip install scipy numpy")

mat = scipy.io.loadmat(sys.argv[1], simplify_cells=True)
expected = json.load(open(sys.argv[2]))
inputs = list(mat["inputs"])
outputs = list(mat["outputs"])
provenance = expected.get("provenance", {})
for key in ["model", "case_name", "stage", "pendkit_version"]:
    if key in provenance and str(mat[key]) != provenance[key]:
        sys.exit(f"{key}: {mat[key]!r} in the file, expected {provenance[key]!r}")
names = list(mat["parameter_names"])
for name, (value, unit) in provenance.get("parameters", {}).items():
    if name not in names:
        sys.exit(f"parameter {name} missing from parameter_names")
    k = names.index(name)
    got = np.ravel(mat["parameter_values"])[k]
    if got != value or list(mat["parameter_units"])[k] != unit:
        sys.exit(f"parameter {name}: {got} {list(mat['parameter_units'])[k]!r}, expected {value} {unit!r}")
if "damping_frequency_hz" in provenance:
    got = float(np.ravel(mat["damping_frequency_hz"])[0])
    if got != provenance["damping_frequency_hz"]:
        sys.exit(f"damping_frequency_hz: {got}, expected {provenance['damping_frequency_hz']}")

w = 2 * np.pi * np.asarray(expected["freqs"])
worst = 0.0
for pair in expected["pairs"]:
    j = inputs.index(pair["input"])
    i = outputs.index(pair["output"])
    system = scipy.signal.StateSpace(mat["A"], mat["B"], mat["C"], mat["D"])
    n = system.A.shape[0]
    h = np.array(
        [
            (system.C[i, :] @ scipy.linalg.solve(1j * wk * np.eye(n) - system.A, system.B[:, j]))
            + system.D[i, j]
            for wk in w
        ]
    )
    want = np.asarray(pair["re"]) + 1j * np.asarray(pair["im"])
    err = np.max(np.abs(h - want)) / np.max(np.abs(want))
    worst = max(worst, err)
    if not err <= 1e-9:
        sys.exit(f"{pair['output']}/{pair['input']}: relative error {err:.3e}")
print(f"ok: worst relative error {worst:.3e}")
