"""Certified stability verdicts (icosim.engine.spectral.certified, the precision policy, ``icosim rho --certify``).

Every proven enclosure is checked against an independent computation: the
spectral radius at 160 digits with mpmath (eigenvalues of the amplification
matrix, a different algorithm in a different arithmetic), numpy's roots for the
root count, and -- where it matters -- where rho = 1 lies, found by a bracketing
root finder at 60 digits.
"""

import json
from fractions import Fraction

import mpmath
import numpy as np
import pytest
from flint import arb

from icosim import TestModel, make_method
from icosim.cli import main
from icosim.engine.spectral import Certification
from icosim.engine.spectral.certified import roots_inside
from icosim.problems.linear.spectral import (
    amplification_matrix,
    certify_spectral_radius,
    spectral_radius,
    spectral_radius_float64,
    spectral_radius_mp,
)

SCHEMES = [
    (make_method("baumgarte", index=1, mu=1.0), "ff", 2),
    (make_method("baumgarte", index=2, mu=0.25), "fd", 1),
    (make_method("baumgarte", index=3), "ff", 1),
    (make_method("weighted", a=1.0, b=1.0), "ff", 2),
    (make_method("weighted", a=0.5, b=0.25), "fd", 0),
    (make_method("projection"), "ff", 1),
    (make_method("projection"), "fd", 2),
    (make_method("projection"), "dd", 0),
]


def test_root_count_matches_numpy_roots():
    """Schur-Cohn-Marden counts against the roots numpy finds, for random real polynomials with clusters at 0
    (the structural zeros of the reduced state) and roots inside, outside and near the circle."""
    rng = np.random.default_rng(0)
    checked = 0
    for _ in range(400):
        roots = list(rng.standard_normal(rng.integers(1, 8)) * rng.uniform(0.3, 1.6)) + [0.0] * rng.integers(0, 3)
        if len(roots) >= 2 and rng.random() < 0.5:
            z = rng.uniform(0.2, 1.5) * np.exp(1j * rng.uniform(0, np.pi))
            roots[:2] = [z, np.conj(z)]
        coeffs = np.real(np.poly(roots))[::-1]  # a_0 ... a_n
        r = float(rng.choice([0.6, 1.0, 1.3]))
        moduli = np.abs(np.roots(coeffs[::-1]))
        if np.min(np.abs(moduli - r)) < 1e-6:
            continue  # the rounded coefficients may move a root across the circle
        assert roots_inside([arb(float(c)) for c in coeffs], r) == int(np.sum(moduli < r))
        checked += 1
    assert checked > 300


@pytest.mark.parametrize("method,dec,k", SCHEMES, ids=[f"{m.name}-{d}-k{k}" for m, d, k in SCHEMES])
def test_enclosure_contains_the_160_digit_value(method, dec, k):
    rng = np.random.default_rng(k + len(dec))
    for _ in range(4):
        point = TestModel(
            -2 * rng.random(), 2 * rng.random(), 10 ** rng.uniform(-1, 1), 3 * rng.random(), 3 * rng.random()
        )
        c = certify_spectral_radius(point, method, dec, k)
        rho = spectral_radius_mp(point, method, dec, k, 160)
        with mpmath.workdps(60):
            assert mpmath.mpf(c.lower(40)) <= rho <= mpmath.mpf(c.upper(40))
        assert c.verdict == ("stable" if rho < 1 else "unstable")


def test_certified_verdicts_agree_with_float64_on_an_audit_sample():
    """Every float64-trusted point audited (audit = 1): certification confirms every verdict it can prove."""
    lr, li = np.meshgrid(np.linspace(-2, 0, 9), np.linspace(0, 2, 9), indexing="ij")
    for method, dec, k in SCHEMES[::2]:
        res = spectral_radius(TestModel(lr, li, 2.0, 2.0, 2.0), method, dec, k, certification=Certification(audit=1.0))
        audited = res.audited & np.isin(res.verdict, ("stable", "unstable"))
        assert audited.sum() > 40
        np.testing.assert_array_equal(res.verdict[audited], res.float64_verdict[audited])
        assert not res.overturned.any()


