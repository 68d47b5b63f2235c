"""The point-by-point check kind (icosim.studies.stability.pointwise) on synthetic panels with known verdicts,
and the mechanism behind the Gauss-Seidel claims that use it, on engine grids."""

import numpy as np
import pytest
import xarray as xr

from icosim import TestModel, make_method
from icosim.claims.registry import evaluate_claim, parse_claims
from icosim.engine.spectral.policy import VERDICTS
from icosim.errors import ParameterError
from icosim.problems.linear.spectral import amplification_matrix

S, U, M, X = (VERDICTS.index(v) for v in ("stable", "unstable", "marginal", "undecided"))


def panel(verdicts, lr1=(-1.0, 0.0), **attrs):
    v = np.asarray(verdicts, dtype=np.int8)
    base = {"method": "projection", "decomposition": "ff", "row": 1, "k": 1, "view": "full", "figure": "11"}
    base.update(attrs)
    return xr.Dataset(
        {"verdict": (("lr1", "li1"), v), "rho": (("lr1", "li1"), np.where(v == U, 1.5, 0.5))},
        coords={"lr1": np.linspace(*lr1, v.shape[0]), "li1": np.linspace(0.0, 1.0, v.shape[1])},
        attrs=base,
    )


def verdict(relation, datasets, **extra):
    check = {"kind": "pointwise", "a": {"scheme": "gs"}, "b": {"scheme": "jacobi"}, "relation": relation, **extra}
    item = {"id": "c", "source": "test", "statement": "test", "figures": ["11"], "check": check}
    return evaluate_claim(parse_claims([item])[0], datasets)


BASE = [[S, S, U], [S, U, U], [M, M, U]]


@pytest.mark.parametrize(
    "change, relation, expected",
    [
        (None, "same", "pass"),  # identical verdicts, marginal points included
        ((0, 2, S), "same", "fail"),  # one point stable in a, unstable in b
        ((2, 0, S), "same", "undecided"),  # marginal in b, stable in a: cannot tell
        ((0, 0, X), "same", "undecided"),  # undecided in a
        ((0, 2, S), "subset", "fail"),  # a stable where b is not
        ((0, 0, U), "subset", "pass"),  # a lost a point: still within b
        ((0, 0, U), "proper_subset", "pass"),
        (None, "proper_subset", "fail"),  # equal regions: not a proper subset
        ((0, 0, U), "differ", "pass"),
        (None, "differ", "fail"),
        ((2, 0, S), "differ", "undecided"),
    ],
)
def test_relations(change, relation, expected):
    a = np.array(BASE)
    if change:
        a[change[0], change[1]] = change[2]
    v = verdict(relation, [panel(a, scheme="gs"), panel(BASE, scheme="jacobi")])
    assert v.verdict == expected, v.measured


def test_the_contradicting_points_are_listed_with_rho():
    a = np.array(BASE)
    a[0, 2] = S
    v = verdict("same", [panel(a, scheme="gs"), panel(BASE, scheme="jacobi")])
    (entry,) = v.numbers.values()
    assert entry["n_failing"] == 1 and entry["failing_points"] == [
        {"lr1": -1.0, "li1": 1.0, "a": "S", "b": "U", "rho_a": 0.5, "rho_b": 1.5}
    ]
    assert "(-1, 1) S/U" in v.measured


def test_panels_are_paired_by_attributes_and_a_region_restricts_the_points():
    a = [panel(BASE, scheme="gs", k=k) for k in (1, 2)]
    b = [panel(BASE, scheme="jacobi", k=1), panel(np.full((3, 3), U), scheme="jacobi", k=2)]
    assert verdict("same", a + b).verdict == "fail"  # k = 2 differs
    assert verdict("same", a + b, pair_by=["method", "k"]).verdict == "fail"
    # the differing points of k = 2 all lie at lr1 <= -0.5 (rows 0 and 1 of the grid): outside the region
    v = verdict("same", [a[1], b[1]], region={"lr1": [0.0, 0.0]})
    assert v.verdict == "undecided"  # the marginal row left: M against U


