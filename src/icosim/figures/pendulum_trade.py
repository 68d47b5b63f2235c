"""Figures of the pendulum's speed-accuracy trade; they draw datasets and never recompute.

* :func:`work_precision_figure` -- error against CPU seconds, one panel per
  ``k`` (one row per coupling scheme) with one line per configuration (each
  point one H) and the monolithic baselines; below, adaptive against fixed H
  on the adaptive study's horizon (error against CPU seconds and against macro
  steps);
* :func:`error_over_H_figure` -- error over H per ``k`` and scheme (unstable H as crosses);
* :func:`stability_limit_figure` -- measured against predicted largest stable H, one panel per scheme;
* :func:`tolerance_figure` -- error and integration effect over the links' rtol;
* :func:`adaptive_figure` -- the adaptive step sizes over time.
"""

from __future__ import annotations

import numpy as np

from ..engine.methods import METHODS
from ..engine.schemes import get_scheme
from .styles import decomposition_style, method_colour

__all__ = [
    "TRADE_FIGURES",
    "work_precision_figure",
    "error_over_H_figure",
    "stability_limit_figure",
    "tolerance_figure",
    "adaptive_figure",
]

_MONO = {"Radau": ("black", "s"), "DOP853": ("0.5", "D")}


def _label(method, decomposition, k=None, scheme="jacobi"):
    spec = METHODS.get(method)
    text = f"{spec.label if spec else method} {decomposition}"
    text = text if k is None else f"{text} k={k}"
    return text if get_scheme(scheme).name == "jacobi" else f"{text}, {get_scheme(scheme).label}"


def _scheme(row) -> str:
    return str(row["scheme"].values) if "scheme" in row.coords else "jacobi"


def _schemes(ds) -> list:
    """The coupling schemes of a dataset's configurations, in order (Jacobi for data without them)."""
    if "scheme" not in ds.coords:
        return ["jacobi"]
    return list(dict.fromkeys(str(s) for s in ds["scheme"].values))


def _rows(ds, k=None, scheme=None):
    for i in range(ds.sizes["config"]):
        row = ds.isel(config=i)
        if (k is None or int(row["k"]) == k) and (scheme is None or _scheme(row) == scheme):
            yield row, str(row["method"].values), str(row["decomposition"].values)


def _mono_lines(ax, wp, x="cpu_seconds"):
    for integ in wp["integrator"].values:
        colour, marker = _MONO.get(str(integ), ("k", "o"))
        sel = wp.sel(integrator=integ)
        ax.loglog(
            sel[f"monolithic_{x}"].values,
            sel["monolithic_error_max"].values,
            color=colour,
            marker=marker,
            ms=4,
            lw=1.4,
            label=f"monolithic {integ} (over tol)",
        )


def work_precision_figure(wp, adaptive, *, title=None):
    """Error against CPU seconds per ``k`` and the monolithic baselines; adaptive against fixed H below."""
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    ks = sorted({int(k) for k in wp["k"].values})
    schemes = _schemes(wp)
    ns = len(schemes)
    fig = Figure(figsize=(4.6 * max(3, len(ks)), 4.75 * (ns + 1)), layout="constrained")
    axes = fig.subplots(ns + 1, max(3, len(ks)), squeeze=False)
    for ax, k, scheme in [(axes[r, j], k, scheme) for r, scheme in enumerate(schemes) for j, k in enumerate(ks)]:
        for row, m, d in _rows(wp, k, scheme):
            ok = row["status"].values == "stable"
            ax.loglog(
                row["cpu_seconds"].values[ok],
                row["error_max"].values[ok],
                ls=decomposition_style(d)[0],
                marker=decomposition_style(d)[1],
                ms=3,
                color=method_colour(m),
                label=_label(m, d),
            )
        _mono_lines(ax, wp)
        ax.set_title(
            f"{get_scheme(scheme).label}, k = {k}\n(each point one H, T = {wp.attrs.get('t_end', float('nan')):g} s)"
        )
        ax.xaxis.set_minor_formatter(NullFormatter())  # decade labels only: the minor ones overlap
        ax.set_xlabel("CPU seconds")
        ax.set_ylabel(r"max error of $\varphi_1, \varphi_2$ [rad]")
        ax.grid(True, which="major", alpha=0.3)
    handles, labels = axes[0, 0].get_legend_handles_labels()
    for r in range(ns):
        for j in range(len(ks), axes.shape[1]):
            axes[r, j].set_axis_off()
    for col, (x, xlabel) in enumerate((("cpu_seconds", "CPU seconds"), ("n_macro_steps", "macro steps"))):
        ax = axes[ns, col]
        for i in range(adaptive.sizes["config"]):
            row = adaptive.isel(config=i)
            m, d, k = str(row["method"].values), str(row["decomposition"].values), int(row["k"])
            colour = method_colour(m)
            lab = _label(m, d, k, _scheme(row))
            gs = _scheme(row) != "jacobi"  # a Gauss-Seidel configuration: open markers
            ok = row["fixed_status"].values == "stable"
            ax.loglog(
                row[f"fixed_{x}"].values[ok],
                row["fixed_error_max"].values[ok],
                color=colour,
                marker="o",
                ms=4,
                mfc="none" if gs else colour,
                ls="-",
                label=f"{lab}: fixed H",
            )
            ok = row["status"].values == "stable"
            xs = row[x].values[ok]
            if x == "n_macro_steps":
                xs = xs + row["n_rejected_macro_steps"].values[ok]  # attempts, rejected ones included
            ax.loglog(
                xs,
                row["error_max"].values[ok],
                color=colour,
                marker="^",
                ms=6,
                mfc="none" if gs else colour,
                ls="--",
                label=f"{lab}: adaptive",
            )
        ax.xaxis.set_minor_formatter(NullFormatter())  # decade labels only: the minor ones overlap
        ax.set_xlabel(xlabel + (" (accepted + rejected for adaptive)" if x == "n_macro_steps" else ""))
        ax.set_ylabel(r"max error [rad]")
        ax.set_title(f"adaptive against fixed H, T = {adaptive.attrs.get('t_end', float('nan')):g} s")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize="x-small")
    axes[ns, 2].set_axis_off()
    axes[ns, 2].legend(handles, labels, loc="center", fontsize="small", title="upper rows")
    fig.suptitle(title or "Double pendulum: work-precision (co-simulation and monolithic)")
    return fig


