"""The package's boundary: numbers of any real type taken exactly, wrong types and values
refused naming the argument, `PendkitError` importable and picklable, every result type
picklable and equal after the round trip, and models compared by value.

The references are independent of the path under test: a number given as numpy's scalar is
checked against the same number given as the decimal text that reads back as it (the
expression parser's route), and the value the model resolved is read back through
`parameters()`; an error's message against the command line's for the same mistake."""

import concurrent.futures
import fractions
import math
import multiprocessing
import pickle

import numpy as np
import pytest

import pendkit
from pendkit import PendkitError

FREQS = np.logspace(-1, 1.5, 40)  # Hz


def m3_of(model):
    """The test mass (kg) as the model resolved it."""
    return next(p.value for p in model.parameters() if p.name == "m3")


# --- numbers -------------------------------------------------------------------------


def test_numpy_floats_from_linspace_set_parameters():
    # the reported defect: under numpy 2, repr(np.float64(30.0)) is "np.float64(30.0)",
    # which was passed on as an expression ("unknown function 'np.float64'")
    for v in np.linspace(30, 50, 11):
        assert type(v) is np.float64
        model = pendkit.Model("quad", set={"m3": v})
        assert m3_of(model) == float(v)
        # the same value through the command line's route: the decimal text that reads
        # back as the same f64
        as_text = pendkit.Model("quad", set=[f"m3={float(v)!r}"])
        assert np.array_equal(model.run().modes().frequencies,
                              as_text.run().modes().frequencies)


@pytest.mark.parametrize("value", [
    np.float32(40.1), np.float16(40.5), np.int64(40), np.int8(40), np.uint16(40),
    np.array(40.3), np.array(40, dtype=np.int32), fractions.Fraction(401, 10), 40,
    np.longdouble(40.2),
])
def test_any_real_number_is_taken_as_its_exact_float(value):
    # float32(40.1) is 40.09999847..., not 40.1: the value is the number itself, with no
    # decimal text in between to round it
    expected = float(value)
    model = pendkit.Model("quad", set={"m3": value})
    assert m3_of(model) == expected
    # `sets` shows it as a text that reads back as the same float
    [text] = model.sets
    assert text.startswith("m3=") and float(text[3:]) == expected


def test_numbers_set_damping_fields_too():
    exact = pendkit.Model("quad", set={"damping.fibre_bending.structural": np.float64(2e-7)})
    text = pendkit.Model("quad", set=["damping.fibre_bending.structural=2e-7"])
    assert np.array_equal(exact.run().noise("x3", FREQS).psd,
                          text.run().noise("x3", FREQS).psd)


def test_numpy_numbers_elsewhere():
    r = pendkit.Model("pendulum").run()
    assert np.array_equal(pendkit.log_grid(np.float64(1.0), np.array(100.0), np.int64(5)),
                          pendkit.log_grid(1.0, 100.0, 5))
    a = r.state_space(damping_frequency=np.float32(2.0))
    b = r.state_space(damping_frequency=2.0)
    assert a == b
    assert pendkit.Model("quad").run(np.int64(2)) == pendkit.Model("quad").run("2")


@pytest.mark.parametrize("bad, text", [
    (math.nan, "nan"), (np.float64("inf"), "inf"), (-np.inf, "-inf"),
    (np.array(np.nan), "nan"), (np.float32("nan"), "nan"),
])
def test_non_finite_values_are_refused_naming_the_parameter(bad, text):
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad", set={"m3": bad})
    assert str(e.value) == f"set['m3']: value {text} is not finite"


def test_a_number_too_large_for_a_float_names_the_parameter():
    with pytest.raises(PendkitError, match=r"^set\['m3'\]: .*too large"):
        pendkit.Model("quad", set={"m3": 10 ** 400})


# --- types ---------------------------------------------------------------------------


@pytest.mark.parametrize("bad, name", [
    ([1, 2], "list"), (True, "bool"), (np.bool_(True), "numpy.bool"), (None, "NoneType"),
    (1 + 2j, "complex"), (np.array([40.0, 41.0]), "numpy.ndarray"), (b"40", "bytes"),
    (np.complex128(40), "numpy.complex128"),
])
def test_a_value_of_the_wrong_type_is_a_type_error_naming_it(bad, name):
    with pytest.raises(TypeError) as e:
        pendkit.Model("quad", set={"m3": bad})
    assert str(e.value) == (
        f"set['m3']: expected a real number or an expression string, got {name}")


