"""The coupling scheme as a dimension of the workflow and the library around it: configuration,
scheduling, the comparison of stable shares, the report's comparison of schemes, and the pendulum's
Gauss-Seidel step.

Dry runs work on a copy of the workflow; nothing here writes to the checkout's results/.
"""

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
import yaml
from helpers import ROOT, copy_workflow, scheduled, scheme_panel_spec, snakemake, validate_config

from icosim import ParameterError, make_method
from icosim.engine.schemes import GS12, GS21
from icosim.problems.pendulum.config import configured_schemes
from icosim.problems.pendulum.model import PendulumParameters
from icosim.problems.pendulum.names import run_name
from icosim.problems.pendulum.problem import PendulumCosimulation
from icosim.problems.pendulum.reference import Monolithic, consistent_history
from icosim.problems.pendulum.runs import run_cosimulation
from icosim.report.schemes import order_rows, pendulum_rows, share_cells, stability_schemes
from icosim.studies.convergence.config import configured_curves
from icosim.studies.convergence.panels import figure_panels as conv_figure_panels
from icosim.studies.stability.comparison import scheme_shares
from icosim.studies.stability.datasets import stability_panel
from icosim.studies.stability.panels import figure_panels

BOTH = ("jacobi", "gauss-seidel-12", "gauss-seidel-21")


def part(name):
    return yaml.safe_load((ROOT / "config" / f"{name}.yaml").read_text())[name]


@pytest.fixture(scope="module")
def workflow_copy(tmp_path_factory):
    return copy_workflow(tmp_path_factory.mktemp("wf"))


# -- configuration ------------------------------------------------------------------------------
def test_jacobi_only_config_switches_off_every_other_scheme():
    only = yaml.safe_load((ROOT / "config" / "jacobi_only.yaml").read_text())
    for name in ("stability", "convergence"):
        for fig, cfg in part(name)["figures"].items():
            if [s if isinstance(s, str) else s["name"] for s in cfg.get("schemes", ["jacobi"])] != ["jacobi"]:
                assert only[name]["figures"][str(fig)]["schemes"] == ["jacobi"], (name, fig)
    assert only["pendulum"]["schemes"] == ["jacobi"]


def test_default_config_computes_figs_9_to_15_and_21_to_23_with_both_orders():
    for name, figs in (("stability", range(9, 16)), ("convergence", range(21, 24))):
        for fig in figs:
            names = {s if isinstance(s, str) else s["name"] for s in part(name)["figures"][str(fig)]["schemes"]}
            assert set(BOTH) <= names
    assert set(configured_schemes(part("pendulum"))) == set(BOTH)


@pytest.mark.parametrize(
    "name, override, message",
    [
        ("stability", {"figures": {"9": {"schemes": ["seidel"]}}}, "seidel"),
        ("stability", {"figures": {"9": {"schemes": [{"name": "gauss-seidel-12"}]}}}, "rows"),
        ("convergence", {"figures": {"21": {"schemes": []}}}, "schemes"),
        ("pendulum", {"schemes": ["gauss-seidel-12"]}, "jacobi"),
    ],
)
def test_bad_schemes_are_refused_by_the_schemas(name, override, message):
    cfg = part(name)
    for key, value in override.items():
        if key == "figures":
            for fig, sub in value.items():
                cfg["figures"][fig].update(sub)
        else:
            cfg[key] = value
    with pytest.raises(Exception, match=message):
        validate_config(cfg, name)


def test_pendulum_schemes_must_include_jacobi():
    with pytest.raises(ParameterError, match="pendulum.schemes must include jacobi"):
        configured_schemes({"schemes": ["gauss-seidel-21"]})
    with pytest.raises(ParameterError, match="pendulum.schemes: scheme must be one of"):
        configured_schemes({"schemes": ["jacobi", "sequential"]})


