"""Is my chain stable?  Every configuration for a chain of linear oscillator segments joined by rigid joints.

A chain file is the mapping :meth:`~icosim.problems.linear.chain.Chain.from_dict` reads (``docs/cli.md``)::

    segments:                      # one per unit, in the chain's order; SI units
      - {masses: [1.0], ground_stiffness: [1000.0], ground_damping: [2.0]}
      - {masses: [2.0], ground_stiffness: [4000.0], ground_damping: [1.0]}
    joints: ff                     # one decomposition for every joint, or a list of one per joint

:class:`ChainSystem` answers :func:`~icosim.advise.core.evaluate` as :class:`~icosim.advise.core.TwoMassSystem` does,
with the chain's points (:class:`~icosim.problems.linear.chain.ChainFamily`); :func:`chain_configurations` lists
every method, index, ``k`` and scheme (Jacobi, Gauss-Seidel in the chain's order and in reverse, or orders named)
and, apart, those the engine refuses for the chain, with its reason; :func:`advise_chain` ranks them like
:func:`~icosim.advise.advise`.

>>> chain = Chain.from_dict({"segments": [{"masses": [1.0], "ground_stiffness": [100.0]}] * 3, "joints": "ff"})
>>> chain_scheme("gauss-seidel-reverse", chain).name, chain_scheme("2,1,3", chain).name
('gauss-seidel-321', 'gauss-seidel-213')
"""

from __future__ import annotations

import re
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from ..engine import methods as _methods
from ..engine.bounds import check_k
from ..engine.schemes import GaussSeidel, Scheme, get_scheme
from ..engine.stages import check
from ..errors import ParameterError
from ..io.yamlio import load_yaml
from ..problems.linear.chain import Chain, ChainFamily
from ..studies.chains.config import SCHEME_KINDS, scheme_name
from .core import DEFAULT_K, Configuration, index_parameters
from .output import configuration_table
from .scan import DEFAULT_RTOL, DEFAULT_SCAN, check_settings, configuration_row, ranked, settings_attrs

__all__ = [
    "ChainSystem",
    "read_chain",
    "chain_scheme",
    "chain_configurations",
    "advise_chain",
    "chain_advice_text",
    "SCHEME_KINDS",
    "UNIT_ORDER",
]

#: An order of the units: their numbers separated by commas (``3,1,2``).
UNIT_ORDER = re.compile(r"\d+(,\d+)+")


def read_chain(path) -> Chain:
    """The chain of a YAML file (module docstring); a missing or unreadable file, or a bad key, is a
    :class:`~icosim.errors.ParameterError` naming the file or the key."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ParameterError(f"chain file {str(path)!r} cannot be read: {exc.strerror or exc}") from None
    try:
        data = load_yaml(text)
    except Exception as exc:  # noqa: BLE001 -- any YAML error: the file is not a chain
        raise ParameterError(f"chain file {str(path)!r} is not valid YAML: {exc}") from None
    try:
        return Chain.from_dict(data)
    except ParameterError as exc:
        raise ParameterError(f"chain file {str(path)!r}: {exc}") from None


def chain_scheme(text: str | Scheme, chain: Chain) -> Scheme:
    """The scheme ``text`` names for ``chain``: ``jacobi``, ``gauss-seidel-forward`` (units 1 → N),
    ``gauss-seidel-reverse`` (N → 1), an order of the units separated by commas (``3,1,2``), or a scheme's name
    (:func:`icosim.engine.schemes.get_scheme`); a Gauss-Seidel order must name each unit once."""
    n = chain.n_segments
    if isinstance(text, str) and text in SCHEME_KINDS:
        scheme = get_scheme(scheme_name(text, n))
    elif isinstance(text, str) and UNIT_ORDER.fullmatch(text):
        order = [int(i) for i in text.split(",")]
        if sorted(order) != list(range(1, n + 1)):
            raise ParameterError(f"scheme {text!r}: an order must name each of the units 1 ... {n} once")
        scheme = GaussSeidel(order)
    else:
        scheme = get_scheme(text)
    if isinstance(scheme, GaussSeidel) and len(scheme.order) != n:
        raise ParameterError(f"scheme {text!r}: an order must name each of the units 1 ... {n} once")
    return scheme


@dataclass(frozen=True)
class ChainSystem:
    """A chain at any macro step: what :func:`~icosim.advise.core.evaluate` asks of a system."""

    chain: Chain

    @property
    def decomposition(self) -> str:
        """The joints' decompositions joined by ``-`` (a configuration's ``decomposition``)."""
        return "-".join(self.chain.decompositions)

    def family(self, H, decomposition, k: int) -> ChainFamily:
        """The chain's points at macro step(s) ``H`` (``decomposition``: the chain's own, its joints')."""
        return ChainFamily(self.chain.with_H(np.asarray(H, dtype=float)), k)


