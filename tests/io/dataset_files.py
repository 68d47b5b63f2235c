"""What a reader sees of a NetCDF file, to compare files written by icosim.io.dataset.write_nc4 with xarray's."""

import math

import netCDF4
import numpy as np
import xarray as xr

from icosim.io.dataset import DatasetDict
from icosim.io.netcdf import open_dataset, write_netcdf


def _value(v):
    """An attribute value with its type, NaN comparable to NaN."""
    if isinstance(v, np.ndarray):
        return ("array", str(v.dtype), tuple(_value(x)[2] for x in v.ravel()))
    kind = type(v).__name__
    if isinstance(v, float | np.floating) and math.isnan(v):
        return (kind, str(getattr(v, "dtype", "")), "NaN")
    return (kind, str(getattr(v, "dtype", "")), v.item() if isinstance(v, np.generic) else v)


def structure(path, *, ordered=True) -> dict:
    """ncdump -s level: dimensions with sizes, global attributes with types, and per variable its netCDF
    datatype, dimensions, storage (chunking, filters, endianness) and attributes with types, in file order
    (``ordered``) or sorted by name."""
    order = list if ordered else sorted
    with netCDF4.Dataset(path) as nc:
        out = {
            "format": nc.data_model,
            "dims": [(name, len(d), d.isunlimited()) for name, d in order(nc.dimensions.items())],
            "attrs": [(name, _value(nc.getncattr(name))) for name in nc.ncattrs()],
            "variables": [],
        }
        for name, var in order(nc.variables.items()):
            out["variables"].append(
                (
                    name,
                    str(var.datatype),
                    var.dimensions,
                    var.chunking(),
                    var.filters(),
                    var.endian(),
                    [(a, _value(var.getncattr(a))) for a in var.ncattrs()],
                )
            )
    return out


def assert_written_as_xarray_writes(d: DatasetDict, tmp_path, name="d", *, round_trips=True):
    """``write_netcdf(d)`` (netCDF4 directly) gives the file xarray writes for the same dataset: the same
    structure (in the same order as ``d.to_xarray().to_netcdf``; the same by name as
    ``xr.Dataset.from_dict(d).to_netcdf``), and xarray reads identical datasets from all three and, if
    ``round_trips`` (no own fill value, no one-string list attribute: xarray reads those back otherwise), from d."""
    ours, theirs, from_dict = (tmp_path / f"{name}_{w}.nc" for w in ("ours", "xarray", "from_dict"))
    write_netcdf(d, ours)
    d.to_xarray().to_netcdf(theirs, engine="netcdf4")
    xr.Dataset.from_dict(d).to_netcdf(from_dict, engine="netcdf4")
    assert structure(ours) == structure(theirs)
    assert structure(ours, ordered=False) == structure(from_dict, ordered=False)
    read = open_dataset(ours)
    for other in (theirs, from_dict):
        with xr.open_dataset(other, engine="netcdf4") as ds:
            xr.testing.assert_identical(read, ds.load())
    if round_trips:
        xr.testing.assert_identical(read, d.to_xarray())
        xr.testing.assert_identical(read, xr.Dataset.from_dict(d))
    return read
