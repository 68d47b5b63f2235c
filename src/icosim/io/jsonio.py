"""Strict JSON for every file and answer icosim writes: no NaN or Infinity, ``null`` with the reason.

JSON has no NaN or infinity; Python's ``json`` writes them anyway unless told
not to, and strict parsers (JavaScript's, jq, most other languages) then refuse
the file.  :func:`dumps` turns every non-finite number into ``null`` and, where
there was one, adds ``"null_reasons"`` to the top-level object: a JSON pointer
per replaced value with what it was (``"nan"``, ``"inf"``, ``"-inf"``).
NumPy scalars and arrays become plain numbers and lists.

>>> dumps({"order": float("nan"), "H": [1e-3, float("inf")]})
'{"order": null, "H": [0.001, null], "null_reasons": {"/order": "nan", "/H/1": "inf"}}'
"""

from __future__ import annotations

import json
import math

import numpy as np

__all__ = ["strict", "dumps"]


def strict(obj, path: str = "", reasons: dict | None = None):
    """``(clean, reasons)``: ``obj`` with non-finite floats replaced by None, NumPy types made plain."""
    reasons = {} if reasons is None else reasons
    if isinstance(obj, dict):
        return {k: strict(v, f"{path}/{k}", reasons)[0] for k, v in obj.items()}, reasons
    if isinstance(obj, (list, tuple, np.ndarray)):
        return [strict(v, f"{path}/{i}", reasons)[0] for i, v in enumerate(obj)], reasons
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj), reasons
    if isinstance(obj, (int, np.integer)):
        return int(obj), reasons
    if isinstance(obj, (float, np.floating)):
        x = float(obj)
        if math.isfinite(x):
            return x, reasons
        reasons[path or "/"] = "nan" if math.isnan(x) else ("inf" if x > 0 else "-inf")
        return None, reasons
    return obj, reasons


def dumps(obj, **kwargs) -> str:
    """``json.dumps`` of :func:`strict` ``obj`` with ``allow_nan=False``; ``null_reasons`` added where needed."""
    clean, reasons = strict(obj)
    if reasons and isinstance(clean, dict):
        clean["null_reasons"] = {**clean.get("null_reasons", {}), **reasons}
    return json.dumps(clean, allow_nan=False, **kwargs)