def chain_configurations(chain: Chain, *, methods=None, k=DEFAULT_K, params=None, schemes=None):
    """``(configurations, refused)``: every method (or those named), index, ``k`` and scheme (default
    :data:`SCHEME_KINDS`) for ``chain``; ``refused`` lists ``(configuration, reason)`` for those the engine
    refuses (a method not defined for a joint's decomposition, a Gauss-Seidel order it cannot serve)."""
    params = dict(params or {})
    names = list(_methods.METHODS) if methods is None else list(methods)
    for name in names:
        _methods.get_spec(name)
    known = set(_methods.parameters())
    if unknown := sorted(set(params) - known):
        raise ParameterError(f"parameter {unknown[0]} is not a method parameter (known: {', '.join(sorted(known))})")
    ks = sorted({check_k(v) for v in k})
    kinds = list(SCHEME_KINDS) if schemes is None else list(schemes)
    resolved = [chain_scheme(s, chain) for s in kinds]
    graph = ChainSystem(chain).decomposition
    out, refused = [], []
    for name in names:
        spec = _methods.get_spec(name)
        for index in spec.indices:
            p = index_parameters(spec, index, params)
            for kk in ks:
                for scheme in resolved:
                    c = Configuration(name, index, p, graph, kk, scheme.name)
                    try:
                        check(scheme, chain.graph(), c.engine_method(1.0))
                    except ParameterError as exc:
                        refused.append((c, str(exc)))
                        continue
                    out.append(c)
    return out, refused


def advise_chain(
    chain: Chain,
    H,
    *,
    configuration_list=None,
    refused=(),
    n_scan: int = DEFAULT_SCAN,
    rtol: float = DEFAULT_RTOL,
    policy: str = "auto",
    digits: int = 128,
    progress=None,
):
    """:func:`~icosim.advise.advise` for a chain: one row per configuration (default
    :func:`chain_configurations`), stable ones ranked first; those refused in ``df.attrs["refused"]`` with the
    reason."""
    H = check_settings(H, n_scan=n_scan, rtol=rtol, policy=policy)
    if configuration_list is None:
        configuration_list, refused = chain_configurations(chain)
    system = ChainSystem(chain)
    rows = []
    for n, s in enumerate(configuration_list, start=1):
        rows.append(configuration_row(system, s, H, n_scan=n_scan, rtol=rtol, policy=policy, digits=digits))
        if progress is not None:
            progress(n)
    df = ranked(rows, H) if rows else _empty()
    df.attrs.update(
        chain={"segments": [asdict(s) for s in chain.segments_], "joints": list(chain.decompositions)},
        refused=[{"configuration": c.label, "scheme": c.scheme, "reason": why} for c, why in refused],
        **settings_attrs(H, n_scan, rtol, policy, digits),
    )
    return df


def _empty():
    """The table of no configuration (every one refused)."""
    import pandas as pd

    return pd.DataFrame({"rank": pd.array([], dtype="Int64"), "configuration": [], "verdict": []})


def chain_advice_text(df) -> str:
    """The answer as text: the chain, then the configurations (:func:`~icosim.advise.output.configuration_table`),
    then those the engine refused, with its reason."""
    a = df.attrs
    segs, joints = a["chain"]["segments"], a["chain"]["joints"]
    lines = [f"Chain of {len(segs)} units joined by {', '.join(joints)} (SI units):"]
    for i, sg in enumerate(segs, start=1):
        parts = [f"{name} {', '.join(f'{v:g}' for v in sg[name])}" for name in sg if sg[name]]
        lines.append(f"  unit {i}: " + "; ".join(parts))
    lines.append(f"Method parameters: {a['defaults']}.")
    lines += configuration_table(df) if len(df) else ["\nNo configuration the engine can serve."]
    if a["refused"]:
        lines.append(f"\n{len(a['refused'])} configurations refused by the engine:")
        lines += [f"  {r['configuration']}: {r['reason']}" for r in a["refused"]]
    return "\n".join(lines)
