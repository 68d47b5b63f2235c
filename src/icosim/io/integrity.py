"""Integrity of the written datasets: a SHA-256 beside each one, corrupt files set aside, stale temporaries removed.

Every dataset ``x.nc`` written by :func:`icosim.io.netcdf.write_netcdf` gets a
sidecar ``x.nc.sha256`` (``sha256sum`` format) written *before* the dataset is
renamed into place, so a run killed in between leaves a sidecar that no longer
matches, never a dataset that looks complete and is not.  Reading a dataset
checks it (:func:`verify`); the workflow, when it starts, sets every dataset
whose checksum does not match aside as ``x.nc.corrupt`` (:func:`quarantine_corrupt`)
so Snakemake computes it again, and removes the ``.*.part`` temporaries a killed
run left behind (:func:`remove_stale_parts`).  A dataset without a sidecar
(written before checksums) is accepted as it is.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path

__all__ = [
    "atomic_path",
    "sha256_file",
    "sidecar",
    "write_checksum",
    "verify",
    "quarantine_corrupt",
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
