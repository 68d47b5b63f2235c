"""The linear two-mass model (icosim.problems.linear) checked against independent routes: its subsystems'
exact propagation against numerical quadrature of their ODEs, the closed-form 2 x 2 matrix exponential against
scipy's, and the test model's parameters (the physical model and back, what is refused)."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from icosim import ParameterError, PhysicalModel, TestModel, projection, spectral_radius_float64
from icosim.engine.backends import Float64
from icosim.engine.lagrange import corrector_nodes
from icosim.problems.linear.subsystems import LinearSubsystem


# -- exact subsystem propagation against numerical quadrature ------------------
@pytest.mark.parametrize(
    "kind,stiffness,damping,gain",
    [
        ("force", 2.0, 0.6, 1.0),  # underdamped
        ("force", 4.0, 4.0, -0.5),  # critically damped
        ("force", 1.0, 9.0, 2.0),  # overdamped
        ("force", 0.0, 0.0, 1.0),  # free mass
        ("kinematic", 3.0, 0.2, -0.25),
    ],
)
@pytest.mark.parametrize("k", [0, 1, 2])
def test_subsystem_step_matches_ode_solution(kind, stiffness, damping, gain, k):
    sub = LinearSubsystem.single(kind, stiffness, damping, gain, k, Float64())
    rng = np.random.default_rng(k)
    s0, U = rng.standard_normal(2), rng.standard_normal(k + 1)
    nodes = corrector_nodes(k)
    coeffs = np.polyfit(np.array(nodes, float), U, k) if k else U

    def u(t):
        return np.polyval(coeffs, t)

    def rhs(t, s):
        acc = -stiffness * s[0] - damping * s[1] + gain * u(t) if kind == "force" else u(t)
        return [s[1], acc]

    ref = solve_ivp(rhs, (0, 1), s0, rtol=1e-12, atol=1e-13).y[:, -1]
    s1, y = sub.step(s0, U[None], nodes)
    y = y[0]  # the one port
    np.testing.assert_allclose(s1, ref, rtol=1e-9, atol=1e-11)
    acc_ref = rhs(1.0, ref)[1]
    assert y[2] == pytest.approx(acc_ref, rel=1e-8, abs=1e-10)
    if kind == "kinematic":  # the multiplier realises v' = u through the equation of motion
        assert y[3] == pytest.approx((u(1.0) + stiffness * ref[0] + damping * ref[1]) / gain, rel=1e-8)


# -- test model conversions ------------------------------------------------------
def test_test_model_physical_round_trip():
    model = TestModel(-0.3, 1.7, 2.5, 0.4, 1.9)
    back = model.to_physical(m1=3.0, H=0.01).test_model()
    for name in ("lr1", "li1", "am21", "alr21", "ali21"):
        assert getattr(back, name) == pytest.approx(getattr(model, name), rel=1e-12)
    c1, c2 = model.coefficients(), model.to_physical(m1=3.0, H=0.01).coefficients()
    for name in ("k1", "delta1", "k2", "delta2", "am21"):
        assert getattr(c2, name) == pytest.approx(getattr(c1, name), rel=1e-12)


def test_overdamped_physical_model_is_accepted_but_has_no_eq71_form():
    pm = PhysicalModel(1.0, 2.0, 1.0, 1.0, 10.0, 1.0, 0.1)
    assert pm.overdamped[0] and not pm.overdamped[1]
    rho, _ = spectral_radius_float64(pm, projection(), "ff", 1)
    assert np.isfinite(rho)
    with pytest.raises(ParameterError, match="overdamped"):
        pm.test_model()


@pytest.mark.parametrize(
    "kwargs,name",
    [
        (dict(lr1=0.1, li1=1), "lr1"),
        (dict(lr1=-1, li1=-1), "li1"),
        (dict(lr1=-1, li1=1, am21=0), "am21"),
        (dict(lr1=-1, li1=float("nan")), "li1"),
        (dict(lr1=-1, li1=1, ali21=-2), "ali21"),
    ],
)
def test_test_model_validation_names_the_parameter(kwargs, name):
    with pytest.raises(ParameterError, match=rf"^{name} "):
        TestModel(**kwargs)


@pytest.mark.parametrize(
    "A", [[[0, 1], [-3, -0.4]], [[0, 1], [-1, -2]], [[0, 1], [-1, -5]], [[0, 1], [0, 0]], [[0, 1], [-4, 0]]]
)
def test_closed_form_2x2_exponential_matches_scipy(A):
    import scipy.linalg

    from icosim.problems.linear.exact import expm_2x2

    A = np.array(A, dtype=float)
    ts = np.linspace(-3, 7, 23)
    ref = np.array([scipy.linalg.expm(t * A) for t in ts])
    np.testing.assert_allclose(expm_2x2(A, ts), ref, rtol=1e-11, atol=1e-12)
