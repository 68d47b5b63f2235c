"""Stability plots (paper Figs. 9-20) drawn from panel datasets.

Layout as in the paper: one row per parameter set, one column per
approximation order ``k``; zoom panels near the origin get extra columns on
the right (one per ``k`` that has zooms), aligned with their rows.  Each panel
shows the spectral radius as a colour field (green stable, red unstable,
yellow at ``rho = 1``), the ``rho = 1`` boundary, and -- in the paper's style
-- optionally green dots at the stable grid points instead of the field.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from matplotlib.colors import TwoSlopeNorm
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

from ..engine.methods import parameters
from ..studies.stability.panels import format_row_label
from .grid import PANEL_TITLE, Margins, grid_axes

__all__ = ["stability_figure", "drawn_variables", "panel_layout", "row_labels", "STYLES"]

STYLES = ("field", "dots")
#: How points that are neither stable nor unstable are drawn: verdict code (icosim.engine.spectral.policy.VERDICTS)
#: -> scatter style.  Marginal: the proven enclosure of rho contains 1; undecided: nothing could be computed.
OPEN_VERDICTS = {
    2: {"color": "#2c7bb6", "marker": "s", "label": "marginal: the proven enclosure of ρ contains 1"},
    3: {"color": "#000000", "marker": "x", "label": "undecided: no result for the point"},
}
#: Room for the labels (inches): row labels and tick labels left, the colour bar right, the titles on
#: top, a panel's title above and its tick labels below it between rows.
MARGINS = Margins(left=0.72, right=1.1, bottom=0.42, top=0.46, wspace=0.42, hspace=0.32)
LEGEND_HEIGHT = 0.25  # inches below the grid for the legend of the open verdicts
COLORBAR = (0.25, 0.2)  # gap to the grid and width of the colour bar (inches)
#: TeX symbols of the ratios; the method parameters' come from the registry (:mod:`icosim.engine.methods`).
RATIO_SYMBOLS = {
    "am21": r"$\alpha_{m21}$",
    "alr21": r"$\alpha_{\lambda r21}$",
    "ali21": r"$\alpha_{\lambda i21}$",
}


def drawn_variables(style: str) -> tuple:
    """The panel variables :func:`stability_figure` draws in ``style`` (a reader need not load the others)."""
    return ("lr1", "li1", "rho", "verdict") + (("stable",) if style == "dots" else ())


def symbols() -> dict:
    """TeX symbols of everything a row may change: the ratios and every method parameter."""
    return {**RATIO_SYMBOLS, **{name: p.tex for name, p in parameters().items()}}


def panel_layout(panels):
    """Map each dataset to ``(row_index, column_index)`` and name the columns.

    Columns: every ``k`` of the full views in increasing order, then one
    column per ``k`` that has zoom views.  Rows follow the ``row`` attribute.
    """
    rows = sorted({int(ds.attrs["row"]) for ds in panels})
    full_k = sorted({int(ds.attrs["k"]) for ds in panels if ds.attrs["view"] == "full"})
    zoom_k = sorted({int(ds.attrs["k"]) for ds in panels if ds.attrs["view"] == "zoom"})
    columns = [("full", k) for k in full_k] + [("zoom", k) for k in zoom_k]
    place = {}
    for i, ds in enumerate(panels):
        key = (rows.index(int(ds.attrs["row"])), columns.index((ds.attrs["view"], int(ds.attrs["k"]))))
        if key in place.values():
            raise ValueError(f"two datasets for row {ds.attrs['row']}, k = {ds.attrs['k']}, view {ds.attrs['view']}")
        place[i] = key
    return rows, columns, place


def row_labels(panels) -> dict:
    """Row number -> label, from the panels' ``row_label_keys`` attribute.

    The keys are decided once, by :func:`icosim.studies.stability.panels.row_label_keys` (the rule
    the report uses as well), and stored in every panel; here they are only
    typeset with the TeX symbols.
    """
    labels = {}
    for ds in panels:
        keys = ds.attrs.get("row_label_keys")
        if not keys:
            raise ValueError(
                f"panel of figure {ds.attrs.get('figure')} row {ds.attrs.get('row')} has no row_label_keys "
                "attribute (written by icosim.studies.stability.panels.stability_panel): recompute it"
            )
        labels[int(ds.attrs["row"])] = format_row_label(keys.split(), ds.attrs, symbols())
    return labels


def _draw_panel(ax, ds, *, style, norm, cmap, dots_stride):
    lr1 = np.asarray(ds["lr1"])
    li1 = np.asarray(ds["li1"])
    rho = np.asarray(ds["rho"])
    mappable = None
    if style == "field":
        shown = np.where(np.isfinite(rho), np.minimum(rho, norm.vmax), np.nan)
        mappable = ax.pcolormesh(lr1, li1, shown.T, norm=norm, cmap=cmap, shading="nearest", rasterized=True)
    else:
        sel = (slice(None, None, dots_stride), slice(None, None, dots_stride))
        LR, LI = np.meshgrid(lr1, li1, indexing="ij")
        # always include the end points (the undamped axis lr1 = 0 and li1 = 0)
        idx_r = np.unique(np.r_[np.arange(lr1.size)[sel[0]], lr1.size - 1])
        idx_i = np.unique(np.r_[np.arange(li1.size)[sel[1]], li1.size - 1])
        sub = np.ix_(idx_r, idx_i)
        s = np.asarray(ds["stable"]).astype(bool)[sub]
        ax.scatter(LR[sub][s], LI[sub][s], s=6, facecolors="none", edgecolors="#1a9641", linewidths=0.6)
    finite = np.where(np.isfinite(rho), rho, np.inf)
    if np.nanmin(finite) < 1 < np.nanmax(finite):
        ax.contour(lr1, li1, np.minimum(finite, 1e6).T, levels=[1.0], colors="k", linewidths=0.7)
    if "verdict" in ds:  # marginal (the proven enclosure contains 1) and undecided points in their own colours
        LR, LI = np.meshgrid(lr1, li1, indexing="ij")
        verdict = np.asarray(ds["verdict"])
        for code, style_kw in OPEN_VERDICTS.items():
            sel = verdict == code
            if sel.any():
                ax.scatter(LR[sel], LI[sel], s=4, linewidths=0, clip_on=False, zorder=4, **style_kw)
    ax.set_xlim(lr1[0], lr1[-1])
    ax.set_ylim(li1[0], li1[-1])
    ax.tick_params(labelsize=6, length=2)
    return mappable


def stability_figure(
    panels,
    *,
    title: str = "",
    style: str = "field",
    rho_max: float = 2.0,
    dots_stride: int = 4,
    panel_size: float = 2.1,
) -> Figure:
    """Draw one figure of the paper from its panel datasets.

    Parameters
    ----------
    panels : the panel datasets written by :func:`icosim.studies.stability.panels.stability_panel`, each an
        :class:`xarray.Dataset` or its :func:`drawn_variables` as :func:`icosim.io.netcdf.open_variables` reads them.
    style : ``"field"`` (rho colour field and boundary) or ``"dots"`` (the
        paper's green dots at stable points, every ``dots_stride``-th grid point).
    rho_max : top of the colour scale; larger values use the top colour.
    """
    if style not in STYLES:
        raise ValueError(f"style must be one of {', '.join(STYLES)}, got {style!r}")
    if not panels:
        raise ValueError("no panels to draw")
    rows, columns, place = panel_layout(panels)
    labels = row_labels(panels)
    shown = {int(c) for ds in panels if "verdict" in ds for c in np.unique(np.asarray(ds["verdict"]))}
    handles = [
        Line2D([], [], ls="none", ms=4, color=kw["color"], marker=kw["marker"], label=kw["label"])
        for code, kw in OPEN_VERDICTS.items()
        if code in shown
    ]
    legend = LEGEND_HEIGHT if handles else 0.0
    fig = Figure(figsize=(panel_size * len(columns) + 1.2, panel_size * len(rows) + 0.7))
    margins = replace(MARGINS, bottom=MARGINS.bottom + legend)
    axes = grid_axes(fig, len(rows), len(columns), margins)
    occupied = set(place.values())
    for (i, j), ax in np.ndenumerate(axes):
        if (i, j) not in occupied:
            ax.set_axis_off()
    norm = TwoSlopeNorm(vmin=0.0, vcenter=1.0, vmax=rho_max)
    cmap = _cmap()
    mappable = None
    for n, ds in enumerate(panels):
        i, j = place[n]
        ax = axes[i, j]
        m = _draw_panel(ax, ds, style=style, norm=norm, cmap=cmap, dots_stride=dots_stride)
        mappable = mappable or m
        view, k = columns[j]
        if i == 0 or (i - 1, j) not in occupied:
            ax.set_title(f"k = {k}" + (" (zoom)" if view == "zoom" else ""), fontsize=8, **PANEL_TITLE)
        if j == 0:
            ax.set_ylabel(labels[rows[i]] + "\n" + r"$\bar\lambda_{i1}$", fontsize=7)
        if i == len(rows) - 1 or (i + 1, j) not in occupied:
            ax.set_xlabel(r"$\bar\lambda_{r1}$", fontsize=7)
    _mark_zoom_regions(panels, place, columns, axes)
    if mappable is not None:
        fig.colorbar(mappable, cax=_colorbar_axes(fig, margins), extend="max", label=r"spectral radius $\rho$")
    if handles:
        fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=7, frameon=False)
    if title:
        fig.suptitle(title, fontsize=9)
    return fig


def _colorbar_axes(fig, margins):
    """The colour bar's axes right of the grid, 60 % of its height, centred on it."""
    width, height = fig.get_size_inches()
    gap, bar = COLORBAR
    grid_h = height - margins.top - margins.bottom
    x = width - margins.right + gap
    y = margins.bottom + 0.2 * grid_h
    # labelled as matplotlib labels the colour bar axes it makes itself
    return fig.add_axes((x / width, y / height, bar / width, 0.6 * grid_h / height), label="<colorbar>")


def _mark_zoom_regions(panels, place, columns, axes):
    """Outline each zoom's region on the full panel of the same row and k."""
    full = {(ds.attrs["row"], ds.attrs["k"]): place[n] for n, ds in enumerate(panels) if ds.attrs["view"] == "full"}
    for ds in panels:
        if ds.attrs["view"] != "zoom":
            continue
        target = full.get((ds.attrs["row"], ds.attrs["k"]))
        if target is None:
            continue
        lr1, li1 = np.asarray(ds["lr1"]), np.asarray(ds["li1"])
        axes[target].add_patch(
            Rectangle(
                (lr1[0], li1[0]),
                lr1[-1] - lr1[0],
                li1[-1] - li1[0],
                fill=False,
                edgecolor="#2c7bb6",
                linewidth=0.8,
                clip_on=False,
            )
        )


def _cmap():
    from matplotlib import colormaps

    return colormaps["RdYlGn_r"].with_extremes(bad="#9e9e9e")  # grey: non-finite rho
