"""The displacement/force decomposition (df), the mirror of force/displacement (fd).

df is a registry entry (``icosim.engine.decompositions``): subsystem 1 kinematically driven, subsystem 2
force driven.  The independent route: exchanging the two subsystems of the test model turns df into fd,
so rho of df at a point equals rho of fd at the *mirrored* point, whose five dimensionless parameters are
re-expressed relative to the other subsystem (Eq. 71):

    lr1' = lr2 = alr21 lr1,  li1' = li2 = ali21 li1,  am21' = 1/am21,  alr21' = 1/alr21,  ali21' = 1/ali21.

The two sides run different code: df integrates subsystem 1 with the kinematic propagator and solves
``mu_1 - lambda = 0``; fd integrates subsystem 2 kinematically and solves ``mu_2 - lambda = 0``.  A
Gauss-Seidel order names subsystems, so 1->2 of df mirrors 2->1 of fd.
"""

import json

import numpy as np
import pytest

from icosim import make_method
from icosim.cli import main
from icosim.engine.decompositions import DECOMPOSITIONS, get_decomposition
from icosim.engine.schemes import GS12, GS21, JACOBI
from icosim.problems.linear.model import TestModel
from icosim.problems.linear.spectral import spectral_radius_float64

METHODS = [
    ("baumgarte", {"index": 1, "mu": 1.0}),
    ("baumgarte", {"index": 2, "mu": 0.5}),
    ("baumgarte", {"index": 3}),
    ("weighted", {"a": 1.0, "b": 1.0}),
    ("weighted", {"a": 2.5, "b": 5.0}),
    ("projection", {}),
]


def mirrored(m: TestModel) -> TestModel:
    """The same physical model with subsystems 1 and 2 exchanged, in the dimensionless parameters."""
    return TestModel(m.alr21 * m.lr1, m.ali21 * m.li1, 1 / m.am21, 1 / m.alr21, 1 / m.ali21)


def _models(seed, n):
    rng = np.random.default_rng(seed)
    return [
        TestModel(
            -2 * rng.random(),
            2 * rng.random(),
            10 ** rng.uniform(-1, 1),
            10 ** rng.uniform(-1, 1),
            10 ** rng.uniform(-1, 1),
        )
        for _ in range(n)
    ]


def test_df_is_the_mirror_of_fd_in_the_registry():
    df, fd = get_decomposition("df"), get_decomposition("fd")
    assert df.kinds == fd.mirrored() == ("kinematic", "force")
    assert list(DECOMPOSITIONS) == ["ff", "fd", "df", "dd"]


@pytest.mark.parametrize("name,params", METHODS, ids=lambda x: x if isinstance(x, str) else "-".join(map(str, x)))
@pytest.mark.parametrize("k", [0, 1, 2])
def test_rho_of_df_equals_rho_of_fd_at_the_mirrored_point(name, params, k):
    method = make_method(name, **params)
    models = _models(100 + k, 12)
    # the 12 points as one batch (the float64 radius is vectorised over points)
    batch = TestModel(*(np.array([getattr(m, f) for m in models]) for f in ("lr1", "li1", "am21", "alr21", "ali21")))
    for scheme, mirror in ((JACOBI, JACOBI), (GS12, GS21), (GS21, GS12)):
        rho, err = spectral_radius_float64(batch.coefficients(), method, "df", k, scheme=scheme)
        rho_m, err_m = spectral_radius_float64(mirrored(batch).coefficients(), method, "fd", k, scheme=mirror)
        assert rho.shape == rho_m.shape == (len(models),)
        for i, model in enumerate(models):
            # equal within float64's own error estimates of the two radii
            assert np.isfinite(rho[i]), (model, scheme.name)
            assert abs(rho[i] - rho_m[i]) <= err[i] + err_m[i] + 1e-14, (model, scheme.name)


def test_df_and_fd_differ_where_the_subsystems_differ():
    """Not a relabelling: at the same (unmirrored) point df and fd give different radii."""
    method = make_method("baumgarte", index=1, mu=1.0)
    model = TestModel(-0.5, 1.0, 1.0, 1.0, 10.0)
    rho_df, _ = spectral_radius_float64(model.coefficients(), method, "df", 1)
    rho_fd, _ = spectral_radius_float64(model.coefficients(), method, "fd", 1)
    assert abs(float(rho_df) - float(rho_fd)) > 1e-3
    same = TestModel(-0.5, 1.0)  # identical subsystems: the mirror is the point itself
    assert mirrored(same) == same


def test_icosim_rho_df_equals_fd_at_the_mirrored_point(capsys):
    """The command line takes df like any registered decomposition, and the mirror holds end to end."""
    point = TestModel(-0.8, 1.3, 2.0, 0.5, 4.0)

    def rho(decomposition, m):
        args = ["rho", "--method", "weighted", "--a", "1", "--b", "1", "--decomposition", decomposition]
        args += ["--k", "2", "--json"]
        for key in ("lr1", "li1", "am21", "alr21", "ali21"):
            args += [f"--{key}", repr(float(getattr(m, key)))]
        assert main(args) == 0
        return json.loads(capsys.readouterr().out)

    a, b = rho("df", point), rho("fd", mirrored(point))
    assert a["decomposition"] == "df" and b["decomposition"] == "fd"
    assert a["verdict"] == b["verdict"]
    assert abs(a["rho"] - b["rho"]) <= 1e-12 * max(1.0, a["rho"])
