"""The FMU study (icosim.studies.fmi): the validation functions the workflow calls against independent
computations, its check kinds, its claims file and its report section.  The workflow's side (its jobs and rerun
triggers): tests/workflow/test_fmi_workflow.py.

The runs build the test units: they are marked ``fmu`` (fmpy, CMake, a C compiler).
"""

import json

import numpy as np
import pytest
import xarray as xr
import yaml
from helpers import ROOT

from icosim.claims.registry import CHECKS, evaluate
from icosim.report.fmi import fmi_section
from icosim.studies.fmi.checks import check_bound, check_orders
from icosim.verdicts import parse_claims

CACHE = ROOT / "build" / "fmus"


# -- the validation functions against independent computations -----------------------------------------------


def test_measured_growth_of_a_synthetic_mode():
    """A pure mode growing by r per step (the phase turning): the measure gives r."""
    from icosim.studies.fmi.validation import measured_growth

    n, r, theta = 400, 1.05, 2.6
    steps = np.arange(n + 1)
    x = 0.1 * r**steps * np.cos(theta * steps)
    omega = np.sqrt(1500.0 / 3.0)
    v = -0.1 * omega * r**steps * np.sin(theta * steps)
    scene = {"subsystems": {"a": {"start": {"m": 1.0, "c": 1000.0}}, "b": {"start": {"m": 2.0, "c": 500.0}}}}
    ds = xr.Dataset(
        {"position": (("subsystem", "time"), np.stack([x, x])), "velocity": (("subsystem", "time"), np.stack([v, v]))},
        coords={"time": steps * 1e-3},
        attrs={"scene_json": json.dumps(scene)},
    )
    assert measured_growth(ds) == pytest.approx(r, rel=1e-12)


@pytest.mark.fmu  # the run builds the test units
def test_unstable_scene_against_the_engine(monkeypatch):
    """two_mass_unstable: the predicted rho is the engine's spectral radius for the typed-in parameters, the
    measured growth is that rho, and the built-in difference is that of an independent built-in run."""
    from icosim.engine.methods import engine_method, make_method
    from icosim.engine.run import simulate
    from icosim.problems.fmu.run import run_dataset, run_scene
    from icosim.problems.fmu.scene import load_scene
    from icosim.problems.linear.model import PhysicalModel
    from icosim.problems.linear.problem import LinearCosimulation
    from icosim.problems.linear.spectral import spectral_radius_float64
    from icosim.studies.fmi.validation import scene_validation

    monkeypatch.setenv("ICOSIM_FMU_CACHE", str(CACHE))
    scene = load_scene(ROOT / "config" / "scenes" / "two_mass_unstable.yaml")
    run = run_dataset(run_scene(scene, cache=CACHE))
    checked = scene_validation(scene, run, name="two_mass_unstable", builtin="linear", cache=CACHE)
    H, P = 1e-3, dict(m1=1.0, m2=2.0, c1=1000.0, c2=500.0, d1=2.0, d2=1.0)
    method = engine_method(make_method("weighted", index=1, a=1.0, b=1.0), H)
    rho, _ = spectral_radius_float64(PhysicalModel(H=H, **P).coefficients(), method, "ff", 2, scheme="jacobi")
    assert float(checked["predicted_rho"]) == pytest.approx(float(rho), rel=1e-9)
    assert float(checked["measured_growth"]) == pytest.approx(float(rho), rel=1e-3)
    assert checked.attrs["predicted_verdict"] == "unstable"
    problem = LinearCosimulation(PhysicalModel(H=H, **P).coefficients(), "ff", 2)
    assert run["coupling"].values[0, 0] == 0.0  # the scene's initial coupling force
    traj = simulate(problem, method, np.array([[0.1, 0.0], [0.1, 0.0]]), np.zeros((3, 1)), 400)
    assert run.attrs["status"] == "diverged"  # the state passes 1e10 (1 + 0.1) before t_end
    n = run.sizes["time"]
    x = np.array(traj.states)[:n, :, 0]
    independent = np.max(np.abs(run["position"].values.T - x)) / np.max(np.abs(x))
    assert float(checked["builtin_difference"]) >= independent * (1 - 1e-12)
    assert float(checked["builtin_difference"]) < 1e-9


