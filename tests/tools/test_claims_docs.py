"""The documentation's table of claims is the one the claims files give (tools/claims_table.py)."""

import subprocess
import sys

from helpers import ROOT


def test_docs_claims_table_is_current():
    proc = subprocess.run(
        [sys.executable, str(ROOT / "tools" / "claims_table.py"), "--check"], capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr
