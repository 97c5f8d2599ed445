"""The fit example's data (examples/python/measured.csv) is what its header says, and the
documented fit of it (docs/python.md, fitting.md) finds the values it was made with."""

import importlib
import sys

import pendkit

from conftest import REPO

FOLDER = REPO / "examples" / "python"


def load_example():
    if str(FOLDER) not in sys.path:
        sys.path.insert(0, str(FOLDER))
    return importlib.import_module("fit_measured")


def test_measured_csv_is_what_its_header_says(tmp_path):
    # written again from the quad at the stated values: the same file, digit for digit
    example = load_example()
    again = tmp_path / "measured.csv"
    example.write(again)
    assert (FOLDER / "measured.csv").read_text() == again.read_text(), (
        "examples/python/measured.csv is not what fit_measured.py writes: "
        "python examples/python/fit_measured.py --write")
    header = (FOLDER / "measured.csv").read_text()
    assert f"m1 = {example.TRUTH['m1']} kg and l1 = {example.TRUTH['l1']} m" in header


def test_the_documented_fit_finds_the_values_the_data_were_made_with():
    example = load_example()
    fit = pendkit.Model("quad").fit(str(FOLDER / "measured.csv"), ["m1", "l1"])
    assert fit == example.fit()  # the example's call (a Path, jacobian="exact") is the same
    for p in fit["parameters"]:
        # within 3 of its stated uncertainties of the truth, and moved there from a start
        # many uncertainties away
        truth = example.TRUTH[p["name"]]
        assert abs(p["value"] - truth) < 3 * p["uncertainty"], p
        assert abs(p["start"] - truth) > 10 * p["uncertainty"], p
    # the stand-in noise has unit variance over the 24 modes: χ²/dof near 1
    assert fit["dof"] == 22 and 0.5 < fit["reduced_chi_squared"] < 2.0
