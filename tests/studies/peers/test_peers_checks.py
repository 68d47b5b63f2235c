"""The peers study's check kinds (icosim.studies.peers.checks) on datasets made by hand: errors of a chosen order
in the step give that order; equal end values agree, values apart by more than the claimed share of the error do
not."""

import pytest
from peers_data import dataset, run

from icosim.claims.registry import CHECKS

ORDER, AGREE = CHECKS["peers_order"].fn, CHECKS["peers_agree"].fn
STEPS = [4e-3, 2e-3, 1e-3, 5e-4]


def series(master, power, c=1.0):
    return [run(master, h, c * h**power, 0.1, 2 / h, 1 / h) for h in STEPS]


@pytest.mark.parametrize(("power", "verdict"), [(1, True), (2, False)])
def test_the_order_is_the_power_of_the_step_the_errors_follow(power, verdict):
    ds = dataset(series("libcosim", power) + series("Ecos", 1))
    outcome = ORDER([ds], system="dual_mass", masters=["libcosim", "Ecos"], order=1, tolerance=0.1)
    assert outcome.holds is verdict, outcome.measured


def test_no_completed_series_is_undecided_and_an_ecco_series_is_not_a_fixed_step():
    missing = [run("FMPy", h, 0.0, 0.0, 0, 0, status="missing: fmpy (test)") for h in STEPS]
    ecco = [run("libcosim", 1e-4, 10**-t, 0.1, 2e4, 1e4, series="libcosim, ECCO", tolerance=10**-t) for t in (3, 4, 5)]
    ds = dataset(missing + ecco)
    assert ORDER([ds], system="dual_mass", masters=["FMPy", "libcosim"], order=1, tolerance=0.1).holds is None


def test_equal_end_values_agree_and_values_a_thousandth_of_the_error_apart_do_not():
    same = dataset(series("libcosim", 1) + series("Ecos", 1))
    assert AGREE([same], system="dual_mass", masters=["libcosim", "Ecos"], value=1e-6).holds is True
    apart = dataset(series("libcosim", 1) + series("Ecos", 1, c=1.001))
    assert AGREE([apart], system="dual_mass", masters=["libcosim", "Ecos"], value=1e-6).holds is False
    other = dataset(series("libcosim", 1))
    assert AGREE([other], system="dual_mass", masters=["libcosim", "Ecos"], value=1e-6).holds is None
