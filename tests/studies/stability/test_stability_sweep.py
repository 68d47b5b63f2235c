"""Stability panels (icosim.studies.stability.panels) and their figures (icosim.figures.stability).

The dataset names are a contract other tools read (icosim map, the claims, the report); the numbers are
checked against an independent route: the multiprecision spectral radius of
single points.
"""

import os

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402
import yaml  # noqa: E402
from helpers import ROOT  # noqa: E402

from icosim import TestModel, make_method  # noqa: E402
from icosim.errors import ParameterError  # noqa: E402
from icosim.figures import save_figure  # noqa: E402
from icosim.figures.stability import (  # noqa: E402
    drawn_variables,
    panel_layout,
    row_labels,
    stability_figure,  # noqa: E402
)
from icosim.io.netcdf import open_dataset, open_variables, provenance_attrs, write_netcdf  # noqa: E402
from icosim.problems.linear.spectral import spectral_radius_mp  # noqa: E402
from icosim.studies.stability.datasets import stability_panel  # noqa: E402
from icosim.studies.stability.panels import (  # noqa: E402
    PanelSpec,
    figure_panels,
    figure_schemes,
    grid_axis,
    panel_id,
    row_label,
    row_label_keys,
)

CFG = yaml.safe_load((ROOT / "config" / "stability.yaml").read_text())["stability"]
COARSE = {"lr1": [-2.0, 0.0], "li1": [0.0, 2.0], "n": 5}
ZOOM = {"lr1": [-0.2, 0.0], "li1": [0.0, 0.2], "n": 3}
PREC = {"policy": "auto", "digits": 30}


def spec(**kw):
    base = dict(
        figure="10",
        row=1,
        k=2,
        view="full",
        method="weighted",
        method_params={"a": 1.0, "b": 1.0},
        decomposition="ff",
        am21=1.0,
        alr21=1.0,
        ali21=1.0,
        lr1=(-2.0, 0.0),
        li1=(0.0, 2.0),
        n=5,
        digits=30,
    )
    base.update(kw)
    return PanelSpec(**base)


@pytest.fixture(scope="module")
def weighted_panel():
    return stability_panel(spec(), provenance=provenance_attrs(spec().as_dict(), title="test panel"))


def test_dataset_naming_contract(weighted_panel, tmp_path):
    path = tmp_path / "panel.nc"
    write_netcdf(weighted_panel, path)
    ds = open_dataset(path)
    assert ds["rho"].dims == ("lr1", "li1")
    for coord in ("lr1", "li1"):
        assert ds[coord].attrs["long_name"] and ds[coord].attrs["units"] == "1"
    for var in ("rho", "stable", "digits"):
        assert ds[var].attrs["long_name"]
    a = ds.attrs
    assert (a["figure"], a["method"], a["decomposition"], a["k"]) == ("10", "weighted", "ff", 2)
    assert (a["am21"], a["alr21"], a["ali21"], a["a"], a["b"]) == (1.0, 1.0, 1.0, 1.0, 1.0)
    assert a["Conventions"].startswith("CF-") and "icosim" in a["source"] and a["history"]
    assert len(a["config_sha256"]) == 64 and '"method":"weighted"' in a["config_json"]
    # the precision that decided each point, and the counts that summarise it
    assert a["n_high_precision"] == int((ds["digits"] > 15).sum())
    assert a["n_points"] == 25 and a["n_stable"] == int(ds["stable"].sum())
    assert a["seconds_float64"] >= 0 and a["seconds_certify"] >= 0
    # per point: the verdict, what decided it, whether it is proven, and the proof's enclosure
    assert ds["verdict"].attrs["flag_meanings"] == "stable unstable marginal undecided"
    assert ds["decided_by"].attrs["flag_meanings"] == "float64 ball mpmath none"
    certified = ds["certified"].values
    proof = (ds["decided_by"].values == 1) & (ds["verdict"].values != 3)  # ball arithmetic, not undecided
    assert np.array_equal(certified, proof) and a["n_certified"] == int(certified.sum())
    lo, hi, rho = ds["rho_lower"].values, ds["rho_upper"].values, ds["rho"].values
    assert np.all(lo[certified] <= rho[certified]) and np.all(rho[certified] <= hi[certified])
    assert np.isnan(lo[~certified]).all() and a["n_marginal"] == int((ds["verdict"] == 2).sum())


def test_baumgarte_panel_records_beta_gamma():
    ds = stability_panel(spec(method="baumgarte", method_params={"index": 1, "mu": 0.5}, k=0, n=3))
    assert (ds.attrs["beta"], ds.attrs["gamma"], ds.attrs["mu"], ds.attrs["index"]) == (1.0, 0.25, 0.5, 1)


