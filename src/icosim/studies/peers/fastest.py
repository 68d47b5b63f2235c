"""The peers study's datasets (:mod:`icosim.studies.peers.study`) read back: the runs as rows, per error level each
master's fastest run and icosim's time over each peer's, and where icosim does not win with what its time and a
peer's go to -- macro steps, doSteps per macro step, time per doStep.  Reads datasets only: the figure, the report
section and the claims take the data from here and compute nothing again.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["runs", "fastest", "not_won", "cost", "series_of", "order_of", "PEERS"]

#: The masters beside icosim, in the order the study shows them.
PEERS = ("libcosim", "Ecos", "FMPy")
_TEXT = ("master", "series", "setting", "status", "interface")


def runs(ds) -> list[dict]:
    """One dict per run of a system's dataset: its text fields and every per-run number (NaN where none)."""
    names = [n for n, v in ds.data_vars.items() if v.dims == ("run",)]
    out = []
    for i in range(ds.sizes["run"]):
        row = {n: (str(ds[n].values[i]) if n in _TEXT else float(ds[n].values[i])) for n in names}
        out.append(row)
    return out


def series_of(rows: list[dict]) -> dict:
    """Series label -> its completed runs with an error, in the configured order (the figure's lines)."""
    out: dict = {}
    for r in rows:
        if r["status"] == "completed" and math.isfinite(r["error"]):
            out.setdefault(r["series"], []).append(r)
    return out


def fastest(rows: list[dict], levels) -> list[dict]:
    """Per level (largest first) that some run reaches: ``best`` master -> its fastest run with ``error <= level``,
    and ``icosim_over`` peer -> icosim's fastest time over the peer's (absent where either reaches no run)."""
    table = []
    done = [r for r in rows if r["status"] == "completed" and math.isfinite(r["error"]) and math.isfinite(r["wall"])]
    for level in sorted((float(v) for v in levels), reverse=True):
        best: dict = {}
        for r in done:
            if r["error"] <= level and (r["master"] not in best or r["wall"] < best[r["master"]]["wall"]):
                best[r["master"]] = r
        if not best:
            continue
        entry = {"level": level, "best": best, "icosim_over": {}}
        if "icosim" in best:
            entry["icosim_over"] = {m: best["icosim"]["wall"] / r["wall"] for m, r in best.items() if m != "icosim"}
        table.append(entry)
    return table


def cost(r: dict) -> dict:
    """What a run's time goes to: its macro steps, doSteps per macro step, wall time per doStep (s), and the
    probing doSteps of icosim's checks (outside the doSteps)."""
    per = r["do_steps"] / r["macro_steps"] if r["macro_steps"] > 0 else math.nan
    return {"macro_steps": r["macro_steps"], "do_steps_per_macro_step": per,
            "wall_per_do_step": r["wall"] / r["do_steps"] if r["do_steps"] > 0 else math.nan,
            "check_steps": r.get("check_steps", 0.0)}  # fmt: skip


def not_won(table: list[dict]) -> list[dict]:
    """Each level and peer where icosim's fastest run is slower than the peer's (``ratio`` > 1) or icosim reaches
    no run (``icosim`` None): the two runs and their :func:`cost`, and the ratios of icosim's cost to the peer's
    (``macro_steps``, ``do_steps_per_macro_step``, ``wall_per_do_step``: their product is the time ratio up to the
    checks' probing steps)."""
    out = []
    for e in table:
        ic = e["best"].get("icosim")
        for peer in [m for m in e["best"] if m != "icosim"]:
            p = e["best"][peer]
            ratio = e["icosim_over"].get(peer, math.inf)
            if ratio <= 1:
                continue
            item = {
                "level": e["level"],
                "peer": peer,
                "ratio": ratio,
                "peer_run": p,
                "icosim": ic,
                "peer_cost": cost(p),
            }
            if ic is not None:
                a, b = cost(ic), item["peer_cost"]
                item["icosim_cost"] = a
                item["cost_ratio"] = {k: a[k] / b[k] if b[k] else math.nan for k in
                                      ("macro_steps", "do_steps_per_macro_step", "wall_per_do_step")}  # fmt: skip
            out.append(item)
    return out


def order_of(rows: list[dict], series: str) -> tuple[np.ndarray, np.ndarray]:
    """A series' macro steps and errors, the steps increasing (the claims' order fits)."""
    picked = sorted((r["step"], r["error"]) for r in rows if r["series"] == series and r["status"] == "completed")
    return np.array([s for s, _ in picked]), np.array([e for _, e in picked])
