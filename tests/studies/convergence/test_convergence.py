"""Unit tests of icosim.studies.convergence: Eq. (72), the asymptotic order, stepping, unstable detection."""

import numpy as np
import pytest
import xarray as xr
import yaml
from helpers import ROOT, validate_config

import icosim
import icosim.problems.linear.spectral
import icosim.studies.convergence.experiment
import icosim.studies.convergence.study
import icosim.studies.convergence.work_precision
from icosim.claims.registry import load_claims, parse_claims
from icosim.errors import ParameterError
from icosim.order_fit import asymptotic_order, local_slopes
from icosim.studies.convergence.config import check_claims_against_config, study_from_config
from icosim.studies.convergence.curves import fastest_configurations
from icosim.studies.convergence.datasets import run_panel
from icosim.studies.convergence.experiment import (
    Setup,
    dimensional_method,
    method_attrs,
    oscillation_summary,
    step_counts,
)
from icosim.studies.convergence.metric import nrmse
from icosim.studies.convergence.panels import PanelSpec, figure_layout, figure_panels, figure_schemes
from icosim.studies.convergence.study import Study, iterate_linear_map
from icosim.studies.convergence.work_precision import resolve_configuration, step_cost, time_macro_steps


# ------------------------------------------------------------------ Eq. (72)
def _signals(n=400):
    t = np.linspace(0.01, 1, n)
    return np.stack(
        [np.exp(-t) * np.cos(9 * t), np.exp(-t) * np.cos(9 * t) + 0.1, np.sin(7 * t), np.cos(5 * t) * t], -1
    )


def test_nrmse_constant_offset_matches_variance_formula():
    ref = _signals()
    delta = np.array([1e-3, -2e-3, 5e-4, 0.0])
    # independent: mean squared offset over the population variance (numpy.var), summed, root
    expected = np.sqrt(np.sum(delta**2 / np.var(ref, axis=0)))
    assert nrmse(ref, ref + delta) == pytest.approx(expected, rel=1e-12)


def test_nrmse_relative_scaling_and_zero():
    ref = _signals()
    eps = 1e-4
    expected = eps * np.sqrt(np.sum(np.mean(ref**2, 0) / np.var(ref, 0)))
    assert nrmse(ref, ref * (1 + eps)) == pytest.approx(expected, rel=1e-9)
    assert nrmse(ref, ref) == 0.0


def test_nrmse_bad_input():
    ref = _signals()
    assert np.isnan(nrmse(ref, np.full_like(ref, np.inf)))
    with pytest.raises(ValueError, match="same shape"):
        nrmse(ref, ref[:-1])
    with pytest.raises(ValueError, match="constant"):
        nrmse(np.ones((10, 4)), np.ones((10, 4)))


def test_partial_nrmse_of_a_run_match_an_independent_computation():
    """nrmse_x, nrmse_v, nrmse_lambda of a panel against Eq. (72) recomputed here from the engine's
    time stepper (simulate, not the matrix path) and numpy's population variance."""
    setup = Setup(end_time=0.2)
    study = Study(setup, [100, 200])
    r = study.run("baumgarte", {"index": 1, "mu": 5e-3}, "fd", 1)
    for i, (H, N) in enumerate(zip(study.H, study.n_steps)):
        m = dimensional_method("baumgarte", H, index=1, mu=5e-3)
        c = setup.model(H).coefficients()
        prob = icosim.LinearCosimulation(c, "fd", 1)
        sol = icosim.problems.linear.exact.MonolithicSolution(c, setup.x0, setup.v0 * H)
        traj = icosim.engine.run.simulate(prob, m, *icosim.problems.linear.exact.consistent_start(prob, sol), int(N))
        states = np.array(traj.states[1:])  # (N, subsystem, (x, v_bar))
        lam = np.array(traj.coupling[1:])[:, 0]  # lambda_c is the first fd coupling variable
        exact = sol.state(np.arange(1, N + 1, dtype=float))

        def ratio(ref, num):
            return np.sum((ref - num) ** 2) / (ref.size * np.var(ref))

        rx = ratio(exact[:, 0], states[:, 0, 0]) + ratio(exact[:, 0], states[:, 1, 0])
        rv = ratio(exact[:, 1] / H, states[:, 0, 1] / H) + ratio(exact[:, 1] / H, states[:, 1, 1] / H)
        assert r.nrmse_x[i] == pytest.approx(np.sqrt(rx), rel=1e-6)
        assert r.nrmse_v[i] == pytest.approx(np.sqrt(rv), rel=1e-6)
        assert r.nrmse[i] == pytest.approx(np.sqrt(rx + rv), rel=1e-6)  # the main reading of Eq. (72)
        # lambda_bar = lambda H^2 / m1 on both sides: the ratio is scale-free
        assert r.nrmse_lambda[i] == pytest.approx(np.sqrt(ratio(exact[:, 3], lam)), rel=1e-6)
    # the other reading (two roots added) lies within [1, sqrt 2] times the main one
    assert np.all(r.nrmse <= r.nrmse_x + r.nrmse_v) and np.all(r.nrmse_x + r.nrmse_v <= np.sqrt(2) * r.nrmse)
    # dd has no multiplier among its coupling variables
    assert np.isnan(study.run("projection", {}, "dd", 0).nrmse_lambda).all()