def test_float64_points_agree_with_multiprecision(weighted_panel):
    """Independent route: every float64-decided point against 40-digit mpmath."""
    ds = weighted_panel
    method = make_method("weighted", a=1.0, b=1.0)
    checked = 0
    for i, lr1 in enumerate(ds["lr1"].values):
        for j, li1 in enumerate(ds["li1"].values[::2]):
            j *= 2
            if ds["digits"].values[i, j] != 15:
                continue
            ref = float(spectral_radius_mp(TestModel(lr1, li1, 1.0, 1.0, 1.0), method, "ff", 2, 40))
            assert abs(ds["rho"].values[i, j] - ref) <= ds["rho_float64_error"].values[i, j]
            assert bool(ds["stable"].values[i, j]) == (ref <= 1)
            checked += 1
    assert checked >= 5


def test_points_float64_cannot_decide_are_certified_and_counted():
    ds = stability_panel(spec(method="baumgarte", method_params={"index": 1, "mu": 1.0}))
    certified, audited = ds["certified"].values, ds["audited"].values
    rho, err = ds["rho"].values, ds["rho_float64_error"].values
    assert ds.attrs["n_high_precision"] == int(certified.sum()) > 0
    assert ds.attrs["n_high_precision_undamped"] == int(certified[-1, :].sum())
    assert np.all(ds["digits"].values[certified] >= 38)  # at least 128 bits
    # certified without being audited: float64 could not decide (rho there is the proven one, within the estimate)
    assert np.all(np.abs(rho[certified & ~audited] - 1) <= 2 * err[certified & ~audited])
    # not certified: float64 decided
    assert np.all(np.abs(rho[~certified] - 1) > err[~certified])
    # the undamped axis with identical subsystems: rho = 1 exactly, marginal
    assert np.all(ds["verdict"].values[-1, 1:] == 2)


def test_grid_axis_hits_the_end_points_exactly():
    axis = grid_axis([-2.0, 0.0], 101)
    assert axis[0] == -2.0 and axis[-1] == 0.0 and axis.size == 101
    with pytest.raises(ParameterError, match="increasing"):
        grid_axis([0.0, -2.0], 5)


def test_configured_figures_expand_to_the_papers_layout():
    """The paper's layout for every scheme a figure is computed with (the scheme is a dimension, like k)."""
    counts = {}
    for fig, fc in CFG["figures"].items():
        specs = figure_panels(fig, fc, grid=CFG["grid"], zoom_grid=CFG["zoom_grid"], precision=CFG["precision"])
        assert len({(s.scheme, panel_id(s.row, s.k, s.view)) for s in specs}) == len(specs)
        schemes = figure_schemes(fig, fc)
        assert {s.scheme for s in specs} == set(dict(schemes))
        for scheme, rows in schemes:
            if rows is None:  # every row: the figure's whole layout
                own = [s for s in specs if s.scheme == scheme]
                full = [s for s in own if s.view == "full"]
                counts.setdefault(fig, set()).add((len(full), len(own) - len(full)))
    assert all(len(c) == 1 for c in counts.values())  # the same layout for every scheme
    counts = {fig: c.pop() for fig, c in counts.items()}
    for fig in map(str, range(9, 16)):  # 4 rows x k = 0, 1, 2
        assert counts[fig][0] == 12
    for fig in ("16", "17", "19", "20"):  # 3 rows x 3 k
        assert counts[fig][0] == 9
    assert counts["18"] == (3, 0)
    assert counts["9"][1] == 1 and counts["10"][1] == 4 and counts["16"][1] == 6
    # Figs. 9-15: row 1 is (1, 1, 1), rows 2-4 raise am21, alr21, ali21 in turn (for every scheme)
    for fig in map(str, range(9, 16)):
        fc = CFG["figures"][fig]
        specs = figure_panels(fig, fc, grid=CFG["grid"], zoom_grid=CFG["zoom_grid"], precision=CFG["precision"])
        for scheme in [name for name, rows in figure_schemes(fig, fc) if rows is None]:
            triples = [
                (x.am21, x.alr21, x.ali21) for x in specs if x.scheme == scheme and x.k == 0 and x.view == "full"
            ]
            assert triples[0] == (1.0, 1.0, 1.0)
            for row, triple in enumerate(triples[1:]):
                raised = [i for i, v in enumerate(triple) if v != 1.0]
                assert raised == [row], (fig, scheme, triples)
    # Figs. 16-20 use (2, 2, 2)
    for fig in ("16", "17", "18", "19", "20"):
        assert CFG["figures"][fig]["ratios"] == {"am21": 2.0, "alr21": 2.0, "ali21": 2.0}


