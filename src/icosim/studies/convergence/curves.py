"""The convergence datasets read back: panels as one record per curve (what the claims and the report
select), the work-precision dataset as the fastest schemes per target error.

The module reads datasets only (it imports no module that runs the co-simulation): it is the
convergence study's data contract for the report."""

from __future__ import annotations

import numpy as np

from ...engine.methods import METHODS, parameters

__all__ = ["curves", "curve_label", "stable_span", "fastest_configurations"]


# --------------------------------------------------------------------------- curves and claims
def curves(datasets) -> list:
    """Flatten panel datasets into one record per curve (dict)."""
    out = []
    for ds in datasets:
        # every variable read once per dataset: a dataset lookup builds a new DataArray each time
        var = ds.variables
        values = {name: var[name].values for name in _CURVE_VARIABLES}
        params = {name: var[name].values for name in parameters() if name in ds.coords}
        head = {
            "figure": str(ds.attrs["figure"]),
            "scheme": str(ds.attrs.get("scheme", "jacobi")),
            "decomposition": ds.attrs["decomposition"],
            "method": ds.attrs["method"],
            "panel": ds.attrs["panel"],
        }
        for i, index in enumerate(values["index"]):
            for j, k in enumerate(values["k"]):
                rec = {**head, "index": int(index), "k": int(k)}
                for name in parameters():
                    if name in params:
                        rec[name] = float(params[name][i])
                    elif name in ds.attrs:
                        rec[name] = float(ds.attrs[name])
                for name in ("order", "order_spread", "fit_H_min", "fit_H_max", "order_second_half", "order_startup"):
                    rec[name] = float(values[name][i, j])
                rec["order_status"] = str(values["order_status"][i, j])
                rec["fit_note"] = str(values["fit_note"][i, j])
                rec["fit_n_points"] = int(values["fit_n_points"][i, j])
                rec["H"] = values["H"]
                rec["nrmse"] = values["nrmse"][i, j]
                rec["unstable"] = values["unstable"][i, j].astype(bool)
                rec["H_mid"] = values["H_mid"]
                rec["local_slope"] = values["local_slope"][i, j]
                out.append(rec)
    return out


#: The variables and coordinates of a panel dataset a curve record is made of.
_CURVE_VARIABLES = (
    "index",
    "k",
    "order",
    "order_spread",
    "fit_H_min",
    "fit_H_max",
    "order_second_half",
    "order_startup",
    "order_status",
    "fit_note",
    "fit_n_points",
    "H",
    "nrmse",
    "unstable",
    "H_mid",
    "local_slope",
)


def curve_label(rec) -> str:
    """E.g. ``ff, baumgarte, index 1, mu = 0.005, k = 0`` (the parameters the registry labels curves by)."""
    parts = [rec["decomposition"], rec["method"]]
    spec = METHODS.get(rec["method"])
    if spec is None or spec.takes_index:
        parts.append(f"index {rec['index']}")
    unused = spec.unused(rec["index"]) if spec else ()
    for name in spec.label_parameters if spec else ():
        if name in rec and np.isfinite(rec[name]) and name not in unused:
            parts.append(f"{name} = {rec[name]:g}")
    parts.append(f"k = {rec['k']}")
    return ", ".join(parts)


def stable_span(rec) -> str:
    """Human-readable range of H where the curve is stable."""
    H, u = rec["H"], rec["unstable"]
    if u.all():
        return "none"
    if not u.any():
        return "all"
    Hs = H[~u]
    return f"{Hs.min():.2g} to {Hs.max():.2g} s"


def fastest_configurations(wp, targets) -> list:
    """Per decomposition and target error: configurations ordered by the least CPU time reaching it.

    A configuration reaches ``target`` at the measured step sizes with
    ``nrmse <= target``; its cost is the least CPU time per simulated second
    among those.  Returns dicts ``{decomposition, target, ranking: [(label, seconds, H), ...]}``.
    """
    out = []
    for dec in sorted(set(wp["decomposition"].values.tolist())):
        sub = wp.where(wp["decomposition"] == dec, drop=True)
        for target in targets:
            ranking = []
            for s in range(sub.sizes["configuration"]):
                err = sub["nrmse"].values[s]
                cost = sub["cpu_seconds_per_simulated_second"].values[s]
                ok = np.isfinite(err) & np.isfinite(cost) & (err <= target)
                if ok.any():
                    i = np.flatnonzero(ok)[np.argmin(cost[ok])]
                    ranking.append((str(sub["configuration"].values[s]), float(cost[i]), float(sub["H"].values[i])))
            ranking.sort(key=lambda r: r[1])
            out.append({"decomposition": dec, "target": float(target), "ranking": ranking})
    return out
