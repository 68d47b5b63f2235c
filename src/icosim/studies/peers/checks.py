"""The check kinds of the peers study (config/claims/peers.yaml), on its system datasets (attribute ``dataset:
system``; :mod:`icosim.studies.peers.study`).

* ``peers_order`` -- the asymptotic order over the macro step (:func:`icosim.order_fit.asymptotic_order`) of
  every fixed-step series of the ``masters`` on ``system``: pass if each is within ``tolerance`` of ``order``,
  fail if one is not, undecided if an order is not asymptotic or no such series completed;
* ``peers_agree`` -- the end values of two masters' fixed-step runs at every step both ran: pass if each
  difference is below ``value`` times the first master's error there, fail if one is not, undecided if no step
  is common.

Reads datasets only (no unit is loaded): the claims machinery imports this module.
"""

from __future__ import annotations

import math

from ...errors import ParameterError
from ...order_fit import asymptotic_order
from ...verdicts import CheckKind, Outcome, combine_holds
from .config import SYSTEMS
from .fastest import order_of, runs

__all__ = ["CHECKS", "check_order", "check_agree"]

_VERDICT = {True: "pass", False: "fail", None: "undecided"}


def _rows(datasets, system):
    return [r for ds in datasets if ds.attrs.get("dataset") == "system" and ds.attrs.get("system") == system
            for r in runs(ds)]  # fmt: skip


def _fixed_step(rows, master):
    return list(dict.fromkeys(r["series"] for r in rows if r["master"] == master and not r["tolerance"] > 0))


def check_order(datasets, *, system: str, masters: list, order: float, tolerance: float):
    """Every fixed-step series of ``masters`` on ``system``: its asymptotic order within ``tolerance`` of ``order``."""
    rows, holds, parts = _rows(datasets, system), [], []
    for master in masters:
        for series in _fixed_step(rows, master):
            steps, errors = order_of(rows, series)
            fit = asymptotic_order(steps, errors) if len(steps) else None
            if fit is None or fit.status != "asymptotic":
                ok = None
                parts.append(f"{series}: {fit.status if fit else 'no completed run'} -> undecided")
            else:
                ok = abs(fit.order - order) <= tolerance
                parts.append(f"{series}: order {fit.order:.3f} (claimed {order:g}) -> {_VERDICT[ok]}")
            holds.append(ok)
    if not holds:
        return Outcome(None, f"no fixed-step series of {', '.join(masters)} on {system}", {"rows": []})
    return Outcome(combine_holds(holds), "; ".join(parts), {"parts": parts})


def check_agree(datasets, *, system: str, masters: list, value: float):
    """The end values of ``masters[0]`` and ``masters[1]`` at every common fixed step: their difference below
    ``value`` times the first's error."""
    rows = [r for r in _rows(datasets, system) if r["status"] == "completed" and not r["tolerance"] > 0]
    a, b = ({r["step"]: r for r in rows if r["master"] == m} for m in masters)
    holds, parts = [], []
    ends = sorted({n[4:] for r in rows for n in r if n.startswith("end_")})
    for step in sorted(set(a) & set(b)):
        error = a[step]["error"]  # the system's measure of the first master's error there
        worst = max(abs(a[step][f"end_{q}"] - b[step][f"end_{q}"]) for q in ends) / error if error > 0 else math.nan
        ok = bool(worst < value) if math.isfinite(worst) else None
        parts.append(f"h = {step:g} s: largest difference / error {worst:.3g}")
        holds.append(ok)
    if not holds:
        return Outcome(None, f"no fixed step common to {masters[0]} and {masters[1]} on {system}", {})
    return Outcome(combine_holds(holds), "; ".join(parts) + f" (claimed < {value:g})", {"parts": parts})


def _validate(label, params):
    for key in ("tolerance", "value"):
        v = params.get(key)
        if key in params and (not isinstance(v, (int, float)) or isinstance(v, bool) or not v > 0):
            raise ParameterError(f"{label}: check.{key} must be a number > 0, got {v!r}")
    masters = params.get("masters")
    if not isinstance(masters, list) or not masters:
        raise ParameterError(f"{label}: check.masters must be a non-empty list of masters, got {masters!r}")
    if "value" in params and len(masters) != 2:
        raise ParameterError(f"{label}: check.masters must name two masters (peers_agree), got {masters!r}")


def _describe_order(p):
    return (f"asymptotic order over the step of the fixed-step series of {', '.join(p['masters'])} on {p['system']} "
            f"(order {p['order']:g} ± {p['tolerance']:g})", "an order lies outside the tolerance")  # fmt: skip


def _describe_agree(p):
    a, b = p["masters"]
    return (f"end values of {a} and {b} at every common fixed step on {p['system']}",
            f"a difference is not below {p['value']:g} times {a}'s error")  # fmt: skip


_SYSTEMS = tuple(SYSTEMS)
#: check kind -> :class:`~icosim.verdicts.CheckKind`, collected by :mod:`icosim.claims.registry`.
CHECKS = {
    "peers_order": CheckKind(check_order, validate=_validate, choices={"system": _SYSTEMS}, describe=_describe_order),
    "peers_agree": CheckKind(check_agree, validate=_validate, choices={"system": _SYSTEMS}, describe=_describe_agree),
}
