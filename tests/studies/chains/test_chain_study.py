"""The chain study's datasets against independent computations: the paper's two-mass model for two units, the
spectral radius on both sides of the bisected stable step, the order k + 1 of Gauss-Seidel, Eq. (72) by hand,
the changed unit of the placement part, and the configuration refused with the key named."""

import copy
from pathlib import Path

import numpy as np
import pytest
import yaml

from icosim import ParameterError, PhysicalModel, make_method
from icosim.engine.spectral.radius import spectral_radius_float64 as family_rho
from icosim.problems.linear.chain import Chain, ChainFamily
from icosim.problems.linear.spectral import spectral_radius_float64
from icosim.studies.chains.config import build_chain, check_config, scheme_name
from icosim.studies.chains.convergence import convergence_data, nrmse
from icosim.studies.chains.placement import changed_chain, position_index
from icosim.studies.chains.stability import stability_data

ROOT = Path(__file__).resolve().parents[3]


def _config(ci=True):
    cfg = yaml.safe_load((ROOT / "config" / "chains.yaml").read_text())["chains"]
    if ci:
        for key, value in yaml.safe_load((ROOT / "config" / "ci" / "chains.yaml").read_text())["chains"].items():
            cfg[key].update(value)
    return cfg


def _small():
    cfg = _config()
    cfg["stability"].update(n_units=[2, 3], methods=["projection"], k=[1], patterns=["ff", "fd-df"])
    cfg["stability"]["scan"] = {"min": 1e-3, "max": 1.0, "n": 10}
    return cfg


@pytest.fixture(scope="module")
def stability():
    return stability_data(_small()).to_xarray()


def test_both_configurations_are_accepted():
    check_config(_config(ci=False))
    check_config(_config(ci=True))


def test_two_single_masses_are_the_papers_model(stability):
    """The chain's rho at N = 2 and the dataset's two-mass column against the paper's model computed here."""
    a, b = _small()["units"]["mass"]
    H = stability["H"].values
    pm = PhysicalModel(
        m1=a["masses"][0], m2=b["masses"][0], c1=a["ground_stiffness"][0], c2=b["ground_stiffness"][0],
        d1=a["ground_damping"][0], d2=b["ground_damping"][0], H=H,
    )  # fmt: skip
    for pattern, dec in (("ff", "ff"), ("fd-df", "fd")):
        for kind in stability["scheme"].values:
            paper = spectral_radius_float64(
                pm.coefficients(), make_method("projection"), dec, 1, scheme=scheme_name(kind, 2)
            )[0]
            sel = {"unit": "mass", "pattern": pattern, "method": "projection", "k": 1, "scheme": kind}
            np.testing.assert_allclose(stability["rho"].sel({**sel, "n_units": 2}).values, paper, rtol=1e-10)
            np.testing.assert_allclose(stability["rho_two_mass"].sel(sel).values, paper, rtol=1e-10)


def test_the_bisected_step_is_stable_and_its_neighbour_above_is_not(stability):
    cfg = _small()
    res = cfg["stability"]["resolution"]
    bisected = np.argwhere(stability["status"].values == "bisected")
    assert len(bisected) >= 6
    for idx in bisected:
        sel = {d: stability[d].values[i] for d, i in zip(stability["status"].dims, idx)}
        n = int(sel["n_units"])
        chain = build_chain(cfg["units"][str(sel["unit"])], str(sel["pattern"]), n, 1.0)
        lo, hi = float(stability["H_max"].sel(sel)), float(stability["H_unstable"].sel(sel))
        rho, err = family_rho(
            ChainFamily(chain.with_H(np.array([lo, hi])), int(sel["k"])),
            make_method(str(sel["method"])),
            scheme=scheme_name(str(sel["scheme"]), n),
        )
        assert rho[0] + err[0] < 1 <= rho[1] + err[1]
        assert lo < hi <= lo * (1 + res)


def test_a_kinematically_driven_single_mass_in_two_joints_is_recorded_not_served(stability):
    sel = {"unit": "mass", "pattern": "fd-df", "n_units": 3}
    assert set(stability["status"].sel(sel).values.ravel()) == {"not served"}
    assert np.isnan(stability["H_max"].sel(sel).values).all()
    assert "not served" not in set(stability["status"].sel({"unit": "segment"}).values.ravel())


