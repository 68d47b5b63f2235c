"""The chain study as configured (``config/chains.yaml``): its unit kinds, decomposition patterns, schemes and
methods, checked before any work with errors that name the key and the values allowed.

* A **unit kind** is a list of segments (:class:`~icosim.problems.linear.chain.ChainSegment`'s parameters)
  repeated along the chain: unit ``i`` of a chain is segment ``(i - 1) mod len`` of its kind, so a kind of two
  single masses gives the paper's two-mass model for two units and alternates them for more.
* A **pattern** is decompositions joined by ``-`` and repeated over the joints: ``ff`` (every joint
  force/force), ``fd-df`` (force/displacement and displacement/force alternating).  A kinematically driven
  single mass can sit in one joint only (``docs/chains.md``, section 1), so a pattern with ``fd`` is served by
  single masses for two units only: such chains are recorded as not served, not refused.
* A **scheme** is ``jacobi``, ``gauss-seidel-forward`` (the order 1 → N) or ``gauss-seidel-reverse`` (N → 1),
  spelled for N units by :func:`scheme_name`.

>>> scheme_name("gauss-seidel-reverse", 3), scheme_name("gauss-seidel-forward", 10)
('gauss-seidel-321', 'gauss-seidel-1.2.3.4.5.6.7.8.9.10')
>>> pattern_decompositions("fd-df", 4)
('fd', 'df', 'fd')
"""

from __future__ import annotations

from ...engine.decompositions import DECOMPOSITIONS
from ...engine.methods import METHODS, make_method
from ...errors import ParameterError
from ...problems.linear.chain import Chain, ChainSegment, read_segments

__all__ = [
    "SCHEME_KINDS",
    "scheme_name",
    "pattern_decompositions",
    "unit_segments",
    "build_chain",
    "refusal",
    "method_of",
    "check_config",
]

#: The schemes of the study: the paper's Jacobi and Gauss-Seidel in the chain's order and in reverse.
SCHEME_KINDS = ("jacobi", "gauss-seidel-forward", "gauss-seidel-reverse")


def scheme_name(kind: str, n_units: int) -> str:
    """The engine's name of a scheme kind for ``n_units`` units (:mod:`icosim.engine.schemes`)."""
    if kind == "jacobi":
        return "jacobi"
    if kind not in SCHEME_KINDS:
        raise ParameterError(f"scheme must be one of {', '.join(SCHEME_KINDS)}, got {kind!r}")
    order = list(range(1, n_units + 1))
    if kind == "gauss-seidel-reverse":
        order.reverse()
    return "gauss-seidel-" + ("." if n_units >= 10 else "").join(map(str, order))


def pattern_decompositions(pattern: str, n_units: int) -> tuple[str, ...]:
    """The decompositions of the ``n_units - 1`` joints: the pattern's repeated."""
    cycle = pattern.split("-")
    return tuple(cycle[j % len(cycle)] for j in range(n_units - 1))


def unit_segments(kind: list, n_units: int) -> tuple[ChainSegment, ...]:
    """The ``n_units`` segments of a chain of the unit kind ``kind`` (a list of segment parameters)."""
    return tuple(ChainSegment(**kind[i % len(kind)]) for i in range(n_units))


def build_chain(kind: list, pattern: str, n_units: int, H) -> Chain:
    return Chain(unit_segments(kind, n_units), pattern_decompositions(pattern, n_units), H)


def refusal(kind: list, pattern: str, n_units: int) -> str | None:
    """Why the chain cannot be built (the model's refusal), or None where it can."""
    try:
        build_chain(kind, pattern, n_units, 1.0)
    except ParameterError as exc:
        return str(exc)
    return None


def method_of(methods: dict, name: str):
    """The configured method ``name`` with its parameters (``chains.methods``)."""
    return make_method(name, **methods[name])


def _fail(key, message):
    raise ParameterError(f"chains.{key}: {message}")


def _require(section, where, keys):
    if not isinstance(section, dict):
        _fail(where.rstrip(".") or "chains", "must be a mapping")
    for key in keys:
        if key not in section:
            _fail(f"{where}{key}", "is missing")
    unknown = sorted(set(section) - set(keys)) if where else []
    if unknown:
        _fail(f"{where}{unknown[0]}", f"is not a key of the study; allowed: {', '.join(keys)}")


