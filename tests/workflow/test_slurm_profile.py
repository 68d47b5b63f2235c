"""The SLURM profile (workflow/profiles/slurm): what run.py makes of a cluster's answers.

The cluster is faked (scontrol and sinfo outputs); the one test that asks a real cluster is marked
``slurm`` (skipped where none answers).  The profile on a real one-node cluster is
workflow/profiles/slurm/ci_check.sh (CI's SLURM step).
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import pytest
import yaml
from helpers import ROOT

PROFILE = ROOT / "workflow" / "profiles" / "slurm"


def _load_run():
    spec = importlib.util.spec_from_file_location("slurm_profile_run", PROFILE / "run.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


run = _load_run()

CONFIG_OFF = "AccountingStorageEnforce = none\nAccountingStorageType   = accounting_storage/none\nMinJobAge = 300 sec\n"
CONFIG_ENFORCED = (
    "AccountingStorageEnforce = associations,limits\n"
    "AccountingStorageType   = accounting_storage/slurmdbd\nMinJobAge = 300 sec\n"
)


def fake_cluster(monkeypatch, config=CONFIG_OFF, partitions="debug*\nlong\n", nodes="2|23593|infinite\n", accounts=""):
    def slurm(*cmd):
        if cmd[:2] == ("scontrol", "show"):
            return config
        if cmd[0] == "sinfo" and "-N" in cmd:
            return nodes if cmd[cmd.index("-p") + 1] in partitions.replace("*", "").split() else ""
        if cmd[0] == "sinfo":
            return partitions
        if cmd[0] == "sacctmgr":
            return accounts
        raise AssertionError(cmd)

    monkeypatch.setattr(run, "slurm", slurm)


def resources(args):
    start = args.index("--default-resources") + 1
    return dict(a.split("=", 1) for a in args[start:] if "=" in a and not a.startswith("--"))


def test_profile_asks_squeue_one_core_and_no_site_names():
    profile = yaml.safe_load((PROFILE / "config.yaml").read_text())
    assert profile["executor"] == "slurm"
    assert profile["slurm-status-command"] == "squeue"  # sacct finds no job without accounting
    res = profile["default-resources"]
    assert res["cpus_per_task"] == 1
    assert "slurm_partition" not in res and "slurm_account" not in res


@pytest.mark.parametrize(
    "limit, minutes",
    [("infinite", None), ("UNLIMITED", None), ("30", 30), ("30:00", 30), ("2:00:00", 120), ("1-00:00:00", 1440)],
)
def test_time_limits(limit, minutes):
    assert run.minutes(limit) == minutes


def test_default_partition_and_smallest_node():
    assert run.default_partition("long\ndebug*\n") == "debug"
    assert run.default_partition("long\nshort\n") is None
    assert run.node_limits("8|64000|1-00:00:00\n2|1500|1-00:00:00\n") == (2, 1500, 1440)


def test_plan_on_a_cluster_without_accounting(monkeypatch):
    fake_cluster(monkeypatch)
    args, notes = run.plan(None, None)
    res = resources(args)
    assert res["slurm_partition"] == "debug" and "slurm_account" not in res
    assert res["cpus_per_task"] == "1" and res["mem_mb"] == "2000"
    assert "--slurm-no-account" in args
    assert any("squeue" in n for n in notes)


def test_resources_cut_to_the_partitions_smallest_node(monkeypatch):
    fake_cluster(monkeypatch, partitions="tiny*\n", nodes="1|900|10\n4|8000|10\n")
    res = resources(run.plan(None, None)[0])
    assert (res["cpus_per_task"], res["mem_mb"], res["runtime"]) == ("1", "900", "10")


def test_partition_and_account_given(monkeypatch):
    fake_cluster(monkeypatch, config=CONFIG_ENFORCED)
    args, _ = run.plan("proj1", "long")
    res = resources(args)
    assert res["slurm_partition"] == "long" and res["slurm_account"] == "proj1"
    assert "--slurm-no-account" not in args


def test_unknown_partition_is_named(monkeypatch):
    fake_cluster(monkeypatch)
    with pytest.raises(run.ClusterError, match="'gpu' has no nodes or is unknown"):
        run.plan(None, "gpu")


def test_no_default_partition_says_how_to_give_one(monkeypatch):
    fake_cluster(monkeypatch, partitions="long\nshort\n")
    with pytest.raises(run.ClusterError, match="--partition NAME or SBATCH_PARTITION"):
        run.plan(None, None)


def test_enforced_account_missing_says_how_to_give_one(monkeypatch):
    fake_cluster(monkeypatch, config=CONFIG_ENFORCED)
    with pytest.raises(run.ClusterError, match="requires an account .* --account NAME or SBATCH_ACCOUNT"):
        run.plan(None, None)


def test_enforced_account_falls_back_to_the_users_default(monkeypatch):
    fake_cluster(monkeypatch, config=CONFIG_ENFORCED, accounts="proj2\n")
    assert resources(run.plan(None, None)[0])["slurm_account"] == "proj2"


def test_main_reports_a_cluster_error_without_traceback(monkeypatch, capsys):
    fake_cluster(monkeypatch, config=CONFIG_ENFORCED)
    monkeypatch.delenv("SBATCH_ACCOUNT", raising=False)
    monkeypatch.delenv("SBATCH_PARTITION", raising=False)
    assert run.main(["--check"]) == 2
    assert "requires an account" in capsys.readouterr().err


@pytest.mark.slurm
def test_check_on_the_live_cluster():
    out = subprocess.run(
        [sys.executable, str(PROFILE / "run.py"), "--check"], capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    assert "SLURM: partition" in out.stderr and "--workflow-profile" in out.stderr
