"""A result as plain data, written to NetCDF without xarray.

A job that computes a result and writes it needs no :class:`xarray.Dataset` (whose import costs a
writer process about 0.4 CPU-s): the builders return a :class:`DatasetDict`, which is xarray's
own documented dictionary form of a dataset (:meth:`xarray.Dataset.to_dict` with numpy arrays as
``data``; :meth:`xarray.Dataset.from_dict` reads it back)::

    {"coords": {name: {"dims": (...), "data": array, "attrs": {...}}},
     "attrs": {...}, "dims": {name: size},
     "data_vars": {name: {"dims": (...), "data": array, "attrs": {...}}}}

:func:`write_nc4` writes it with netCDF4 directly, as ``to_netcdf(engine="netcdf4")`` writes the
same dataset (the kinds the project writes: floats with ``_FillValue`` NaN, booleans stored as
``int8`` with ``dtype: bool``, integers, strings as variable-length strings, the ``coordinates``
attribute of non-dimension coordinates; the same variable order, dimensions, creation settings
and attributes), so every reader sees the same file; a variable of any other kind is refused.
:meth:`DatasetDict.to_xarray` gives the :class:`xarray.Dataset` to code that wants one.

>>> import numpy as np
>>> d = DatasetDict({"rho": ("x", np.array([0.5, np.nan]), {"units": "1"})},
...                 coords={"x": ("x", np.array([1, 2]))}, attrs={"title": "t"})
>>> d.dims, d.attrs["title"], list(d["data_vars"]), d["coords"]["x"]["dims"]
({'x': 2}, 't', ['rho'], ('x',))
>>> DatasetDict({"v": ("x", np.array([1j]))})
Traceback (most recent call last):
...
TypeError: variable 'v': dtype complex128 is not one write_nc4 writes (float, integer, bool, str)
"""

from __future__ import annotations

from numbers import Number

import numpy as np

__all__ = ["DatasetDict", "write_nc4"]

#: Attribute value types xarray's ``to_netcdf`` accepts (its ``_validate_attrs``), refused otherwise here too.
_ATTR_TYPES = (str, Number, np.ndarray, np.number, list, tuple, bytes)


def _entry(name, spec) -> dict:
    """One variable as ``{"dims", "data", "attrs"}`` from what :class:`xarray.Dataset` takes:
    ``(dims, values[, attrs])`` (``dims`` a name or a tuple of names) or, for a coordinate, its values."""
    if isinstance(spec, tuple):
        if len(spec) not in (2, 3):
            raise ValueError(f"variable {name!r}: give (dims, values) or (dims, values, attrs), not {len(spec)} items")
        dims, values, attrs = (*spec, {}) if len(spec) == 2 else spec
    else:
        dims, values, attrs = (name,), spec, {}
    dims = (dims,) if isinstance(dims, str) else tuple(dims)
    data = np.asarray(values)
    if data.ndim != len(dims):
        raise ValueError(f"variable {name!r}: {data.ndim}-dimensional values for the dimensions {dims}")
    if data.dtype.kind not in "fiubUO" or (
        data.dtype.kind == "O" and not all(isinstance(x, str) for x in data.ravel())
    ):
        raise TypeError(
            f"variable {name!r}: dtype {data.dtype} is not one write_nc4 writes (float, integer, bool, str)"
        )
    if data.dtype.kind == "O" and not data.size:
        raise TypeError(
            f"variable {name!r}: no values of dtype object (xarray would store float64): give a dtype, e.g. str"
        )
    return {"dims": dims, "data": data, "attrs": dict(attrs or {})}


class DatasetDict(dict):
    """xarray's dictionary form of a dataset (see the module), built from what :class:`xarray.Dataset`
    takes: ``data_vars`` and ``coords`` map names to ``(dims, values[, attrs])``, ``attrs`` are the
    global attributes; a dimension's sizes must agree across variables."""

    def __init__(self, data_vars, coords=None, attrs=None):
        data_vars = {name: _entry(name, spec) for name, spec in data_vars.items()}
        coords = {name: _entry(name, spec) for name, spec in (coords or {}).items()}
        dims = {}
        for name, var in {**data_vars, **coords}.items():
            for dim, size in zip(var["dims"], var["data"].shape, strict=True):
                if dims.setdefault(dim, size) != size:
                    raise ValueError(f"variable {name!r}: dimension {dim!r} has size {size}, elsewhere {dims[dim]}")
        super().__init__(coords=coords, attrs=dict(attrs or {}), dims=dims, data_vars=data_vars)

    @classmethod
    def from_dict(cls, d):
        """From xarray's dictionary form (``xarray.Dataset.to_dict(data="array")``), checked as above."""
        if not isinstance(d, dict) or "data_vars" not in d:
            raise TypeError(
                f"not a dataset in xarray's dictionary form (keys coords, attrs, dims, data_vars): {d!r:.80}"
            )

        def specs(group):
            return {name: (v["dims"], v["data"], v.get("attrs")) for name, v in d.get(group, {}).items()}

        return cls(specs("data_vars"), coords=specs("coords"), attrs=d.get("attrs"))

    @property
    def attrs(self) -> dict:
        return self["attrs"]

    @attrs.setter
    def attrs(self, value):
        self["attrs"] = dict(value)

    @property
    def dims(self) -> dict:
        return self["dims"]

    @property
    def sizes(self) -> dict:
        """The dimensions' sizes (as :attr:`xarray.Dataset.sizes`)."""
        return self["dims"]

    def array(self, name) -> np.ndarray:
        """The values of the data variable or coordinate ``name``."""
        for group in ("data_vars", "coords"):
            if name in self[group]:
                return self[group][name]["data"]
        raise KeyError(f"no variable {name!r}; the dataset has {sorted(self.variables())}")

    @property
    def nbytes(self) -> int:
        return sum(var["data"].nbytes for var in self.variables().values())

    def variables(self) -> dict:
        """Every variable by name, data variables first, in the order :class:`xarray.Dataset` keeps them."""
        return {**self["data_vars"], **self["coords"]}

    def to_xarray(self):
        """The same dataset as an :class:`xarray.Dataset` (imported here)."""
        import xarray as xr

        def arg(group):
            return {name: (v["dims"], v["data"], dict(v["attrs"])) for name, v in self[group].items()}

        return xr.Dataset(arg("data_vars"), coords=arg("coords"), attrs=dict(self["attrs"]))


