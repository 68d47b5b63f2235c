"""Chains of linear segments (icosim.problems.linear.chain) against independent routes: the paper's two-mass
model (the chain of two single masses), the monolithic DAE integrated numerically with its multipliers, the
growth of time stepping against the spectral radius, the convergence order of the co-simulation, and the
Gauss-Seidel orders the engine refuses."""

import re

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from icosim import ParameterError, PhysicalModel, make_method
from icosim.engine.run import simulate
from icosim.engine.spectral.certified import certify_spectral_radius
from icosim.engine.spectral.radius import spectral_radius_float64 as family_rho
from icosim.order_fit import asymptotic_order
from icosim.problems.linear.chain import Chain, ChainFamily, ChainSegment, ChainSolution, chain_start
from icosim.problems.linear.spectral import spectral_radius_float64
from icosim.studies.convergence.metric import nrmse

SEGMENT = ChainSegment(
    masses=(1.0, 0.5), ground_stiffness=(100.0, 50.0), ground_damping=(0.5, 0.2), stiffness=(2000.0,), damping=(1.0,)
)
METHODS = [("projection", {}), ("baumgarte", {"index": 1, "mu": 1.0}), ("weighted", {"index": 3})]


@pytest.mark.parametrize("decomposition", ["ff", "fd", "df", "dd"])
@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-12", "gauss-seidel-21"])
def test_two_single_masses_are_the_papers_model(decomposition, scheme):
    """The same spectral radius to rounding (the coefficients ``c H^2 / m`` formed in another order)."""
    pm = PhysicalModel(m1=1.0, m2=2.0, c1=1000.0, c2=500.0, d1=2.0, d2=1.0, H=np.array([1e-3, 1e-2, 0.05]))
    chain = Chain.two_mass(1.0, 2.0, 1000.0, 500.0, 2.0, 1.0, pm.H, decomposition)
    for name, params in METHODS if decomposition != "dd" else METHODS[:1]:
        method = make_method(name, **params)
        for k in (0, 1, 2):
            paper = spectral_radius_float64(pm.coefficients(), method, decomposition, k, scheme=scheme)[0]
            np.testing.assert_allclose(family_rho(ChainFamily(chain, k), method, scheme=scheme)[0], paper, rtol=1e-13)


def _monolithic_by_quadrature(chain, x0, t_end):
    """The chain's DAE ``M a + K x + D v = G^T lambda``, ``G a = 0`` solved for ``(a, lambda)`` at every instant
    and integrated by scipy's DOP853: an independent route to positions and joint forces (SI)."""
    M, K, D = chain.full_matrices()
    G = chain.joint_matrix()
    n, m = M.shape[0], G.shape[0]
    KKT = np.block([[M, -G.T], [G, np.zeros((m, m))]])

    def accel(x, v):
        sol = np.linalg.solve(KKT, np.concatenate([-K @ x - D @ v, np.zeros(m)]))
        return sol[:n], sol[n:]

    def rhs(t, z):
        return np.concatenate([z[n:], accel(z[:n], z[n:])[0]])

    z = solve_ivp(rhs, (0, t_end), np.concatenate([x0, np.zeros(n)]), method="DOP853", rtol=1e-12, atol=1e-14)
    x, v = z.y[:n, -1], z.y[n:, -1]
    return x, v, accel(x, v)[1]