@pytest.mark.parametrize("method,dec,k", SCHEMES, ids=[f"{m.name}-{d}-k{k}" for m, d, k in SCHEMES])
def test_undamped_axis_with_identical_subsystems(method, dec, k):
    """lr1 = 0, ratios (1, 1, 1): both subsystems undamped.  Where rho = 1 (to 160 digits: the symmetric ff schemes
    that keep the coupled motion's energy) the proof cannot separate it from 1 at any precision -- marginal; where
    a root lies exactly on the circle beside a larger one, the larger one still decides."""
    point = TestModel(0.0, 0.7, 1.0, 1.0, 1.0)
    c = certify_spectral_radius(point, method, dec, k)
    rho = spectral_radius_mp(point, method, dec, k, 160)
    if abs(rho - 1) < 1e-100:
        assert c.verdict == "marginal" and c.rho_lower <= 1 <= c.rho_upper
    else:
        assert c.verdict == ("stable" if rho < 1 else "unstable")
    with mpmath.workdps(60):
        assert mpmath.mpf(c.lower(40)) <= rho <= mpmath.mpf(c.upper(40))


def test_identical_undamped_ff_schemes_are_marginal():
    """The marginal case: rho = 1 exactly on the undamped axis with identical subsystems (projection, Baumgarte
    index 1, force/force) comes out marginal, as does the origin (a Jordan block at 1)."""
    cases = (
        (make_method("projection"), 1, (0.0, 0.3, 0.7)),
        (make_method("baumgarte", index=1, mu=1.0), 2, (0.0, 0.3, 1.9)),
    )
    for method, k, li1s in cases:
        for li1 in li1s:
            point = TestModel(0.0, li1, 1.0, 1.0, 1.0)
            assert abs(spectral_radius_mp(point, method, "ff", k, 80) - 1) < 1e-20  # rho = 1 (half the digits)
            assert certify_spectral_radius(point, method, "ff", k).verdict == "marginal"


def _boundary(method, dec, k, li1, lo, hi):
    """lr1 where rho = 1 on the line li1 = const, at 60 digits: the Illinois method (regula falsi that halves
    the value kept at a stale end), which keeps rho - 1 changing sign on its bracket [lo, hi] as bisection
    does, in some 15 evaluations of rho instead of bisection's 120."""
    f = lambda lr1: spectral_radius_mp(TestModel(lr1, li1, 1.0, 1.0, 1.0), method, dec, k, 60) - 1  # noqa: E731
    with mpmath.workdps(60):
        a, b = mpmath.mpf(lo), mpmath.mpf(hi)
        fa, fb = f(a), f(b)
        assert fa * fb < 0
        for _ in range(100):
            c = b - fb * (b - a) / (fb - fa)
            fc = f(c)
            if fc * fb < 0:
                a, fa = b, fb  # the root lies between c and the old b
            else:
                fa /= 2  # a stays an end: halve its value so that the next secant moves off it
            b, fb = c, fc
            if abs(fb) < mpmath.mpf("1e-40"):
                return b
        raise AssertionError("no root of rho - 1 found")


def test_points_1e_11_from_the_weighted_k2_boundary_are_proven_right():
    """Near the weighted multiplier's k = 2 stability boundary (a = b = 1, li1 = 0.3), points whose rho differs from
    1 by about +/- 1e-11 -- far below float64's error estimate there -- are proven stable or unstable correctly."""
    method, li1 = make_method("weighted", a=1.0, b=1.0), 0.3
    edge = _boundary(method, "ff", 2, li1, -0.2, -0.01)
    with mpmath.workdps(60):
        slope = (
            spectral_radius_mp(TestModel(edge + mpmath.mpf("1e-8"), li1, 1, 1, 1), method, "ff", 2, 60)
            - spectral_radius_mp(TestModel(edge - mpmath.mpf("1e-8"), li1, 1, 1, 1), method, "ff", 2, 60)
        ) / mpmath.mpf("2e-8")
        for sign in (1, -1):
            lr1 = edge + sign * mpmath.mpf("1e-11") / slope  # rho - 1 = sign * 1e-11 to first order
            point = TestModel(float(lr1), li1, 1.0, 1.0, 1.0)
            rho = spectral_radius_mp(point, method, "ff", 2, 60)
            assert 0.5e-11 < sign * (rho - 1) < 2e-11
            assert certify_spectral_radius(point, method, "ff", 2).verdict == ("unstable" if sign > 0 else "stable")
            # the policy certifies it too: within the band |rho - 1| < 1e-6, float64 is never taken on trust
            res = spectral_radius(point, method, "ff", 2)
            assert res.certified and res.verdict == ("unstable" if sign > 0 else "stable")


