"""Adding a coupling method touches the registry and its rule only.

A toy method -- a velocity-level correction ``g' + tau g'' = 0`` with a time
constant ``tau`` (seconds where the setting is dimensional), index 2 -- is
registered here, in the test, through :func:`icosim.engine.methods.register` alone.
Nothing else in the package names it, yet the factory, the command line, the
convergence study, the stability policy, the pendulum and the configuration
schemas accept it, and its ``tau`` is scaled with ``H`` as the registry says.
"""

import json
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import ROOT, validate_config

from icosim import TestModel
from icosim.cli import main
from icosim.engine import methods
from icosim.engine.methods import CouplingMethod, MethodSpec, Parameter, make_method
from icosim.engine.methods.base import finite
from icosim.errors import ParameterError
from icosim.problems.linear.spectral import spectral_radius
from icosim.problems.pendulum.config import configured_runs
from icosim.problems.pendulum.linearised import linear_test_model_rho
from icosim.problems.pendulum.model import PendulumParameters
from icosim.problems.pendulum.runs import run_cosimulation
from icosim.studies.convergence.datasets import run_panel
from icosim.studies.convergence.experiment import Setup, dimensional_method, step_counts
from icosim.studies.convergence.panels import figure_panels
from icosim.studies.convergence.study import Study
from icosim.studies.stability.datasets import stability_panel
from icosim.studies.stability.panels import PanelSpec as StabilityPanel

NAME = "toy_velocity"


def toy_velocity(tau=None):
    """The rule: one solve on ``g' + tau g''`` (velocity level, damped by the acceleration level)."""
    if tau is None:
        raise ParameterError(f"{NAME} needs tau")
    tau = finite("tau", tau)
    if tau <= 0:
        raise ParameterError(f"tau must be > 0, got {tau!r}")
    return CouplingMethod(NAME, ((1, (0, 1, tau)),), params={"tau": tau, "index": 2}, requires_constraint=True)


SPEC = MethodSpec(
    name=NAME,
    label="velocity-level correction",
    short_label="velocity",
    build=toy_velocity,
    parameters=(
        Parameter(
            "tau",
            "toy: time constant of the acceleration level",
            unit="s",
            scaling=1,
            symbol="τ̄",
            tex=r"$\bar\tau$",
            tex_dimensional=r"$\tau$",
            exclusive_minimum=True,
        ),
    ),
    indices=(2,),
    requires_constraint=True,
    label_parameters=("tau",),
)


@pytest.fixture
def toy():
    spec = methods.register(SPEC)
    yield spec
    del methods.METHODS[NAME]  # the registry as it was


def test_no_file_of_the_package_names_the_toy():
    assert not [p for p in (ROOT / "src").rglob("*.py") if NAME in p.read_text()]


def test_factory_and_scaling(toy):
    assert make_method(NAME, tau=0.5).solves == ((1, (0, 1, 0.5)),)
    with pytest.raises(ParameterError, match=r"parameter\(s\) mu not used by method 'toy_velocity' \(it takes tau\)"):
        make_method(NAME, tau=1.0, mu=1.0)
    # tau is in seconds in the dimensional setting: tau_bar = tau / H
    assert dimensional_method(NAME, 1e-3, tau=2e-3).params["tau"] == pytest.approx(2.0)
    with pytest.raises(ParameterError, match="not defined for decomposition 'dd'"):
        make_method(NAME, tau=1.0).check_decomposition(_dd())


def _dd():
    from icosim.engine.decompositions import get_decomposition

    return get_decomposition("dd")