def error_over_H_figure(wp, *, title=None):
    """``error_max`` over ``H`` per ``k``; unstable step sizes as crosses on the upper edge."""
    from matplotlib.figure import Figure

    ks = sorted({int(k) for k in wp["k"].values})
    schemes = _schemes(wp)
    fig = Figure(figsize=(4.6 * len(ks), 5.2 * len(schemes)), layout="constrained")
    grid = fig.subplots(len(schemes), len(ks), squeeze=False, sharey=True)
    H = wp["H"].values
    finite = wp["error_max"].values[(wp["status"].values == "stable")]
    top = float(np.nanmax(finite)) * 10 if finite.size else 1.0
    panels = [(ax, k, scheme) for axes_row, scheme in zip(grid, schemes) for ax, k in zip(axes_row, ks)]
    for ax, k, scheme in panels:
        for row, m, d in _rows(wp, k, scheme):
            ok = row["status"].values == "stable"
            order = float(row["order"])
            status = str(row["order_status"].values)
            tag = f"{order:.2f}" if status == "asymptotic" else status
            ax.loglog(
                H[ok],
                row["error_max"].values[ok],
                ls=decomposition_style(d)[0],
                marker=decomposition_style(d)[1],
                ms=3,
                color=method_colour(m),
                label=f"{_label(m, d)} ({tag})",
            )
            if (~ok).any():
                ax.plot(H[~ok], np.full((~ok).sum(), top), "x", color=method_colour(m), ms=7, mew=2, clip_on=False)
        ax.set_title(f"{get_scheme(scheme).label}, k = {k}")
        ax.set_xlabel("H [s]")
        ax.grid(True, which="major", alpha=0.3)
        if ax.get_legend_handles_labels()[0]:  # a scheme may lack configurations at some k
            ax.legend(fontsize="x-small", title="order (smallest-H decade)", title_fontsize="x-small")
    for axes in grid:
        axes[0].set_ylabel(r"max error of $\varphi_1, \varphi_2$ [rad]  (x: unstable)")
    fig.suptitle(title or f"Double pendulum: error over H, T = {wp.attrs.get('t_end', float('nan')):g} s")
    return fig


