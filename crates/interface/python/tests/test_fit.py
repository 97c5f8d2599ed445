"""`Model.fit`: the fit from Python agrees with `pendkit fit --json` (the command line as
the independent reference: the same library through clap, a file and a separate process),
recovers parameter values from noise-free synthetic modes, and refuses bad measurements
with the command line's message."""

import json

import numpy as np
import pytest

import pendkit
from pendkit import PendkitError


def synthetic_modes(truth, model="quad"):
    """(label, hz, sigma_hz, shape) of every mode of `model` at `truth`, sigma 1e-4
    relative, the shape its three largest kinetic-energy coordinates."""
    modes = pendkit.Model(model, set=truth).run().modes()
    rows = []
    for k, hz in enumerate(modes.frequencies):
        top = np.argsort(modes.energy_fractions[k])[::-1][:3]
        shape = "+".join(modes.coordinates[c] for c in top)
        rows.append((modes.labels[k], repr(float(hz)), repr(1e-4 * float(hz)), shape))
    return rows


def test_fit_agrees_with_the_command_line_and_recovers_the_truth(cli, tmp_path):
    rows = synthetic_modes({"m1": 23.0, "l1": 0.31})
    path = tmp_path / "measured.csv"
    path.write_text("label,hz,sigma_hz,shape\n" + "".join(",".join(r) + "\n" for r in rows))
    free = ["m1", "l1", "silica_phi"]
    from_file = pendkit.Model("quad").fit(path, free)
    from_list = pendkit.Model("quad").fit(rows, free)
    reference = json.loads(cli("fit", "quad", "--modes", str(path), "--free", ",".join(free), "--json"))["fit"]
    for mine in (from_file, from_list):
        for p, q in zip(mine["parameters"], reference["parameters"]):
            assert p["name"] == q["name"]
            assert p["value"] == q["value"]
            assert p["uncertainty"] == q["uncertainty"]
        assert mine["chi_squared"] == reference["chi_squared"]
    # noise-free data: the truth far inside the stated uncertainty; the loss angle
    # (no mode frequency depends on it) undetermined and left at its start value
    m1, l1, phi = from_file["parameters"]
    assert abs(m1["value"] - 23.0) < 0.01 * m1["uncertainty"]
    assert abs(l1["value"] - 0.31) < 0.01 * l1["uncertainty"]
    assert phi["uncertainty"] is None and phi["value"] == phi["start"]
    assert from_file["undetermined"][0]["combination"][0][0] == "silica_phi"
    assert from_file["case_file"].startswith("# written by pendkit fit")
    assert from_file["jacobian"] == "exact"
    # central differences for the Jacobian: the command line's numbers with the same option
    differenced = pendkit.Model("quad").fit(path, free, jacobian="differences")
    reference = json.loads(
        cli("fit", "quad", "--modes", str(path), "--free", ",".join(free), "--jacobian", "differences", "--json")
    )["fit"]
    assert differenced["jacobian"] == reference["jacobian"] == "differences"
    for p, q in zip(differenced["parameters"], reference["parameters"]):
        assert p["value"] == q["value"] and p["uncertainty"] == q["uncertainty"]
    with pytest.raises(ValueError, match="not a Jacobian method"):
        pendkit.Model("quad").fit(path, free, jacobian="adjoint")
    # more starts: the command line's numbers with the same options, and how many it tried
    started = pendkit.Model("quad").fit(path, free, starts=3, more_starts=0)
    reference = json.loads(
        cli("fit", "quad", "--modes", str(path), "--free", ",".join(free), "--starts", "3",
            "--more-starts", "0", "--json")
    )["fit"]
    assert started["starts"] == reference["starts"] == 3
    for p, q in zip(started["parameters"], reference["parameters"]):
        assert p["value"] == q["value"] and p["uncertainty"] == q["uncertainty"]