def test_every_scheme_of_a_figure_has_the_jacobi_layout():
    cfg = part("stability")
    kw = dict(grid=cfg["grid"], zoom_grid=cfg["zoom_grid"], precision=cfg["precision"])
    for fig in ("9", "13"):
        specs = figure_panels(fig, cfg["figures"][fig], **kw)
        strip = lambda s: {**s.as_dict(), "scheme": None}  # noqa: E731
        by_scheme = {scheme: [strip(s) for s in specs if s.scheme == scheme] for scheme in BOTH}
        assert by_scheme["gauss-seidel-21"] == by_scheme["jacobi"] == by_scheme["gauss-seidel-12"]
        assert {s.figure for s in specs} == {fig}
    conv = part("convergence")
    specs = conv_figure_panels("21", conv["figures"]["21"], conv["k"])
    assert {s.figure for s in specs} == {"21"} and {s.scheme for s in specs} == set(BOTH)
    curves = configured_curves(conv)
    assert {c["scheme"] for c in curves if c["figure"] == "22"} == set(BOTH)


def test_a_scheme_for_some_rows_only():
    cfg = part("stability")
    fig = dict(cfg["figures"]["11"], schemes=["jacobi", {"name": "gauss-seidel-12-as-integrated", "rows": [1]}])
    specs = figure_panels("11", fig, grid=cfg["grid"], zoom_grid=cfg["zoom_grid"], precision=cfg["precision"])
    variant = [s for s in specs if s.scheme == "gauss-seidel-12-as-integrated"]
    assert {s.row for s in variant} == {1} and len(variant) == len(fig["k"])
    with pytest.raises(ParameterError, match="rows: \\[5\\]"):
        figure_panels(
            "11",
            dict(fig, schemes=[{"name": "jacobi", "rows": [5]}]),
            grid=cfg["grid"],
            zoom_grid=cfg["zoom_grid"],
            precision=cfg["precision"],
        )


def test_run_names():
    assert run_name("projection", "dd", 1) == "projection_dd_k1"
    assert run_name("projection", "dd", 1, GS12) == "projection_dd_k1_gauss-seidel-12"


# -- scheduling -------------------------------------------------------------------------------------
def test_one_figure_target_schedules_that_figures_job_only(workflow_copy):
    proc = snakemake(workflow_copy, "-n", "results/stability/figures/fig9_gauss-seidel-21.png")
    text = proc.stdout + proc.stderr
    assert "rule stability_panels_fig9:" in text and "rule stability_figure_fig9:" in text
    assert "stability_panels_fig10" not in text and "rule pendulum" not in text and "rule convergence" not in text
    panels = scheduled(proc, "stability_panels_fig9")
    assert len([p for p in panels if "/gauss-seidel-21/" in p]) == 4 * 3 + 1
    assert len([p for p in panels if "/jacobi/" in p]) == 4 * 3 + 1


@pytest.fixture(scope="module")
def full_dry_run(workflow_copy):
    """The default command's dry run on the fresh copy, where nothing is built yet: every job of the workflow
    is listed (as ``--forceall`` would list them); one run for the tests that read the whole listing."""
    return snakemake(workflow_copy, "-n")


def test_default_run_has_every_scheme_and_jacobi_only_none_but_jacobi(workflow_copy, full_dry_run):
    proc = full_dry_run
    text = proc.stdout + proc.stderr
    assert "rule stability_scheme_figure:" in text
    runs = scheduled(proc, "pendulum_run")
    assert len(runs) == len(BOTH) * 21 and {r.split("/")[3] for r in runs} == set(BOTH)
    only = snakemake(workflow_copy, "-n", "--configfile", "config/jacobi_only.yaml")
    text = only.stdout + only.stderr
    assert "gauss-seidel" not in text and "stability_scheme" not in text


