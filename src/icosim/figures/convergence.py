"""Convergence plots (paper Figs. 21-23) and work-precision diagrams, drawn from datasets.

Layout as in the paper: one column per parameter set (Fig. 21: ``mu``;
Fig. 22: ``(a, b)``), one row per index, one curve per ``k``.  The NRMSE of
stable runs is drawn over ``H`` on log-log axes; a run that is unstable at
some ``H`` is drawn as an ``x`` marker pinned to the top of the panel -- never
as an error value.  The points of the smallest-H decade the order is read off
are filled, the order and its status (asymptotic or why not) are in the
legend, and dotted auxiliary lines show ``O(H^p)`` as in the paper.

The companion slope figure (:func:`slope_figure`) shows, in the same layout,
the local slopes ``d log(nrmse) / d log(H)`` over ``H``: flat where the order
is asymptotic, with the +/- tolerance band over the decade the order is read
off.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from ..engine.decompositions import DECOMPOSITIONS
from ..engine.methods import METHODS, parameters
from .grid import PANEL_TITLE, Margins, grid_axes

__all__ = [
    "convergence_figure",
    "slope_figure",
    "work_precision_figure",
    "row_title",
    "K_COLOURS",
    "DRAWN_VARIABLES",
    "WORK_PRECISION_VARIABLES",
]

#: Room for the labels of :func:`convergence_figure` and :func:`slope_figure` (inches): the y label and
#: tick labels left, the title and the panels' titles on top, tick labels, x label and legend below.
MARGINS = Margins(left=0.8, right=0.25, bottom=0.8, top=0.55, wspace=0.15, hspace=0.32)

#: The variables of a panel :func:`convergence_figure` and :func:`slope_figure` draw.
DRAWN_VARIABLES = (
    "H",
    "H_mid",
    "k",
    "index",
    "nrmse",
    "unstable",
    "fit_used",
    "order",
    "order_status",
    "local_slope",
    "fit_H_min",
    "fit_H_max",
)

#: The variables of the work-precision dataset :func:`work_precision_figure` draws.
WORK_PRECISION_VARIABLES = ("configuration", "decomposition", "k", "nrmse", "cpu_seconds_per_simulated_second")

#: How an order that is not asymptotic is shown in a legend.
STATUS_SHORT = {
    "pre-asymptotic": "pre-asymptotic",
    "unstable as H -> 0": "unstable as H→0",
    "unstable at every H": "unstable",
    "too few points": "too few points",
}


def _order_label(k, order, status) -> str:
    if status == "asymptotic":
        return f"k = {int(k)}: $p$ = {order:.2f}"
    if np.isfinite(order):
        return f"k = {int(k)}: {order:.2f}, {STATUS_SHORT.get(status, status)}"
    return f"k = {int(k)}: {STATUS_SHORT.get(status, status)}"


K_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink")


def param_label(name: str, value) -> str:
    r"""A dimensional parameter as a column title, e.g. ``$\mu$ = 0.005 s`` (symbol and unit from the registry)."""
    p = parameters().get(name)
    if p is None:
        return f"{name} = {value:g}"
    unit = {"1": "", "s": " s", "s2": " s$^2$"}[p.unit]
    return f"{p.tex_dimensional} = {value:g}{unit}"


def row_title(method: str, index: int) -> str:
    """Title of a figure row: ``index i`` for a method formulated at several indices, else its label."""
    spec = METHODS.get(method)
    return f"index {index}" if spec is None or spec.takes_index else spec.label


def _column_label(column: dict) -> str:
    return ", ".join(param_label(k, v) for k, v in column.items())


def _values(ds, name):
    """A variable of a panel as a numpy array: ``ds`` an :class:`xarray.Dataset` or the arrays of
    :func:`icosim.io.netcdf.open_variables` (what the figure job reads: only :data:`DRAWN_VARIABLES`)."""
    return np.asarray(ds[name])


def _row(ds, index):
    """The variables of a panel at the row ``index`` (the curves of one cell), by name."""
    (row,) = np.flatnonzero(_values(ds, "index") == index)
    return lambda name: _values(ds, name)[row]


def _limits(datasets):
    vals = np.concatenate([_values(ds, "nrmse").ravel() for ds in datasets])
    vals = vals[np.isfinite(vals) & (vals > 0)]
    if vals.size == 0:
        return 1e-12, 10.0
    ylo = 10 ** np.floor(np.log10(vals.min()) - 0.3)
    top = max(vals.max(), 1e-3) * 2
    # the data fill the lower 78 % of the height: the unstable markers sit above them
    return ylo, ylo * (top / ylo) ** (1 / 0.78)


def _guides(ax, H, orders, ylo, yhi):
    """Dotted O(H^p) lines from the lower-left corner, labelled where they leave the panel."""
    h0, h1 = float(np.min(H)), float(np.max(H))
    y0 = ylo * 3
    for p in orders:
        h_end = min(h1, h0 * (yhi / 3 / y0) ** (1 / p))
        hh = np.geomspace(h0, h_end, 20)
        ax.plot(hh, y0 * (hh / h0) ** p, ls=":", color="0.45", lw=0.9, zorder=1)
        ax.text(h_end, y0 * (h_end / h0) ** p, f" $H^{p}$", fontsize=7, color="0.35", va="center", ha="left")


def _draw_cell(ax, ds, index, guide_orders, ylo, yhi):
    sub = _row(ds, index)
    H = _values(ds, "H")
    for j, k in enumerate(_values(ds, "k")):
        colour = K_COLOURS[j % len(K_COLOURS)]
        err = sub("nrmse")[j]
        unstable = sub("unstable")[j].astype(bool)
        used = sub("fit_used")[j].astype(bool)
        label = _order_label(k, float(sub("order")[j]), str(sub("order_status")[j]))
        ax.plot(H, err, "-", color=colour, lw=1.2, label=label, zorder=3)
        ax.plot(H[~used], err[~used], "o", mfc="white", mec=colour, ms=3.5, zorder=4)
        ax.plot(H[used], err[used], "o", color=colour, ms=3.5, zorder=4)
        if unstable.any():  # pinned to the top of the panel, never at an error value
            ax.plot(
                H[unstable],
                np.full(unstable.sum(), 0.96 - 0.05 * j),
                "x",
                color=colour,
                ms=5,
                mew=1.4,
                transform=ax.get_xaxis_transform(),
                clip_on=False,
                zorder=5,
            )
    _guides(ax, H, guide_orders, ylo, yhi)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_ylim(ylo, yhi)
    ax.grid(True, which="major", lw=0.4, alpha=0.5)
    ax.legend(loc="lower right", fontsize=7, framealpha=0.85)


def convergence_figure(datasets: dict, layout, *, columns, rows, title="", guide_orders=(1, 2, 3, 4)):
    """One figure: ``layout[c][r] = (panel, index)`` into ``datasets[panel]``.

    ``columns`` are the column parameter dicts (titles), ``rows`` the row
    labels.
    """
    n_cols, n_rows = len(layout), len(rows)
    ylo, yhi = _limits(list(datasets.values()))
    fig = Figure(figsize=(4.0 * n_cols + 0.6, 3.2 * n_rows + 0.9))
    axes = grid_axes(fig, n_rows, n_cols, MARGINS, sharex=True, sharey=True)
    for c, col in enumerate(layout):
        for r, (panel, index) in enumerate(col):
            ax = axes[r, c]
            ds = datasets[panel]
            _draw_cell(ax, ds, index, guide_orders, ylo, yhi)
            ax.set_title(_cell_title(ds, index, rows[r], columns[c], n_cols), fontsize=9, **PANEL_TITLE)
            if r == n_rows - 1:
                ax.set_xlabel("macro-step size $H$ (s)")
            if c == 0:
                ax.set_ylabel(r"NRMSE $\varepsilon_{glo}$, Eq. (72)")
    handles = [
        Line2D([], [], ls="none", marker="o", color="0.3", label="smallest-H decade (the order is read off it)"),
        Line2D([], [], ls="none", marker="o", mfc="white", mec="0.3", label="larger H"),
        Line2D([], [], ls="none", marker="x", color="0.3", mew=1.4, label="unstable at this H (no error shown)"),
        Line2D([], [], ls=":", color="0.45", label="auxiliary lines $O(H^p)$"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=4, fontsize=8, frameon=False)
    if title:
        fig.suptitle(title, fontsize=11)
    return fig


def _cell_title(ds, index, row: str, column: dict, n_cols: int) -> str:
    head = _column_label(column)
    if ds.attrs.get("shared_across_columns") and n_cols > 1:
        head = f"{head} (index {index} does not use it)" if head else ""
    return f"{row}" + (f"; {head}" if head else "")


def _draw_slopes(ax, ds, index, tolerance):
    sub = _row(ds, index)
    H_mid = _values(ds, "H_mid")
    for j, k in enumerate(_values(ds, "k")):
        colour = K_COLOURS[j % len(K_COLOURS)]
        slope = sub("local_slope")[j]
        status = str(sub("order_status")[j])
        order = float(sub("order")[j])
        ax.plot(H_mid, slope, "o-", color=colour, ms=3, lw=1.1, label=_order_label(k, order, status), zorder=3)
        if np.isfinite(order):  # the decade the order is read off, with the tolerance band
            lo, hi = float(sub("fit_H_min")[j]), float(sub("fit_H_max")[j])
            ax.fill_between([lo, hi], order - tolerance, order + tolerance, color=colour, alpha=0.18, lw=0)
            ax.plot([lo, hi], [order, order], "--", color=colour, lw=1.0)
    ax.set_xscale("log")
    ax.grid(True, which="major", lw=0.4, alpha=0.5)
    ax.legend(loc="best", fontsize=7, framealpha=0.85)


def slope_figure(datasets: dict, layout, *, columns, rows, title="", tolerance=0.1):
    """Local slopes over ``H`` in the layout of :func:`convergence_figure`.

    Each point is the slope between two neighbouring step sizes, drawn at their
    geometric mean; the shaded band spans the smallest-H decade at the order
    +/- ``tolerance``: every point inside it means the order is asymptotic.
    """
    n_cols, n_rows = len(layout), len(rows)
    values = np.concatenate([_values(ds, "local_slope").ravel() for ds in datasets.values()])
    values = values[np.isfinite(values)]
    lo, hi = (np.floor(values.min()) - 0.5, np.ceil(values.max()) + 0.5) if values.size else (0.0, 5.0)
    fig = Figure(figsize=(4.0 * n_cols + 0.6, 3.0 * n_rows + 0.9))
    axes = grid_axes(fig, n_rows, n_cols, MARGINS, sharex=True, sharey=True)
    for c, col in enumerate(layout):
        for r, (panel, index) in enumerate(col):
            ax = axes[r, c]
            _draw_slopes(ax, datasets[panel], index, tolerance)
            ax.set_ylim(max(lo, -1.0), min(hi, 8.0))
            ax.set_title(_cell_title(datasets[panel], index, rows[r], columns[c], n_cols), fontsize=9, **PANEL_TITLE)
            if r == n_rows - 1:
                ax.set_xlabel("macro-step size $H$ (s)")
            if c == 0:
                ax.set_ylabel(r"local slope $d\log\varepsilon_{glo} / d\log H$")
    handles = [
        Line2D([], [], ls="--", color="0.3", label=f"order over the smallest-H decade (band: ± {tolerance:g})"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=1, fontsize=8, frameon=False)
    if title:
        fig.suptitle(title, fontsize=11)
    return fig


def work_precision_figure(wp, *, title=""):
    """CPU time per simulated second over NRMSE, one panel per decomposition, one line per configuration.

    ``wp``: the work-precision dataset, an :class:`xarray.Dataset` or its :data:`WORK_PRECISION_VARIABLES` as
    :func:`icosim.io.netcdf.open_variables` reads them.
    """
    v = {name: np.asarray(wp[name]) for name in WORK_PRECISION_VARIABLES}
    decs = [d for d in DECOMPOSITIONS if d in set(v["decomposition"].tolist())]
    fig = Figure(figsize=(5.2 * len(decs), 4.6), layout="constrained")
    axes = fig.subplots(1, len(decs), squeeze=False, sharey=True)[0]
    families = sorted({s.split(" k=")[0].split(" ", 1)[1] for s in v["configuration"].tolist()})
    colours = {f: f"C{i % 10}" for i, f in enumerate(families)}
    markers = ("o", "s", "^", "D", "v")
    for ax, dec in zip(axes, decs):
        for s in range(len(v["configuration"])):
            if str(v["decomposition"][s]) != dec:
                continue
            label = str(v["configuration"][s])
            err = v["nrmse"][s]
            cost = v["cpu_seconds_per_simulated_second"][s]
            ok = np.isfinite(err) & np.isfinite(cost)
            if not ok.any():
                continue
            fam = label.split(" k=")[0].split(" ", 1)[1]
            k = int(v["k"][s])
            ax.plot(
                err[ok],
                cost[ok],
                ls=("-", "--", "-.", ":")[k % 4],
                marker=markers[k % len(markers)],
                ms=3.5,
                color=colours[fam],
                label=label.split(" ", 1)[1],
            )
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.invert_xaxis()  # more accurate to the right
        ax.grid(True, lw=0.4, alpha=0.5)
        ax.set_xlabel(r"NRMSE $\varepsilon_{glo}$, Eq. (72)")
        ax.set_title(DECOMPOSITIONS[dec].long_name, fontsize=10)
        ax.legend(fontsize=6.5, loc="upper left")
    axes[0].set_ylabel("CPU time per simulated second (s)")
    if title:
        fig.suptitle(title, fontsize=11)
    return fig
