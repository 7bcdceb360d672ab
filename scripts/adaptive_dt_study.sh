#!/bin/bash
# Runs of the adaptive growth step study (docs/growth.md, "Adaptive growth step"): for every P0 and
# seed, one run with the nominal step and one with growth.adaptive_dt, same minimiser, then the
# moduli of every target packing. Usage:
#   scripts/adaptive_dt_study.sh OUT_DIR [L] [SEEDS] [NOMINAL_MAX_STEPS]
# e.g. scripts/adaptive_dt_study.sh runs/adaptive-study 8 "$(seq 1 20)" 40000; then
#   python3 scripts/adaptive_dt_table.py runs/adaptive-study
# Two runs at a time (JOBS=2), each under nice. BUDJAM (default build/budjam) is the executable;
# P0S (default "1e-2 1e-3 1e-4 1e-5") the feedback strengths.
set -euo pipefail
out=${1:?usage: adaptive_dt_study.sh OUT_DIR [L] [SEEDS] [NOMINAL_MAX_STEPS]}
L=${2:-8}
seeds=${3:-$(seq 1 20)}
nominal_max=${4:-40000}
budjam=${BUDJAM:-build/budjam}
jobs=${JOBS:-2}
scene=data/scenes/paper-L15.toml
# The paper's grid per P0: Δφ up to 0.12 at P0 = 1e-2, 0.06 at 1e-3 and 1e-4, 0.03 at 1e-5.
declare -A targets=([1e-2]='[1e-4,3e-4,1e-3,3e-3,1e-2,3e-2,6e-2,0.1,0.12]' [1e-3]='[1e-4,3e-4,1e-3,3e-3,1e-2,3e-2,6e-2]' [1e-4]='[1e-4,3e-4,1e-3,3e-3,1e-2,3e-2,6e-2]'
                    [1e-5]='[1e-4,3e-4,1e-3,3e-3,1e-2,3e-2]')
minimiser=(--set minimiser.newton_force=1e-6)

one_run() {  # protocol P0 seed
  local dir=$out/$1/P0_$2/seed$3 protocol=()
  [ -f "$dir/summary.json" ] && return 0
  if [ "$1" = adaptive ]; then
    protocol=(--set growth.adaptive_dt=true --set growth.adaptive_floor=1e-300 --set growth.max_steps=40000)
  else
    protocol=(--set growth.max_steps="$nominal_max")
  fi
  nice -n 5 "$budjam" grow "$scene" --out "$dir" --overwrite --seed "$3" --quiet --set box.L="$L" --set growth.P0="$2" \
    --set "jamming.targets=${targets[$2]}" --set jamming.continue_to_phi2=true "${minimiser[@]}" "${protocol[@]}" || [ $? = 1 ]
  for p in "$dir"/packings/target_*.pack; do
    [ -e "$p" ] && nice -n 5 "$budjam" moduli "$p" --out "${p%.pack}.moduli" || [ $? = 1 ]
  done
}
for protocol in adaptive nominal; do
  for P0 in ${P0S:-1e-2 1e-3 1e-4 1e-5}; do
    for s in $seeds; do echo "$protocol $P0 $s"; done
  done
done | {
  while read -r protocol P0 s; do
    while [ "$(jobs -rp | wc -l)" -ge "$jobs" ]; do wait -n; done
    one_run "$protocol" "$P0" "$s" &
  done
  wait
}