# ------------------------------------------------------------------ setup, reference, methods
def test_the_reference_in_pieces_is_the_exact_solution_at_once(monkeypatch):
    """Study.reference evaluates the exact solution a piece of times at a time (here pieces of 7, the last
    one short): bit for bit the exact solution at every T_N at once."""
    monkeypatch.setattr(icosim.studies.convergence.study, "REFERENCE_CHUNK", 7)
    setup = Setup(end_time=0.2)
    study = Study(setup, [100, 40])
    for i, (H, N) in enumerate(zip(study.H, study.n_steps)):
        st = study.solution(H).state(np.arange(1, N + 1, dtype=float))
        x, v = st[:, 0], st[:, 1] / H
        assert np.array_equal(study.reference(i), np.stack([x, x, v, v], axis=-1))
        assert np.array_equal(study.reference_multiplier(i), st[:, 3])


def test_step_counts_end_exactly_at_end_time():
    n = step_counts(1.0, 1e-5, 1e-2, 16)
    assert n[0] == 100 and n[-1] == 100000 and len(n) == 16
    with pytest.raises(ParameterError, match="H_min"):
        step_counts(1.0, 1e-2, 1e-5, 16)


def test_reference_matches_closed_form():
    s = Setup()
    study = Study(s, [50, 200])
    M, C, D = s.m1 + s.m2, s.c1 + s.c2, s.d1 + s.d2
    delta, omega = D / (2 * M), np.sqrt(C / M - (D / (2 * M)) ** 2)
    for i, H in enumerate(study.H):
        t = H * np.arange(1, study.n_steps[i] + 1)
        x = np.exp(-delta * t) * (s.x0 * np.cos(omega * t) + (s.v0 + delta * s.x0) / omega * np.sin(omega * t))
        v = np.gradient(x, t)  # checked loosely; exact velocity below
        v_exact = (
            np.exp(-delta * t) * (-s.x0 * omega * np.sin(omega * t) + (s.v0 + delta * s.x0) * np.cos(omega * t))
            - delta * x
        )
        ref = study.reference(i)
        np.testing.assert_allclose(ref[:, 0], x, atol=1e-14)
        np.testing.assert_allclose(ref[:, 1], x, atol=1e-14)
        np.testing.assert_allclose(ref[:, 2], v_exact, atol=1e-12)
        assert np.max(np.abs(v[5:-5] - v_exact[5:-5])) < 0.05 * np.max(np.abs(v_exact))


def test_dimensional_baumgarte_parameters():
    m = dimensional_method("baumgarte", 1e-3, index=1, mu=5e-3)
    assert m.params["beta"] == pytest.approx(10.0) and m.params["gamma"] == pytest.approx(25.0)
    attrs = method_attrs("baumgarte", index=1, mu=5e-3)
    assert attrs["beta"] == pytest.approx(1e-2) and attrs["gamma"] == pytest.approx(2.5e-5)
    assert dimensional_method("weighted", 1e-3, a=1.0, b=1.0).params == {"a": 1.0, "b": 1.0, "index": 1}