@pytest.mark.fmu  # the run builds the test units
def test_order_case_against_the_exact_solution():
    """Projection ff, k = 1 on three step sizes: the built-in errors are those of an independent run against
    the exact solution, the FMU errors agree with them, and the order is about 3."""
    from icosim.engine.methods import engine_method, make_method
    from icosim.engine.run import simulate
    from icosim.problems.linear.exact import MonolithicSolution, consistent_start
    from icosim.problems.linear.model import PhysicalModel
    from icosim.problems.linear.problem import LinearCosimulation
    from icosim.studies.fmi.orders import order_case

    model = dict(m1=1.0, m2=2.0, c1=1000.0, c2=1000.0, d1=10.0, d2=10.0)
    H = [2.5e-3, 1.25e-3, 5.0e-4]
    case = {"method": "projection", "decomposition": "ff", "k": 1}
    ds = order_case(case, H=H, t_end=0.05, model=model, x0=0.1, units_dir=ROOT / "fmus", cache=CACHE)
    for h, err in zip(ds["H"].values, ds["error_builtin"].values):
        c = PhysicalModel(H=h, **model).coefficients()
        problem = LinearCosimulation(c, "ff", 1)
        sol = MonolithicSolution(c, 0.1, 0.0)
        n = int(round(0.05 / h))
        traj = simulate(problem, engine_method(make_method("projection"), h), *consistent_start(problem, sol), n)
        exact = sol.state(np.arange(n + 1.0))[:, 0]
        assert err == pytest.approx(np.max(np.abs(np.array(traj.states)[..., 0] - exact[:, None])), rel=1e-12)
    np.testing.assert_allclose(ds["error_fmu"].values, ds["error_builtin"].values, rtol=1e-6, atol=1e-14)
    assert ds.attrs["order_fmu"] == pytest.approx(3.0, abs=0.25)
    assert ds.attrs["case"] == "projection_ff_k1" and ds.attrs["scheme"] == "jacobi"


# -- the check kinds and the report section ---------------------------------------------------------------------


def scene_ds(name, *, difference, growth, rho, builtin="linear", verdict="stable"):
    ds = xr.Dataset(
        {
            "predicted_rho": ((), rho),
            "measured_growth": ((), growth),
            "growth_deviation": ((), abs(growth / rho - 1)),
            "builtin_difference": ((), difference),
            "builtin_force_difference": ((), np.nan),
            "scheme_rho": (("predicted_for",), [rho, 1.4]),
            "scheme_rho_error": (("predicted_for",), [1e-14, 1e-14]),
            "scheme_verdict": (("predicted_for",), [verdict, "unstable"]),
        },
        coords={"predicted_for": ["jacobi", "gauss-seidel-12"]},
    )
    ds.attrs.update(
        part="fmi", dataset="scene", scene=name, method="projection", decomposition="ff", k=1, scheme="jacobi",
        H=1e-3, t_end=0.5, macro_steps=500, status="completed", builtin=builtin, exact_inputs="yes",
        units="body1: msd (FMI 2.0, inputs by derivatives)", predicted_verdict=verdict, do_step_calls=3000,
    )  # fmt: skip
    return ds


def orders_ds(k, order_fmu, order_builtin, status="asymptotic"):
    ds = xr.Dataset(
        {"error_fmu": (("H",), [1e-6, 1e-8]), "error_builtin": (("H",), [1e-6, 1e-8]), "difference": (("H",), [0, 0])},
        coords={"H": [1e-4, 1e-3]},
    )
    ds.attrs.update(
        part="fmi", dataset="orders", case=f"projection_ff_k{k}", method="projection", decomposition="ff", k=k,
        scheme="jacobi", t_end=0.1, order_fmu=order_fmu, order_builtin=order_builtin, status_fmu=status,
        status_builtin="asymptotic",
    )  # fmt: skip
    return ds


def test_bound_check_passes_fails_and_cannot_decide():
    good, bad = (
        scene_ds("a", difference=1e-13, growth=0.9995, rho=0.9995),
        scene_ds("b", difference=1e-6, growth=1, rho=1),
    )
    kw = dict(quantity="builtin_difference", op="<", value=1e-9)
    assert check_bound([good], select={"builtin": "linear"}, **kw).holds is True
    out = check_bound([good, bad], select={"builtin": "linear"}, **kw)
    assert out.holds is False and "b: 1e-06" in out.measured
    assert check_bound([good], select={"builtin": "pendulum"}, **kw).holds is None


def test_orders_check_compares_with_the_claim_and_the_builtin_model():
    expect = [{"k": 0, "order": 2}, {"k": 1, "order": 3}]
    kw = dict(select={"method": "projection"}, expect=expect, tolerance=0.25, match=0.05)
    assert check_orders([orders_ds(0, 2.07, 2.07), orders_ds(1, 3.07, 3.06)], **kw).holds is True
    assert check_orders([orders_ds(0, 2.07, 2.07), orders_ds(1, 3.07, 2.9)], **kw).holds is False  # built-in differs
    assert check_orders([orders_ds(0, 1.5, 1.5), orders_ds(1, 3.07, 3.07)], **kw).holds is False  # claim differs
    undecided = check_orders([orders_ds(0, 2.0, 2.0, "pre-asymptotic"), orders_ds(1, 3.0, 3.0)], **kw)
    assert undecided.holds is None


