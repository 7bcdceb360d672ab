#!/usr/bin/env bash
# Whole growth runs of two budjam builds side by side, in CPU seconds (docs/speed.md).
#
#   bench/whole_runs.sh OLD_BUDJAM NEW_BUDJAM [options] [-- extra grow arguments for NEW only]
#     --L "15 20"          box sides (default 15)
#     --seeds "1 2 3"      seeds (default 1 2 3)
#     --targets LIST       jamming.targets (default [1e-4,3e-4,1e-3,3e-3,1e-2]); runs go on to φ_2
#     --out DIR            where the run directories go (default a temporary directory, removed)
#
# The scene is data/scenes/paper-L15.toml (P0 = 1e-3) with box.L, targets and seed set on the
# command line, keys that every build since the first release reads. The builds alternate run by
# run, so that both see the same load on a shared machine; user + system CPU seconds come from
# /usr/bin/time. Prints one line per run and the ratio of the sums, old over new, per L.
set -euo pipefail

usage() { sed -n '2,14p' "$0" | sed 's/^# \{0,1\}//'; }
[ $# -ge 2 ] || { usage >&2; exit 2; }
OLD=$1 NEW=$2
shift 2
LS=15 SEEDS="1 2 3" TARGETS="[1e-4,3e-4,1e-3,3e-3,1e-2]" OUT=""
EXTRA=()
while [ $# -gt 0 ]; do
  case $1 in
    --L) LS=$2; shift 2 ;;
    --seeds) SEEDS=$2; shift 2 ;;
    --targets) TARGETS=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --) shift; EXTRA=("$@"); break ;;
    -h|--help) usage; exit 0 ;;
    *) echo "whole_runs.sh: unknown option $1" >&2; exit 2 ;;
  esac
done
for b in "$OLD" "$NEW"; do
  [ -x "$b" ] || { echo "whole_runs.sh: $b is not an executable" >&2; exit 2; }
done
SCENE=$(cd "$(dirname "$0")/.." && pwd)/data/scenes/paper-L15.toml
if [ -z "$OUT" ]; then
  OUT=$(mktemp -d)
  trap 'rm -rf "$OUT"' EXIT
fi

# cpu_seconds BUDJAM DIR L SEED [extra...]: runs one growth run, prints its user + system CPU seconds
cpu_seconds() {
  local budjam=$1 dir=$2 L=$3 seed=$4
  shift 4
  rm -rf "$dir"
  /usr/bin/time -f "%U %S" -o "$dir.time" "$budjam" grow "$SCENE" --out "$dir" --quiet --seed "$seed" \
    --set box.L="$L" --set "jamming.targets=$TARGETS" --set jamming.continue_to_phi2=true "$@" ||
    { echo "whole_runs.sh: $budjam failed on L = $L, seed $seed" >&2; exit 1; }
  awk '{ printf "%.2f", $1 + $2 }' "$dir.time"
}

printf "%-4s %-5s %10s %10s %7s\n" L seed "old CPU s" "new CPU s" ratio
for L in $LS; do
  sum_old=0 sum_new=0
  for seed in $SEEDS; do
    old=$(cpu_seconds "$OLD" "$OUT/old_L${L}_s$seed" "$L" "$seed")
    new=$(cpu_seconds "$NEW" "$OUT/new_L${L}_s$seed" "$L" "$seed" "${EXTRA[@]}")
    printf "%-4s %-5s %10s %10s %7.2f\n" "$L" "$seed" "$old" "$new" "$(echo "$old / $new" | bc -l)"
    sum_old=$(echo "$sum_old + $old" | bc -l) sum_new=$(echo "$sum_new + $new" | bc -l)
  done
  printf "%-4s %-5s %10.2f %10.2f %7.2f\n" "$L" sum "$sum_old" "$sum_new" "$(echo "$sum_old / $sum_new" | bc -l)"
done