# ------------------------------------------------------------------ stepping
@pytest.mark.parametrize(
    "method,params,dec,k",
    [
        ("baumgarte", {"index": 1, "mu": 5e-3}, "ff", 1),
        ("weighted", {"index": 1, "a": 1.0, "b": 1.0}, "fd", 1),
        ("projection", {}, "dd", 2),
        ("projection", {}, "ff", 0),
    ],
)
def test_steppings_agree(method, params, dec, k):
    """The amplification-matrix path is the same macro-step algorithm as simulate (by linearity), and the
    floor-free error recurrence gives the same errors where float64 state stepping has no floor yet."""
    study = Study(Setup(end_time=0.3), [300, 600])  # 600 > one block of powers
    for i, H in enumerate(study.H):
        m = dimensional_method(method, H, **params)
        fast, d1, _, _ = study._errors(m, dec, k, i, "matrix")
        slow, d2, _, _ = study._errors(m, dec, k, i, "simulate")
        floor_free, d3, bits, cert = study._errors(m, dec, k, i, "error")
        assert d1 is None and d2 is None and d3 is None and bits >= 128 and cert.verdict == "stable"
        # round-off only: ~eps per step amplified by the conditioning of the corrections
        # (an algorithmic difference would show at the size of the error, >= 1e-9 here)
        fast, slow = fast.array(), slow.array()
        floor_free = floor_free.array()[:, : fast.shape[1]]  # its further columns: the history of e
        np.testing.assert_allclose(fast, slow, rtol=0, atol=1e-10 * Setup().x0)
        np.testing.assert_allclose(floor_free, fast, rtol=0, atol=1e-10 * Setup().x0)
    a = study.run(method, params, dec, k, stepping="matrix")
    b = study.run(method, params, dec, k, stepping="simulate")
    c = study.run(method, params, dec, k)
    np.testing.assert_allclose(a.nrmse, b.nrmse, rtol=1e-6)
    np.testing.assert_allclose(c.nrmse, a.nrmse, rtol=1e-6)


def test_iterate_linear_map_powers_and_bound():
    rng = np.random.default_rng(1)
    M = rng.standard_normal((5, 5))
    M *= 0.9 / np.max(np.abs(np.linalg.eigvals(M)))
    w0 = rng.standard_normal(5)
    W, d = iterate_linear_map(M, w0, 700, block=64)
    assert d is None and W.shape == (701, 5)
    w = w0.copy()
    for _ in range(700):
        w = M @ w
    np.testing.assert_allclose(W[-1], w, atol=1e-12)
    # doubling: |w_n| = 2^n exceeds 100 first at n = 7
    W, d = iterate_linear_map(2 * np.eye(5), np.ones(5), 50, bound=100.0, block=4)
    assert d == 7 and W.shape == (7, 5)


# ------------------------------------------------------------------ unstable detection
def test_diverging_run_is_unstable_and_has_no_error():
    study = Study(Setup(), [100, 200, 400])
    r = study.run("baumgarte", {"index": 3}, "ff", 1)
    assert r.unstable.all()
    assert np.isnan(r.nrmse).all()
    assert (r.spectral_radius > 1).all()


def test_slowly_growing_run_flagged_by_spectral_radius():
    """Index 2, k = 1, mu = 5e-3 at small H grows too slowly to leave the bound within 1 s:
    its finished error looks small, but the spectral radius exceeds 1 -- unstable, NaN."""
    study = Study(Setup(), [50000, 100000])
    r = study.run("baumgarte", {"index": 2, "mu": 5e-3}, "ff", 1)
    assert (r.diverged_at == -1).all()
    assert np.isfinite(r.nrmse_unfiltered).all() and (r.nrmse_unfiltered < 1e-2).all()
    assert (r.spectral_radius > 1).all() and r.unstable.all() and np.isnan(r.nrmse).all()


# ------------------------------------------------------------------ asymptotic order
def test_local_slopes_of_a_power_law_and_of_an_unstable_gap():
    H = np.geomspace(1e-5, 1e-2, 7)
    err = 3.0 * H**2.5
    err[2] = np.nan  # an unstable run: no slope on either side of it
    H_mid, slope = local_slopes(H[::-1], err[::-1])  # any order in, increasing H out
    np.testing.assert_allclose(H_mid, np.sqrt(H[:-1] * H[1:]), rtol=1e-12)
    np.testing.assert_allclose(slope[[0, 3, 4, 5]], 2.5, rtol=1e-12)
    assert np.isnan(slope[[1, 2]]).all()


