#!/usr/bin/env python3
"""Loads the .mat and .npz that tests/python_load.rs writes, with scipy.io.loadmat and
numpy.load, and checks every value bit for bit and the names as strings.

Usage: python3 load_check.py FILE.mat FILE.npz   (exit status 0 when all checks pass)
Needs: python3 -m pip install scipy numpy
"""

import sys

try:
    import numpy as np
    import scipy.io
except ImportError:
    sys.exit("scipy is needed: python3 -m pip install scipy numpy")

# Keep in step with python_load.rs.
A = np.array([[0.1, -2.5, 1e-300], [1.0 / 3.0, 6.02214076e23, -0.0]])
B = np.array([[1.0], [2.0], [3.0]])
E = np.zeros((0, 0))
STATES = ["x1", "theta_dot", "\u03c6_pitch", ""]

failures = []


def check(what, ok):
    if not ok:
        failures.append(what)


def check_matrix(where, name, got, want):
    ok = (
        isinstance(got, np.ndarray)
        and got.dtype == np.float64
        and got.shape == want.shape
        and np.ascontiguousarray(got).tobytes() == want.tobytes()
    )
    check(f"{where} {name}: got {got!r}, want {want!r}", ok)


def check_mat(path):
    m = scipy.io.loadmat(path)
    variables = sorted(k for k in m if not k.startswith("__"))
    check(f"mat variables: {variables}", variables == ["A", "B", "E", "inputs", "states"])
    check(f"mat header: {m['__header__']!r}", m["__header__"].startswith(b"MATLAB 5.0 MAT-file"))
    for name, want in [("A", A), ("B", B), ("E", E)]:
        check_matrix("mat", name, m[name], want)

    # A cell array of char arrays: object array of shape (n, 1), each cell a string array
    # (empty for an empty string).
    states = m["states"]
    check(f"mat states shape {states.shape}", states.dtype == object and states.shape == (4, 1))
    got = ["".join(str(s) for s in cell.ravel()) for cell in states.ravel()]
    check(f"mat states: {got}", got == STATES)
    inputs = m["inputs"]
    check(f"mat inputs: {inputs!r}", inputs.dtype == object and inputs.shape == (0, 1))

    simple = scipy.io.loadmat(path, simplify_cells=True)
    got = [s if isinstance(s, str) else "" for s in simple["states"]]
    check(f"mat simplify_cells states: {simple['states']!r}", got == STATES)


def check_npz(path):
    with np.load(path) as z:  # allow_pickle stays False: strings load as a unicode array
        check(f"npz entries: {sorted(z.files)}", sorted(z.files) == ["A", "B", "E", "inputs", "states"])
        for name, want in [("A", A), ("B", B), ("E", E)]:
            check_matrix("npz", name, z[name], want)
        states = z["states"]
        check(
            f"npz states: {states!r}",
            states.dtype.kind == "U" and states.shape == (4,) and states.tolist() == STATES,
        )
        inputs = z["inputs"]
        check(f"npz inputs: {inputs!r}", inputs.dtype.kind == "U" and inputs.shape == (0,))


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: python3 load_check.py FILE.mat FILE.npz")
    check_mat(sys.argv[1])
    check_npz(sys.argv[2])
    if failures:
        print("load_check: FAILED", *failures, sep="\n  ", file=sys.stderr)
        sys.exit(1)
    print(f"load_check: ok (scipy {scipy.__version__}, numpy {np.__version__})")


if __name__ == "__main__":
    main()
