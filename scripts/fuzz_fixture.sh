#!/usr/bin/env bash
# Regenerates what the checkpoint and resume fuzz harnesses start from, after a change of the
# checkpoint format: the run directory fuzz/fixtures/resume/ (a run of the harnesses' scene,
# checkpoint_scene() in fuzz/harnesses.hpp, killed after a checkpoint of its jammed phase) and the
# seeds fuzz/corpus/{checkpoint,resume}/{unjammed,relaxation,jammed}.txt (its first checkpoint before
# jamming, its first inside a relaxation, and the one the fixture holds), fuzz/corpus/checkpoint/bracket.txt (a checkpoint between two
# trials of the bracket search, with its open bracket); and the checkpoint reproducers
# fuzz/reproducers/checkpoint/*.txt, each with its defect made again in the new jammed seed.
#   bash scripts/fuzz_fixture.sh [BUDJAM]   (default build/budjam)
set -euo pipefail
cd "$(dirname "$0")/.."
budjam=${1:-build/budjam}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cp fuzz/fixtures/resume/scene.toml "$work/scene.toml"
"$budjam" grow "$work/scene.toml" --out "$work/run" --quiet &
pid=$!
# The run goes on in short bursts between SIGSTOP and SIGCONT, and its checkpoint is read while it
# is stopped: so a checkpoint and the logs beside it belong to one moment, as a kill leaves them, and
# the moment a checkpoint of each phase is written is not missed.
phase() {  # the phase on the checkpoint's `state` line (its sixth), or nothing
  local lines=()
  [[ -f $work/run/checkpoint.txt ]] && mapfile -n 6 -t lines < "$work/run/checkpoint.txt"
  local state=${lines[5]:-}
  [[ $state == state\ * ]] && { state=${state#state }; echo "${state%% *}"; }
}
wait_for() {  # wait_for PHASE: returns with the run stopped at a checkpoint of PHASE, between two steps
  while true; do
    kill -STOP $pid 2>/dev/null || { echo "fuzz_fixture: the run ended before a checkpoint while $1" >&2; exit 1; }
    [[ $(phase) == "$1" ]] && grep -q '^relaxation 0$' "$work/run/checkpoint.txt" && return
    kill -CONT $pid
    read -r -t 0.002 <> <(:) || true
  done
}
wait_for unjammed
cp "$work/run/checkpoint.txt" "$work/unjammed.txt"
kill -CONT $pid
# A checkpoint inside a relaxation (the scene's checkpoint_evaluations is small), before jamming.
while true; do
  kill -STOP $pid 2>/dev/null || { echo "fuzz_fixture: the run ended before a checkpoint inside a relaxation" >&2; exit 1; }
  grep -q '^relaxation 1 ' "$work/run/checkpoint.txt" && break
  [[ $(phase) == jammed ]] && { echo "fuzz_fixture: no checkpoint inside a relaxation before jamming" >&2; exit 1; }
  kill -CONT $pid
  read -r -t 0.002 <> <(:) || true
done
cp "$work/run/checkpoint.txt" "$work/relaxation.txt"
kill -CONT $pid
wait_for jammed
rm -rf fuzz/fixtures/resume.new
mkdir -p fuzz/fixtures/resume.new/packings
cp "$work/run/checkpoint.txt" "$work/run/scene.toml" "$work/run/"*.partial fuzz/fixtures/resume.new/
cp "$work/run/packings/"*.pack fuzz/fixtures/resume.new/packings/
kill -KILL $pid
{ wait $pid; } 2>/dev/null || true
rm -rf fuzz/fixtures/resume
mv fuzz/fixtures/resume.new fuzz/fixtures/resume
for corpus in checkpoint resume; do
  cp "$work/unjammed.txt" "fuzz/corpus/$corpus/unjammed.txt"
  cp "$work/relaxation.txt" "fuzz/corpus/$corpus/relaxation.txt"
  cp fuzz/fixtures/resume/checkpoint.txt "fuzz/corpus/$corpus/jammed.txt"
done
# The bracket seed: the same run stopped by SIGTERM soon after each start (once its logs exist) and
# resumed, until a signal lands in its search onto phi_J with both ends of the bracket kept (in a
# trial's relaxation, as a signal in the search mostly does: the state before the trial holds the
# bracket).
in_bracket() { grep -q '^trial below ' "$1" 2>/dev/null; }
"$budjam" grow "$work/scene.toml" --out "$work/b" --quiet 2>/dev/null &
pid=$!
for ((k = 0; k < 5000; ++k)); do
  for ((w = 0; w < 2000; ++w)); do
    [[ -f $work/b/steps.csv.partial ]] && break
    read -r -t 0.001 <> <(:) || true
  done
  read -r -t "$(printf '0.%03d' $((RANDOM % 40 + 5)))" <> <(:) || true  # 5-44 ms: a resume's start, a few trials
  kill -TERM $pid 2>/dev/null || true
  { wait $pid; } 2>/dev/null || true
  in_bracket "$work/b/checkpoint.txt" && break
  [[ -f $work/b/summary.json ]] && { echo "fuzz_fixture: no signal landed inside the search" >&2; exit 1; }
  if [[ -f $work/b/checkpoint.txt ]]; then
    "$budjam" grow --resume "$work/b" --quiet 2>/dev/null &
  else
    "$budjam" grow "$work/scene.toml" --out "$work/b" --overwrite --quiet 2>/dev/null &
  fi
  pid=$!
done
in_bracket "$work/b/checkpoint.txt" || { echo "fuzz_fixture: no checkpoint inside the search" >&2; exit 1; }
cp "$work/b/checkpoint.txt" fuzz/corpus/checkpoint/bracket.txt
echo "fuzz_fixture: $(grep -c . fuzz/fixtures/resume/steps.csv.partial) rows of steps.csv;" \
     "checkpoint at $(sed -n 's/^state \([a-z]*\) [^ ]* [^ ]* [^ ]* \([0-9]*\) .*/\1, step \2/p' fuzz/fixtures/resume/checkpoint.txt)" >&2
# The checkpoint reproducers, each its defect made again in the new jammed seed.
/usr/bin/python3 - <<'PY'
seed = open('fuzz/corpus/checkpoint/jammed.txt').read().split('\n')
def line(lines, word):
    return next(k for k, x in enumerate(lines) if x.startswith(word + ' '))
def remade(name, edit):
    lines = list(seed)
    edit(lines)
    open('fuzz/reproducers/checkpoint/' + name, 'w').write('\n'.join(lines))
def field(word, index, value):
    def edit(lines):
        k = line(lines, word)
        w = lines[k].split()
        w[index] = value
        lines[k] = ' '.join(w)
    return edit
def without_section(name):
    def edit(lines):
        k = line(lines, 'observer ' + name)
        del lines[k:k + 1 + int(lines[k].split()[2])]
    return edit
remade('huge-next-target.txt', field('state', 7, '9223372036854775807'))
remade('shear-1e308.txt', field('packing', 2, '1e308'))
remade('no-run-log-section.txt', without_section('run_log'))
PY
