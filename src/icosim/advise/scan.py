"""Where a configuration is stable over an H range (scan, then bracket every transition), and the answer as a table."""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from .core import TwoMassSystem, configurations, evaluate

__all__ = [
    "stable_intervals",
    "check_settings",
    "advise",
    "configuration_row",
    "ranked",
    "settings_attrs",
    "DEFAULT_SCAN",
    "DEFAULT_RTOL",
]

#: Grid points of the first scan over an H range.
DEFAULT_SCAN = 32
#: Relative width of the bracket at which the refinement of a transition stops.
DEFAULT_RTOL = 1e-6
#: Points per refinement pass of a transition (one batched call each).
_SECTIONS = 8


def _refine(f, lo, hi, stable_lo: bool, rtol: float):
    """Shrink ``[lo, hi]`` (``f(lo)`` stable or not as ``stable_lo``, ``f(hi)`` the opposite) to ``hi/lo - 1 <= rtol``.

    Each pass evaluates ``_SECTIONS - 1`` interior points (log-spaced) in one call and keeps the
    first sub-bracket where the state changes.  Returns ``(lo, hi)`` and the number of passes.
    """
    passes = 0
    while hi / lo - 1 > rtol:
        inner = np.geomspace(lo, hi, _SECTIONS + 1)[1:-1]
        state = f(inner)
        change = np.flatnonzero(state != stable_lo)
        if change.size:
            j = change[0]
            hi = inner[j]
            lo = inner[j - 1] if j > 0 else lo
        else:
            lo = inner[-1]
        passes += 1
    return lo, hi, passes


def stable_intervals(
    system, configuration, H_lo, H_hi, *, n_scan=DEFAULT_SCAN, rtol=DEFAULT_RTOL, policy="auto", digits=128
):
    """Where ``configuration`` is stable on ``[H_lo, H_hi]``: scan, then refine every transition.

    Returns a dict: ``intervals`` (list of ``[lo, hi]``, both ends evaluated stable), ``unstable_above``
    (per interval the evaluated unstable H just above its upper end, None at ``H_hi``), the scan
    (``H``, ``rho``, ``verdict``), and ``n_undecided`` (scan points no precision decided; they count
    as not stable).
    """
    H = np.geomspace(H_lo, H_hi, n_scan)
    H[0], H[-1] = H_lo, H_hi
    ev = evaluate(system, configuration, H, policy=policy, digits=digits)
    ok = ev.stable

    def state(h):
        return evaluate(system, configuration, h, policy=policy, digits=digits).stable

    intervals, above = [], []
    start = H[0] if ok[0] else None
    for i in range(n_scan - 1):
        if ok[i] == ok[i + 1]:
            continue
        lo, hi, _ = _refine(state, H[i], H[i + 1], bool(ok[i]), rtol)
        if ok[i]:  # stable -> unstable: the interval ends at the stable side
            intervals.append([float(start), float(lo)])
            above.append(float(hi))
            start = None
        else:  # unstable -> stable: an interval starts at the stable side
            start = hi
    if start is not None:
        intervals.append([float(start), float(H[-1])])
        above.append(None)
    return {
        "intervals": intervals,
        "unstable_above": above,
        "scan": ev,
        "n_undecided": int(np.sum(ev.verdict == "undecided")),
    }


def check_settings(H, *, n_scan=DEFAULT_SCAN, rtol=DEFAULT_RTOL, policy="auto") -> np.ndarray:
    """``H`` (one macro step or an increasing range, in s) and the scan settings; returns ``H`` as an array."""
    if policy not in ("auto", "float64"):
        raise ParameterError(f"policy must be 'auto' or 'float64', got {policy!r}")
    H = np.atleast_1d(np.asarray(H, dtype=float))
    if H.size not in (1, 2) or not np.all(np.isfinite(H)) or not np.all(H > 0):
        raise ParameterError(f"H must be one macro step or a range H_LO H_HI, in s (> 0), got {H.tolist()}")
    if H.size == 2 and not H[0] < H[1]:
        raise ParameterError(f"H range must be increasing (H_LO < H_HI), got {H.tolist()}")
    if int(n_scan) != n_scan or n_scan < 2:
        raise ParameterError(f"scan must be an integer >= 2, got {n_scan!r}")
    if not 0 < rtol < 1:
        raise ParameterError(f"rtol must lie in (0, 1), got {rtol!r}")
    return H