def stability_limit_figure(limits, *, title=None):
    """Measured ``H_max`` against the linear test model's ``H_max_linear`` (log-log, diagonal = agreement),
    one panel per coupling scheme.

    Censored limits (stable up to the last scan point) are drawn with arrows
    pointing away from the axes; configurations without a stable step size in
    the scan are listed under the plot.
    """
    from matplotlib.figure import Figure

    schemes = _schemes(limits)
    fig = Figure(figsize=(7.5 * len(schemes), 7.0), layout="constrained")
    axes = fig.subplots(1, len(schemes), squeeze=False)[0]
    scan = np.asarray(limits.attrs.get("scan", [1e-3, 1.0]), float)
    lo, hi = scan.min() / 2, scan.max() * 2
    for ax, scheme in zip(axes, schemes):
        ax.loglog([lo, hi], [lo, hi], color="0.6", lw=1, label="measured = predicted")
        missing = []
        seen = set()
        for row, m, d in _rows(limits, scheme=scheme):
            k = int(row["k"])
            x, y = float(row["H_max_linear"]), float(row["H_max"])
            if not (np.isfinite(x) and np.isfinite(y)):
                missing.append(
                    f"{_label(m, d, k)}: measured {row['status'].values}, linear {row['status_linear'].values}"
                )
                continue
            key = (m, d)
            growth = str(row["limited_by"].values) == "growth"
            ax.plot(
                x,
                y,
                decomposition_style(d)[1],
                color=method_colour(m),
                ms=8,
                mfc=method_colour(m) if growth else "none",
                label=_label(m, d) if key not in seen else None,
            )
            seen.add(key)
            ax.annotate(f"k{k}", (x, y), textcoords="offset points", xytext=(5, 3), fontsize=7)
            if str(row["status"].values) == "stable up to the cap":
                ax.annotate("", (x, y * 1.6), (x, y), arrowprops={"arrowstyle": "->", "color": method_colour(m)})
            if str(row["status_linear"].values) == "stable up to the cap":
                ax.annotate("", (x * 1.6, y), (x, y), arrowprops={"arrowstyle": "->", "color": method_colour(m)})
        ax.set_xlim(lo, hi)
        ax.set_ylim(lo, hi)
        ax.set_title(get_scheme(scheme).label)
        ax.set_xlabel(r"predicted: largest H with a stable verdict (linear test model at the pendulum's points) [s]")
        ax.set_ylabel(f"measured: largest H without divergence over {limits.attrs.get('t_end', float('nan')):g} s [s]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(
            fontsize="small",
            title="filled: limit set by growth; open: by the |g_c| bound\n(or censored: arrow); label: k",
            title_fontsize="small",
        )
        if missing:
            ax.text(
                0.01,
                -0.14,
                "not drawn: " + "; ".join(missing),
                transform=ax.transAxes,
                fontsize=7,
                va="top",
                wrap=True,
            )
    fig.suptitle(title or "Double pendulum: stability limit in H, measured against predicted")
    return fig


def tolerance_figure(tol, *, title=None):
    """Per fixed H: ``error_max`` (solid) and the integration effect (dashed) over rtol, per configuration."""
    from matplotlib.figure import Figure

    Hs = tol["H"].values
    fig = Figure(figsize=(5.5 * len(Hs), 5.0), layout="constrained")
    axes = fig.subplots(1, len(Hs), squeeze=False, sharey=True)[0]
    floor = 1e-17
    for ax, H in zip(axes, Hs):
        for i in range(tol.sizes["config"]):
            row = tol.isel(config=i).sel(H=H)
            m, d, k = str(row["method"].values), str(row["decomposition"].values), int(row["k"])
            colour = method_colour(m)
            lab = _label(m, d, k, _scheme(row))
            ax.loglog(
                row["rtol"].values,
                row["error_max"].values,
                marker=decomposition_style(d)[1],
                color=colour,
                label=f"{lab}: error",
            )
            eff = np.maximum(row["integration_effect"].values[:-1], floor)
            ax.loglog(
                row["rtol"].values[:-1],
                eff,
                ls="--",
                marker=".",
                color=colour,
                label=f"{lab}: integration effect",
            )
        ax.invert_xaxis()
        ax.set_xlabel("rtol = atol of the links' Radau IIA")
        ax.set_title(f"H = {H:g} s")
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel(r"[rad] (integration effect $\leq$ 1e-17 drawn at 1e-17)")
    axes[-1].legend(fontsize="x-small")
    fig.suptitle(
        title or "Subsystem tolerance: error against the reference (solid) and change from the tightest rtol (dashed)"
    )
    return fig


def adaptive_figure(adaptive, *, title=None):
    """Accepted macro-step sizes over time, one panel per configuration, one line per tolerance."""
    from matplotlib.figure import Figure

    n = adaptive.sizes["config"]
    fig = Figure(figsize=(5.5 * n, 4.8), layout="constrained")
    axes = fig.subplots(1, n, squeeze=False, sharey=True)[0]
    for i, ax in enumerate(axes):
        row = adaptive.isel(config=i)
        m, d, k = str(row["method"].values), str(row["decomposition"].values), int(row["k"])
        for j, tol in enumerate(row["tol"].values):
            t, H = row["step_t"].values[j], row["step_H"].values[j]
            ok = np.isfinite(t)
            if ok.any():
                ax.semilogy(t[ok], H[ok], lw=1, label=f"tol = {tol:g} ({int(ok.sum())} steps)")
        ax.set_title(_label(m, d, k, _scheme(row)))
        ax.set_xlabel("t [s]")
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize="x-small")
    axes[0].set_ylabel("accepted macro step H [s]")
    fig.suptitle(title or "Adaptive macro steps (PI control of the predictor-corrector difference)")
    return fig


#: figure name -> function; it takes the datasets icosim.problems.pendulum.names.TRADE_FIGURE_DATASETS lists
#: for the name.  One workflow job per figure.
TRADE_FIGURES = {
    "work_precision": work_precision_figure,
    "error_over_H": error_over_H_figure,
    "stability_limit": stability_limit_figure,
    "tolerance": tolerance_figure,
    "adaptive": adaptive_figure,
}
