"""The signal-coupled linear model against the recurrence derived on paper (docs/signals.md): two first-order lags
``x_i' = -a_i x_i + b_i u_i``, ``y_i = x_i`` in a loop ``u_1 = g_1 y_2``, ``u_2 = g_2 y_1``, Jacobi and
Gauss-Seidel (1 then 2), inputs held (k = 0) and extrapolated linearly (k = 1).

The closed forms take the lag's step responses in closed form (``phi = exp(-a H)``, ``gamma = b (1 - phi) / a``,
``gamma' = (b / a) (1 - (1 - phi) / (a H))`` for the input ``tau``), not from the model's matrix exponential.
"""

import numpy as np
import pytest

from icosim.engine.backends import Float64
from icosim.engine.graph import Connection
from icosim.engine.run import simulate
from icosim.engine.schemes import JACOBI, GaussSeidel, get_scheme
from icosim.engine.spectral.matrix import matrix_of
from icosim.errors import ParameterError
from icosim.problems.linear.signals import (
    SignalFamily,
    SignalLinearCosimulation,
    StateSpaceUnit,
    signal_limit,
    signal_radius,
)

A1, B1, A2, B2 = 1.0, 2.0, 3.0, 0.5
G1, G2 = -1.5, 2.0
LOOP = (Connection(1, 0, 0, 0, G1, 0.7), Connection(0, 0, 1, 0, G2, -0.2))  # offsets: not in the recurrence
GS12 = GaussSeidel([1, 2])
EPS = np.finfo(float).eps


def lag(a, b):
    return StateSpaceUnit([[-a]], [[b]], [[1.0]], [[0.0]])


def responses(a, b, H):
    phi = np.exp(-a * H)
    return phi, b * (1 - phi) / a, b / a * (1 - (1 - phi) / (a * H))


def derived(scheme, k, H):
    """The recurrence of docs/signals.md in ``w = (x1, x2, e1_N, e2_N[, e1_N-1, e2_N-1])``."""
    p1, c1, d1 = responses(A1, B1, H)
    p2, c2, d2 = responses(A2, B2, H)
    if k == 0:
        x1 = np.array([p1, 0, c1, 0])
        x2 = np.array([0, p2, 0, c2]) if scheme == "jacobi" else np.array([0, p2, 0, 0]) + c2 * G2 * x1
        return np.array([x1, x2, G1 * x2, G2 * x1])
    x1 = np.array([p1, 0, c1 + d1, 0, -d1, 0])
    if scheme == "jacobi":
        x2 = np.array([0, p2, 0, c2 + d2, 0, -d2])
    else:  # through the new sample at T_N+1 and e2_N
        x2 = np.array([0, p2, 0, c2 - d2, 0, 0]) + d2 * G2 * x1
    shift = np.eye(6)[[2, 3]]  # e_N becomes e_N-1
    return np.array([x1, x2, G1 * x2, G2 * x1, *shift])


@pytest.mark.parametrize("k", [0, 1])
@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-12"])
@pytest.mark.parametrize("H", [0.05, 0.4, 1.3])
def test_the_macro_step_matrix_is_the_derived_recurrence(scheme, k, H):
    family = SignalFamily((lag(A1, B1), lag(A2, B2)), LOOP, k, H)
    M = matrix_of(family.problem(Float64()), None, JACOBI if scheme == "jacobi" else GS12)
    D = derived(scheme, k, H)
    assert np.max(np.abs(M - D)) <= 100 * EPS * np.max(np.abs(D)), np.max(np.abs(M - D))  # expm's rounding


