"""Which curves form a panel dataset, and where each cell of a figure is stored.

A figure of the configuration (``convergence.figures``) has columns (parameter
sets, e.g. ``mu``) and rows (usually the index); one panel dataset holds the
curves (rows x k) of one column and decomposition.  Rows whose parameters do
not depend on the column form one shared panel.
"""

from __future__ import annotations

from dataclasses import dataclass

from ...engine.decompositions import get_decomposition
from ...engine.methods import METHODS, get_spec
from ...engine.schemes import get_scheme
from ...engine.stages import check
from ...errors import ParameterError
from .experiment import dimensional_method

__all__ = ["PanelSpec", "effective_params", "panel_name", "figure_panels", "figure_schemes", "figure_layout"]


def effective_params(method: str, column: dict, row: dict) -> dict:
    """A curve's method parameters: the column's and the row's, minus those its index does not use.

    (Baumgarte at index 3 has no ``mu``; the weighted multiplier at index 2
    has ``b = 0``, at index 3 ``a = b = 0``.)  Raises :class:`ParameterError`
    naming the parameter if the method rejects the combination.
    """
    merged = {**column, **row}
    index = merged.get("index")
    unused = get_spec(method).unused(index) if method in METHODS else ()
    for name in unused:
        merged.pop(name, None)
    dimensional_method(method, 1.0, **merged)  # validates (message names the parameter)
    return merged


def panel_name(params: dict) -> str:
    """File-name part for a set of parameters, e.g. ``mu0.005``, ``a0.5_b0.25``, ``index3``."""
    return "_".join(f"{k}{v:g}" for k, v in params.items()) or "all"


@dataclass(frozen=True)
class PanelSpec:
    """One dataset: the curves (rows x k) of one figure column and decomposition.

    Rows whose parameters do not depend on the column (Baumgarte index 3 in
    Fig. 21: no ``mu``) form one *shared* panel per figure and decomposition,
    drawn in every column, so each distinct curve is computed once.
    """

    figure: str
    decomposition: str
    panel: str
    method: str
    column: dict
    rows: tuple  # effective parameters of each row (dicts)
    k: tuple
    shared: bool = False
    #: the coupling scheme (:mod:`icosim.engine.schemes`), by name
    scheme: str = "jacobi"

    def as_dict(self) -> dict:
        return {
            "figure": self.figure,
            "decomposition": self.decomposition,
            "panel": self.panel,
            "method": self.method,
            "column": dict(self.column),
            "rows": [dict(r) for r in self.rows],
            "k": list(self.k),
            "shared": self.shared,
            "scheme": self.scheme,
        }

    @classmethod
    def from_dict(cls, d: dict) -> PanelSpec:
        return cls(
            d["figure"],
            d["decomposition"],
            d["panel"],
            d["method"],
            dict(d["column"]),
            tuple(dict(r) for r in d["rows"]),
            tuple(d["k"]),
            bool(d.get("shared", False)),
            get_scheme(d.get("scheme", "jacobi")).name,
        )

    @property
    def indices(self) -> list:
        return [int(dimensional_method(self.method, 1.0, **r).params["index"]) for r in self.rows]


def figure_schemes(fig_cfg: dict) -> list[str]:
    """The coupling schemes a figure is computed with (``schemes``, default ``[jacobi]``, the paper's), checked."""
    return [get_scheme(name).name for name in fig_cfg.get("schemes", ["jacobi"])]


def figure_panels(figure: str, fig_cfg: dict, k) -> list:
    """All panel specs of one configured figure: every scheme, decomposition and column.

    ``fig_cfg`` has ``method``, ``columns`` (list of parameter dicts),
    ``rows`` (list of parameter dicts, usually ``{index: i}``),
    ``decompositions`` and ``schemes``.  Where each cell of a figure is
    stored: :func:`figure_layout`.
    """
    method = fig_cfg["method"]
    columns, rows = fig_cfg["columns"], fig_cfg["rows"]
    where = f"figure {figure}"
    try:
        schemes = figure_schemes(fig_cfg)
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None
    try:
        cells = [[effective_params(method, c, r) for r in rows] for c in columns]
    except ParameterError as exc:
        raise ParameterError(f"{where}: {exc}") from None
    shared_rows = [
        j for j in range(len(rows)) if len(columns) > 1 and all(cells[i][j] == cells[0][j] for i in range(len(columns)))
    ]
    specs = []
    for scheme in schemes:
        for dec in fig_cfg["decompositions"]:
            try:
                dimensional_method(method, 1.0, **cells[0][0]).check_decomposition(get_decomposition(dec))
                check(get_scheme(scheme), dec)
            except ParameterError as exc:
                raise ParameterError(f"{where}, decomposition {dec!r}: {exc}") from None
            for i, c in enumerate(columns):
                own = tuple(cells[i][j] for j in range(len(rows)) if j not in shared_rows)
                if own:
                    specs.append(
                        PanelSpec(str(figure), dec, panel_name(c), method, dict(c), own, tuple(k), scheme=scheme)
                    )
            if shared_rows:
                shared = tuple(cells[0][j] for j in shared_rows)
                name = "_".join(panel_name({"index": r.get("index")}) for r in shared)
                specs.append(
                    PanelSpec(str(figure), dec, name, method, {}, shared, tuple(k), shared=True, scheme=scheme)
                )
    for spec in specs:
        idx = spec.indices
        if len(set(idx)) != len(idx):
            raise ParameterError(f"{where}: rows of panel {spec.panel} must have distinct index, got {idx}")
    return specs


def figure_layout(figure: str, fig_cfg: dict, decomposition: str, k) -> list:
    """``[[(panel, index), ...] per column]``: where each cell's curves are stored."""
    specs = {
        s.panel: s
        for s in figure_panels(figure, fig_cfg, k)
        if s.decomposition == decomposition and s.scheme == figure_schemes(fig_cfg)[0]
    }
    method = fig_cfg["method"]
    layout = []
    for c in fig_cfg["columns"]:
        col = []
        for r in fig_cfg["rows"]:
            eff = effective_params(method, c, r)
            for s in specs.values():
                if eff in s.rows:
                    col.append((s.panel, s.indices[s.rows.index(eff)]))
                    break
        layout.append(col)
    return layout