def test_order_is_read_off_the_smallest_decade_only():
    """A power law is asymptotic; the order is its exponent whatever happens at larger H."""
    H = np.geomspace(1e-6, 1e-2, 21)
    err = H**3 + np.where(H > 1e-4, 1e2 * H**4, 0.0)  # a different slope above 1e-4 does not matter
    f = asymptotic_order(H, err)
    assert f.status == "asymptotic" and f.order == pytest.approx(3.0, abs=1e-9)
    assert f.H_min == pytest.approx(1e-6) and f.H_max == pytest.approx(1e-5) and f.n_points == 6
    assert f.used.sum() == 6 and f.used[H <= 1e-5 * (1 + 1e-9)].all()


def test_a_curve_still_turning_is_pre_asymptotic():
    """H^2 + c H: the local slope moves from 1 toward 2 across the decade -- not yet an order."""
    H = np.geomspace(1e-6, 1e-2, 21)
    turning = asymptotic_order(H, H**2 + 3e-6 * H)
    assert turning.status == "pre-asymptotic" and not turning.decided
    assert "differ from their fit" in turning.reason and turning.spread > 0.1
    settled = asymptotic_order(H, H**2 + 1e-9 * H)  # the H term is negligible above 1e-6 only by 1e-3
    assert settled.status == "asymptotic" and settled.order == pytest.approx(2.0, abs=0.01)


def test_instability_leaves_no_asymptotic_order():
    H = np.geomspace(1e-6, 1e-2, 9)
    err = H**2
    small_unstable = H < 5e-6
    f = asymptotic_order(H, np.where(small_unstable, np.nan, err), small_unstable)
    assert f.status == "unstable as H -> 0" and np.isnan(f.order) and "stable only from H" in f.reason
    g = asymptotic_order(H, np.full(H.shape, np.nan), np.ones(H.shape, bool))
    assert g.status == "unstable at every H"
    few = asymptotic_order(H[:3], err[:3], min_points=4)
    assert few.status == "too few points"


# ------------------------------------------------------------------ panels, datasets, work-precision
def _config():
    return yaml.safe_load((ROOT / "config" / "convergence.yaml").read_text())["convergence"]


def test_panels_share_the_index3_row():
    cfg = _config()
    specs = figure_panels("21", cfg["figures"]["21"], cfg["k"])
    schemes = figure_schemes(cfg["figures"]["21"])
    assert {s.scheme for s in specs} == set(schemes)
    for scheme in schemes:  # the same panels for every scheme (a dimension of the figure, like k)
        ff = [s for s in specs if s.decomposition == "ff" and s.scheme == scheme]
        assert [s.panel for s in ff] == ["mu0.00025", "mu0.001", "mu0.005", "index3"]
        assert ff[-1].shared and ff[-1].rows == ({"index": 3},)
    layout = figure_layout("21", cfg["figures"]["21"], "ff", cfg["k"])
    assert layout[1] == [("mu0.001", 1), ("mu0.001", 2), ("index3", 3)]
    assert PanelSpec.from_dict(ff[0].as_dict()) == ff[0]


def test_bad_parameters_name_the_figure():
    with pytest.raises(ParameterError, match="figure 9.*mu"):
        figure_panels(
            "9", {"method": "weighted", "columns": [{"mu": 1.0}], "rows": [{"index": 1}], "decompositions": ["ff"]}, [0]
        )
    with pytest.raises(ParameterError, match="decomposition 'dd'"):
        figure_panels(
            "9",
            {"method": "baumgarte", "columns": [{"mu": 1e-3}], "rows": [{"index": 1}], "decompositions": ["dd"]},
            [0],
        )
    with pytest.raises(ParameterError, match="exactly one column"):
        resolve_configuration({"figure": "21", "mu": 7.0, "index": 1}, _config()["figures"], [0])


def test_schema_rejects_unknown_key():
    from snakemake.exceptions import WorkflowError

    cfg = _config()
    cfg["step_sizes"]["H_mni"] = 1e-5
    with pytest.raises(WorkflowError, match="H_mni"):
        validate_config(cfg, "convergence")


