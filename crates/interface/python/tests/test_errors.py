"""Bad input raises `pendkit.PendkitError` (a ValueError) with the command line's one-line
message, never a crash or a NaN. The reference messages come from running the command
line (tests/conftest.py) on the same mistake."""

import math
from pathlib import Path

import numpy as np
import pytest

import pendkit
from pendkit import PendkitError


def test_error_class_is_a_value_error():
    assert issubclass(PendkitError, ValueError)


def test_unknown_model(cli):
    with pytest.raises(PendkitError) as e:
        pendkit.Model("nosuch")
    assert str(e.value) == cli.error("modes", "nosuch")


def test_unknown_parameter(cli):
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad", set={"nosuch": 3}).run()
    assert str(e.value) == cli.error("modes", "quad", "--set", "nosuch=3")
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad", set={"nosuch": 3}).parameters()
    assert str(e.value) == cli.error("modes", "quad", "--set", "nosuch=3")


def test_bad_override_syntax(cli):
    # the library's own terms (an override); the command line names its flag instead
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad", set=["d4"])
    assert str(e.value) == "override 'd4': expected NAME=EXPR or damping.<tag>.<field>=EXPR"
    assert cli.error("modes", "quad", "--set", "d4").startswith("--set 'd4': expected NAME=EXPR")


def test_bad_parameter_value(cli):
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad", set={"m3": "2*"}).run()
    assert str(e.value) == cli.error("modes", "quad", "--set", "m3=2*")


def test_missing_case_file(cli, tmp_path):
    path = str(tmp_path / "none.toml")
    with pytest.raises(PendkitError) as e:
        pendkit.Model(path)
    assert str(e.value) == cli.error("modes", path)


