"""The answer for people (text, progress bar) and for programs (strict JSON)."""

from __future__ import annotations

import math
import sys
import time

import numpy as np

__all__ = ["Progress", "advice_records", "advice_text", "configuration_table"]


class Progress:
    """A progress bar on stderr, shown only once a scan has taken more than ``delay`` seconds and only on a terminal.

    >>> import io
    >>> p = Progress(3, stream=io.StringIO()); p(1); p(3); p.close()  # not a terminal: prints nothing
    """

    def __init__(self, total: int, *, label: str = "configurations", stream=None, delay: float = 1.0, width: int = 30):
        self.total, self.label, self.delay, self.width = total, label, delay, width
        self.stream = sys.stderr if stream is None else stream
        self.start = time.perf_counter()
        self.shown = False

    def __call__(self, done: int):
        if time.perf_counter() - self.start < self.delay or not _isatty(self.stream):
            return
        filled = int(self.width * done / max(self.total, 1))
        bar = "#" * filled + "-" * (self.width - filled)
        self.stream.write(f"\r[{bar}] {done}/{self.total} {self.label}")
        self.stream.flush()
        self.shown = True

    def close(self):
        if self.shown:
            self.stream.write("\r" + " " * (self.width + 30) + "\r")
            self.stream.flush()


def _isatty(stream) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False


def _pandas_na():
    """pandas' missing value, imported only where a table is written: ``icosim rho`` and ``map`` build the
    ``advise`` parser too, and need not pay pandas' import (about 0.15 s)."""
    import pandas as pd

    return pd.NA


def _clean(value, reason: str):
    """A JSON-safe value: non-finite floats become None, with the reason recorded."""
    if isinstance(value, (float, np.floating)):
        return (float(value), None) if math.isfinite(value) else (None, reason)
    if isinstance(value, np.integer):
        return int(value), None
    if value is None or value is _pandas_na():
        return None, reason
    return value, None


def advice_records(df) -> dict:
    """The answer as strict JSON-ready data (no NaN or infinity: ``null``, and a ``null_reasons`` entry per row)."""
    reasons = {
        "rank": "not stable",
        "rho": "no precision could compute it",
        "rho_float64_error": "float64 gave no finite value",
        "H_max": "no stable H in the range",
        "H_max_from_lo": "unstable at the range's lower end",
        "unstable_above": "stable up to the range's upper end",
        "rho_at_H_max": "no stable H in the range",
        "lr1": "no Eq. (71) form",
        "li1": "no Eq. (71) form",
    }
    rows = []
    for rec in df.to_dict(orient="records"):
        out, nulls = {}, {}
        for key, value in rec.items():
            v, why = _clean(value, reasons.get(key, "not available"))
            if isinstance(value, float) and key == "rho_float64_error" and not math.isfinite(value):
                why = "float64 could not decide (infinite estimate)"
            out[key] = v
            if v is None and why:
                nulls[key] = why
        if nulls:
            out["null_reasons"] = nulls
        rows.append(out)
    attrs = {k: v for k, v in df.attrs.items()}
    return {**_jsonable(attrs), "configurations": rows}


