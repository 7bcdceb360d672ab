#!/usr/bin/env bash
# One array task of a Slurm sweep (submit_sweep.sh): the run on line SLURM_ARRAY_TASK_ID + 1 of
# RUNS_FILE, through the Makefile's per-run rules. A run interrupted by preemption or by the time
# limit is requeued (sbatch --requeue; USR1 shortly before the limit, see --signal) and continues
# from its checkpoint when it has one: the Makefile's rule resumes it.
#SBATCH --requeue
set -euo pipefail
runs=$1 makecmd=$2 per_run=$3
dir=$(sed -n "$((SLURM_ARRAY_TASK_ID + 1))p" "$runs")
targets=()
for t in $per_run; do targets+=("$dir/$t"); done

requeue() {
  echo "run_task: time limit near: stopping $dir and requeueing" >&2
  kill -TERM "$child" 2>/dev/null || true
  wait "$child" || true
  scontrol requeue "${SLURM_ARRAY_JOB_ID}_${SLURM_ARRAY_TASK_ID}"
  exit 0
}
trap requeue USR1
# shellcheck disable=SC2086  # the make command is words
$makecmd "${targets[@]}" &
child=$!
rc=0
wait "$child" || rc=$?
# The status, beside the task's log, for the submitter (submit_sweep.sh with SLURM_WAIT=1).
echo "$rc" >"$(dirname "$runs")/run-${SLURM_ARRAY_JOB_ID}_${SLURM_ARRAY_TASK_ID}.rc"
exit "$rc"