def test_row_labels_name_what_varies():
    assert row_label(CFG["figures"]["9"], 4) == "αm21 = 1, αλr21 = 1, αλi21 = 10"
    assert row_label(CFG["figures"]["16"], 1) == "μ̄ = 0.25"
    assert row_label(CFG["figures"]["20"], 3) == "a = 2.5, b = 5"


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda fc: fc.update(method="baumgarte", decomposition="dd", params={"index": 1, "mu": 1.0}), "dd"),
        (lambda fc: fc.update(rows=[{"mu": 1.0}]), "row 1"),
        (lambda fc: fc.update(zoom={"rows": [1], "k": [7]}), "zoom.k"),
    ],
)
def test_figure_errors_name_the_figure_and_key(change, message):
    fc = dict(CFG["figures"]["15"])
    change(fc)
    with pytest.raises(ParameterError, match=message):
        figure_panels("15", fc, grid=COARSE, zoom_grid=ZOOM, precision=PREC)


@pytest.mark.parametrize(
    "name, grid, message",
    [
        ("grid", {**COARSE, "lr1": [0.0, -2.0]}, r"stability\.grid\.lr1 must be increasing"),
        ("grid", {**COARSE, "li1": [1.0, 1.0]}, r"stability\.grid\.li1 must be increasing"),
        ("zoom_grid", {**ZOOM, "n": 1}, r"stability\.zoom_grid\.n must be an integer >= 2"),
        ("zoom_grid", {**ZOOM, "li1": [-0.1, 0.2]}, r"stability\.zoom_grid\.li1 must lie in li1 >= 0"),
        ("grid", {**COARSE, "lr1": [-2.0]}, r"stability\.grid\.lr1 must be \[start, stop\]"),
    ],
)
def test_bad_grids_are_refused_naming_the_key(name, grid, message):
    grids = {"grid": COARSE, "zoom_grid": ZOOM, name: grid}
    with pytest.raises(ParameterError, match=message):
        figure_panels("15", CFG["figures"]["15"], precision=PREC, **grids)


def test_figure_and_report_label_rows_by_one_rule():
    """The figure's row labels come from the keys stored in the panels, chosen by
    icosim.studies.stability.panels.row_label_keys -- the rule of the report's row_label."""
    tiny = {**COARSE, "n": 2}
    for fig, fc in CFG["figures"].items():
        specs = [
            s
            for s in figure_panels(fig, fc, grid=tiny, zoom_grid=ZOOM, precision={"policy": "float64", "digits": 30})
            if s.k == fc["k"][0] and s.view == "full"
        ]
        panels = [stability_panel(s) for s in specs]
        tex = row_labels(panels)
        for ds in panels:
            row = ds.attrs["row"]
            assert ds.attrs["row_label"] == row_label(fc, row), (fig, row)
            assert ds.attrs["row_label_keys"].split() == list(row_label_keys(fc))
            # same parameters and values, typeset in TeX
            values = [part.split(" = ")[1] for part in row_label(fc, row).split(", ")]
            assert [part.split(" = ")[1] for part in tex[row].split(", ")] == values, (fig, row)
            assert "mu_bar = mu/H" in ds.attrs["method_parameters_units"]


def test_figure_refuses_panels_without_row_label_keys(fig16_panels):
    ds = fig16_panels[0].copy()
    ds.attrs = {k: v for k, v in ds.attrs.items() if k != "row_label_keys"}
    with pytest.raises(ValueError, match="row_label_keys"):
        row_labels([ds])


def test_positive_lr1_grid_is_refused():
    with pytest.raises(ParameterError, match="lr1"):
        figure_panels("15", CFG["figures"]["15"], grid={**COARSE, "lr1": [-1.0, 1.0]}, zoom_grid=ZOOM, precision=PREC)


@pytest.fixture(scope="module")
def fig16_panels():
    fc = {
        **CFG["figures"]["16"],
        "rows": CFG["figures"]["16"]["rows"][:2],
        "k": [1, 2],
        "zoom": {"rows": [1, 2], "k": [2]},
    }
    specs = figure_panels("16", fc, grid={**COARSE, "n": 4}, zoom_grid=ZOOM, precision=PREC)
    return [stability_panel(s) for s in specs]


def test_figure_layout_puts_zooms_in_extra_columns(fig16_panels):
    rows, columns, place = panel_layout(fig16_panels)
    assert rows == [1, 2]
    assert columns == [("full", 1), ("full", 2), ("zoom", 2)]
    assert len(set(place.values())) == len(fig16_panels) == 6
    labels = row_labels(fig16_panels)
    assert "0.25" in labels[1] and "mu" in labels[1]


