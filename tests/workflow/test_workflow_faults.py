"""Faults of the workflow's files: nothing corrupt trusted, nothing lost, the same command brings it back.

A real run of a one-figure configuration (Fig. 18, two rows, 4 x 4 grid) and its claims, in a copy of
the workflow; then, one at a time, a dataset truncated, bit-flipped, deleted or replaced by another
panel's file, a stale temporary, and a killed run.  Each case is compared with the clean run: the
rebuilt datasets hold the same numbers, and everything built from them is rebuilt.
"""

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
import yaml
from helpers import SNAKEMAKE, copy_workflow, scheduled_jobs, snakemake

from icosim.io.integrity import lost_datasets, outputs_built_from, quarantine_corrupt, sidecar, verify
from icosim.io.netcdf import open_dataset

FIGURE = "results/stability/figures/fig18_jacobi.png"
CLAIMS = "results/stability/claims.json"
PANEL = "results/stability/fig18/jacobi/r1_k0_full.nc"
OTHER = "results/stability/fig18/jacobi/r2_k1_full.nc"


def _configure(wf: Path):
    cfg = yaml.safe_load((wf / "config" / "stability.yaml").read_text())
    st = cfg["stability"]
    st["grid"]["n"] = 4
    st["zoom_grid"]["n"] = 3
    st["figures"] = {"18": {**st["figures"]["18"], "rows": [{}, {"am21": 3.0}]}}
    (wf / "config" / "stability.yaml").write_text(yaml.safe_dump(cfg))


@pytest.fixture(scope="module")
def clean_run(tmp_path_factory):
    wf = copy_workflow(tmp_path_factory.mktemp("clean"))
    _configure(wf)
    snakemake(wf, "-c2", FIGURE, CLAIMS)
    return wf


@pytest.fixture
def run(clean_run, tmp_path):
    """A copy of the clean run (its results and Snakemake's records) to break."""
    wf = tmp_path / "wf"
    shutil.copytree(clean_run, wf, symlinks=True)
    return wf


def _rho(path):
    with open_dataset(path) as ds:
        return ds["rho"].values.copy(), ds["verdict"].values.copy()


def _same_numbers(a: Path, b: Path):
    (ra, va), (rb, vb) = _rho(a), _rho(b)
    np.testing.assert_array_equal(va, vb)
    np.testing.assert_array_equal(ra, rb)


def _truncate(path):
    path.write_bytes(path.read_bytes()[:1000])


def _flip_bit(path):
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x10
    path.write_bytes(bytes(data))


def _replace_by_other_panel(path):
    shutil.copy2(path.parent / Path(OTHER).name, path)


def _delete(path):
    path.unlink()


@pytest.mark.parametrize("fault", [_truncate, _flip_bit, _replace_by_other_panel, _delete])
def test_a_broken_dataset_is_rebuilt_by_a_one_figure_target(run, clean_run, fault):
    fault(run / PANEL)
    dry = snakemake(run, "-n", FIGURE)
    jobs = scheduled_jobs(dry, "stability_")
    assert set(jobs) == {"stability_panels_fig18", "stability_figure_fig18"}, dry.stdout[-2000:]
    snakemake(run, "-c2", FIGURE)
    assert verify(run / PANEL) is True  # rebuilt, its checksum recorded again
    _same_numbers(run / PANEL, clean_run / PANEL)
    assert (run / FIGURE).stat().st_mtime > (run / PANEL).stat().st_mtime
    # the claims, built from the lost dataset, were set aside with it; the next run of them rebuilds them
    assert not (run / CLAIMS).exists()
    snakemake(run, "-c2", CLAIMS)
    assert (run / CLAIMS).read_text() and (run / CLAIMS).stat().st_mtime > (run / PANEL).stat().st_mtime


def test_claims_target_rebuilds_a_deleted_dataset_and_the_claims(run, clean_run):
    (run / PANEL).unlink()
    snakemake(run, "-c2", CLAIMS)
    _same_numbers(run / PANEL, clean_run / PANEL)
    assert (run / CLAIMS).stat().st_mtime > (run / PANEL).stat().st_mtime


