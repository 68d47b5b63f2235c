"""One stability panel computed and written as a NetCDF-ready dataset.

The names are a contract other tools read: data variable ``rho`` over the
coordinates ``lr1`` and ``li1``; attributes ``figure``, ``method``,
``decomposition``, ``k``, ``scheme``, ``am21``, ``alr21``, ``ali21`` and the method
parameters under their command-line names (``beta``, ``gamma``, ``mu``,
``index``, ``a``, ``b``), ``row`` (1-based, as in the paper) and ``view``
(``full`` or ``zoom``).  Per point the dataset records the verdict
(``verdict``: stable, unstable, marginal, undecided; ``stable`` as a boolean),
which arithmetic decided it (``decided_by``: float64 or a ball-arithmetic
proof), whether it is ``certified`` with the proven enclosure
``[rho_lower, rho_upper]``, and whether a float64 verdict was checked by
certification (``audited``) and ``overturned``; the attributes count them
and say how long each pass took, so the cost of the policy is measured on
every run (:mod:`icosim.engine.spectral.policy`).
"""

from __future__ import annotations

import numpy as np

from ...engine.backends import FLOAT64_DIGITS
from ...engine.decompositions import DECOMPOSITIONS
from ...engine.schemes import get_scheme
from ...engine.spectral.policy import ARITHMETICS, REASONS, VERDICTS, Certification
from ...engine.stages import check
from ...io.dataset import DatasetDict
from ...io.jsonio import dumps
from ...problems.linear.model import TestModel
from ...problems.linear.spectral import spectral_radius
from .panels import PanelSpec, format_row_label, grid_axis, method_parameters_units

__all__ = ["stability_panel", "stability_panel_data", "LONG_NAMES"]

LONG_NAMES = {
    "lr1": "real part of the eigenvalue of subsystem 1, lambda_bar_r1 = -d_bar_1/2",
    "li1": "imaginary part of the eigenvalue of subsystem 1, lambda_bar_i1 = sqrt(4 c_bar_1 - d_bar_1^2)/2",
    "rho": "spectral radius of the co-simulation recurrence (one macro step)",
    "stable": "stable point: rho < 1 proven, or float64 trusted with rho <= 1 (marginal points are not)",
    "verdict": "stability verdict of the point",
    "decided_by": "arithmetic that decided the point",
    "certified": "verdict from a proven enclosure of rho (ball arithmetic)",
    "rho_lower": "proven lower bound of rho (certified points; NaN elsewhere)",
    "rho_upper": "proven upper bound of rho (certified points; NaN elsewhere)",
    "audited": "float64-trusted point also certified (within the band around 1, or in the audit sample)",
    "overturned": "audited point whose certified verdict is the opposite of float64's",
    "undecided_reason": "why the point is undecided (none for decided points)",
    "digits": "decimal digits of the arithmetic that decided the point",
    "rho_float64_error": "error estimate of the float64 spectral radius",
}


def _finite_or_none(x):
    """A float for JSON, ``None`` where it is not finite (strict JSON has no NaN or Infinity)."""
    return float(x) if np.isfinite(x) else None


def _codes(values, names) -> np.ndarray:
    lookup = {name: i for i, name in enumerate(names)}
    return np.vectorize(lookup.__getitem__, otypes=[np.int8])(np.asarray(values, dtype=object))


def _flags(names) -> dict:
    """CF flag attributes of a coded variable."""
    return {"flag_values": np.arange(len(names), dtype=np.int8), "flag_meanings": " ".join(names)}


def stability_panel(spec: PanelSpec, *, provenance: dict | None = None):
    """Compute one panel and return it as an :class:`xarray.Dataset` (:func:`stability_panel_data`, converted).

    ``provenance`` are extra global attributes (normally
    :func:`icosim.io.netcdf.provenance_attrs` of the job's configuration).
    """
    return stability_panel_data(spec, provenance=provenance).to_xarray()