def test_missing_partner_or_other_grid_is_undecided_and_ambiguity_an_error():
    a = panel(BASE, scheme="gs")
    assert verdict("same", [a, panel(BASE, scheme="jacobi", k=2)]).verdict == "undecided"
    assert verdict("same", [a, panel(BASE, scheme="jacobi", lr1=(-2.0, 0.0))]).verdict == "undecided"
    with pytest.raises(ParameterError, match="picks two panels"):
        verdict("same", [a, panel(BASE, scheme="jacobi"), panel(BASE, scheme="jacobi", figure="9")])
    with pytest.raises(ParameterError, match="relation"):
        verdict("equal", [a])
    with pytest.raises(ParameterError, match="pair_by"):
        verdict("same", [a], pair_by="row")


# -- the mechanism behind the Gauss-Seidel projection claims (docs/gauss_seidel.md) -------------------------
ROWS = {1: (1, 1, 1), 2: (10, 1, 1), 3: (1, 10, 1), 4: (1, 1, 10)}  # Fig. 11: am21, alr21, ali21


def _grid(row, k, scheme, n=41):
    lr1, li1 = np.meshgrid(np.linspace(-2, 0, n), np.linspace(0, 2, n), indexing="ij")
    ev = np.linalg.eigvals(
        amplification_matrix(TestModel(lr1, li1, *ROWS[row]), make_method("projection"), "ff", k, scheme=scheme)
    )
    dominant = np.take_along_axis(ev, np.argmax(np.abs(ev), axis=-1)[..., None], axis=-1)[..., 0]
    rho = np.abs(dominant)
    return rho < 1 - 1e-9, rho > 1 + 1e-9, dominant  # points within 1e-9 of 1 are left out


@pytest.mark.parametrize("k", [1, 2])
def test_projection_ff_boundary_is_a_real_eigenvalue_through_one_in_rows_1_to_3(k):
    """Rows 1-3 of Fig. 11: every unstable point next to a stable one has a real dominant eigenvalue > 1, the
    case every scheme shares (test_an_eigenvalue_one_is_shared_by_every_scheme), and the three schemes have the
    same verdicts point by point."""
    for row in (1, 2, 3):
        stable, unstable, dominant = _grid(row, k, "jacobi")
        near = np.zeros_like(stable)
        near[1:] |= stable[:-1]
        near[:-1] |= stable[1:]
        near[:, 1:] |= stable[:, :-1]
        near[:, :-1] |= stable[:, 1:]
        boundary = unstable & near
        assert boundary.sum() > 10
        assert np.all(np.abs(dominant[boundary].imag) < 1e-8) and np.all(dominant[boundary].real > 1)
        for scheme in ("gauss-seidel-12", "gauss-seidel-21"):
            s, u, _ = _grid(row, k, scheme)
            assert not np.any((stable & u) | (unstable & s)), (row, scheme)


@pytest.mark.parametrize("k", [1, 2])
def test_projection_ff_row4_differs_where_a_complex_pair_crosses(k):
    """Row 4 (ali21 = 10): the schemes' verdicts differ at some points, and at each of them the dominant
    eigenvalue of the scheme that is unstable there is a complex pair, which the shared eigenvalue 1 does not
    govern."""
    stable_j, unstable_j, dom_j = _grid(4, k, "jacobi")
    for scheme in ("gauss-seidel-12", "gauss-seidel-21"):
        stable_g, unstable_g, dom_g = _grid(4, k, scheme)
        lost, gained = stable_j & unstable_g, unstable_j & stable_g
        assert lost.sum() + gained.sum() > 0, scheme
        assert np.all(np.abs(dom_g[lost].imag) > 1e-6) and np.all(np.abs(dom_j[gained].imag) > 1e-6)
