"""Fault injection on the workflow (the long cases; the fast ones are in tests/workflow/test_workflow_faults.py).

On a clean copy of this tree and the CI configuration's stability part (or ``--part``), each case is
compared with a clean run of the same configuration:

* **kills**: Snakemake and its jobs get SIGKILL at random moments (seeded), at least ``--kills`` times,
  each followed by the documented recovery (the same command; ``snakemake --unlock`` first where
  Snakemake asks for it), until a run completes;
* **job killed**: one job's process is killed while Snakemake goes on: Snakemake reports the rule and its
  log, and the same command completes without redoing finished jobs;
* **second run**: a second ``snakemake`` on the same directory while one runs is refused, and the first
  completes;
* **datasets**: truncated, bit-flipped, deleted, replaced by another panel's file, a stale temporary;
  then the same command;
* **read-only results/**: the run fails naming the path; once writable, the same command completes;
* **full disk**: ``results/`` on a small tmpfs: the run fails naming the path, every dataset left behind
  verifies (none half-written that looks complete); moved to a roomy disk, the same command completes.

Every dataset of every case is then compared with the clean run's (``tools/compare_results.py``:
bitwise, timings aside).  Prints a table: faults injected, survived, datasets compared, differences,
anything lost.  Never a timed assertion.

    python benchmarks/faults.py [--kills 20] [--seed 0] [--part stability]
"""

from __future__ import annotations

import argparse
import os
import random
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

from _workflow import ROOT, snakemake_binary, tree

sys.path.insert(0, str(ROOT / "tools"))
from compare_results import compare  # noqa: E402

CONFIGS = ["config/ci/stability.yaml", "config/ci/convergence.yaml", "config/ci/pendulum.yaml"]
TARGETS = {
    "stability": ["results/report/stability.html"],
    "convergence": ["results/report/convergence.html"],
    "all": [],
}


def command(workdir: Path, targets, *extra):
    return [snakemake_binary(), "--directory", str(workdir), "-c2", *targets, *extra, "--configfile", *CONFIGS]


def run(workdir: Path, targets, *extra, check=False):
    proc = subprocess.run(command(workdir, targets, *extra), cwd=workdir, capture_output=True, text=True)
    if check and proc.returncode:
        raise SystemExit(f"snakemake failed in {workdir}:\n{proc.stderr[-3000:]}")
    return proc


def recover(workdir: Path, targets) -> tuple[int, bool]:
    """The documented recovery: the same command; ``--unlock`` once where Snakemake asks for it.
    Returns (runs needed, unlock needed)."""
    proc = run(workdir, targets)
    if proc.returncode == 0:
        return 1, False
    if "--unlock" in proc.stdout + proc.stderr:
        run(workdir, targets, "--unlock", check=True)
        run(workdir, targets, check=True)
        return 2, True
    run(workdir, targets, check=True)  # a job that failed: the same command once more
    return 2, False


def start(workdir: Path, targets, log: Path | None = None):
    out = open(log, "w") if log else subprocess.DEVNULL  # noqa: SIM115 - closed by the caller's wait
    return subprocess.Popen(
        command(workdir, targets), cwd=workdir, stdout=out, stderr=subprocess.STDOUT, start_new_session=True
    )


def kills(workdir: Path, targets, n: int, rng: random.Random, max_wait: float) -> dict:
    """SIGKILL Snakemake (and its jobs) at random moments, at least ``n`` times, each followed by the
    documented recovery (``--unlock`` where Snakemake asks for it); then the same command to the end."""
    killed = unlocks = restarts = 0
    log = workdir / "faults_run.log"
    while killed < n:
        proc = start(workdir, targets, log)
        time.sleep(rng.uniform(0.5, max_wait))
        if proc.poll() is not None:
            if proc.returncode and "--unlock" in log.read_text():  # the lock a killed run left: recover
                run(workdir, targets, "--unlock", check=True)
                unlocks += 1
            elif proc.returncode == 0:  # finished before the kill: start over for more kills
                shutil.rmtree(workdir / "results", ignore_errors=True)
                restarts += 1
            else:
                raise SystemExit(f"snakemake failed in {workdir} (not a lock):\n{log.read_text()[-3000:]}")
            continue
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        killed += 1
        print(f"  kill {killed}", flush=True)
    runs, unlocked = recover(workdir, targets)
    return dict(injected=killed, unlocks=unlocks + unlocked, restarts=restarts)


