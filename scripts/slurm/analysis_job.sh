#!/usr/bin/env bash
# The analysis stage of a Slurm sweep (submit_sweep.sh): runs after every run task succeeded.
set -euo pipefail
makecmd=$1 final=$2
# shellcheck disable=SC2086  # the make command is words
exec $makecmd "$final"
