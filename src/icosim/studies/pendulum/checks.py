"""The ``pendulum_stability`` check kind (config/claims/pendulum.yaml) on the run summary.

>>> expected_outcome({"default": "stable", "exceptions": [
...     {"method": "weighted", "decomposition": "ff", "k": 2, "expected": "unstable"}]}, "weighted", "ff", 2)
'unstable'
>>> run_verdict("unstable", "failed")
'undecided'
"""

from __future__ import annotations

from ...engine.schemes import get_scheme
from ...errors import ParameterError
from ...problems.pendulum.names import run_name
from ...verdicts import CheckKind, Outcome, combine_holds

__all__ = ["CHECKS", "check_pendulum_stability", "expected_outcome", "run_verdict", "OUTCOMES"]


OUTCOMES = ("stable", "unstable")


def _validate_stability_check(label: str, params: dict):
    """Parameters of a ``pendulum_stability`` check (read with the claims file; errors name claim and key)."""
    try:
        get_scheme(params.get("scheme", "jacobi"))
    except ParameterError as exc:
        raise ParameterError(f"{label}: check.{exc}") from None
    if params["default"] not in OUTCOMES:
        raise ParameterError(f"{label}: check.default must be one of {list(OUTCOMES)}, got {params['default']!r}")
    exceptions = params.get("exceptions", [])
    if not isinstance(exceptions, list):
        raise ParameterError(f"{label}: check.exceptions must be a list of {{method, decomposition, k, expected}}")
    for j, ex in enumerate(exceptions):
        where = f"{label}: check.exceptions[{j}]"
        keys = {"method", "decomposition", "k", "expected"}
        if not isinstance(ex, dict) or set(ex) != keys:
            got = sorted(ex) if isinstance(ex, dict) else ex
            raise ParameterError(f"{where} must have exactly the keys {sorted(keys)}, got {got}")
        if ex["expected"] not in OUTCOMES:
            raise ParameterError(f"{where}.expected must be one of {list(OUTCOMES)}, got {ex['expected']!r}")


def expected_outcome(check: dict, method: str, decomposition: str, k: int) -> str:
    """``stable`` or ``unstable`` according to a ``pendulum_stability`` check (default and exceptions)."""
    for ex in check.get("exceptions", []):
        if ex["method"] == method and ex["decomposition"] == decomposition and int(ex["k"]) == int(k):
            return ex["expected"]
    return check["default"]


def run_verdict(expected: str, observed: str) -> str:
    """One run against the claim: a failed run (no step computed) decides nothing."""
    return "undecided" if observed == "failed" else "pass" if expected == observed else "fail"


def check_pendulum_stability(datasets, *, default: str, exceptions: list | None = None, scheme: str = "jacobi"):
    """Sect. 4: every run behaves as claimed (``default``, or its entry of ``exceptions``).

    ``datasets`` are summaries (:func:`summarize`, one row per run); only the runs
    with the coupling scheme ``scheme`` (default the paper's, Jacobi) are checked.  Fails if a
    run does not behave as claimed; otherwise undecided if a run failed (no
    verdict of its own) or a configuration named in ``exceptions`` was not run;
    else passes.
    """
    check = {"default": default, "exceptions": exceptions or []}
    scheme = get_scheme(scheme).name
    numbers, holds, have = {}, [], set()
    for ds in datasets:
        schemes = ds["scheme"].values if "scheme" in ds.coords else ["jacobi"] * ds.sizes["run"]
        for m, d, k, s, observed in zip(
            ds["method"].values, ds["decomposition"].values, ds["k"].values, schemes, ds["observed"].values
        ):
            m, d, k, observed = str(m), str(d), int(k), str(observed)
            if str(s) != scheme:
                continue
            have.add((m, d, k))
            expected = expected_outcome(check, m, d, k)
            verdict = run_verdict(expected, observed)
            numbers[run_name(m, d, k, scheme)] = {"expected": expected, "observed": observed, "verdict": verdict}
            holds.append({"pass": True, "fail": False}.get(verdict))
    missing = [
        run_name(ex["method"], ex["decomposition"], ex["k"], scheme)
        for ex in check["exceptions"]
        if (ex["method"], ex["decomposition"], int(ex["k"])) not in have
    ]
    holds += [None] * len(missing)
    counts = {v: sum(n["verdict"] == v for n in numbers.values()) for v in ("pass", "fail", "undecided")}
    text = (
        f"{len(numbers)} runs: {counts['pass']} as claimed, {counts['fail']} not, {counts['undecided']} failed"
        + "".join(
            f"; {name}: expected {n['expected']}, observed {n['observed']}"
            for name, n in numbers.items()
            if n["verdict"] != "pass"
        )
        + (f"; not run: {', '.join(missing)}" if missing else "")
    )
    return Outcome(combine_holds(holds), text, {"runs": numbers, "not_run": missing})


def _describe_stability(p):
    scheme = p.get("scheme", "jacobi")
    exceptions = ", ".join(
        f"{e['method']} {e['decomposition']} k = {e['k']} {e['expected']}" for e in p.get("exceptions") or []
    )
    what = f"every {scheme} run {p['default']} up to the end time" + (f", except {exceptions}" if exceptions else "")
    return what, "a run diverges that should stay bounded, or stays bounded where it should diverge"


#: The pendulum's check kinds (collected by :mod:`icosim.claims.registry`).
CHECKS = {
    "pendulum_stability": CheckKind(check_pendulum_stability, _validate_stability_check, describe=_describe_stability)
}
