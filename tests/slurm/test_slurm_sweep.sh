#!/usr/bin/env bash
# ctest slurm_sweep: a small sweep of Makefile.analysis through a real Slurm (a single-node cluster
# on this machine, scripts/slurm/start_local_slurm.sh) gives the same files, byte for byte, as the
# local path. Needs root and Debian's slurm-wlm and munge; exits 77 (ctest: skipped) without them.
#   bash tests/slurm/test_slurm_sweep.sh SOURCE_DIR BUDJAM_EXE
set -euo pipefail
source=$1 budjam=$2
if [[ $(id -u) != 0 ]] || ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
  echo "test_slurm_sweep: needs root, slurm-wlm and munge: skipped" >&2
  exit 77
fi
started=0
sinfo -h -o %T 2>/dev/null | grep -qE '^(idle|mixed|allocated)' || started=1
bash "$source/scripts/slurm/start_local_slurm.sh"

work=$(mktemp -d /tmp/budjam-slurm-test.XXXXXX)  # /tmp: visible to the jobs on this node
cleanup() {
  rm -rf "$work"
  ((started)) && bash "$source/scripts/slurm/start_local_slurm.sh" stop  # leave the machine as found
  return 0
}
trap cleanup EXIT
# Two: 2 seeds x 2 P0 at L = 8, to two targets, with moduli and spectra; the analysis tables.
sweep=(PRESET=quick "BUDJAM=$budjam" LS=8 "P0S=none 1e-3" "SEEDS=1 2" "TARGETS=[1e-3,1e-2]" MAX_STEPS=20000)
for where in local slurm; do
  mkdir -p "$work/$where"
  ln -s "$source/Makefile.analysis" "$source/scripts" "$source/data" "$work/$where/"
done
(cd "$work/local" && make -s -f Makefile.analysis "${sweep[@]}" analysis >/dev/null)
(cd "$work/slurm" && SLURM_WAIT=1 make -s -f Makefile.analysis "${sweep[@]}" quick SCHEDULER=slurm \
   SLURM_FINAL=analysis >/dev/null) || { cat "$work"/slurm/analysis/quick/slurm/*.log >&2; exit 1; }

tasks=$(ls "$work"/slurm/analysis/quick/slurm/run-*.log | wc -l)
[[ $tasks == 4 ]] || { echo "test_slurm_sweep: expected 4 array tasks, found $tasks logs" >&2; exit 1; }
# Everything but the wall-clock timings, the lock files and the Slurm logs must be identical:
# timing.json (wall time) and .budjam-lock (the pid and host of the last writer) name the machine, not the result.
diff -r --exclude=timing.json --exclude=.budjam-lock --exclude=slurm "$work/local/runs" "$work/slurm/runs"
diff -r --exclude=slurm "$work/local/analysis" "$work/slurm/analysis"
echo "test_slurm_sweep: 4 runs through Slurm (array + dependent analysis) equal the local sweep byte for byte"