def test_panel_dataset_and_work_precision():
    spec = PanelSpec("23", "ff", "all", "projection", {}, ({},), (0, 1))
    study = Study(Setup(end_time=0.2), step_counts(0.2, 2e-4, 2e-2, 5))
    ds = run_panel(spec, study, {"min_points": 2, "decades": 1.0, "tolerance": 0.1})
    assert ds["nrmse"].dims == ("index", "k", "H") and ds["H"].attrs["units"] == "s"
    assert ds.attrs["figure"] == "23" and ds.attrs["method"] == "projection" and ds.attrs["decomposition"] == "ff"
    assert np.all(np.diff(ds["order"].values[0]) > 0.5)  # k = 1 converges faster than k = 0
    entries = resolve_configuration(
        {"figure": "23"},
        {"23": {"method": "projection", "columns": [{}], "rows": [{}], "decompositions": ["ff"]}},
        [0, 1],
    )
    wp = icosim.studies.convergence.work_precision.work_precision(
        entries, {(spec.scheme, "ff", "23", "all"): ds}, study.setup, steps=2, repeats=1, warmup_steps=1
    )
    cost = wp["cpu_seconds_per_simulated_second"].values
    assert np.all(cost[np.isfinite(wp["nrmse"].values)] > 0)
    ranking = fastest_configurations(wp, [1.0])[0]["ranking"]
    assert [r[0] for r in ranking] and all(a[1] <= b[1] for a, b in zip(ranking, ranking[1:]))
    assert wp["subsystem_integrations_per_step"].values.tolist() == [4, 4]
    assert wp["coupling_solves_per_step"].values.tolist() == [1, 1]
    assert "Python overhead" in wp.attrs["cost_caveat"]
    assert "mu and beta in s" in ds.attrs["method_parameters_units"]


def test_time_macro_steps_times_the_documented_runs(monkeypatch):
    """The timing runs what it says: one warm-up of `warmup_steps`, then `repeats` runs of `steps`
    macro steps of the engine's simulate, each from the exact consistent start."""
    import icosim.studies.convergence.work_precision as conv

    calls = []
    real = conv.simulate

    def recording(problem, method, state, history, n_steps, **kw):
        calls.append((n_steps, problem.decomposition.name, problem.k, method.params.get("beta")))
        np.testing.assert_allclose(state[:, 0], Setup().x0)  # exact start, both subsystems
        return real(problem, method, state, history, n_steps, **kw)

    monkeypatch.setattr(conv, "simulate", recording)
    time_macro_steps(Setup(), 1e-3, "baumgarte", {"index": 1, "mu": 5e-3}, "fd", 1, steps=3, repeats=2, warmup_steps=4)
    # beta is handed on dimensionless: 2 mu / H = 10
    assert calls == [(4, "fd", 1, pytest.approx(10.0))] + [(3, "fd", 1, pytest.approx(10.0))] * 2
    with pytest.raises(ParameterError, match="steps"):
        time_macro_steps(Setup(), 1e-3, "projection", {}, "ff", 0, steps=0)


@pytest.mark.parametrize(
    "method,params,solves,projections",
    [
        ("baumgarte", {"index": 1, "mu": 1e-3}, 1, 0),  # one solve, levels (1, beta, gamma)
        ("baumgarte", {"index": 3}, 1, 0),
        ("weighted", {"index": 1, "a": 1.0, "b": 1.0}, 3, 0),  # position, velocity, acceleration level
        ("weighted", {"index": 2, "a": 1.0}, 2, 0),  # b = 0: the acceleration solve drops out
        ("projection", {}, 1, 1),  # acceleration level, then the projection
    ],
)
@pytest.mark.parametrize("dec", ["ff", "fd"])
def test_step_cost_counts_the_work_of_one_macro_step(method, params, solves, projections, dec):
    """Counted on the engine's macro step: predictor + corrector of each subsystem = 4 integrations;
    the coupling solves are those of the method's definition (Sect. 2) with a nonzero weight."""
    cost = step_cost(method, params, dec, 1)
    assert cost == {"subsystem_integrations": 4, "coupling_solves": solves, "projections": projections}


