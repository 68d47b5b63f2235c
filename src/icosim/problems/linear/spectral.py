"""The spectral analysis of the linear two-mass model, by its parameters: the engine's
(:mod:`icosim.engine.spectral`) on the points of a :class:`~icosim.problems.linear.family.TwoMass` family.

Each function takes the model as the studies, the command line and the tests give it -- a
:class:`~icosim.problems.linear.model.TestModel` (Eq. 71), a :class:`~icosim.problems.linear.model.PhysicalModel`
or :class:`~icosim.problems.linear.model.Coefficients`, attributes broadcasting to a grid -- with the
decomposition and ``k``, and passes everything else on.

>>> from icosim import TestModel, make_method
>>> rho, err = spectral_radius_float64(TestModel(-0.05, 0.5), make_method("weighted", a=1, b=1), "ff", 2)
>>> bool(rho > 1), bool(err < 1e-12)
(True, True)
"""

from __future__ import annotations

from ...engine.schemes import JACOBI
from ...engine.spectral import batched, certified, matrix, policy, radius
from .family import TwoMass

__all__ = [
    "amplification_matrix",
    "spectral_radius",
    "spectral_radius_float64",
    "spectral_radius_mp",
    "certify_spectral_radius",
    "certify_spectral_radii",
    "as_family",
]


def as_family(model, decomposition, k) -> TwoMass:
    """The points of ``model`` (or a family, returned as it is) for ``decomposition`` and ``k``."""
    return model if isinstance(model, TwoMass) else TwoMass(model, decomposition, k)


def amplification_matrix(model, method, decomposition, k: int, backend=None, *, scheme=JACOBI):
    """``M`` with ``w_N+1 = M w_N`` (:func:`icosim.engine.spectral.matrix.amplification_matrix`), the model's
    attributes used as they are (numbers of ``backend``, or floats)."""
    family = as_family(model, decomposition, k)
    return matrix.amplification_matrix(family, method, backend=backend, scheme=scheme, exact=False)


def spectral_radius_float64(model, method, decomposition, k, **kwargs):
    """``(rho, err)`` in float64 (:func:`icosim.problems.linear.spectral.spectral_radius_float64`)."""
    return radius.spectral_radius_float64(as_family(model, decomposition, k), method, **kwargs)


def spectral_radius_mp(model, method, decomposition, k, digits: int = 128, *, scheme=JACOBI):
    """``rho`` of one point at ``digits`` digits (:func:`icosim.engine.spectral.radius.spectral_radius_mp`)."""
    return radius.spectral_radius_mp(as_family(model, decomposition, k), method, digits, scheme=scheme)


def spectral_radius(model, method, decomposition, k, **kwargs):
    """The precision policy's rho and verdict per point (:func:`icosim.engine.spectral.policy.spectral_radius`)."""
    return policy.spectral_radius(as_family(model, decomposition, k), method, **kwargs)


def certify_spectral_radius(model, method, decomposition, k, **kwargs):
    """A proof about one point (:func:`icosim.engine.spectral.certified.certify_spectral_radius`)."""
    return certified.certify_spectral_radius(as_family(model, decomposition, k), method, **kwargs)


def certify_spectral_radii(models, method, decomposition, k, **kwargs):
    """Proofs about many points, batched (:func:`icosim.engine.spectral.batched.certify_spectral_radii`)."""
    return batched.certify_spectral_radii([as_family(m, decomposition, k) for m in models], method, **kwargs)
