"""Stability maps on demand: any method, parameters and grid, with the pipeline's own code.

A map is a row of stability panels (one per ``k``) over a ``(lr1, li1)`` grid,
computed by :func:`icosim.studies.stability.datasets.stability_panel` from a
:class:`~icosim.studies.stability.panels.PanelSpec` and drawn by
:func:`icosim.figures.stability.stability_figure` -- the functions the
workflow's sweep and figure rules call, so a map and a figure of the report
agree point for point and look alike.  The datasets carry the pipeline's
variable names and attributes (``rho``, ``stable``, ``digits``,
``rho_float64_error`` over ``lr1``, ``li1``; ``figure = "map"``).

:func:`stable_extent` says where the stable region ends: per ``li1`` row of a
panel, the ``lr1`` intervals that are stable, as a :class:`pandas.DataFrame`.

>>> panels = map_panels("projection", {}, "ff", [0], ratios=(1, 1, 1), lr1=(-1, 0), li1=(0, 1), n=5)
>>> stable_extent(panels[0])["stable_lr1"].tolist()  # per li1 = 0, 0.25, ..., 1: projection ff k=0
[[[-0.75, -0.25]], [[-1.0, -0.25]], [[-1.0, -0.25]], [[-1.0, -0.25]], [[-1.0, -0.25]]]

Stable everywhere except the undamped axis lr1 = 0, which is marginal (rho = 1), and the point
(-1, 0), where the coupling is undefined (its linear system is singular: undecided).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd

from ..engine.decompositions import DECOMPOSITIONS
from ..engine.schemes import get_scheme
from ..engine.stages import check
from ..io.netcdf import provenance_attrs, write_netcdf
from ..studies.stability.datasets import stability_panel
from ..studies.stability.panels import RATIOS, PanelSpec, grid_axis

__all__ = ["map_specs", "map_panels", "map_figure", "stable_extent", "boundary_extent", "write_map", "FIGURE_ID"]

#: The ``figure`` attribute of a map's panels (the pipeline's are the paper's figure numbers).
FIGURE_ID = "map"


def map_specs(
    method, method_params, decomposition, ks, *, ratios, lr1, li1, n, digits=128, policy="auto", scheme="jacobi"
):
    """One :class:`PanelSpec` per ``k`` (row 1, full view) for the coupling ``scheme`` (:mod:`icosim.engine.schemes`);
    invalid input raises :class:`~icosim.errors.ParameterError` naming the parameter."""
    am21, alr21, ali21 = (float(r) for r in ratios)
    return [
        PanelSpec(
            figure=FIGURE_ID,
            row=1,
            k=int(k),
            view="full",
            method=method,
            method_params=dict(method_params),
            decomposition=decomposition,
            am21=am21,
            alr21=alr21,
            ali21=ali21,
            lr1=tuple(float(v) for v in lr1),
            li1=tuple(float(v) for v in li1),
            n=int(n),
            digits=int(digits),
            policy=policy,
            row_keys=RATIOS,
            scheme=get_scheme(scheme).name,
        )
        for k in ks
    ]


def map_panels(method, method_params, decomposition, ks, *, command: str = "", progress=None, **grid):
    """The panels of a map (one dataset per ``k``), computed as the workflow computes a figure's panels."""
    specs = map_specs(method, method_params, decomposition, ks, **grid)
    for spec in specs:  # every panel checked (method, decomposition, grid) before the first is computed
        spec.coupling_method().check_decomposition(DECOMPOSITIONS[spec.decomposition])
        check(get_scheme(spec.scheme), spec.decomposition)
        grid_axis(spec.lr1, spec.n)
        grid_axis(spec.li1, spec.n)
    out = []
    for i, spec in enumerate(specs, start=1):
        prov = provenance_attrs(spec.as_dict(), title=f"icosim stability map, k = {spec.k}", command=command)
        out.append(stability_panel(spec, provenance=prov))
        if progress is not None:
            progress(i)
    return out


def map_figure(panels, *, title: str = "", style: str = "field"):
    """The map drawn by the report's figure builder (one column per ``k``)."""
    from ..figures.stability import stability_figure

    return stability_figure(panels, title=title, style=style)


