"""A ``convergence:`` configuration checked before any job runs.

The workflow calls these at parse time, so a bad value or a claim that selects
no configured curve fails with a message naming the configuration key or the
claim, not in a job after every panel has run.
"""

from __future__ import annotations

import numpy as np

from ...engine.methods import get_spec
from ...errors import ParameterError
from ...problems.linear.model import PhysicalModel
from ...verdicts import matches
from .experiment import Setup, method_attrs, step_counts
from .panels import figure_panels
from .study import Study

__all__ = ["study_from_config", "configured_curves", "check_claims_against_config"]


def study_from_config(cfg: dict, *, where: str = "convergence") -> Study:
    """The :class:`Study` a convergence configuration describes, validated.

    Cheap (no run): the workflow calls it at parse time so that a bad value
    fails before any job, with a message naming the configuration key
    (``convergence.step_sizes.H_max`` etc.).
    """
    try:
        PhysicalModel(**cfg["model"], H=1.0)
    except ParameterError as exc:
        raise ParameterError(f"{where}.model: {exc}") from None
    ic = cfg["initial_conditions"]
    for name in ("x0", "v0"):
        if not np.isfinite(ic[name]):
            raise ParameterError(f"{where}.initial_conditions.{name} must be a finite number, got {ic[name]!r}")
    if ic["x0"] == 0 and ic["v0"] == 0:
        raise ParameterError(
            f"{where}.initial_conditions: x0 and v0 are both zero, the exact solution is "
            "identically zero and Eq. (72) has no denominator; give x0 or v0 != 0"
        )
    end_time = cfg["end_time"]
    if not (np.isfinite(end_time) and end_time > 0):
        raise ParameterError(f"{where}.end_time must be a finite number > 0, got {end_time!r}")
    growth_bound = cfg["unstable"]["growth_bound"]
    if not (np.isfinite(growth_bound) and growth_bound > 1):
        raise ParameterError(f"{where}.unstable.growth_bound must be a finite number > 1, got {growth_bound!r}")
    setup = Setup(**cfg["model"], **ic, end_time=end_time, growth_bound=growth_bound)
    st = cfg["step_sizes"]
    H_min, H_max, num = st["H_min"], st["H_max"], st["num"]
    if not (0 < H_min < H_max):
        raise ParameterError(f"{where}.step_sizes: need 0 < H_min < H_max, got H_min = {H_min!r}, H_max = {H_max!r}")
    if H_max > end_time / 2:
        raise ParameterError(
            f"{where}.step_sizes.H_max = {H_max!r} must be at most {where}.end_time / 2 = "
            f"{end_time / 2!r} (at least two macro steps per run)"
        )
    if int(num) != num or num < 2:
        raise ParameterError(f"{where}.step_sizes.num must be an integer >= 2, got {num!r}")
    n_steps = step_counts(end_time, H_min, H_max, int(num))
    if n_steps.size < 2:
        raise ParameterError(
            f"{where}.step_sizes: [H_min, H_max] = [{H_min!r}, {H_max!r}] gives only the step "
            f"count(s) {n_steps.tolist()} after rounding N_total = end_time / H; widen the range"
        )
    fit = cfg.get("fit", {})
    if "min_points" in fit:
        H = end_time / n_steps
        in_decade = int(np.sum(H <= H.min() * 10 ** fit.get("decades", 1.0) * (1 + 1e-9)))
        if fit["min_points"] > in_decade:
            raise ParameterError(
                f"{where}.fit.min_points = {fit['min_points']} exceeds the {in_decade} step sizes of "
                f"{where}.step_sizes in the smallest-H window of {where}.fit.decades = {fit.get('decades', 1.0)!r}: "
                "no order could ever be decided; add step sizes (num) or widen the window"
            )
    return Study(
        setup,
        n_steps,
        spectral_policy=cfg["unstable"]["spectral_policy"],
        digits=cfg["unstable"]["digits"],
        startup_steps=cfg.get("startup_steps", 50),
    )


def configured_curves(cfg: dict) -> list:
    """The curve records (as :func:`curves` makes from the datasets) a configuration will produce.

    Built from the panel specs without running anything, so that claims can be
    matched against the configuration before any job runs.
    """
    out = []
    for fig, fig_cfg in cfg["figures"].items():
        for spec in figure_panels(str(fig), fig_cfg, cfg["k"]):
            for row, index in zip(spec.rows, spec.indices):
                attrs = method_attrs(spec.method, **row)
                rec = {
                    "figure": spec.figure,
                    "scheme": spec.scheme,
                    "decomposition": spec.decomposition,
                    "method": spec.method,
                    "panel": spec.panel,
                    "index": int(index),
                }
                rec.update({n: float(v) for n, v in spec.column.items() if n != "index"})
                rec.update({n: float(attrs.get(n, np.nan)) for n in get_spec(spec.method).coordinates})
                out += [{**rec, "k": int(k)} for k in spec.k]
    return out


def check_claims_against_config(claims, cfg: dict):
    """Every expectation of every ``convergence_order`` claim selects at least one curve the
    ``convergence`` configuration will produce (checked before any job runs)."""
    recs = configured_curves(cfg)
    configured = {r["scheme"] for r in recs}
    for claim in claims:
        if claim.check["kind"] != "convergence_order":
            continue
        select = claim.check["select"]
        named = select.get("scheme", "jacobi")
        if not set(named if isinstance(named, list) else [named]) <= configured:
            continue  # a claim about a scheme left out of the configuration: undecided (no data), no error
        for j, exp in enumerate(claim.check["expect"]):
            if not any(matches(r, {**select, "k": exp["k"]}) for r in recs):
                raise ParameterError(
                    f"claim {claim.id}: check.expect[{j}]: no configured curve matches select {select} with "
                    f"k = {exp['k']} (check figure, decomposition, method, parameters and the configured k)"
                )