def test_a_point_float64_gets_wrong_is_certified_at_its_true_value():
    """lambda_bar = -100 + 100i, projection ff k = 1: float64 says rho = 1 (the stiff exponentials cancel), the true
    value is about 271; the proof encloses the 160-digit value and the policy reports it."""
    point, method = TestModel(-100.0, 100.0, 1.0, 1.0, 1.0), make_method("projection")
    raw, err = spectral_radius_float64(point, method, "ff", 1)
    rho = spectral_radius_mp(point, method, "ff", 1, 160)
    assert abs(float(raw) - float(rho)) > 100  # float64 is wrong ...
    c = certify_spectral_radius(point, method, "ff", 1)
    with mpmath.workdps(60):
        assert c.verdict == "unstable" and mpmath.mpf(c.lower(30)) <= rho <= mpmath.mpf(c.upper(30))
    res = spectral_radius(point, method, "ff", 1)
    assert res.verdict == "unstable" and res.certified and float(res.rho) == pytest.approx(float(rho), rel=1e-12)


def test_command_line_certify(capsys):
    argv = ["rho", "--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "ff", "--k", "2"]
    argv += ["--lr1", "-0.05", "--li1", "0.5", "--am21", "1", "--alr21", "1", "--ali21", "1", "--certify"]
    assert main(argv + ["--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # the command line takes the decimals as typed (-0.05 = -1/20 exactly, not the double): so does the reference
    point = TestModel(Fraction(-1, 20), Fraction(1, 2), 1, 1, 1)
    rho = spectral_radius_mp(point, make_method("weighted", a=1, b=1), "ff", 2, 60)
    assert out["verdict"] == "unstable" and out["certified"] is True and out["precision_bits"] >= 128
    with mpmath.workdps(60):
        assert mpmath.mpf(out["rho_lower"]) <= rho <= mpmath.mpf(out["rho_upper"])
    assert main(argv) == 0
    text = capsys.readouterr().out
    assert "unstable, proven: rho in [" in text and "at 129 bits" in text  # 128 + 1 guard bit
    marginal = ["rho", "--method", "projection", "--decomposition", "ff", "--k", "1", "--lr1", "0", "--li1", "0.5"]
    assert (
        main(marginal + ["--am21", "1", "--alr21", "1", "--ali21", "1", "--certify", "--max-bits", "256", "--json"])
        == 0
    )
    out = json.loads(capsys.readouterr().out)
    assert out["verdict"] == "marginal" and out["precision_bits"] == 256 + 0 and out["stable"] is False  # no guard


def test_enclosure_narrowed_to_the_digits_asked_for():
    """digits=N narrows a proven enclosure to N significant digits (it contains the 80-digit value); a marginal
    one (the origin: a Jordan block at 1) is kept as the cap decided it, so that no digits asked for can turn
    the verdict (narrowed at a higher precision it could exclude 1)."""
    point = TestModel(Fraction(-3, 10), Fraction(1, 20), 1, 1, 1)
    method = make_method("weighted", a=1, b=1)
    c = certify_spectral_radius(point, method, "ff", 2, digits=50)
    rho = spectral_radius_mp(point, method, "ff", 2, 80)
    assert c.verdict == "stable" and c.rho_upper - c.rho_lower <= Fraction(1, 10**50) * c.rho_upper
    with mpmath.workdps(80):
        assert mpmath.mpf(c.lower(70)) <= rho <= mpmath.mpf(c.upper(70))
    origin = TestModel(0.0, 0.0, 1, 1, 1)
    narrowed = certify_spectral_radius(origin, make_method("projection"), "ff", 0, digits=100)
    assert narrowed.verdict == "marginal" and narrowed.rho_lower <= 1 <= narrowed.rho_upper
    assert narrowed == certify_spectral_radius(origin, make_method("projection"), "ff", 0)


def test_a_singular_coupling_is_undecided_not_guessed():
    """At lr1 = -1, li1 = 0 (ratios 1) both subsystems are critically damped with k = 1, delta = 2: the acceleration
    at the end of a step responds to a constant force by (1 - t) e^-t at t = 1, exactly 0, so projection's linear
    system is singular there and the recurrence is undefined.  float64 still prints a number (its error estimate
    says it cannot be trusted); the proof says undecided.  Next to it the matrix grows like 1/(2 eps) (theory:
    a simple zero of the pivot) while rho stays near e^-1, proven on both sides."""
    method = make_method("projection")
    rho, err = spectral_radius_float64(TestModel(-1.0, 0.0), method, "ff", 0)
    assert err > 1 and np.isfinite(rho)
    c = certify_spectral_radius(TestModel(-1.0, 0.0), method, "ff", 0)
    assert c.verdict == "undecided" and "singular" in c.reason
    res = spectral_radius(TestModel(np.array([-1.0]), np.array([0.0])), method, "ff", 0)
    assert res.verdict[0] == "undecided" and res.reason_code[0] == "not_finite" and np.isnan(res.rho[0])
    for eps in (Fraction(1, 10**4), Fraction(-1, 10**4), Fraction(1, 10**6)):
        M = amplification_matrix(TestModel(float(-1 + eps), 0.0).coefficients(), method, "ff", 0)
        assert np.max(np.abs(M)) == pytest.approx(1 / (2 * abs(float(eps))), rel=1e-3)
        near = certify_spectral_radius(TestModel(-1 + eps, 0), method, "ff", 0)
        assert near.verdict == "stable" and abs(float(near.rho_lower) - np.exp(-1)) < 10 * abs(float(eps))


@pytest.mark.parametrize("method,dec,k", SCHEMES, ids=[f"{m.name}-{d}-k{k}" for m, d, k in SCHEMES])
def test_no_scheme_is_stable_at_the_origin(method, dec, k):
    """The reason the stability claims leave out lr1 = li1 = 0 (region.exclude_origin): both subsystems are free
    masses there (every coefficient is 0, whatever the ratios) and every scheme reproduces the rigid motion
    x0 + v t, so 1 is an eigenvalue of the recurrence (to 160 digits, up to the square root of the precision a
    Jordan block allows): rho >= 1, and the proof can only say marginal (rho = 1) or unstable, never stable."""
    from icosim.engine.backends import Multiprecision
    from icosim.problems.linear.spectral import amplification_matrix

    for ratios in ((1.0, 1.0, 1.0), (0.5, 2.0, 3.0)):
        point = TestModel(0.0, 0.0, *ratios)
        c = point.coefficients()
        assert all(getattr(c, f) == 0 for f in ("k1", "delta1", "k2", "delta2"))
        be = Multiprecision(160)
        with be.context(), mpmath.workdps(160):
            M = amplification_matrix(c.map(be.const), method, dec, k, backend=be)
            eigenvalues = mpmath.eig(mpmath.matrix(M.tolist()), left=False, right=False)
            assert min(abs(z - 1) for z in eigenvalues) < mpmath.mpf(10) ** -60
        cert = certify_spectral_radius(point, method, dec, k)
        assert cert.verdict in ("marginal", "unstable") and cert.rho_upper >= 1


def test_batched_certificates_are_those_of_each_point_alone():
    """A panel's points certified in one batch (icosim.engine.spectral.batched) get, point for point, the
    certificate each gets alone: stable, unstable, marginal (the undamped axis, the origin), points with
    guard bits (heavy damping), one beyond the guard cap; twice, the second time from the cache of ball
    exponentials."""
    from icosim.engine import backends
    from icosim.problems.linear.spectral import certify_spectral_radii

    points = [
        TestModel(-0.05, 0.5),
        TestModel(0.0, 0.3),
        TestModel(0.0, 0.0),
        TestModel(-1.9, 0.1, 2.0, 10.0, 1.0),  # decay ~ 38 macro steps: 55 guard bits
        TestModel(-0.4, 1.3, 10.0, 1.0, 10.0),
        TestModel(-12000.0, 0.0),  # past the guard cap: undecided, alone as in the batch
    ]
    for method, dec, k in SCHEMES[:2] + SCHEMES[6:]:
        for scheme in ("jacobi", "gauss-seidel-21"):
            alone = [certify_spectral_radius(p, method, dec, k, scheme=scheme) for p in points]
            backends._BALL_EXPM_CACHE.clear()
            for _ in range(2):
                batch = certify_spectral_radii(points, method, dec, k, scheme=scheme)
                assert batch == alone
    assert {c.verdict for c in alone} >= {"marginal", "undecided"}


def test_float64_grid_matrices_are_those_of_each_point_alone():
    """The amplification matrices of a grid in float64 (its arrays laid out with the grid axes fastest:
    icosim.engine.layout) are bit for bit those of each point computed alone (small arrays, NumPy's order)."""
    lr, li = np.meshgrid(np.linspace(-2, 0, 24), np.linspace(0, 2, 23), indexing="ij")
    grid = TestModel(lr, li, 10.0, 1.0, 10.0)
    for method, dec, k in SCHEMES:
        for scheme in ("jacobi", "gauss-seidel-12"):
            M = amplification_matrix(grid, method, dec, k, scheme=scheme)
            assert M.shape[:2] == lr.shape and lr.size * M.shape[-1] * 2 >= 4096  # the step's arrays laid out as a grid
            for idx in [(0, 0), (3, 5), (23, 22), (23, 0), (11, 17)]:
                one = amplification_matrix(TestModel(lr[idx], li[idx], 10.0, 1.0, 10.0), method, dec, k, scheme=scheme)
                assert M[idx].tobytes() == np.ascontiguousarray(one).tobytes()
