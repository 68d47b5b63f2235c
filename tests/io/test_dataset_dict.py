"""Results written without xarray (icosim.io.dataset) are the files xarray writes, for every kind the project writes.

Each builder's dataset (a small one) is written by ``write_netcdf`` with netCDF4 directly and by xarray's
``to_netcdf`` of the same dataset; the files must agree at ncdump level (dimensions, variable datatypes and
storage, variable and global attributes with their types, in order) and read back identically in xarray.
"""

import numpy as np
import pytest
import xarray as xr
import yaml
from dataset_files import assert_written_as_xarray_writes, structure
from helpers import ROOT, scheme_panel_spec

from icosim.io.dataset import DatasetDict
from icosim.io.netcdf import open_variables, provenance_attrs, write_netcdf


def test_stability_panel(tmp_path):
    from icosim.studies.stability.datasets import stability_panel_data
    from icosim.studies.stability.panels import PanelSpec

    spec = PanelSpec(
        figure="9",
        row=1,
        k=2,
        view="full",
        method="baumgarte",
        method_params={"index": 1, "mu": 1.0},
        decomposition="ff",
        am21=1.0,
        alr21=1.0,
        ali21=1.0,
        lr1=(-0.5, 0.0),
        li1=(0.0, 0.5),
        n=5,
    )
    d = stability_panel_data(spec, provenance=provenance_attrs(spec.as_dict(), title="t"))
    assert_written_as_xarray_writes(d, tmp_path)


def test_convergence_panel(tmp_path):
    from icosim.studies.convergence.curves import curve_label, curves
    from icosim.studies.convergence.datasets import curve_summaries, run_panel_data
    from icosim.studies.convergence.experiment import Setup, step_counts
    from icosim.studies.convergence.panels import PanelSpec
    from icosim.studies.convergence.study import Study

    rows = ({"index": 1, "mu": 5e-3}, {"index": 2, "mu": 5e-3})
    spec = PanelSpec("21", "ff", "p", "baumgarte", {"mu": 5e-3}, rows, (0, 1))
    study = Study(Setup(end_time=0.05), step_counts(0.05, 1e-3, 1e-2, 3))
    d = run_panel_data(spec, study, {"min_points": 2}, provenance=provenance_attrs({"a": 1}, title="t"))
    read = assert_written_as_xarray_writes(d, tmp_path)
    # the job's log line per curve: as the curves read back are labelled
    back = [(curve_label(r), r["order"], r["order_status"], int(r["unstable"].sum())) for r in curves([read])]
    np.testing.assert_equal(curve_summaries(d), back)


PENDULUM = yaml.safe_load((ROOT / "config" / "pendulum.yaml").read_text())["pendulum"]
SETTINGS = {
    key: PENDULUM[key] for key in ("model", "methods", "integrator", "sensitivities", "corrector", "divergence")
}


def test_pendulum_run_and_reference(tmp_path):
    from icosim.problems.pendulum.model import PendulumParameters
    from icosim.studies.pendulum.datasets import reference_dataset_data, run_job_data

    for k, scheme in ((0, "jacobi"), (1, "gauss-seidel-12")):
        job = {
            "method": "projection",
            "decomposition": "fd",
            "k": k,
            "method_params": PENDULUM["methods"]["projection"],
            "model": PENDULUM["model"],
            "H": PENDULUM["H"],
            "t_end": 0.02,
            "scheme": scheme,
            **{key: PENDULUM[key] for key in ("integrator", "sensitivities", "corrector", "divergence")},
        }
        assert_written_as_xarray_writes(run_job_data(job)[1], tmp_path, f"run{k}")
    ref = reference_dataset_data(PendulumParameters(**PENDULUM["model"]), PENDULUM["H"], 0.02, {"title": "t"})
    assert_written_as_xarray_writes(ref, tmp_path, "reference")


def test_pendulum_trade_sweep_and_limits(tmp_path):
    from icosim.studies.trade.stability_limit import limits_study_data
    from icosim.studies.trade.sweep import sweep_group_data

    ref = PENDULUM["trade"]["reference"]
    sweep = sweep_group_data(
        SETTINGS, "jacobi", "baumgarte", "ff", [0, 1], [1e-2, 2e-2], 0.04, reference=ref, repeats=1
    )
    assert_written_as_xarray_writes(sweep, tmp_path, "sweep")
    limits = {"scan": [5e-3, 2e-2], "t_end": 0.05, "resolution": 0.5}
    lim = limits_study_data(SETTINGS, "gauss-seidel-21", "projection", "ff", [0, 1], limits=limits)
    assert_written_as_xarray_writes(lim, tmp_path, "limits")


