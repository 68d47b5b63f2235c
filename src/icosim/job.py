"""The process of a workflow job: its log file, and an exit that does not collect what stays anyway.

Every script of ``workflow/scripts`` starts with :func:`start_job`.  At exit, Python's last garbage
collections walk every object the job's imports made (numpy, scipy, xarray, matplotlib: about
0.15 CPU-s of each job, measured on a figure job), objects that live until the process ends in any
case.  The job's last exit handler moves them out of the collector's sight (:func:`gc.freeze`); the
handlers registered before it still run (the log is flushed and closed, as are files), and every
output is written and closed before the script ends.
"""

from __future__ import annotations

import atexit
import gc
import logging

__all__ = ["start_job"]

#: The exit handlers :func:`start_job` registered (atexit does not list them): registered once.
_HANDLERS: list = []


def start_job(log_path: str) -> None:
    """Log to ``log_path`` (INFO, time-stamped lines) and freeze the collector's objects at exit."""
    logging.basicConfig(filename=log_path, level=logging.INFO, format="%(asctime)s %(message)s")
    if not _HANDLERS:
        atexit.register(gc.freeze)
        _HANDLERS.append(gc.freeze)
