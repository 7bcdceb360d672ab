#!/usr/bin/env bash
# One progress line on stderr for a stage of Makefile.analysis, after each of its items is done:
#   [moduli 12/48 runs, ETA 3m05s]
# The items are the stage's stamp files (summary.json, moduli.done, dos.done of every run): the
# count is of those that exist now, so it is right under make -j and in every Slurm task. The ETA
# extrapolates the pace of this make: the stamps made since it started (START, epoch seconds;
# AT_START of them existed then), timed from the first of them, so that a stage that waited for
# another does not count the wait.
#   bash scripts/progress.sh STAGE START AT_START STAMP...
set -euo pipefail
stage=$1 start=$2 at_start=$3
shift 3
total=$# done=0 first=
existing=()
for stamp in "$@"; do [[ -e $stamp ]] && existing+=("$stamp"); done
done=${#existing[@]}
# one stat for all of them: a process per stamp costs seconds per item on a sweep of a thousand runs
if ((done > 0)); then
  while read -r made_at; do
    if ((made_at >= start)) && [[ -z $first || $made_at -lt $first ]]; then first=$made_at; fi
  done < <(stat -c %Y "${existing[@]}")
fi
line="[$stage $done/$total runs"
paced=$((done - at_start - 1))  # items made after the first one of this make
elapsed=$(($(date +%s) - ${first:-0}))
if ((paced > 0 && elapsed > 0 && done < total)); then  # (a pace within one second is no pace)
  eta=$((elapsed * (total - done) / paced))
  if ((eta >= 3600)); then
    line+=$(printf ', ETA %dh%02dm' $((eta / 3600)) $((eta % 3600 / 60)))
  else
    line+=$(printf ', ETA %dm%02ds' $((eta / 60)) $((eta % 60)))
  fi
fi
echo "$line]" >&2