def test_pendulum_trade_tolerance_and_baselines(tmp_path):
    from icosim.problems.pendulum.model import PendulumParameters
    from icosim.studies.trade.baselines import linear_orders_dataset_data, monolithic_baselines_data
    from icosim.studies.trade.tolerance import tolerance_study_data

    ref = PENDULUM["trade"]["reference"]
    configs = [{"method": "projection", "decomposition": "ff", "k": 1}]
    tol = tolerance_study_data(SETTINGS, configs, [1e-2], [1e-3, 1e-8], 0.02, reference=ref)
    assert_written_as_xarray_writes(tol, tmp_path, "tolerance")
    mono = monolithic_baselines_data(PendulumParameters(), [1e-4, 1e-8], 0.02, reference=ref, repeats=1)
    assert_written_as_xarray_writes(mono, tmp_path, "monolithic")
    configurations = [
        ("baumgarte_ff_k0", "jacobi", "baumgarte", "ff", 0),
        ("p", "gauss-seidel-12", "projection", "ff", 1),
    ]
    model = PENDULUM["trade"]["linear_orders"]["model"]
    lin = linear_orders_dataset_data(SETTINGS, configurations, [1e-2, 2e-2], model=model, x0=0.1, t_end=0.1)
    assert_written_as_xarray_writes(lin, tmp_path, "linear")


def test_pendulum_adaptive(tmp_path):
    from icosim.studies.trade.adaptive import adaptive_study_data

    study = dict(
        PENDULUM["trade"]["adaptive"],
        t_end=0.04,
        H_fixed=[2e-3, 1e-2],
        configurations=[
            {"method": "projection", "decomposition": "ff", "k": 1, "tol": [1e-2, 1e-4]},
            {"scheme": "gauss-seidel-21", "method": "projection", "decomposition": "ff", "k": 1, "tol": [1e-2]},
        ],
    )
    d = adaptive_study_data(SETTINGS, study, reference=PENDULUM["trade"]["reference"])
    assert_written_as_xarray_writes(d, tmp_path)


def test_stability_scheme_shares(tmp_path):
    from icosim.studies.stability.checks import PANEL_VARIABLES
    from icosim.studies.stability.comparison import scheme_shares_data
    from icosim.studies.stability.datasets import stability_panel_data

    def panel(figure, scheme, row, k):
        spec = scheme_panel_spec(figure, scheme, row, k, n=3)
        path = tmp_path / f"panel_{figure}_{scheme}_{row}_{k}.nc"
        write_netcdf(stability_panel_data(spec), path)
        return open_variables(path, PANEL_VARIABLES)  # as the workflow's job reads them

    panels = [panel("9", s, row, 1) for s in ("jacobi", "gauss-seidel-12") for row in (1, 2)] + [
        panel("16", "jacobi", 1, 1)
    ]
    assert_written_as_xarray_writes(scheme_shares_data(panels), tmp_path)


@pytest.mark.fmu  # runs scenes on the test units
@pytest.mark.parametrize(("scene", "builtin"), [("two_mass_unstable", "linear"), ("double_pendulum_fd", "pendulum")])
def test_fmi_scene_and_validation(tmp_path, monkeypatch, scene, builtin):
    from icosim.problems.fmu.run import run_dataset_data, run_scene
    from icosim.problems.fmu.scene import load_scene
    from icosim.studies.fmi.validation import scene_validation, scene_validation_data

    cache = ROOT / "build" / "fmus"
    monkeypatch.setenv("ICOSIM_FMU_CACHE", str(cache))
    loaded = load_scene(ROOT / "config" / "scenes" / f"{scene}.yaml")
    run = run_dataset_data(run_scene(loaded, cache=cache), command="test")
    read = assert_written_as_xarray_writes(run, tmp_path, "run")
    checked = scene_validation_data(loaded, run, name=scene, builtin=builtin, cache=cache)
    assert_written_as_xarray_writes(checked, tmp_path, "validation")
    # the validation of the run's dataset read back (xarray) is the same, timing aside
    again = scene_validation(loaded, read, name=scene, builtin=builtin, cache=cache)
    for name in checked["data_vars"]:
        np.testing.assert_array_equal(again[name].values, checked.array(name))


@pytest.mark.fmu  # runs scenes on the test units
def test_fmi_orders(tmp_path):
    from icosim.studies.fmi.orders import order_case_data

    model = dict(m1=1.0, m2=2.0, c1=1000.0, c2=1000.0, d1=10.0, d2=10.0)
    case = {"method": "projection", "decomposition": "ff", "k": 1}
    d = order_case_data(
        case,
        H=[2.5e-3, 1.25e-3],
        t_end=0.02,
        model=model,
        x0=0.1,
        units_dir=ROOT / "fmus",
        cache=ROOT / "build" / "fmus",
    )
    assert_written_as_xarray_writes(d, tmp_path)