def test_figures_from_the_drawn_variables_are_those_from_the_whole_dataset(tmp_path):
    """The figure job reads only DRAWN_VARIABLES (open_variables, no xarray): the same pixels as the
    figures drawn from the whole dataset (open_dataset), for a panel of two rows."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from icosim.figures.convergence import DRAWN_VARIABLES, convergence_figure, slope_figure
    from icosim.io.netcdf import open_dataset, open_variables, write_netcdf

    rows = ({"index": 1, "mu": 5e-3}, {"index": 2, "mu": 5e-3})
    spec = PanelSpec("21", "ff", "p", "baumgarte", {"mu": 5e-3}, rows, (0, 1))
    study = Study(Setup(end_time=0.2), step_counts(0.2, 2e-4, 2e-2, 5))
    write_netcdf(run_panel(spec, study, {"min_points": 2, "decades": 1.0, "tolerance": 0.1}), tmp_path / "p.nc")
    layout = [[("p", 2), ("p", 1)]]
    kw = {"columns": [{"mu": 5e-3}], "rows": ["index 2", "index 1"]}

    def pixels(ds, draw):
        canvas = FigureCanvasAgg(draw({"p": ds}, layout, **kw))
        canvas.draw()
        return np.asarray(canvas.buffer_rgba())

    drawn, whole = open_variables(tmp_path / "p.nc", DRAWN_VARIABLES), open_dataset(tmp_path / "p.nc")
    assert set(drawn) == set(DRAWN_VARIABLES)
    for draw in (convergence_figure, slope_figure):
        assert np.array_equal(pixels(drawn, draw), pixels(whole, draw))
    # each cell draws its own row: index 2 on top, as xarray selects it
    top = convergence_figure({"p": drawn}, layout, **kw).axes[0].get_lines()[0]
    assert np.array_equal(top.get_ydata(), whole.sel(index=2)["nrmse"].values[0], equal_nan=True)
    assert not np.array_equal(top.get_ydata(), whole.sel(index=1)["nrmse"].values[0], equal_nan=True)


def test_figure_never_draws_unstable_as_error():
    from icosim.figures.convergence import convergence_figure

    H = np.array([1e-3, 2e-3, 4e-3, 8e-3])
    err = np.array([[[1e-6, 4e-6, np.nan, np.nan]]])
    unstable = np.array([[[False, False, True, True]]])
    ds = xr.Dataset(
        {
            "nrmse": (("index", "k", "H"), err),
            "unstable": (("index", "k", "H"), unstable),
            "fit_used": (("index", "k", "H"), np.zeros_like(unstable)),
            "order": (("index", "k"), [[np.nan]]),
            "order_status": (("index", "k"), [["unstable as H -> 0"]]),
        },
        coords={"H": H, "index": [1], "k": [0]},
    )
    fig = convergence_figure({"p": ds}, [[("p", 1)]], columns=[{}], rows=["index 1"], guide_orders=[2])
    ax = fig.axes[0]
    xs = [line for line in ax.get_lines() if line.get_marker() == "x"]
    assert len(xs) == 1 and list(xs[0].get_xdata()) == [4e-3, 8e-3]
    assert xs[0].get_transform() == ax.get_xaxis_transform()  # axes height, not an error value
    data_lines = [
        line for line in ax.get_lines() if line.get_marker() in ("o", "None", "") and line.get_linestyle() != ":"
    ]
    for line in data_lines:
        y = np.asarray(line.get_ydata(), float)
        x = np.asarray(line.get_xdata(), float)
        assert not np.any(np.isfinite(y) & np.isin(x, [4e-3, 8e-3]))


# ------------------------------------------------------------------ configuration checked before any job
@pytest.mark.parametrize(
    "change,message",
    [
        (lambda c: c["step_sizes"].update(H_min=1e-2, H_max=1e-3), r"convergence\.step_sizes: need 0 < H_min < H_max"),
        (lambda c: c["step_sizes"].update(H_min=1e-2, H_max=1e-2), r"convergence\.step_sizes: need 0 < H_min < H_max"),
        (
            lambda c: c["step_sizes"].update(H_max=2.0),
            r"convergence\.step_sizes\.H_max = 2\.0 must be at most convergence\.end_time",
        ),
        (lambda c: c.update(end_time=1e-3), r"convergence\.step_sizes\.H_max .* convergence\.end_time"),
        (
            lambda c: c["initial_conditions"].update(x0=0.0, v0=0.0),
            r"convergence\.initial_conditions: x0 and v0 are both zero",
        ),
        (lambda c: c["initial_conditions"].update(v0=float("nan")), r"convergence\.initial_conditions\.v0"),
        (lambda c: c["model"].update(m1=-1.0), r"convergence\.model: m1"),
        (lambda c: c["unstable"].update(growth_bound=1.0), r"convergence\.unstable\.growth_bound"),
        (
            lambda c: c["step_sizes"].update(H_min=0.45, H_max=0.5, num=4),
            r"convergence\.step_sizes: .* only the step count",
        ),
        (
            lambda c: c["fit"].update(min_points=20),
            r"convergence\.fit\.min_points = 20 exceeds the 6 step sizes .* smallest-H window",
        ),
    ],
)
def test_bad_configuration_is_refused_naming_the_key(change, message):
    cfg = _config()
    study_from_config(cfg)  # the shipped configuration is fine
    change(cfg)
    with pytest.raises(ParameterError, match=message):
        study_from_config(cfg)


def test_study_from_config_is_the_study_the_jobs_run():
    cfg = _config()
    study = study_from_config(cfg)
    s = cfg["step_sizes"]
    np.testing.assert_array_equal(study.n_steps, step_counts(cfg["end_time"], s["H_min"], s["H_max"], s["num"]))
    assert study.setup.x0 == cfg["initial_conditions"]["x0"] and study.digits == cfg["unstable"]["digits"]


def test_oscillation_summary_matches_the_monolithic_eigenvalues():
    """Frequency and decay of the report's text against the eigenvalues of the rigidly coupled system."""
    s = Setup()
    M, C, D = s.m1 + s.m2, s.c1 + s.c2, s.d1 + s.d2
    ev = np.linalg.eigvals(np.array([[0.0, 1.0], [-C / M, -D / M]]))
    o = oscillation_summary(s)
    assert o["omega"] == pytest.approx(abs(ev.imag).max(), rel=1e-12)
    assert o["decay"] == pytest.approx(np.exp(ev.real.max() * s.end_time), rel=1e-12)
    assert o["periods"] == pytest.approx(s.end_time * abs(ev.imag).max() / (2 * np.pi), rel=1e-12)
    assert oscillation_summary(Setup(d1=200.0, d2=200.0))["overdamped"]


