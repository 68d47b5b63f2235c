"""The unit fmus/statespace_fmi3 (an FMI 3.0 linear state-space system, structural parameters setting its array
sizes) through fmpy's low-level API: with its defaults (the mass-spring-damper) a step with the input held matches
the exact solution (scipy's matrix exponential of the system augmented by the constant input), y follows u without
a step, configuration mode resizes it to a scalar system, and what the standard does not allow is refused."""

import numpy as np
import pytest
from helpers import fmu_instance
from scipy.linalg import expm

pytestmark = pytest.mark.fmu

TIME, M, N, R, A, B, C, D, X0, U, Y = range(11)


def exact_step(a, b, x, u, h):
    """x(t + h) for x' = a x + b u with u held: exp(h [a b; 0 0]) applied to [x; u]."""
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n], aug[:n, n:] = a, b
    return (expm(h * aug) @ np.concatenate([x, u]))[:n]


def test_defaults_are_the_mass_spring_damper(tmp_path):
    from fmpy import read_model_description

    fmu = fmu_instance("statespace_fmi3", tmp_path / "unit")
    md = read_model_description(fmu.unzipDirectory)
    start = {v.name: [float(s) for s in v.start.split()] for v in md.modelVariables if v.start is not None}
    assert fmu.getUInt64([M, N, R]) == [1, 2, 3] == [int(start[k][0]) for k in "mnr"]
    values = fmu.getFloat64([A, B, C, D, X0, U], nValues=4 + 2 + 6 + 3 + 2 + 1)
    assert values == sum((start[k] for k in ["A", "B", "C", "D", "x0", "u"]), [])
    assert values[:12] == [0, 1, -1000, -2, 0, 1, 1, 0, 0, 1, -1000, -2]  # A, B, C row major
    fmu.freeInstance()


def test_steps_are_exact_and_y_follows_u_at_once(tmp_path):
    """Each step from the unit's state to 1e-12 of the largest output."""
    a, b = np.array([[0.0, 1.0], [-1000.0, -2.0]]), np.array([[0.0], [1.0]])
    c, d = np.array([[1.0, 0.0], [0.0, 1.0], [-1000.0, -2.0]]), np.array([[0.0], [0.0], [1.0]])
    x, u = np.array([0.01, -0.2]), np.array([3.0])
    fmu = fmu_instance("statespace_fmi3", tmp_path / "unit")
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setFloat64([X0, U], [*x, *u])
    fmu.exitInitializationMode()
    np.testing.assert_array_equal(fmu.getFloat64([Y], nValues=3), c @ x + d @ u)
    t = 0.0
    for h in [1e-3] * 10 + [2.5e-3, 4e-4, 1e-2] * 3:
        assert fmu.doStep(t, h) == (False, False, False, t + h)
        want, t = c @ exact_step(a, b, x, u, h) + d @ u, t + h
        y = fmu.getFloat64([Y], nValues=3)
        assert np.max(np.abs(y - want)) <= 1e-12 * np.max(np.abs(want))
        x = np.array(y[:2])  # the unit's state (C's first rows pick it): the next step starts from it
    fmu.setFloat64([U], [-5.0])  # no step: only the feedthrough D u moves y
    moved = fmu.getFloat64([Y], nValues=3)
    assert moved[:2] == y[:2] and moved[2] == pytest.approx(y[2] - 8.0, rel=1e-15)
    assert fmu.getFloat64([TIME]) == [t]
    fmu.terminate()
    fmu.freeInstance()


def test_configuration_mode_gives_a_scalar_system(tmp_path):
    fmu = fmu_instance("statespace_fmi3", tmp_path / "unit")
    fmu.enterConfigurationMode()
    fmu.setUInt64([M, N, R], [1, 1, 1])
    fmu.exitConfigurationMode()
    assert fmu.getUInt64([M, N, R]) == [1, 1, 1]
    assert fmu.getFloat64([A, B, C, D, X0, U], nValues=6) == [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]  # the upper-left entries
    fmu.setFloat64([A, B, C, D, X0], [-4.0, 2.0, 3.0, 0.5, 1.0])
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setFloat64([U], [1.5])
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 0.1)
    x = np.exp(-0.4) + (1 - np.exp(-0.4)) / 4 * 2 * 1.5
    assert fmu.getFloat64([Y]) == pytest.approx([3 * x + 0.5 * 1.5], rel=1e-14)
    fmu.terminate()
    fmu.freeInstance()


def test_what_is_refused(tmp_path):
    messages = []
    fmu = fmu_instance("statespace_fmi3", tmp_path / "unit", messages)
    with pytest.raises(Exception, match="fmi3SetUInt64 failed"):
        fmu.setUInt64([N], [1])  # not in configuration mode
    fmu.enterConfigurationMode()
    with pytest.raises(Exception, match="fmi3SetUInt64 failed"):
        fmu.setUInt64([N], [6])
    with pytest.raises(Exception, match="fmi3SetFloat64 failed"):
        fmu.setFloat64([U], [1.0])  # only structural parameters in configuration mode
    fmu.exitConfigurationMode()
    with pytest.raises(Exception, match="fmi3GetFloat64 failed"):
        fmu.getFloat64([A])  # one value asked for, A has four
    fmu.enterInitializationMode(startTime=0.0)
    fmu.exitInitializationMode()
    with pytest.raises(Exception, match="fmi3EnterConfigurationMode failed"):
        fmu.enterConfigurationMode()
    with pytest.raises(Exception, match="fmi3SetFloat64 failed"):
        fmu.setFloat64([D], [0.0, 0.0, 2.0])  # fixed
    assert fmu.getUInt64([M, N, R]) == [1, 2, 3]
    assert [m.status for m in messages] == [3] * 6
    assert [m.text for m in messages] == [
        "fmi3SetUInt64: the structural parameter n is set in Configuration Mode only",
        "fmi3SetUInt64: n = 6 is beyond the largest size, 5",
        "fmi3SetFloat64: u cannot be set in this state",
        "fmi3GetFloat64: 1 values given, but the variables have 4 (arrays whole, row major)",
        "fmi3EnterConfigurationMode: only from the state Instantiated (the structural parameters are fixed)",
        "fmi3SetFloat64: D cannot be set in this state",
    ]
    fmu.freeInstance()


def test_restored_and_deserialised_steps_repeat_bit_for_bit(tmp_path):
    fmu = fmu_instance("statespace_fmi3", tmp_path / "unit")
    fmu.enterInitializationMode(startTime=0.0)
    fmu.setFloat64([X0, U], [0.01, 0.0, 2.0])
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1e-3)
    state = fmu.getFMUState()
    serialised = fmu.serializeFMUState(state)
    fmu.doStep(1e-3, 1e-3)
    first = fmu.getFloat64([Y], nValues=3)
    fmu.setFMUState(state)
    fmu.doStep(1e-3, 1e-3)
    assert fmu.getFloat64([Y], nValues=3) == first
    fmu.setFloat64([U], [7.0])
    fmu.doStep(2e-3, 1e-3)
    restored = fmu.deserializeFMUState(serialised)
    fmu.setFMUState(restored)
    fmu.doStep(1e-3, 1e-3)
    assert fmu.getFloat64([Y], nValues=3) == first
    for s in (state, restored):
        fmu.freeFMUState(s)
    fmu.terminate()
    fmu.freeInstance()
