"""The engine's registries as JSON-schema definitions, filled into the workflow's configuration schemas.

The schemas under ``workflow/schemas/`` refer to these ``$defs`` instead of
listing methods, parameters, decompositions and schemes themselves;
:func:`with_registries` fills them in before a configuration is validated
(``workflow/rules/common.smk``), so a method, decomposition or coupling scheme
added to its registry (:data:`icosim.engine.methods.METHODS`,
:data:`icosim.engine.decompositions.DECOMPOSITIONS`,
:data:`icosim.engine.schemes.SCHEMES`) is accepted by every schema.

==============================  =====================================================
``$defs`` entry                 what it allows
==============================  =====================================================
``method``                      a registered method's name
``method_parameters``           any method argument (``index`` and every parameter);
                                open, combine with ``unevaluatedProperties: false``
``method_row_parameters``       the same without ``index`` (what a figure row changes)
``methods_parameters``          ``{name: {its arguments}}`` for every method
``decomposition``               a registered decomposition's name
``scheme``                      a registered coupling scheme's name
==============================  =====================================================

>>> defs = schema_defs()
>>> defs["method"]["enum"]
['baumgarte', 'weighted', 'projection']
>>> sorted(defs["methods_parameters"]["properties"]["weighted"]["properties"])
['a', 'b', 'index']
"""

from __future__ import annotations

import copy

from .decompositions import DECOMPOSITIONS
from .methods import METHODS, indices, parameters
from .schemes import SCHEMES

__all__ = ["schema_defs", "with_registries", "PLACEHOLDERS"]

#: The ``$defs`` entries a schema may leave for :func:`with_registries` to fill.
PLACEHOLDERS = (
    "method",
    "method_parameters",
    "method_row_parameters",
    "methods_parameters",
    "decomposition",
    "scheme",
)


def _index() -> dict:
    return {"enum": list(indices())}


def schema_defs() -> dict:
    params = {name: p.schema() for name, p in parameters().items()}
    per_method = {}
    for spec in METHODS.values():
        props = {"index": {"enum": list(spec.indices)}} if spec.takes_index else {}
        props.update({p.name: p.schema() for p in spec.parameters})
        per_method[spec.name] = {"type": "object", "additionalProperties": False, "properties": props}
    return {
        "method": {"enum": list(METHODS)},
        "method_parameters": {"type": "object", "properties": {"index": _index(), **params}},
        "method_row_parameters": {"type": "object", "properties": params},
        "methods_parameters": {"type": "object", "additionalProperties": False, "properties": per_method},
        "decomposition": {"enum": list(DECOMPOSITIONS)},
        "scheme": {"enum": list(SCHEMES)},
    }


def with_registries(schema: dict) -> dict:
    """A copy of ``schema`` whose placeholder ``$defs`` hold the registered methods, decompositions and schemes."""
    out = copy.deepcopy(schema)
    defs = out.setdefault("$defs", {})
    missing = [name for name in defs if name in PLACEHOLDERS and defs[name] not in ({}, None)]
    if missing:
        raise ValueError(f"schema $defs {missing} are filled from the engine's registries; leave them empty")
    filled = schema_defs()
    for name in PLACEHOLDERS:
        if name in defs:
            defs[name] = filled[name]
    return out
