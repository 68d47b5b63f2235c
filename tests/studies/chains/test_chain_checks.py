"""The chain study's check kinds on constructed datasets: each decides pass and fail where its data can decide,
and is undecided (saying why) where they cannot."""

import numpy as np
import pytest
import xarray as xr

from icosim import ParameterError
from icosim.claims.registry import parse_claims
from icosim.studies.chains.checks import check_order, check_placement, check_trend, check_two_unit

ATTRS = {"part": "chains"}


def _stability(rho2, paper, H_max, H_unstable, status, n_units=(2, 3)):
    dims = ("unit", "pattern", "n_units", "method", "k", "scheme")
    coords = {"unit": ["mass"], "pattern": ["ff"], "n_units": list(n_units), "method": ["projection"], "k": [1],
              "scheme": ["jacobi"], "H": [0.01, 0.02]}  # fmt: skip
    shape = (1, 1, len(n_units), 1, 1, 1)
    rho = np.full(shape + (2,), 0.5)
    rho[0, 0, 0, 0, 0, 0] = rho2
    return xr.Dataset(
        {
            "rho": (dims + ("H",), rho),
            "rho_error": (dims + ("H",), np.full(shape + (2,), 1e-15)),
            "rho_two_mass": (("unit", "pattern", "method", "k", "scheme", "H"), np.reshape(paper, (1, 1, 1, 1, 1, 2))),
            "H_max": (dims, np.reshape(H_max, shape)),
            "H_unstable": (dims, np.reshape(H_unstable, shape)),
            "status": (dims, np.reshape(np.array(status, dtype=str), shape)),
        },
        coords=coords,
        attrs={**ATTRS, "dataset": "stability"},
    )


def test_two_unit_agreement_decides_both_ways_and_says_when_it_cannot():
    bisected = ["bisected", "bisected"]
    same = _stability([0.9, 1.2], [0.9, 1.2], [0.1, 0.1], [0.11, 0.11], bisected)
    off = _stability([0.9, 1.2], [0.9, 1.2 + 1e-6], [0.1, 0.1], [0.11, 0.11], bisected)
    assert check_two_unit([same], where={}, rtol=1e-10).holds is True
    assert check_two_unit([off], where={}, rtol=1e-10).holds is False
    segments_only = _stability([0.9, 1.2], [np.nan, np.nan], [0.1, 0.1], [0.11, 0.11], bisected)
    out = check_two_unit([segments_only], where={}, rtol=1e-10)
    assert out.holds is None and "single masses" in out.measured
    out = check_two_unit([same], where={"unit": "segment"}, rtol=1e-10)
    assert out.holds is None and "undecided, because" in out.measured


@pytest.mark.parametrize(
    "H_max, H_unstable, status, relation, holds",
    [
        ([0.10, 0.09], [0.11, 0.10], ["bisected"] * 2, "nonincreasing", True),
        ([0.10, 0.105], [0.11, 0.115], ["bisected"] * 2, "nonincreasing", True),  # within the bracket
        ([0.10, 0.12], [0.11, 0.13], ["bisected"] * 2, "nonincreasing", False),
        ([0.10, 0.12], [0.11, 0.13], ["bisected"] * 2, "nondecreasing", True),
        ([0.10, 0.08], [0.11, 0.09], ["bisected"] * 2, "nondecreasing", False),
        ([0.10, 1.0], [0.11, np.nan], ["bisected", "stable up to the cap"], "nonincreasing", None),
        ([0.10, np.nan], [0.11, np.nan], ["bisected", "not served"], "nonincreasing", None),
    ],
)
def test_trend_over_n_decides_only_on_bisected_brackets(H_max, H_unstable, status, relation, holds):
    ds = _stability([0.9, 1.2], [0.9, 1.2], H_max, H_unstable, status)
    assert check_trend([ds], where={}, relation=relation).holds is holds


def _convergence(orders, statuses, n_units=(2, 3)):
    dims = ("n_units", "method", "k", "scheme")
    shape = (len(n_units), 1, 1, 1)
    return xr.Dataset(
        {
            "order": (dims, np.reshape(orders, shape)),
            "order_status": (dims, np.reshape(np.array(statuses, dtype=str), shape)),
        },
        coords={"n_units": list(n_units), "method": ["projection"], "k": [1], "scheme": ["gauss-seidel-forward"]},
        attrs={**ATTRS, "dataset": "convergence"},
    )


@pytest.mark.parametrize(
    "orders, statuses, expect, holds",
    [
        ([2.02, 1.97], ["asymptotic"] * 2, "k+1", True),  # k = 1
        ([2.02, 1.5], ["asymptotic"] * 2, "k+1", False),
        ([2.02, 1.5], ["asymptotic", "pre-asymptotic"], "k+1", None),
        ([3.4, 3.45], ["asymptotic"] * 2, "two-unit", True),
        ([3.4, 2.0], ["asymptotic"] * 2, "two-unit", False),
        ([3.4, 2.0], ["pre-asymptotic", "asymptotic"], "two-unit", None),
    ],
)
def test_orders_decide_only_where_asymptotic(orders, statuses, expect, holds):
    assert check_order([_convergence(orders, statuses)], where={}, expect=expect, tolerance=0.15).holds is holds


def test_orders_against_two_units_undecided_without_a_longer_chain():
    out = check_order([_convergence([2.0], ["asymptotic"], n_units=(2,))], where={}, expect="two-unit", tolerance=0.1)
    assert out.holds is None and "undecided, because" in out.measured


def _placement(H_max, H_unstable, status):
    dims = ("variant", "position", "method", "k", "scheme")
    shape = (1, 4, 1, 1, 1)
    return xr.Dataset(
        {
            "H_max": (dims, np.reshape(H_max, shape)),
            "H_unstable": (dims, np.reshape(H_unstable, shape)),
            "status": (dims, np.reshape(np.array(status, dtype=str), shape)),
        },
        coords={
            "variant": ["heavy"],
            "position": ["none", "first", "middle", "last"],
            "method": ["projection"],
            "k": [1],
            "scheme": ["jacobi"],
        },  # fmt: skip
        attrs={**ATTRS, "dataset": "placement"},
    )


def test_placement_same_or_not_within_the_brackets():
    b = ["bisected"] * 4
    assert check_placement([_placement([0.1] * 4, [0.102] * 4, b)], where={}, relation="same").holds is True
    assert (
        check_placement(
            [_placement([0.1, 0.1, 0.05, 0.1], [0.102, 0.102, 0.051, 0.102], b)], where={}, relation="same"
        ).holds
        is False
    )
    censored = ["bisected", "bisected", "no stable step size", "bisected"]
    assert check_placement([_placement([0.1] * 4, [0.102] * 4, censored)], where={}, relation="same").holds is None


def test_a_claim_picking_an_unknown_coordinate_is_refused_naming_it():
    claim = {"id": "x", "source": "s", "statement": "t", "figures": ["f"],
             "check": {"kind": "chain_trend", "where": {"colour": "red"}, "relation": "nonincreasing"}}  # fmt: skip
    with pytest.raises(ParameterError, match=r"check\.where\.colour: must be one of unit, pattern, n_units"):
        parse_claims([claim])
