"""The signal study's functions (icosim.studies.signals.config, .study) against independent computations: the
configured cases and their refusals, the growth measure on a mode of known growth, and -- on OMSimulator's units
-- a case's errors against a run built from the units without the study (test_signals_outside's route), its
predicted rho against the recurrence of the Modelica equations formed here by hand, its measured growth
against that rho.  The workflow's side: tests/workflow/test_signals_workflow.py."""

import numpy as np
import pytest
import yaml
from helpers import ROOT
from scipy.linalg import expm
from toolchains import OUTSIDE

from icosim.problems.fmu.errors import SceneError
from icosim.studies.signals.config import check_cases, study_cases
from icosim.studies.signals.study import case_data, measured_growth


def config():
    return yaml.safe_load((ROOT / "config" / "signals.yaml").read_text())["signals"]


def test_the_configured_cases_are_every_k_of_each_setting():
    cases = check_cases(config())  # the stand-in units: no unit is needed to check the scenes
    assert sorted(cases) == sorted(
        [f"connections_jacobi_k{k}" for k in (0, 1, 2)]
        + [f"connections_gauss-seidel-12_k{k}" for k in (0, 1)]
        + [f"connections_jacobi_k{k}_implicit" for k in (0, 1)]
        + [f"joint_baumgarte_fd_k{k}" for k in (0, 1, 2)]
    )
    assert cases["joint_baumgarte_fd_k2"]["params"] == {"index": 1, "mu": 1e-3}
    assert cases["connections_jacobi_k0"]["H"] == sorted(cases["connections_jacobi_k0"]["H"])


@pytest.mark.parametrize(
    "change, match",
    [
        ({"H": [3e-3, 1e-3]}, "does not divide t_end"),
        ({"by": "joint", "method": "baumgarte", "growth_H": [0.2]}, "growth_H, order and implicit belong"),
        ({"scheme": "gauss-seidel"}, r"connections_gauss-seidel-_k0: coupling.order: gauss-seidel needs every"),
        ({"scheme": "sideways"}, r"connections_sideways_k0: coupling.scheme: 'sideways' is not allowed"),
    ],
)
def test_a_bad_case_is_refused_naming_it(change, match):
    cfg = config()
    cfg["cases"] = [{"by": "connections", "k": [0], "H": [5e-3, 2.5e-3]} | change]
    with pytest.raises(SceneError, match=match):
        check_cases(cfg)


def test_a_case_configured_twice_is_refused():
    cfg = config()
    cfg["cases"] = [cfg["cases"][0], cfg["cases"][0]]
    with pytest.raises(SceneError, match="connections_jacobi_k0 is configured twice"):
        study_cases(cfg)


@pytest.mark.parametrize("r, theta", [(1.05, 2.6), (1.2, 0.9), (0.97, 1.7)])
def test_the_growth_of_a_mode_is_its_modulus(r, theta):
    """``x_N = r^N cos(N theta)``: within 5 % of ``|r - 1|`` (the claim's tolerance) over 300 steps."""
    n = np.arange(301)
    assert abs(measured_growth(r**n * np.cos(theta * n)) - r) < 0.05 * abs(r - 1)


def test_a_run_too_short_or_not_finite_has_no_growth():
    assert np.isnan(measured_growth(np.ones(8)))
    assert np.isnan(measured_growth([1.0] * 100 + [np.inf]))


# -- on OMSimulator's units ---------------------------------------------------------------------------------------


def small(case, **cfg):
    base = config() | {"units_dir": str(OUTSIDE / "omsimulator"), "t_end": 0.1, "growth_steps": 300} | cfg
    return base, case


# OMSimulator's four connections (source, output, target, input) and the units' Modelica equations in physical
# coordinates: System1 (x1, v1), input F, outputs x1, v1, a1; System2 (x2, v2), inputs x1, v1, a1, output
# F = k2 (x2 - x1) + c2 (v2 - v1), m2 a2 = -k3 x2 - c3 v2 - F (DualMassOscillator.mo)
CONNECTIONS = [("system2", "F", "system1", "F")] + [("system1", v, "system2", v) for v in ("x1", "v1", "a1")]
M1, K1, C1, M2, K2, C2, K3, C3 = 1.0, 10.0, 0.2, 1.0, 10.0, 0.5, 20.0, 0.3
MODELICA = {
    "system1": ([[0, 1], [-K1 / M1, -C1 / M1]], [[0], [1 / M1]], [[1, 0], [0, 1], [-K1 / M1, -C1 / M1]],
                [[0], [0], [1 / M1]]),
    "system2": ([[0, 1], [-(K2 + K3) / M2, -(C2 + C3) / M2]], [[0, 0, 0], [K2 / M2, C2 / M2, 0]], [[K2, C2]],
                [[-K2, -C2, 0]]),
}  # fmt: skip


