"""Models pickle and go to worker processes and Dask clusters with the same results.

The reference is the same sweep run serially in this process: pendkit is deterministic
(no threads, no random numbers), so a model rebuilt from its pickle in another process must
give bit-identical numbers (exact equality, no tolerance)."""

import concurrent.futures
import importlib
import multiprocessing
import pickle
import shutil
import sys

import numpy as np

import pendkit

from conftest import CASES, REPO

FREQS = np.logspace(-1, 2, 50)  # Hz
HEAVIER = CASES / "ligo" / "cases" / "quad" / "heavier-test-mass.toml"


def summary(model):
    """Numbers of one sweep point (module level, so a process pool can import it)."""
    result = model.run()
    return (model.sets, result.modes().frequencies, result.noise("x3", FREQS).psd,
            result.tf("x00", "x3", FREQS))


def assert_same(a, b):
    assert a[0] == b[0]
    for x, y in zip(a[1:], b[1:]):
        assert np.array_equal(x, y)


def test_models_round_trip_through_pickle(tmp_path):
    # a case file copied away and deleted after pickling: the pickle carries its text
    case = tmp_path / "heavier.toml"
    shutil.copy(HEAVIER, case)
    models = [pendkit.Model("quad"), pendkit.Model("quad", set={"d4": 0.01, "m3": "45"}),
              pendkit.Model(case, set=["damping.fibre_bending.structural=2*silica_phi"])]
    blobs = [pickle.dumps(m) for m in models]
    case.unlink()
    for model, blob in zip(models, blobs):
        copy = pickle.loads(blob)
        assert repr(copy) == repr(model) and copy.sets == model.sets
        assert copy.name == model.name and copy.description == model.description
        assert_same(summary(copy), summary(model))
    assert models[2].name == "heavier" and models[2].description == "50 kg test mass and PUM"


def test_process_pool_gives_the_serial_results():
    models = [pendkit.Model("quad", set={"d4": d}) for d in (0.0, 0.005, 0.01, 0.02)]
    serial = [summary(m) for m in models]
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(2, mp_context=context) as pool:
        parallel = list(pool.map(summary, models))
    for a, b in zip(serial, parallel):
        assert_same(a, b)
    # different overrides give different numbers (the workers did not all run one model)
    assert not np.array_equal(serial[0][2], serial[-1][2])


def load_example():
    # imported by its file name from examples/python, which goes on sys.path
    folder = str(REPO / "examples" / "python")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    return importlib.import_module("dask_sweep")


def test_dask_example_sweep_equals_the_plain_loop(dask_client):
    example = load_example()
    model = pendkit.Model("quad", set={"d4": 0.01})
    values = np.linspace(39.0, 41.0, 30)
    loop = example.plain_loop(model, values)
    on_cluster = example.on_cluster(dask_client, model, values)
    assert np.array_equal(loop, on_cluster)
    # every point is its own: 30 different sets of frequencies
    assert len({row.tobytes() for row in loop}) == 30