def _runs(mask, axis):
    """Contiguous runs of True in ``mask`` as ``[[axis[start], axis[end]], ...]``."""
    out, start = [], None
    for i, m in enumerate(mask):
        if m and start is None:
            start = i
        if not m and start is not None:
            out.append([float(axis[start]), float(axis[i - 1])])
            start = None
    if start is not None:
        out.append([float(axis[start]), float(axis[-1])])
    return out


def stable_extent(ds) -> pd.DataFrame:
    """Per ``li1`` row of a panel: the stable ``lr1`` intervals (grid points with ``rho <= 1``).

    Columns ``k``, ``li1``, ``stable_lr1`` (list of ``[lo, hi]``), ``n_stable``, and
    ``stable_from`` -- the least damped stable point of the row (the largest stable ``lr1``):
    where the stable region ends on the way towards the undamped axis.
    """
    lr1, li1 = ds["lr1"].values, ds["li1"].values
    stable = ds["stable"].values.astype(bool)  # (lr1, li1)
    rows = []
    for j, v in enumerate(li1):
        col = stable[:, j]
        rows.append(
            {
                "k": int(ds.attrs["k"]),
                "li1": float(v),
                "stable_lr1": _runs(col, lr1),
                "n_stable": int(col.sum()),
                "stable_from": float(lr1[np.flatnonzero(col)[-1]]) if col.any() else None,
            }
        )
    return pd.DataFrame(rows)


def _verdict_is(ds, name: str) -> np.ndarray:
    """Points of a panel with the verdict ``name`` (the ``verdict`` flag variable; ``stable`` for older panels)."""
    if "verdict" not in ds:
        s = ds["stable"].values.astype(bool)
        return s if name == "stable" else ~s if name == "unstable" else np.zeros_like(s)
    codes = dict(zip(ds["verdict"].attrs["flag_meanings"].split(), ds["verdict"].attrs["flag_values"]))
    return ds["verdict"].values == codes[name]


def _extent(mask, ds) -> dict:
    if not mask.any():
        return {"lr1": None, "li1": None, "n_points": 0}
    i, j = np.nonzero(mask)
    lr1, li1 = ds["lr1"].values, ds["li1"].values
    return {
        "lr1": [float(lr1[i].min()), float(lr1[i].max())],
        "li1": [float(li1[j].min()), float(li1[j].max())],
        "n_points": int(mask.sum()),
    }


def boundary_extent(ds) -> dict:
    """Extent of the ``rho = 1`` boundary on the grid: stable points with an unstable neighbour
    (4-neighbourhood; a marginal neighbour -- rho = 1 within the proof -- is not a crossing)."""
    s, u = _verdict_is(ds, "stable"), _verdict_is(ds, "unstable")
    edge = np.zeros_like(s)
    edge[:-1] |= s[:-1] & u[1:]
    edge[1:] |= s[1:] & u[:-1]
    edge[:, :-1] |= s[:, :-1] & u[:, 1:]
    edge[:, 1:] |= s[:, 1:] & u[:, :-1]
    return _extent(edge, ds)


def marginal_extent(ds) -> dict:
    """Extent of the marginal points (the proven enclosure of rho contains 1: e.g. rho = 1 on the undamped axis)."""
    return _extent(_verdict_is(ds, "marginal"), ds)


def write_map(panels, fig, prefix) -> list[str]:
    """Write ``<prefix>.png``, ``<prefix>.pdf`` and ``<prefix>_k<k>.nc`` per panel (atomically); returns the paths."""
    from ..figures import save_figure

    prefix = Path(prefix)
    images = [prefix.with_name(prefix.name + ".png"), prefix.with_name(prefix.name + ".pdf")]
    save_figure(fig, *images)
    paths = [str(p) for p in images]
    for ds in panels:
        path = prefix.with_name(f"{prefix.name}_k{int(ds.attrs['k'])}.nc")
        write_netcdf(ds, path)
        paths.append(str(path))
    return paths
