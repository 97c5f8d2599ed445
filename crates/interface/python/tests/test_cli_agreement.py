"""The Python package gives the command line's numbers, digit for digit.

Reference: the `pendkit` command line (tests/conftest.py) on the same model, case and
overrides: `modes --json`, `tf --csv`, `noise --csv --breakdown`, whose JSON and CSV print
the shortest text that reads back the same f64. Both run the same library functions on the
same inputs in the same order, so equality is exact (no tolerance): any difference would
mean the binding converts, reorders or recomputes something.
"""

import json

import numpy as np
import pytest

import pendkit

from conftest import CASES, parse_csv

HEAVIER = str(CASES / "ligo" / "cases" / "quad" / "heavier-test-mass.toml")

# (CLI model argument, --set overrides, a displacement output, a support input)
CASES_RUN = [
    ("pendulum", [], "x1", "x00"),
    ("double-pendulum", [], "x2", "x00"),
    ("triple", [], "x3", "x00"),
    ("quad", [], "x3", "x00"),
    ("quad", ["d4=0.01", "m3=scale(1.1)"], "pitch3", "pitch00"),
    (HEAVIER, [], "x3", "x00"),
]


def set_args(sets):
    return [a for s in sets for a in ("--set", s)]


def ids(case):
    spec, sets, _, _ = case
    return spec.rsplit("/", 1)[-1] + ("+" + ",".join(sets) if sets else "")


@pytest.fixture(scope="module", params=CASES_RUN, ids=ids)
def case(request):
    spec, sets, output, support = request.param
    result = pendkit.Model(spec, set=sets).run()
    return spec, sets, output, support, result


def test_modes_equal_the_command_line(cli, case):
    spec, sets, _, _, result = case
    expected = json.loads(cli("modes", spec, "--json", *set_args(sets)))
    modes = result.modes()
    assert modes.coordinates == expected["coordinates"]
    assert modes.coordinate_units == expected["coordinate_units"]
    assert len(modes) == len(expected["modes"])
    want = expected["modes"]
    assert modes.frequencies.tolist() == [m["hz"] for m in want]
    assert modes.omega_squared.tolist() == [m["omega_squared"] for m in want]
    assert modes.stable.tolist() == [m["stable"] for m in want]
    assert modes.labels == [m["label"] for m in want]
    assert modes.families == [m["family"] for m in want]
    assert modes.shapes.tolist() == [m["vector"] for m in want]
    assert modes.energy_fractions.tolist() == [m["energy_fractions"] for m in want]
    assert result.equilibrium() == expected["equilibrium"]
    assert bool(result.stability()) == all(m["stable"] for m in want)


def test_modes_in_ligo_names_equal_the_command_line(cli):
    expected = json.loads(cli("modes", "quad", "--json", "--naming", "ligo"))
    modes = pendkit.Model("quad").run().modes(naming="ligo")
    assert modes.labels == [m["label"] for m in expected["modes"]]
    assert modes.coordinates == expected["coordinates"]


def test_transfer_functions_equal_the_command_line(cli, case):
    spec, sets, output, support, result = case
    grid = ["--from", "0.05", "--to", "50", "--points", "37"]
    freqs = pendkit.log_grid(0.05, 50.0, 37)
    for inp in [support, f"force:{output}"]:
        text = cli("tf", spec, "--input", inp, "--output", output, "--csv", *grid,
                   *set_args(sets))
        header, (f, re, im) = parse_csv(text)
        assert f == freqs.tolist()
        h = result.tf(inp, output, freqs)
        assert h.dtype == np.complex128 and h.shape == (37,)
        assert h.real.tolist() == re and h.imag.tolist() == im, inp
        assert header[1] == "re_" + pendkit_slug(result.transfer_unit(inp, output))


def pendkit_slug(unit):
    # the command line's column-name form of a unit (unit_slug, crates/interface/pendkit/src/describe.rs)
    text = unit.replace("√Hz", "rthz").replace("^", "").replace("/", " per ")
    return "_".join(text.replace("(", " ").replace(")", " ").split())


