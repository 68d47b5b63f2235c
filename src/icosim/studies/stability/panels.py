"""Stability panels: what one plot of Figs. 9-20 is, as configured.

One *panel* is one plot of the paper's Figs. 9-20: a coupling method with its
parameters, a decomposition, the approximation order ``k`` and the three fixed
ratios ``(am21, alr21, ali21)`` of Eq. (71), evaluated over a grid of
``lr1`` (real part) and ``li1`` (imaginary part of subsystem 1's eigenvalue).
:class:`PanelSpec` holds exactly that; :func:`figure_panels` builds them from
``config/stability.yaml``, checked before any job runs; the row labels are
decided here once.  :mod:`icosim.studies.stability.datasets` computes a panel and
writes it as a dataset.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...engine import methods as _methods
from ...engine.bounds import MAX_GRID_N, check_k
from ...engine.decompositions import DECOMPOSITIONS, get_decomposition
from ...engine.methods import make_method
from ...engine.schemes import get_scheme
from ...engine.spectral.policy import POLICIES, Certification
from ...engine.stages import check
from ...errors import ParameterError

__all__ = [
    "PanelSpec",
    "grid_axis",
    "panel_id",
    "figure_panels",
    "figure_schemes",
    "row_label",
    "row_label_keys",
    "format_row_label",
    "row_symbols",
    "row_keys",
    "method_param_names",
    "method_parameters_units",
    "RATIOS",
    "VIEWS",
]

#: The three fixed ratios of Eq. (71) that a panel holds constant.
RATIOS = ("am21", "alr21", "ali21")
#: A panel shows the whole parameter range or a zoom near the origin.
VIEWS = ("full", "zoom")
#: Symbols of the ratios (plain text; the figures use their TeX form).
RATIO_SYMBOLS = {"am21": "αm21", "alr21": "αλr21", "ali21": "αλi21"}


def method_param_names() -> tuple:
    """Method parameters under their command-line names (every registered method's, and ``index``)."""
    return _methods.argument_names()


def row_keys() -> tuple:
    """What a row of a figure may change: a ratio or a method parameter (not the index)."""
    return RATIOS + tuple(_methods.parameters())


def row_symbols() -> dict:
    """Symbols of the row parameters (plain text; the figures use their TeX form)."""
    return {**RATIO_SYMBOLS, **{name: p.symbol for name, p in _methods.parameters().items()}}


def method_parameters_units() -> str:
    """The ``method_parameters_units`` attribute: the panels hold the engine's dimensionless parameters."""
    params = _methods.parameters()
    scaled = [name for name, p in params.items() if p.scaling]
    plain = sorted(name for name, p in params.items() if not p.scaling)

    def per_H(name):
        power = params[name].scaling
        return f"{name}_bar = {name}/H" + (f"^{power}" if power != 1 else "")

    return (
        f"dimensionless ({', '.join(per_H(n) for n in sorted(scaled))}; {', '.join(plain)} dimensionless): "
        f"the attributes {', '.join(scaled)} are {', '.join(n + '_bar' for n in scaled)}"
    )


def grid_axis(bounds, n: int) -> np.ndarray:
    """``n`` equally spaced values from ``bounds[0]`` to ``bounds[1]`` (both included).

    The end points are set exactly, so the undamped axis ``lr1 = 0`` and the
    axis ``li1 = 0`` are on the grid whatever the spacing.
    """
    lo, hi = (float(b) for b in bounds)
    if not lo < hi:
        raise ParameterError(f"grid bounds must be increasing, got {list(bounds)!r}")
    if int(n) != n or not 2 <= n <= MAX_GRID_N:
        raise ParameterError(f"grid size n must be an integer >= 2 and <= {MAX_GRID_N}, got {n!r}")
    axis = np.linspace(lo, hi, int(n))
    axis[0], axis[-1] = lo, hi
    return axis


@dataclass(frozen=True)
class PanelSpec:
    """Everything that determines one panel (and nothing else).

    ``method_params`` are the parameters as given in the configuration
    (e.g. ``{"index": 1, "mu": 1.0}``); the dataset records the resolved set
    (``beta``, ``gamma`` included).
    """

    figure: str
    row: int
    k: int
    view: str
    method: str
    method_params: dict
    decomposition: str
    am21: float
    alr21: float
    ali21: float
    lr1: tuple  # (start, stop)
    li1: tuple
    n: int
    digits: int = 128
    policy: str = "auto"
    #: the parameters that tell this figure's rows apart (:func:`row_label_keys`)
    row_keys: tuple = RATIOS
    #: settings of the certified rechecks (:class:`icosim.engine.spectral.policy.Certification`), as a mapping
    certify: dict = field(default_factory=dict)
    #: the coupling scheme (:mod:`icosim.engine.schemes`), by name
    scheme: str = "jacobi"

    @classmethod
    def from_params(cls, params: dict) -> PanelSpec:
        """Build from the plain dict a workflow passes (keys as the field names)."""
        known = {f for f in cls.__dataclass_fields__}
        unknown = sorted(set(params) - known)
        if unknown:
            raise ParameterError(f"unknown panel parameter(s) {unknown}; allowed: {sorted(known)}")
        p = dict(params)
        p["lr1"] = tuple(p["lr1"])
        p["li1"] = tuple(p["li1"])
        if "row_keys" in p:
            p["row_keys"] = tuple(p["row_keys"])
        p["certify"] = dict(p.get("certify") or {})
        return cls(**p)

    def __post_init__(self):
        _methods.get_spec(self.method)  # refuses an unknown method, naming the known ones
        if self.decomposition not in DECOMPOSITIONS:
            raise ParameterError(
                f"decomposition must be one of {', '.join(DECOMPOSITIONS)}, got {self.decomposition!r}"
            )
        if self.view not in VIEWS:
            raise ParameterError(f"view must be one of {', '.join(VIEWS)}, got {self.view!r}")
        check_k(self.k)  # 0 .. icosim.engine.bounds.MAX_K
        if self.policy not in POLICIES:
            raise ParameterError(f"policy must be one of {', '.join(POLICIES)}, got {self.policy!r}")
        Certification.from_dict(self.certify)  # refuses a bad setting, naming it
        get_scheme(self.scheme)  # refuses an unknown scheme, naming the known ones
        bad = [key for key in self.row_keys if key not in row_keys()]
        if bad or not self.row_keys:
            raise ParameterError(
                f"row_keys must be a non-empty list of {', '.join(row_keys())}, got {list(self.row_keys)}"
            )

    def coupling_method(self):
        return make_method(self.method, **self.method_params)

    def as_dict(self) -> dict:
        d = {f: getattr(self, f) for f in self.__dataclass_fields__}
        d["lr1"], d["li1"] = list(self.lr1), list(self.li1)
        d["row_keys"] = list(self.row_keys)
        d["certify"] = dict(self.certify)
        return d


def panel_id(row: int, k: int, view: str) -> str:
    """File stem of a panel inside its figure's folder, e.g. ``r4_k2_zoom``."""
    return f"r{int(row)}_k{int(k)}_{view}"


def row_label_keys(figure_cfg: dict) -> tuple:
    """The parameters that tell a figure's rows apart -- the one rule for row labels.

    Figures whose rows vary the ratios are labelled by the full ratio triple
    (as the paper lists parameter sets); figures whose rows vary a method
    parameter by the parameters the rows set.  The keys are stored in every
    panel (attribute ``row_label_keys``), so the figure, the report and any
    other reader label rows alike.
    """
    varied = sorted({key for r in figure_cfg["rows"] for key in r}, key=row_keys().index)
    if any(key in RATIOS for key in varied) or not varied:
        return RATIOS
    return tuple(varied)


def format_row_label(keys, values: dict, symbols: dict | None = None) -> str:
    """``"symbol = value, ..."`` for ``keys`` (plain-text symbols unless given)."""
    symbols = symbols or row_symbols()
    return ", ".join(f"{symbols[key]} = {float(values[key]):g}" for key in keys)


def row_label(figure_cfg: dict, row: int) -> str:
    """What distinguishes row ``row`` (1-based) of a figure, in the paper's symbols."""
    values = {**figure_cfg["ratios"], **figure_cfg["params"], **figure_cfg["rows"][row - 1]}
    return format_row_label(row_label_keys(figure_cfg), values)


def _check_grid(name: str, g: dict, *, where: str = "stability"):
    """A grid of ``config/stability.yaml``: ordered ranges in the plotted quadrant, ``n >= 2``."""
    for axis in ("lr1", "li1"):
        bounds = g[axis]
        if len(bounds) != 2 or not all(np.isfinite(float(b)) for b in bounds):
            raise ParameterError(f"{where}.{name}.{axis} must be [start, stop] (two finite numbers), got {bounds!r}")
        if not float(bounds[0]) < float(bounds[1]):
            raise ParameterError(
                f"{where}.{name}.{axis} must be increasing, [start, stop] with start < stop, got {list(bounds)!r}"
            )
    if max(g["lr1"]) > 0:
        raise ParameterError(f"{where}.{name}.lr1 must lie in lr1 <= 0 (a damped subsystem), got {list(g['lr1'])!r}")
    if min(g["li1"]) < 0:
        raise ParameterError(f"{where}.{name}.li1 must lie in li1 >= 0, got {list(g['li1'])!r}")
    if int(g["n"]) != g["n"] or not 2 <= g["n"] <= MAX_GRID_N:
        raise ParameterError(f"{where}.{name}.n must be an integer >= 2 and <= {MAX_GRID_N}, got {g['n']!r}")
    for axis in ("lr1", "li1"):
        grid_axis(g[axis], g["n"])  # the grid the sweep job will build


def figure_schemes(figure: str, figure_cfg: dict) -> list[tuple[str, tuple | None]]:
    """The coupling schemes a figure is computed with: ``(name, rows)`` per entry of its ``schemes``
    (default ``[jacobi]``, the paper's); ``rows`` None for every row, else the rows (1-based) the entry
    names (``{name: gauss-seidel-12-as-integrated, rows: [1]}``)."""
    where = f"stability.figures.{figure}.schemes"
    out = []
    for i, entry in enumerate(figure_cfg.get("schemes", ["jacobi"])):
        name, rows = (entry, None) if isinstance(entry, str) else (entry.get("name"), entry.get("rows"))
        try:
            name = get_scheme(name).name
        except ParameterError as err:
            raise ParameterError(f"{where}[{i}]: {err}") from None
        if rows is not None:
            bad = [r for r in rows if not 1 <= r <= len(figure_cfg["rows"])]
            if bad:
                raise ParameterError(
                    f"{where}[{i}].rows: {bad} not among the figure's rows 1..{len(figure_cfg['rows'])}"
                )
            rows = tuple(int(r) for r in rows)
        if name in [n for n, _ in out]:
            raise ParameterError(f"{where}: {name} is listed twice")
        out.append((name, rows))
    return out


def figure_panels(figure: str, figure_cfg: dict, *, grid: dict, zoom_grid: dict, precision: dict) -> list[PanelSpec]:
    """The panels of one figure as configured: every scheme x row x k, plus the zooms.

    ``figure_cfg`` has the layout of ``config/stability.yaml`` (``method``,
    ``decomposition``, ``params``, ``ratios``, ``rows``, ``k``, optional
    ``zoom`` and ``schemes``: :func:`figure_schemes`).  Every panel's method is
    built once here, so a parameter the method does not accept is reported
    with the figure and row before any job runs.
    """
    where = f"stability.figures.{figure}"
    n_rows = len(figure_cfg["rows"])
    _check_grid("grid", grid)
    _check_grid("zoom_grid", zoom_grid)
    row_keys = row_label_keys(figure_cfg)
    zoom = figure_cfg.get("zoom") or {"rows": [], "k": []}
    bad_rows = [r for r in zoom["rows"] if not 1 <= r <= n_rows]
    if bad_rows:
        raise ParameterError(f"{where}.zoom.rows: {bad_rows} not among the figure's rows 1..{n_rows}")
    bad_k = [k for k in zoom["k"] if k not in figure_cfg["k"]]
    if bad_k:
        raise ParameterError(f"{where}.zoom.k: {bad_k} not among the figure's k {figure_cfg['k']}")
    decomposition = get_decomposition(figure_cfg["decomposition"])
    panels = []
    for scheme, scheme_rows in figure_schemes(figure, figure_cfg):
        for row, overrides in enumerate(figure_cfg["rows"], start=1):
            if scheme_rows is not None and row not in scheme_rows:
                continue
            values = {**figure_cfg["ratios"], **figure_cfg["params"], **overrides}
            missing = [r for r in RATIOS if r not in values]
            if missing:
                raise ParameterError(f"{where}: row {row} has no value for {', '.join(missing)} (give it in ratios)")
            method_params = {key: values[key] for key in method_param_names() if key in values}
            try:
                make_method(figure_cfg["method"], **method_params).check_decomposition(decomposition)
                check(get_scheme(scheme), decomposition)
            except ParameterError as err:
                raise ParameterError(f"{where}, row {row}: {err}") from None
            for k in figure_cfg["k"]:
                views = [("full", grid)] + ([("zoom", zoom_grid)] if row in zoom["rows"] and k in zoom["k"] else [])
                for view, g in views:
                    panels.append(
                        PanelSpec(
                            figure=str(figure),
                            row=row,
                            k=int(k),
                            view=view,
                            method=figure_cfg["method"],
                            method_params=method_params,
                            decomposition=decomposition.name,
                            am21=float(values["am21"]),
                            alr21=float(values["alr21"]),
                            ali21=float(values["ali21"]),
                            lr1=tuple(float(v) for v in g["lr1"]),
                            li1=tuple(float(v) for v in g["li1"]),
                            n=int(g["n"]),
                            digits=int(precision["digits"]),
                            policy=precision["policy"],
                            row_keys=row_keys,
                            certify=dict(precision.get("certify") or {}),
                            scheme=scheme,
                        )
                    )
    return panels
