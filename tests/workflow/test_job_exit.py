"""A workflow job's process (icosim.job.start_job): its log is written in full, and its objects are frozen
at exit, after the job's own work and before the exit handlers registered earlier (the log's flush)."""

import subprocess
import sys
import textwrap

JOB = textwrap.dedent(
    """
    import atexit, gc, logging, sys
    # registered before start_job, so run after its handler (atexit is last in, first out)
    atexit.register(lambda: print("frozen at exit:", gc.get_freeze_count() > 0))
    from icosim.job import start_job
    start_job(sys.argv[1])
    start_job(sys.argv[1])  # a second call registers nothing more
    print("frozen during the job:", gc.get_freeze_count() > 0)
    logging.info("the last line of the job")
    """
)


def test_the_log_is_complete_and_the_objects_are_frozen_only_at_exit(tmp_path):
    log = tmp_path / "job.log"
    out = subprocess.run([sys.executable, "-c", JOB, str(log)], capture_output=True, text=True, check=True).stdout
    assert out.splitlines() == ["frozen during the job: False", "frozen at exit: True"]
    assert log.read_text().rstrip().endswith("the last line of the job")


def test_every_job_script_starts_with_its_log():
    from helpers import ROOT

    scripts = sorted((ROOT / "workflow" / "scripts").glob("*.py"))
    assert scripts
    for script in scripts:
        text = script.read_text()
        assert "start_job(snakemake.log[0])" in text, script.name
        assert "logging.basicConfig" not in text, script.name