def kinds() -> DatasetDict:
    """One variable of every kind, coordinates of every role, attributes of every type."""
    t = np.linspace(0.0, 1.0, 4)
    return DatasetDict(
        {
            "x": (("config", "t"), np.arange(12.0).reshape(3, 4), {"units": "m", "flags": np.arange(2, dtype=np.int8)}),
            "ok": ("config", np.array([True, False, True]), {"long_name": "ok"}),
            "n": ("config", np.array([1, 2, 3], dtype=np.int16)),
            "n64": ("t", np.arange(4)),
            "u": ("t", np.arange(4, dtype=np.uint8)),
            "status": ("config", np.array(["pass", "", "ünïcode"], dtype=object)),
            "fixed": ("config", np.array(["a", "bb", "ccc"])),
            "scalar": ((), 2.5),
            "label": ((), "diverged"),
            "empty": ("none", np.array([], dtype=float)),
            "empty_str": ("none", np.array([], dtype=str)),
            "own_fill": ("t", np.array([1.0, -9.0, 3.0, np.nan]), {"_FillValue": -9.0}),
        },
        coords={
            "t": ("t", t, {"units": "s"}),
            "config": ["a", "b", "c"],
            "method": ("config", np.array(["x", "y", "z"])),
            "k": ("config", np.array([0, 1, 2], dtype=np.int32)),
            "weight": ("config", np.array([0.5, np.nan, 1.0])),
            "free": ("other", np.array([1.0, 2.0])),
        },
        attrs={
            "title": "kinds",
            "count": 3,
            "ratio": 0.25,
            "missing": np.nan,
            "levels": [1e-4, 1e-8],
            "ints": (1, 2),
            "names": ["a", "b"],
            "one_name": ["a"],
            "np_int": np.int64(7),
            "np_float": np.float32(0.5),
            "text": "μ̄ = 1",
        },
    )


def test_every_kind(tmp_path):
    read = assert_written_as_xarray_writes(kinds(), tmp_path, round_trips=False)
    assert read["ok"].dtype == bool and read["status"].values[2] == "ünïcode"
    assert set(read.coords) == {"t", "config", "method", "k", "weight", "free"}
    with xr.open_dataset(tmp_path / "d_ours.nc") as raw:  # as open_variables decodes it
        raw_vars = open_variables(tmp_path / "d_ours.nc", list(raw.variables))
        for name in ("x", "ok", "n", "status", "weight"):
            np.testing.assert_array_equal(raw_vars[name], raw[name].values)


def test_plain_dict_from_xarray_is_accepted(tmp_path):
    plain = kinds().to_xarray().to_dict(data="array")
    write_netcdf(plain, tmp_path / "a.nc")
    xr.Dataset.from_dict(plain).to_netcdf(tmp_path / "b.nc", engine="netcdf4")
    assert structure(tmp_path / "a.nc", ordered=False) == structure(tmp_path / "b.nc", ordered=False)


@pytest.mark.parametrize(
    ("data_vars", "match"),
    [
        ({"v": ("x", np.array([1j]))}, r"variable 'v': dtype complex128 .* \(float, integer, bool, str\)"),
        ({"v": ("x", np.array([None, "a"], dtype=object))}, "variable 'v': dtype object"),
        ({"v": ("x", np.array([], dtype=object))}, "variable 'v': no values of dtype object"),
        ({"v": (("x", "y"), np.zeros(3))}, "variable 'v': 1-dimensional values for the dimensions"),
        ({"v": ("x", np.zeros(3)), "w": ("x", np.zeros(2))}, "variable 'w': dimension 'x' has size 2, elsewhere 3"),
        ({"v": ("x",)}, r"variable 'v': give \(dims, values\)"),
    ],
)
def test_bad_variables_are_refused_by_name(data_vars, match):
    with pytest.raises((TypeError, ValueError), match=match):
        DatasetDict(data_vars)


def test_bad_attributes_are_refused_by_name(tmp_path):
    with pytest.raises(TypeError, match="global attributes: attribute 'when' = None"):
        write_netcdf(DatasetDict({}, attrs={"when": None}), tmp_path / "a.nc")
    with pytest.raises(TypeError, match="attribute 'flag' = True: NetCDF has no boolean attributes"):
        write_netcdf(DatasetDict({}, attrs={"flag": True}), tmp_path / "d.nc")
    with pytest.raises(TypeError, match="variable 'v': attribute 'meta'"):
        write_netcdf(DatasetDict({"v": ("x", np.zeros(2), {"meta": {"a": 1}})}), tmp_path / "b.nc")
    with pytest.raises(TypeError, match="not a dataset in xarray's dictionary form"):
        write_netcdf({"rho": np.zeros(2)}, tmp_path / "c.nc")
    assert not list(tmp_path.iterdir())  # nothing complete-looking left behind


def test_a_full_disk_is_a_clear_error_and_leaves_no_dataset(tmp_path):
    """As for an xarray.Dataset (tests/workflow/test_workflow_faults.py): a 200 kB tmpfs, where it can be mounted."""
    import subprocess

    mnt = tmp_path / "small"
    mnt.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(mnt)], capture_output=True).returncode:
        pytest.skip("cannot mount a tmpfs here (not root)")
    try:
        d = DatasetDict({"rho": (("lr1", "li1"), np.random.default_rng(0).random((300, 300)))})
        with pytest.raises(OSError, match=r"could not write .*x\.nc: no space left on its file system"):
            write_netcdf(d, mnt / "x.nc")
        assert list(mnt.iterdir()) == []  # no dataset, no sidecar, no temporary
    finally:
        subprocess.run(["umount", str(mnt)], capture_output=True)
