"""The pygwinc drop-in: the same call as pygwinc 0.6's suspension thermal noise, answered
by pendkit's quad (skipped where pygwinc is not installed)."""

import copy
import re
import subprocess
import sys
import warnings

import numpy as np
import pytest

import pendkit
from conftest import REPO

gwinc = pytest.importorskip("gwinc")
from gwinc.noise.suspensionthermal import suspension_thermal as gwinc_suspension_thermal  # noqa: E402
from gwinc.suspension import precomp_suspension  # noqa: E402

from pendkit.gwinc import (  # noqa: E402
    DEFAULT_MODEL,
    UnmappedSuspensionSetting,
    ViolinModeWarning,
    first_violin_mode,
    suspension_settings,
    suspension_thermal,
)


@pytest.fixture(scope="module")
def aligo():
    freq = np.logspace(0, 3, 31)  # Hz
    ifo = gwinc.load_budget("aLIGO", freq=freq).ifo
    return freq, ifo, precomp_suspension(freq, ifo)


def test_same_call_and_shape_as_pygwinc(aligo):
    freq, ifo, sustf = aligo
    with pytest.warns(ViolinModeWarning):  # the grid reaches 1 kHz
        ours = suspension_thermal(freq, ifo.Suspension, sustf)
    theirs = gwinc_suspension_thermal(freq, ifo.Suspension, sustf)
    assert ours.shape == theirs.shape == freq.shape
    assert np.all(np.isfinite(ours)) and np.all(ours > 0)


def test_maps_temperature_dilution_and_vertical_coupling(aligo):
    # the documented mapping of the aLIGO struct, rebuilt by hand from its fields: where
    # pygwinc's aLIGO values differ from quad-aligo's own they are the given dilution
    # factors of the steel stages (Stage[1..3].Dilution; quad-aligo computes its own);
    # temperature from sus.Temp; S_L + θ² S_V with θ from the precomputed VHCoupling
    # (pygwinc's own beam-line coupling). Exact, as the same calls in the same order
    freq, ifo, sustf = aligo
    sus = ifo.Suspension
    theta = sustf.VHCoupling.theta
    assert 1e-4 < theta < 1e-2  # L / R_earth for a 4 km arm
    sets = {"temperature": sus.Temp, "dilution_w2": sus.Stage[1].Dilution,
            "dilution_w1": sus.Stage[2].Dilution, "dilution_wn": sus.Stage[3].Dilution}
    assert sorted(s.split("=")[0] for s in suspension_settings(sus)) == sorted(
        k for k in sets if k != "temperature")  # 290 K is quad-aligo's own
    run = pendkit.Model(DEFAULT_MODEL, set=sets).run()
    expected = run.noise("x3", freq).psd + theta**2 * run.noise("z3", freq).psd
    with pytest.warns(ViolinModeWarning):
        assert np.allclose(suspension_thermal(freq, sus, sustf), expected, rtol=1e-12, atol=0)
    # without sus and sustf nothing is mapped: the model's own values, no coupling
    with pytest.warns(ViolinModeWarning):
        assert np.array_equal(suspension_thermal(freq), pendkit.Model(DEFAULT_MODEL).run()
                              .noise("x3", freq).psd)


def test_agrees_with_pygwinc_for_aligo(aligo):
    # independent reference: pygwinc 0.6.2's own suspension thermal noise for aLIGO. The
    # default model (quad-aligo) takes its numbers from the same ifo.yaml; the residual
    # differences are named in the README (pygwinc's fibres carry mass, pendkit's one-wire
    # fibre does not: +3 % in the ASD at 100 Hz; computed vs given dilution, 3-D coupling:
    # well under 1 % below 50 Hz), so the ASDs must agree to 5 % over 20-100 Hz
    freq, ifo, sustf = aligo
    band = (freq >= 20) & (freq <= 100)
    ours = suspension_thermal(freq[band], ifo.Suspension, sustf)
    theirs = gwinc_suspension_thermal(freq, ifo.Suspension, sustf)[band]
    ratio = np.sqrt(ours / theirs)
    assert np.all(np.abs(ratio - 1) < 0.05), ratio


BAND = np.logspace(np.log10(20), 2, 9)  # Hz: the band of the 5 % agreement above


def changed(ifo, change):
    """pendkit's and pygwinc's terms over BAND for a copy of `ifo` whose Suspension
    `change` edits (pygwinc's precomputation redone from the edited struct)."""
    ifo = copy.deepcopy(ifo)
    change(ifo.Suspension)
    sustf = precomp_suspension(BAND, ifo)
    return (suspension_thermal(BAND, ifo.Suspension, sustf),
            gwinc_suspension_thermal(BAND, ifo.Suspension, sustf))