# ------------------------------------------------------------------ claims checked before any job
def _claims_doc():
    return yaml.safe_load((ROOT / "config" / "claims" / "convergence.yaml").read_text())


def test_claims_file_matches_the_configuration():
    claims = load_claims(ROOT / "config" / "claims" / "convergence.yaml")
    check_claims_against_config(claims, _config())
    assert [c.id for c in claims] == [c["id"] for c in _claims_doc()["claims"]]
    assert {c.check["kind"] for c in claims} == {"convergence_order"}


def _parse_and_match(doc):
    check_claims_against_config(parse_claims(doc["claims"]), _config())


@pytest.mark.parametrize(
    "change,message",
    [
        (lambda c: c.update(colour="red"), r"baumgarte_index2.*unknown key.*colour"),
        (lambda c: c["check"].pop("expect"), r"baumgarte_index2.*check \(convergence_order\) lacks \['expect'\]"),
        (lambda c: c["check"]["select"].update(mux=1e-3), r"baumgarte_index2.*select: unknown key.*mux"),
        (lambda c: c["check"]["expect"][0].pop("k"), r"baumgarte_index2.*expect\[0\]\.k must be an integer"),
        (
            lambda c: c["check"]["expect"][0].update(order="two"),
            r"baumgarte_index2.*expect\[0\]\.order must be a number",
        ),
        (lambda c: c["check"]["expect"][0].pop("order"), r"baumgarte_index2.*expect\[0\]: give exactly one of"),
        (lambda c: c["check"]["expect"][1].update(order=2), r"baumgarte_index2.*expect\[1\]: give exactly one of"),
        (lambda c: c["check"]["expect"][0].update(ordre=2), r"baumgarte_index2.*expect\[0\]: unknown key.*ordre"),
        (lambda c: c.update(reference="maybe"), r"baumgarte_index2.*reference must be one of"),
        (lambda c: c["check"].update(tolerance=-1), r"baumgarte_index2.*tolerance must be a number > 0"),
        (
            lambda c: c["check"]["select"].update(figure="24"),
            r"baumgarte_index2.*expect\[0\]: no configured curve matches",
        ),
        (lambda c: c["check"]["select"].update(decomposition="dd"), r"baumgarte_index2.*no configured curve matches"),
        (
            lambda c: c["check"]["expect"][0].update(k=7),
            r"baumgarte_index2.*expect\[0\]: no configured curve matches .* k = 7",
        ),
    ],
)
def test_malformed_claims_name_the_claim_and_key(change, message):
    doc = _claims_doc()
    _parse_and_match(doc)  # the shipped file itself passes
    claim = next(c for c in doc["claims"] if c["id"] == "baumgarte_index2")
    change(claim)
    with pytest.raises(ParameterError, match=message):
        _parse_and_match(doc)


