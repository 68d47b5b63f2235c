"""The added-mass rule of the Gauss-Seidel schemes, with its scope (docs/gauss_seidel.md, Sect. 3).

At the origin of the parameter plane both subsystems are free masses; write
A for the subsystem that advances first, B for the corrected one and
alpha = m_B/m_A.  Where the rule is exact (index 3, and index 2 at k = 0) the
characteristic polynomial of the amplification matrix is derived by hand and
checked coefficient by coefficient against the engine's matrix in ball
arithmetic (an enclosure must contain the exact coefficient).  Elsewhere the
tests pin what the data show: where the threshold sits (an eigenvalue -1
exactly, shown by the characteristic polynomial vanishing at -1), and rho
measured in float64 and at 50 digits alike.
"""

from fractions import Fraction

import flint
import numpy as np
import pytest

from icosim import TestModel, make_method
from icosim.engine.backends import Ball
from icosim.problems.linear.spectral import amplification_matrix, spectral_radius_mp

GS12, GS21 = "gauss-seidel-12", "gauss-seidel-21"
RATIOS = [Fraction(1, 10), Fraction(1, 2), Fraction(2), Fraction(10)]


def origin(alpha_B_over_A, scheme, const=float):
    """The free-mass model whose corrected subsystem is alpha times heavier than the leading one."""
    am21 = alpha_B_over_A if scheme.startswith(GS12) else 1 / alpha_B_over_A  # am21 = m2/m1
    return TestModel(*(const(Fraction(v)) for v in (0, 0, am21, 1, 1)))


def charpoly(alpha, method, k, scheme, dec="ff"):
    """Characteristic polynomial of the engine's matrix at the origin, in ball arithmetic (exact
    parameters; coefficients low to high)."""
    be = Ball(256)
    with be.context():
        M = amplification_matrix(origin(alpha, scheme, be.const), method, dec, k, be, scheme=scheme)
        n = M.shape[0]
        return flint.arb_mat([[M[i, j] for j in range(n)] for i in range(n)]).charpoly()


def expand(roots):
    """Monic polynomial with these (rational) roots, coefficients low to high."""
    coeffs = [Fraction(1)]
    for r in roots:
        coeffs = [Fraction(0)] + coeffs  # times x
        coeffs = [c - r * d for c, d in zip(coeffs, coeffs[1:] + [Fraction(0)])]
    return coeffs


def assert_charpoly(poly, roots):
    want = expand(roots)
    got = poly.coeffs()
    assert len(got) == len(want)
    for g, w in zip(got, want):
        assert (g * w.denominator - w.numerator).contains(0), (g, w)  # integers: exact at any precision
        assert float(g.rad()) < 1e-40


def rho_float64(model, method, k, scheme):
    M = amplification_matrix(model, method, "ff", k, scheme=scheme)
    return float(np.max(np.abs(np.linalg.eigvals(M))))


def rho_both(model, method, k, scheme):
    """rho in float64 and at 50 digits; they must agree."""
    r64 = rho_float64(model, method, k, scheme)
    r50 = float(spectral_radius_mp(model, method, "ff", k, digits=50, scheme=scheme))
    assert r64 == pytest.approx(r50, rel=1e-7)
    return r50


# -- exact: index 3 and index 2 at k = 0 ---------------------------------------------------
@pytest.mark.parametrize("scheme", [GS12, GS21])
@pytest.mark.parametrize("alpha", RATIOS, ids=str)
@pytest.mark.parametrize(
    "method, r",
    [
        # Baumgarte index 2 with beta_bar = 2 mu_bar: r = (2 beta - 1)/(2 beta + 1); index 3: beta = 0, r = -1
        (make_method("baumgarte", index=3), Fraction(-1)),
        (make_method("weighted", index=3), Fraction(-1)),
        (make_method("baumgarte", index=2, mu=Fraction(1, 4)), Fraction(0)),
        (make_method("baumgarte", index=2, mu=1), Fraction(3, 5)),
        # weighted multiplier index 2: r = (a - 1)/(a + 1)
        (make_method("weighted", index=2, a=1), Fraction(0)),
        (make_method("weighted", index=2, a=3), Fraction(1, 2)),
    ],
    ids=["B3", "W3", "B2-mu1/4", "B2-mu1", "W2-a1", "W2-a3"],
)
def test_added_mass_rule_is_exact_at_index_3_and_2_for_k0(method, r, alpha, scheme):
    """x (x - r) (x + m_B/m_A) (x - 1)^2: the gap and relative velocity decouple from lambda, whose
    eigenvalue is -m_B/m_A, so rho = max(1, m_B/m_A) at k = 0."""
    assert_charpoly(charpoly(alpha, method, 0, scheme), [0, r, -alpha, 1, 1])


