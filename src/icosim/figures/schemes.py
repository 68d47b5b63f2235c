"""The coupling schemes side by side: stable shares per method, decomposition and ``k`` (one panel per figure).

Drawn from :func:`icosim.studies.stability.comparison.scheme_shares`: per panel (one
figure: a method and a decomposition) a group of bars per ``k``, one bar
per scheme (the mean stable share over the figure's rows), with each row's
share as a marker on its bar.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from ..engine.methods import METHODS
from ..engine.schemes import SCHEMES
from ..labels import figure_label
from .styles import scheme_colour

__all__ = ["scheme_comparison_figure"]

ROW_MARKERS = ("o", "s", "^", "v", "D", "P", "X")


def scheme_comparison_figure(ds, *, title: str = "", panel_size: float = 2.6) -> Figure:
    """Bars of the mean stable share per ``k`` and scheme, one panel per figure; rows as markers."""
    figures = [str(f) for f in ds["figure"].values]
    if not figures:
        raise ValueError("no figure computed with several schemes to compare")
    schemes = [str(s) for s in ds["scheme"].values]
    ks = [int(k) for k in ds["k"].values]
    ncol = min(4, len(figures))
    nrow = -(-len(figures) // ncol)
    fig = Figure(figsize=(panel_size * ncol + 0.8, panel_size * 0.85 * nrow + 1.0), layout="constrained")
    axes = fig.subplots(nrow, ncol, squeeze=False, sharey=True)
    width = 0.8 / len(schemes)
    for n, figure in enumerate(figures):
        ax = axes[n // ncol, n % ncol]
        share = ds["stable_share"].sel(figure=figure).values  # (row, k, scheme)
        for j, scheme in enumerate(schemes):
            x = np.arange(len(ks)) + (j - (len(schemes) - 1) / 2) * width
            mean = np.nanmean(share[:, :, j], axis=0)
            if np.all(np.isnan(mean)):
                continue  # a scheme this figure is not computed with
            ax.bar(x, mean, width * 0.92, color=scheme_colour(scheme), label=SCHEMES[scheme].label)
            for r in range(share.shape[0]):
                if np.all(np.isnan(share[r, :, j])):
                    continue
                ax.scatter(
                    x, share[r, :, j], s=9, marker=ROW_MARKERS[r % len(ROW_MARKERS)], color="k", linewidths=0, zorder=3
                )
        method = str(ds["method"].sel(figure=figure).values)
        label = METHODS[method].label if method in METHODS else method
        ax.set_title(f"{figure_label(figure)}: {label}, {ds['decomposition'].sel(figure=figure).values}", fontsize=8)
        ax.set_xticks(np.arange(len(ks)), [f"k = {k}" for k in ks], fontsize=7)
        ax.set_ylim(0, 1.05)
        ax.tick_params(labelsize=7)
        if n % ncol == 0:
            ax.set_ylabel("stable share", fontsize=8)
    for n in range(len(figures), nrow * ncol):
        axes[n // ncol, n % ncol].set_axis_off()
    legend = {}
    for ax in axes.flat:
        for handle, text in zip(*ax.get_legend_handles_labels()):
            legend.setdefault(text, handle)
    handles, labels = list(legend.values()), list(legend)
    rows = [int(r) for r in ds["row"].values]
    handles += [
        axes[0, 0].scatter([], [], s=9, marker=ROW_MARKERS[i % len(ROW_MARKERS)], color="k") for i in range(len(rows))
    ]
    labels += [f"row {r}" for r in rows]
    fig.legend(handles, labels, loc="outside lower center", ncol=len(labels), fontsize=7, frameon=False)
    if title:
        fig.suptitle(title, fontsize=9)
    return fig
