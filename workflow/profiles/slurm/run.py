"""Run the workflow on a SLURM cluster through this profile, fitted to the cluster it finds.

    python workflow/profiles/slurm/run.py [--account A] [--partition P] [--check] [snakemake args ...]

Asks the cluster (``scontrol show config``, ``sinfo``) and then runs
``snakemake --workflow-profile workflow/profiles/slurm`` with:

* the partition: ``--partition``, else ``$SBATCH_PARTITION``, else SLURM's default partition
  (``sinfo``'s ``*``); an error naming the partitions if there is none or it is unknown;
* the account: ``--account``, else ``$SBATCH_ACCOUNT``, else none (``--slurm-no-account``); on a
  cluster that enforces associations (``AccountingStorageEnforce``) without an account given, the
  user's default account (``sacctmgr``), else an error saying how to give one;
* every job's resources (the profile's ``default-resources``) cut to what every node of the
  partition has (``sinfo``: CPUs, memory; and the partition's time limit): a job never asks
  for more than the node it lands on;
* job status by ``squeue`` (the profile's ``slurm-status-command``), which works with accounting
  off, where ``sacct`` knows no job; a warning if SLURM forgets finished jobs too early
  (``MinJobAge``) for ``squeue`` to see them.

``--check`` prints what it found and the snakemake command, and runs nothing.  Snakemake's own
arguments (targets, ``--configfile``, ``-n`` ...) follow and are passed on unchanged.
"""

from __future__ import annotations

import argparse
import getpass
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import yaml

PROFILE = Path(__file__).resolve().parent


class ClusterError(RuntimeError):
    """The cluster cannot take the workflow as asked; the message says what to give."""


def slurm(*cmd: str) -> str:
    """Output of a SLURM command; ClusterError with its message if it fails."""
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    except FileNotFoundError:
        raise ClusterError(f"{cmd[0]} not found: is this a SLURM login node (slurm-client installed)?") from None
    if out.returncode:
        raise ClusterError(f"`{shlex.join(cmd)}` failed: {out.stderr.strip() or out.stdout.strip()}")
    return out.stdout


def parse_config(text: str) -> dict[str, str]:
    """``scontrol show config`` as key -> value."""
    conf = {}
    for line in text.splitlines():
        key, sep, value = line.partition("=")
        if sep:
            conf[key.strip()] = value.strip()
    return conf


def minutes(limit: str) -> float | None:
    """A SLURM time limit (``sinfo %l``: ``[D-]HH:MM:SS``, ``MM:SS``, ``MM``, ``infinite``) in minutes."""
    if limit.lower() in ("infinite", "unlimited", "n/a", ""):
        return None
    days, _, clock = limit.rpartition("-")
    parts = [int(p) for p in clock.split(":")]
    if len(parts) == 3:
        h, m, s = parts
    elif len(parts) == 2:
        h, (m, s) = 0, parts
    else:
        h, m, s = 0, parts[0], 0
    return (int(days or 0) * 24 + h) * 60 + m + s / 60


def seconds(value: str) -> int | None:
    """``MinJobAge = 300 sec`` -> 300."""
    match = re.match(r"(\d+)", value or "")
    return int(match.group(1)) if match else None


def default_partition(sinfo_p: str) -> str | None:
    """The partition ``sinfo -h -o %P`` marks with ``*``."""
    for name in sinfo_p.split():
        if name.endswith("*"):
            return name[:-1]
    return None


def node_limits(sinfo_nodes: str) -> tuple[int, int, float | None]:
    """Smallest CPUs and memory (MB) over the partition's nodes, and its time limit (minutes),
    from ``sinfo -h -N -p P -o '%c|%m|%l'``."""
    rows = [line.split("|") for line in sinfo_nodes.splitlines() if line.strip()]
    cpus = min(int(r[0].rstrip("+")) for r in rows)
    mem = min(int(r[1].rstrip("+")) for r in rows)
    return cpus, mem, minutes(rows[0][2])


def needs_account(conf: dict[str, str]) -> bool:
    """Does the cluster refuse jobs without a valid account (enforced associations)?"""
    enforce = conf.get("AccountingStorageEnforce", "none").lower()
    return conf.get("AccountingStorageType", "") != "accounting_storage/none" and any(
        word in enforce for word in ("associations", "limits", "qos", "safe")
    )


