#!/usr/bin/env bash
# The demo of `bootstrap.sh demo`: grow data/scenes/demo.toml into OUT and draw its jammed packing
# beside its packings (the top level of a run holds only the run's own files).
#   bash scripts/demo_run.sh BUDJAM OUT
set -euo pipefail
budjam=$1 out=$2
scene="$(dirname "$0")/../data/scenes/demo.toml"
"$budjam" grow "$scene" --out "$out" --overwrite
"$budjam" render "$out/packings/jammed.pack" -o "$out/packings/jammed.svg" --png
for f in summary.json packings/jammed.svg packings/jammed.png; do
  [[ -s $out/$f ]] || { echo "demo_run: no $out/$f" >&2; exit 1; }
done
