"""The peers -- libcosim (libcosimpy), Ecos (ecospy), FMPy's ``simulate_ssp`` -- on the same unit files as icosim:
OSP's quarter truck (../shared/outside/osp-quarter-truck) and OMSimulator's DualMassOscillator
(../shared/outside/omsimulator), each master as its users run it: the runners of
icosim.studies.peers.runners, which the peers study and benchmarks/peers.py time (docs/benchmarks.md,
work-precision against the peers).

What the tests compare follows from the methods, not from numbers of the code under test:

* every peer here is a non-iterative Jacobi master with a zero-order hold of the exchanged signals, first order
  in its step.  On the quarter truck (the units' internal solver RK4 at 1e-5 s, its own error far below the
  coupling's) the difference between libcosim and icosim (k = 1) at the same step falls by 2 per halving, and
  icosim's own changes are a small part of it: the difference is libcosim's first-order error;
* the DualMassOscillator's co-simulation units integrate with explicit Euler at the communication step, so a
  peer's error against the exact solution (DualMassOscillator.mo, test_drives.exact) falls by 2 per halving;
  libcosim and Ecos exchange the same values, so they agree far below that error, and FMPy (whose connectors
  start at 0) differs from them by a first-order amount;
* icosim (System1 and System2 as Model Exchange, Baumgarte index 1, k = 2, test_drives_outside.om_scene) is far
  closer to the exact solution than a peer at the same step.

Marked ``peers`` (tests/toolchains.py): the outside units, fmpy and the peer packages (the ``peers`` extra);
Ecos also needs TBB's shared library (Debian: libtbb12).  No timing is asserted.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pytest
from test_drives import AMPLITUDE, exact
from test_drives_outside import BAUMGARTE, om_scene
from toolchains import OUTSIDE

from icosim.order_fit import asymptotic_order
from icosim.studies.peers import runners as R
from icosim.studies.peers.runners import fmpy_dmo, icosim_run, libcosim_dmo, libcosim_truck, quiet

pytestmark = pytest.mark.peers

TRUCK = OUTSIDE / "osp-quarter-truck"
OM = OUTSIDE / "omsimulator"
#: OMSimulator's own test of the DualMassOscillator (tests/DualMassOscillator1.py's ``## Result``: co-simulation,
#: fixed step 1e-4): x1(10), x2(10); benchmarks/peers.py prints their errors beside the peers'.
OMSIMULATOR_CS = (0.051412690223479836, 0.031858470461315964)
#: The same as Model Exchange under CVODE (tests/DualMassOscillator2.py).
OMSIMULATOR_ME = (0.05067159474969803, 0.03142555558313003)


#: The runners of icosim.studies.peers.runners on the outside units (the study's and the benchmarks' runners).
truck_osp = partial(R.truck_osp, unit_dir=TRUCK)
ecos_truck = partial(R.ecos_truck, unit_dir=TRUCK)
truck_scene = partial(R.truck_scene, unit_dir=TRUCK)
dmo_osp = partial(R.dmo_osp, unit_dir=OM)
dmo_ssp = partial(R.dmo_ssp, unit_dir=OM)
ecos_dmo = partial(R.ecos_dmo, unit_dir=OM)


# -- the tests --------------------------------------------------------------------------------------------------

TRUCK_HS = [4e-4, 2e-4, 1e-4]
TRUCK_END = 0.2  # the chassis rises by 8 cm from its start


@pytest.fixture(scope="module")
def truck_runs(tmp_path_factory):
    """libcosim fixed step and icosim (Baumgarte index 1, k = 1) at the same steps, the units' solver RK4 at 1e-5 s."""
    tmp = tmp_path_factory.mktemp("truck")
    lc, ic = [], []
    with quiet():
        for H in TRUCK_HS:
            lc.append(libcosim_truck(truck_osp(tmp / f"lc_{H:g}", H, solver="RK4"), TRUCK_END))
            ic.append(icosim_run(truck_scene(tmp, H, 1, TRUCK_END, solver="RK4")))
    return lc, ic


def test_libcosim_and_icosim_differ_on_the_quarter_truck_by_libcosim_first_order_error(truck_runs):
    lc, ic = truck_runs
    assert all(r["status"] == "completed" for r in ic), ic
    assert all(abs(r["t"] - TRUCK_END) < 1e-12 for r in lc + ic)
    difference = [abs(a["x"] - b["x"]) for a, b in zip(lc, ic)]
    own = [abs(a["x"] - b["x"]) for a, b in zip(ic, ic[1:])]  # icosim's changes per halving
    fit = asymptotic_order(TRUCK_HS, difference)
    assert fit.status == "asymptotic" and abs(fit.order - 1.0) < 0.15, (difference, fit)
    assert own[-1] < 0.05 * difference[-1], (own, difference)  # the difference is libcosim's error