def advise(
    system: TwoMassSystem,
    H,
    *,
    configuration_list=None,
    n_scan: int = DEFAULT_SCAN,
    rtol: float = DEFAULT_RTOL,
    policy: str = "auto",
    digits: int = 128,
    progress=None,
):
    """Every configuration of ``configuration_list`` (default :func:`~.core.configurations`) for ``system`` at macro step ``H`` or over
    ``H = (H_lo, H_hi)``: a :class:`pandas.DataFrame`, one row per configuration (its label in ``configuration``),
    stable ones ranked first.

    ``progress``, if given, is called with the number of configurations done.

    Columns at one H: ``rank`` (1, 2, ... for stable configurations, else missing), ``configuration``, ``scheme``,
    ``method``, ``index``, ``parameters``, ``decomposition``, ``k``, ``H``, ``rho``, ``rho_float64_error``,
    ``digits``, ``verdict``.  Over a range: ``rank``, the configuration's columns, ``H_max`` (largest stable H, missing
    if none), ``H_max_from_lo`` (the largest H such that every H from ``H_lo`` up to it is stable: the
    upper end of a stable interval starting at ``H_lo``; missing if ``H_lo`` is unstable), ``unstable_above`` (the evaluated unstable H just above ``H_max``; missing where ``H_max`` is the
    range's end), ``rho_at_H_max``, ``stable_intervals``, ``verdict`` (``stable`` on the whole range, ``stable
    up to H_max``, ``stable on intervals`` when not monotone, ``unstable`` everywhere, ``undecided``) and
    ``note``.  Where the system has an Eq. (71) form, ``lr1`` and ``li1`` at the row's H.
    """
    H = check_settings(H, n_scan=n_scan, rtol=rtol, policy=policy)
    configuration_list = configurations() if configuration_list is None else list(configuration_list)
    eq71 = system.dimensionless(float(H[-1]))["eq71"] == "ok"
    rows = []
    for n, s in enumerate(configuration_list, start=1):
        row = configuration_row(system, s, H, n_scan=n_scan, rtol=rtol, policy=policy, digits=digits)
        row_H = row.get("H", row.get("H_max"))
        if eq71:
            p = system.dimensionless(row_H) if row_H is not None and np.isfinite(row_H) else {}
            row["lr1"], row["li1"] = p.get("lr1"), p.get("li1")
        rows.append(row)
        if progress is not None:
            progress(n)
    df = ranked(rows, H)
    df.attrs.update(
        system=system.as_dict(),
        dimensionless=[system.dimensionless(h) for h in H],
        overdamped=list(system.overdamped),
        per_second=system.per_second() if eq71 else None,
        **settings_attrs(H, n_scan, rtol, policy, digits),
    )
    return df


def settings_attrs(H, n_scan, rtol, policy, digits) -> dict:
    """The settings of an answer, for its ``df.attrs``."""
    return {
        "H": H.tolist(),
        "mode": "point" if H.size == 1 else "range",
        "n_scan": int(n_scan) if H.size == 2 else None,
        "rtol": float(rtol) if H.size == 2 else None,
        "policy": policy,
        "digits": int(digits),
        "defaults": "those not given are 1 in the paper's dimensionless form (mu_bar = mu/H = 1, a = b = 1)",
    }


