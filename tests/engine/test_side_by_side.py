"""The float64 estimate's shortcuts give the numbers of the plain computation bit for bit: a problem and its
disturbed copy side by side in one macro step, the points of a family asked for apart, and a coupling matrix
factored once for the many right-hand sides it serves."""

from pathlib import Path

import numpy as np
import pytest
import yaml

from icosim import TestModel, make_method
from icosim.engine.backends import Float64
from icosim.engine.methods import solve
from icosim.engine.methods.solve import solve_small
from icosim.engine.schemes import get_scheme
from icosim.engine.spectral.matrix import matrix_of
from icosim.engine.spectral.radius import DISTURBANCE, Float64Radius, _PointNoise
from icosim.problems.linear.chain import ChainFamily
from icosim.problems.linear.family import TwoMass
from icosim.studies.chains.config import build_chain, method_of

CFG = yaml.safe_load((Path(__file__).resolve().parents[2] / "config" / "chains.yaml").read_text())["chains"]

H = np.geomspace(2e-3, 0.5, 7)
# (family, method, scheme): a chain of segments (Jacobi: a coupling matrix larger than 2), a kinematically
# driven single mass (a block the same at every H), and the two-mass model with every mass driven (no block
# depends on the point)
FAMILIES = [
    (ChainFamily(build_chain(CFG["units"]["segment"], "ff", 4, 1.0).with_H(H), 2), "weighted", "jacobi"),
    (ChainFamily(build_chain(CFG["units"]["mass"], "fd-df", 2, 1.0).with_H(H), 1), "baumgarte", "jacobi"),
    (TwoMass(TestModel(-np.linspace(0.01, 1, 5), 0.5), "dd", k=1), "projection", "gauss-seidel-12"),
]


def _method(name):
    return method_of(CFG["methods"], name)


@pytest.mark.parametrize("family, mname, scheme", FAMILIES, ids=["segments", "driven-mass", "two-mass-dd"])
def test_a_problem_and_its_disturbed_copy_side_by_side_are_each_alone(family, mname, scheme):
    method, scheme = _method(mname), get_scheme(scheme)
    problem = family.problem(Float64())
    disturbed = problem.disturbed(_PointNoise(np.random.default_rng(3), family.shape), DISTURBANCE * Float64.eps)
    both = matrix_of(problem.side_by_side([disturbed]), method, scheme)
    np.testing.assert_array_equal(both[0], matrix_of(family.problem(Float64()), method, scheme))
    np.testing.assert_array_equal(both[1], matrix_of(disturbed, method, scheme))


@pytest.mark.parametrize("family, mname, scheme", FAMILIES[:2], ids=["segments", "driven-mass"])
def test_points_asked_for_apart_get_the_numbers_of_the_whole_family(family, mname, scheme):
    rho, err = Float64Radius(family, _method(mname), scheme=scheme, pointwise=True)()
    radius = Float64Radius(family, _method(mname), scheme=scheme, pointwise=True)
    for i in (5, 0, 3):
        r, e = radius(np.arange(H.size) == i)
        assert (r[0], e[0]) == (rho[i], err[i])  # bitwise
    with pytest.raises(ValueError):
        Float64Radius(family, _method(mname), scheme=scheme)(np.ones(H.size, dtype=bool))


def test_a_matrix_serving_many_right_hand_sides_is_solved_as_numpy_solves_each():
    rng = np.random.default_rng(0)
    J = rng.standard_normal((3, 1, 6, 6)) + 4 * np.eye(6)
    b = rng.standard_normal((3, 40, 6))
    expected = np.linalg.solve(np.broadcast_to(J, (3, 40, 6, 6)), b[..., None])[..., 0]
    np.testing.assert_array_equal(solve_small(J, b), expected)
    with pytest.raises(np.linalg.LinAlgError):
        solve_small(np.zeros((1, 6, 6)), b[0])


def test_a_chain_matrix_is_the_same_with_the_coupling_matrix_factored_once(monkeypatch):
    """The Jacobi coupling matrix of 32 single masses (31 rows) serves every basis vector: factored once, or
    (MANY out of reach) by numpy.linalg.solve for each."""
    chain = build_chain(CFG["units"]["mass"], "ff", 32, 1.0).with_H(H[:2].copy())
    family, method, scheme = ChainFamily(chain, 0), make_method("projection"), get_scheme("jacobi")
    M = matrix_of(family.problem(Float64()), method, scheme)
    monkeypatch.setattr(solve, "MANY", np.inf)
    np.testing.assert_array_equal(M, matrix_of(family.problem(Float64()), method, scheme))
