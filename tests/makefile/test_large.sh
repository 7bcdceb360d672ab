#!/usr/bin/env bash
# `make -f Makefile.analysis large` on data/scenes/jammed-1e5.toml shrunk to 500 cells: the run, its
# moduli and its spectrum are written, and a second make has nothing left to do.
#   test_large.sh SOURCE_DIR BUDJAM OUT
set -euo pipefail
src=$1 budjam=$2 out=$3
rm -rf "$out"
large() {
  make -C "$src" -f Makefile.analysis large BUDJAM="$budjam" LARGE_OUT="$out" \
    LARGE_SET="--quiet --set box.L=25 --set init.cells=250 --set minimiser.threads=1"
}
large
for f in summary.json packings/jammed.pack packings/jammed.moduli.json packings/jammed.dos.json packings/jammed.dos.csv; do
  test -s "$out/$f" || { echo "test_large: $out/$f missing" >&2; exit 1; }
done
grep -q '"status": "finished"' "$out/summary.json"
again=$(large)
if grep -E -q ' (grow|moduli|dos) ' <<<"$again"; then
  echo "test_large: the second make ran again:" >&2
  echo "$again" >&2
  exit 1
fi