def test_bad_case_file(cli, tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('model = "quad"\n[parameters]\nm3 = [1, 2]\n')
    with pytest.raises(PendkitError) as e:
        pendkit.Model(path)  # a pathlib.Path works as a spec
    assert str(e.value) == cli.error("modes", str(path))


def test_unknown_output_and_input(cli):
    r = pendkit.Model("quad").run()
    with pytest.raises(PendkitError) as e:
        r.tf("x00", "nope", [1.0])
    assert str(e.value) == cli.error("tf", "quad", "--input", "x00", "--output", "nope",
                                     "--freqs", "1")
    with pytest.raises(PendkitError) as e:
        r.tf("x3", "x3", [1.0])
    assert str(e.value) == cli.error("tf", "quad", "--input", "x3", "--output", "x3",
                                     "--freqs", "1")
    with pytest.raises(PendkitError) as e:
        r.noise("force:x00", [1.0])
    assert str(e.value) == cli.error("noise", "quad", "--output", "force:x00", "--freqs", "1")


def test_losses_need_stage_0b(cli):
    r = pendkit.Model("quad").run("0a")
    message = cli.error("noise", "quad", "--stage", "0a", "--output", "x3", "--freqs", "1")
    for call in [lambda: r.noise("x3", [1.0]), lambda: r.tf("x00", "x3", [1.0]),
                 lambda: r.state_space()]:
        with pytest.raises(PendkitError) as e:
            call()
        assert str(e.value) == message


def test_unknown_stage(cli):
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad").run("3")
    # clap puts its own words around the library's message
    assert str(e.value) in cli.error("modes", "quad", "--stage", "3")


def test_unknown_naming_scheme(cli):
    with pytest.raises(PendkitError) as e:
        pendkit.Model("quad").run().modes(naming="foo")
    assert str(e.value) == cli.error("modes", "quad", "--naming", "foo")


@pytest.mark.parametrize("bad, cli_text", [
    ([1.0, math.nan], "nan"), ([1.0, -2.0], "-2"), ([0.0], "0"), ([math.inf], "inf"),
    ([-math.inf], "-inf"),
])
def test_bad_frequencies(cli, bad, cli_text):
    r = pendkit.Model("pendulum").run()
    for call in [lambda: r.tf("x00", "x1", np.array(bad)), lambda: r.noise("x1", bad)]:
        with pytest.raises(PendkitError) as e:
            call()
        place, message = str(e.value).split(": ", 1)
        assert place == f"freqs[{len(bad) - 1}]"
        expected = cli.error("noise", "pendulum", "--output", "x1", "--freqs",
                             ",".join(["1"] * (len(bad) - 1) + [cli_text]))
        assert expected == f"--freqs: {message}"


@pytest.mark.parametrize("bad", [
    np.ones((2, 3)), [[1.0], [2.0]], [], np.array([]), ["a", "b"], [1.0, None], "10",
])
def test_frequency_arrays_of_the_wrong_shape_or_kind(bad):
    r = pendkit.Model("pendulum").run()
    with pytest.raises(PendkitError, match="^freqs"):
        r.tf("x00", "x1", bad)
    with pytest.raises(PendkitError, match="^freqs"):
        r.noise("x1", bad)


def test_frequencies_of_any_real_dtype_and_strides_work():
    r = pendkit.Model("pendulum").run()
    f = np.linspace(1.0, 10.0, 10)
    reference = r.tf("x00", "x1", f)
    assert np.array_equal(r.tf("x00", "x1", f.astype(np.float32).astype(np.float64)),
                          r.tf("x00", "x1", f.astype(np.float32)))
    assert np.array_equal(r.tf("x00", "x1", list(f)), reference)
    assert np.array_equal(r.tf("x00", "x1", np.arange(1, 11)), reference)
    assert np.array_equal(r.tf("x00", "x1", np.repeat(f, 2)[::2]), reference)
    assert np.array_equal(r.tf("x00", "x1", f[::-1])[::-1], reference)
    # a misaligned buffer (as Dask unpickles arrays out of band): read by copying, not a
    # panic
    raw = np.zeros(8 * f.size + 1, dtype=np.uint8)
    misaligned = np.frombuffer(raw.data, dtype=np.float64, count=f.size, offset=1)
    misaligned[:] = f
    assert not misaligned.flags.aligned
    assert np.array_equal(r.tf("x00", "x1", misaligned), reference)
    assert np.array_equal(r.noise("x1", misaligned).psd, r.noise("x1", f).psd)


def test_bad_spec_and_set_types():
    # wrong types are TypeErrors naming the argument (test_boundary.py has their words)
    with pytest.raises(TypeError, match="^spec"):
        pendkit.Model(3)
    with pytest.raises(TypeError, match="^set"):
        pendkit.Model("quad", set="d4=1")
    with pytest.raises(TypeError, match="^set"):
        pendkit.Model("quad", set=[1, 2])
    with pytest.raises(TypeError, match="^set"):
        pendkit.Model("quad", set=5)


def test_state_space_names_are_checked():
    r = pendkit.Model("pendulum").run()
    with pytest.raises(PendkitError, match="'nope': not an input of the state space"):
        r.state_space(["nope"])
    with pytest.raises(PendkitError, match="'nope': not an output of the state space"):
        r.state_space(None, ["nope"])


def test_unstable_equilibrium_is_a_verdict_not_a_crash(cli):
    # gravity reversed at stage 0A (fibres stretch only): an inverted pendulum of length
    # l_fibre = 0.6 m, whose two swing modes grow at sqrt(g/l)/2π; pendkit reports them as
    # negative frequencies of that size (the fibres' axial stiffness does not enter the
    # swing, hence the tight tolerance)
    r = pendkit.Model("pendulum", set={"g": -9.81}).run("0a")
    verdict = r.stability()
    assert not verdict.stable and not verdict
    modes = r.modes()
    assert verdict.unstable_modes == [0, 1]
    growth = math.sqrt(9.81 / 0.6) / (2 * math.pi)
    np.testing.assert_allclose(modes.frequencies[:2], [-growth, -growth], rtol=1e-9)
    assert not modes.stable[:2].any() and modes.stable[2]
    message = cli.error("modes", "pendulum", "--stage", "0a", "--set", "g=-9.81")
    assert verdict.message == message
    with pytest.raises(PendkitError) as e:
        r.check_stable()
    assert str(e.value) == message
