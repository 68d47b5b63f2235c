"""The float64 error estimate: its second disturbed run, made only where the first one leaves doubt,
decides which points float64 may decide exactly as the estimate with both runs on every point."""

import numpy as np
import pytest

from icosim import TestModel, make_method
from icosim.engine.spectral.policy import Certification
from icosim.problems.linear.spectral import spectral_radius_float64, spectral_radius_mp
from icosim.studies.stability.panels import grid_axis

# the plane of Figs. 9-20 with its edges: the origin (a Jordan block at 1) and the undamped axis (rho = 1)
LR, LI = np.meshgrid(np.linspace(-2, 0, 61), np.linspace(0, 2, 61), indexing="ij")
CASES = [
    ("projection", {}, "ff", 2, "jacobi"),
    ("baumgarte", {"index": 2, "mu": 1.0}, "ff", 0, "gauss-seidel-12"),
    ("weighted", {"a": 1, "b": 1}, "fd", 1, "jacobi"),
    ("projection", {}, "dd", 1, "gauss-seidel-12"),
    ("baumgarte", {"index": 3}, "fd", 0, "jacobi"),
]


@pytest.mark.parametrize("method, params, decomposition, k, scheme", CASES)
def test_trust_is_decided_as_with_two_disturbed_runs_everywhere(method, params, decomposition, k, scheme):
    m, point = make_method(method, **params), TestModel(LR, LI)
    rho, err = spectral_radius_float64(point, m, decomposition, k, scheme=scheme)
    rho2, err2 = spectral_radius_float64(point, m, decomposition, k, scheme=scheme, doubt=np.inf)
    np.testing.assert_array_equal(rho, rho2)
    band = Certification().band  # nearer to 1 every point is certified, trusted or not
    outside = np.abs(rho - 1) >= band
    trusted, trusted2 = np.abs(rho - 1) > err, np.abs(rho2 - 1) > err2
    np.testing.assert_array_equal(trusted[outside], trusted2[outside])
    # where one run sufficed, the estimate is the first run's: never above the estimate of both runs
    once = np.abs(rho - 1) > 1000 * err
    assert np.all(err[once] <= err2[once])


def test_a_point_alone_gets_its_estimate_too():
    m = make_method("projection")
    rho, err = spectral_radius_float64(TestModel(0.0, 0.0), m, "ff", 0)
    assert abs(float(rho) - 1) <= float(err)  # the origin: a Jordan block at 1, float64 cannot decide it
    rho, err = spectral_radius_float64(TestModel(-0.5, 1.0), m, "ff", 0)
    assert np.isfinite(err) and float(err) < 1e-12


def test_rho_is_the_same_with_and_without_the_estimate():
    """The estimate takes rho from the eigenvalues it computes with the eigenvectors: the very ones."""
    for method, params, decomposition, k, scheme in CASES:
        m, point = make_method(method, **params), TestModel(LR, LI)
        rho, _ = spectral_radius_float64(point, m, decomposition, k, scheme=scheme)
        plain, _ = spectral_radius_float64(point, m, decomposition, k, scheme=scheme, error_estimate=False)
        np.testing.assert_array_equal(rho, plain)


# Points of the CI stability panels (config/ci/stability.yaml: 21 x 21 grids, zooms 11 x 11) where the estimate
# with the rounding floor 8 eps max(rho, 1) was below the error against 40 digits, with OPENBLAS_CORETYPE=Haswell
# or without it; the disturbances are drawn per grid, so each panel's grid is computed whole, as the panel is.
# (figure: method, parameters, decomposition, k, scheme, (am21, alr21, ali21), view, [(i, j) of lr1, li1])
MISSED = {
    "9 gs12 r2 k0": ("baumgarte", {"index": 1, "mu": 1.0}, "ff", 0, "gauss-seidel-12", (10, 1, 1), "full", [(14, 0)]),
    "11 gs12 r1 k1": ("projection", {}, "ff", 1, "gauss-seidel-12", (1, 1, 1), "full", [(2, 1)]),
    "11 gs12 r4 k0": ("projection", {}, "ff", 0, "gauss-seidel-12", (1, 1, 10), "full", [(2, 6)]),
    "11 gs12 r4 k1": ("projection", {}, "ff", 1, "gauss-seidel-12", (1, 1, 10), "full", [(20, 4)]),
    "11 gs21 r2 k0": ("projection", {}, "ff", 0, "gauss-seidel-21", (10, 1, 1), "full", [(5, 1)]),
    "11 gs21 r2 k1": ("projection", {}, "ff", 1, "gauss-seidel-21", (10, 1, 1), "full", [(5, 0)]),
    "13 jac r1 k0": ("weighted", {"a": 1.0, "b": 1.0}, "fd", 0, "jacobi", (1, 1, 1), "full", [(7, 17)]),
    "13 jac r4 k0": ("weighted", {"a": 1.0, "b": 1.0}, "fd", 0, "jacobi", (1, 1, 10), "full", [(16, 13)]),
    "13 gs21 r2 k2 zoom": ("weighted", {"a": 1.0, "b": 1.0}, "fd", 2, "gauss-seidel-21", (10, 1, 1), "zoom", [(0, 3)]),
    "14 jac r1 k1": ("projection", {}, "fd", 1, "jacobi", (1, 1, 1), "full", [(10, 3)]),
    "14 gs21 r1 k0": ("projection", {}, "fd", 0, "gauss-seidel-21", (1, 1, 1), "full", [(1, 17)]),
    "14 gs21 r1 k1": ("projection", {}, "fd", 1, "gauss-seidel-21", (1, 1, 1), "full", [(4, 20)]),
    "15 gs21 r2 k2": ("projection", {}, "dd", 2, "gauss-seidel-21", (10, 1, 1), "full", [(11, 18)]),
    "16 jac r1 k0": ("baumgarte", {"index": 2, "mu": 0.25}, "ff", 0, "jacobi", (2, 2, 2), "full", [(13, 16), (16, 16)]),
    "19 jac r2 k2": ("baumgarte", {"index": 1, "mu": 1.0}, "ff", 2, "jacobi", (2, 2, 2), "full", [(16, 17)]),
}


@pytest.mark.parametrize("panel", MISSED)
def test_the_estimate_bounds_the_error_where_a_floor_proportional_to_rho_did_not(panel):
    """A disturbed run's effect on rho is a random draw that can come out near zero: the floor, the first-order
    effect of rounding at u nu ||M||_F on the eigenvalue (its condition number times that), must not rest on it."""
    method, params, decomposition, k, scheme, ratios, view, points = MISSED[panel]
    lr_box, li_box, n = ((-2.0, 0.0), (0.0, 2.0), 21) if view == "full" else ((-0.2, 0.0), (0.0, 0.2), 11)
    lr1, li1 = np.meshgrid(grid_axis(lr_box, n), grid_axis(li_box, n), indexing="ij")
    m = make_method(method, **params)
    rho, err = spectral_radius_float64(TestModel(lr1, li1, *ratios), m, decomposition, k, scheme=scheme)
    for i, j in points:
        point = TestModel(float(lr1[i, j]), float(li1[i, j]), *ratios)
        ref = float(spectral_radius_mp(point, m, decomposition, k, digits=40, scheme=scheme))
        assert abs(rho[i, j] - ref) <= err[i, j], (lr1[i, j], li1[i, j], rho[i, j], ref, err[i, j])