def stability_panel_data(spec: PanelSpec, *, provenance: dict | None = None) -> DatasetDict:
    """Compute one panel as a :class:`~icosim.io.dataset.DatasetDict` (written without xarray)."""
    method = spec.coupling_method()
    method.check_decomposition(DECOMPOSITIONS[spec.decomposition])
    check(get_scheme(spec.scheme), spec.decomposition)
    lr1 = grid_axis(spec.lr1, spec.n)
    li1 = grid_axis(spec.li1, spec.n)
    LR, LI = np.meshgrid(lr1, li1, indexing="ij")
    model = TestModel(LR, LI, spec.am21, spec.alr21, spec.ali21)
    settings = Certification.from_dict(spec.certify)
    result = spectral_radius(
        model,
        method,
        spec.decomposition,
        spec.k,
        digits=spec.digits,
        policy=spec.policy,
        certification=settings,
        scheme=spec.scheme,
    )

    dims = ("lr1", "li1")

    def var(name, values, **attrs):
        return (dims, values, {"long_name": LONG_NAMES[name], **attrs})

    ds = DatasetDict(
        {
            "rho": var("rho", np.asarray(result.rho, dtype=float), units="1"),
            "stable": var("stable", np.asarray(result.stable, dtype=bool)),
            "verdict": var("verdict", _codes(result.verdict, VERDICTS), **_flags(VERDICTS)),
            "decided_by": var("decided_by", _codes(result.arithmetic, ARITHMETICS), **_flags(ARITHMETICS)),
            "certified": var("certified", np.asarray(result.certified, dtype=bool)),
            "rho_lower": var("rho_lower", np.asarray(result.rho_lower, dtype=float), units="1"),
            "rho_upper": var("rho_upper", np.asarray(result.rho_upper, dtype=float), units="1"),
            "audited": var("audited", np.asarray(result.audited, dtype=bool)),
            "overturned": var("overturned", np.asarray(result.overturned, dtype=bool)),
            "undecided_reason": var("undecided_reason", _codes(result.reason_code, REASONS), **_flags(REASONS)),
            "digits": var(
                "digits",
                np.asarray(result.digits, dtype=np.int16),
                units="1",
                comment=f"{FLOAT64_DIGITS} = float64; larger = the ball arithmetic (bits * log10 2) or mpmath "
                "that decided a point float64 could not; -1 = undecided",
            ),
            "rho_float64_error": var(
                "rho_float64_error",
                np.asarray(result.err, dtype=float),
                units="1",
                comment="spread of float64 results under rounding-size disturbances times a safety factor "
                "(icosim.engine.spectral.radius); a point is certified if |rho - 1| <= this or rho is not finite",
            ),
        },
        coords={
            "lr1": ("lr1", lr1, {"long_name": LONG_NAMES["lr1"], "units": "1"}),
            "li1": ("li1", li1, {"long_name": LONG_NAMES["li1"], "units": "1"}),
        },
    )
    attrs = dict(provenance or {})
    attrs.update(
        figure=str(spec.figure),
        row=int(spec.row),
        view=spec.view,
        method=spec.method,
        decomposition=spec.decomposition,
        k=int(spec.k),
        scheme=get_scheme(spec.scheme).name,
        am21=float(spec.am21),
        alr21=float(spec.alr21),
        ali21=float(spec.ali21),
    )
    for name, value in method.params.items():  # beta, gamma, mu, index, a, b as resolved
        attrs[name] = int(value) if name == "index" else float(value)
    attrs["method_parameters_units"] = method_parameters_units()
    # what tells the rows of the figure apart: the figure labels its rows from these
    attrs["row_label_keys"] = " ".join(spec.row_keys)
    attrs["row_label"] = format_row_label(spec.row_keys, attrs)
    verdict = np.asarray(result.verdict)
    over = np.argwhere(np.asarray(result.overturned))
    overturned_points = [
        {
            "lr1": float(lr1[i]),
            "li1": float(li1[j]),
            "float64_verdict": str(result.float64_verdict[i, j]),
            "verdict": str(result.verdict[i, j]),
            "rho_lower": _finite_or_none(result.rho_lower[i, j]),
            "rho_upper": _finite_or_none(result.rho_upper[i, j]),
        }
        for i, j in over
    ]
    codes = np.asarray(result.reason_code)
    attrs.update(
        precision_policy=spec.policy,
        mp_digits=int(spec.digits),
        certify_band=float(settings.band),
        certify_audit=float(settings.audit),
        certify_seed=int(settings.seed),
        certify_bits=int(settings.bits),
        certify_max_bits=int(settings.max_bits),
        certify_point_seconds=float(settings.point_seconds),
        n_points=int(LR.size),
        n_high_precision=int(result.n_high_precision),
        # rechecked points on the undamped axis lr1 = 0, where rho = 1 to working precision
        n_high_precision_undamped=int(np.sum((np.asarray(result.arithmetic) != "float64") & (LR == 0))),
        n_stable=int(np.sum(result.stable)),
        n_certified=int(np.sum(result.certified)),
        n_marginal=int(np.sum(verdict == "marginal")),
        n_undecided=int(np.sum(verdict == "undecided")),
        # undecided points per reason (JSON), e.g. {"timeout": 2}
        undecided_reasons=dumps({r: int(np.sum(codes == r)) for r in REASONS[1:] if np.any(codes == r)}),
        n_audited=int(np.sum(result.audited)),
        n_overturned=int(np.sum(result.overturned)),
        # every float64 verdict certification overturned, with the proven enclosure (JSON; usually "[]")
        overturned_points=dumps(overturned_points),
        seconds_total=float(sum(result.seconds.values())),
        seconds_float64=float(result.seconds["float64"]),
        seconds_certify=float(result.seconds["certify"]),
        seconds_mp=float(result.seconds["mp"]),
        cpu_seconds_total=float(sum(result.cpu_seconds.values())),
        cpu_seconds_float64=float(result.cpu_seconds["float64"]),
        cpu_seconds_certify=float(result.cpu_seconds["certify"]),
        cpu_seconds_mp=float(result.cpu_seconds["mp"]),
    )
    ds.attrs = attrs
    return ds
