"""Snakemake job: assemble reports/icosim_report.html from the parts' sections + provenance."""

import datetime as dt
import hashlib
import logging
import platform
import subprocess
from pathlib import Path

import icosim
from icosim import report as rp
from icosim.datasets import atomic_path

snakemake = snakemake  # noqa: F821 (injected by Snakemake)

logging.basicConfig(filename=snakemake.log[0], level=logging.INFO, format="%(asctime)s %(message)s")
p = snakemake.params
esc = rp.escape


def git(*args):
    try:
        out = subprocess.run(["git", *args], capture_output=True, text=True, timeout=10, check=True)
        return out.stdout.strip()
    except (OSError, subprocess.SubprocessError):
        return None


commit = git("rev-parse", "HEAD")
dirty = bool(git("status", "--porcelain", "--untracked-files=no")) if commit else False
commit_text = (
    "not available (not a git checkout)"
    if commit is None
    else commit + (" (with uncommitted changes)" if dirty else "")
)

sections = [Path(path).read_text() for path in snakemake.input.sections]
files = [
    [esc(f), f"<code>{hashlib.sha256(Path(f).read_bytes()).hexdigest()}</code>"] for f in snakemake.input.configfiles
]
merged = [[esc(part), f"<code>{sha}</code>"] for part, sha in p.config_sha256.items()]
prec = p.precision
now = dt.datetime.now(dt.timezone.utc).replace(microsecond=0).isoformat()
provenance = (
    '<section id="provenance"><h2>Provenance</h2><ul>'
    f"<li>icosim {esc(icosim.__version__)} (Python {esc(platform.python_version())})</li>"
    f"<li>git commit: <code>{esc(commit_text)}</code></li>"
    f"<li>generated: {esc(now)}</li>"
    f"<li>precision policy: '{esc(prec['policy'])}': float64, with every point float64 cannot decide "
    f"(|ρ − 1| within its error estimate, or not finite) recomputed with mpmath at {int(prec['digits'])} digits; "
    "each dataset records the precision of every point</li>"
    + (f"<li>parts without a section (not built): {esc(', '.join(p.skipped))}</li>" if p.skipped else "")
    + "</ul><h3>Configuration files (SHA-256)</h3>"
    + rp.table(["file", "sha256"], files, raw_columns=(0, 1))
    + "<h3>Effective configuration per part (SHA-256 of its canonical JSON)</h3>"
    + rp.table(["part", "sha256"], merged, raw_columns=(0, 1))
    + "</section>"
)
toc = (
    "<nav><ul>"
    + "".join(f'<li><a href="#{esc(part)}">{esc(part)}</a></li>' for part in p.parts)
    + '<li><a href="#provenance">provenance</a></li></ul></nav>'
)
html = rp.page(p.title, [toc] + sections, provenance)
with atomic_path(snakemake.output[0]) as tmp:
    tmp.write_text(html)
logging.info("report with sections %s (skipped: %s), commit %s", p.parts, p.skipped, commit_text)
