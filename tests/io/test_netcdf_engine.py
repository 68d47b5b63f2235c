"""The switch of NetCDF engine (h5netcdf -> netCDF4): files written before and after read back identically."""

import numpy as np
import pytest
import xarray as xr

from icosim.io.netcdf import NETCDF_ENGINE, open_dataset, provenance_attrs, write_netcdf
from icosim.studies.stability.datasets import stability_panel
from icosim.studies.stability.panels import PanelSpec

h5netcdf = pytest.importorskip("h5netcdf", reason="h5netcdf (test extra) writes the files of before the switch")


def samples():
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
        n=6,
    )
    panel = stability_panel(spec, provenance=provenance_attrs(spec.as_dict(), title="t"))
    t = np.linspace(0, 1, 11)
    run = xr.Dataset(
        {"phi1": ("t", np.sin(t)), "status": ((), "diverged")},
        coords={"t": ("t", t, {"units": "s"})},
        attrs={"t_diverged": np.nan, "diverged": 1, "test_model_lr1": [-1e-3, -2e-3], "label": "μ̄ = 1, λ̄r1"},
    )
    summary = xr.Dataset(
        {"verdict": ("run", ["pass", "undecided"]), "flag": ("run", np.array([True, False]))},
        coords={"run": ["a", "b"], "k": ("run", np.array([0, 2], dtype=np.int32))},
    )
    return [panel, run, summary]


@pytest.mark.parametrize("which", range(3))
def test_files_of_either_engine_read_back_identically(tmp_path, which):
    ds = samples()[which]
    before, after = tmp_path / "before.nc", tmp_path / "after.nc"
    ds.to_netcdf(before, engine="h5netcdf")  # how results were written before the switch
    write_netcdf(ds, after)  # and now
    old, new = open_dataset(before), open_dataset(after)
    xr.testing.assert_identical(old, new)
    xr.testing.assert_identical(new, ds.load())
    with xr.open_dataset(after, engine="h5netcdf") as back:  # a new file for a reader still on h5netcdf
        xr.testing.assert_identical(back.load(), new)
    for name in ds.variables:
        assert new[name].dtype == ds[name].dtype, name  # bool stays bool, int32 stays int32


def test_engine_is_netcdf4():
    assert NETCDF_ENGINE == "netcdf4"