def _jsonable(x):
    if isinstance(x, dict):
        return {k: _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    v, _ = _clean(x, "")
    return v


def advice_text(df) -> str:
    """The answer as text: the system, its dimensionless parameters, then the configurations (stable ones ranked first)."""
    a = df.attrs
    s = a["system"]
    lines = [
        f"Two-mass system: m1 = {s['m1']:g} kg, m2 = {s['m2']:g} kg, c1 = {s['c1']:g} N/m, c2 = {s['c2']:g} N/m, "
        f"d1 = {s['d1']:g} N s/m, d2 = {s['d2']:g} N s/m"
    ]
    for p in a["dimensionless"]:
        head = f"at H = {p['H']:g} s: "
        coeff = (
            f"k1 = {p['k1']:.4g}, delta1 = {p['delta1']:.4g}, k2 = {p['k2']:.4g}, delta2 = {p['delta2']:.4g}, "
            f"am21 = {p['am21']:.4g}"
        )
        if p["eq71"] == "ok":
            lines.append(
                f"Eq. (71) {head}lr1 = {p['lr1']:.4g}, li1 = {p['li1']:.4g}, am21 = {p['am21']:.4g}, "
                f"alr21 = {p['alr21']:.4g}, ali21 = {p['ali21']:.4g}  ({coeff})"
            )
        else:
            lines.append(f"Eq. (71) has no real form: {p['eq71']}; coefficients {head}{coeff}")
    if a["per_second"]:
        ps = a["per_second"]
        lines.append(
            f"(lr1 = {ps['lr1_per_H']:.4g} 1/s * H, li1 = {ps['li1_per_H']:.4g} 1/s * H; the ratios do not depend on H)"
        )
    lines.append(f"Method parameters: {a['defaults']}.")
    return "\n".join(lines + configuration_table(df))


def configuration_table(df) -> list[str]:
    """The lines of :func:`advice_text` below the system: what was computed and how, and the ranked table."""
    a = df.attrs
    lines = []
    prec = "float64; certified in ball arithmetic (a proven enclosure of rho) where float64 cannot decide"
    if a["policy"] == "float64":
        prec = "float64 only (points float64 cannot decide are 'undecided')"
    n_stable = int(df["rank"].notna().sum())
    if a["mode"] == "point":
        lines.append(
            f"\n{len(df)} configurations at H = {a['H'][0]:g} s, {n_stable} stable, ranked by rho (smaller: a coupling "
            f"error decays faster per macro step). Precision: {prec}."
        )
        table = df[["rank", "configuration", "rho", "verdict", "decided_by"]].copy()
        table["rho"] = table["rho"].map(lambda r: f"{r:.6f}" if math.isfinite(r) else "nan")
        table["decided_by"] = table["decided_by"].map({"ball": "proof", "none": "failed"}).fillna(table["decided_by"])
        table = table.rename(columns={"decided_by": "decided by"})
    else:
        lo, hi = a["H"]
        lines.append(
            f"\n{len(df)} configurations over H in [{lo:g}, {hi:g}] s, {n_stable} stable somewhere in it, ranked: "
            "first those stable from the range's lower end, by how far up they stay stable, then those stable only "
            f"on higher intervals, by their largest stable H. Scan: {a['n_scan']} log-spaced H, then every stable/unstable "
            f"transition bracketed to a relative width of {a['rtol']:g}; stable intervals narrower than the scan "
            f"spacing can be missed. Precision: {prec}."
        )
        table = df[["rank", "configuration", "H_max", "stable_intervals", "verdict"]].copy()
        table["H_max"] = table["H_max"].map(lambda h: "-" if not np.isfinite(h) else f"{h:.6g}")
        table["stable_intervals"] = table["stable_intervals"].map(
            lambda iv: " and ".join(f"[{lo:.4g}, {hi:.4g}]" for lo, hi in iv) or "-"
        )
        table = table.rename(columns={"H_max": "largest stable H [s]", "stable_intervals": "stable for H in [s]"})
        lines.append(
            f"A largest stable H equal to {hi:g} s means stable at the range's upper end (larger H not scanned); "
            "'stable on intervals': not stable at every H below it."
        )
    na = _pandas_na()
    table["rank"] = table["rank"].map(lambda r: "-" if r is None or r is na else str(r))
    table = table.astype(str)
    widths = {c: max(len(c), *(len(v) for v in table[c])) for c in table.columns}
    left = {c: (lambda w: lambda v: f"{v:<{w}}")(widths[c]) for c in table.columns}
    lines += [line.rstrip() for line in table.to_string(index=False, justify="left", formatters=left).splitlines()]
    return lines
