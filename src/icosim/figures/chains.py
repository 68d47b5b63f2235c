"""Figures of the chain study, drawn from its datasets (:mod:`icosim.studies.chains`) and never recomputed:

* :func:`chain_stability_figure` -- the largest stable macro step against the number of units, one panel per
  unit kind and pattern (rows) and method (columns), a line per scheme and ``k``;
* :func:`chain_convergence_figure` -- Eq. (72)'s error over ``H``, one panel per scheme, a line per ``N`` and ``k``;
* :func:`chain_placement_figure` -- the largest stable macro step against the place of the changed unit, one
  panel per variant, a line per method, ``k`` and scheme.
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

__all__ = ["chain_stability_figure", "chain_convergence_figure", "chain_placement_figure"]

_LINESTYLES = ("-", "--", ":")
_COLOURS = {"jacobi": "0.35", "gauss-seidel-forward": "tab:blue", "gauss-seidel-reverse": "tab:orange"}


def _colour(scheme: str) -> str:
    return _COLOURS.get(scheme, "tab:green")


def chain_stability_figure(ds, *, title: str):
    rows = [(u, p) for u in ds["unit"].values.tolist() for p in ds["pattern"].values.tolist()]
    methods = ds["method"].values.tolist()
    fig, axes = plt.subplots(
        len(rows), len(methods), figsize=(3.2 * len(methods), 2.4 * len(rows)), squeeze=False, sharex=True
    )
    N = ds["n_units"].values
    for r, (unit, pattern) in enumerate(rows):
        for c, method in enumerate(methods):
            ax = axes[r][c]
            for i, k in enumerate(ds["k"].values.tolist()):
                for scheme in ds["scheme"].values.tolist():
                    H = (
                        ds["H_max"]
                        .sel({"unit": unit, "pattern": pattern, "method": method, "k": k, "scheme": scheme})
                        .values
                    )
                    if np.isfinite(H).any():
                        ax.plot(
                            N,
                            H,
                            _LINESTYLES[i % 3],
                            marker="o",
                            ms=3,
                            color=_colour(scheme),
                            label=f"{scheme}, k = {k}",
                        )
            ax.set_xscale("log", base=2)
            ax.set_yscale("log")
            ax.set_title(f"{unit}, {pattern}, {method}", fontsize=8)
            if c == 0:
                ax.set_ylabel("largest stable H (s)", fontsize=8)
            if r == len(rows) - 1:
                ax.set_xlabel("number of units N", fontsize=8)
    handles, labels = axes[0][0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="lower center", ncol=3, fontsize=7, frameon=False)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout(rect=(0, 0.08, 1, 0.97))
    return fig


def chain_convergence_figure(ds, *, title: str):
    schemes = ds["scheme"].values.tolist()
    fig, axes = plt.subplots(1, len(schemes), figsize=(3.4 * len(schemes), 3.2), squeeze=False, sharey=True)
    H = ds["H"].values
    for c, scheme in enumerate(schemes):
        ax = axes[0][c]
        for method in ds["method"].values.tolist():
            for i, k in enumerate(ds["k"].values.tolist()):
                for j, n in enumerate(ds["n_units"].values.tolist()):
                    sel = {"n_units": n, "method": method, "k": k, "scheme": scheme}
                    order = float(ds["order"].sel(sel))
                    ax.loglog(
                        H,
                        ds["error"].sel(sel).values,
                        _LINESTYLES[j % 3],
                        marker="o",
                        ms=3,
                        color=f"C{i}",
                        label=f"N = {n}, k = {k} ({order:.2f})"
                        if len(ds["method"]) == 1
                        else f"{method}, N = {n}, k = {k}",
                    )
        ax.set_title(scheme, fontsize=9)
        ax.set_xlabel("H (s)", fontsize=8)
        if c == 0:
            ax.set_ylabel("NRMSE, Eq. (72)", fontsize=8)
        ax.legend(fontsize=6)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig


def chain_placement_figure(ds, *, title: str):
    variants = ds["variant"].values.tolist()
    fig, axes = plt.subplots(1, len(variants), figsize=(3.6 * len(variants), 3.2), squeeze=False, sharey=True)
    places = ds["position"].values.tolist()
    x = np.arange(len(places))
    for c, variant in enumerate(variants):
        ax = axes[0][c]
        for method in ds["method"].values.tolist():
            for i, k in enumerate(ds["k"].values.tolist()):
                for scheme in ds["scheme"].values.tolist():
                    H = ds["H_max"].sel({"variant": variant, "method": method, "k": k, "scheme": scheme}).values
                    ax.plot(
                        x,
                        H,
                        _LINESTYLES[i % 3],
                        marker="o",
                        ms=3,
                        color=_colour(scheme),
                        label=f"{method}, k = {k}, {scheme}",
                    )
        ax.set_xticks(x, places)
        ax.set_yscale("log")
        ax.set_title(f"{variant} unit", fontsize=9)
        ax.set_xlabel("place of the changed unit", fontsize=8)
        if c == 0:
            ax.set_ylabel("largest stable H (s)", fontsize=8)
        ax.legend(fontsize=6)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return fig
