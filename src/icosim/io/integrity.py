"""Integrity of the written datasets: a SHA-256 beside each one, corrupt files set aside, stale temporaries removed.

Every dataset ``x.nc`` written by :func:`icosim.io.netcdf.write_netcdf` gets a
sidecar ``x.nc.sha256`` (``sha256sum`` format) written *before* the dataset is
renamed into place, so a run killed in between leaves a sidecar that no longer
matches, never a dataset that looks complete and is not.  Reading a dataset
checks it (:func:`verify`); the workflow, when it starts, sets every dataset
whose checksum does not match aside as ``x.nc.corrupt`` (:func:`quarantine_corrupt`),
forces every dataset that is missing while such a trace remains to be computed again
with everything built from it (:func:`lost_datasets`), and removes the ``.*.part``
temporaries a killed run left behind (:func:`remove_stale_parts`).  A dataset without a sidecar
(written before checksums) is accepted as it is.
"""

from __future__ import annotations

import hashlib
import os
import re
import tempfile
from pathlib import Path

__all__ = [
    "atomic_path",
    "sha256_file",
    "sidecar",
    "write_checksum",
    "verify",
    "quarantine_corrupt",
    "lost_datasets",
    "outputs_built_from",
    "remove_stale_parts",
]


def sha256_file(path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for chunk in iter(lambda: fh.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


class atomic_path:
    """Context manager yielding a temporary path next to ``path``; renamed on success."""

    def __init__(self, path):
        self.path = Path(path)

    def __enter__(self):
        self.path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".part", dir=self.path.parent)
        os.close(fd)
        self.tmp = Path(tmp)
        return self.tmp

    def __exit__(self, exc_type, exc, tb):
        if exc_type is None:
            # mkstemp creates 0600; give the result the permissions of an ordinary file
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(self.tmp, 0o666 & ~umask)
            os.replace(self.tmp, self.path)
        else:
            self.tmp.unlink(missing_ok=True)
        return False


def sidecar(path) -> Path:
    """``x.nc`` -> ``x.nc.sha256``."""
    path = Path(path)
    return path.with_name(path.name + ".sha256")


def write_checksum(data_file, path) -> str:
    """Record the SHA-256 of ``data_file`` (the finished temporary) as the checksum of ``path`` (atomically)."""
    digest = sha256_file(data_file)
    with atomic_path(sidecar(path)) as tmp:
        tmp.write_text(f"{digest}  {Path(path).name}\n")
    return digest


def recorded(path) -> str | None:
    """The SHA-256 recorded for ``path``, or None if it has no sidecar."""
    s = sidecar(path)
    if not s.exists():
        return None
    text = s.read_text().split()
    return text[0] if text else ""


def verify(path) -> bool | None:
    """True if ``path`` matches its recorded SHA-256, False if not, None if nothing is recorded."""
    digest = recorded(path)
    if digest is None:
        return None
    return Path(path).exists() and sha256_file(path) == digest


def quarantine_corrupt(root) -> list[Path]:
    """Rename every ``*.nc`` under ``root`` whose checksum does not match to ``*.nc.corrupt``; the renamed paths."""
    moved = []
    root = Path(root)
    if not root.exists():
        return moved
    for path in sorted(root.rglob("*.nc")):
        if verify(path) is False:
            target = path.with_name(path.name + ".corrupt")
            path.replace(target)
            sidecar(path).unlink(missing_ok=True)
            moved.append(target)
    return moved


def lost_datasets(root) -> list[Path]:
    """Datasets under ``root`` that are missing while a trace of an earlier copy remains: its checksum
    sidecar (the dataset was deleted) or the copy set aside as ``x.nc.corrupt`` (:func:`quarantine_corrupt`).

    Snakemake does not rerun a job whose output is missing when everything built from it is present and
    up to date, so the workflow forces these (and through them everything downstream) to be built again.
    """
    root = Path(root)
    if not root.exists():
        return []
    traces = [(p, ".sha256") for p in root.rglob("*.nc.sha256")] + [(p, ".corrupt") for p in root.rglob("*.nc.corrupt")]
    lost = {p.with_name(p.name[: -len(suffix)]) for p, suffix in traces}
    return sorted(p for p in lost if not p.exists())


def _pattern(template: str) -> re.Pattern:
    """A file pattern with ``{wildcard}`` fields as a regular expression (a field matches any text)."""
    parts = re.split(r"\{(\w+)(?:,[^}]*)?\}", template)
    seen, out = set(), []
    for i, part in enumerate(parts):
        if i % 2 == 0:
            out.append(re.escape(part))
        elif part in seen:
            out.append(f"(?P={part})")
        else:
            seen.add(part)
            out.append(f"(?P<{part}>.+)")
    return re.compile("".join(out) + r"\Z")


def outputs_built_from(path, rules) -> list[str]:
    """The outputs of the jobs that read ``path`` directly.

    ``rules`` are ``(inputs, outputs)`` pairs of file templates (``{wildcard}`` fields allowed, as in
    Snakemake's rules); a job's outputs are its rule's outputs with the wildcards the matching input
    fixes.  Outputs with a wildcard the input does not fix are left out (no single job is meant).

    >>> rules = [(["r/fig9/{s}/p.nc", "src/a.py"], ["r/fig9_{s}.png"]), (["r/fig9/jacobi/p.nc"], ["r/claims.json"])]
    >>> outputs_built_from("r/fig9/jacobi/p.nc", rules)
    ['r/claims.json', 'r/fig9_jacobi.png']
    """
    path = str(path)
    found = set()
    for inputs, outputs in rules:
        for template in inputs:
            match = _pattern(str(template)).match(path)
            if match is None:
                continue
            fixed = match.groupdict()
            for out in outputs:
                try:
                    found.add(str(out).format(**fixed) if fixed or "{" in str(out) else str(out))
                except (KeyError, IndexError, ValueError):
                    continue  # a wildcard the input does not fix
    return sorted(found)


def remove_stale_parts(root) -> list[Path]:
    """Delete the ``.*.part`` temporaries under ``root`` (left by a killed run; call under the workflow's lock)."""
    removed = []
    root = Path(root)
    if not root.exists():
        return removed
    for path in sorted(root.rglob(".*.part")):
        path.unlink(missing_ok=True)
        removed.append(path)
    return removed