def _check_attrs(owner, attrs):
    for key, value in attrs.items():
        if not isinstance(key, str) or not key:
            raise TypeError(f"{owner}: attribute name {key!r} is not a non-empty string")
        if isinstance(value, bool | np.bool_) or (isinstance(value, np.ndarray) and value.dtype.kind == "b"):
            raise TypeError(f"{owner}: attribute {key!r} = {value!r}: NetCDF has no boolean attributes (give 0/1)")
        if not isinstance(value, _ATTR_TYPES):
            raise TypeError(
                f"{owner}: attribute {key!r} = {value!r} is not one of " + ", ".join(t.__name__ for t in _ATTR_TYPES)
            )


def _coordinates(d: DatasetDict):
    """The ``coordinates`` attribute of each variable and the global one, as xarray's CF encoding writes them."""
    variables = d.variables()
    non_dim = {name for name in d["coords"] if name not in d.dims}
    per_var = {}
    for name, var in variables.items():
        if name in non_dim or "coordinates" in var["attrs"]:
            continue
        names = sorted(c for c in non_dim if name not in var["dims"] and set(variables[c]["dims"]) <= set(var["dims"]))
        if names:
            per_var[name] = " ".join(names)
    written = {c for var in variables.values() for c in str(var["attrs"].get("coordinates", "")).split()}
    written |= {c for text in per_var.values() for c in text.split()}
    global_names = sorted(non_dim - written)
    return per_var, (" ".join(global_names) if global_names and "coordinates" not in d.attrs else None)


def _encoded(name, var, coordinates):
    """netCDF datatype, fill value, attributes and data of a variable, as xarray encodes it."""
    attrs = dict(var["attrs"])
    data = var["data"]
    if coordinates:
        attrs["coordinates"] = coordinates
    fill = attrs.pop("_FillValue", None)
    kind = data.dtype.kind
    if kind == "f":
        fill = data.dtype.type(np.nan) if fill is None else fill
        return data.dtype, fill, attrs, data
    if kind == "b":
        attrs["dtype"] = "bool"
        return np.dtype(np.int8), fill, attrs, data.astype(np.int8)
    if kind in "iu":
        return data.dtype, fill, attrs, data
    return str, fill, attrs, data.astype(object)  # U or O of str: variable-length strings


def write_nc4(d: DatasetDict, path):
    """Write ``d`` to ``path`` (NetCDF-4) as ``d.to_xarray().to_netcdf(path, engine="netcdf4")`` writes it."""
    import netCDF4

    _check_attrs("global attributes", d.attrs)
    per_var, global_coordinates = _coordinates(d)
    encoded = {}
    for name, var in d.variables().items():
        if not isinstance(name, str) or not name or "/" in name:
            raise ValueError(f"variable name {name!r}: a non-empty string without '/'")
        _check_attrs(f"variable {name!r}", var["attrs"])
        encoded[name] = _encoded(name, var, per_var.get(name))
    with netCDF4.Dataset(path, mode="w", clobber=True, diskless=False, persist=False, format="NETCDF4") as nc:
        attrs = dict(d.attrs)
        if global_coordinates:
            attrs["coordinates"] = global_coordinates
        for key, value in attrs.items():
            if np.asarray(value).dtype.kind in "US" and np.size(value) > 1:  # a list of strings: NC_STRING
                nc.setncattr_string(key, value)
            else:
                nc.setncattr(key, value)
        for dim, size in d.dims.items():
            nc.createDimension(dim, size)
        for name, var in d.variables().items():
            datatype, fill, var_attrs, data = encoded[name]
            nc_var = nc.createVariable(
                varname=name,
                datatype=datatype,
                dimensions=var["dims"],
                zlib=False,
                complevel=4,
                shuffle=True,
                fletcher32=False,
                contiguous=False,
                chunksizes=None,
                endian="native",
                least_significant_digit=None,
                fill_value=fill,
            )
            nc_var.setncatts(var_attrs)
            nc_var.set_auto_maskandscale(False)
            nc_var.set_auto_chartostring(False)
            if data.size:
                nc_var[...] = data
