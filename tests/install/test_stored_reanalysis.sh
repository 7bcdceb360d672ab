#!/usr/bin/env bash
# ctest stored_reanalyses_are_this_builds: data/reference/*/reanalysed is what this build's
# `budjam analyse --tables` makes of the committed tables (Makefile.analysis stored-report writes
# them there), so that a report or `make quick` leaves the checkout as it found it.
#   bash tests/install/test_stored_reanalysis.sh BUDJAM SOURCE_DIR WORK_DIR
set -euo pipefail
budjam=$1 source=$2 work=$3
rm -rf "$work"
cd "$source"  # analysis.json records the tables as named, relative as in Makefile.analysis
status=0
for stored in data/reference/*/reanalysed; do
  preset=$(basename "$(dirname "$stored")")
  main_L=$(python3 -c 'import json, sys; print(json.load(open(sys.argv[1]))["main_L"])' "$stored/analysis.json")
  "$budjam" analyse --tables "$(dirname "$stored")/tables" --out "$work/$preset" --main-L "$main_L" >/dev/null 2>&1
  for f in "$stored"/*; do
    cmp -s "$f" "$work/$preset/$(basename "$f")" ||
      { echo "test_stored_reanalysis: $f is not this build's (make -f Makefile.analysis PRESET=$preset stored-report)" >&2; status=1; }
  done
done
exit $status