def exact_jacobi_radius(H):
    """rho of explicit Jacobi with held inputs on the Modelica equations integrated exactly over H, in the block
    form of the recurrence on ``(x_1, x_2, e)``: ``x_i' = Phi_i x_i + Gamma_i E_i e``, ``e' = S y'`` with
    ``y_i' = C_i x_i' + D_i E_i e``; ``Phi = e^{AH}``, ``Gamma = int_0^H e^{As} ds B`` by Van Loan's block
    exponential."""
    names = ["system1", "system2"]
    inputs = {n: [u for a, y, b, u in CONNECTIONS if b == n] for n in names}
    outputs = {"system1": ["x1", "v1", "a1"], "system2": ["F"]}
    cols = [f"{b}.{u}" for a, y, b, u in CONNECTIONS]
    rows = [f"{a}.{y}" for a, y, b, u in CONNECTIONS]
    ys = [f"{n}.{y}" for n in names for y in outputs[n]]
    S = np.array([[1.0 if r == y else 0.0 for y in ys] for r in rows])
    blocks = []
    for n in names:
        A, B, C, D = (np.asarray(m, dtype=float) for m in MODELICA[n])
        E = np.array([[1.0 if c == f"{n}.{u}" else 0.0 for c in cols] for u in inputs[n]])
        nx, nu = B.shape
        big = expm(np.block([[A, B], [np.zeros((nu, nx + nu))]]) * H)
        blocks.append((big[:nx, :nx], big[:nx, nx:] @ E, C, D @ E))
    Phi = np.block([[blocks[0][0], np.zeros((2, 2))], [np.zeros((2, 2)), blocks[1][0]]])
    G = np.vstack([blocks[0][1], blocks[1][1]])
    C = np.block([[blocks[0][2], np.zeros((3, 2))], [np.zeros((1, 2)), blocks[1][2]]])
    D = np.vstack([blocks[0][3], blocks[1][3]])
    M = np.block([[Phi, G], [S @ C @ Phi, S @ (C @ G + D)]])
    return float(np.max(np.abs(np.linalg.eigvals(M))))


def direct_error(k, H, t_end):
    """The units opened and coupled without the study or a scene (icosim's problem and run loop), from the exact
    coupling history: the largest displacement error of either mass at t_end (m)."""
    from icosim.engine.run import simulate
    from icosim.problems.fmu.dual_mass import DualMass
    from icosim.problems.fmu.exchange import open_fmu_unit
    from icosim.problems.fmu.signals import SignalCosimulation, connections_of

    dmo = DualMass()
    names = ["system1", "system2"]
    cons, inputs, outputs = connections_of([(*c, 1.0, 0.0) for c in CONNECTIONS], names)
    starts = {"system1": {"x1_start": 0.0}, "system2": {"x2_start": 0.5}}
    units = [open_fmu_unit(n, OUTSIDE / "omsimulator" / f"DualMassOscillator.System{i + 1}.fmu",
                           {"signal_input": inputs[i], "signal_output": outputs[i]}, starts[n],
                           interface="model-exchange", tolerance=1e-12) for i, n in enumerate(names)]  # fmt: skip
    try:
        problem = SignalCosimulation(units, inputs, outputs, cons, k, H)
        rows = [[dmo.outputs(-j * H)[f"{a}.{y}"] for a, y, _, _ in CONNECTIONS] for j in range(k + 1)]
        history = problem.initial_history(np.array(rows))
        simulate(problem, None, problem.initial_state(), history, round(t_end / H), record=False)
        x = [units[0].get(("signal_output",)).ravel()[0], units[1].get_named("mass2.s")]
    finally:
        for unit in units:
            unit.close()
    return float(np.max(np.abs(np.array(x) - dmo.exact([t_end])[0, :2])))


@pytest.mark.outside
def test_a_case_by_connections_is_the_run_of_its_units():
    cfg, case = small({"by": "connections", "k": 0, "scheme": "jacobi", "H": [1e-2, 5e-3, 2.5e-3], "growth_H": [0.2]})
    ds = case_data(cfg, case).to_xarray()
    for h, e in zip(ds["H"].values, ds["error_end"].values):
        # the study's error is relative to the amplitude (x2_start = 0.5)
        assert e * 0.5 == pytest.approx(direct_error(0, float(h), 0.1), rel=1e-6)
    assert ds["error"].values[0] >= ds["error_end"].values[0]
    assert ds.attrs["order_status"] == "asymptotic" and abs(ds.attrs["order"] - 1) < 0.1
    rho = float(ds["growth_rho"].values[0])
    assert rho == pytest.approx(exact_jacobi_radius(0.2), rel=1e-7)
    assert str(ds["growth_verdict"].values[0]) == "unstable"
    assert abs(float(ds["measured_growth"].values[0]) - rho) < 0.05 * (rho - 1)
    for h, r in zip(ds["H"].values, ds["predicted_rho"].values):
        assert r == pytest.approx(exact_jacobi_radius(float(h)), rel=1e-7)


@pytest.mark.outside
def test_a_case_by_a_joint_converges_and_has_no_prediction():
    cfg, case = small({"by": "joint", "k": 0, "method": "baumgarte", "params": {"index": 1, "mu": 1e-3},
                       "H": [2e-3, 1e-3, 5e-4]}, t_end=0.05)  # fmt: skip
    ds = case_data(cfg, case).to_xarray()
    assert ds.attrs["order_status"] == "asymptotic" and abs(ds.attrs["order"] - 1) < 0.1, ds["error"].values
    assert set(ds["predicted_verdict"].values.tolist()) == {"undecided"}
    assert "not predicted" in ds.attrs["prediction_reason"] and "growth_H" not in ds.coords


def test_a_missing_unit_is_named_before_any_run(tmp_path):
    cfg, case = small({"by": "connections", "k": 0, "scheme": "jacobi", "H": [1e-2, 5e-3]})
    with pytest.raises(SceneError, match=r"signals.units.system1: no unit .*DualMassOscillator.System1.fmu"):
        case_data(cfg | {"units_dir": str(tmp_path)}, case)