def _check_names(key, given, allowed):
    if not isinstance(given, list) or not given:
        _fail(key, f"must be a non-empty list of {', '.join(map(str, allowed))}")
    for i, name in enumerate(given):
        if name not in allowed:
            _fail(f"{key}[{i}]", f"must be one of {', '.join(map(str, allowed))}, got {name!r}")


def _check_ints(key, given, low):
    if not isinstance(given, list) or not given:
        _fail(key, f"must be a non-empty list of integers >= {low}")
    for i, n in enumerate(given):
        if isinstance(n, bool) or not isinstance(n, int) or n < low:
            _fail(f"{key}[{i}]", f"must be an integer >= {low}, got {n!r}")


def _check_pattern(key, pattern):
    parts = pattern.split("-") if isinstance(pattern, str) else [None]
    for p in parts:
        if p not in DECOMPOSITIONS:
            _fail(key, f"must be decompositions ({', '.join(DECOMPOSITIONS)}) joined by '-', got {pattern!r}")


def check_config(cfg: dict) -> None:
    """Refuse a configuration the study cannot run, naming the key and the values allowed."""
    _require(cfg, "", ("units", "methods", "stability", "convergence", "placement", "claims"))
    _require(
        cfg["stability"],
        "stability.",
        ("n_units", "units", "patterns", "methods", "k", "schemes", "scan", "resolution"),
    )
    _require(
        cfg["convergence"],
        "convergence.",
        ("n_units", "unit", "pattern", "methods", "k", "schemes", "H", "t_end", "x0"),
    )
    _require(cfg["placement"], "placement.", ("n_units", "unit", "pattern", "variants", "methods", "k", "schemes"))
    _require(cfg["stability"]["scan"], "stability.scan.", ("min", "max", "n"))
    units = cfg["units"]
    for name, kind in units.items():
        try:
            read_segments(kind, f"units.{name}")
        except ParameterError as exc:
            raise ParameterError(f"chains.{exc}") from None
        if len({len(seg["masses"]) for seg in kind}) != 1:
            _fail(f"units.{name}", "every segment of a kind has the same number of masses")
    methods = cfg["methods"]
    for name, params in methods.items():
        if name not in METHODS:
            _fail(f"methods.{name}", f"must be one of {', '.join(METHODS)}")
        try:
            make_method(name, **params)
        except (ParameterError, TypeError) as exc:
            _fail(f"methods.{name}", str(exc))
    for part in ("stability", "convergence", "placement"):
        p = cfg[part]
        _check_names(f"{part}.methods", p["methods"], list(methods))
        _check_names(f"{part}.schemes", p["schemes"], SCHEME_KINDS)
        _check_ints(f"{part}.k", p["k"], 0)
        for i, k in enumerate(p["k"]):
            if k > 2:
                _fail(f"{part}.k[{i}]", f"must be 0, 1 or 2 (the paper's orders), got {k!r}")
    st = cfg["stability"]
    _check_ints("stability.n_units", st["n_units"], 2)
    _check_names("stability.units", st["units"], list(units))
    for i, pattern in enumerate(st["patterns"]):
        _check_pattern(f"stability.patterns[{i}]", pattern)
    cv = cfg["convergence"]
    _check_ints("convergence.n_units", cv["n_units"], 2)
    if 2 not in cv["n_units"]:
        _fail("convergence.n_units", "must include 2 (the two-unit case the chains are compared with)")
    _check_names("convergence.unit", [cv["unit"]], list(units))
    _check_pattern("convergence.pattern", cv["pattern"])
    for n in cv["n_units"]:
        if why := refusal(units[cv["unit"]], cv["pattern"], n):
            _fail("convergence", f"unit {cv['unit']!r}, pattern {cv['pattern']!r}, {n} units: {why}")
    pl = cfg["placement"]
    _check_ints("placement.n_units", [pl["n_units"]], 3)
    _check_names("placement.unit", [pl["unit"]], list(units))
    _check_pattern("placement.pattern", pl["pattern"])
    if why := refusal(units[pl["unit"]], pl["pattern"], pl["n_units"]):
        _fail("placement", f"unit {pl['unit']!r}, pattern {pl['pattern']!r}: {why}")
    for name, factors in pl["variants"].items():
        for key, f in factors.items():
            if key not in ("masses", "ground_stiffness", "ground_damping"):
                _fail(f"placement.variants.{name}", f"scales masses, ground_stiffness or ground_damping, got {key!r}")
            if isinstance(f, bool) or not isinstance(f, (int, float)) or not f > 0:
                _fail(f"placement.variants.{name}.{key}", f"must be a number > 0, got {f!r}")
