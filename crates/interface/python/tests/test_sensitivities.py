"""`Model.sensitivities` gives the command line's numbers (`pendkit sensitivity --json`,
which prints every digit of an f64: equality is exact, both run the same library function
on the same inputs) as numpy arrays, and a closed form for the simplest model."""

import json
import math

import numpy as np
import pytest

import pendkit
from pendkit import PendkitError


def test_modes_match_the_command_line(cli):
    s = pendkit.Model("double-pendulum").sensitivities("2")
    ref = json.loads(cli("sensitivity", "double-pendulum", "--stage", "2", "--json"))
    assert s.parameters == ref["parameters"]
    assert s.dfdp.shape == (len(ref["modes_hz"]), len(ref["parameters"]))
    assert np.array_equal(s.modes_hz, np.array(ref["modes_hz"]))
    assert np.array_equal(s.dfdp, np.array(ref["dfdp"]))
    assert s.exact == ref["exact"]


def test_tf_and_noise_match_the_command_line(cli):
    s = pendkit.Model("pendulum").sensitivities(
        modes=False, tf=("x00", "x1"), noise="x1", freqs=[0.1, 2.0], parameters=["l_fibre", "m1"]
    )
    ref = json.loads(
        cli(
            "sensitivity", "pendulum", "--tf", "x00:x1", "--noise", "x1", "--freqs", "0.1,2",
            "--parameters", "l_fibre,m1", "--json",
        )
    )
    assert s.dtf_abs_dp.shape == (2, 2)
    assert np.array_equal(s.tf_abs, np.array(ref["tf_abs"]))
    assert np.array_equal(s.dtf_abs_dp, np.array(ref["dtf_abs_dp"]))
    assert np.array_equal(s.dnoise_asd_dp, np.array(ref["dnoise_asd_dp"]))


def test_mass_on_springs_closed_form():
    # the toy: f = √(k/m)/2π for springs in series, so df/dm = −f/(2m) exactly (1e-9:
    # exact derivatives, or the matrices' difference of linear springs, exact but for
    # rounding)
    s = pendkit.Model("toy").sensitivities("0a", parameters=["m"])
    f = s.modes_hz[0]
    assert s.dfdp[0, 0] == pytest.approx(-f / (2 * s.values[0]), rel=1e-9)
    # the difference route gives the same within its own accuracy
    d = pendkit.Model("toy").sensitivities("0a", parameters=["m"], differences=True)
    assert d.exact == [False]
    assert d.dfdp[0, 0] == pytest.approx(-f / (2 * s.values[0]), rel=1e-9)


def test_bad_parameter_is_an_error(cli):
    with pytest.raises(PendkitError) as e:
        pendkit.Model("pendulum").sensitivities(parameters=["nope"])
    assert str(e.value) == cli.error("sensitivity", "pendulum", "--parameters", "nope")


def _sensitivities_in_child(queue):
    s = pendkit.Model("double-pendulum").sensitivities("2")
    queue.put(s.dfdp.tolist())


@pytest.mark.skipif(
    "fork" not in __import__("multiprocessing").get_all_start_methods(),
    reason="no fork on this platform",
)
def test_a_forked_process_computes_after_its_parent_did():
    # the library keeps worker threads once it has used them; a process forked afterwards
    # (multiprocessing's fork start method) has their handles but not the threads, and must
    # make its own rather than hand them work (which waited forever before this test)
    import multiprocessing

    parent = pendkit.Model("double-pendulum").sensitivities("2")
    context = multiprocessing.get_context("fork")
    queue = context.Queue()
    child = context.Process(target=_sensitivities_in_child, args=(queue,))
    child.start()
    child.join(60)
    if child.is_alive():
        child.kill()
        pytest.fail("the forked process did not finish in 60 s")
    assert child.exitcode == 0
    # the same numbers as the parent's (the same library on the same inputs)
    assert np.array_equal(np.array(queue.get(timeout=5)), parent.dfdp)