def fit_resources(profile: dict, cpus: int, mem_mb: int, max_minutes: float | None) -> dict:
    """The profile's default-resources, each job's CPUs, memory and runtime cut to the partition."""
    res = dict(profile.get("default-resources") or {})
    res["cpus_per_task"] = min(int(res.get("cpus_per_task", 1)), cpus)
    res["mem_mb"] = min(int(res.get("mem_mb", mem_mb)), mem_mb)
    if max_minutes is not None and "runtime" in res:
        res["runtime"] = min(int(res["runtime"]), int(max_minutes))
    return res


def plan(account: str | None, partition: str | None) -> tuple[list[str], list[str]]:
    """(snakemake arguments, lines describing the cluster) for this cluster."""
    conf = parse_config(slurm("scontrol", "show", "config"))
    notes = []
    partitions = slurm("sinfo", "-h", "-o", "%P")
    if not partition:
        partition = default_partition(partitions)
        if not partition:
            raise ClusterError(
                "this cluster has no default partition: give one with --partition NAME or "
                f"SBATCH_PARTITION=NAME (partitions: {partitions.split()})"
            )
        notes.append(f"partition {partition} (the cluster's default)")
    else:
        notes.append(f"partition {partition}")
    nodes = slurm("sinfo", "-h", "-N", "-p", partition, "-o", "%c|%m|%l")
    if not nodes.strip():
        raise ClusterError(f"partition {partition!r} has no nodes or is unknown (partitions: {partitions.split()})")
    cpus, mem, max_minutes = node_limits(nodes)
    notes.append(f"its smallest node: {cpus} CPUs, {mem} MB; time limit {max_minutes or 'none'} min")

    if not account and needs_account(conf):
        try:
            user = getpass.getuser()
            default = slurm("sacctmgr", "-n", "-P", "show", "user", user, "format=DefaultAccount").strip()
        except ClusterError:
            default = ""
        if not default:
            raise ClusterError(
                "this cluster requires an account (AccountingStorageEnforce="
                f"{conf.get('AccountingStorageEnforce')}) and none was given: "
                "give --account NAME or SBATCH_ACCOUNT=NAME (`sacctmgr show assoc user=$USER` lists yours)"
            )
        account = default
        notes.append(f"account {account} (your default account)")

    profile = yaml.safe_load((PROFILE / "config.yaml").read_text())
    accounting = conf.get("AccountingStorageType", "")
    age = seconds(conf.get("MinJobAge", ""))
    # the plugin takes sacct instead of squeue where MinJobAge < 3 x its first status check
    min_age = 3 * int(profile.get("slurm-init-seconds-before-status-checks", 40))
    if accounting == "accounting_storage/none":
        notes.append(f"accounting off: job status by squeue (finished jobs kept {age} s)")
        if age is not None and age < min_age:
            notes.append(
                f"WARNING: MinJobAge={age} s is too short for squeue to see every finished job "
                f"(needs >= {min_age} s) and sacct has no accounting: ask for MinJobAge=300"
            )
    else:
        notes.append(f"accounting {accounting}: job status by squeue, sacct where MinJobAge is short")

    res = fit_resources(profile, cpus, mem, max_minutes)
    res["slurm_partition"] = partition
    if account:
        res["slurm_account"] = account
    notes.append("each job: " + ", ".join(f"{k}={v}" for k, v in res.items()))
    args = ["--workflow-profile", str(PROFILE), "--default-resources", *(f"{k}={v}" for k, v in res.items())]
    if not account:
        args.append("--slurm-no-account")
    return args, notes


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], allow_abbrev=False)
    parser.add_argument("--account", default=os.environ.get("SBATCH_ACCOUNT"), help="default: $SBATCH_ACCOUNT")
    parser.add_argument("--partition", default=os.environ.get("SBATCH_PARTITION"), help="default: $SBATCH_PARTITION")
    parser.add_argument("--check", action="store_true", help="print the cluster found and the command; run nothing")
    ours, rest = parser.parse_known_args(argv)
    try:
        args, notes = plan(ours.account, ours.partition)
    except ClusterError as exc:
        print(f"run.py: {exc}", file=sys.stderr)
        return 2
    cmd = [sys.executable, "-m", "snakemake", *args, *rest]
    for note in notes:
        print(f"SLURM: {note}", file=sys.stderr)
    print(f"SLURM: {shlex.join(cmd)}", file=sys.stderr)
    if ours.check:
        return 0
    sys.stderr.flush()
    os.execv(sys.executable, cmd)
    return 1  # not reached


if __name__ == "__main__":
    sys.exit(main())
