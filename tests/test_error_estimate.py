"""The float64 error estimate: its second disturbed run, made only where the first one leaves doubt,
decides which points float64 may decide exactly as the estimate with both runs on every point."""

import numpy as np
import pytest

from icosim import TestModel, make_method
from icosim.engine.spectral.policy import Certification
from icosim.engine.spectral.radius import spectral_radius_float64

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