def configuration_row(system, s, H, *, n_scan=DEFAULT_SCAN, rtol=DEFAULT_RTOL, policy="auto", digits=128) -> dict:
    """One row of :func:`advise`'s table: the configuration ``s`` of ``system`` (anything :func:`~.core.evaluate`
    takes) at one macro step ``H`` (an array of one) or over the range ``H = (H_lo, H_hi)``."""
    base = {
        "configuration": s.label,
        "scheme": s.scheme,
        "method": s.method,
        "index": s.index,
        "parameters": s.parameter_text,
        "method_parameters": dict(s.params),
        "decomposition": s.decomposition,
        "k": s.k,
    }
    if H.size == 1:
        ev = evaluate(system, s, H, policy=policy, digits=digits)
        return {
            **base,
            "H": float(H[0]),
            "rho": float(ev.rho[0]),
            "rho_float64_error": float(ev.err[0]),
            "digits": int(ev.digits[0]),
            "verdict": str(ev.verdict[0]),
            "decided_by": str(ev.arithmetic[0]),
        }
    return {**base, **_range_row(system, s, H, n_scan, rtol, policy, digits)}


def ranked(rows: list, H):
    """:func:`advise`'s table from its rows: stable configurations ranked first (module :mod:`icosim.advise`), a
    ``rank`` column in front (missing for those not stable)."""
    import pandas as pd  # here: the commands that only build advise's parser need not import it

    df = pd.DataFrame(rows)
    if H.size == 1:
        order = df.assign(_s=df["verdict"] != "stable").sort_values(["_s", "rho"], kind="stable").index
    else:
        # stable from the range's lower end first, by how far up; then stable on higher intervals only
        low = df["H_max_from_lo"].astype(float)
        order = (
            df.assign(
                _a=low.isna(),
                _l=-low.fillna(0.0),
                _h=-df["H_max"].astype(float).fillna(-np.inf),
                _r=df["rho_at_H_max"].astype(float),
            )
            .sort_values(["_a", "_l", "_h", "_r"], kind="stable")
            .index
        )
        df["H_max_from_lo"] = low
        df["H_max"] = df["H_max"].astype(float)
    df = df.loc[order].reset_index(drop=True)
    stable = df["verdict"] == "stable" if H.size == 1 else df["H_max"].notna()
    df.insert(0, "rank", pd.array([i + 1 if s else None for i, s in enumerate(stable)], dtype="Int64"))
    return df


def _range_row(system, s, H, n_scan, rtol, policy, digits) -> dict:
    res = stable_intervals(system, s, H[0], H[1], n_scan=n_scan, rtol=rtol, policy=policy, digits=digits)
    iv, above = res["intervals"], res["unstable_above"]
    notes = []
    if not iv:
        verdict = "undecided" if res["n_undecided"] == n_scan else "unstable"
        H_max = above_max = rho_max = None
        notes.append(f"no stable H among {n_scan} scanned in [{H[0]:.4g}, {H[1]:.4g}] s")
    else:
        H_max, above_max = iv[-1][1], above[-1]
        rho_max = float(evaluate(system, s, H_max, policy=policy, digits=digits).rho[0])
        if len(iv) == 1 and iv[0][0] == H[0]:
            verdict = "stable" if above_max is None else "stable up to H_max"
        else:
            verdict = "stable on intervals"
            notes.append(
                "not monotone in H: stable only on "
                + ", ".join(f"[{lo:.4g}, {hi:.4g}]" for lo, hi in iv)
                + " s; H_max is the upper end of the last stable interval"
            )
        if above_max is None:
            notes.append(f"stable at the range's upper end {H[1]:.4g} s (larger H not scanned)")
    if res["n_undecided"]:
        notes.append(f"{res['n_undecided']} scanned H undecided (counted as not stable)")
    from_lo = iv[0][1] if iv and iv[0][0] == H[0] else None
    return {
        "H_max": H_max,
        "H_max_from_lo": from_lo,
        "unstable_above": above_max,
        "rho_at_H_max": rho_max,
        "stable_intervals": iv,
        "verdict": verdict,
        "note": "; ".join(notes),
    }
