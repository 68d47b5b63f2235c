"""The problem contract's checkpoint (icosim.engine.problem.CosimulationProblem.checkpoint/restore): a problem
checkpointed, stepped on, restored and stepped again gives what its first step gave, bit for bit -- the linear
model, a chain and the double pendulum (the FMU problem: tests/problems/fmu/test_controlled_scenes.py); the run
loop's rollback leaves the problem at the trajectory's last state.
"""

import numpy as np
import pytest

from icosim import make_method
from icosim.engine.macrostep import macro_step
from icosim.engine.methods import engine_method
from icosim.engine.run import simulate
from icosim.problems.linear.chain import Chain, ChainSegment
from icosim.problems.linear.model import PhysicalModel
from icosim.problems.linear.problem import LinearCosimulation
from icosim.problems.pendulum.model import PendulumParameters
from icosim.problems.pendulum.problem import PendulumCosimulation
from icosim.problems.pendulum.reference import consistent_history

H = 1e-3
SEGMENT = ChainSegment(
    masses=(1.0, 0.5), ground_stiffness=(100.0, 50.0), ground_damping=(0.5, 0.2), stiffness=(2000.0,), damping=(1.0,)
)


def linear():
    problem = LinearCosimulation(
        PhysicalModel(m1=1.0, m2=2.0, c1=1000.0, c2=500.0, d1=2.0, d2=1.0, H=H).coefficients(), "fd", 2
    )
    rng = np.random.default_rng(1)
    return problem, rng.standard_normal((2, 2)), rng.standard_normal((3, problem.n_coupling)), "jacobi"


def chain():
    problem = Chain((SEGMENT,) * 3, ("ff", "fd"), H).problem(1)
    rng = np.random.default_rng(2)
    return problem, rng.standard_normal((3, 4)), rng.standard_normal((2, problem.n_coupling)), "gauss-seidel-321"


def pendulum():
    P = PendulumParameters()
    problem = PendulumCosimulation(P, "ff", 1, H)
    return problem, P.initial_state(), consistent_history(P, "ff", 1, H), "gauss-seidel-12"


@pytest.mark.parametrize("make", [linear, chain, pendulum], ids=lambda f: f.__name__)
def test_restored_problem_repeats_its_step_bit_for_bit(make):
    problem, state, history, scheme = make()
    method = engine_method(make_method("baumgarte", index=1, mu=1e-2), H)
    checkpoint = problem.checkpoint()
    first = macro_step(problem, method, state, history, scheme=scheme)
    on = macro_step(problem, method, first[0], first[1], scheme=scheme)  # a step further: the problem moves on
    assert not np.array_equal(on[0], first[0])
    problem.restore(checkpoint)
    again = macro_step(problem, method, state, history, scheme=scheme)
    for a, b in zip(first, again):
        assert np.array_equal(a, b)


def test_rollback_leaves_the_problem_at_the_last_kept_step():
    """A run stopped by its observer: with rollback the next step from the last kept state is the one a run
    without the stop takes (the trivial checkpoint of the linear model; the FMU problem's is tested with units)."""
    problem, state, history, scheme = chain()
    method = engine_method(make_method("projection"), H)
    full = simulate(problem, method, state, history, 4, scheme=scheme)
    stopped = simulate(
        problem,
        method,
        state,
        history,
        4,
        scheme=scheme,
        rollback=True,
        observe=lambda n, *_: "stop" if n == 3 else None,
    )
    assert stopped.diverged_at == 3 and len(stopped.states) == 3
    for a, b in zip(full.states[:3], stopped.states):
        assert np.array_equal(a, b)
