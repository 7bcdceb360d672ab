#!/usr/bin/env bash
# The analysis stage of a Slurm sweep (submit_sweep.sh): runs after every run task succeeded and
# leaves its exit status in STATE_DIR/analysis-<job>.rc for the submitter.
#   analysis_job.sh STATE_DIR "MAKE COMMAND" FINAL_TARGET
set -euo pipefail
state=$1 makecmd=$2 final=$3
rc=0
# shellcheck disable=SC2086  # the make command is words
$makecmd "$final" || rc=$?
echo "$rc" >"$state/analysis-$SLURM_JOB_ID.rc"
exit "$rc"
