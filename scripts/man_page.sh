#!/usr/bin/env bash
# budjam.1 from the help text (help2man): `budjam --help` as the synopsis and options, and a
# SUBCOMMANDS section with every subcommand's own --help.
#   bash scripts/man_page.sh BUDJAM_EXE OUT.1
set -euo pipefail
exe=$1 out=$2
include=$(mktemp)
trap 'rm -f "$include"' EXIT
{
  echo "[SUBCOMMANDS]"
  for sub in $("$exe" --help | awk '/^Subcommands:/ { s = 1; next } s && /^  [a-z]/ { print $1 }'); do
    echo ".SS budjam $sub"
    echo ".nf"
    "$exe" "$sub" --help | sed -e 's/\\/\\e/g' -e 's/^\./\\\&./'
    echo ".fi"
  done
  echo "[FILES]"
  echo "Scene, packing, run-directory and export formats, the output convention (--out DIR for grow, analyse and accuracy; --out BASE writing BASE.json (and BASE.csv for rigidity, dos and survival), --json and --quiet for moduli, rigidity, dos and survival), exit codes: docs/files.md in the source tree; every column with its units: docs/columns.md."
} > "$include"
help2man --locale=C.UTF-8 --no-info --no-discard-stderr --name "growing budding-cell packings, jamming and rigidity" \
  --section 1 --include "$include" --output "$out.tmp" "$exe"
mv "$out.tmp" "$out"