@pytest.mark.parametrize("H", [0.05, 0.4, 1.3])
def test_the_spectral_radius_is_that_of_the_reduced_two_by_two(H):
    """After one step ``e_1 = g_1 x_2``, ``e_2 = g_2 x_1``: the recurrence on ``(x1, x2)`` has the eigenvalues of
    ``[[phi1, g1 gamma1], [g2 gamma2, phi2]]`` (Jacobi) and the roots of ``l^2 - (phi1 + phi2 + p) l + phi1 phi2``
    (Gauss-Seidel), ``p = g1 g2 gamma1 gamma2``."""
    p1, c1, _ = responses(A1, B1, H)
    p2, c2, _ = responses(A2, B2, H)
    p = G1 * G2 * c1 * c2
    jacobi = np.max(np.abs(np.roots([1, -(p1 + p2), p1 * p2 - p])))
    gauss_seidel = np.max(np.abs(np.roots([1, -(p1 + p2 + p), p1 * p2])))
    units = (lag(A1, B1), lag(A2, B2))
    for scheme, expected in ((JACOBI, jacobi), (GS12, gauss_seidel)):
        rho, err = signal_radius(units, LOOP, 0, H, scheme)
        assert abs(rho - expected) <= max(err, 4e-16), (scheme.name, rho, expected, err)


def test_the_largest_stable_step_of_a_negative_loop_of_equal_lags():
    """Equal lags (a = b = 1) and a loop gain ``G = g1 g2 < -1``, Jacobi, held inputs: ``|l|^2 = phi^2 + |G|
    gamma^2 < 1`` holds while ``phi > (|G| - 1) / (|G| + 1)``, up to ``H = ln((|G| + 1) / (|G| - 1))``."""
    G = 3.0
    cons = (Connection(1, 0, 0, 0, -G), Connection(0, 0, 1, 0, 1.0))
    limit = signal_limit((lag(1, 1), lag(1, 1)), cons, 0, 0.1)
    H_max = np.log((G + 1) / (G - 1))
    assert limit.status == "bisected" and limit.H_max <= H_max <= limit.H_unstable, (limit.H_max, H_max)
    assert limit.H_unstable / limit.H_max < 1.002


def test_a_run_grows_by_the_spectral_radius():
    """The macro step run from a start grows per step by rho once the dominant mode dominates (an unstable H)."""
    units = (lag(A1, B1), lag(A2, B2))
    cons = tuple(Connection(c.source, c.output, c.target, c.input, c.factor) for c in LOOP)
    H = 1.3
    rho, _ = signal_radius(units, cons, 1, H)
    assert rho > 1
    problem = SignalLinearCosimulation(units, cons, 1, H)
    traj = simulate(problem, None, np.array([1.0, 0.0]), np.zeros((2, 2)), 200, record=True)
    amp = np.abs(np.asarray(traj.states)[:, 0])
    growth = (np.max(amp[180:200]) / np.max(amp[80:100])) ** (1 / 100)
    assert growth == pytest.approx(rho, rel=1e-3)


def test_a_one_step_map_serves_held_inputs_at_its_own_step_only():
    phi, gamma, _ = responses(A1, B1, 0.2)
    unit = StateSpaceUnit([[phi]], [[gamma]], [[1.0]], [[0.0]], H=0.2)
    cons = (Connection(1, 0, 0, 0, G1), Connection(0, 0, 1, 0, G2))
    rho, _ = signal_radius((unit, lag(A2, B2)), cons, 0, 0.2)
    assert abs(rho - signal_radius((lag(A1, B1), lag(A2, B2)), cons, 0, 0.2)[0]) < 1e-14
    with pytest.raises(ParameterError, match="k = 0 only"):
        signal_radius((unit, lag(A2, B2)), cons, 1, 0.2)
    with pytest.raises(ParameterError, match="cannot take a step"):
        signal_radius((unit, lag(A2, B2)), cons, 0, 0.1)


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-12"])
def test_a_unit_with_direct_feedthrough_gives_its_output_with_the_input_it_ends_the_step_with(scheme):
    """``y_2 = x_2 + d u_2``, held inputs: Jacobi reads ``y_2`` with the held ``e_2,N``, Gauss-Seidel (1 then 2)
    with the new sample ``g_2 x_1'`` it stepped with."""
    d = 0.7
    p1, c1, _ = responses(A1, B1, 0.3)
    p2, c2, _ = responses(A2, B2, 0.3)
    x1 = np.array([p1, 0, c1, 0])
    if scheme == "jacobi":
        x2 = np.array([0, p2, 0, c2])
        e1 = G1 * (x2 + d * np.array([0, 0, 0, 1]))
    else:
        e2 = G2 * x1
        x2 = np.array([0, p2, 0, 0]) + c2 * e2
        e1 = G1 * (x2 + d * e2)
    expected = np.array([x1, x2, e1, G2 * x1])
    units = (lag(A1, B1), StateSpaceUnit([[-A2]], [[B2]], [[1.0]], [[d]]))
    M = matrix_of(SignalFamily(units, LOOP, 0, 0.3).problem(Float64()), None, JACOBI if scheme == "jacobi" else GS12)
    assert np.max(np.abs(M - expected)) <= 100 * EPS * np.max(np.abs(expected))