def test_wrong_types_of_the_other_arguments():
    with pytest.raises(TypeError, match=r"^spec: expected a model name or a case-file "
                                        r"path \(str or os.PathLike\), got int$"):
        pendkit.Model(3)
    with pytest.raises(TypeError, match=r"^set: .*, got one str$"):
        pendkit.Model("quad", set="d4=1")
    with pytest.raises(TypeError, match=r"^set\[1\]: expected a 'NAME=EXPR' string, got int$"):
        pendkit.Model("quad", set=["d4=1", 2])
    with pytest.raises(TypeError, match=r"^set: .*, got int$"):
        pendkit.Model("quad", set=5)
    with pytest.raises(TypeError, match=r"^set: the keys are parameter names \(str\), got int$"):
        pendkit.Model("quad", set={3: 1.0})
    with pytest.raises(TypeError, match=r"^stage: expected a stage name .*, got list$"):
        pendkit.Model("quad").run([2])
    with pytest.raises(TypeError, match=r"^stage: .*, got bool$"):
        pendkit.Model("quad").run(True)
    r = pendkit.Model("pendulum").run()
    with pytest.raises(TypeError, match="input"):
        r.tf(1, "x1", FREQS)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="damping_frequency"):
        r.state_space(damping_frequency="1")  # type: ignore[arg-type]
    model = pendkit.Model("quad")
    with pytest.raises(TypeError, match=r"^modes\[0\]\[1\]: expected a real number \(Hz\), "
                                        r"got list$"):
        model.fit([("x3", [0.43], 0.001)], ["m1"])
    with pytest.raises(TypeError, match=r"^modes: expected a file path or a list .*, got int$"):
        model.fit(3, ["m1"])  # type: ignore[arg-type]
    with pytest.raises(TypeError, match=r"^tf: expected a path \(str or os.PathLike\), got int$"):
        model.fit([("x3", 0.43, 0.001)], ["m1"], tf=3)  # type: ignore[arg-type]
    with pytest.raises(PendkitError, match=r"^jacobian: 'adjoint' is not a Jacobian method"):
        model.fit([("x3", 0.43, 0.001)], ["m1"], jacobian="adjoint")  # type: ignore[arg-type]


def test_numpy_numbers_in_measured_mode_tuples_are_exact(cli, tmp_path):
    # the fit from numpy numbers equals the fit from the command line's file of their
    # exact texts
    rows = [("x3", np.float64(0.4327705) * 1.01, np.float32(0.002)),
            ("y3", np.array(0.4680829) * 1.01, np.float16(0.002))]
    path = tmp_path / "two.csv"
    path.write_text("".join(f"{label},{float(hz)!r},{float(sigma)!r}\n"
                            for label, hz, sigma in rows))
    from_tuples = pendkit.Model("quad").fit(rows, ["m3"])
    from_file = pendkit.Model("quad").fit(str(path), ["m3"])
    assert from_tuples["parameters"] == from_file["parameters"]
    with pytest.raises(PendkitError, match=r"^modes:1: hz must be positive and finite, got nan"):
        pendkit.Model("quad").fit([("x3", np.nan, 0.001)], ["m3"])


# --- PendkitError --------------------------------------------------------------------


def test_pendkit_error_is_one_class_importable_from_pendkit():
    assert pendkit.PendkitError is pendkit._pendkit.PendkitError
    assert PendkitError.__module__ == "pendkit" and PendkitError.__name__ == "PendkitError"
    assert issubclass(PendkitError, ValueError)


def test_pendkit_error_pickles_with_its_message(cli):
    with pytest.raises(PendkitError) as e:
        pendkit.Model("nosuch")
    copy = pickle.loads(pickle.dumps(e.value))
    assert type(copy) is PendkitError
    assert str(copy) == str(e.value) == cli.error("modes", "nosuch")


def run_point(m3):
    """A sweep point in a worker process (module level, so the pool can import it)."""
    return pendkit.Model("quad", set={"m3": m3}).run().modes()


def test_a_worker_process_returns_results_and_raises_pendkit_errors(cli):
    context = multiprocessing.get_context("spawn")
    with concurrent.futures.ProcessPoolExecutor(1, mp_context=context) as pool:
        good = pool.submit(run_point, np.float64(41.0)).result()
        bad = pool.submit(run_point, -1.0)
        with pytest.raises(PendkitError) as e:
            bad.result()
    assert good == run_point(41.0)
    assert str(e.value) == cli.error("modes", "quad", "--set", "m3=-1")