@pytest.mark.parametrize("segment", [SEGMENT, ChainSegment(masses=(2.0,), ground_stiffness=(300.0,))])
def test_the_exact_solution_is_the_dae_integrated_numerically(segment):
    chain = Chain((segment, segment.__class__(**{**segment.__dict__, "masses": (1.5,) * segment.n_masses}), segment),
                  ("ff", "fd"), 1e-3)  # fmt: skip
    n_all = 3 * segment.n_masses
    x0 = np.full(n_all, 0.02)
    t_end = 0.05
    x, v, lam = _monolithic_by_quadrature(chain, x0, t_end)
    exact = ChainSolution(chain, x0, np.zeros(n_all)).state(t_end / chain.H)
    H, m_ref = chain.H, chain.reference_mass
    np.testing.assert_allclose(exact["x"][0], x, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(exact["v"][0] / H, v, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(exact["lam"][0] * m_ref / H**2, lam, rtol=1e-7, atol=1e-7)


def test_inconsistent_start_is_refused():
    chain = Chain((SEGMENT,) * 2, ("ff",), 1e-3)
    with pytest.raises(ParameterError, match="joined masses must be equal"):
        ChainSolution(chain, np.array([0.0, 0.1, 0.0, 0.0]), np.zeros(4))


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel-123", "gauss-seidel-321", "gauss-seidel-213"])
@pytest.mark.parametrize("decomposition", ["ff", "fd"])
def test_time_stepping_grows_by_the_spectral_radius(scheme, decomposition):
    """An unstable configuration (Baumgarte index 1, small mu, k = 1) grows by rho per macro step."""
    chain = Chain((SEGMENT,) * 3, (decomposition,) * 2, 1e-3)
    method = make_method("baumgarte", index=1, mu=1e-3)
    rho = float(family_rho(ChainFamily(chain, 1), method, scheme=scheme)[0])
    problem = chain.problem(1)
    rng = np.random.default_rng(3)
    state, history = rng.standard_normal((3, 4)), rng.standard_normal((2, problem.n_coupling))
    traj = simulate(problem, method, state, history, 80, scheme=scheme)
    norms = [np.linalg.norm(np.concatenate([s.ravel(), c.ravel()])) for s, c in zip(traj.states, traj.coupling)]
    assert rho > 1.5 and abs(norms[-1] / norms[-2] / rho - 1) < 1e-3


def _errors(chain_of_H, method, k, scheme, steps):
    out = []
    for H in steps:
        chain = chain_of_H(H)
        problem = chain.problem(k)
        n_all = chain.n_segments * chain.n_masses
        solution = ChainSolution(chain, np.full(n_all, 0.01), np.zeros(n_all))
        state, history = chain_start(problem, solution)
        n = int(round(0.4 / H))
        traj = simulate(problem, method, state, history, n, scheme=scheme)
        S = np.array(traj.states[1:])
        exact = solution.state(np.arange(1, n + 1, dtype=float))
        m = chain.n_masses
        numeric = np.concatenate([S[..., :m].reshape(n, -1), S[..., m:].reshape(n, -1)], axis=-1)
        out.append(float(nrmse(np.concatenate([exact["x"], exact["v"]], axis=-1), numeric)))
    return np.array(out)


@pytest.mark.parametrize("k", [0, 1, 2])
@pytest.mark.parametrize("scheme", ["gauss-seidel-123", "gauss-seidel-321"])
def test_gauss_seidel_chain_converges_with_order_k_plus_1(k, scheme):
    steps = np.array([4e-3, 2e-3, 1e-3, 5e-4])
    errors = _errors(lambda H: Chain((SEGMENT,) * 3, ("ff", "ff"), H), make_method("projection"), k, scheme, steps)
    order = asymptotic_order(steps, errors)
    assert order.order == pytest.approx(k + 1, abs=0.15), order


def test_orders_a_unit_cannot_serve_are_refused_naming_it():
    """A single mass after both neighbours has two position conditions and one input: refused for methods
    without an acceleration-level solve; Baumgarte at index 1 and projection are served, and a segment with
    two ports (its first and last mass) is served by every method.  With Jacobi the neighbours are corrected
    with the middle mass and respond through their own inputs: served."""
    single = Chain((ChainSegment(masses=(1.0,), ground_stiffness=(10.0,)),) * 3, ("ff", "ff"), 1e-3)
    for name, params in (("weighted", {"index": 3}), ("baumgarte", {"index": 3}), ("baumgarte", {"index": 2, "mu": 1})):
        with pytest.raises(ParameterError, match=r"subsystem 2 advances after 1, 3.*e\.g\. gauss-seidel-123"):
            family_rho(ChainFamily(single, 1), make_method(name, **params), scheme="gauss-seidel-132")
        assert np.isfinite(family_rho(ChainFamily(single, 1), make_method(name, **params), scheme="jacobi")[0])
    for name, params in (("baumgarte", {"index": 1, "mu": 1}), ("projection", {})):
        assert np.isfinite(
            family_rho(ChainFamily(single, 1), make_method(name, **params), scheme="gauss-seidel-132")[0]
        )
    double = Chain((SEGMENT,) * 3, ("ff", "ff"), 1e-3)
    assert np.isfinite(
        family_rho(ChainFamily(double, 1), make_method("weighted", index=3), scheme="gauss-seidel-132")[0]
    )


def test_a_kinematically_driven_single_mass_in_two_joints_is_refused():
    with pytest.raises(ParameterError, match="kinematically driven by joint 1"):
        Chain((ChainSegment(masses=(1.0,)),) * 3, ("fd", "ff"), 1e-3)
    Chain((SEGMENT,) * 3, ("fd", "df"), 1e-3)  # two ports: the middle segment driven at both ends


def test_certified_verdict_of_a_chain_point_agrees_with_float64():
    chain = Chain((SEGMENT,) * 4, ("ff", "fd", "ff"), np.array([1e-3, 2e-2]))
    family = ChainFamily(chain, 1)
    method = make_method("projection")
    rho, err = family_rho(family, method, scheme="gauss-seidel-1234")
    for i in range(2):
        cert = certify_spectral_radius(family.point((i,)), method, scheme="gauss-seidel-1234")
        assert float(cert.rho_lower) <= rho[i] + err[i] and rho[i] - err[i] <= float(cert.rho_upper)
        assert cert.verdict == ("stable" if rho[i] + err[i] < 1 else "unstable")


_ONE = {"masses": [1.0], "ground_stiffness": [1000.0], "ground_damping": [2.0]}
_TWO = {"masses": [2.0], "ground_stiffness": [4000.0], "ground_damping": [1.0]}


def test_from_dict_builds_the_chain_of_its_segments_and_joints():
    chain = Chain.from_dict({"segments": [_ONE, _TWO, _ONE], "joints": "ff"}, H=1e-2)
    direct = Chain((ChainSegment(**_ONE), ChainSegment(**_TWO), ChainSegment(**_ONE)), ("ff", "ff"), 1e-2)
    assert chain == direct


@pytest.mark.parametrize(
    "d,key",
    [
        ({"joints": "ff"}, "segments:"),
        ({"segments": [_ONE, _TWO]}, "joints:"),
        ({"segments": [_ONE, _TWO], "joints": ["ff", "ff"]}, "joints:"),
        ({"segments": [_ONE, _TWO], "joints": ["xy"]}, "joints[0]:"),
        ({"segments": [_ONE, {"masses": [-1.0]}], "joints": "ff"}, "segments[1]:"),
        ({"segments": [_ONE, {"masses": [1.0], "mass": 2}], "joints": "ff"}, "segments[1]:"),
        ({"segments": [_ONE, _TWO, _ONE], "joints": ["fd", "df"]}, "joints:"),  # a driven single mass in two joints
        ({"segments": [_ONE, _TWO], "joints": "ff", "H": 1}, "H:"),
    ],
)
def test_from_dict_refuses_bad_input_naming_the_key(d, key):
    with pytest.raises(ParameterError, match=re.escape(key)):
        Chain.from_dict(d)
