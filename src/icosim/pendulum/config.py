"""A ``pendulum:`` configuration checked before any job runs (methods, decompositions, end time)."""

from __future__ import annotations

from ..decompositions import get_decomposition
from ..methods import make_method
from ..model import ParameterError

__all__ = ["configured_runs"]


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
