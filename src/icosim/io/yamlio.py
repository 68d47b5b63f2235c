"""YAML as the configuration, claims and scene files are read: safe, through libyaml where installed.

PyYAML's pure-Python parser takes about ten times as long as its C binding (libyaml)
for the same safe subset of YAML; the workflow reads a dozen files each time Snakemake
starts, so the binding is used when PyYAML was built with it, the Python parser otherwise.
Both accept the same documents and give the same objects.

>>> load_yaml("a: [1, 2.5, x]")
{'a': [1, 2.5, 'x']}
"""

from __future__ import annotations

import yaml

__all__ = ["load_yaml", "SafeLoader"]

#: libyaml's safe loader where PyYAML has it, else PyYAML's own.
SafeLoader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def load_yaml(stream):
    """``yaml.safe_load(stream)`` (a string or an open file), with :data:`SafeLoader`."""
    return yaml.load(stream, Loader=SafeLoader)