def test_the_claims_file_reads_and_evaluates():
    claims = parse_claims(yaml.safe_load((ROOT / "config" / "claims" / "fmi.yaml").read_text())["claims"], CHECKS)
    assert {c.check["kind"] for c in claims} == {"fmi_bound", "fmi_orders"}
    data = [
        scene_ds("two_mass_ff", difference=1e-13, growth=0.9996, rho=0.9995),
        scene_ds("two_mass_unstable", difference=1e-11, growth=1.1312, rho=1.1312, verdict="unstable"),
    ]
    verdicts = {v.claim.id: v.verdict for v in evaluate(claims, data)}
    assert verdicts["fmu_two_mass_follows_builtin_linear"] == "pass"
    assert verdicts["fmu_growth_is_the_predicted_rho"] == "pass"
    assert verdicts["fmu_pendulum_follows_builtin_pendulum"] == "undecided"  # no pendulum scene given


def test_the_report_section_renders():
    validations = [
        scene_ds("two_mass_ff", difference=4e-14, growth=0.9996, rho=0.9995001),
        scene_ds("double_pendulum_ff", difference=4e-14, growth=np.nan, rho=np.nan, builtin="pendulum", verdict="not predicted"),
    ]  # fmt: skip
    claims = [
        {
            "id": "fmu_two_mass_follows_builtin_linear", "source": "docs/fmi.md", "statement": "s", "figures": ["scenes"],
            "verdict": "pass", "reference": "pass", "matches_reference": True, "measured": "m", "note": "",
            "scope": "beyond", "numbers": {"rows": [{"scene": "two_mass_ff", "holds": True}]},
        }
    ]  # fmt: skip
    html = fmi_section(validations=validations, orders=[orders_ds(0, 2.07, 2.07)], claims=claims)
    assert html.startswith('<section id="fmi">')
    for text in ("two_mass_ff", "double_pendulum_ff", "0.9995001 (stable)", "not predicted", "projection_ff_k0"):
        assert text in html
    assert 'id="claim-fmi-fmu_two_mass_follows_builtin_linear"' in html or "fmu_two_mass_follows_builtin_linear" in html
    assert "gauss-seidel-12: 1.4 (unstable)" in html


@pytest.mark.fmu  # the run builds the test units
@pytest.mark.skipif(not hasattr(__import__("os"), "fork"), reason="the supervised run needs os.fork")
def test_scene_job_opens_each_unit_once_and_writes_what_a_run_and_a_check_write(monkeypatch, tmp_path):
    """The workflow's job of a scene opens each unit once (predicted from its start, then run): its run and its
    check are those of :func:`run_scene` and :func:`scene_validation` made apart (each opening the units), the
    run's counters without the prediction's probes."""
    from icosim.problems.fmu import run as fmu_run
    from icosim.problems.fmu.run import run_dataset, run_scene
    from icosim.problems.fmu.scene import load_scene
    from icosim.studies.fmi.validation import scene_job, scene_validation

    monkeypatch.setenv("ICOSIM_FMU_CACHE", str(CACHE))
    scene = load_scene(ROOT / "config" / "scenes" / "two_mass_unstable.yaml")
    opens = tmp_path / "opens"
    opened = fmu_run.open_unit

    def counted(scene, name, kind, **kw):  # the child's openings, one line each
        with opens.open("a") as f:
            f.write(f"{name}\n")
        return opened(scene, name, kind, **kw)

    monkeypatch.setattr(fmu_run, "open_unit", counted)
    paths = tmp_path / "run.nc", tmp_path / "validation.nc"
    scene_job(
        scene, name="two_mass_unstable", builtin="linear", cache=CACHE, run_path=paths[0], validation_path=paths[1]
    )
    assert sorted(opens.read_text().split()) == sorted(scene.names)
    monkeypatch.setattr(fmu_run, "open_unit", opened)
    run = run_dataset(run_scene(scene, cache=CACHE))
    checked = scene_validation(scene, run, name="two_mass_unstable", builtin="linear", cache=CACHE)
    job_run, job_checked = xr.open_dataset(paths[0]), xr.open_dataset(paths[1])
    for name in ("position", "velocity", "coupling"):
        np.testing.assert_array_equal(job_run[name].values, run[name].values)
    for key in ("do_step_calls", "states_saved", "states_restored", "status", "diverged_at"):
        assert job_run.attrs[key] == run.attrs[key], key
    for name in ("predicted_rho", "measured_growth", "builtin_difference"):
        assert float(job_checked[name]) == float(checked[name]), name
    assert job_checked.attrs["identified_json"] == checked.attrs["identified_json"]
