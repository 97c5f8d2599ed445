"""The pygwinc drop-in: the same call as pygwinc 0.6's suspension thermal noise, answered
by pendkit's quad (skipped where pygwinc is not installed)."""

import subprocess
import sys

import numpy as np
import pytest

import pendkit
from conftest import REPO

gwinc = pytest.importorskip("gwinc")
from gwinc.noise.suspensionthermal import suspension_thermal as gwinc_suspension_thermal  # noqa: E402
from gwinc.suspension import precomp_suspension  # noqa: E402

from pendkit.gwinc import DEFAULT_MODEL, suspension_thermal  # noqa: E402


@pytest.fixture(scope="module")
def aligo():
    freq = np.logspace(0, 3, 31)  # Hz
    ifo = gwinc.load_budget("aLIGO", freq=freq).ifo
    return freq, ifo, precomp_suspension(freq, ifo)


def test_same_call_and_shape_as_pygwinc(aligo):
    freq, ifo, sustf = aligo
    ours = suspension_thermal(freq, ifo.Suspension, sustf)
    theirs = gwinc_suspension_thermal(freq, ifo.Suspension, sustf)
    assert ours.shape == theirs.shape == freq.shape
    assert np.all(np.isfinite(ours)) and np.all(ours > 0)


def test_maps_temperature_and_vertical_coupling(aligo):
    # the documented mapping, rebuilt from the public API: temperature from sus.Temp, and
    # S_L + θ² S_V with θ from the precomputed VHCoupling (pygwinc's own beam-line
    # coupling); exact, as the same calls in the same order
    freq, ifo, sustf = aligo
    theta = sustf.VHCoupling.theta
    assert 1e-4 < theta < 1e-2  # L / R_earth for a 4 km arm
    run = pendkit.Model(DEFAULT_MODEL, set={"temperature": ifo.Suspension.Temp}).run()
    expected = run.noise("x3", freq).psd + theta**2 * run.noise("z3", freq).psd
    assert np.array_equal(suspension_thermal(freq, ifo.Suspension, sustf), expected)
    # without sus and sustf nothing is mapped: the model's own temperature, no coupling
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
    ours = suspension_thermal(freq, ifo.Suspension, sustf)[band]
    theirs = gwinc_suspension_thermal(freq, ifo.Suspension, sustf)[band]
    ratio = np.sqrt(ours / theirs)
    assert np.all(np.abs(ratio - 1) < 0.05), ratio


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