def test_every_dataset_is_a_target_of_all(run):
    """A dataset lost with its sidecar (no trace left) is still built again by the README's command."""
    (run / PANEL).unlink()
    sidecar(run / PANEL).unlink()
    dry = snakemake(run, "-n")  # rule all
    assert PANEL in scheduled_jobs(dry, "stability_panels_fig18")["stability_panels_fig18"]
    assert "stability_claims" in scheduled_jobs(dry, "stability_claims")


def test_a_stale_temporary_is_never_taken_for_a_dataset_and_the_next_working_run_removes_it(run, clean_run):
    part = run / "results/stability/fig18/jacobi/.r1_k0_full.nc.abc123.part"
    part.write_bytes(b"half a dataset")
    proc = snakemake(run, "-c2", FIGURE)
    assert "Nothing to be done" in proc.stdout + proc.stderr  # a temporary is nobody's output
    (run / OTHER).unlink()
    snakemake(run, "-c2", FIGURE)  # a run with jobs clears temporaries under its lock before they start
    assert not part.exists()
    _same_numbers(run / OTHER, clean_run / OTHER)


def test_a_killed_run_resumes_with_the_documented_recovery(clean_run, tmp_path):
    """SIGKILL of Snakemake while a job runs; then `snakemake --unlock` where Snakemake asks for it and the
    same command: the datasets equal the clean run's (the repository's default profile reruns incomplete
    outputs, as `snakemake` loads it from profiles/default)."""
    (tmp_path / "wf").mkdir()
    wf = copy_workflow(tmp_path / "wf")
    _configure(wf)
    cmd = [SNAKEMAKE, "--directory", str(wf), "--snakefile", str(wf / "Snakefile"), "-c2", FIGURE]
    proc = subprocess.Popen(cmd, cwd=wf, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True)
    deadline = time.monotonic() + 120
    while not list((wf / ".snakemake").glob("incomplete/*")) and time.monotonic() < deadline:
        time.sleep(0.05)  # until a job has started (its outputs are marked incomplete)
    assert list((wf / ".snakemake").glob("incomplete/*")), "no job started within 120 s"
    os.killpg(proc.pid, signal.SIGKILL)  # Snakemake and its job, as an out-of-memory kill would
    proc.wait()
    assert not (wf / FIGURE).exists()  # killed before the end
    again = snakemake(wf, "-c2", FIGURE, check=False)
    if again.returncode != 0:
        assert "--unlock" in again.stdout + again.stderr
        snakemake(wf, "--unlock")
        snakemake(wf, "-c2", FIGURE)
    for rel in (PANEL, OTHER):
        _same_numbers(wf / rel, clean_run / rel)
    assert (wf / FIGURE).exists()


# -- the library side --------------------------------------------------------------------------------
def test_lost_datasets_are_those_with_a_trace(tmp_path):
    for name in ("a.nc", "b.nc", "c.nc", "d.nc"):
        (tmp_path / name).write_bytes(b"x")
        sidecar(tmp_path / name).write_text("0" * 64 + "  x\n")
    (tmp_path / "a.nc").unlink()  # deleted: the sidecar stays
    (tmp_path / "b.nc").write_bytes(b"y")  # corrupt: set aside below
    (tmp_path / "d.nc").unlink()
    sidecar(tmp_path / "d.nc").unlink()  # no trace
    moved = quarantine_corrupt(tmp_path)
    assert sorted(p.name for p in moved) == ["b.nc.corrupt", "c.nc.corrupt"]  # c's checksum never matched either
    assert [p.name for p in lost_datasets(tmp_path)] == ["a.nc", "b.nc", "c.nc"]