def double_test_mass(sus):
    sus.Stage[0].Mass = 2 * sus.Stage[0].Mass


@pytest.mark.parametrize("change", [
    double_test_mass,
    lambda sus: setattr(sus.Stage[0], "Length", 1.2 * sus.Stage[0].Length),
    lambda sus: setattr(sus.Fiber, "EndRadius", 1.2 * sus.Fiber.EndRadius),
    lambda sus: setattr(sus.Silica, "Phi", 10 * sus.Silica.Phi),
    lambda sus: setattr(sus, "Temp", 120.0),
    lambda sus: setattr(sus, "FiberType", "Round"),
], ids=["test mass x2", "fibre length x1.2", "neck radius x1.2", "silica loss x10",
        "120 K", "round fibres"])
def test_suspension_settings_change_the_term_as_pygwincs(aligo, change):
    # independent reference: pygwinc 0.6.2 recomputed from the same edited struct. Doubling
    # the test mass changes pygwinc's PSD by x1.95 at 20 Hz to x0.71 at 100 Hz (x0.001 to
    # x750 near the pendulum resonances); the drop-in must follow it: the ASDs agree to the
    # 5 % of the aLIGO comparison above (same reasons: the fibres' mass grows with the
    # frequency), and so does the change itself, ours / pygwinc's
    _, ifo, _ = aligo
    base_ours, base_theirs = changed(ifo, lambda sus: None)
    ours, theirs = changed(ifo, change)
    assert np.all(np.abs(np.sqrt(ours / theirs) - 1) < 0.05), np.sqrt(ours / theirs)
    change_ratio = np.sqrt((ours / base_ours) / (theirs / base_theirs))
    assert np.all(np.abs(change_ratio - 1) < 0.05), change_ratio
    # and the change is real: not the x1.000 of a drop-in that ignores the struct
    assert np.max(np.abs(np.sqrt(theirs / base_theirs) - 1)) > 0.1


@pytest.mark.parametrize("change, named", [
    (lambda sus: setattr(sus, "FiberType", "Ribbon"), "Suspension.FiberType = 'Ribbon'"),
    (lambda sus: setattr(sus.Stage[1], "NWires", 3), "Suspension.Stage[1].NWires = 3"),
    (lambda sus: setattr(sus.Stage[2], "Temp", 120.0), "Suspension.Stage[2].Temp = 120.0"),
    (lambda sus: setattr(sus.Stage[0], "WireMaterial", "Silicon"),
     "Suspension.Stage[0].WireMaterial = 'Silicon'"),
    (lambda sus: setattr(sus, "Stage", sus.Stage[:3]), "Suspension.Stage (3 stages"),
])
def test_settings_it_cannot_take_are_refused_by_name(aligo, change, named):
    _, ifo, _ = aligo
    ifo = copy.deepcopy(ifo)
    change(ifo.Suspension)
    with pytest.raises(UnmappedSuspensionSetting, match=re.escape(named)):
        suspension_thermal(BAND, ifo.Suspension)
    # map_sus=False is the explicit way to take the model's own suspension
    assert np.all(suspension_thermal(BAND, ifo.Suspension, map_sus=False) > 0)


def test_violin_mode_warning(aligo):
    # the first violin mode against pygwinc's continuum fibres: the first peak of pygwinc's
    # term above 300 Hz. The string formula leaves out the fibres' bending stiffness,
    # which raises pygwinc's mode by about 2 δ/L (δ = 3.9 mm at the necks: 1.3 %), so 2 %
    _, ifo, _ = aligo
    f1 = first_violin_mode()
    fine = np.linspace(300, 700, 4001)
    ifo = copy.deepcopy(ifo)
    psd = gwinc_suspension_thermal(fine, ifo.Suspension, precomp_suspension(fine, ifo))
    peak = fine[np.argmax(psd)]
    assert abs(f1 / peak - 1) < 0.02, (f1, peak)
    with pytest.warns(ViolinModeWarning, match="first violin mode"):
        suspension_thermal(np.array([10.0, 1.01 * f1]))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        suspension_thermal(np.array([10.0, 0.99 * f1]))  # below it: no warning
        # beads give the fibres violin modes: no warning above it either
        suspension_thermal(np.array([10.0, 600.0]), set=["n_beads=2"])


def test_example_budget_runs():
    done = subprocess.run(
        [sys.executable, str(REPO / "examples" / "python" / "gwinc_budget.py"),
         "--points", "60"],
        capture_output=True, text=True, timeout=600,
    )
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().splitlines()
    assert lines[0].startswith("f_hz,susp_thermal_pygwinc")
    rows = [[float(x) for x in line.split(",")] for line in lines[1:]]
    assert len(rows) == 8 and all(v > 0 for row in rows for v in row)
