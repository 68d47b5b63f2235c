"""A ``pendulum:`` configuration checked before any job runs (methods, decompositions, end time)."""

from __future__ import annotations

from ...engine.decompositions import get_decomposition
from ...engine.methods import make_method
from ...engine.schemes import get_scheme
from ...errors import ParameterError
from .conditions import check_decomposition
from .names import run_name

__all__ = ["configured_runs", "configured_schemes", "trade_plan", "run_settings", "study_methods", "RUN_KEYS"]


def configured_runs(cfg: dict) -> list:
    """``(method, decomposition, k)`` of every run of a ``pendulum:`` config, checked up front.

    Builds each method (so a parameter it does not take, or Baumgarte/weighted with
    dd, fails here naming the configuration) and checks ``t_end`` against ``H``.
    """
    H, t_end = cfg["H"], cfg["t_end"]
    n = round(t_end / H)
    if n < 1 or abs(n * H - t_end) > 1e-9 * t_end:
        raise ParameterError(f"pendulum.t_end = {t_end!r} must be a positive whole number of macro steps H = {H!r}")
    runs = []
    for i, c in enumerate(cfg["configurations"]):
        name, dec = c["method"], c["decomposition"]
        if name not in cfg["methods"]:
            raise ParameterError(
                f"pendulum.configurations[{i}]: method {name!r} has no parameters under pendulum.methods (give {name}: {{}} if it takes none)"
            )
        try:
            method = make_method(name, **cfg["methods"][name])
            method.check_decomposition(get_decomposition(dec))
            check_decomposition(dec)
        except ParameterError as exc:
            raise ParameterError(f"pendulum.configurations[{i}] ({name}, {dec}): {exc}") from None
        runs += [(name, dec, int(k)) for k in cfg["k"]]
    if len(set(runs)) != len(runs):
        raise ParameterError("pendulum.configurations lists a (method, decomposition) pair twice")
    return runs


def configured_schemes(cfg: dict) -> list:
    """The coupling schemes of a ``pendulum:`` config (``schemes``, default ``[jacobi]``), by name, checked.

    Every run of :func:`configured_runs` is made with each of them; Jacobi (the paper's)
    must be among them: the figures and the claim of Sect. 4 are about it.
    """
    names = cfg.get("schemes", ["jacobi"])
    try:
        schemes = [get_scheme(name).name for name in names]
    except ParameterError as exc:
        raise ParameterError(f"pendulum.schemes: {exc}") from None
    if "jacobi" not in schemes:
        raise ParameterError(f"pendulum.schemes must include jacobi (the paper's scheme), got {names!r}")
    return schemes


def trade_plan(cfg: dict) -> dict:
    """The speed-accuracy studies of a ``pendulum:`` config (``schemes``, ``trade``), checked up front.

    The studies run with every scheme of :func:`configured_schemes` (the Figs. 6-8 runs' schemes).

    Returns ``tolerance`` and ``adaptive`` (the studies' settings with the
    configurations whose scheme is configured), ``groups`` (``(scheme, method, decomposition)`` of every sweep and
    limit job, each over all ``k``) and ``configs`` (``(label, scheme, method,
    decomposition, k)`` of every configuration): every one of
    ``pendulum.configurations`` unless ``trade.configurations`` names a subset.  Errors
    name the key: an unknown scheme, an ``error_over_H.t_end`` that is not a
    whole number of every ``H``, a tolerance or adaptive configuration whose
    method cannot take its decomposition or that has no parameters.
    """
    trade = cfg["trade"]
    schemes = configured_schemes(cfg)
    sweep = trade["error_over_H"]
    T = sweep["t_end"]
    for H in sweep["H"]:
        n = round(T / H)
        if n < 1 or abs(n * H - T) > 1e-9 * T:
            raise ParameterError(
                f"pendulum.trade.error_over_H.t_end = {T!r} must be a whole number of macro steps of every H; H = {H!r} is not"
            )
    runs = configured_runs(cfg)
    subset = trade.get("configurations")
    if subset is not None:  # a subset of pendulum.configurations (e.g. for CI); default: all of them
        pairs = {(c["method"], c["decomposition"]) for c in cfg["configurations"]}
        for i, c in enumerate(subset):
            if (c["method"], c["decomposition"]) not in pairs:
                raise ParameterError(
                    f"pendulum.trade.configurations[{i}] ({c['method']}, {c['decomposition']}) is not one of "
                    "pendulum.configurations"
                )
        wanted = {(c["method"], c["decomposition"]) for c in subset}
        runs = [r for r in runs if (r[0], r[1]) in wanted]
    groups, configs = [], []
    for scheme in schemes:
        for method, dec, _ in runs:
            if (scheme, method, dec) not in groups:
                groups.append((scheme, method, dec))
        for method, dec, k in runs:
            configs.append((run_name(method, dec, int(k), scheme), scheme, method, dec, k))
    for key in ("tolerance", "adaptive"):
        for i, c in enumerate(trade[key]["configurations"]):
            where = f"pendulum.trade.{key}.configurations[{i}]"
            try:
                get_scheme(c.get("scheme", "jacobi"))
            except ParameterError as exc:
                raise ParameterError(f"{where}: {exc}") from None
            if c["method"] not in cfg["methods"]:
                raise ParameterError(f"{where}: method {c['method']!r} has no parameters under pendulum.methods")
            try:
                make_method(c["method"], **cfg["methods"][c["method"]]).check_decomposition(
                    get_decomposition(c["decomposition"])
                )
                check_decomposition(c["decomposition"])
            except ParameterError as exc:
                raise ParameterError(f"{where} ({c['method']}, {c['decomposition']}): {exc}") from None
    ad = trade["adaptive"]
    ctl = ad["controller"]
    if not ctl["H_min"] <= ad["H0"] <= ctl["H_max"]:
        raise ParameterError(
            f"pendulum.trade.adaptive.H0 = {ad['H0']!r} must lie in [controller.H_min, controller.H_max] = "
            f"[{ctl['H_min']!r}, {ctl['H_max']!r}]"
        )
    # the tolerance and adaptive configurations of the configured schemes only (config/jacobi_only.yaml
    # thus leaves out their Gauss-Seidel ones too)
    studies = {}
    for key in ("tolerance", "adaptive"):
        kept = [c for c in trade[key]["configurations"] if get_scheme(c.get("scheme", "jacobi")).name in schemes]
        if not kept:
            raise ParameterError(
                f"pendulum.trade.{key}.configurations: none uses a scheme of pendulum.schemes {schemes}"
            )
        studies[key] = dict(trade[key], configurations=kept)
    return {"groups": groups, "configs": configs, **studies}


#: The keys of a ``pendulum:`` configuration that a run of the speed-accuracy studies needs.
RUN_KEYS = ("model", "integrator", "sensitivities", "corrector", "divergence")


def run_settings(cfg: dict, methods=None) -> dict:
    """What a speed-accuracy job needs of a ``pendulum:`` config: :data:`RUN_KEYS` and ``methods``
    (only the parameters of the named ``methods`` when given, so that a job reruns only when they change)."""
    out = {key: cfg[key] for key in RUN_KEYS}
    out["methods"] = dict(cfg["methods"]) if methods is None else {m: cfg["methods"][m] for m in sorted(set(methods))}
    return out


def study_methods(cfg: dict, *studies) -> list:
    """The methods of the configurations of the named studies of ``trade`` (``tolerance``, ``adaptive``)."""
    return sorted({c["method"] for key in studies for c in cfg["trade"][key]["configurations"]})
