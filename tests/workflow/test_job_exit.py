"""A workflow job's process (icosim.job.start_job): its log is written in full."""

import subprocess
import sys
import textwrap

JOB = textwrap.dedent(
    """
    import logging, sys
    from icosim.job import start_job
    start_job(sys.argv[1])
    logging.info("the last line of the job")
    """
)


def test_the_log_is_complete(tmp_path):
    log = tmp_path / "job.log"
    subprocess.run([sys.executable, "-c", JOB, str(log)], capture_output=True, text=True, check=True)
    assert log.read_text().rstrip().endswith("the last line of the job")


def test_every_job_script_starts_with_its_log():
    from helpers import ROOT

    scripts = sorted((ROOT / "workflow" / "scripts").glob("*.py"))
    assert scripts
    for script in scripts:
        text = script.read_text()
        assert "start_job(snakemake.log[0])" in text, script.name
        assert "logging.basicConfig" not in text, script.name
