"""netCDF4 against h5netcdf for the project's datasets: write and read time, file size, install size.

    python benchmarks/netcdf_engines.py

Three datasets typical of the results: a stability panel (101 x 101 grid, the
float64 pass of :func:`icosim.studies.stability.datasets.stability_panel`), a pendulum run
(3000 steps x 6 series) and a claims-like dataset of strings.  Each is written
and read back ``REPEATS`` times per engine (best time kept), and read back with the
other engine to show the files are interchangeable.
"""

from __future__ import annotations

import importlib.metadata as md
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr

from icosim.studies.stability.datasets import stability_panel
from icosim.studies.stability.panels import PanelSpec

REPEATS = 5
ENGINES = ("netcdf4", "h5netcdf")


def datasets():
    spec = PanelSpec(
        figure="9",
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
        n=101,
        policy="float64",
    )
    panel = stability_panel(spec)
    t = np.linspace(0, 3, 3001)
    rng = np.random.default_rng(0)
    run = xr.Dataset(
        {n: ("t", rng.standard_normal(t.size)) for n in ("phi1", "phi2", "g_cax", "g_cay", "lambda_cax", "lambda_cay")},
        coords={"t": t},
        attrs={"method": "weighted", "diverged": 0, "t_diverged": np.nan, "unicode": "μ̄ = 1"},
    )
    runs = [f"run_{i}" for i in range(21)]
    summary = xr.Dataset(
        {"status": ("run", ["stable"] * 21), "err": ("run", rng.random(21)), "diverged": ("run", np.zeros(21, bool))},
        coords={"run": runs},
    )
    return {"stability panel": panel, "pendulum run": run, "summary": summary}


def best(fn, *args, **kwargs):
    times = []
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        fn(*args, **kwargs)
        times.append(time.perf_counter() - t0)
    return min(times)


def read(path, engine):
    with xr.open_dataset(path, engine=engine) as ds:
        ds.load()


def site_size(dist) -> float:
    d = md.distribution(dist)
    paths = (Path(d.locate_file(f)) for f in d.files or [])
    return sum(p.stat().st_size for p in paths if p.exists()) / 1e6


def main():
    with tempfile.TemporaryDirectory() as tmp:
        print(f"{'dataset':<16} {'engine':<9} {'write ms':>9} {'read ms':>8} {'size kB':>8}  read by the other engine")
        for name, ds in datasets().items():
            for engine in ENGINES:
                path = Path(tmp) / f"{engine}.nc"
                w = best(ds.to_netcdf, path, engine=engine)
                r = best(read, path, engine)
                other = ENGINES[1 - ENGINES.index(engine)]
                back = xr.open_dataset(path, engine=other).load()
                same = back.identical(xr.open_dataset(path, engine=engine).load())
                print(
                    f"{name:<16} {engine:<9} {1e3 * w:9.2f} {1e3 * r:8.2f} {path.stat().st_size / 1e3:8.1f}  {'identical' if same else 'DIFFERENT'}"
                )
    print("\ninstalled size (MB):")
    for dist in ("netCDF4", "cftime", "h5netcdf", "h5py"):
        try:
            print(f"  {dist:<9} {md.version(dist):<14} {site_size(dist):6.1f}")
        except md.PackageNotFoundError:
            print(f"  {dist:<9} not installed")


if __name__ == "__main__":
    main()