def test_one_trade_job_per_method_and_decomposition_writes_both_studies_for_every_scheme(full_dry_run):
    """Error over H and the stability limit of one (method, decomposition) share one job (one start-up),
    which writes each study's dataset of every scheme at its own path."""
    import re

    proc = full_dry_run
    text = proc.stdout + proc.stderr
    jobs = [
        re.search(r"output: ([^\n]+)", block).group(1).split(", ")
        for block in re.split(r"\n(?=\S*rule [\w-]+:)", text)
        if re.match(r"\S*rule pendulum_trade_group:", block)
    ]
    pairs = {(c["method"], c["decomposition"]) for c in part("pendulum")["configurations"]}
    assert len(jobs) == len(pairs)
    expected = {
        f"results/pendulum/trade/{study}/{scheme}/{m}_{d}.nc": (m, d)
        for m, d in pairs
        for study in ("sweep", "limits")
        for scheme in BOTH
    }
    assert sorted(o for outputs in jobs for o in outputs) == sorted(expected)
    assert all(len({expected[o] for o in outputs}) == 1 for outputs in jobs)
    assert "rule pendulum_sweep:" not in text and "rule pendulum_limits:" not in text


# -- the comparison and the report ------------------------------------------------------------------
def _panel(figure, scheme, row, k, n=5):
    return stability_panel(scheme_panel_spec(figure, scheme, row, k, n))


def test_scheme_shares_tabulates_the_panels():
    panels = [_panel("9", s, row, k) for s in BOTH for row in (1, 2) for k in (1, 2)]
    panels += [_panel("16", "jacobi", 1, 1)]  # one scheme only: not compared
    ds = scheme_shares(panels)
    assert list(ds["figure"].values) == ["9"] and list(ds["scheme"].values) == list(BOTH)
    for p in panels[:-1]:
        share = float(ds["stable_share"].sel(figure="9", row=p.attrs["row"], k=p.attrs["k"], scheme=p.attrs["scheme"]))
        assert share == pytest.approx(float(p["stable"].values.mean()))
    cells = share_cells(ds)
    assert len(cells) == 2 and cells[0]["resolution"] == pytest.approx(0.25)
    html = stability_schemes(shares=ds, claims=[], comparison_png=_png(), figure_pngs=[], figures_cfg={})
    assert "Gauss–Seidel 1→2" in html and "Fig. 9 (baumgarte, ff) k = 1" in html


def _png(tmp=[]):  # noqa: B006 - one small PNG per session
    if not tmp:
        import tempfile

        from matplotlib.figure import Figure

        path = Path(tempfile.mkdtemp()) / "x.png"
        Figure(figsize=(1, 1)).savefig(path, dpi=10)
        tmp.append(path)
    return tmp[0]


def test_order_rows_and_pendulum_rows_read_the_data():
    recs = [
        {
            "figure": "23",
            "scheme": scheme,
            "decomposition": "ff",
            "method": "projection",
            "panel": "all",
            "index": 1,
            "k": 0,
            "order": order,
            "unstable": np.array([unstable] * 3),
        }
        for scheme, order, unstable in zip(BOTH, (2.0, 1.0, np.nan), (False, False, True))
    ]
    schemes, rows = order_rows(recs)
    assert schemes == list(BOTH)
    [(label, values)] = rows
    assert label.startswith("Fig. 23: ff, projection") and values == {
        "jacobi": 2.0,
        "gauss-seidel-12": 1.0,
        "gauss-seidel-21": "unstable",
    }
    summary = xr.Dataset(
        {
            "status": ("run", ["stable", "diverged"]),
            "t_diverged": ("run", [np.nan, 0.02]),
            "t_failed": ("run", [np.nan, np.nan]),
            "t_last": ("run", [0.5, 0.019]),
            "err_phi1": ("run", [1e-6, 1.0]),
            "err_phi2": ("run", [2e-6, 1.0]),
            "rho_test_model": ("run", [0.999, 1.85]),
            "reason": ("run", ["none", "|lambda_c| > 1000 N"]),
        },
        coords={
            "method": ("run", ["baumgarte"] * 2),
            "decomposition": ("run", ["ff"] * 2),
            "k": ("run", [1, 1]),
            "scheme": ("run", ["jacobi", "gauss-seidel-12"]),
        },
    )
    schemes, rows = pendulum_rows(summary)
    assert schemes == ["jacobi", "gauss-seidel-12"]
    [(key, by)] = rows
    assert key == ("baumgarte", "ff", 1) and by["gauss-seidel-12"]["t"] == 0.02
    assert by["jacobi"]["err_phi"] == 2e-6


