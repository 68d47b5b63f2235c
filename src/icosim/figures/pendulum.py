"""Figs. 6-8 of the paper: the double pendulum for one approximation order k.

Six panels over time -- ``phi1``, ``phi2``, ``g_cax``, ``g_cay``,
``lambda_cax``, ``lambda_cay`` -- with one line per co-simulation
configuration and the monolithic reference.  The builders only draw the
datasets they are given.

A diverged or failed run ends at its last stored step (the datasets hold no
NaN) and is marked there with a cross (diverged) or a circle (failed: a step
could not be computed) and says so in the legend.  The y-limits of the
constraint and multiplier panels follow the runs that did *not* diverge (and
the reference), so a blow-up does not flatten the other curves; the diverged
curves are clipped at the panel edge.
"""

from __future__ import annotations

import numpy as np

from ..engine.methods import METHODS
from .styles import decomposition_style, method_colour

__all__ = ["pendulum_figure", "error_figure", "PANELS", "DRAWN_VARIABLES", "label"]

#: (variable, y label) of the six panels, in the paper's order.
PANELS = (
    ("phi1", r"$\varphi_1$ [rad]"),
    ("phi2", r"$\varphi_2$ [rad]"),
    ("g_cax", r"$g_{cax}$ [m]"),
    ("g_cay", r"$g_{cay}$ [m]"),
    ("lambda_cax", r"$\lambda_{cax}$ [N]"),
    ("lambda_cay", r"$\lambda_{cay}$ [N]"),
)
#: The variables of a run or reference dataset the figures draw (a reader need not load the others).
DRAWN_VARIABLES = ("t",) + tuple(name for name, _ in PANELS)


def label(ds) -> str:
    """Legend text of a run dataset, e.g. ``Baumgarte ff``."""
    spec = METHODS.get(ds.attrs["method"])
    return f"{spec.label if spec else ds.attrs['method']} {ds.attrs['decomposition']}"


def _limits(values, pad=0.08):
    lo = min(float(np.min(v)) for v in values)
    hi = max(float(np.max(v)) for v in values)
    if hi - lo <= 0:
        span = max(abs(hi), 1e-300)
        return lo - span, hi + span
    return lo - pad * (hi - lo), hi + pad * (hi - lo)


def pendulum_figure(runs, reference, *, k: int, title: str | None = None):
    """Figure with the six panels for the runs of one ``k`` (a list of datasets) and the reference.

    The datasets are :class:`xarray.Dataset` or their :data:`DRAWN_VARIABLES` as
    :func:`icosim.io.netcdf.open_variables` reads them (numpy arrays and the attributes).
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 10.5), layout="constrained")
    axes = fig.subplots(3, 2, sharex=True).ravel()
    stable = [ds for ds in runs if ds.attrs.get("status", "stable") == "stable"]
    for ax, (name, ylabel) in zip(axes, PANELS):
        ax.plot(reference["t"], reference[name], color="black", lw=2.6, alpha=0.35, label="monolithic reference")
        ends = []
        for ds in runs:
            m, d = ds.attrs["method"], ds.attrs["decomposition"]
            status = ds.attrs.get("status", "stable")
            lab = label(ds) + (
                f" ({status} at t = {float(ds.attrs['t_' + status]):.3f} s)" if status != "stable" else ""
            )
            ax.plot(ds["t"], ds[name], ls=decomposition_style(d)[0], color=method_colour(m), lw=1.1, label=lab)
            if status != "stable":
                marker = "x" if status == "diverged" else "o"
                ends.append((float(ds["t"][-1]), float(ds[name][-1]), method_colour(m), marker))
        if name.startswith(("g_", "lambda_")):
            basis = [np.asarray(ds[name]) for ds in stable] + [np.asarray(reference[name])]
            ax.set_ylim(*_limits(basis))
        lo, hi = ax.get_ylim()
        for t_end, value, colour, marker in ends:  # the last stored step, clipped into view
            ax.plot(t_end, min(max(value, lo), hi), marker, color=colour, ms=9, mew=2, mfc="none", clip_on=False)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if name.startswith("g_"):
            ax.ticklabel_format(axis="y", style="sci", scilimits=(-2, 2))
    for ax in axes[-2:]:
        ax.set_xlabel("t [s]")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize="small")
    fig.suptitle(title or f"Double pendulum, k = {k}")
    return fig


def error_figure(runs_by_k: dict, reference, *, title: str | None = None):
    """``|phi1 - phi1_ref|`` and ``|phi2 - phi2_ref|`` (log scale) per k: one column per k (datasets as for
    :func:`pendulum_figure`)."""
    from matplotlib.figure import Figure

    ks = sorted(runs_by_k)
    fig = Figure(figsize=(4.2 * len(ks), 6.5), layout="constrained")
    axes = fig.subplots(2, len(ks), sharex=True, sharey="row", squeeze=False)
    floor = 1e-16
    for j, k in enumerate(ks):
        for i, name in enumerate(("phi1", "phi2")):
            ax = axes[i, j]
            for ds in runs_by_k[k]:
                n = len(ds["t"])
                err = np.abs(np.asarray(ds[name]) - np.asarray(reference[name])[:n])
                m, d = ds.attrs["method"], ds.attrs["decomposition"]
                ax.semilogy(
                    ds["t"][1:],
                    np.maximum(err[1:], floor),
                    ls=decomposition_style(d)[0],
                    color=method_colour(m),
                    lw=1.0,
                    label=label(ds),
                )
            ax.grid(True, which="major", alpha=0.3)
            if j == 0:
                ax.set_ylabel(
                    rf"$|\{name[:-1]}_{name[-1]} - \{name[:-1]}_{{{name[-1]},ref}}|$ [rad]".replace("\\phi", "\\varphi")
                )
            if i == 0:
                ax.set_title(f"k = {k}")
            if i == 1:
                ax.set_xlabel("t [s]")
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncol=4, fontsize="small")
    fig.suptitle(title or "Error of the co-simulation against the monolithic reference")
    return fig