def test_outputs_built_from_follow_wildcards():
    rules = [
        (["results/runs/{scheme}/{method}_k{k}.nc", "src/x.py"], ["results/figures/{method}_{scheme}.png"]),
        (["results/runs/jacobi/a_k1.nc", "results/runs/jacobi/b_k1.nc"], ["results/summary.nc"]),
        (["results/summary.nc"], ["report.html"]),  # downstream of a downstream: not a direct reader
        (["results/runs/{scheme}/{method}_k{k}.nc"], ["results/{other}.png"]),  # a wildcard the input leaves open
    ]
    assert outputs_built_from("results/runs/jacobi/a_k1.nc", rules) == [
        "results/figures/a_jacobi.png",
        "results/summary.nc",
    ]
    assert outputs_built_from("results/runs/gauss-seidel-12/b_k0.nc", rules) == [
        "results/figures/b_gauss-seidel-12.png"
    ]
    assert outputs_built_from("results/elsewhere.nc", rules) == []


@pytest.fixture
def small_disk(tmp_path):
    """A 200 kB tmpfs (needs root, as CI has); skipped where it cannot be mounted."""
    mnt = tmp_path / "small"
    mnt.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=200k", "tmpfs", str(mnt)], capture_output=True).returncode:
        pytest.skip("cannot mount a tmpfs here (not root)")
    yield mnt
    subprocess.run(["umount", str(mnt)], capture_output=True)


def test_a_full_disk_is_a_clear_error_and_leaves_no_dataset(small_disk):
    import xarray as xr

    from icosim.io.netcdf import write_netcdf

    ds = xr.Dataset({"rho": (("lr1", "li1"), np.random.default_rng(0).random((300, 300)))})
    with pytest.raises(OSError, match=r"could not write .*x\.nc: no space left on its file system"):
        write_netcdf(ds, small_disk / "x.nc")
    assert list(small_disk.iterdir()) == []  # no dataset, no sidecar, no temporary


# -- the command line, interrupted ---------------------------------------------------------------------
def _wait_for_cpu(proc, seconds: float, timeout: float = 300.0):
    """Until ``proc`` has used ``seconds`` of CPU (its own, from /proc) or ended: a wall-clock sleep is too
    short on a loaded machine, where the imports alone can take longer."""
    tick = os.sysconf("SC_CLK_TCK")
    deadline = time.monotonic() + timeout
    while proc.poll() is None and time.monotonic() < deadline:
        fields = Path(f"/proc/{proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        if (int(fields[11]) + int(fields[12])) / tick >= seconds:  # utime + stime
            return
        time.sleep(0.05)


@pytest.mark.parametrize(
    "args",
    [
        ["map", "--method", "weighted", "--a", "1", "--b", "1", "--decomposition", "ff", "--k", "1", "2"]
        + ["--lr1", "-0.2", "0", "--li1", "0", "0.2", "--n", "301", "--out", "{out}/wm"],
        ["advise", "--m1", "1", "--m2", "2", "--c1", "1e3", "--c2", "2e3", "--d1", "2", "--d2", "4"]
        + ["--H", "1e-4", "1e-1", "--scan", "2000", "--rtol", "1e-12", "--json"],
    ],
    ids=["map", "advise-json"],
)
def test_sigint_leaves_no_partial_output(tmp_path, args):
    import sys

    out = tmp_path / "out"
    out.mkdir()
    cmd = [sys.executable, "-m", "icosim.cli", *[a.format(out=out) for a in args]]
    # a test worker may ignore SIGINT, and a child inherits that: give the command the terminal's default
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    _wait_for_cpu(proc, 2.0)  # past the imports (about 1 CPU-s), inside the computation, however loaded the machine
    assert proc.poll() is None, "finished before it could be interrupted"
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert "interrupted; no output file was left half-written" in stderr and "Traceback" not in stderr
    assert stdout == ""  # no half-printed JSON
    leftovers = list(out.iterdir())
    assert not [p for p in leftovers if p.name.endswith(".part")]
    for path in leftovers:  # whatever was finished before the signal is whole
        if path.suffix == ".nc":
            assert verify(path) is True
