#!/usr/bin/env bash
# "Behaviour unchanged", measured: builds two revisions in git worktrees, runs the same workload
# with each, and compares every output file byte for byte.
#
#   scripts/same_outputs.sh REV_A REV_B [WORKDIR]
#
# Workload, run inside each revision's worktree so that the paths written into the outputs agree:
#   - budjam grow data/scenes/demo.toml --out demo-run
#   - make -f Makefile.analysis PRESET=quick SEEDS="1 2" P0S="none 1e-2" runs moduli dos analysis
#     (other seeds and P0 values: SAME_SEEDS="..." SAME_P0S="..." in the environment)
#   - ctest -L fast: both revisions must pass it (its output holds timings, so only the verdict counts)
#
# Left out of the comparison, because they describe the session and not the results:
#   - timing.json of every run (wall-clock seconds and rates; summary.json holds no timing)
#   - .budjam-lock of every run directory ("pid host" of the process that wrote it)
#   - *.done stamps and *.tmp files of Makefile.analysis (empty or transient)
# Everything else — summary.json, scene.toml, steps.csv, divisions.csv, bud_events.csv, packings,
# moduli / dos sidecars, the analysis tables and JSON — must be identical.
#
# WORKDIR (default: a new temporary directory) keeps one worktree per commit, reused by later calls
# (only the outputs are made afresh). Put it below ccache's base_dir (`ccache -p | grep base_dir`)
# so that the two builds share cached objects. Exit 0: all compared files identical and both test
# runs passed; 1: a difference or a failed test (listed); 2: bad arguments or a failed build.
set -euo pipefail

if (($# < 2 || $# > 3)); then
  sed -n '2,22p' "$0" | sed 's/^# \{0,1\}//' >&2
  exit 2
fi
repo=$(git -C "$(dirname "$0")/.." rev-parse --show-toplevel)
work=${3:-$(mktemp -d "${TMPDIR:-/tmp}/same_outputs.XXXXXX")}
mkdir -p "$work"
work=$(cd "$work" && pwd)
jobs=${JOBS:-2}
seeds=${SAME_SEEDS:-1 2}
p0s=${SAME_P0S:-none 1e-2}

# Worktree and build of one revision; prints the worktree path.
prepare() {
  local sha wt
  sha=$(git -C "$repo" rev-parse --verify "$1^{commit}") || { echo "same_outputs: no commit '$1'" >&2; exit 2; }
  wt=$work/$sha
  if [ ! -d "$wt" ]; then
    git -C "$repo" worktree add --detach "$wt" "$sha" >&2
  fi
  cmake -S "$wt" -B "$wt/build" -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_COMPILER_LAUNCHER=ccache >"$wt/build.log" 2>&1 &&
    cmake --build "$wt/build" -j"$jobs" >>"$wt/build.log" 2>&1 ||
    { echo "same_outputs: build of $1 failed, see $wt/build.log" >&2; exit 2; }
  echo "$wt"
}

# The workload in worktree $1; outputs land in $1/demo-run, $1/runs, $1/analysis.
workload() {
  local wt=$1
  (
    cd "$wt"
    rm -rf demo-run runs analysis
    build/budjam grow data/scenes/demo.toml --out demo-run --quiet
    make -f Makefile.analysis PRESET=quick SEEDS="$seeds" P0S="$p0s" runs moduli dos analysis >make.log 2>&1 ||
      { echo "same_outputs: Makefile.analysis failed in $wt, see $wt/make.log" >&2; exit 2; }
  )
}

tests_pass() {
  (cd "$1/build" && ctest -L fast -j"$jobs" --output-on-failure >"$1/ctest.log" 2>&1)
}

wt_a=$(prepare "$1")
wt_b=$(prepare "$2")
status=0
for wt in "$wt_a" "$wt_b"; do
  workload "$wt"
  if ! tests_pass "$wt"; then
    echo "FAILED ctest -L fast in $wt (see $wt/ctest.log)"
    status=1
  fi
done

# Every output file of either side, relative to the worktree.
list() {
  (cd "$1" && find demo-run runs analysis -type f ! -name timing.json ! -name .budjam-lock ! -name '*.done' \
    ! -name '*.tmp' | sort)
}
compared=0 differ=0
while IFS= read -r f; do
  compared=$((compared + 1))
  if [ ! -f "$wt_a/$f" ] || [ ! -f "$wt_b/$f" ]; then
    echo "ONLY ONE SIDE: $f"
    differ=$((differ + 1))
  elif ! cmp -s "$wt_a/$f" "$wt_b/$f"; then
    echo "DIFFERS: $f"
    diff "$wt_a/$f" "$wt_b/$f" | head -n 6 | sed 's/^/    /' || true
    differ=$((differ + 1))
  fi
done < <(sort -u <(list "$wt_a") <(list "$wt_b"))

echo "same_outputs: $1 vs $2: $compared files compared, $((compared - differ)) identical, $differ differ" \
  "(timing.json, .budjam-lock excluded); ctest -L fast $([ $status = 0 ] && echo passed || echo FAILED)"
[ $differ = 0 ] || status=1
exit $status
