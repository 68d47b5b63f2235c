"""``icosim map``: the pipeline's panels and figure for any method, parameters and grid."""

import json

import numpy as np
import pytest

from icosim import TestModel, make_method, spectral_radius_float64
from icosim.advise.maps import boundary_extent, map_specs, marginal_extent, stable_extent
from icosim.cli import main
from icosim.engine.schemes import SCHEMES, GaussSeidel
from icosim.io.netcdf import open_dataset
from icosim.problems.linear.spectral import certify_spectral_radius
from icosim.studies.stability.datasets import stability_panel

WM = ["map", "--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "ff"]
GRID = ["--lr1", "-2e-1", "-1e-2", "--li1", "0", "0.2", "--n", "11"]


def test_map_writes_the_pipelines_panel_and_figure(tmp_path, capsys):
    prefix = tmp_path / "out" / "wm"
    assert main([*WM, "--k", "1", "2", *GRID, "--out", str(prefix)]) == 0
    out = capsys.readouterr().out
    for name in ("wm.png", "wm.pdf", "wm_k1.nc", "wm_k2.nc"):
        assert (tmp_path / "out" / name).stat().st_size > 0, name
    ds = open_dataset(tmp_path / "out" / "wm_k2.nc")
    # the same computation as the workflow's sweep job for this panel: equal values, same variable names
    [spec] = map_specs(
        "weighted", {"a": 1.0, "b": 1.0}, "ff", [2], ratios=(1, 1, 1), lr1=(-0.2, -0.01), li1=(0, 0.2), n=11
    )
    ref = stability_panel(spec)
    assert set(ds.data_vars) == set(ref.data_vars) >= {"rho", "verdict", "decided_by", "certified", "stable"}
    for name in ("rho", "verdict", "decided_by"):
        np.testing.assert_array_equal(ds[name].values, ref[name].values)
    for key in ("figure", "method", "decomposition", "k", "am21", "a", "b", "row_label_keys", "n_stable"):
        assert ds.attrs[key] == ref.attrs[key], key
    assert ds.attrs["figure"] == "map" and "icosim map" in ds.attrs["history"]
    assert "k = 2:" in out and "stable for lr1 in" in out


def test_where_the_stable_region_ends_agrees_with_an_independent_evaluation():
    """Weighted multiplier ff, k = 2: unstable near the origin (lr1 > about -0.08), Sect. 3.1.2."""
    [spec] = map_specs(
        "weighted", {"a": 1.0, "b": 1.0}, "ff", [2], ratios=(1, 1, 1), lr1=(-0.2, -0.01), li1=(0.05, 0.2), n=20
    )
    ds = stability_panel(spec)
    extent = stable_extent(ds)
    lr1 = ds["lr1"].values
    for _, row in extent.iterrows():
        rho, _ = spectral_radius_float64(
            TestModel(lr1, np.full_like(lr1, row["li1"]), 1, 1, 1), make_method("weighted", a=1, b=1), "ff", 2
        )
        stable = rho <= 1
        assert row["n_stable"] == stable.sum()
        assert row["stable_from"] == lr1[stable].max()
        assert -0.1 < row["stable_from"] < -0.07  # the paper's boundary near lr1 = -0.08
        assert row["stable_lr1"] == [[lr1[0], row["stable_from"]]]
    b = boundary_extent(ds)
    assert b["n_points"] == 20 and -0.1 < b["lr1"][0] <= b["lr1"][1] < -0.07


def test_marginal_points_are_where_the_proof_contains_1_and_are_no_boundary():
    """Weighted multiplier ff, k = 1, identical subsystems: the undamped axis lr1 = 0 is marginal (rho = 1 within the
    proof, checked point by point), the rest stable: no rho = 1 crossing, only the marginal column."""
    [spec] = map_specs("weighted", {"a": 1.0, "b": 1.0}, "ff", [1], ratios=(1, 1, 1), lr1=(-0.2, 0), li1=(0, 0.2), n=6)
    ds = stability_panel(spec)
    method = make_method("weighted", a=1, b=1)
    for li1 in ds["li1"].values[::2]:
        assert certify_spectral_radius(TestModel(0.0, float(li1), 1, 1, 1), method, "ff", 1).verdict == "marginal"
    m = marginal_extent(ds)
    assert m == {"lr1": [0.0, 0.0], "li1": [0.0, 0.2], "n_points": 6}
    assert boundary_extent(ds)["n_points"] == 0 and int(ds.attrs["n_marginal"]) == 6


def test_json_output_is_strict(tmp_path, capsys):
    assert (
        main(
            [
                "map",
                "--method",
                "projection",
                "--decomposition",
                "dd",
                "--k",
                "0",
                *GRID,
                "--out",
                str(tmp_path / "p"),
                "--json",
            ]
        )
        == 0
    )

    def refuse(name):
        raise AssertionError(name)

    data = json.loads(capsys.readouterr().out, parse_constant=refuse)
    [panel] = data["panels"]
    assert panel["n_points"] == 121 and len(panel["rows"]) == 11
    assert data["files"][-1].endswith("p_k0.nc")


@pytest.mark.parametrize(
    "argv,argument",
    [
        (["--method", "weighted", "--decomposition", "ff", "--k", "0"], "--a"),
        (["--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "dd", "--k", "0"], "position level"),
        (["--method", "projection", "--mu", "1", "--decomposition", "ff", "--k", "0"], "--mu"),
        (["--method", "projection", "--decomposition", "ff", "--k", "0", "--lr1", "0", "-1"], "--lr1"),
        (["--method", "projection", "--decomposition", "ff", "--k", "0", "--lr1", "-1", "1"], "--lr1"),
        (["--method", "projection", "--decomposition", "ff", "--k", "0", "--li1", "-1", "1"], "--li1"),
        (["--method", "projection", "--decomposition", "ff", "--k", "0", "--n", "1"], "--n"),
        (["--method", "projection", "--decomposition", "ff", "--k", "0", "--am21", "0"], "--am21"),
        (["--method", "projection", "--decomposition", "ff", "--k", "-2"], "--k"),
        (["--method", "nope", "--decomposition", "ff", "--k", "0"], "--method"),
    ],
)
def test_bad_input_exits_2_naming_the_argument(capsys, monkeypatch, tmp_path, argv, argument):
    import icosim.advise.maps

    def no_work(*a, **k):
        raise AssertionError("computed before the input was checked")

    monkeypatch.setattr(icosim.advise.maps, "stability_panel", no_work)
    with pytest.raises(SystemExit) as exc:
        main(["map", *argv, "--out", str(tmp_path / "x")])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert argument in err and "Traceback" not in err
    assert not list(tmp_path.iterdir())  # nothing written


@pytest.mark.parametrize("first,name", [(1, "gauss-seidel-12"), (2, "gauss-seidel-21")])
def test_map_with_a_gauss_seidel_scheme(tmp_path, capsys, first, name):
    """``--scheme gauss-seidel-12`` / ``-21``: the panel is the scheme's (attribute ``scheme``, rho of the library
    with subsystem ``first`` advancing first)."""
    prefix = tmp_path / "gs"
    argv = [*WM, "--k", "0", *GRID, "--out", str(prefix), "--scheme", name]
    assert main(argv) == 0
    assert "Gauss–Seidel" in capsys.readouterr().out
    ds = open_dataset(tmp_path / "gs_k0.nc")
    assert ds.attrs["scheme"] == name
    lr1, li1 = ds["lr1"].values[3], ds["li1"].values[5]
    method = make_method("weighted", a=1, b=1)
    rho, _ = spectral_radius_float64(TestModel(lr1, li1), method, "ff", 0, scheme=GaussSeidel(first=first))
    assert ds["rho"].values[3, 5] == pytest.approx(float(rho), rel=1e-12)


@pytest.mark.parametrize(
    "extra,argument",
    [
        (["--scheme", "gauss-seidel"], "argument --scheme: invalid choice: 'gauss-seidel'"),  # the old generic name
        (["--scheme", "jacobi", "--first", "2"], "unrecognized arguments: --first 2"),  # first is in the name now
    ],
)
def test_map_old_gauss_seidel_spelling_exits_2(tmp_path, capsys, extra, argument):
    with pytest.raises(SystemExit) as exc:
        main([*WM, "--k", "0", *GRID, "--out", str(tmp_path / "x"), *extra])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and argument in err and "Traceback" not in err
    if "--scheme" in argument:  # the allowed values are listed: every registered scheme
        assert all(f"'{name}'" in err for name in SCHEMES)
    assert not list(tmp_path.iterdir())  # nothing written
