"""The figure of the peers study, drawn from its system datasets (:mod:`icosim.studies.peers.study`, read back by
:mod:`icosim.studies.peers.fastest`) and never recomputed: per system, work against precision in SciMLBenchmarks'
style -- the error against the reference on the horizontal log axis, the minimum wall time on the vertical one (top
row) and the doStep calls (bottom row) -- one line per master and setting, coloured by master; the error levels
of the report's table as faint verticals.
"""

from __future__ import annotations

import matplotlib.pyplot as plt

from ..studies.peers.fastest import PEERS, runs, series_of

__all__ = ["peers_figure", "master_colour"]

_COLOURS = dict(zip(("icosim", *PEERS), ("tab:red", "tab:blue", "tab:green", "tab:purple")))
_MARKERS = ("o", "s", "D", "^", "v", "P")
_STYLES = ("-", "--", "-.", ":")


def master_colour(master: str) -> str:
    return _COLOURS.get(master, "0.4")


def peers_figure(datasets, *, title: str):
    """``datasets``: the system datasets; one column per system."""
    n = max(len(datasets), 1)
    fig, axes = plt.subplots(2, n, figsize=(5.2 * n, 7.4), layout="constrained", squeeze=False)
    handles: dict = {}
    for j, ds in enumerate(datasets):
        top, bottom = axes[0, j], axes[1, j]
        seen: dict = {}
        for series, rows in series_of(runs(ds)).items():
            master = rows[0]["master"]
            i = seen[master] = seen.get(master, -1) + 1
            rows = sorted(rows, key=lambda r: r["error"])
            style = {"color": master_colour(master), "marker": _MARKERS[i % len(_MARKERS)], "ms": 4,
                     "ls": _STYLES[i % len(_STYLES)], "label": series}  # fmt: skip
            (line,) = top.loglog([r["error"] for r in rows], [r["wall"] for r in rows], **style)
            bottom.loglog([r["error"] for r in rows], [r["do_steps"] for r in rows], **style)
            handles.setdefault(series, line)
        for ax in (top, bottom):
            for level in ds.attrs.get("levels", []):
                ax.axvline(float(level), color="0.88", lw=0.6, zorder=0)
            ax.invert_xaxis()  # smaller errors to the right: more accurate, more work
        a = ds.attrs
        top.set_title(f"{a['system_title']}, {a['t_end']:g} s", fontsize=9)
        top.set_ylabel("wall time, minimum of the timed runs (s)")
        bottom.set_ylabel("doStep calls (summed over the units)")
        bottom.set_xlabel(f"error: {a['measure']}", fontsize=8)
    if handles:
        fig.legend(list(handles.values()), list(handles), loc="outside lower center", ncol=2, fontsize=6,
                   frameon=False)  # fmt: skip
    fig.suptitle(title, fontsize=10)
    return fig
