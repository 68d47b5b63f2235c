"""The process of a workflow job: its log file.

Every script of ``workflow/scripts`` starts with :func:`start_job`.
"""

from __future__ import annotations

import logging

__all__ = ["start_job"]


def start_job(log_path: str) -> None:
    """Log to ``log_path`` (INFO, time-stamped lines)."""
    logging.basicConfig(filename=log_path, level=logging.INFO, format="%(asctime)s %(message)s")
