"""Signal connections in the one macro step, on a problem whose every step is known in closed form: two integrators
``x_i' = u_i`` (exact for polynomial inputs), coupled ``u_1 = x_2``, ``u_2 = -x_1`` -- the harmonic oscillator
``x_1 = cos t``, ``x_2 = -sin t`` from ``(1, 0)``.

Theory: Jacobi with held inputs (``k = 0``) is the forward Euler map ``[[1, H], [-H, 1]]`` (amplification
``sqrt(1 + H^2)`` per step); Gauss-Seidel 1 then 2 is symplectic Euler ``[[1, H], [-H, 1 - H^2]]`` (determinant 1);
Lagrange extrapolation of order ``k`` makes the global error of order ``k + 1``.
"""

from __future__ import annotations

import numpy as np
import pytest

from icosim.engine.graph import Connection, CouplingGraph, Joint
from icosim.engine.lagrange import monomial_coefficients
from icosim.engine.macrostep import macro_step
from icosim.engine.problem import CosimulationProblem
from icosim.engine.run import simulate
from icosim.errors import ParameterError
from icosim.order_fit import asymptotic_order

GRAPH = CouplingGraph(2, (), connections=(Connection(1, 0, 0, 0), Connection(0, 0, 1, 0, factor=-1.0)))


class Integrators(CosimulationProblem):
    """``x_i' = u_i`` integrated exactly over a macro step of size ``H``: the state is ``(x_1, x_2)``, a unit's
    outputs its ``x`` at ``T_N+1``."""

    def __init__(self, k, H):
        super().__init__(GRAPH, k)
        self.H = H
        self.C_pred = np.array(monomial_coefficients(self.pred_nodes), dtype=float)
        self.C_corr = np.array(monomial_coefficients(self.corr_nodes), dtype=float)

    def _step(self, i, state, rows, C):
        ((_, col),) = self.graph.signal_inputs(i)
        coef = C @ rows[..., col]  # u(tau) = sum_m coef_m tau^m on [0, 1]
        x = state[i] + self.H * sum(c / (m + 1) for m, c in enumerate(coef))
        return x, np.array([x])

    def predict(self, i, state, history, *, final=False, e_new=None):
        if e_new is not None:
            return self.correct(i, state, history, e_new)
        return self._step(i, state, history[: self.k + 1], self.C_pred)

    def correct(self, i, state, history, e):
        return self._step(i, state, self.corrector_samples(history, e), self.C_corr)

    def signal_output(self, i, y, output):
        return y[output]

    def stack(self, ys):
        return np.concatenate(ys)

    def join(self, ends):
        return np.array(ends)


def run(k, H, t_end, scheme="jacobi"):
    """The error against the exact solution at ``t_end``, from the exact history."""
    problem = Integrators(k, H)
    history = np.array([[-np.sin(-j * H), -np.cos(-j * H)] for j in range(k + 1)])  # u_1 = x_2, u_2 = -x_1
    traj = simulate(problem, None, np.array([1.0, 0.0]), history, int(round(t_end / H)), scheme=scheme)
    return np.max(np.abs(traj.states[-1] - [np.cos(t_end), -np.sin(t_end)]))


@pytest.mark.parametrize("scheme, matrix", [
    ("jacobi", lambda H: [[1, H], [-H, 1]]),
    ("gauss-seidel-12", lambda H: [[1, H], [-H, 1 - H**2]]),
    ("gauss-seidel-21", lambda H: [[1 - H**2, H], [-H, 1]]),
])  # fmt: skip
def test_held_inputs_are_euler_and_gauss_seidel_the_symplectic_euler(scheme, matrix):
    H, state = 0.1, np.array([0.3, -0.7])
    problem = Integrators(0, H)
    history = np.array([[state[1], -state[0]]])
    new, new_history, _ = macro_step(problem, None, state, history, scheme=scheme)
    assert np.allclose(new, np.array(matrix(H)) @ state, rtol=1e-15, atol=1e-16)
    assert np.allclose(new_history[0], [new[1], -new[0]], rtol=0, atol=0)  # the connections' new samples


@pytest.mark.parametrize("k", [0, 1, 2])
@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-12"])
def test_extrapolation_of_order_k_gives_global_order_k_plus_one(k, scheme):
    Hs = [0.02, 0.01, 0.005]
    errors = [run(k, H, 2.0, scheme) for H in Hs]
    fit = asymptotic_order(Hs, errors)
    assert abs(fit.order - (k + 1)) < 0.15, (errors, fit)


def test_an_input_fed_twice_and_joints_without_a_method_are_refused():
    with pytest.raises(ParameterError, match="input 1 of subsystem 1 is fed by connections 1 and 2"):
        CouplingGraph(3, (), connections=(Connection(1, 0, 0, 0), Connection(2, 0, 0, 0)))
    with pytest.raises(ParameterError, match="take part in no joint or connection"):
        CouplingGraph(3, (), connections=(Connection(1, 0, 0, 0),))
    mixed = CouplingGraph(3, (Joint(0, 1, "ff"),), connections=(Connection(1, 0, 2, 0),))
    assert mixed.n_coupling == 2 and mixed.connection_column(0) == 1

    class Joined(Integrators):
        def __init__(self):
            CosimulationProblem.__init__(self, mixed, 0)

    with pytest.raises(ParameterError, match="needs a coupling method"):
        macro_step(Joined(), None, np.zeros(3), np.zeros((1, 2)))