# -- no added mass: projection (every k) and Baumgarte index 1 at k = 0 ----------------------
@pytest.mark.parametrize("scheme", [GS12, GS21])
@pytest.mark.parametrize("alpha", RATIOS, ids=str)
@pytest.mark.parametrize("k", [0, 1, 2])
def test_projection_has_no_added_mass_effect(k, alpha, scheme):
    """Projection solves the acceleration level, where A's re-evaluated acceleration follows lambda*
    exactly as B's does: every eigenvalue but the rigid motion's double 1 is 0."""
    n = 4 + (k + 1)
    assert_charpoly(charpoly(alpha, make_method("projection"), k, scheme), [0] * (n - 2) + [1, 1])


@pytest.mark.parametrize("scheme", [GS12, GS21])
@pytest.mark.parametrize("alpha", RATIOS + [Fraction(1000)], ids=str)
def test_baumgarte_index1_k0_is_stable_for_every_mass_ratio(alpha, scheme):
    """Measured: besides the double eigenvalue 1, every eigenvalue lies inside the unit circle; the most
    negative one approaches -1 only as m_B/m_A grows without bound (-0.603 at 10, -0.995 at 1000)."""
    model, method = origin(alpha, scheme), make_method("baumgarte", index=1, mu=1)
    ev = np.linalg.eigvals(amplification_matrix(model, method, "ff", 0, scheme=scheme))
    rest = np.sort(np.abs(ev))[:-2]  # without the rigid motion's double 1
    assert np.all(np.abs(np.sort(np.abs(ev))[-2:] - 1) < 1e-6)
    assert rest.max() < 1
    assert rho_both(model, method, 0, scheme) == pytest.approx(1.0, abs=1e-12)


# -- thresholds elsewhere ----------------------------------------------------------------------
@pytest.mark.parametrize("scheme", [GS12, GS21])
@pytest.mark.parametrize(
    "method, k, threshold",
    [
        # the weighted multiplier (a = b = 1) at k = 0 loses stability at m_B/m_A = 3, not at 1
        (make_method("weighted", index=1, a=1, b=1), 0, Fraction(3)),
        # Baumgarte index 1 at k = 1: at m_B/m_A = 1, as the rule says, but rho grows more slowly than m_B/m_A
        (make_method("baumgarte", index=1, mu=1), 1, Fraction(1)),
    ],
    ids=["W1-k0", "B1-k1"],
)
def test_threshold_is_an_eigenvalue_minus_one(method, k, threshold, scheme):
    """At the threshold -1 is an eigenvalue (the characteristic polynomial vanishes there, proven); just
    below it rho = 1 (the rigid motion), just above it rho > 1."""
    poly = charpoly(threshold, method, k, scheme)
    with Ball(256).context():
        at_minus_one = poly(flint.arb(-1))
    assert at_minus_one.contains(0) and float(at_minus_one.rad()) < 1e-40
    below = rho_both(origin(threshold * Fraction(9, 10), scheme), method, k, scheme)
    above = rho_both(origin(threshold * Fraction(11, 10), scheme), method, k, scheme)
    assert below == pytest.approx(1.0, abs=1e-9) and above > 1.01


