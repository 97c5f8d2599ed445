"""The exported state space: closed-form matrices on the toy model, and python-control's
own frequency response of it against `tf`."""

import numpy as np
import pytest

import pendkit

control = pytest.importorskip("control")


def test_toy_state_space_is_the_closed_form():
    # DESIGN.md §5: the toy (1 kg on k1 = 1000 N/m in series with k2 = 3000 N/m through a
    # massless junction, so k = 750 N/m) with inputs (s, force:x) and outputs (x, force:s):
    # A = [[0, 1], [-k, 0]], B = [[0, 0], [k, 1]], C = [[1, 0], [k, 0]], D = [[0, 0], [-k, 0]]
    # (the Rust oracle tests/oracles_responses.rs checks the same matrices in the library)
    ss = pendkit.Model("toy").run("0b").state_space()
    k = 750.0
    assert ss.states == ["x", "x_dot"]
    assert ss.inputs == ["s", "force:x"] and ss.outputs == ["x", "force:s"]
    assert ss.input_units == ["m", "N"] and ss.output_units == ["m", "N"]
    for got, want in [(ss.A, [[0, 1], [-k, 0]]), (ss.B, [[0, 0], [k, 1]]),
                      (ss.C, [[1, 0], [k, 0]]), (ss.D, [[0, 0], [-k, 0]])]:
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * k)
    # selecting inputs and outputs by name picks columns and rows
    one = pendkit.Model("toy").run("0b").state_space(["force:x"], ["x"])
    np.testing.assert_array_equal(one.B, ss.B[:, [1]])
    np.testing.assert_array_equal(one.C, ss.C[[0], :])
    np.testing.assert_array_equal(one.D, ss.D[[0]][:, [1]])


@pytest.mark.parametrize("model, coordinate", [
    ("quad", "x3"), ("quad", "pitch3"), ("quad", "z3"), ("triple", "x3"), ("triple", "yaw3"),
])
def test_python_control_response_reproduces_tf_at_the_damping_frequency(model, coordinate):
    # The state space represents each damping term as viscous at damping_frequency f_d:
    # C = Im K(f_d) / (2π f_d), so at s = 2πi f_d its response to a force is exactly
    # (K(f_d) - ω² M)^-1, the transfer function `tf` computes directly from the complex
    # stiffness. python-control evaluates C (sI - A)^-1 B + D with its own linear algebra
    # (a second, independent method); the tolerance 1e-9 is rounding in solving the
    # 2n × 2n system, whose conditioning grows with the spread of the modes' frequencies.
    result = pendkit.Model(model).run()
    force = f"force:{coordinate}"
    for f_d in [0.3, 1.0, 3.0, 10.0, 40.0]:
        ss = result.state_space([force], [coordinate], damping_frequency=f_d)
        sys = ss.to_control()
        assert sys.ninputs == 1 and sys.noutputs == 1
        # python-control's names are identifiers: force:x3 is force_x3
        assert sys.input_labels == [f"force_{coordinate}"]
        assert sys.output_labels == [coordinate]
        response = complex(np.squeeze(sys(2j * np.pi * f_d)))
        expected = result.tf(force, coordinate, [f_d])[0]
        assert abs(response - expected) <= 1e-9 * abs(expected), (f_d, response, expected)


def test_state_space_in_ligo_names():
    ss = pendkit.Model("quad").run().state_space(["force:L3_L"], ["L3_L", "L3_P"],
                                                  naming="ligo")
    assert ss.inputs == ["force:L3_L"] and ss.outputs == ["L3_L", "L3_P"]
    assert ss.output_units == ["m", "rad"] and ss.input_units == ["N"]
    assert "L3_P_dot" in ss.states