def test_gauss_seidel_on_chains_converges_with_order_k_plus_1():
    cfg = _config()
    cfg["convergence"].update(n_units=[2, 3], k=[1], schemes=["gauss-seidel-forward", "gauss-seidel-reverse"])
    ds = convergence_data(cfg).to_xarray()
    assert set(ds["order_status"].values.ravel()) == {"asymptotic"}
    np.testing.assert_allclose(ds["order"].values, 2.0, atol=0.1)


def test_eq_72_by_hand():
    ref = np.array([[1.0, 0.0], [-1.0, 2.0]])
    num = ref + np.array([[0.1, 0.0], [0.0, 0.0]])
    # sum of squares of the error 0.01; of the deviations from the means (1, 1) per variable: 2 + 2
    assert nrmse(ref, num) == pytest.approx(np.sqrt(0.01 / 4.0))
    assert np.isnan(nrmse(ref, num * np.nan))


@pytest.mark.parametrize("position, index", [("first", 0), ("middle", 2), ("last", 4), ("none", None)])
def test_the_changed_unit_is_the_one_at_its_place(position, index):
    base = build_chain(_config()["units"]["mass"], "ff", 5, 1.0)
    changed = changed_chain(base, {"masses": 10.0}, position)
    assert position_index(position, 5) == index
    for i, (s, t) in enumerate(zip(base.segments_, changed.segments_)):
        assert t.masses[0] == pytest.approx(s.masses[0] * (10.0 if i == index else 1.0))
        assert t.ground_stiffness == s.ground_stiffness
    assert isinstance(changed, Chain)


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda c: c["stability"].update(patterns=["ff", "fx"]), r"chains\.stability\.patterns\[1\].*ff, fd, df, dd"),
        (
            lambda c: c["stability"].update(schemes=["jacobi", "gs"]),
            r"chains\.stability\.schemes\[1\].*gauss-seidel-forward",
        ),
        (lambda c: c["placement"].update(unit="brick"), r"chains\.placement\.unit\[0\].*mass, segment"),
        (lambda c: c["convergence"].update(n_units=[3, 5]), r"chains\.convergence\.n_units: must include 2"),
        (lambda c: c["convergence"].update(unit="mass", pattern="fd"), r"chains\.convergence: unit 'mass'.*3 units"),
        (lambda c: c["stability"].pop("scan"), r"chains\.stability\.scan: is missing"),
        (lambda c: c["methods"].update(newton={}), r"chains\.methods\.newton: must be one of baumgarte"),
        (lambda c: c["stability"].update(k=[3]), r"chains\.stability\.k\[0\]: must be 0, 1 or 2"),
    ],
)
def test_a_bad_configuration_is_refused_naming_the_key(edit, message):
    cfg = copy.deepcopy(_config())
    edit(cfg)
    with pytest.raises(ParameterError, match=message):
        check_config(cfg)


def test_the_batched_runs_are_the_runs_alone():
    """Eq. (72) of a batch of step sizes against each step size run alone from the exact solution."""
    from icosim.engine.run import simulate
    from icosim.problems.linear.chain import chain_start
    from icosim.studies.chains.convergence import exact_samples, run_errors

    cfg = _config()
    H, method, scheme = np.array([2e-3, 1e-3]), make_method("projection"), scheme_name("gauss-seidel-forward", 3)
    chain = build_chain(cfg["units"]["segment"], "ff", 3, H)
    exact = [exact_samples(chain.with_H(h), t_end=0.05, x0=0.01) for h in H]
    batched = run_errors(chain, method, 1, scheme, exact)
    for j, (solution, ref) in enumerate(exact):
        problem = solution.chain.problem(1)
        S = np.array(simulate(problem, method, *chain_start(problem, solution), len(ref), scheme=scheme).states[1:])
        m = chain.n_masses
        numerical = np.concatenate([S[..., :m].reshape(len(ref), -1), S[..., m:].reshape(len(ref), -1)], axis=-1)
        assert batched[j] == pytest.approx(nrmse(ref, numerical), rel=1e-12)
    assert len(exact[0][1]) == 25 and len(exact[1][1]) == 50
