"""The report page: the parts' sections in the configured order, navigation and provenance."""

from __future__ import annotations

import datetime as dt
import hashlib
import platform
import subprocess
from pathlib import Path

from .. import __version__
from .html import escape as esc
from .html import page, table

__all__ = ["report_page", "git_commit_text", "utc_now"]


def git_commit_text(cwd=None) -> str:
    """The checkout's commit, marked if the tracked files have uncommitted changes."""

    def git(*args):
        try:
            out = subprocess.run(["git", *args], capture_output=True, text=True, timeout=10, check=True, cwd=cwd)
            return out.stdout.strip()
        except (OSError, subprocess.SubprocessError):
            return None

    commit = git("rev-parse", "HEAD")
    dirty = bool(git("status", "--porcelain", "--untracked-files=no")) if commit else False
    if commit is None:
        return "not available (not a git checkout)"
    return commit + (" (with uncommitted changes)" if dirty else "")


def utc_now() -> str:
    return dt.datetime.now(dt.UTC).replace(microsecond=0).isoformat()


def report_page(
    *,
    title: str,
    parts: list,
    skipped: list,
    sections: list,
    configfiles: list,
    config_sha256: dict,
    precision: dict,
    commit_text: str,
    generated: str,
) -> str:
    """The whole page.

    ``parts`` name the ``sections`` (HTML fragments, in order), ``skipped`` the
    configured parts without a section; ``configfiles`` are hashed as they are
    on disk, ``config_sha256`` is the hash of each part's effective
    configuration; ``precision`` the stability precision policy;
    ``commit_text`` and ``generated`` say which code made the page, and when.
    """
    files = [[esc(f), f"<code>{hashlib.sha256(Path(f).read_bytes()).hexdigest()}</code>"] for f in configfiles]
    merged = [[esc(part), f"<code>{sha}</code>"] for part, sha in config_sha256.items()]
    prec = precision
    provenance = (
        '<section id="provenance"><h2>Provenance</h2><ul>'
        f"<li>icosim {esc(__version__)} (Python {esc(platform.python_version())})</li>"
        f"<li>git commit: <code>{esc(commit_text)}</code></li>"
        f"<li>generated: {esc(generated)}</li>"
        f"<li>precision policy: '{esc(prec['policy'])}': float64, with every point float64 cannot decide "
        f"(|ρ − 1| within its error estimate, or not finite) recomputed with mpmath at {int(prec['digits'])} digits; "
        "each dataset records the precision of every point</li>"
        + (f"<li>parts without a section (not built): {esc(', '.join(skipped))}</li>" if skipped else "")
        + "</ul><h3>Configuration files (SHA-256)</h3>"
        + table(["file", "sha256"], files, raw_columns=(0, 1))
        + "<h3>Effective configuration per part (SHA-256 of its canonical JSON)</h3>"
        + table(["part", "sha256"], merged, raw_columns=(0, 1))
        + "</section>"
    )
    toc = (
        "<nav><ul>"
        + "".join(f'<li><a href="#{esc(part)}">{esc(part)}</a></li>' for part in parts)
        + '<li><a href="#provenance">provenance</a></li></ul></nav>'
    )
    return page(title, [toc] + list(sections), provenance)