def test_claims_duplicates():
    doc = _claims_doc()
    with pytest.raises(ParameterError, match="duplicate id"):
        parse_claims(doc["claims"] + doc["claims"][:1])


# ------------------------------------------------------------------ theory: Baumgarte index 1, k = 0, fixed mu
@pytest.mark.parametrize("ratio", [0.1, 0.01])
def test_baumgarte_index1_k0_has_the_drift_mode_of_time_scale_mu(ratio):
    """Why Baumgarte index 1 with k = 0 and a fixed dimensional mu is of order 1 as H -> 0.

    Theory (rigid masses; the springs and dampers only perturb it): with k = 0 the relative
    acceleration a of the gap g = x2 - x1 is constant over a macro step, and the Baumgarte
    condition g + 2 mu g' + mu^2 g'' = 0 at T_N+1 gives the recurrence
    g+ = g + H g' + H^2 a / 2, g'+ = g' + H a, a = -(g + (H + 2 mu) g') / (mu^2 + 2 mu H + H^2 / 2).
    With r = H / mu its eigenvalues are the pair
    z = [(1 + r - r^2/4) +- i sqrt(r^3/2 - r^4/16)] / (1 + 2 r + r^2/2),
    of modulus |z| = (1 + 2 r + r^2/2)^(-1/2) = 1 - r + (5/4) r^2 + O(r^3): the constraint drift decays
    like exp(-t / mu), on the time scale mu, not H, so a start-up gap of O(H) is corrected only over
    mu / H steps and the global error keeps O(H).  (The eigenvalue itself is 1 - r +- i r^(3/2)/sqrt 2
    + O(r^2): a split double root; its modulus, which sets the decay, is 1 - r + O(r^2).)
    """
    mu = 1.0e-3
    H = ratio * mu
    c = icosim.PhysicalModel(**icosim.studies.convergence.experiment.PAPER_MODEL, H=H).coefficients()
    M = icosim.problems.linear.spectral.amplification_matrix(
        c, icosim.make_method("baumgarte", beta=2 * mu / H, gamma=mu**2 / H**2), "ff", 0
    )
    ev = np.linalg.eigvals(M)
    r = ratio
    z_rigid = ((1 + r - r**2 / 4) + 1j * np.sqrt(r**3 / 2 - r**4 / 16)) / (1 + 2 * r + r**2 / 2)
    z = ev[np.argmin(np.abs(ev - z_rigid))]
    # the O(r^2) term of |z| is (5/4) r^2 (+ O(r^3)); 3/2 r^2 bounds it at both ratios, while a
    # different first-order term (1 - r/2, 1 - 2r) would be off by r/2 >= 50 r^2
    assert abs(abs(z) - (1 - r)) <= 1.5 * r**2
    assert abs(z.real - (1 - r)) <= 1.5 * r**2
    assert np.conj(z) == pytest.approx(ev[np.argmin(np.abs(ev - np.conj(z)))])  # a complex pair
    # the springs and dampers (d H / m ~ 1e-3 here) move the pair by a small fraction of its distance
    # from 1 - r
    assert abs(z - z_rigid) <= 0.02 * abs(z_rigid - (1 - r))
