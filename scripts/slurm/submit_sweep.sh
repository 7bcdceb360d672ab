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
#   SLURM_GRACE           seconds before the time limit at which a task is requeued (default 120)
#   SLURM_WAIT=1          wait for the analysis job and exit with its status
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
wait_flag=()
[[ ${SLURM_WAIT:-0} == 1 ]] && wait_flag=(--wait)
echo "submit_sweep: $n runs as job array $array; $final after them" >&2
sbatch --parsable --job-name=budjam-analysis --dependency="afterok:$array" --kill-on-invalid-dep=yes \
  --output="$state/analysis-%j.log" "${wait_flag[@]}" "${extra[@]}" \
  "$here/analysis_job.sh" "$makecmd" "$final"
