"""Stable shares of the same figure under different coupling schemes (Jacobi, Gauss-Seidel 1→2, 2→1, ...).

Reads the full-view panels of :mod:`icosim.studies.stability.panels` (attributes
``figure`` and ``scheme``) and tabulates the share of stable grid points per
figure, row, ``k`` and scheme -- what the comparison figure draws and the
report tabulates.  Nothing is recomputed.
"""

from __future__ import annotations

import numpy as np

from ...engine.schemes import SCHEMES
from ...io.dataset import DatasetDict
from .checks import stable_share

__all__ = ["scheme_shares", "scheme_shares_data"]


def scheme_shares(panels, *, provenance: dict | None = None):
    """:func:`scheme_shares_data` as an :class:`xarray.Dataset`."""
    return scheme_shares_data(panels, provenance=provenance).to_xarray()


def scheme_shares_data(panels, *, provenance: dict | None = None) -> DatasetDict:
    """A dataset (:class:`~icosim.io.dataset.DatasetDict`) ``stable_share(figure, row, k, scheme)`` from full-view panels.

    ``figure`` is the figure's id (``"9"``); ``method`` and ``decomposition`` are
    coordinates along it, ``row_label`` along ``(figure, row)``.  Missing
    combinations are NaN.  Only figures computed with more than one scheme are
    included; the schemes in registry order (:data:`icosim.engine.schemes.SCHEMES`).
    """
    full = [ds for ds in panels if ds.attrs["view"] == "full"]
    by_key, meta, row_labels = {}, {}, {}
    for ds in full:
        fig, scheme = str(ds.attrs["figure"]), str(ds.attrs["scheme"])
        key = (fig, int(ds.attrs["row"]), int(ds.attrs["k"]), scheme)
        if key in by_key:
            raise ValueError(f"two panels for figure {fig}, row {key[1]}, k = {key[2]}, scheme {key[3]}")
        share = stable_share(
            ds
        )  # stable verdicts; marginal and undecided points apart (icosim.studies.stability.checks)
        by_key[key] = (share.low, share.stable, share.n, share.open)
        meta.setdefault(fig, (str(ds.attrs["method"]), str(ds.attrs["decomposition"])))
        row_labels[(fig, key[1])] = str(ds.attrs.get("row_label", ""))
    schemes_of = {}
    for fig, _, _, scheme in by_key:
        schemes_of.setdefault(fig, set()).add(scheme)
    compared = {fig for fig, found in schemes_of.items() if len(found) > 1}
    figures = sorted(compared, key=lambda f: (not f.isdigit(), int(f) if f.isdigit() else 0, f))
    rows = sorted({r for fig, r, _, _ in by_key if fig in compared})
    ks = sorted({k for fig, _, k, _ in by_key if fig in compared})
    schemes = [s for s in SCHEMES if any(key[3] == s and key[0] in compared for key in by_key)]
    shape = (len(figures), len(rows), len(ks), len(schemes))
    share = np.full(shape, np.nan)
    n_stable = np.full(shape, -1, dtype=np.int64)
    n_points = np.full(shape, -1, dtype=np.int64)
    n_marginal = np.full(shape, -1, dtype=np.int64)
    for (fig, r, k, s), (sh, ns, n, nm) in by_key.items():
        if fig not in compared:
            continue
        idx = (figures.index(fig), rows.index(r), ks.index(k), schemes.index(s))
        share[idx], n_stable[idx], n_points[idx], n_marginal[idx] = sh, ns, n, nm
    labels = np.array([[row_labels.get((fig, r), "") for r in rows] for fig in figures], dtype=object).astype(str)
    dims = ("figure", "row", "k", "scheme")
    ds = DatasetDict(
        {
            "stable_share": (
                dims,
                share,
                {
                    "long_name": "share of stable grid points of the full panel (verdict stable: rho < 1 proven or "
                    "float64 trusted; marginal points are not counted)",
                    "units": "1",
                },
            ),
            "n_stable": (dims, n_stable, {"long_name": "stable grid points (-1: not computed)"}),
            "n_marginal": (
                dims,
                n_marginal,
                {"long_name": "marginal or undecided grid points: neither stable nor unstable (-1: not computed)"},
            ),
            "n_points": (dims, n_points, {"long_name": "grid points of the panel (-1: not computed)"}),
        },
        coords={
            "figure": ("figure", np.array(figures, dtype=object).astype(str), {"long_name": "figure"}),
            "row": ("row", np.array(rows, dtype=np.int32), {"long_name": "row of the figure (1-based)"}),
            "k": ("k", np.array(ks, dtype=np.int32), {"long_name": "degree of the approximation polynomials"}),
            "scheme": ("scheme", np.array(schemes, dtype=object).astype(str), {"long_name": "coupling scheme"}),
            "method": ("figure", np.array([meta[f][0] for f in figures], dtype=object).astype(str)),
            "decomposition": ("figure", np.array([meta[f][1] for f in figures], dtype=object).astype(str)),
            "row_label": (("figure", "row"), labels),
        },
    )
    ds.attrs = dict(provenance or {})
    ds.attrs["source_panels"] = "full views of every configured figure computed with more than one scheme"
    return ds