def derived_implicit(k, H):
    """Jacobi with the connections closed at ``T_N+1`` (the corrector's interpolation through the new samples:
    ``k = 0`` holds ``e_N+1``, ``k = 1`` runs from ``e_N`` to ``e_N+1``): ``x_i' = a_i + d_i g_i x_j'`` with ``a_i``
    what the step gives without the new sample, solved for ``(x_1', x_2')`` with ``q = d_1 d_2 g_1 g_2``."""
    p1, c1, d1 = responses(A1, B1, H)
    p2, c2, d2 = responses(A2, B2, H)
    if k == 0:  # u = e_N+1 over the step: a_i = phi_i x_i, d_i = gamma_i
        a1, a2, w1, w2 = np.array([p1, 0, 0, 0]), np.array([0, p2, 0, 0]), c1, c2
    else:  # u = e_N + tau (e_N+1 - e_N): a_i = phi_i x_i + (gamma_i - gamma'_i) e_i,N, d_i = gamma'_i
        a1, a2, w1, w2 = np.array([p1, 0, c1 - d1, 0, 0, 0]), np.array([0, p2, 0, c2 - d2, 0, 0]), d1, d2
    q = w1 * w2 * G1 * G2
    x1 = (a1 + w1 * G1 * a2) / (1 - q)
    x2 = (a2 + w2 * G2 * a1) / (1 - q)
    shift = [np.eye(6)[2], np.eye(6)[3]] if k == 1 else []
    return np.array([x1, x2, G1 * x2, G2 * x1, *shift])


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-12", "gauss-seidel-21"])
@pytest.mark.parametrize("k", [0, 1])
@pytest.mark.parametrize("H", [0.05, 0.4, 1.3])
def test_the_implicit_macro_step_matrix_is_the_derived_recurrence(k, H, scheme):
    """One Newton step from the predictor solves the linear conditions exactly (the difference quotients of a linear
    unit are exact): the macro step's matrix is the recurrence of the conditions at T_N+1, in either Gauss-Seidel
    order too (the same conditions; the order moves Newton's start only)."""
    family = SignalFamily((lag(A1, B1), lag(A2, B2)), LOOP, k, H, implicit=True)
    M = matrix_of(family.problem(Float64()), None, get_scheme(scheme))
    D = derived_implicit(k, H)
    # expm's rounding, carried through the residual (a difference of the unit's outputs) and the Newton solve
    assert np.max(np.abs(M - D)) <= 1000 * EPS * np.max(np.abs(D)), np.max(np.abs(M - D))


@pytest.mark.parametrize("H", [0.1, 1.0, 3.0])
def test_implicit_coupling_of_a_negative_loop_of_equal_lags_is_stable_at_every_step(H):
    """Equal lags, ``G = g1 g2 = -3``, k = 0: the recurrence on ``(x1, x2)`` is ``phi [[1, g1 gamma], [g2 gamma, 1]]
    / (1 - G gamma^2)``, eigenvalues ``phi (1 +- i sqrt(3) gamma) / (1 + 3 gamma^2)``, ``|l| = phi / sqrt(1 + 3
    gamma^2) < 1`` at every H (explicit Jacobi: stable only below ln 2)."""
    G = 3.0
    cons = (Connection(1, 0, 0, 0, -G), Connection(0, 0, 1, 0, 1.0))
    phi = np.exp(-H)
    expected = phi / np.sqrt(1 + G * (1 - phi) ** 2)
    rho, err = signal_radius((lag(1, 1), lag(1, 1)), cons, 0, H, implicit=True)
    assert abs(rho - expected) <= max(err, 4e-16), (rho, expected, err)
    assert (signal_radius((lag(1, 1), lag(1, 1)), cons, 0, H)[0] < 1) == (H < np.log(2))