def test_command_line(toy, capsys):
    argv = ["rho", "--method", NAME, "--tau", "1", "--decomposition", "ff", "--k", "1"]
    argv += ["--lr1", "-0.5", "--li1", "1", "--am21", "1", "--alr21", "1", "--ali21", "1", "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["method"] == NAME and out["method_parameters"] == {"tau": 1.0, "index": 2}
    assert np.isfinite(out["rho"])
    with pytest.raises(SystemExit):  # the toy takes no index argument
        main(argv[:-1] + ["--index", "2"])
    assert "argument --index: not used by --method toy_velocity (its parameters: --tau)" in capsys.readouterr().err


def test_stability_policy_and_panel(toy):
    model = TestModel(np.array([-0.1, -0.5]), np.array([0.5, 1.0]))
    res = spectral_radius(model, make_method(NAME, tau=1.0), "ff", 1)
    assert res.rho.shape == (2,) and np.all(np.isfinite(res.rho))
    spec = StabilityPanel(
        figure="99",
        row=1,
        k=1,
        view="full",
        method=NAME,
        method_params={"tau": 1.0},
        decomposition="fd",
        am21=1.0,
        alr21=1.0,
        ali21=1.0,
        lr1=(-1.0, 0.0),
        li1=(0.0, 1.0),
        n=3,
        digits=30,
    )
    ds = stability_panel(spec)
    assert ds.attrs["method"] == NAME and ds.attrs["tau"] == 1.0 and ds["rho"].shape == (3, 3)
    assert "tau_bar = tau/H" in ds.attrs["method_parameters_units"]


def test_convergence_study(toy):
    study = Study(Setup(end_time=0.2), step_counts(0.2, 2e-4, 2e-2, 5))
    curve = study.run(NAME, {"tau": 1e-3}, "ff", 1)
    assert np.all(np.isfinite(curve.nrmse)) and np.all(np.diff(curve.nrmse) < 0)  # smaller H, smaller error
    fig = {"method": NAME, "columns": [{"tau": 1e-3}], "rows": [{}], "decompositions": ["ff"]}
    [panel] = figure_panels("99", fig, [1])
    ds = run_panel(panel, study, {"min_points": 3})
    assert ds.attrs["method"] == NAME and float(ds.attrs["tau"]) == 1e-3 and ds["tau"].attrs["units"] == "s"
    assert np.isfinite(ds["order"].values).all()


def test_pendulum(toy):
    params = PendulumParameters()
    res = run_cosimulation(params, make_method(NAME, tau=1e-3), "ff", 1, H=1e-3, t_end=0.01)
    assert res.status == "stable" and len(res.t) == 11
    rho, _ = linear_test_model_rho(params, 1e-3, make_method(NAME, tau=1e-3), "fd", 1)
    assert np.isfinite(rho)
    cfg = yaml.safe_load((ROOT / "config" / "pendulum.yaml").read_text())["pendulum"]
    cfg["methods"][NAME] = {"tau": 1e-3}
    cfg["configurations"].append({"method": NAME, "decomposition": "fd"})
    assert (NAME, "fd", 2) in configured_runs(cfg)
    validate_config(cfg, "pendulum")  # the schema accepts it too


def test_schemas(toy):
    cfg = yaml.safe_load((ROOT / "config" / "convergence.yaml").read_text())["convergence"]
    cfg["figures"]["99"] = {
        "title": "toy",
        "method": NAME,
        "columns": [{"tau": 1e-3}],
        "rows": [{}],
        "decompositions": ["ff"],
    }
    validate_config(cfg, "convergence")
    cfg = yaml.safe_load((ROOT / "config" / "stability.yaml").read_text())["stability"]
    fig = next(iter(cfg["figures"].values()))
    cfg["figures"]["99"] = {
        **fig,
        "method": NAME,
        "decomposition": "ff",
        "params": {"tau": 1.0},
        "rows": [{"tau": 2.0}],
    }
    validate_config(cfg, "stability")
    cfg["figures"]["99"]["params"] = {"tau": -1.0}
    with pytest.raises(Exception, match="tau"):
        validate_config(cfg, "stability")


def test_without_registration_the_toy_is_unknown():
    with pytest.raises(ParameterError, match="method must be one of baumgarte, weighted, projection"):
        make_method(NAME, tau=1.0)
    assert Path(__file__).is_file()
