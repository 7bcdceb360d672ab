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

# `budjam grow` stops at the end of the growth attempt it is in, with a checkpoint; one trial of a
# marginal search of a large packing can outlast the grace, so the task waits at most half of it
# and requeues anyway: the run then resumes from its last checkpoint (the periodic one, or the one
# after its last marginal relaxation), and only the trial in progress is grown again.
requeue() {
  echo "run_task: time limit near: stopping $dir and requeueing" >&2
  kill -TERM "$child" 2>/dev/null || true
  # polled every tenth of a second: a run that stops at once is requeued at once
  local tenths=0
  while kill -0 "$child" 2>/dev/null && ((tenths < ${SLURM_GRACE:-120} * 5)); do
    sleep 0.1
    tenths=$((tenths + 1))
  done
  kill -0 "$child" 2>/dev/null &&
    echo "run_task: $dir did not stop within $((tenths / 10)) s; requeued from its last checkpoint" >&2
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