def test_bad_measurements_raise_the_command_lines_message(cli, tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("x3,0.43,0.001\nz3,0.67,0\n")
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad").fit(path, ["m1"])
    assert str(e.value) == cli.error("fit", "quad", "--modes", str(path), "--free", "m1")


def test_measured_modes_as_tuples_are_rows_not_text():
    # Once joined into CSV text: a label starting with '#' was a comment (the measurement
    # silently dropped), a ',' in a label shifted the fields, and a str item passed its
    # characters for fields.
    model = pendkit.Model("quad")
    good = [("x3", 0.4328, 0.001), ("y3", 0.4681, 0.001)]
    with pytest.raises(PendkitError, match=r"^modes:3: '#x3' is neither a variable"):
        model.fit(good + [("#x3", 0.98, 0.001)], ["m1"])
    with pytest.raises(PendkitError, match=r"^modes:1: 'x3,y3' is neither a variable"):
        model.fit([("x3,y3", 0.43, 0.001)] + good, ["m1"])
    with pytest.raises(TypeError, match=r"^modes\[1\]: expected a tuple .* got a str$"):
        model.fit([good[0], "y3,0.4681,0.001"], ["m1"])
    with pytest.raises(PendkitError, match=r"^modes:2: sigma_hz = 1e-300 is below the rounding"):
        model.fit([good[0], ("y3", 0.4681, 1e-300)], ["m1"])
    with pytest.raises(PendkitError, match=r"^modes: no measured modes"):
        model.fit([], ["m1"])


# The 20 and 15 parameters of the far-start fits (docs/fitting.md): stage lengths, blade
# frequencies, break-offs, masses and pitch inertias.
FAR_START_FREE = {
    "quad": ["ln", "l1", "l2", "l3", "ufcn", "ufc1", "ufc2", "dm", "dn", "d0", "d1", "d2",
             "d3", "d4", "mn", "m1", "m2", "m3", "Iny", "I1y"],
    "triple": ["l1", "l2", "l3", "ufc1", "ufc2", "d0", "d1", "d2", "d3", "d4", "m1", "m2",
               "m3", "I1y", "I2y"],
}


@pytest.mark.parametrize("model", ["quad", "triple"])
def test_fits_from_twenty_percent_away_reach_the_truth_for_many_sign_patterns(model):
    # Twelve fits. Every free parameter 20 % from the start, up or down by a fixed random
    # pattern (numpy's generator, seed 35: drawn here, not the fit's own starts'); the
    # measured modes are the truth's, solved independently of the fit, noise-free with
    # sigma 1e-4 f. Each fit, eight starts and up to eight more (the setting docs/fitting.md
    # measured at 80 of 80 quad patterns), must end at the truth: every parameter within 1e-4
    # of it (noise-free data leave only the convergence tolerance; a wrong minimum is off by
    # per cents). Release build: about 3 s a quad fit, 0.5 s a triple's.
    free = FAR_START_FREE[model]
    nominal = {p.name: p.value for p in pendkit.Model(model).parameters()}
    rng = np.random.default_rng(35)
    failed, fitted, pattern = [], 0, 0
    while fitted < 12 and pattern < 48:
        pattern += 1
        signs = rng.choice([-1.0, 1.0], size=len(free))
        truth = {name: nominal[name] * (1.0 + 0.2 * sign) for name, sign in zip(free, signs)}
        try:
            measured = synthetic_modes(truth, model)
        except PendkitError as e:
            # a truth no rigid body has (the triple's intermediate mass 20 % heavier with
            # its pitch inertia 20 % lower breaks the triangle inequality) is not a suspension:
            # the next pattern is drawn instead, up to twelve that are
            assert "triangle inequality" in str(e), str(e)
            continue
        fitted += 1
        result = pendkit.Model(model).fit(measured, free, starts=8, more_starts=8)
        worst = max(abs(p["value"] / truth[p["name"]] - 1.0) for p in result["parameters"])
        if worst > 1e-4:
            failed.append((pattern, "".join("+" if x > 0 else "-" for x in signs), worst))
    assert fitted == 12, f"{model}: only {fitted} of {pattern} patterns make a suspension"
    assert not failed, f"{model}: fits that did not reach the truth (pattern, signs, worst): {failed}"
