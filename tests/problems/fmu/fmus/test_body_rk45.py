"""The unit fmus/body_rk45 (a tool export's style: an embedded RK45/RK4 solver, value references per type, typed
parameters, outputs only from doStep) through fmpy's low-level API: under a constant force the free body follows
the parabola for both solvers, its typed start values round-trip without aliasing across types, the acceleration
changes only at a step, a bad solverType is refused with a message, and a restored step repeats bit for bit."""

import numpy as np
import pytest
from helpers import fmu_instance

pytestmark = pytest.mark.fmu


# value references, per type
M, G, F, X, V, A, TOL = range(7)  # Real
GRAVITY = 0  # Boolean
NSTEPS, DIRECTION = 0, 1  # Integer, Enumeration
SOLVER = 0  # String
DOWN, UP = 1, 2


def initialised(tmp_path, messages=None, *, solver="RK45", m=400.0, F0=0.0, x0=0.0, v0=0.0, gravity=None):
    body = fmu_instance("body_rk45", tmp_path / "unit", messages)
    body.setupExperiment(startTime=0.0)
    body.enterInitializationMode()
    body.setString([SOLVER], [solver])
    body.setReal([M, F, X, V], [m, F0, x0, v0])
    if gravity is not None:
        body.setBoolean([GRAVITY], [True])
        body.setInteger([DIRECTION], [gravity])
    body.exitInitializationMode()
    return body


@pytest.mark.parametrize("solver", ["RK45", "RK4"])
@pytest.mark.parametrize("gravity", [None, DOWN, UP])
def test_constant_force_gives_the_parabola(tmp_path, solver, gravity):
    """x = x0 + v0 t + a t^2 / 2 with a = -F/m - g (down) or + g (up): both solvers are exact for it up to rounding,
    over steps of H = 1e-3 and steps of other sizes."""
    m, F, x0, v0, g = 400.0, 1000.0, 0.3, -1.5, 9.81
    body = initialised(tmp_path, solver=solver, m=m, F0=F, x0=x0, v0=v0, gravity=gravity)
    acc = -F / m - {None: 0.0, DOWN: g, UP: -g}[gravity]
    sizes = [1e-3] * 20 + [2.5e-3, 0.4e-3, 7e-3] * 5
    t, got, want = 0.0, [], []
    for h in sizes:
        body.doStep(t, h)
        t += h
        got.append(body.getReal([X, V, A]))
        want.append([x0 + v0 * t + acc * t**2 / 2, v0 + acc * t, acc])
    body.terminate()
    body.freeInstance()
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)


def test_typed_start_values_round_trip_without_aliasing(tmp_path):
    """The defaults are the model description's start values; each type's setter changes only its own variable,
    though Real, Boolean, Integer and String all have a variable with value reference 0."""
    from fmpy import read_model_description

    body = fmu_instance("body_rk45", tmp_path / "unit")
    md = read_model_description(body.unzipDirectory)
    start = {v.name: v.start for v in md.modelVariables}
    assert body.getReal([M, G, TOL]) == [float(start["m"]), float(start["g"]), float(start["tolerance"])]
    assert body.getBoolean([GRAVITY]) == [start["inGravityField"] == "true"]
    assert body.getInteger([NSTEPS, DIRECTION]) == [int(start["nSteps"]), int(start["gravityDirection"])]
    assert body.getString([SOLVER]) == [start["solverType"].encode()]

    body.setBoolean([GRAVITY], [True])
    assert body.getReal([M]) == [400.0] and body.getInteger([NSTEPS]) == [10] and body.getString([SOLVER]) == [b"RK45"]
    body.setInteger([NSTEPS, DIRECTION], [7, UP])
    assert body.getReal([M, G]) == [400.0, 9.81] and body.getBoolean([GRAVITY]) == [True]
    body.setString([SOLVER], ["RK4"])
    body.setReal([M], [250.0])
    assert body.getBoolean([GRAVITY]) == [True] and body.getInteger([NSTEPS, DIRECTION]) == [7, UP]
    assert body.getString([SOLVER]) == [b"RK4"] and body.getReal([M]) == [250.0]
    body.freeInstance()


def test_acceleration_changes_only_at_a_step(tmp_path):
    """No direct feedthrough: setting F leaves a (and x, v) as the last step or the initialisation left them."""
    body = initialised(tmp_path, F0=200.0)
    assert body.getReal([A]) == [-0.5]
    body.setReal([F], [800.0])
    assert body.getReal([X, V, A]) == [0.0, 0.0, -0.5]
    body.doStep(0.0, 1e-3)
    assert body.getReal([A]) == [-2.0]
    body.setReal([F], [0.0])
    assert body.getReal([A]) == [-2.0]
    body.doStep(1e-3, 1e-3)
    assert body.getReal([A]) == [0.0]
    body.terminate()
    body.freeInstance()


def test_bad_solver_type_is_refused_at_initialisation(tmp_path):
    messages = []
    with pytest.raises(Exception, match="fmi2ExitInitializationMode failed with status 3"):
        initialised(tmp_path, messages, solver="Euler")
    assert [(m.instance, m.status) for m in messages] == [("unit", 3)]
    assert '"Euler"' in messages[0].text and '"RK4"' in messages[0].text and '"RK45"' in messages[0].text


def test_parameters_are_fixed_after_initialisation(tmp_path):
    messages = []
    body = initialised(tmp_path, messages)
    with pytest.raises(Exception, match="status 3"):
        body.setReal([M], [1.0])
    with pytest.raises(Exception, match="status 3"):
        body.setBoolean([GRAVITY], [True])
    assert body.getReal([M]) == [400.0] and body.getBoolean([GRAVITY]) == [False]
    assert [m.text for m in messages] == [
        "fmi2SetReal: m cannot be set after initialisation",
        "fmi2SetBoolean: inGravityField cannot be set after initialisation",
    ]
    body.freeInstance()


def test_restored_and_deserialised_steps_repeat_bit_for_bit(tmp_path):
    """The RK45 step size carried from step to step is part of the saved state."""
    body = initialised(tmp_path, F0=-300.0, v0=2.0, gravity=DOWN)
    t = 0.0
    for _ in range(3):
        body.doStep(t, 1e-3)
        t += 1e-3
    state = body.getFMUstate()
    serialised = body.serializeFMUstate(state)
    body.doStep(t, 3e-3)
    first = body.getReal([X, V, A])
    body.setFMUstate(state)
    body.doStep(t, 3e-3)
    assert body.getReal([X, V, A]) == first
    body.doStep(t + 3e-3, 1e-3)
    restored = body.deSerializeFMUstate(serialised)
    body.setFMUstate(restored)
    body.doStep(t, 3e-3)
    assert body.getReal([X, V, A]) == first
    body.freeFMUstate(state)
    body.freeFMUstate(restored)
    body.terminate()
    body.freeInstance()