# --- results pickle and compare by value ---------------------------------------------


def round_trip(x):
    return pickle.loads(pickle.dumps(x))


def every_result(model):
    r = model.run()
    return [
        r,
        r.modes(),
        r.modes(naming="ligo"),
        r.noise("x3", FREQS),
        r.stability(),
        r.state_space(["force:x3", "x00"], ["x3", "x3_dot"]),
        model.sensitivities(tf=("x00", "x3"), noise="x3", freqs=FREQS[:5],
                            parameters=["m3", "d4"]),
        r.parameters()[0],
    ]


def test_every_result_type_pickles_and_is_equal_after_the_round_trip():
    a = every_result(pendkit.Model("quad", set={"d4": 0.01}))
    b = every_result(pendkit.Model("quad", set={"d4": 0.012}))
    for x, y in zip(a, b):
        copy = round_trip(x)
        assert type(copy) is type(x)
        assert copy == x and not copy != x, type(x).__name__
        # the equality can fail: another model gives another result (the Parameter
        # listed first is the same in both, and so is a stable verdict)
        if not isinstance(x, (pendkit.Parameter, pendkit.Stability)):
            assert x != y, type(x).__name__
    # a result unpickled is computed again, to the same numbers
    r = round_trip(a[0])
    assert r.modes() == a[1] and r.noise("x3", FREQS) == a[3]
    assert r.stage == "2" and r.name == "quad"


def test_an_unstable_verdict_and_a_case_file_result_round_trip(tmp_path):
    verdict = pendkit.Model("pendulum", set={"g": -9.81}).run("0a").stability()
    assert not verdict and round_trip(verdict) == verdict
    assert verdict != pendkit.Model("pendulum").run("0a").stability()
    case = tmp_path / "heavy.toml"
    case.write_text('model = "quad"\n[parameters]\nm3 = 45\n')
    r = pendkit.Model(case).run("1b")
    case.unlink()  # the pickle carries the case file's text
    copy = round_trip(r)
    assert copy == r and copy.stage == "1B" and copy.modes() == r.modes()


def test_arrays_compare_with_nan_equal_to_nan_and_by_dtype():
    r = pendkit.Model("pendulum").run()
    modes = r.modes()
    changed = pendkit.Modes(**{**vars(modes), "frequencies": modes.frequencies + 1e-15})
    assert changed != modes
    nan = pendkit.Modes(**{**vars(modes), "frequencies": np.full(len(modes), np.nan)})
    assert round_trip(nan) == nan
    as_float32 = pendkit.Modes(**{**vars(modes),
                                  "frequencies": modes.frequencies.astype(np.float32)})
    assert as_float32 != modes


# --- models compare by value ---------------------------------------------------------


def test_models_compare_by_value(tmp_path):
    a = pendkit.Model("quad", set={"d4": 0.01, "m3": 40})
    same = [
        pendkit.Model("quad", set={"m3": 40.0, "d4": 0.01}),
        pendkit.Model("quad", set=["m3=40", "d4=0.01"]),
        pendkit.Model("quad", set={"m3": np.int64(40), "d4": np.float64(0.01)}),
        pendkit.Model("quad").with_set({"m3": 40}).with_set(["d4 = 0.01"]),
        round_trip(a),
    ]
    for b in same:
        assert a == b and hash(a) == hash(b), b
    different = [
        pendkit.Model("quad", set={"d4": 0.01}),
        pendkit.Model("quad", set={"d4": 0.01, "m3": 40.000000001}),
        pendkit.Model("quad", set={"d4": 0.01, "m3": "39+1"}),
        pendkit.Model("triple", set={"d4": 0.01, "m3": 40}),
    ]
    for b in different:
        assert a != b, b
    assert len({a, *same, *different}) == 1 + len(different)
    assert pendkit.Model("quad") != "quad"
    case = tmp_path / "c.toml"
    case.write_text('model = "quad"\n')
    assert pendkit.Model(case) == pendkit.Model(str(case))
    other = tmp_path / "d.toml"
    other.write_text('model = "quad"\n')
    assert pendkit.Model(case) != pendkit.Model(other)


def test_results_compare_by_model_and_stage():
    assert pendkit.Model("quad").run() == pendkit.Model("quad").run("2")
    assert pendkit.Model("quad").run() != pendkit.Model("quad").run("1b")
    assert pendkit.Model("quad").run() != pendkit.Model("quad", set={"m3": 41}).run()
