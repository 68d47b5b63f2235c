"""Atomic writes: a result is either complete or absent.

Its own module so that :mod:`icosim.datasets` and :mod:`icosim.integrity`
(which writes the checksum sidecars) can both use it without importing each
other; :mod:`icosim.datasets` re-exports it.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

__all__ = ["atomic_path"]


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
