"""Signal connections closed implicitly by the one macro step (:mod:`icosim.engine.connection_conditions`), on
test_signals' two exact integrators ``x_i' = u_i`` coupled ``u_1 = x_2``, ``u_2 = -x_1`` (the harmonic oscillator
from ``(1, 0)``).

Theory: with the conditions at ``T_N+1`` and held inputs (``k = 0``: each input holds ``e_N+1`` over the step) the
macro step is backward Euler, ``x' = x + H J x'`` with ``J = [[0, 1], [-1, 0]]``: ``|x|`` shrinks by exactly
``1 / sqrt(1 + H^2)`` per step.  With ``k = 1`` the input runs linearly from ``e_N`` to ``e_N+1``: the trapezoidal
rule (Crank-Nicolson), a Cayley transform of ``J``: ``|x|`` is kept, and the phase advances by ``2 atan(H / 2)``
per step.  The problem is linear, so Newton closes the conditions in one step.
"""

from __future__ import annotations

import numpy as np
import pytest
from test_signals import GRAPH, Integrators

from icosim.engine.connection_conditions import NotConverged
from icosim.engine.graph import Connection, CouplingGraph, Joint
from icosim.engine.joint_signal_conditions import JointSignalConditions
from icosim.engine.macrostep import macro_step
from icosim.engine.run import simulate
from icosim.engine.schemes import get_scheme
from icosim.engine.stages import plan


def implicit(k, H):
    problem = Integrators(k, H)
    problem.implicit_connections = True
    problem.connection_perturbation = 1.0  # a linear problem: the difference quotient is exact at any step
    return problem


@pytest.mark.parametrize("H", [0.1, 1.0, 3.0])
def test_held_inputs_give_backward_euler(H):
    problem = implicit(0, H)
    n = 20
    traj = simulate(problem, None, np.array([1.0, 0.0]), np.array([[0.0, -1.0]]), n, iterations=10, tol=1e-12)
    radius = np.linalg.norm(np.asarray(traj.states), axis=-1)
    assert np.allclose(radius, (1 + H**2) ** (-np.arange(n + 1) / 2), rtol=1e-12, atol=0)
    step = np.linalg.solve(np.eye(2) - H * np.array([[0, 1], [-1, 0]]), np.eye(2))
    assert np.allclose(traj.states[1], step @ [1.0, 0.0], rtol=0, atol=1e-12)
    assert problem.implicit_work.iterations == [1] * n  # one Newton step, then the test
    assert problem.implicit_work.perturbed_steps == 2 * n  # one per connection and step


@pytest.mark.parametrize("H", [0.1, 1.0, 3.0])
def test_linear_inputs_give_the_trapezoidal_rule(H):
    problem = implicit(1, H)
    n = 20
    history = np.array([[0.0, -1.0], [0.0, 0.0]])  # e_N consistent with x; e_N-1 enters only the predictor
    traj = simulate(problem, None, np.array([1.0, 0.0]), history, n, iterations=10, tol=1e-12)
    x = np.asarray(traj.states)
    assert np.allclose(np.linalg.norm(x, axis=-1), 1.0, rtol=0, atol=1e-12)
    phase = 2 * np.arctan(H / 2) * np.arange(n + 1)
    assert np.allclose(x, np.array([np.cos(phase), -np.sin(phase)]).T, rtol=0, atol=1e-11)


def test_gauss_seidel_closes_every_connection_at_its_last_stage():
    """The conditions at ``T_N+1`` are one system in the new values whatever the order: the last stage closes them
    all and steps again every unit a connection feeds, the earlier stage's too."""
    p = plan(get_scheme("gauss-seidel-12"), GRAPH, implicit=True)
    assert [(s.units, s.connections, s.corrected) for s in p.stages] == [((0,), (), ()), ((1,), (0, 1), (0, 1))]
    stage = plan(get_scheme("jacobi"), GRAPH, implicit=True).stages[0]
    assert stage.connections == (0, 1) and stage.corrected == (0, 1) and stage.joints == ()


@pytest.mark.parametrize("k", [0, 1])
@pytest.mark.parametrize("order", ["gauss-seidel-12", "gauss-seidel-21"])
def test_gauss_seidel_gives_jacobis_run(k, order):
    """Either order: Newton starts elsewhere (the later unit fed by the earlier one's new output) and reaches the
    same solution of the same conditions: backward Euler (``k = 0``) or the trapezoidal rule (``k = 1``) to
    rounding."""
    H, n = 0.5, 20
    history = np.array([[0.0, -1.0]] * (k + 1))
    runs = [simulate(implicit(k, H), None, np.array([1.0, 0.0]), history, n, scheme=scheme, iterations=10, tol=1e-13)
            for scheme in ("jacobi", order)]  # fmt: skip
    assert np.allclose(runs[1].states, runs[0].states, rtol=0, atol=1e-14)


def test_implicit_connections_beside_joints_are_closed_with_them_at_the_last_stage():
    """Unit 3 reads unit 1 beside the joint of units 1 and 2: one corrector closes the joint's conditions and the
    connection's (the joint's variables' columns first), stepping every joint unit and the unit the connection feeds
    again; explicitly, the joint closes alone."""
    graph = CouplingGraph(3, [Joint(0, 1, "fd")], connections=(Connection(0, 0, 2, 0),))
    for scheme in ("jacobi", "gauss-seidel-312"):
        last = plan(get_scheme(scheme), graph, implicit=True).stages[-1]
        assert isinstance(last.conditions, JointSignalConditions)
        assert (last.joints, last.connections, last.corrected, last.columns) == ((0,), (0,), (0, 1, 2), (0, 1, 2))
    assert plan(get_scheme("jacobi"), graph).stages[0].joints == (0,)


def test_a_unit_only_read_is_not_stepped_again():
    """Unit 3 feeds unit 1 and takes no connection: its predictor step is final."""
    graph = CouplingGraph(3, (), connections=(Connection(1, 0, 0, 0), Connection(0, 0, 1, 0), Connection(2, 0, 0, 1)))
    stage = plan(get_scheme("jacobi"), graph, implicit=True).stages[0]
    assert stage.corrected == (0, 1) and stage.units == (0, 1, 2)


def test_a_step_that_does_not_converge_names_the_connections():
    """One Newton step tested against a tolerance below rounding: the second solve's change is the first's rounding,
    above ``tol = 1e-300``."""
    problem = implicit(0, 0.5)
    with pytest.raises(NotConverged, match=r"did not converge in 1 iterations .*connection \d \(\d -> \d\)"):
        macro_step(problem, None, np.array([1.0, 0.3]), np.array([[0.3, -1.0]]), iterations=1, tol=1e-300)
