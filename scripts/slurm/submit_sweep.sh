#!/usr/bin/env bash
# Submits a sweep of Makefile.analysis to Slurm (called by `make -f Makefile.analysis slurm`, or
# `quick`/`paper` with SCHEDULER=slurm): a job array with one task per run (the run, then its
# moduli and spectra: the Makefile's own per-run rules), and the analysis stage as a job that
# starts when every task has succeeded. The jobs run the same make rules as the local path, so
# the results are the same files, byte for byte.
#   submit_sweep.sh STATE_DIR "MAKE COMMAND" "PER-RUN TARGETS" FINAL_TARGET
# STATE_DIR/runs.txt lists the run directories, one a line. The environment (make's command-line
# variables travel in MAKEFLAGS) is exported to the jobs. Knobs (environment):
#   SLURM_SBATCH_OPTIONS  extra sbatch options for every job, e.g. "--partition=long --time=2:00:00"
#   SLURM_MAX_PARALLEL    at most this many array tasks at once (default: no limit)
#   SLURM_GRACE           seconds before the time limit at which a task is stopped and requeued
#                         (default 120; a run still in a growth attempt after half of it is requeued
#                         from its last checkpoint)
#   SLURM_WAIT=1          wait: a progress line every SLURM_POLL seconds (default 30), then exit
#                         with the sweep's status; on failure, the last SLURM_LOG_LINES (default 15)
#                         lines of each failed job's log. Without it the script returns once the
#                         jobs are submitted and says how to follow them.
# Each job leaves its exit status beside its log (run-<array>_<task>.rc, analysis-<job>.rc).
set -euo pipefail
state=$1 makecmd=$2 per_run=$3 final=$4
here=$(cd "$(dirname "$0")" && pwd)
n=$(wc -l < "$state/runs.txt")
((n > 0)) || { echo "submit_sweep: no runs in $state/runs.txt" >&2; exit 2; }
read -r -a extra <<<"${SLURM_SBATCH_OPTIONS:-}"
limit=${SLURM_MAX_PARALLEL:+%$SLURM_MAX_PARALLEL}

array=$(sbatch --parsable --job-name=budjam-runs --array="0-$((n - 1))$limit" --requeue \
  --signal="B:USR1@${SLURM_GRACE:-120}" --output="$state/run-%A_%a.log" --open-mode=append "${extra[@]}" \
  "$here/run_task.sh" "$state/runs.txt" "$makecmd" "$per_run")
analysis=$(sbatch --parsable --job-name=budjam-analysis --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --output="$state/analysis-%j.log" "${extra[@]}" "$here/analysis_job.sh" "$state" "$makecmd" "$final")
echo "submit_sweep: $n runs as job array $array; $final as job $analysis after them; logs in $state/" >&2
if [[ ${SLURM_WAIT:-0} != 1 ]]; then
  echo "submit_sweep: not waiting; follow with: squeue -j $array,$analysis (SLURM_WAIT=1 waits and reports)" >&2
  echo "$analysis"
  exit 0
fi

while squeue -h -j "$array,$analysis" -o %i 2>/dev/null | grep -q .; do
  left=$(squeue -h -r -j "$array" -o %i 2>/dev/null | wc -l)
  echo "submit_sweep: [$((n - left)) of $n runs done; $final waits for them]" >&2
  sleep "${SLURM_POLL:-30}"
done
if [[ $(cat "$state/analysis-$analysis.rc" 2>/dev/null) == 0 ]]; then
  echo "$analysis"
  exit 0
fi
# The failed jobs, each with the end of its log; a run task that failed cancels the analysis.
failed=0
for rc in "$state/run-${array}_"*.rc "$state/analysis-$analysis.rc"; do
  [[ -f $rc && $(cat "$rc") != 0 ]] || continue
  failed=$((failed + 1))
  echo "submit_sweep: ${rc%.rc}.log (exit $(cat "$rc")) ends with:" >&2
  tail -n "${SLURM_LOG_LINES:-15}" "${rc%.rc}.log" | sed 's/^/  /' >&2
done
((failed)) || echo "submit_sweep: job $analysis did not run to its end and no job reported a failure" \
  "(cancelled, or a node lost?): see the logs in $state/" >&2
exit 1
