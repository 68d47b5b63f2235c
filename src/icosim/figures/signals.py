"""The figure of the signal-coupling study, drawn from its case datasets (:mod:`icosim.studies.signals.study`) and
never recomputed: the error against the exact solution over ``H`` (log-log), a line per case, coloured by ``k``,
the coupling by its line style; and the measured growth per macro step against the predicted spectral radius
(the diagonal: equal).
"""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.ticker import NullFormatter

__all__ = ["signals_figure"]

_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red", "tab:purple")


def _style(ds) -> str:
    a = ds.attrs
    if a["by"] == "joint":
        return "--"
    return ":" if a["scheme"] != "jacobi" else "-"


def signals_figure(cases, *, title: str):
    """``cases``: the case datasets; two panels side by side."""
    fig, (err, growth) = plt.subplots(1, 2, figsize=(9.5, 5.0), layout="constrained")
    for ds in cases:
        a = ds.attrs
        k = int(a["k"])
        error = ds["error"].values
        good = np.isfinite(error) & (error > 0)
        err.loglog(
            ds["H"].values[good],
            error[good],
            _style(ds),
            marker="o",
            ms=3,
            color=_COLOURS[k % len(_COLOURS)],
            label=f"{a['case']} (order {a['order']:.2f}, {a['order_status']})",
        )
    err.set_xlabel("macro step H (s)")
    err.set_ylabel("largest displacement error / amplitude")
    err.set_title("error against the exact solution", fontsize=9)
    err.xaxis.set_minor_formatter(NullFormatter())
    handles, labels = err.get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="outside lower center", ncol=3, fontsize=6, frameon=False)
    points = []
    for ds in cases:
        if "growth_H" not in ds.coords:
            continue
        k = int(ds.attrs["k"])
        rho, g = ds["growth_rho"].values, ds["measured_growth"].values
        growth.plot(rho, g, "o", ms=5, color=_COLOURS[k % len(_COLOURS)], mfc="none" if ds.attrs["scheme"] != "jacobi"
                    else None, label=ds.attrs["case"])  # fmt: skip
        points.extend(v for v in np.concatenate([rho, g]) if np.isfinite(v))
    if points:
        lo, hi = min(points), max(points)
        pad = 0.05 * (hi - lo or 1.0)
        growth.plot([lo - pad, hi + pad], [lo - pad, hi + pad], "-", color="0.6", lw=0.8, zorder=0)
        growth.axhline(1.0, color="0.8", lw=0.6, zorder=0)
        growth.axvline(1.0, color="0.8", lw=0.6, zorder=0)
        growth.legend(fontsize=6, loc="best")
    growth.set_xlabel("predicted spectral radius ρ")
    growth.set_ylabel("measured growth per macro step")
    growth.set_title("prediction against the run", fontsize=9)
    fig.suptitle(title, fontsize=10)
    return fig