def test_noise_and_its_breakdown_equal_the_command_line(cli, case):
    spec, sets, output, _, result = case
    text = cli("noise", spec, "--output", output, "--csv", "--breakdown", "--from", "0.1",
               "--to", "1000", "--points", "41", *set_args(sets))
    header, columns = parse_csv(text)
    noise = result.noise(output, pendkit.log_grid(0.1, 1000.0, 41))
    assert noise.freqs.tolist() == columns[0]
    assert noise.asd.tolist() == columns[1]
    slug = header[1][len("asd_"):]
    tags = [h[len("asd_"):-len(slug) - 1] for h in header[2:]]
    assert list(noise.asd_by_tag) == tags
    for tag, column in zip(tags, columns[2:]):
        assert noise.asd_by_tag[tag].tolist() == column, tag
    # the breakdown adds up to the total (a property of the PSDs, to rounding)
    total = sum(noise.psd_by_tag.values())
    np.testing.assert_allclose(total, noise.psd, rtol=1e-12)
    assert np.array_equal(noise.asd, np.sqrt(noise.psd))


def test_full_solve_gives_the_restricted_numbers():
    # the restricted solve (only the blocks the output couples to) against solving every
    # variable: the same equations, different elimination order, so rounding-level
    r = pendkit.Model("quad").run()
    f = pendkit.log_grid(0.1, 100.0, 25)
    np.testing.assert_allclose(r.tf("x00", "x3", f, full=True), r.tf("x00", "x3", f),
                               rtol=1e-9)
    np.testing.assert_allclose(r.noise("x3", f, full=True).psd, r.noise("x3", f).psd,
                               rtol=1e-9)


def test_parameters_list_what_the_model_resolves(cli):
    m = pendkit.Model("quad", set={"m3": 45, "d4": "0.01"})
    params = {p.name: p for p in m.parameters()}
    assert params["m3"].value == 45.0 and params["m3"].overridden
    assert params["m3"].unit == "kg" and params["m3"].definition == "45"
    assert params["d4"].value == 0.01 and params["d4"].unit == "m"
    assert not params["g"].overridden
    # the resolved values the state-space export records as provenance
    assert [p.name for p in m.run().parameters()] == list(params)


def test_fibres_choice_equals_the_command_line(cli, tmp_path):
    # `Model.run(fibres=...)` against `noise --fibres ...`, and a file's `continuum = true`
    # without a flag against both: the same terms of the same wires, so the same digits.
    # The continuum's violin peak at 493 Hz and the static model's no peak make the cases
    # far apart, so an ignored choice cannot pass.
    freqs = [100.0, 493.0]
    marked = tmp_path / "marked.toml"
    marked.write_text('extends = "quad-aligo"\n[stages.testmass.fibres]\ncontinuum = true\n')

    def command_line(spec, *flag):
        _, columns = parse_csv(cli("noise", spec, "--output", "tm_beam", "--csv",
                                   "--freqs", "100,493", *flag))
        return columns[1]

    continuum = command_line("quad-aligo", "--fibres", "continuum")
    static = command_line("quad-aligo")
    assert continuum[1] > 100 * static[1]
    cases = [
        (pendkit.Model("quad-aligo").run(fibres="continuum"), continuum),
        (pendkit.Model("quad-aligo").run(fibres=["f1", "f2", "f3", "f4"]), continuum),
        (pendkit.Model("quad-aligo").run(), static),
        (pendkit.Model(str(marked)).run(), continuum),
        (pendkit.Model(str(marked)).run(fibres="static"), static),
    ]
    for result, expected in cases:
        assert result.noise("tm_beam", freqs).asd.tolist() == expected
    assert command_line(str(marked)) == continuum
    # a result pickles with its fibres
    import pickle
    again = pickle.loads(pickle.dumps(cases[0][0]))
    assert again == cases[0][0] and again != cases[2][0]
    assert again.noise("tm_beam", freqs).asd.tolist() == continuum
    with pytest.raises(ValueError, match="fibres"):
        pendkit.Model("quad-aligo").run(fibres="beads")
    with pytest.raises(TypeError, match="fibres"):
        pendkit.Model("quad-aligo").run(fibres=3)
    with pytest.raises(pendkit.PendkitError, match="no wire"):
        pendkit.Model("quad-aligo").run(fibres=["nowire"])