def test_baumgarte_index1_k1_follows_the_rule_only_as_a_tendency():
    """rho = 1.41 at m_B/m_A = 2, 1.65 at 3, 2.23 at 10: unstable beyond equal masses, but not max(1, m_B/m_A)."""
    method = make_method("baumgarte", index=1, mu=1)
    rhos = [rho_both(origin(Fraction(a), GS12), method, 1, GS12) for a in (2, 3, 10)]
    assert rhos == pytest.approx([1.40826, 1.65207, 2.22620], abs=5e-5)
    assert all(1 < r < a for r, a in zip(rhos, (2, 3, 10)))


@pytest.mark.parametrize(
    "method, k",
    [(make_method("baumgarte", index=1, mu=1), 2), (make_method("weighted", index=1, a=1, b=1), 1)],
    ids=["B1-k2", "W1-k1"],
)
def test_threshold_below_equal_masses(method, k):
    """Baumgarte index 1 at k = 2 and the weighted multiplier at k = 1 are unstable already with a
    corrected subsystem half as heavy as the leading one, and stable with a tenth."""
    assert rho_both(origin(Fraction(1, 2), GS12), method, k, GS12) > 1.3
    assert rho_both(origin(Fraction(1, 10), GS12), method, k, GS12) == pytest.approx(1.0, abs=1e-9)


# -- the other reading: the leading subsystem's outputs left as integrated ----------------------
@pytest.mark.parametrize("alpha", RATIOS, ids=str)
def test_outputs_as_integrated_bring_the_added_mass_effect_to_projection(alpha):
    """Projection ff, k = 0, at the origin.  Re-evaluated (the project's choice): A's acceleration at
    T_N+1 follows lambda*, the acceleration condition leaves lambda* = 0 and x^3 (x - 1)^2.  As integrated:
    B's acceleration must match A's, integrated with lambda_N, so lambda* = -(m_B/m_A) lambda_N and
    x^2 (x + m_B/m_A) (x - 1)^2."""
    method = make_method("projection")
    assert_charpoly(charpoly(alpha, method, 0, GS12), [0, 0, 0, 1, 1])
    assert_charpoly(charpoly(alpha, method, 0, "gauss-seidel-12-as-integrated"), [0, 0, -alpha, 1, 1])


@pytest.mark.parametrize(
    "point, k, built, as_integrated",
    [((-0.05, 0.1, 5, 1, 1), 0, 0.951229, 5.0), ((-0.25, 1.25, 10, 1, 1), 1, 0.804957, 11.67527)],
)
def test_outputs_as_integrated_away_from_the_origin(point, k, built, as_integrated):
    """The two readings of "sequential" at the points of docs/gauss_seidel.md: rho in float64 and at
    50 digits (two arithmetics), and as the growth of plain time stepping (an independent route)."""
    from helpers import growth_rate

    from icosim.problems.linear.problem import LinearCosimulation

    model, method = TestModel(*point), make_method("projection")
    for scheme, want in ((GS12, built), ("gauss-seidel-12-as-integrated", as_integrated)):
        rho = rho_both(model, method, k, scheme)
        assert rho == pytest.approx(want, rel=1e-5)
        prob = LinearCosimulation(model.coefficients(), "ff", k)
        assert growth_rate(prob, method, scheme=scheme) == pytest.approx(rho, rel=2e-2)


@pytest.mark.parametrize("alpha", RATIOS, ids=str)
@pytest.mark.parametrize(
    "method",
    [
        make_method("baumgarte", index=3),
        make_method("baumgarte", index=2, mu=1),
        make_method("weighted", index=2, a=1),
        make_method("weighted", index=1, a=1, b=1),
    ],
    ids=["B3", "B2", "W2", "W1"],
)
def test_no_mass_ratio_helps_at_k2(method, alpha):
    """Index 2 and 3 (at k = 1, 2) and the weighted multiplier at k = 2 are unstable at the origin whatever the
    mass ratio, as with Jacobi (the paper: index 2 and 3 are stable only at k = 0): the rule does not apply."""
    ks = (2,) if method.params["index"] == 1 else (1, 2)
    for k in ks:
        assert rho_both(origin(alpha, GS12), method, k, GS12) > 1.5