# -- the pendulum's Gauss-Seidel step -----------------------------------------------------------------
P, H = PendulumParameters(), 1e-3


@pytest.mark.parametrize("decomposition", ["ff", "fd", "dd"])
@pytest.mark.parametrize("lead", [0, 1])
def test_pendulum_gauss_seidel_jacobians_match_central_differences(decomposition, lead):
    """The finished link responds algebraically, the other through its corrector: d residuals / d e
    of that map by central differences (separate corrector runs and re-evaluations)."""
    k = 1
    prob = PendulumCosimulation(P, decomposition, k, H)
    state = Monolithic(P).cosim_state(np.array([0.5, -1.2, 1.1, -0.4]))
    hist = consistent_history(P, decomposition, k, H)
    e = prob.extrapolate(hist)
    end, y_lead = prob.predict(lead, state, hist, final=True)
    fixed = [None, None]
    fixed[lead] = end
    jac = prob.jacobians(state, hist, e, None, tuple(fixed))

    def residuals(ee):
        ys = [None, None]
        ys[lead] = prob.reevaluate(lead, end, y_lead, e, ee)
        ys[1 - lead] = prob.correct(1 - lead, state, hist, ee)[1]
        return prob.residuals(prob.stack(ys))

    for j in range(prob.n_coupling):
        h = 1e-2 * max(1.0, abs(e[j]))
        ep, em = e.copy(), e.copy()
        ep[j] += h
        em[j] -= h
        rp, rm = residuals(ep), residuals(em)
        for key in ("acc", "force"):  # the levels every decomposition's projection solves
            central = (rp[key] - rm[key]) / (2 * h)
            scale = np.max(np.abs(jac[key])) if jac[key].size else 1.0
            np.testing.assert_allclose(jac[key][..., j], central, rtol=0, atol=1e-5 * scale, err_msg=key)


@pytest.mark.parametrize("decomposition", ["ff", "fd"])
def test_pendulum_link2_first_leaves_position_level_singular(decomposition):
    """docs/gauss_seidel.md, Sect. 5: with link 2 finished, only link 1 (one degree of freedom) can move
    the joint: the position-level rows are of rank one; with link 1 finished link 2 meets them."""
    prob = PendulumCosimulation(P, decomposition, 1, H)
    state = Monolithic(P).cosim_state(np.array([0.5, -1.2, 1.1, -0.4]))
    hist = consistent_history(P, decomposition, 1, H)
    e = prob.extrapolate(hist)

    def scaled_condition(lead, level):
        fixed = [None, None]
        fixed[lead] = prob.predict(lead, state, hist, final=True)[0]
        jac = prob.jacobians(state, hist, e, None, tuple(fixed))
        A = np.concatenate([jac[level], jac["force"]])
        return np.linalg.cond(A / np.max(np.abs(A), axis=1, keepdims=True))

    assert scaled_condition(1, "pos") > 1e5 and scaled_condition(1, "vel") > 1e5  # link 2 first
    assert scaled_condition(0, "pos") < 1e2 and scaled_condition(1, "acc") < 1e2


def test_pendulum_gauss_seidel_runs_count_three_integrations_and_detect_divergence():
    stable = run_cosimulation(P, make_method("projection"), "ff", 1, H=H, t_end=0.02, scheme=GS12)
    assert stable.status == "stable" and stable.stats["integrations"] == 3 * stable.stats["macro_steps"]
    assert np.max(np.abs(np.hypot(stable.series["g_cax"], stable.series["g_cay"]))) < 1e-9  # projected
    singular = run_cosimulation(P, make_method("weighted", a=1, b=1), "ff", 0, H=H, t_end=0.02, scheme=GS21)
    assert singular.status == "diverged" and singular.t_diverged <= 2 * H and "lambda_c" in singular.reason