def job_killed(workdir: Path, targets) -> dict:
    proc = subprocess.Popen(command(workdir, targets), cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
    victim = None
    deadline = time.monotonic() + 120
    while victim is None and time.monotonic() < deadline:
        out = subprocess.run(["pgrep", "-f", str(workdir / ".snakemake/scripts")], capture_output=True, text=True)
        victim = int(out.stdout.split()[0]) if out.stdout.split() else None
        time.sleep(0.05)
    if victim:
        os.kill(victim, signal.SIGKILL)
    log = proc.communicate()[0].decode(errors="replace")
    reported = "Error in rule" in log and "log:" in log
    run(workdir, targets, check=True)
    return dict(injected=int(victim is not None), reported=reported)


def second_run(workdir: Path, targets) -> dict:
    first = start(workdir, targets)
    time.sleep(3.0)
    second = run(workdir, targets)
    refused = second.returncode != 0 and "lock" in (second.stdout + second.stderr).lower()
    first.wait()
    if first.returncode:
        run(workdir, targets, check=True)
    return dict(injected=1, refused=refused, first_ok=first.returncode == 0)


def dataset_faults(workdir: Path, targets, rng: random.Random) -> dict:
    panels = sorted((workdir / "results").rglob("*.nc"))
    picks = rng.sample(panels, 5)
    picks[0].write_bytes(picks[0].read_bytes()[:1000])  # truncated
    data = bytearray(picks[1].read_bytes())
    data[len(data) // 2] ^= 0x01  # one bit flipped
    picks[1].write_bytes(bytes(data))
    picks[2].unlink()  # deleted
    shutil.copy2(picks[4], picks[3])  # replaced by another panel's file
    (picks[4].parent / f".{picks[4].name}.x1y2z3.part").write_bytes(b"half")  # a stale temporary
    run(workdir, targets, check=True)
    left = list((workdir / "results").rglob(".*.part"))
    return dict(injected=5, stale_left=len(left))


def read_only_results(workdir: Path, targets) -> dict:
    """``results/`` read-only (a read-only bind mount: root too is refused) with a dataset to rebuild: the run
    fails naming the path; after the mount is gone the same command completes."""
    victim = sorted((workdir / "results").rglob("*.nc"))[0]
    victim.unlink()
    res = str(workdir / "results")
    if subprocess.run(["mount", "--bind", res, res], capture_output=True).returncode:
        return dict(injected=0, note="no bind mount here (not root)")
    subprocess.run(["mount", "-o", "remount,ro,bind", res], check=True)
    try:
        proc = run(workdir, targets)
        text = proc.stdout + proc.stderr
        # Snakemake refuses before any job ("Write-protected output files", naming them); a job would say
        # "Read-only file system" with its path
        refused = "Write-protected output files" in text or "Read-only file system" in text
        named = proc.returncode != 0 and refused and "results/" in text
    finally:
        subprocess.run(["umount", res], check=True)
    run(workdir, targets, check=True)
    return dict(injected=1, refused_naming_the_path=named)


def full_disk(workdir: Path, targets, clean: Path) -> dict:
    """``results/`` on a tmpfs a third the size of a finished run's: the run fails naming a path and the full
    disk; every dataset it left verifies against its checksum and opens (none half-written that looks
    complete) and no temporary is left; the finished datasets moved to a roomy disk, the same command completes."""
    from icosim.io.integrity import verify
    from icosim.io.netcdf import open_dataset

    size = sum(p.stat().st_size for p in (clean / "results").rglob("*") if p.is_file())
    res = workdir / "results"
    res.mkdir(exist_ok=True)
    if subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size // 3}", "tmpfs", str(res)]).returncode:
        return dict(injected=0, note="no tmpfs mount here (not root)")
    try:
        proc = run(workdir, targets)
        text = proc.stdout + proc.stderr
        named = proc.returncode != 0 and "results/" in text and ("no space left" in text.lower())
        datasets = sorted(res.rglob("*.nc"))
        whole = 0
        for path in datasets:
            ok = verify(path)
            if ok:
                open_dataset(path).close()
                whole += 1
        parts = list(res.rglob("*.part"))
        keep = workdir / "results.kept"
        shutil.copytree(res, keep, symlinks=True)
    finally:
        subprocess.run(["umount", str(res)], check=True)
    res.rmdir()
    keep.rename(res)
    run(workdir, targets, check=True)
    return dict(
        injected=1,
        refused_naming_the_path=named,
        datasets_left=len(datasets),
        verified=whole,
        unverified=len(datasets) - whole,
        parts_left=len(parts),
    )


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--kills", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--part", choices=sorted(TARGETS), default="stability")
    ap.add_argument("--max-wait", type=float, default=6.0, help="longest time before a kill, s")
    args = ap.parse_args(argv)
    rng = random.Random(args.seed)
    targets = TARGETS[args.part]
    rows = []
    with tree(None) as clean, tree(None) as work:
        run(clean, targets, check=True)
        cases = [
            ("SIGKILL of Snakemake at random moments", lambda: kills(work, targets, args.kills, rng, args.max_wait)),
            ("a job's process killed", lambda: job_killed(work, targets)),
            ("a second snakemake while one runs", lambda: second_run(work, targets)),
            (
                "datasets truncated, flipped, deleted, replaced; a stale .part",
                lambda: dataset_faults(work, targets, rng),
            ),
            ("results/ read-only", lambda: read_only_results(work, targets)),
            ("results/ on a full disk (tmpfs)", lambda: full_disk(work, targets, clean)),
        ]
        for i, (name, case) in enumerate(cases):
            if i:  # each case from a clean results/
                shutil.rmtree(work / "results", ignore_errors=True)
                if name.startswith(("datasets", "results/ read-only")):  # these damage a finished run
                    run(work, targets, check=True)
            info = case()
            set_aside = sorted((work / "results").rglob("*.corrupt"))  # the damaged copies, kept for a look
            for path in set_aside:
                path.unlink()
            if set_aside:
                info["set_aside"] = len(set_aside)
            problems, notes = compare(clean, work)
            n = sum(1 for _ in (work / "results").rglob("*.nc"))
            lost = sum(1 for p in problems if "only in OLD" in p)
            rows.append((name, info, n, problems, lost))
    print(f"fault injection, CI configuration ({args.part}), seed {args.seed}")
    print(f"{'fault':<62}{'injected':>9}{'survived':>9}{'datasets':>9}{'differ':>8}{'lost':>6}  detail")
    total_injected = 0
    for name, info, n, problems, lost in rows:
        survived = info["injected"] if not problems else 0
        total_injected += info["injected"]
        detail = ", ".join(f"{k}={v}" for k, v in info.items() if k != "injected")
        print(f"{name:<62}{info['injected']:>9}{survived:>9}{n:>9}{len(problems):>8}{lost:>6}  {detail}")
        for p in problems[:10]:
            print("    DIFFERS:", p)
    print(f"faults injected: {total_injected}; runs with any difference: {sum(bool(r[3]) for r in rows)}")
    return 1 if any(r[3] for r in rows) else 0


if __name__ == "__main__":
    sys.exit(main())
