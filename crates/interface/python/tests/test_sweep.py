"""`pendkit.sweep` gives, bit for bit, what the plain loop over `Model.with_set` gives, in
threads and on a Dask cluster, whatever the chunking; a failing point is named.

The reference is the loop a user writes without `sweep` (pendkit is deterministic, so the
numbers must be identical: exact equality, no tolerance). Chunks are made small here
(`CHUNK_SECONDS`), so that a few dozen points make many chunks and every path runs."""

import numpy as np
import pytest

import pendkit
import pendkit._sweep
from pendkit import PendkitError

FREQS = pendkit.log_grid(0.1, 30.0, 25)  # Hz


def plain_loop(model, values, what):
    """What the sweep must equal: one `with_set` and `run` per point."""
    rows = []
    for point in zip(*values.values()):
        r = model.with_set(dict(zip(values, point))).run()
        if what == "modes":
            rows.append(r.modes().frequencies)
        elif what[0] == "tf":
            rows.append(r.tf(*what[1:]))
        else:
            rows.append(r.noise(*what[1:]).asd)
    return np.array(rows)


@pytest.fixture
def small_chunks(monkeypatch):
    """Chunks of a few points each (the sizing rule with a 1 ms target)."""
    monkeypatch.setattr(pendkit._sweep, "CHUNK_SECONDS", 0.001)
    monkeypatch.setattr(pendkit._sweep, "CALIBRATION_SECONDS", 0.0)


@pytest.mark.parametrize("what", [
    "modes", ("tf", "x00", "x3", FREQS), ("noise", "x3", FREQS),
    ("tf", "GND_L", "L3_P", FREQS),
])
def test_sweep_in_threads_equals_the_plain_loop(small_chunks, what):
    model = pendkit.Model("quad", set={"d4": 0.01})
    values = {"m3": np.linspace(39.0, 41.0, 13), "l3": np.linspace(0.6, 0.61, 13)}
    got = pendkit.sweep(model, values, what, threads=2)
    expected = plain_loop(model, values, what)
    assert got.dtype == expected.dtype and got.shape == expected.shape
    assert np.array_equal(got, expected)
    # the points differ (the rows are not one point repeated)
    assert len({row.tobytes() for row in got}) == len(got)


def test_sweep_with_default_chunks_and_numpy_values():
    model = pendkit.Model("triple")
    values = {"m3": np.arange(38, 43, dtype=np.int32)}
    assert np.array_equal(pendkit.sweep(model, values), plain_loop(model, values, "modes"))
    assert np.array_equal(pendkit.sweep(model, {"m3": [40.0]}, threads=1),
                          plain_loop(model, {"m3": [40.0]}, "modes"))


def test_a_failing_point_is_named(small_chunks, recwarn):
    model = pendkit.Model("quad")
    values = {"m3": [40.0, 41.0, -1.0, 42.0, -2.0, 43.0]}
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad", set={"m3": -1.0}).run()
    expected = e.value
    with pytest.raises(PendkitError) as e:
        pendkit.sweep(model, values, threads=2)
    assert str(e.value) == f"sweep point 2 (m3=-1.0): {expected}"
    with pytest.warns(RuntimeWarning, match=r"^2 of 6 sweep points failed .*; the first, "
                                            r"sweep point 2 \(m3=-1.0\)"):
        got = pendkit.sweep(model, values, errors="nan", threads=2)
    assert np.isnan(got[[2, 4]]).all()
    good = [0, 1, 3, 5]
    assert np.array_equal(got[good], plain_loop(model, {"m3": np.array(values["m3"])[good]},
                                                "modes"))


def test_bad_sweeps_are_refused_naming_the_argument():
    model = pendkit.Model("pendulum")
    with pytest.raises(PendkitError, match=r"^values\['m'\]\[1\]: value nan is not finite$"):
        pendkit.sweep(model, {"m": [1.0, np.nan]})
    with pytest.raises(PendkitError, match=r"^values\['l'\]: 3 values, where values\['m'\] "
                                           r"has 2"):
        pendkit.sweep(model, {"m": [1.0, 2.0], "l": [1.0, 2.0, 3.0]})
    with pytest.raises(TypeError, match=r"^values\['m'\]: expected real numbers"):
        pendkit.sweep(model, {"m": ["1", "2"]})
    with pytest.raises(TypeError, match=r"^model: expected a pendkit.Model, got str$"):
        pendkit.sweep("pendulum", {"m": [1.0]})  # type: ignore[arg-type]
    with pytest.raises(PendkitError, match=r"^what: 'eigen' is not"):
        pendkit.sweep(model, {"m": [1.0]}, "eigen")
    with pytest.raises(PendkitError, match=r"^what: expected \(\"tf\", input, output, freqs\)"):
        pendkit.sweep(model, {"m": [1.0]}, ("tf", "x00", FREQS))
    with pytest.raises(PendkitError, match=r"^freqs\[0\]: frequency -1 Hz must be positive$"):
        pendkit.sweep(model, {"m": [1.0]}, ("noise", "x1", [-1.0]))
    with pytest.raises(PendkitError, match=r"^sweep point 0 \(nope=1.0\): "):
        pendkit.sweep(model, {"nope": [1.0]})


def test_dask_sweep_equals_the_plain_loop(dask_client, small_chunks):
    model = pendkit.Model("quad", set={"d4": 0.01})
    values = {"m3": np.linspace(39.0, 41.0, 24)}
    for what in ["modes", ("noise", "x3", FREQS), ("tf", "x00", "x3", FREQS)]:
        got = pendkit.sweep(model, values, what, client=dask_client)
        assert np.array_equal(got, plain_loop(model, values, what))
    # the chunks ran on the workers (more than one, in their own processes)
    assert len(dask_client.run(lambda: 1)) == 2
    with pytest.raises(PendkitError, match=r"^sweep point 1 \(m3=-1.0\): "):
        pendkit.sweep(model, {"m3": [40.0, -1.0, 41.0]}, client=dask_client)


def test_a_pendkit_error_raised_on_a_dask_worker_is_caught_as_one(dask_client, cli):
    future = dask_client.submit(pendkit.Model, "nosuch", pure=False)
    with pytest.raises(pendkit.PendkitError) as e:
        future.result(timeout=120)
    assert str(e.value) == cli.error("modes", "nosuch")
    # and results of every type come back from a worker equal
    r = pendkit.Model("quad").run()
    back = dask_client.submit(lambda m: (m.run(), m.run().modes(), m.run().noise("x3", FREQS)),
                              pendkit.Model("quad"), pure=False).result(timeout=120)
    assert back == (r, r.modes(), r.noise("x3", FREQS))
