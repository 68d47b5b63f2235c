"""A ``pendulum:`` configuration checked before any job runs (methods, decompositions, end time)."""

from __future__ import annotations

from ..decompositions import get_decomposition
from ..methods import make_method
from ..model import ParameterError
from ..schemes import get_scheme

__all__ = ["configured_runs", "configured_schemes"]


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