@pytest.mark.parametrize("style", ["field", "dots"])
def test_figure_is_written_as_png_and_pdf(fig16_panels, tmp_path, style):
    fig = stability_figure(fig16_panels, title="Fig. 16", style=style)
    axes = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    assert len([ax for ax in axes if ax.axison]) == 6
    save_figure(fig, tmp_path / "f.png", tmp_path / "f.pdf", dpi=40)
    assert (tmp_path / "f.png").read_bytes()[:4] == b"\x89PNG"
    assert (tmp_path / "f.pdf").read_bytes()[:4] == b"%PDF"
    assert not list(tmp_path.glob("*.part"))


@pytest.mark.parametrize("style", ["field", "dots"])
def test_figure_from_the_drawn_variables_alone_is_the_figure_from_the_datasets(fig16_panels, tmp_path, style):
    """The figure job reads only what is drawn (open_variables, no xarray): the same values, the same pixels."""
    from PIL import Image

    paths = []
    for n, ds in enumerate(fig16_panels):
        ds = ds.copy()
        ds["rho"][0, 0] = np.nan  # a point without a result: written as the fill value, read back as NaN
        write_netcdf(ds, tmp_path / f"p{n}.nc")
        paths.append(tmp_path / f"p{n}.nc")
    whole = [open_dataset(p) for p in paths]
    drawn = [open_variables(p, drawn_variables(style) + ("no_such_variable",)) for p in paths]
    for ds, light in zip(whole, drawn):
        assert set(light) == set(drawn_variables(style)) and np.isnan(light["rho"][0, 0])
        assert list(light.attrs) == list(ds.attrs)
        assert all(type(light.attrs[a]) is type(v) and np.array_equal(light.attrs[a], v) for a, v in ds.attrs.items())
        for name, values in light.items():
            assert values.dtype == ds[name].dtype and np.array_equal(values, ds[name].values, equal_nan=True), name
    pixels = []
    for panels, name in ((whole, "a"), (drawn, "b")):
        save_figure(stability_figure(panels, title="Fig. 16", style=style), tmp_path / f"{name}.png", dpi=40)
        pixels.append(np.asarray(Image.open(tmp_path / f"{name}.png").convert("RGBA")))
    assert np.array_equal(*pixels)


def test_variables_encoded_beyond_what_open_variables_decodes_are_refused(tmp_path):
    import xarray as xr

    ds = xr.Dataset({"rho": ("x", np.array([0.5, 1.5])), "verdict": ("x", np.array([0, 1], np.int8))})
    ds["rho"].encoding = {"scale_factor": 0.5, "dtype": "int16", "_FillValue": -1}  # xarray: rho = 0.5 * stored
    ds["verdict"].encoding = {"_FillValue": np.int8(-1)}  # xarray: a float, -1 read as NaN
    write_netcdf(ds, tmp_path / "encoded.nc")
    for name in ("rho", "verdict"):
        with pytest.raises(ValueError, match=name):
            open_variables(tmp_path / "encoded.nc", [name])


def test_figure_rejects_unknown_style(fig16_panels):
    with pytest.raises(ValueError, match="style"):
        stability_figure(fig16_panels, style="hexbin")


@pytest.mark.parametrize(
    "method, lr1, li1",
    [(make_method("weighted", a=1.0, b=1.0), -1.44, 1.40), (make_method("projection"), -1.40, 0.98)],
)
def test_force_displacement_instability_is_confirmed_by_time_stepping(method, lr1, li1):
    """Independent route for the reported disagreements (Figs. 13 and 14, k = 0): from an
    exact start, plain time stepping grows by the panel's rho per macro step."""
    from icosim import LinearCosimulation
    from icosim.engine.run import simulate
    from icosim.problems.linear.exact import MonolithicSolution, consistent_start

    s = spec(
        figure="13",
        method=method.name,
        method_params=dict(a=1.0, b=1.0) if method.name == "weighted" else {},
        decomposition="fd",
        k=0,
        lr1=(lr1, 0.0),
        li1=(li1, 2.0),
        n=2,
    )
    rho = float(stability_panel(s)["rho"].values[0, 0])
    assert rho > 1.2  # clearly unstable: force/force is stable there (Figs. 10 and 11)
    c = TestModel(lr1, li1, 1.0, 1.0, 1.0).coefficients()
    problem = LinearCosimulation(c, "fd", 0)
    state, history = consistent_start(problem, MonolithicSolution(c, 1.0, 0.0))
    traj = simulate(problem, method, state, history, 300)
    size = np.array([np.abs(st).max() for st in traj.states])
    assert (size[-1] / size[-101]) ** (1 / 100) == pytest.approx(rho, rel=1e-6)
