#!/usr/bin/env bash
# Whole-run cost against size (docs/speed.md): build/bench_scaling at each box side, each side with
# its own seeds, then the log-log fits of scripts/scaling_fit.py (total CPU ~ N^k ± se over all
# runs) and, per side, the median search trials and marginal relaxations per run.
#
#   bench/scaling.sh [--L "8 15 20 30 40 60"] [--seeds K] [--jobs J] [--out DIR] [--bench PATH]
#                    [-- extra bench_scaling arguments]
#     --seeds K   runs per box side (default 3); side L uses seeds 1000 L + 1 ... 1000 L + K, so no
#                 two sides share a seed list and the sizes are independent samples
#     --jobs J    runs at once (default 2); each run's CPU seconds are its own process's
#     --out DIR   where each run's NAME.csv and NAME.txt go (default a new temporary directory, kept)
#
# The scene is bench_scaling's default (data/scenes/paper-L15.toml, P0 = 1e-3) to Δφ = 1e-2.
set -euo pipefail
cd "$(dirname "$0")/.."
usage() { sed -n '2,13p' "$0" | sed 's/^# \{0,1\}//'; }
LS="8 15 20 30 40 60" K=3 JOBS=2 OUT="" BENCH=build/bench_scaling
EXTRA=()
while [ $# -gt 0 ]; do
  case $1 in
    --L) LS=$2; shift 2 ;;
    --seeds) K=$2; shift 2 ;;
    --jobs) JOBS=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    --bench) BENCH=$2; shift 2 ;;
    --) shift; EXTRA=("$@"); break ;;
    -h|--help) usage; exit 0 ;;
    *) echo "scaling.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
[ -x "$BENCH" ] || { echo "scaling.sh: $BENCH is not an executable (build with -DBUDJAM_BENCHMARKS=ON)" >&2; exit 2; }
[[ $K =~ ^[1-9][0-9]*$ ]] || { echo "scaling.sh: --seeds must be a positive integer, got $K" >&2; exit 2; }
OUT=${OUT:-$(mktemp -d /tmp/budjam-scaling.XXXXXX)}
mkdir -p "$OUT"

jobs_file=$OUT/jobs
: >"$jobs_file"
for L in $LS; do
  for ((k = 1; k <= K; ++k)); do echo "$L $((1000 * L + k))" >>"$jobs_file"; done
done
echo "scaling.sh: $(wc -l <"$jobs_file") runs (box sides $LS, $K seeds each) into $OUT, $JOBS at a time" >&2
export BENCH OUT
# Largest boxes first, so that the long runs do not start last.
sort -k1,1nr "$jobs_file" | xargs -P "$JOBS" -L 1 bash -c '
  L=${@: -2:1} seed=${@: -1}
  name=L$L-s$seed
  "$BENCH" --L "$L" --set run.seed="$seed" --csv "$OUT/$name.csv" "${@:1:$#-2}" >"$OUT/$name.txt" ||
    echo "scaling.sh: $name ended with status $? (see $OUT/$name.txt)" >&2' scaling "${EXTRA[@]}"
python3 scripts/scaling_fit.py "$OUT"/L*-s*.csv
