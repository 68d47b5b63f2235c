"""How results become self-describing NetCDF files (shared by all parts).

Every dataset carries CF ``Conventions``, ``history``, ``source`` (with the
package version), ``institution``-free provenance, and the exact job
configuration as JSON together with its SHA-256, so a file can be traced to
the config that produced it.  Files are written atomically: a failed or
interrupted job never leaves a complete-looking result behind.
"""

from __future__ import annotations

import datetime as _dt
import errno
import hashlib
import json
import platform
import shutil
from pathlib import Path

import numpy as np

from ..errors import CorruptDatasetError
from .dataset import DatasetDict, write_nc4
from .integrity import atomic_path, verify, write_checksum

__all__ = [
    "provenance_attrs",
    "config_json",
    "write_netcdf",
    "atomic_path",
    "open_dataset",
    "open_attributes",
    "open_variables",
]

CONVENTIONS = "CF-1.10"


def config_json(config) -> str:
    """Canonical JSON of a job configuration (sorted keys, no whitespace)."""
    return json.dumps(config, sort_keys=True, separators=(",", ":"), default=_jsonable, allow_nan=False)


def _jsonable(o):
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, np.ndarray):
        return o.tolist()
    raise TypeError(f"not JSON serialisable: {type(o).__name__}")


def provenance_attrs(config, *, title: str, command: str = "") -> dict:
    """Global attributes: CF conventions, history, source, config JSON and SHA-256."""
    from ..version import package_version

    cfg = config_json(config)
    now = _dt.datetime.now(_dt.UTC).replace(microsecond=0).isoformat()
    return {
        "title": title,
        "Conventions": CONVENTIONS,
        "history": f"{now} created by icosim {package_version()}" + (f": {command}" if command else ""),
        "source": f"icosim {package_version()} (Python {platform.python_version()}, numpy {np.__version__})",
        "references": "Schweizer et al., Implicit co-simulation methods: stability and convergence "
        "analysis for solver coupling approaches with algebraic constraints",
        "config_json": cfg,
        "config_sha256": hashlib.sha256(cfg.encode()).hexdigest(),
    }


#: The NetCDF library: netCDF4 (Unidata's netCDF-C), as the design names it; 5-8x faster than h5netcdf
#: on the project's datasets with files of the same size (``benchmarks/netcdf_engines.py``), and
#: either engine reads the other's files (NetCDF-4/HDF5 both).
NETCDF_ENGINE = "netcdf4"


def write_netcdf(ds, path):
    """Write a result to ``path`` atomically (NetCDF-4, :data:`NETCDF_ENGINE`), with its SHA-256 recorded beside it
    (``path.sha256``, written before the rename: :mod:`icosim.io.integrity`).

    ``ds`` is a :class:`~icosim.io.dataset.DatasetDict` (xarray's dictionary form of a dataset, written with
    netCDF4 directly, without importing xarray: the same file as xarray writes) or an :class:`xarray.Dataset`."""

    if not hasattr(ds, "to_netcdf") and not isinstance(ds, DatasetDict):
        ds = DatasetDict.from_dict(ds)
    try:
        with atomic_path(path) as tmp:
            if isinstance(ds, DatasetDict):
                write_nc4(ds, tmp)
            else:
                ds.to_netcdf(tmp, engine=NETCDF_ENGINE)
            write_checksum(tmp, path)
    except (OSError, RuntimeError) as exc:
        # the netCDF library reports a full disk as "NetCDF: HDF error": say what happened, and where
        free = shutil.disk_usage(Path(path).resolve().parent).free
        if free < 2 * max(ds.nbytes, 1 << 20):
            raise OSError(
                errno.ENOSPC,
                f"could not write {path}: no space left on its file system ({free} bytes free, the dataset needs "
                f"about {ds.nbytes}); nothing was written in its place",
            ) from exc
        raise


def open_attributes(path) -> dict:
    """The global attributes of a result written by :func:`write_netcdf`, as :func:`open_dataset` gives them,
    without reading its variables (a report section that lists hundreds of panels needs only these);
    a file that fails its SHA-256 is refused as there."""
    return open_variables(path, ()).attrs


def _refuse_corrupt(path):
    if verify(path) is False:
        raise CorruptDatasetError(
            f"{path}: its SHA-256 does not match {Path(path).name}.sha256 (changed or damaged since it was written); "
            "run snakemake again to recompute it"
        )


def open_dataset(path):
    """Open a result written by :func:`write_netcdf` (loaded into memory); a file whose SHA-256 no longer
    matches the recorded one is refused (:class:`~icosim.errors.CorruptDatasetError`), never read."""
    import xarray as xr

    _refuse_corrupt(path)
    with xr.open_dataset(path, engine=NETCDF_ENGINE) as ds:
        return ds.load()


class Variables(dict):
    """Variables of a result by name, as numpy arrays, with the result's global attributes as ``attrs``
    (what a reader that wants arrays, not an :class:`xarray.Dataset`, takes from :func:`open_variables`)."""

    def __init__(self, arrays, attrs):
        super().__init__(arrays)
        self.attrs = attrs


def open_variables(path, names) -> Variables:
    """The variables ``names`` of a result (those it holds; the others are left out) and its global attributes,
    with the values and types :func:`open_dataset` gives, without importing xarray or reading
    the other variables (a figure draws a few of a panel's dozen); a file that fails its SHA-256 is refused.

    Decoded as xarray decodes the project's variables: a float's ``_FillValue`` becomes NaN, an integer stored
    for a boolean (``dtype: bool``) becomes boolean; a variable encoded otherwise (scale, offset, time units) is
    refused here rather than read differently.
    """
    import netCDF4

    _refuse_corrupt(path)
    arrays = {}
    with netCDF4.Dataset(path) as nc:
        for name in names:
            if name not in nc.variables:
                continue
            var = nc.variables[name]
            var.set_auto_maskandscale(False)
            encoding = set(var.ncattrs())
            values = np.asarray(var[...])
            if (
                encoding & {"scale_factor", "add_offset", "missing_value", "calendar"}
                or ("units" in encoding and " since " in str(var.getncattr("units")))
                or ("_FillValue" in encoding and values.dtype.kind != "f")  # xarray would make it a float
            ):
                raise ValueError(f"{path}: variable {name} is encoded beyond what open_variables decodes")
            if "_FillValue" in encoding and not np.isnan(fill := var.getncattr("_FillValue")):
                values = np.where(values == fill, np.nan, values)
            if "dtype" in encoding and var.getncattr("dtype") == "bool":
                values = values.astype(bool)
            arrays[name] = values
        attrs = {name: nc.getncattr(name) for name in nc.ncattrs()}
    return Variables(arrays, attrs)