def test_ecos_and_libcosim_exchange_the_same_values_on_the_quarter_truck(tmp_path):
    """Both are Jacobi masters with the units' Euler at 1e-5 s of the file: the same steps, the same result up
    to the order in which the units' floating-point work is done."""
    with quiet():
        lc = libcosim_truck(truck_osp(tmp_path, 1e-4), 0.2)
        ec = ecos_truck(1e-4, 0.2)
    assert abs(ec["t"] - lc["t"]) < 1e-9
    assert abs(ec["x"] - lc["x"]) < 1e-9 * max(1.0, abs(lc["x"])), (ec, lc)
    assert abs(lc["x"]) > 1e-3  # it moved


def test_ecco_keeps_the_file_step_bounds_and_ends_past_the_stop_time(tmp_path):
    """The file's own ECCO configuration: at least one step per MaximumStepSize, at most one per
    MinimumStepSize, the last step ending at or past the stop time."""
    with quiet():
        r = libcosim_truck(truck_osp(tmp_path, 1e-4, algorithm="ecco"), 0.2)
    steps = r["do_steps"] // 2
    assert 0.2 <= r["t"] < 0.2 + 1e-2
    assert 0.2 / 1e-2 <= steps <= 0.2 / 1e-5 + 1, steps


DMO_END = 1.0
DMO_HS = [4e-4, 2e-4, 1e-4]


@pytest.fixture(scope="module")
def dmo_peers(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("dmo")
    ssp = dmo_ssp(tmp / "DualMassOscillator.ssp")
    runs = {"libcosim": [], "ecos": [], "fmpy": []}
    with quiet():
        for h in DMO_HS:
            runs["libcosim"].append(libcosim_dmo(dmo_osp(tmp / f"lc_{h:g}", h), DMO_END))
            runs["ecos"].append(ecos_dmo(h, DMO_END))
            runs["fmpy"].append(fmpy_dmo(ssp, h, DMO_END))
    return runs


def test_the_peers_converge_on_the_dual_mass_oscillator_at_first_order(dmo_peers):
    """Each at the time its run ends: FMPy's loop (``while time < stop_time``, the time summed step by step) takes
    one step past the stop time."""
    for name, runs in dmo_peers.items():
        assert all(DMO_END - 1e-9 < r["t"] < DMO_END + 1.5 * h for r, h in zip(runs, DMO_HS)), (name, runs)
        errors = [np.max(np.abs([r["x1"], r["x2"]] - exact([r["t"]])[0, :2])) for r in runs]
        fit = asymptotic_order(DMO_HS, errors)
        assert fit.status == "asymptotic" and abs(fit.order - 1.0) < 0.1, (name, errors, fit)


def test_libcosim_and_ecos_agree_far_below_their_error_and_fmpy_within_their_order(dmo_peers):
    """libcosim and Ecos set the inputs from the outputs at the start; FMPy's connectors start at 0 (System1's
    first step sees F = 0, not System2's 5 N): its difference to them is first order as well."""
    lc, ec, fm = (dmo_peers[name] for name in ("libcosim", "ecos", "fmpy"))
    for a, b in zip(lc, ec):
        error = abs(a["x1"] - exact([a["t"]])[0, 0])
        assert abs(a["t"] - b["t"]) < 1e-9 and abs(a["x1"] - b["x1"]) < 1e-6 * error, (a, b, error)
    difference = [abs(b["x1"] - exact([b["t"]])[0, 0] - (a["x1"] - exact([a["t"]])[0, 0])) for a, b in zip(lc, fm)]
    fit = asymptotic_order(DMO_HS, difference)
    assert fit.status == "asymptotic" and abs(fit.order - 1.0) < 0.1, (difference, fit)


def test_icosim_is_far_closer_to_the_exact_solution_than_a_peer_at_the_same_step(tmp_path, dmo_peers):
    """Baumgarte index 1, k = 2, H = 1e-3 on the Model Exchange units: x1 within a thousandth of libcosim's error
    at the finer step 4e-4."""
    with quiet():
        ic = icosim_run(om_scene(tmp_path, "baumgarte", 2, 1e-3, DMO_END, BAUMGARTE))
    x1 = exact([DMO_END])[0, 0]
    peer = abs(dmo_peers["libcosim"][0]["x1"] - x1)  # at 4e-4, a finer step than icosim's
    assert ic["status"] == "completed"
    assert abs(ic["x"] - x1) < 1e-3 * peer, (ic, peer)
    assert abs(ic["x"] - x1) < 1e-6 * AMPLITUDE
