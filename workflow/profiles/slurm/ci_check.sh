#!/usr/bin/env bash
# The SLURM profile on a one-node cluster of this machine: CI's SLURM step, and a way to try the
# profile on a laptop.  Root; Debian's packages installed (apt-get install -y slurmctld slurmd
# slurm-client munge); the project's .venv set up.  It
#   1. starts the cluster (one_node_cluster.sh up) and stops it on exit, however it exits;
#   2. runs the stability part of the CI configuration twice, each in its own copy of the tree:
#      locally (-c2, workflow/profiles/local) and through the profile (run.py), timed;
#   3. compares the two result trees with tools/compare_results.py: identical;
#   4. kills a job on the cluster (scancel while it runs): Snakemake must fail naming the rule and
#      the job's SLURM log; a rerun through the profile must complete without redoing the jobs that
#      had finished (the other figures' datasets keep their mtimes), and the results stay identical.
#
#   workflow/profiles/slurm/ci_check.sh        # ~4 min on 2 cores; work dirs under /tmp, kept
set -euo pipefail
cd "$(dirname "$0")/../../.."
ROOT=$PWD
PY=$ROOT/.venv/bin/python
HERE=$ROOT/workflow/profiles/slurm
WORK=$(mktemp -d /tmp/icosim-slurm-check.XXXXXX)
TARGET=results/report/stability.html
CONFIG=(--configfile config/ci/stability.yaml)
export MPLBACKEND=Agg

pid=""
cleanup() {
    if [[ -n $pid ]] && kill -0 "$pid" 2>/dev/null; then # a Snakemake of ours still running (a failed check)
        kill "$pid"
        for _ in $(seq 40); do kill -0 "$pid" 2>/dev/null || break; sleep 0.5; done
        kill -9 "$pid" 2>/dev/null || true
    fi
    "$HERE/one_node_cluster.sh" down
}
trap cleanup EXIT
"$HERE/one_node_cluster.sh" up

copy() { # a copy of the tree without results, logs or Snakemake's state: shares nothing with ROOT's runs
    mkdir -p "$1"
    tar -C "$ROOT" --exclude=./.git --exclude=./.venv --exclude=./results --exclude=./reports \
        --exclude=./logs --exclude=./.snakemake --exclude=./docs/_build -cf - . | tar -C "$1" -xf -
}
now() { date +%s.%N; }
fail() {
    echo "SLURM check FAILED: $*" >&2
    exit 1
}
copy "$WORK/local"
copy "$WORK/slurm"

echo "== the stability part (CI configuration), locally with -c2"
t0=$(now)
(cd "$WORK/local" && "$PY" -m snakemake --workflow-profile workflow/profiles/local "$TARGET" "${CONFIG[@]}") \
    >"$WORK/local.log" 2>&1 || { tail -30 "$WORK/local.log"; fail "local run"; }
t_local=$("$PY" -c "print(round($(now) - $t0))")

echo "== the same through the SLURM profile (python workflow/profiles/slurm/run.py)"
t0=$(now)
(cd "$WORK/slurm" && "$PY" workflow/profiles/slurm/run.py "$TARGET" "${CONFIG[@]}") \
    >"$WORK/slurm.log" 2>&1 || { tail -40 "$WORK/slurm.log"; fail "SLURM run (log $WORK/slurm.log)"; }
t_slurm=$("$PY" -c "print(round($(now) - $t0))")
grep -E '^SLURM: ' "$WORK/slurm.log" | grep -v 'python -m snakemake' || true
echo "stability part (CI): local -c2 ${t_local} s, one-node SLURM ${t_slurm} s," \
    "ratio $("$PY" -c "print(f'{$t_slurm / $t_local:.1f}')")"

echo "== results: local against SLURM"
"$PY" tools/compare_results.py "$WORK/local" "$WORK/slurm" | tail -3
"$PY" tools/compare_results.py "$WORK/local" "$WORK/slurm" >/dev/null || fail "SLURM results differ from the local run"

echo "== a job killed by SLURM: stability_panels_fig9 cancelled while it runs"
rule=stability_panels_fig9
# the other figures' panel datasets (what is drawn or summed from fig9 is rebuilt, rightly)
stamp() { (cd "$WORK/slurm" && find results/stability/fig* -name '*.nc' ! -path '*/fig9/*' -printf '%p %T@\n' | sort); }
before=$(stamp)
# targets first: --forcerun and --configfile take several values
(cd "$WORK/slurm" && exec "$PY" workflow/profiles/slurm/run.py "$TARGET" --retries 0 --forcerun "$rule" "${CONFIG[@]}") \
    >"$WORK/fault.log" 2>&1 &
pid=$!
job=""
for _ in $(seq 600); do # up to 120 s for the submission and the job to start
    job=$(grep -oE "rule_$rule/[0-9]+\.log" "$WORK/fault.log" | head -1 | sed -E 's|.*/([0-9]+)\.log|\1|' || true)
    [[ -n $job && $(squeue -h -j "$job" -o %T 2>/dev/null) == RUNNING ]] && break
    sleep 0.2
done
[[ -n $job ]] || fail "the job of $rule was never submitted (log $WORK/fault.log)"
scancel "$job"
echo "scancel $job ($rule)"
if wait "$pid"; then fail "Snakemake did not fail after its job was cancelled"; fi
pid=""
grep -q "Error in rule $rule" "$WORK/fault.log" || fail "no 'Error in rule $rule' in $WORK/fault.log"
grep -q "SLURM status is: 'CANCELLED'" "$WORK/fault.log" || fail "no CANCELLED status in $WORK/fault.log"
grep -q "slurm_logs/rule_$rule/$job.log" "$WORK/fault.log" || fail "the SLURM log is not named in $WORK/fault.log"
grep -A12 "Error in rule $rule" "$WORK/fault.log" | grep -E "Error in rule|message|log:" | cut -c1-200

echo "== rerun through the profile"
(cd "$WORK/slurm" && "$PY" workflow/profiles/slurm/run.py "$TARGET" "${CONFIG[@]}") >"$WORK/rerun.log" 2>&1 ||
    { tail -40 "$WORK/rerun.log"; fail "rerun after the cancelled job"; }
grep -A12 '^Job stats' "$WORK/rerun.log" | head -12
[[ $(stamp) == "$before" ]] || fail "the rerun rewrote datasets of figures that had finished"
grep -qE "^$rule +1" "$WORK/rerun.log" || fail "the rerun did not run $rule"
if grep -A40 '^Job stats' "$WORK/rerun.log" | grep -E '^stability_panels_' | grep -qv "^$rule "; then
    fail "the rerun ran the panels of other figures"
fi
"$PY" tools/compare_results.py "$WORK/local" "$WORK/slurm" >/dev/null || fail "results differ after the rerun"
echo "SLURM check passed: identical results; the cancelled job was reported and rerun, nothing else redone"
